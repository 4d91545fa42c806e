#!/usr/bin/env python3
"""OME-Zarr label images and HCS plates written by ome-zarr-py, read by VolVis.

  zarr_labels_plate_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test). For
OME-NGFF 0.4 (Zarr v2) and 0.5 (Zarr v3), ome-zarr-py writes:

- an image (z, y, x, u16, a pyramid) with a label image "cells" (u8, its
  image-label colours and properties): `volvis info IMAGE` lists the label
  image (name, dims, type, colours) and how to open it; `volvis info
  IMAGE/labels/cells` says it is a label image; its voxels read back equal;
  `volvis render IMAGE/labels/cells` renders it as a label volume (the same
  image as with --labels, not the transfer function's);
- an HCS plate of 2 x 3 wells, 2 fields each: `volvis info PLATE` lists rows,
  columns, wells and fields and the path of the first field; a field
  (PLATE/B/2/1) reads back voxel for voxel and renders; `volvis render PLATE`
  (and a well, and a labels group) is refused in one line naming the field
  path to open;
- hostile plates and label groups: a well path "../x", "/etc", "A/../../x", a
  field path "..", a label name "../s0", too many wells (4097), too many
  labels (257), a well folder that is a link out of the store: refused by
  `volvis info` and `volvis render` in one line naming the file and field.
"""
import json
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import zarr
    from ome_zarr.format import FormatV04, FormatV05
    from ome_zarr.io import parse_url
    from ome_zarr.writer import (write_image, write_labels, write_plate_metadata,
                                 write_well_metadata)
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Checks, run  # noqa: E402
from cli_common import read_nrrd as read_voxels_spacing_origin  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
check = Checks()
failures = check.failures


def volvis(*args):
    return run(VOLVIS, *args)


def read_nrrd(path):
    return read_voxels_spacing_origin(path)[0]


def read_back(store):
    out = os.path.join(OUT, "back.nrrd")
    if os.path.exists(out):
        os.remove(out)
    p = volvis("convert", store, out, "--quiet")
    if p.returncode != 0:
        check(False, f"convert {store}: {p.stderr.strip()}")
        return None
    return read_nrrd(out)


def same(got, want):
    return got is not None and got.shape == want.shape and bool(np.array_equal(got, want))


def refused(args, needles, what):
    p = volvis(*args)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    ok = p.returncode != 0 and len(lines) == 1 and all(n in lines[0] for n in needles)
    check(ok, f"{what}: {lines[:2]} (exit {p.returncode})")


def png(path):
    from PIL import Image
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int64)


Z, Y, X = 8, 16, 20
img = (np.arange(Z * Y * X, dtype=np.uint16).reshape(Z, Y, X) * 7 % 1000).astype(np.uint16)
lab = np.zeros((Z, Y, X), np.uint8)
lab[2:6, 3:9, 4:12] = 1
lab[5:8, 10:15, 1:7] = 2
lab[0:3, 0:4, 14:20] = 3
COLORS = [{"label-value": 1, "rgba": [255, 0, 0, 255]},
          {"label-value": 2, "rgba": [0, 255, 0, 128]},
          {"label-value": 3, "rgba": [0, 0, 255, 255]}]
ROWS, COLS = ["A", "B"], ["1", "2", "3"]
WELLS = [f"{r}/{c}" for r in ROWS for c in COLS]


def new_group(path, fmt):
    store = parse_url(path, mode="w", fmt=fmt).store
    return zarr.group(store=store, zarr_format=fmt.zarr_format)


def meta_file(group_dir):
    """(the metadata file, the OME attributes dict inside it as a reference getter)"""
    v3 = os.path.join(group_dir, "zarr.json")
    if os.path.exists(v3):
        return v3, lambda m: m["attributes"]["ome"]
    return os.path.join(group_dir, ".zattrs"), lambda m: m


def edit(group_dir, fn):
    f, get = meta_file(group_dir)
    m = json.load(open(f))
    fn(get(m))
    json.dump(m, open(f, "w"))


for fmt, tag in ((FormatV04(), "0.4"), (FormatV05(), "0.5")):
    md = "zarr.json" if tag == "0.5" else ".zattrs"
    # ---- an image with a label image -----------------------------------------------------------
    image = os.path.join(OUT, f"image_{tag}.ome.zarr")
    root = new_group(image, fmt)
    write_image(img, group=root, axes="zyx", fmt=fmt, storage_options=dict(chunks=(4, 8, 10)))
    write_labels(lab, group=root, name="cells", axes="zyx", fmt=fmt,
                 label_metadata={"colors": COLORS, "properties": [{"label-value": 1, "class": "a"}]})
    cells = os.path.join(image, "labels", "cells")
    p = volvis("info", image)
    check(p.returncode == 0 and f"label images: cells: {X} x {Y} x {Z} u8" in p.stdout and
          "3 colours" in p.stdout and f"volvis render {image}/labels/cells" in p.stdout,
          f"{tag}: info lists the label image ({p.stderr.strip()}{p.stdout[-400:]})")
    p = volvis("info", cells)
    check(p.returncode == 0 and "a label image" in p.stdout and f"{X} x {Y} x {Z}" in p.stdout,
          f"{tag}: info of labels/cells says a label image ({p.stderr.strip()})")
    check(same(read_back(cells), lab), f"{tag}: the label image's voxels")
    check(same(read_back(image), img), f"{tag}: the image's voxels beside its labels")
    # rendered as a label volume: the same as --labels, not the transfer function's
    how = ["--size", "96x96", "--mode", "composite"]
    a, b, c = (os.path.join(OUT, f"lab_{tag}_{k}.png") for k in ("auto", "flag", "tf"))
    plain = os.path.join(OUT, f"lab_{tag}.nrrd")
    p1 = volvis("render", cells, "-o", a, *how)
    p2 = volvis("render", cells, "-o", b, *how, "--labels")
    p3 = volvis("convert", cells, plain, "--quiet")
    p4 = volvis("render", plain, "-o", c, *how)
    if all(q.returncode == 0 for q in (p1, p2, p3, p4)):
        A, B, C = png(a), png(b), png(c)
        check(np.array_equal(A, B) and A.max() > 0,
              f"{tag}: render labels/cells is a label volume (as --labels)")
        check(not np.array_equal(A, C), f"{tag}: ... not the transfer function's image")
    else:
        check(False, f"{tag}: render the label image: "
              f"{[q.stderr.strip() for q in (p1, p2, p3, p4)]}")
    refused(["render", os.path.join(image, "labels"), "-o", os.path.join(OUT, "x.png")],
            ["a labels group, not an image", f"{image}/labels/cells"],
            f"{tag}: render of the labels group names a label image")

    # ---- an HCS plate --------------------------------------------------------------------------
    plate = os.path.join(OUT, f"plate_{tag}.ome.zarr")
    root = new_group(plate, fmt)
    write_plate_metadata(root, ROWS, COLS, WELLS, fmt=fmt, field_count=2,
                         acquisitions=[{"id": 0}], name="plate 78")
    fields = {}
    for wp in WELLS:
        r, c = wp.split("/")
        wg = root.require_group(r).require_group(c)
        write_well_metadata(wg, ["0", "1"], fmt=fmt)
        for f in ("0", "1"):
            data = (img + (WELLS.index(wp) * 10 + int(f))).astype(np.uint16)
            fields[f"{wp}/{f}"] = data
            write_image(data, group=wg.require_group(f), axes="zyx", fmt=fmt,
                        storage_options=dict(chunks=(4, 8, 10)))
    p = volvis("info", plate)
    out = p.stdout
    check(p.returncode == 0 and '"plate 78", 2 rows x 3 columns, 6 wells' in out and
          "at most 2 fields per well" in out and "1 acquisition" in out and
          all(f"{w}: 2 fields" in out for w in WELLS) and
          f"open a field: volvis render {plate}/A/1/0" in out,
          f"{tag}: info lists the plate ({p.stderr.strip()}{out})")
    p = volvis("info", os.path.join(plate, "B", "2"))
    check(p.returncode == 0 and "fields:       2" in p.stdout and
          f"volvis render {plate}/B/2/0" in p.stdout, f"{tag}: info of a well ({p.stderr.strip()})")
    field = os.path.join(plate, "B", "2", "1")
    check(same(read_back(field), fields["B/2/1"]), f"{tag}: field B/2/1's voxels")
    p = volvis("info", field)
    check(p.returncode == 0 and f"{X} x {Y} x {Z}" in p.stdout, f"{tag}: info of a field")
    p = volvis("render", field, "-o", os.path.join(OUT, f"field_{tag}.png"), "--size", "64x64")
    check(p.returncode == 0, f"{tag}: render a field ({p.stderr.strip()})")
    refused(["render", plate, "-o", os.path.join(OUT, "x.png")],
            [f"{md}: an HCS plate of 2 x 3 wells, not an image", f"{plate}/A/1/0"],
            f"{tag}: render of the plate names its first field")
    refused(["render", os.path.join(plate, "A", "3"), "-o", os.path.join(OUT, "x.png")],
            ["a well of an HCS plate", f"{plate}/A/3/0"], f"{tag}: render of a well")

    # ---- hostile plates and labels -------------------------------------------------------------
    def hostile_plate(name, fn, needles, what):
        bad = os.path.join(OUT, f"bad_{name}_{tag}.ome.zarr")
        shutil.rmtree(bad, ignore_errors=True)
        shutil.copytree(plate, bad, symlinks=True)
        fn(bad)
        for cmd in (["info", bad], ["render", bad, "-o", os.path.join(OUT, "x.png")]):
            refused(cmd, needles, f"{tag}: {what} ({cmd[0]})")

    def well_path(p):
        return lambda d: edit(d, lambda o: o["plate"]["wells"][1].update(path=p))

    for bad_path in ("../x", "/etc", "A/../../x", "A/./1"):
        hostile_plate("well", well_path(bad_path),
                      [md, "plate.wells 1", f'"{bad_path}" leaves the store'],
                      f"a well path {bad_path!r}")
    hostile_plate("wellparts", well_path("A"), [md, "plate.wells 1", "is not ROW/COLUMN"],
                  "a well path of one part")
    hostile_plate("many", lambda d: edit(d, lambda o: o["plate"].update(
        wells=[{"path": "A/1", "rowIndex": 0, "columnIndex": 0}] * 4097)),
        [md, "plate.wells: 4097 entries (at most 4096"], "4097 wells")
    hostile_plate("rowindex", lambda d: edit(d, lambda o: o["plate"]["wells"][0].update(
        rowIndex=5)), [md, "plate.wells 0", "rowIndex"], "a rowIndex past the rows")
    hostile_plate("field", lambda d: edit(os.path.join(d, "A", "1"), lambda o: o["well"].update(
        images=[{"path": ".."}])), [f"A/1/{md}", "well.images 0", '".." leaves the store'],
        "a field path '..'")

    def link_out(d):
        outside = os.path.join(OUT, f"outside_{tag}")
        shutil.rmtree(outside, ignore_errors=True)
        shutil.copytree(os.path.join(d, "A", "2"), outside)
        shutil.rmtree(os.path.join(d, "A", "2"))
        os.symlink(outside, os.path.join(d, "A", "2"))

    # refused by the store's own check (info, in this process) or by the reader
    # sandbox, which cannot see outside the store (render): one line naming the file
    bad = os.path.join(OUT, f"bad_link_{tag}.ome.zarr")
    shutil.rmtree(bad, ignore_errors=True)
    shutil.copytree(plate, bad, symlinks=True)
    link_out(bad)
    refused(["info", bad], [f"A/2/{md}", "leaves the store"],
            f"{tag}: a well folder that links out of the store (info)")
    p = volvis("render", bad, "-o", os.path.join(OUT, "x.png"))
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    check(p.returncode != 0 and len(lines) == 1 and f"A/2/{md}" in lines[0] and
          ("leaves the store" in lines[0] or "Permission denied" in lines[0]),
          f"{tag}: a well folder that links out of the store (render): {lines[:2]}")

    def hostile_labels(name, fn, needles, what):
        bad = os.path.join(OUT, f"badlab_{name}_{tag}.ome.zarr")
        shutil.rmtree(bad, ignore_errors=True)
        shutil.copytree(image, bad, symlinks=True)
        fn(bad)
        refused(["info", bad], needles, f"{tag}: {what} (info)")
        # opened at labels/, the file is named from there
        needles = [n.replace(f"labels/{md}", f"labels: {md}").replace("labels/cells/", "cells/")
                   for n in needles]
        refused(["render", os.path.join(bad, "labels"), "-o", os.path.join(OUT, "x.png")],
                needles, f"{tag}: {what} (render labels)")

    hostile_labels("dotdot", lambda d: edit(os.path.join(d, "labels"), lambda o: o.update(
        labels=["../s0"])), [f"labels/{md}", "labels 0", '"../s0" leaves the store'],
        "a label name '../s0'")
    hostile_labels("abs", lambda d: edit(os.path.join(d, "labels"), lambda o: o.update(
        labels=["/etc"])), [f"labels/{md}", "labels 0", '"/etc" leaves the store'],
        "a label name '/etc'")
    hostile_labels("many", lambda d: edit(os.path.join(d, "labels"), lambda o: o.update(
        labels=["cells"] * 257)), [f"labels/{md}", "labels: 257 entries (at most 256"],
        "257 labels")
    hostile_labels("rgba", lambda d: edit(os.path.join(d, "labels", "cells"), lambda o: o[
        "image-label"]["colors"][0].update(rgba=[255, 0, 0, 999])),
        [f"labels/cells/{md}", "image-label.colors 0"], "an rgba past 255")

if failures:
    print(f"{len(failures)} failed")
    sys.exit(1)
print("all passed")
