#!/usr/bin/python3
"""Seeds of the structure-aware harnesses, from files independent tools write.

  tests/fuzz/make_corpus_structured.py        (from the repository root)

- tests/fuzz/corpus/zarr/: OME-Zarr stores and plain Zarr v2 arrays written
  by zarr-python (its .zarray and chunk files: raw, zlib, gzip, zstd, blosc
  with shuffles, "." and "/" separators, either byte order, fill values and
  missing chunks; the .zattrs multiscales, axes, coordinateTransformations
  and omero written after the OME-NGFF 0.4 / 0.3 specification), in the
  container of fuzz_zarr.c: "--FILE <name>--" sections.
- tests/fuzz/corpus/bdv/: BigDataViewer HDF5 files (t00000/s00/<level>/cells,
  resolutions, subdivisions) and Imaris ones (DataSet/ResolutionLevel N,
  DataSetInfo/Image's attributes as arrays of one-byte strings) written by
  h5py, each turned into fuzz_bdv.c's description (its groups, datasets,
  chunks, filters, attributes and values as h5py reads them back), after the
  dataset XML as Fiji's BigDataViewer export writes it (or none: the HDF5
  pyramid alone).
- tests/fuzz/corpus/tiff/tifffile-*: the ImageDescription that tifffile
  writes into OME-TIFF files (OME-XML with channels, time points, physical
  sizes and their units) and ImageJ hyperstacks (images, channels, slices,
  frames, spacing, unit): fuzz_tiff's input is that text.

The arrays are small crops of ../shared/data/volumes/HeadMRVolume.raw (a
real MR head, 48 x 62 x 42 u8) and ramps, so every seed is a few hundred
bytes to a few KB. Needs python3-zarr, python3-numcodecs, python3-h5py
and python3-tifffile (scripts/install-deps.sh test). Writes only the files it names (the crash-*
regression inputs stay).
"""
import json
import os
import shutil
import sys
import tempfile

import h5py
import numcodecs
import numpy as np
import tifffile
import zarr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corpus_common import head_crop, pack_store  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus")


# ---- OME-Zarr -------------------------------------------------------------------------------


def axes04(names, units="micrometer"):
    kinds = {"t": "time", "c": "channel"}
    out = []
    for n in names:
        a = {"name": n, "type": kinds.get(n, "space")}
        if n in "zyx":
            a["unit"] = units
        elif n == "t":
            a["unit"] = "second"
        out.append(a)
    return out


def write_zarr(name, levels, axes=None, version="0.4", omero=None, prelude=None, extra=None,
               dim_sep=None, top_transform=False):
    """One store: levels[i] = (array, chunks, compressor, dtype, fill); the
    multiscales metadata when @p axes (names) is given, else a plain array."""
    tmp = tempfile.mkdtemp()
    try:
        root = os.path.join(tmp, "s.zarr")
        plain = axes is None
        g = None if plain else zarr.open_group(root, mode="w")
        datasets = []
        for i, (a, chunks, comp, dtype, fill) in enumerate(levels):
            kw = dict(shape=a.shape, chunks=chunks, dtype=dtype, compressor=comp,
                      fill_value=fill)
            if dim_sep:
                kw["dimension_separator"] = dim_sep
            z = zarr.open_array(root, mode="w", **kw) if plain else g.create_dataset(str(i), **kw)
            z[...] = a.astype(dtype)
            if not plain:
                f = 2 ** i
                sc = [1.0] * (len(a.shape) - 3) + [2.0 * f, 0.5 * f, 0.5 * f]
                ds = {"path": str(i),
                      "coordinateTransformations": [{"type": "scale", "scale": sc}]}
                if i == 0:
                    ds["coordinateTransformations"].append(
                        {"type": "translation", "translation": [0.0] * (len(a.shape) - 3)
                         + [10.0, 20.0, 30.0]})
                datasets.append(ds)
        if not plain:
            ms = {"version": version, "name": name, "datasets": datasets}
            if version == "0.4":
                ms["axes"] = axes04(axes)
            elif version == "0.3":
                ms["axes"] = list(axes)
                for d in datasets:
                    d.pop("coordinateTransformations")
            if top_transform:
                ms["coordinateTransformations"] = [
                    {"type": "scale", "scale": [1.0] * len(axes)}]
            attrs = {"multiscales": [ms]}
            if omero:
                attrs["omero"] = omero
            if extra:
                attrs.update(extra)
            with open(os.path.join(root, ".zattrs"), "w") as f:
                json.dump(attrs, f)
        data = pack_store(root, prelude or f"# zarr-python {zarr.__version__}: {name}\n")
    finally:
        shutil.rmtree(tmp)
    out = os.path.join(CORPUS, "zarr", name)
    with open(out, "wb") as f:
        f.write(data)
    return len(data)


def zarr_seeds():
    os.makedirs(os.path.join(CORPUS, "zarr"), exist_ok=True)
    h = head_crop()
    half = h[::2, ::2, ::2]
    blosc = numcodecs.Blosc(cname="lz4", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE)
    bit = numcodecs.Blosc(cname="zstd", clevel=3, shuffle=numcodecs.Blosc.BITSHUFFLE)
    omero = {"channels": [{"label": "MR", "color": "FF8000", "window": {"min": 0, "max": 255}},
                          {"label": "ramp", "color": "00FF00",
                           "window": {"min": 0, "max": 10}}]}
    n = []
    n.append(write_zarr("plain_raw", [(h, (2, 5, 6), None, "|u1", 0)]))
    n.append(write_zarr("plain_zlib_i2be", [(h, (2, 3, 4), numcodecs.Zlib(level=6), ">i2", 7)]))
    n.append(write_zarr("plain_slash_gzip",
                        [(h, (4, 5, 3), numcodecs.GZip(level=6), "<u2", 0)], dim_sep="/"))
    n.append(write_zarr("ome04_two_levels_blosc",
                        [(h, (2, 3, 6), blosc, "<u2", 0), (half, (2, 3, 3), blosc, "<u2", 0)],
                        axes="zyx", omero=omero))
    n.append(write_zarr("ome04_zstd_f4",
                        [(h.astype(np.float32) / 3, (4, 5, 6), numcodecs.Zstd(level=3), "<f4",
                          "NaN")], axes="zyx", top_transform=True))
    c2 = np.stack([h, 255 - h])
    n.append(write_zarr("ome04_czyx_bitshuffle", [(c2, (1, 2, 5, 6), bit, "<i4", 0)],
                        axes="czyx", omero=omero, prelude="0 1 0\n"))
    t2 = np.stack([c2[:1], c2[1:]])
    n.append(write_zarr("ome04_tczyx_u1", [(t2, (1, 1, 4, 5, 6), None, "|u1", 3)],
                        axes="tczyx", prelude="0 0 1\n"))
    n.append(write_zarr("ome03_axes_names_f8", [(h, (4, 5, 6), numcodecs.Zlib(), "<f8", 0)],
                        axes="zyx", version="0.3"))
    n.append(write_zarr("ome02_no_axes_5d", [(t2, (1, 1, 2, 5, 6), None, "|u1", 0)],
                        axes="tczyx", version="0.2"))
    n.append(write_zarr("ome04_2d_yx_i1", [(h[0], (5, 3), None, "|i1", -1)], axes="yx"))
    # missing chunks: a 4x5x6 store of 2^3 chunks with only the first written
    tmp = tempfile.mkdtemp()
    try:
        root = os.path.join(tmp, "m.zarr")
        z = zarr.open_array(root, mode="w", shape=(4, 5, 6), chunks=(2, 2, 2), dtype="<u2",
                            compressor=None, fill_value=513)
        z[0:2, 0:2, 0:2] = h[0:2, 0:2, 0:2]
        data = pack_store(root, "# zarr-python: one chunk written, the rest fill_value\n")
        with open(os.path.join(CORPUS, "zarr", "plain_missing_chunks"), "wb") as f:
            f.write(data)
        n.append(len(data))
    finally:
        shutil.rmtree(tmp)
    print(f"zarr: {len(n)} seeds, {min(n)} .. {max(n)} bytes")


# ---- BigDataViewer / Imaris HDF5 ------------------------------------------------------------

TYPES = {"u1": "u8", "i1": "i8", "u2": "u16", "i2": "i16", "u4": "u32", "i4": "i32",
         "u8": "u64", "i8": "i64", "f4": "f32", "f8": "f64"}


def quote(s):
    return f'"{s}"' if " " in s else s


def num(v):
    return f"{v:.17g}" if isinstance(v, float) else str(v)


def type_name(dt):
    k = dt.kind + str(dt.itemsize)
    t = TYPES.get(k)
    if t is None:
        return None
    return (">" if dt.byteorder == ">" else "") + t


def describe_attrs(path, obj, out):
    for name, v in obj.attrs.items():
        if isinstance(v, np.ndarray) and v.dtype.kind == "S" and v.dtype.itemsize == 1:
            out.append(f"a {quote(path)} {quote(name)} chars {quote(b''.join(v).decode())}")
        elif isinstance(v, (bytes, str)):
            s = v.decode() if isinstance(v, bytes) else v
            out.append(f"a {quote(path)} {quote(name)} str {quote(s)}")
        else:
            a = np.atleast_1d(np.asarray(v))
            t = type_name(a.dtype)
            if t:
                out.append(f"a {quote(path)} {quote(name)} {t} "
                           + " ".join(num(x) for x in a.ravel().tolist()))


def describe_h5(path, options=None):
    """fuzz_bdv.c's description of the HDF5 file at @p path, as h5py reads it."""
    out = [f"# h5py {h5py.__version__}: {os.path.basename(path)}"]
    if options:
        out.append("o " + options)
    with h5py.File(path, "r") as f:
        describe_attrs("/", f, out)

        def visit(name, obj):
            if isinstance(obj, h5py.Group):
                out.append(f"g {quote(name)}")
            else:
                t = type_name(obj.dtype)
                if t is None:
                    return
                dims = ",".join(str(n) for n in obj.shape)
                ch = ",".join(str(n) for n in obj.chunks) if obj.chunks else "-"
                if obj.compression == "gzip":
                    ch += "+z"
                vals = obj[()].ravel().tolist()
                vals = vals if len(vals) <= 512 else vals[:64]
                out.append(f"d {quote(name)} {t} {dims} {ch} " + " ".join(num(v) for v in vals))
            describe_attrs(name, obj, out)

        f.visititems(visit)
    return "\n".join(out) + "\n"


def bdv_xml(h5name="in.h5", setups=("DAPI", "GFP"), shape=(4, 5, 6), timepoints="range",
            affines=True):
    vs = "".join(f"""      <ViewSetup>
        <id>{s}</id>
        <name>{n}</name>
        <size>{shape[2]} {shape[1]} {shape[0]}</size>
        <voxelSize>
          <unit>µm</unit>
          <size>0.5 0.5 2.0</size>
        </voxelSize>
      </ViewSetup>
""" for s, n in enumerate(setups))
    tp = {"range": "<Timepoints type=\"range\">\n      <first>0</first>\n      <last>0</last>\n"
                   "    </Timepoints>",
          "pattern": "<Timepoints type=\"pattern\">\n      <integerpattern>0</integerpattern>\n"
                     "    </Timepoints>",
          "list": "<Timepoints type=\"list\">\n      <Timepoint><id>0</id></Timepoint>\n"
                  "    </Timepoints>"}[timepoints]
    regs = ""
    if affines:
        regs = "".join(f"""    <ViewRegistration timepoint="0" setup="{s}">
      <ViewTransform type="affine">
        <Name>Translation</Name>
        <affine>1.0 0.0 0.0 10.0 0.0 1.0 0.0 20.0 0.0 0.0 1.0 30.0</affine>
      </ViewTransform>
      <ViewTransform type="affine">
        <Name>calibration</Name>
        <affine>0.5 0.0 0.0 0.0 0.0 0.5 0.0 0.0 0.0 0.0 2.0 0.0</affine>
      </ViewTransform>
    </ViewRegistration>
""" for s in range(len(setups)))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<SpimData version="0.2">
  <BasePath type="relative">.</BasePath>
  <SequenceDescription>
    <ImageLoader format="bdv.hdf5">
      <hdf5 type="relative">{h5name}</hdf5>
    </ImageLoader>
    <ViewSetups>
{vs}    </ViewSetups>
    {tp}
  </SequenceDescription>
  <ViewRegistrations>
{regs}  </ViewRegistrations>
</SpimData>
"""


def write_bdv_h5(path, setups=2, levels=2, dtype=np.int16, chunks=(2, 2, 4), gzip=True):
    h = head_crop()
    with h5py.File(path, "w") as f:
        for s in range(setups):
            f[f"s{s:02d}/resolutions"] = np.array([[2.0 ** k] * 3 for k in range(levels)])
            f[f"s{s:02d}/subdivisions"] = np.array([[8, 8, 8]] * levels, dtype=np.int32)
            a = h.astype(np.int64) * (s + 1) * 100
            for k in range(levels):
                lv = a[::2 ** k, ::2 ** k, ::2 ** k]
                f.create_dataset(f"t00000/s{s:02d}/{k}/cells", data=lv.astype(dtype),
                                 chunks=tuple(min(c, n) for c, n in zip(chunks, lv.shape)),
                                 compression="gzip" if gzip else None)


def write_imaris(path):
    h = head_crop(4, 6, 8)

    def chars(s):
        return np.array(list(str(s)), dtype="S1")

    with h5py.File(path, "w") as f:
        img = f.create_group("DataSetInfo/Image")
        img.attrs["Unit"] = chars("um")
        for k, n in enumerate((8, 6, 4)):
            img.attrs[f"ExtMin{k}"] = chars("0")
            img.attrs[f"ExtMax{k}"] = chars(f"{n * 0.5:.3f}")
        for k in range(2):
            a = h[::2 ** k, ::2 ** k, ::2 ** k]
            g = f.create_group(f"DataSet/ResolutionLevel {k}/TimePoint 0/Channel 0")
            pad = np.zeros(tuple(n + 1 for n in a.shape), dtype=np.uint8)
            pad[:a.shape[0], :a.shape[1], :a.shape[2]] = a
            g.create_dataset("Data", data=pad, chunks=(2, 2, 2), compression="gzip")
            for name, n in zip(("ImageSizeX", "ImageSizeY", "ImageSizeZ"), a.shape[::-1]):
                g.attrs[name] = chars(n)
            g.attrs["HistogramMin"] = chars(f"{a.min():.3f}")
            g.attrs["HistogramMax"] = chars(f"{a.max():.3f}")


def bdv_seeds():
    os.makedirs(os.path.join(CORPUS, "bdv"), exist_ok=True)
    tmp = tempfile.mkdtemp()
    sizes = []

    def put(name, xml, h5, options=None):
        data = (xml + "\n--H5--\n" if xml else "--H5--\n") + describe_h5(h5, options)
        with open(os.path.join(CORPUS, "bdv", name), "w", encoding="utf-8") as f:
            f.write(data)
        sizes.append(len(data.encode()))

    try:
        p = os.path.join(tmp, "in.h5")
        write_bdv_h5(p)
        put("xml_two_setups_gzip", bdv_xml(), p)
        put("xml_pattern_channel1", bdv_xml(timepoints="pattern"), p, "0 1 0")
        put("xml_list_level1", bdv_xml(timepoints="list", affines=False), p, "1 0 0")
        put("h5_alone_bdv", "", p)
        write_bdv_h5(p, setups=1, levels=3, dtype=np.uint8, chunks=(4, 5, 6), gzip=False)
        put("xml_one_setup_u8_contiguous", bdv_xml(setups=("one",)), p)
        write_bdv_h5(p, setups=1, levels=1, dtype=np.float32, chunks=(1, 5, 6))
        put("h5_alone_f32", "", p)
        write_imaris(p)
        put("h5_imaris", "", p)
    finally:
        shutil.rmtree(tmp)
    print(f"bdv: {len(sizes)} seeds, {min(sizes)} .. {max(sizes)} bytes")


def tiff_seeds():
    """The descriptions tifffile writes, read back from its files."""
    os.makedirs(os.path.join(CORPUS, "tiff"), exist_ok=True)
    tmp = tempfile.mkdtemp()
    n = 0
    try:
        p = os.path.join(tmp, "t.tif")
        cases = [
            ("ome_zyx", dict(ome=True, metadata={"axes": "ZYX", "PhysicalSizeX": 0.5,
                                                 "PhysicalSizeXUnit": "µm", "PhysicalSizeY": 0.5,
                                                 "PhysicalSizeZ": 2.0}), (3, 4, 5), np.uint16),
            ("ome_tczyx", dict(ome=True, metadata={"axes": "TCZYX", "Channel": {"Name": ["DAPI", "GFP"]},
                                                   "PhysicalSizeZ": 1.5, "PhysicalSizeZUnit": "nm",
                                                   "TimeIncrement": 2.0}), (2, 2, 3, 4, 5), np.uint8),
            ("imagej_zcyx", dict(imagej=True, resolution=(2.0, 2.0),
                                 metadata={"axes": "ZCYX", "spacing": 3.5, "unit": "um"}),
             (3, 2, 4, 5), np.uint16),
            ("imagej_tzyx", dict(imagej=True, metadata={"axes": "TZYX", "finterval": 0.5}),
             (2, 3, 4, 5), np.float32),
        ]
        for name, kw, shape, dtype in cases:
            tifffile.imwrite(p, np.arange(np.prod(shape), dtype=dtype).reshape(shape), **kw)
            with tifffile.TiffFile(p) as t:
                desc = t.pages[0].description
            with open(os.path.join(CORPUS, "tiff", "tifffile-" + name), "w", encoding="utf-8") as f:
                f.write(desc)
            n += 1
    finally:
        shutil.rmtree(tmp)
    print(f"tiff: {n} descriptions written by tifffile {tifffile.__version__}")


if __name__ == "__main__":
    zarr_seeds()
    bdv_seeds()
    tiff_seeds()
    sys.exit(0)
