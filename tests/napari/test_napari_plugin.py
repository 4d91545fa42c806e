"""The napari plug-in (python/volvis/napari, docs/python.md "napari") with
napari from PyPI under Xvfb: the manifest, the reader's layers, the writer's
round trip, and the "VolVis 3-D" dock widget against `volvis render` of
the same World and view, before and after a camera change."""
import math
import pathlib
import subprocess
import sys
import tomllib

import numpy as np
import pytest

import volvis
from conftest import DATA, ROOT, cli


def psnr(a, b):
    a = np.asarray(a, dtype=np.float64)[..., :3]
    b = np.asarray(b, dtype=np.float64)[..., :3]
    assert a.shape == b.shape, (a.shape, b.shape)
    mse = np.mean((a - b) ** 2)
    return math.inf if mse == 0 else 10 * math.log10(255.0 ** 2 / mse)


def test_manifest_valid_and_found(plugin, ct_vvb):
    import npe2
    from volvis.napari import MANIFEST
    # npe2's own validation (the CLI `npe2 validate` on the file)
    r = subprocess.run([sys.executable, "-m", "npe2", "validate", MANIFEST],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    mf = npe2.PluginManifest.from_file(MANIFEST)
    assert mf.name == "volvis"
    assert [w.display_name for w in mf.contributions.widgets] == ["VolVis 3-D"]
    readers = [rd.plugin_name for rd in plugin.iter_compatible_readers([str(ct_vvb)])]
    assert "volvis" in readers
    assert any(w.plugin_name == "volvis" for w in
               plugin.iter_compatible_writers(["image"])), "no volvis writer for image layers"
    # the wheel's entry point names this manifest
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    ep = meta["project"]["entry-points"]["napari.manifest"]["volvis"]
    mod, res = ep.split(":")
    assert mod == "volvis.napari" and res == "napari.yaml"
    import importlib.resources
    assert importlib.resources.files(mod).joinpath(res).is_file()


def test_open_vvb_lazy_multiscale(make_napari_viewer, plugin, ct_vvb):
    v = make_napari_viewer()
    layers = v.open(str(ct_vvb), plugin="volvis")
    assert len(layers) == 1
    L = layers[0]
    assert L.multiscale
    assert [tuple(d.shape) for d in L.data] == [(108, 256, 256), (54, 128, 128), (27, 64, 64)]
    np.testing.assert_allclose(L.scale, (1.5, 0.9570312, 0.9570312), rtol=1e-6)
    np.testing.assert_allclose(L.translate, (0, 0, 0))
    lo, hi = L.contrast_limits
    assert -1024 <= lo < hi <= 2986
    whole = volvis.open(DATA / "ct_head.nrrd").array
    from volvis.napari._reader import level_array
    assert level_array(L.data[0]) is not None  # lazy: read by boxes
    pyr = level_array(L.data[0]).pyramid
    # napari's 2-D view read only the chunks its slice meets, not level 0
    assert 0 < pyr.stats["bytes_read"] < whole.nbytes / 2, pyr.stats
    np.testing.assert_array_equal(np.asarray(L.data[0][50]), whole[50])
    la = level_array(L.data[0])
    np.testing.assert_array_equal(la[3:90:7, ::-5, 17], whole[3:90:7, ::-5, 17])
    np.testing.assert_array_equal(la[-1, 4, ...], whole[-1, 4])
    np.testing.assert_array_equal(np.asarray(L.data[0]), whole)
    # level 1: 2x2x2 means of level 0 (the .vvb's pyramid), to rounding
    l1 = np.asarray(L.data[1]).astype(float)
    means = whole.astype(float).reshape(54, 2, 128, 2, 128, 2).mean(axis=(1, 3, 5))
    assert np.max(np.abs(l1 - means)) <= 1.0


@pytest.mark.parametrize("name,shape,scale", [
    ("HeadMRVolume.mhd", (42, 62, 48), (4, 4, 4)),
    ("neghip.slc", (66, 66, 66), (1, 1, 1)),
    ("ct_head.nrrd", (108, 256, 256), (1.5, 0.9570312, 0.9570312)),
])
def test_open_other_formats(make_napari_viewer, plugin, name, shape, scale):
    v = make_napari_viewer()
    layers = v.open(str(DATA / name), plugin="volvis")
    assert len(layers) == 1
    L = layers[0]
    assert L.data.shape == shape and not L.multiscale
    np.testing.assert_allclose(L.scale, scale, rtol=1e-6)
    np.testing.assert_array_equal(np.asarray(L.data), volvis.open(DATA / name).array)


@pytest.mark.parametrize("ext", [".nrrd", ".mha", ".vvb", ".vti", ".vtk", ".slc", ".ome.zarr"])
def test_writer_round_trip(make_napari_viewer, plugin, out_dir, ext):
    v = make_napari_viewer()
    arr = volvis.open(DATA / "HeadMRVolume.mhd").array
    L = v.add_image(arr, scale=(4, 2, 3), translate=(10, -5, 7), name="mr")
    path = out_dir / ("written" + ext)
    if path.is_dir():
        import shutil
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)
    saved = L.save(str(path), plugin="volvis")
    assert saved == [str(path)]
    back = volvis.open(path)
    np.testing.assert_array_equal(back.array, arr)
    np.testing.assert_allclose(back.spacing, (3, 2, 4))
    origin = (0, 0, 0) if ext == ".slc" else (7, -5, 10)  # SLC's header has no origin
    np.testing.assert_allclose(back.origin, origin)
    # and read back through the plug-in's reader
    R = v.open(str(path), plugin="volvis")[0]
    data = R.data[0] if R.multiscale else R.data
    np.testing.assert_array_equal(np.asarray(data), arr)
    np.testing.assert_allclose(R.scale, (4, 2, 3))
    np.testing.assert_allclose(R.translate, origin[::-1])


def test_writer_refuses_2d(make_napari_viewer, plugin, out_dir):
    from volvis.napari._writer import write_image
    with pytest.raises(volvis.InvalidError, match="3-D"):
        write_image(str(out_dir / "flat.nrrd"), np.zeros((4, 5), np.uint8), {})
    assert not (out_dir / "flat.nrrd").exists()


def _final(qtbot, w, before):
    w.request()
    qtbot.waitUntil(lambda: w.finals > before or w.error is not None, timeout=45000)
    assert w.error is None, w.error
    return w.image.copy()


def _widget_3d(v, angles, max_side, reset_view=False):
    """The viewer V in 3-D (its view first reset to its layers when
    RESET_VIEW), the camera at ANGLES, and a "VolVis 3-D" widget of it
    (frames of at most MAX_SIDE pixels, 10 ms debounce), not docked."""
    from volvis.napari._widget import VolVisWidget, viewer_camera
    v.dims.ndisplay = 3
    if reset_view:
        v.reset_view()
    viewer_camera(v).angles = angles
    return VolVisWidget(v, max_side=max_side, debounce_ms=10)


def _widget_of_file(make_napari_viewer, path, angles, max_side, **layer):
    """A napari viewer with PATH opened by the plug-in (its one layer given the
    attributes LAYER, in order) and _widget_3d's widget of it: (viewer,
    layer, widget)."""
    v = make_napari_viewer()
    L = v.open(str(path), plugin="volvis")[0]
    for k, val in layer.items():
        setattr(L, k, val)
    return v, L, _widget_3d(v, angles, max_side)


def _cli_render(frame, out_dir, name, volumes, options=("--lod", "1")):
    """`volvis render` of a widget frame's World (saved as the scene
    OUT_DIR/NAME.json of the files VOLUMES, one an object) at its view and
    size, with OPTIONS (default: by level of detail 1 pixel a voxel, as napari
    shows it): the image, mirrored back when the frame was drawn mirrored."""
    scene = out_dir / (name + ".json")
    w = frame["world"].clone()
    w.view = frame["view"]
    w.save(str(scene), volume_files=[str(p) for p in volumes])
    png = out_dir / (name + "_cli.png")
    size = "%dx%d" % frame["view"].size
    subprocess.run([cli(), "render", str(scene), *options, "--size", size, "-o", str(png)],
                   check=True, capture_output=True)
    ref = volvis.read_png(str(png))
    return ref[:, ::-1] if frame["mirror"] else ref


@pytest.mark.parametrize("rendering", ["mip", "translucent", "attenuated_mip"])
def test_widget_matches_cli_and_follows_camera(make_napari_viewer, qtbot, plugin, ct_vvb,
                                                out_dir, rendering):
    from volvis.napari._widget import viewer_camera
    v, L, w = _widget_of_file(make_napari_viewer, ct_vvb, (0, 20, 80), 256,
                              rendering=rendering, colormap="inferno", gamma=0.8)
    v.window.add_dock_widget(w, name="VolVis 3-D")
    img1 = _final(qtbot, w, 0)
    f1 = dict(w.frame)
    volvis.save_png(img1, str(out_dir / ("widget_%s_1.png" % rendering)))
    if rendering == "attenuated_mip":  # out of core too (by regions), not drawn as mip
        (o,) = f1["world"].objects
        assert o.mode == "attenuated-mip" and o.attenuation == pytest.approx(L.attenuation)
        assert not f1["notes"], f1["notes"]
    ref1 = _cli_render(f1, out_dir, "widget_%s_1" % rendering, [ct_vvb])
    p1 = psnr(img1, ref1)
    assert p1 >= 40, "widget vs volvis render: %.2f dB" % p1
    assert img1[..., :3].max() > 50, "a black frame"
    assert sum(f1["lod"]["nodes"]) > 0
    # turn napari's camera: the widget follows (debounced) and matches again
    n = w.finals
    viewer_camera(v).angles = (10, -35, 60)
    qtbot.waitUntil(lambda: w.finals > n, timeout=45000)
    img2 = w.image.copy()
    f2 = dict(w.frame)
    volvis.save_png(img2, str(out_dir / ("widget_%s_2.png" % rendering)))
    assert psnr(img1, img2) < 30, "the frame did not change with the camera"
    ref2 = _cli_render(f2, out_dir, "widget_%s_2" % rendering, [ct_vvb])
    p2 = psnr(img2, ref2)
    assert p2 >= 40, "after the turn, widget vs volvis render: %.2f dB" % p2
    print("PSNR %s: %.2f dB, %.2f dB after the turn" % (rendering, p1, p2))


def test_widget_attenuated_mip(make_napari_viewer, qtbot, plugin, out_dir):
    """A layer in napari's attenuated_mip is drawn in VolVis's attenuated-mip
    mode with its attenuation (a numpy layer, in memory): the frame equals
    `volvis render --mode attenuated-mip --attenuation A` of the same data
    and view, differs from mip, and re-renders when the attenuation
    changes."""
    vol = volvis.open(str(DATA / "neghip.slc"))
    v = make_napari_viewer()
    L = v.add_image(np.array(vol.array), scale=tuple(vol.spacing)[::-1],
                    translate=tuple(vol.origin)[::-1], colormap="inferno",
                    contrast_limits=(20, 200), rendering="attenuated_mip")
    L.attenuation = 0.1
    w = _widget_3d(v, (0, 25, 70), 160, reset_view=True)
    img = _final(qtbot, w, 0)
    f = dict(w.frame)
    (o,) = f["world"].objects
    assert o.mode == "attenuated-mip" and o.attenuation == pytest.approx(0.1)
    assert not f["notes"], f["notes"]
    volvis.save_png(img, str(out_dir / "widget_attenuated_mip.png"))

    def cli_ref(name, mode, att):
        return _cli_render(f, out_dir, name, [DATA / "neghip.slc"],
                           ("--mode", mode, "--attenuation", str(att)))

    p = psnr(img, cli_ref("attenuated", "attenuated-mip", 0.1))
    assert p >= 40, "attenuated_mip: widget vs volvis render: %.2f dB" % p
    assert psnr(img, cli_ref("attenuated_as_mip", "mip", 0.1)) < 30, "drawn as mip"
    assert img[..., :3].max() > 50, "a black frame"
    n = w.finals
    L.attenuation = 0.4
    qtbot.waitUntil(lambda: w.finals > n, timeout=45000)
    assert w.frame["world"].objects[0].attenuation == pytest.approx(0.4)
    assert psnr(img, w.image) < 35, "the frame did not change with the attenuation"
    print("PSNR attenuated_mip: %.2f dB" % p)
    # with shadows the ray tracer draws it, still in attenuated-mip (in memory):
    # `volvis render --renderer raytrace` of the same World, not its mip
    n = w.finals
    w.shadows.setChecked(True)
    qtbot.waitUntil(lambda: w.finals > n, timeout=45000)
    f = dict(w.frame)
    (o,) = f["world"].objects
    assert f["renderer"] == "raytrace"
    assert o.mode == "attenuated-mip" and o.attenuation == pytest.approx(0.4)
    assert not any("drawn as mip" in x for x in f["notes"]), f["notes"]
    shadowed = w.image.copy()
    volvis.save_png(shadowed, str(out_dir / "widget_attenuated_mip_shadows.png"))
    rt = ("--renderer", "raytrace")
    ps = psnr(shadowed, _cli_render(f, out_dir, "attenuated_shadows", [DATA / "neghip.slc"], rt))
    assert ps >= 40, "attenuated_mip with shadows: widget vs volvis render: %.2f dB" % ps
    f_mip = dict(f)
    f_mip["world"] = f["world"].clone()
    f_mip["world"].objects[0].mode = "mip"
    pm = psnr(shadowed, _cli_render(f_mip, out_dir, "attenuated_shadows_as_mip",
                                    [DATA / "neghip.slc"], rt))
    assert pm < 30, "attenuated_mip with shadows drawn as mip (%.2f dB)" % pm
    print("PSNR attenuated_mip with shadows: %.2f dB (its mip %.2f dB)" % (ps, pm))


@pytest.mark.parametrize("rendering", ["mip", "translucent"])
def test_widget_additive_blending(make_napari_viewer, qtbot, plugin, out_dir, rendering):
    """Two additive layers in memory on one grid are summed, as napari adds
    them: one object of two channels (VolVis's maximum rule for mip, its
    additive rule for translucent), whose frame is the sum of the frames of
    each layer alone."""
    a = np.array(volvis.open(str(DATA / "neghip.slc")).array)
    v = make_napari_viewer()
    layers = [v.add_image(d, colormap=c, contrast_limits=(0, 255), rendering=rendering,
                          blending="additive", opacity=0.8)
              for d, c in ((a, "green"), (np.ascontiguousarray(a[:, :, ::-1]), "magenta"))]
    w = _widget_3d(v, (0, 20, 75), 128, reset_view=True)
    both = _final(qtbot, w, 0)
    volvis.save_png(both, str(out_dir / ("widget_additive_%s.png" % rendering)))
    both = both.astype(int)
    (o,) = w.frame["world"].objects
    assert o._c.n_channels == 2 and not w.frame["notes"], w.frame["notes"]
    alone = []
    for k in (0, 1):
        n = w.finals
        layers[k].visible = True
        layers[1 - k].visible = False
        qtbot.waitUntil(lambda: w.finals > n, timeout=45000)
        alone.append(w.image.astype(int))
        assert not w.frame["notes"]  # one layer over black: nothing to add to

    want = np.minimum(alone[0] + alone[1], 255)[..., :3]
    err = np.abs(both[..., :3] - want)
    assert err.max() <= 2, "additive %s: the sum differs by up to %d" % (rendering, err.max())
    assert (alone[0][..., 1] > 40).any() and (alone[1][..., 0] > 40).any()
    print("additive %s: sum within %d levels" % (rendering, err.max()))


def test_camera_mapping_against_napari_canvas(make_napari_viewer, qtbot, plugin, out_dir):
    """The widget's view of napari's camera against napari's own 3-D canvas
    (VisPy, OpenGL under Xvfb): MIP of neghip, several camera angles and a
    perspective one; the widget's frame at the canvas's size must look like
    the screenshot (the two sample differently: a loose bound), and better
    than its mirror image (the handedness) and than the previous angle's."""
    from volvis.napari._widget import VolVisWidget, viewer_camera
    v = make_napari_viewer(show=True)
    L = v.open(str(DATA / "neghip.slc"), plugin="volvis")[0]
    L.rendering = "mip"
    L.contrast_limits = (0, 255)
    L.interpolation3d = "linear"
    v.dims.ndisplay = 3
    w = VolVisWidget(v, max_side=4096, debounce_ms=10)
    cam = viewer_camera(v)
    prev = None
    for n, (angles, persp) in enumerate([((0, 0, 90), 0), ((0, 30, 90), 0),
                                         ((20, -40, 60), 0), ((15, 25, 80), 30)]):
        cam.angles = angles
        cam.perspective = persp
        shot = v.screenshot(canvas_only=True, flash=False)
        img = _final(qtbot, w, w.finals)
        if img.shape[:2] != shot.shape[:2]:
            pytest.skip("canvas %s vs frame %s: the canvas model's size lags the canvas"
                        % (shot.shape[:2], img.shape[:2]))
        volvis.save_png(np.ascontiguousarray(shot[..., :4]), str(out_dir / ("napari_%d.png" % n)))
        volvis.save_png(img, str(out_dir / ("widget_napari_%d.png" % n)))
        p = psnr(shot, img)
        pm = psnr(shot, img[:, ::-1])
        print("angles %s perspective %s: %.2f dB (mirrored %.2f dB)" % (angles, persp, p, pm))
        assert p >= 20, "widget vs napari's canvas at %s: %.2f dB" % (angles, p)
        assert p > pm + 3, "the mirror image fits napari's canvas as well (%.2f, %.2f dB)" % (p, pm)
        if prev is not None and prev.shape == img.shape:
            assert p > psnr(shot, prev) + 3
        prev = img


def test_widget_shadows(make_napari_viewer, qtbot, plugin, out_dir):
    v, L, w = _widget_of_file(make_napari_viewer, DATA / "ct_head.nrrd",  # in memory
                              (0, 30, 70), 192, rendering="iso", iso_threshold=300)
    plain = _final(qtbot, w, 0)
    w.shadows.setChecked(True)
    shadowed = _final(qtbot, w, w.finals)
    assert w.frame["renderer"] == "raytrace"
    volvis.save_png(plain, str(out_dir / "widget_iso.png"))
    volvis.save_png(shadowed, str(out_dir / "widget_iso_shadows.png"))
    assert psnr(plain, shadowed) < 35
    # the same silhouette: shadows darken the surface, they do not move it
    # (the ray tracer and the ray caster find the surface alike, to edge pixels)
    assert np.mean((plain[..., 3] > 0) != (shadowed[..., 3] > 0)) < 0.01
    # and it is what volvis render --renderer raytrace draws of the same World
    ref = _cli_render(w.frame, out_dir, "widget_iso_shadows", [DATA / "ct_head.nrrd"],
                      ("--renderer", "raytrace"))
    p = psnr(shadowed, ref)
    assert p >= 40, "shadows: widget vs volvis render --renderer raytrace: %.2f dB" % p


@pytest.fixture(scope="session")
def zarr_pyramid(out_dir):
    """A 256^3 u8 OME-Zarr pyramid (3 levels, volvis convert's 2x2x2 means)
    with detail at every scale: a 1-voxel lattice of bright points over
    smooth shells, so a coarse level is visibly not level 0."""
    n = 256
    z, y, x = np.ogrid[:n, :n, :n]
    r = np.sqrt((x - 127.5) ** 2 + (y - 127.5) ** 2 + (z - 127.5) ** 2)
    vol = (60 + 40 * np.cos(r / 6.0)).astype(np.float32) * (r < 120)
    vol[::4, ::4, ::4] = np.where(r[::4, ::4, ::4] < 120, 255, 0)
    src = out_dir / "lattice.nrrd"
    volvis.Volume(vol.astype(np.uint8), spacing=(0.5, 0.5, 0.5)).save(str(src))
    out = out_dir / "lattice.ome.zarr"
    subprocess.run([cli(), "convert", "-q", str(src), str(out)], check=True)
    return out


def test_widget_level_of_detail(make_napari_viewer, qtbot, plugin, zarr_pyramid, out_dir):
    """napari's own 3-D view of a multiscale layer draws its coarsest level
    only; the widget draws level 0 where the view needs it (zoomed in) and
    coarse levels where it does not (zoomed out), and equals volvis render
    --lod 1 of the same World and view."""
    from volvis.napari._widget import viewer_camera
    v, L, w = _widget_of_file(make_napari_viewer, zarr_pyramid, (0, 25, 80), 256,
                              rendering="translucent", colormap="viridis",
                              contrast_limits=(90, 255))
    assert L.multiscale and [d.shape for d in L.data] == [(256,) * 3, (128,) * 3, (64,) * 3]
    np.testing.assert_allclose(L.scale, (0.5, 0.5, 0.5))
    cam = viewer_camera(v)
    base_zoom = cam.zoom
    cam.zoom = base_zoom / 4
    far = _final(qtbot, w, w.finals)
    nodes_far = list(w.frame["lod"]["nodes"])
    w.follow.setChecked(False)  # one request for the near view: level 0 cold
    qtbot.wait(100)
    cam.zoom = base_zoom * 3
    near = _final(qtbot, w, w.finals)
    f = dict(w.frame)
    # progressive: a quarter-size frame first, then full-size frames from
    # what is resident while level 0's chunks load (some pending), the
    # final frame last with none pending
    kinds = [p[1] for p in w.passes]
    assert kinds[0] == "coarse" and kinds[-1] == "final", w.passes
    assert any(p[2] > 0 for p in w.passes[:-1]) and w.passes[-1][2] == 0, w.passes
    nodes_near = list(f["lod"]["nodes"])
    volvis.save_png(far, str(out_dir / "widget_lod_far.png"))
    volvis.save_png(near, str(out_dir / "widget_lod_near.png"))
    print("nodes per level: zoomed out %s, zoomed in %s" % (nodes_far, nodes_near))
    assert nodes_far[0] == 0 and sum(nodes_far[1:]) > 0, nodes_far
    assert nodes_near[0] > 0, nodes_near
    ref = _cli_render(f, out_dir, "widget_lod_near", [zarr_pyramid])
    p = psnr(near, ref)
    assert p >= 40, "LOD frame vs volvis render --lod 1: %.2f dB" % p


@pytest.fixture(scope="session")
def dicom_folder(out_dir):
    """A CT series written by pydicom (an independent writer): 12 slices of
    40x48 u16, one file a slice, 0.8 mm pixels, 2.5 mm apart; the folder's
    name says nothing of DICOM."""
    pydicom = pytest.importorskip("pydicom")
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
    folder = out_dir / "ct_series"
    folder.mkdir(exist_ok=True)
    for f in folder.iterdir():
        f.unlink()
    rng = np.random.default_rng(3)
    zyx = rng.integers(0, 4000, size=(12, 40, 48)).astype(np.uint16)
    ct = "1.2.840.10008.5.1.4.1.1.2"
    series, study, frame = generate_uid(), generate_uid(), generate_uid()
    for z in rng.permutation(12):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = ct
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        path = folder / ("slice%02d" % z)
        ds = FileDataset(str(path), {}, file_meta=meta, preamble=b"\0" * 128)
        ds.SOPClassUID, ds.SOPInstanceUID = ct, meta.MediaStorageSOPInstanceUID
        ds.StudyInstanceUID, ds.SeriesInstanceUID = study, series
        ds.FrameOfReferenceUID, ds.Modality, ds.SeriesNumber = frame, "CT", 2
        ds.InstanceNumber = int(z) + 1
        ds.ImageOrientationPatient = ["1", "0", "0", "0", "1", "0"]
        ds.ImagePositionPatient = ["-20", "-16", "%.1f" % (10 + 2.5 * z)]
        ds.PixelSpacing = ["0.8", "0.8"]
        ds.SliceThickness = "2.5"
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.Rows, ds.Columns = 40, 48
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
        ds.PixelData = zyx[z].tobytes()
        ds.save_as(str(path), enforce_file_format=True)
    return folder, zyx


def test_open_dicom_folder(make_napari_viewer, plugin, dicom_folder):
    folder, zyx = dicom_folder
    v = make_napari_viewer()
    L = v.open(str(folder), plugin="volvis")[0]
    assert L.data.shape == zyx.shape
    np.testing.assert_allclose(L.scale, (2.5, 0.8, 0.8), rtol=1e-5)
    vol = volvis.open(folder)
    np.testing.assert_allclose(L.translate, vol.origin[::-1])
    np.testing.assert_array_equal(np.asarray(L.data), vol.array)
    np.testing.assert_array_equal(np.asarray(L.data), zyx)  # the voxels pydicom wrote


def test_open_ome_zarr_channels(make_napari_viewer, plugin, out_dir):
    """Two channels of an OME-Zarr 0.4 store written by ngff-zarr (an
    independent writer) with omero names and colours: one lazy multiscale
    layer each, named and coloured by the file, with its scale and
    translation."""
    nz = pytest.importorskip("ngff_zarr")
    rng = np.random.default_rng(1)
    a = rng.integers(0, 1000, size=(2, 32, 40, 48)).astype(np.uint16)
    img = nz.to_ngff_image(a, dims=["c", "z", "y", "x"], scale={"z": 2.0, "y": 0.5, "x": 0.5},
                           translation={"z": 1.0, "y": 2.0, "x": 3.0})
    ms = nz.to_multiscales(img, scale_factors=[2])
    ms.metadata.omero = nz.Omero(channels=[
        nz.OmeroChannel(color="FF0000", window=nz.OmeroWindow(min=0, max=1000, start=10, end=900),
                        label="DAPI"),
        nz.OmeroChannel(color="00FF00", window=nz.OmeroWindow(min=0, max=1000, start=20, end=800),
                        label="GFP")])
    store = out_dir / "channels.ome.zarr"
    nz.to_ngff_zarr(str(store), ms, version="0.4")
    v = make_napari_viewer()
    layers = v.open(str(store), plugin="volvis")
    assert [L.name for L in layers] == ["DAPI", "GFP"]
    for c, (L, rgb) in enumerate(zip(layers, [(1, 0, 0), (0, 1, 0)])):
        assert L.multiscale and len(L.data) == 2
        assert L.data[0].shape == (32, 40, 48)
        np.testing.assert_allclose(L.scale, (2, 0.5, 0.5))
        np.testing.assert_allclose(L.translate, (1, 2, 3))
        np.testing.assert_array_equal(np.asarray(L.data[0]), a[c])
        np.testing.assert_allclose(L.colormap.map(np.array([1.0]))[0][:3], rgb, atol=1e-6)
        np.testing.assert_allclose(L.colormap.map(np.array([0.0]))[0][:3], (0, 0, 0), atol=1e-6)
        assert L.blending == "additive"


def test_widget_closed_stops_following(make_napari_viewer, qtbot, plugin):
    from volvis.napari._widget import VolVisWidget, viewer_camera
    v = make_napari_viewer()
    v.open(str(DATA / "neghip.slc"), plugin="volvis")
    v.dims.ndisplay = 3
    w = VolVisWidget(v, max_side=64, debounce_ms=10)
    _final(qtbot, w, 0)
    w.close()
    n = w.frames
    viewer_camera(v).angles = (0, 40, 90)
    qtbot.wait(300)
    assert w.frames == n


def test_reader_declines_and_fails_cleanly(make_napari_viewer, plugin, out_dir):
    from volvis.napari._reader import get_reader, read
    other = out_dir / "other.xml"
    other.write_text("<?xml version='1.0'?><svg/>")
    assert get_reader(str(other)) is None  # not BigDataViewer's: left to others
    assert get_reader(str(out_dir / "x.png")) is None
    bad = out_dir / "bad.nrrd"
    bad.write_bytes(b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4\n\n")
    with pytest.raises(volvis.Error) as e:
        read(str(bad))
    msg = str(e.value)
    assert "bad.nrrd" in msg and "\n" not in msg.strip(), msg


@pytest.fixture(scope="session")
def hdf5_files(out_dir):
    """A BigDataViewer HDF5 file (two setups) and an Imaris file, 3 levels
    each, written by h5py (Debian's python3, tests/napari/make_hdf5.py)."""
    d = out_dir / "hdf5"
    d.mkdir(exist_ok=True)
    r = subprocess.run(["/usr/bin/python3", str(pathlib.Path(__file__).parent / "make_hdf5.py"),
                        str(d)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip("h5py (python3-h5py) could not write the files: " + r.stderr.strip()[-300:])
    return d


def test_open_bigdataviewer_and_imaris(make_napari_viewer, plugin, hdf5_files):
    from volvis.napari._reader import level_array
    v = make_napari_viewer()
    layers = v.open(str(hdf5_files / "bdv.h5"), plugin="volvis")
    assert len(layers) == 2  # one a setup
    for s, L in enumerate(layers):
        assert L.multiscale and len(L.data) == 3
        assert level_array(L.data[0]) is not None
        for k in range(3):
            np.testing.assert_array_equal(np.asarray(L.data[k]),
                                          np.load(hdf5_files / ("bdv_s%d_l%d.npy" % (s, k))))
    L = v.open(str(hdf5_files / "cells.ims"), plugin="volvis")[0]
    assert L.multiscale and [d.shape for d in L.data] == [(36, 44, 52), (18, 22, 26), (9, 11, 13)]
    np.testing.assert_allclose(L.scale, (2.0, 0.5, 0.25), rtol=1e-5)
    for k in range(3):  # Imaris's padding to 32 cut off
        np.testing.assert_array_equal(np.asarray(L.data[k]), np.load(hdf5_files / ("ims_l%d.npy" % k)))


@pytest.mark.parametrize("rendering,mode", [("translucent", "composite"), ("mip", "mip"),
                                            ("minip", "minip"), ("average", "xray"),
                                            ("iso", "iso"),
                                            ("attenuated_mip", "attenuated-mip")])
def test_layer_transfer_function(make_napari_viewer, rendering, mode):
    """The layer's colormap, contrast limits, gamma and opacity as the
    transfer function evaluates them (vv_tf_eval_*), at data values between
    the points of its table and outside the limits."""
    from volvis.napari._widget import layer_object
    v = make_napari_viewer()
    L = v.add_image(np.zeros((4, 5, 6), np.uint16), colormap="magma", contrast_limits=(100, 900),
                    gamma=0.6, opacity=0.7, rendering=rendering, iso_threshold=500)
    obj, pyr, note = layer_object(L)
    assert pyr is None and obj.mode == mode and not note
    if mode == "attenuated-mip":
        assert obj.attenuation == pytest.approx(L.attenuation) and obj.step == 0.8
    pts = (obj.tf.color[:, 0] - 100) / 800
    assert len(pts) == len(obj.tf.opacity) <= 130
    t = 0.5 * (pts[1:] + pts[:-1])  # midway between the table's points
    values = 100 + 800 * t
    got = obj.tf(values)
    want = L.colormap.map(t ** 0.6)[:, :3]
    # linear between the points: within the curvature of colormap(t^gamma)
    assert np.max(np.abs(got[:, :3] - want)) < 0.01
    want_a = 0.7 * t ** 0.6 if mode == "composite" else np.full_like(t, 0.7)
    assert np.max(np.abs(got[:, 3] - want_a)) < 0.01
    below, above = obj.tf([0, 5000])
    np.testing.assert_allclose(below[:3], L.colormap.map(np.array([0.0]))[0][:3], atol=1e-6)
    np.testing.assert_allclose(above[:3], L.colormap.map(np.array([1.0]))[0][:3], atol=1e-6)
    if mode == "iso":
        assert obj.isovalue == 500
        np.testing.assert_allclose(obj.material.color,
                                   L.colormap.map(np.array([0.5 ** 0.6]))[0][:3], atol=1e-6)


def test_widget_two_layers_and_visibility(make_napari_viewer, qtbot, plugin, out_dir):
    """Two visible layers are two objects of one World (MIP in green and
    magenta, combined by the maximum); hiding one re-renders (the widget
    follows the layers' events) and matches volvis render again."""
    v = make_napari_viewer()
    a = v.open(str(DATA / "neghip.slc"), plugin="volvis")[0]
    b = v.open(str(DATA / "ironProt.vtk"), plugin="volvis")[0]
    for L, cmap in ((a, "green"), (b, "magenta")):
        L.rendering = "mip"
        L.colormap = cmap
        L.contrast_limits = (0, 255)
    b.translate = (0, 0, 80)
    w = _widget_3d(v, (0, 20, 75), 192, reset_view=True)
    both = _final(qtbot, w, 0)
    f = dict(w.frame)
    assert len(f["world"].objects) == 2
    ref = _cli_render(f, out_dir, "two_layers", [DATA / "neghip.slc", DATA / "ironProt.vtk"],
                      options=())
    assert psnr(both, ref) >= 40
    g, m = both[..., 1].astype(int), both[..., 0].astype(int)
    assert (g > m + 50).any() and (m > g + 50).any(), "both layers' colours"
    n = w.finals
    b.visible = False
    qtbot.waitUntil(lambda: w.finals > n, timeout=45000)
    one = w.image.copy()
    f = dict(w.frame)
    assert len(f["world"].objects) == 1
    assert psnr(both, one) < 30
    assert not (one[..., 0].astype(int) > one[..., 1].astype(int) + 50).any()  # no magenta
    ref = _cli_render(f, out_dir, "one_layer", [DATA / "neghip.slc"], options=())
    assert psnr(one, ref) >= 40
    volvis.save_png(both, str(out_dir / "widget_two_layers.png"))
    volvis.save_png(one, str(out_dir / "widget_one_layer.png"))


def _channels_store(path):
    """A 3-channel OME-Zarr 0.5 pyramid written by zarr-python 3 (c, z, y, x; 3 levels;
    shards of 32^3 of inner chunks of one channel x 16^3, zstd), a blob a channel at its
    own place, omero names, colours and windows."""
    import zarr
    from zarr.codecs import ZstdCodec
    zz, yy, xx = np.mgrid[0:64, 0:80, 0:96].astype(np.float32)
    chans = []
    for cz, cy, cx, r2 in ((20, 30, 30, 150), (40, 50, 60, 250), (32, 40, 76, 350)):
        b = 3000 * np.exp(-((zz - cz) ** 2 + (yy - cy) ** 2 + (xx - cx) ** 2) / r2)
        chans.append(b.astype(np.uint16) + 60)
    lv = np.stack(chans)
    g = zarr.open_group(str(path), mode="w")
    ds = []
    for k in range(3):
        a = g.create_array(str(k), shape=lv.shape, dtype=lv.dtype, chunks=(1, 16, 16, 16),
                           shards=(1, 32, 32, 32), compressors=ZstdCodec(level=3))
        a[:] = lv
        f = 2.0 ** k
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [1.0, f, f, f]},
            {"type": "translation", "translation": [0.0] + [(f - 1) / 2] * 3}]})
        s = [d // 2 * 2 for d in lv.shape[1:]]
        lv = np.rint(lv[:, :s[0], :s[1], :s[2]].astype(np.float64).reshape(
            3, s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(2, 4, 6))).astype(np.uint16)
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
        {"name": "c", "type": "channel"}] + [{"name": a, "type": "space"} for a in "zyx"],
        "datasets": ds}], "omero": {"channels": [
            {"label": n, "color": c, "window": {"min": 0, "max": 4000, "start": 100,
                                                 "end": 2500}}
            for n, c in (("nuclei", "FF0000"), ("actin", "00FF00"), ("dna", "0000FF"))]}}
    return path


def test_widget_channels_out_of_core(make_napari_viewer, qtbot, plugin, out_dir):
    """A 3-channel store opened by the VolVis reader (one layer a channel, as
    napari's channel_axis makes them: additive, coloured by the file), read out
    of core as the reader reads a pyramid: the layers share one pyramid whose
    chunks hold every channel; the dock widget draws them as one object in one
    pass out of core at full resolution (level 0 nodes, none pending), the
    status line naming no blending, equal (>= 50 dB) to `volvis render` of the
    same World and view under the same limit; hiding a layer hides its channel
    from the frame and reads no chunk again."""
    store = _channels_store(out_dir / "channels_ooc.ome.zarr")
    limit = "%dM" % (volvis.memory_limit() >> 20)  # the process's (the reader reads out of core)
    v = make_napari_viewer()
    layers = v.open(str(store), plugin="volvis")
    assert [x.name for x in layers] == ["nuclei", "actin", "dna"]
    pyrs = {id(x.data[0].volvis_level.pyramid) for x in layers}
    assert len(pyrs) == 1, "the channels' layers read one pyramid"
    assert all(x.blending == "additive" for x in layers)
    assert all(x.metadata["volvis"]["out_of_core"] for x in layers)
    w = _widget_3d(v, (0, 20, 70), 256, reset_view=True)
    img = _final(qtbot, w, w.finals)
    f = dict(w.frame)
    objs = f["world"].objects
    assert len(objs) == 1 and objs[0]._c.n_channels == 3, "one object of the 3 channels"
    assert objs[0]._c.source != volvis._volvis.ffi.NULL, "drawn out of core"
    assert f["lod"]["nodes"][0] > 0 and f["lod"]["pending"] == 0, f["lod"]
    assert "blending" not in w.status.text(), w.status.text()
    volvis.save_png(img, str(out_dir / "widget_channels_ooc.png"))
    ref = _cli_render(f, out_dir, "widget_channels_ooc", [store],
                      ("--memory-limit", limit, "--lod", "1"))
    p = psnr(img, ref)
    print("3 channels out of core: widget vs volvis render %.1f dB" % p)
    assert p >= 50, "widget vs volvis render of the channels: %.2f dB" % p
    # hide "actin" (green): its colour leaves the frame, no chunk read again
    pyr = layers[0].data[0].volvis_level.pyramid
    reads = sum(pyr.stats["chunk_reads"])
    layers[1].visible = False
    hidden = _final(qtbot, w, w.finals)
    green = lambda a: float(a[..., 1].astype(np.float64).sum())  # noqa: E731
    assert green(hidden) < 0.5 * green(img), (green(hidden), green(img))
    assert sum(pyr.stats["chunk_reads"]) == reads, "hiding a channel read chunks again"
