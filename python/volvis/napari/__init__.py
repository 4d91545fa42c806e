"""VolVis's napari plug-in (npe2; the manifest napari.yaml beside this
file, found through the ``napari.manifest`` entry point of the volvis
wheel): a reader (:mod:`._reader`: .vvb, BigDataViewer, Imaris, DICOM, SLC,
NRRD, MetaImage, VTK, OME-Zarr as lazy multiscale layers), a writer
(:mod:`._writer`) and the "VolVis 3-D" dock widget (:mod:`._widget`:
napari's visible image layers rendered by VolVis from napari's camera, by
level of detail, progressively). docs/python.md, "napari".

napari itself is imported only by the widget and by the reader's colormaps.
"""
import os

#: the npe2 manifest's path
MANIFEST = os.path.join(os.path.dirname(os.path.abspath(__file__)), "napari.yaml")
