#!/usr/bin/env python3
"""N5 and Neuroglancer precomputed volumes written by tensorstore, read by VolVis (issue 91).

  n5_precomputed_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test): tensorstore's n5
driver writes, VolVis reads; numpy is the judge.

- one dataset per compression (raw, gzip, gzip with useZlib, bzip2, xz, blosc, zstd),
  blocks that do not divide the dimensions (the blocks at the end cut to the array, as
  N5 stores them), and one per data type (uint8 .. uint64, int8 .. int64, float32,
  float64): `volvis convert DATASET OUT.nrrd` voxel for voxel (N5 lists x first);
- a 4-D dataset (x, y, z, c, its axes named): two channels, channel 1 read alike;
- a real CT (../shared/data/volumes/ct_head.nrrd, int16, 0.96 x 0.96 x 1.5 mm) as an
  n5-viewer multiscale group s0 .. s2 (2x2x2 and 4x4x4 means; the group's scales,
  resolution, units and axes; each level's downsamplingFactors): `volvis info` names
  N5, three levels and the spacing; --level 1 is s1 voxel for voxel with twice the
  spacing and the centre shift of a 2x2x2 mean; the same group described by
  pixelResolution and downsamplingFactors alone, and by a COSEM multiscales block,
  opens alike; rendered out of core (--memory-limit 8M) as in memory (>= 50 dB);
- BigDataViewer's bdv.n5 (setup<S>/timepoint<T>/s<L>, datasets by tensorstore): `volvis
  info` names its setups as channels and its timepoints as time steps; setups, timepoints
  and levels voxel for voxel; a timepoint group without attributes by itself; both setups
  out of core together as in memory; a dataset XML with ImageLoader bdv.n5: the setups'
  names, the registration's spacing and origin; an XML naming a container outside its
  folder and a setup the container lacks: one line;
- served by nginx on loopback: the dataset and the group by URL equal to the local
  files (convert voxel for voxel, the out-of-core render pixel for pixel);
- hostile datasets and groups (a block shorter than its header, object mode, a block
  of other dimensions, a block larger than blockSize, a block that does not decode,
  absurd or missing sizes, unknown compression and data type, a group whose scales
  name a level it lacks): one line naming the store, a non-zero exit, no output;
- Neuroglancer precomputed (tensorstore's neuroglancer_precomputed driver): the CT as
  raw chunks in two scales with a voxel_offset (chunks cut at the end), each scale
  voxel for voxel with its spacing (nm) and origin; 3 channels; a jpeg scale >= 35 dB
  from its source and >= 45 dB from tensorstore's own decoding; a raw chunk stored as
  gzip; a segmentation read as a label image; out of core as in memory; by URL as
  local; sharded scales (neuroglancer_uint64_sharded_v1: murmurhash3_x86_128 with gzip
  indexes and data, identity raw, jpeg) voxel for voxel, out of core and by URL as
  unsharded and local; by precomputed://URL and gs://BUCKET (STORAGE_EMULATOR_HOST
  pointing at nginx), n5://URL, and `volvis info` of N5 and precomputed URLs; a frame of
  the coarse scale alone (--lod 1) asks nothing of the fine scale's shards;
  compressed_segmentation (uint32, uint64 in two channels with
  blocks that do not divide the chunk, in shards) voxel for voxel; hostile infos, chunks,
  compressed_segmentation (offsets, bits, tables past the chunk)
  and shards (bits, hash, truncated, indexes past the shard, backwards, overlapping or
  ragged, a chunk past the shard): one line, a non-zero exit, no output.
"""
import json
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import tensorstore as ts
    from PIL import Image  # noqa: F401 (pyramid_common's psnr reads the PNGs with it)
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Checks, read_nrrd, render_png, run  # noqa: E402
from http_common import nginx_path, start_nginx, stop_server  # noqa: E402
from pyramid_common import psnr  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
check = Checks()
SIZE = ["--size", "200x160"]
CT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared", "data",
                  "volumes", "ct_head.nrrd")


def volvis(*args):
    return run(VOLVIS, *args)


def n5_write(path, arr, block, comp=None, axes=None, extra=None):
    """ARR (N5 order: x first) written by tensorstore as an N5 dataset at PATH."""
    meta = {"dimensions": list(arr.shape), "blockSize": list(block),
            "dataType": str(arr.dtype), "compression": comp or {"type": "gzip"}}
    t = ts.open({"driver": "n5", "kvstore": {"driver": "file", "path": path},
                 "metadata": meta, "create": True, "delete_existing": True}).result()
    t.write(arr).result()
    if axes or extra:  # attributes beside tensorstore's, as n5-viewer and Neuroglancer add
        f = os.path.join(path, "attributes.json")
        with open(f) as fh:
            at = json.load(fh)
        if axes:
            at["axes"] = axes
        at.update(extra or {})
        with open(f, "w") as fh:
            json.dump(at, fh)
    return path


def read_back(store, *args):
    out = os.path.join(OUT, "back.nrrd")
    if os.path.exists(out):
        os.remove(out)
    p = volvis("convert", store, out, "--quiet", *args)
    if p.returncode != 0:
        check(False, f"convert {os.path.basename(store)} {' '.join(args)}: {p.stderr.strip()}")
        return None, None, None
    return read_nrrd(out)


def same(got, want):
    """GOT (z, y, x, as read back) equal to WANT (N5 order: x, y, z)."""
    if got is None:
        return False
    w = want.transpose(2, 1, 0)
    if got.shape != w.shape:
        return False
    return bool(np.array_equal(got.astype(np.float64), w.astype(np.float64)))


def render(name, store, *args):
    return render_png(VOLVIS, OUT, check, name, store, *SIZE, *args)


rng = np.random.default_rng(91)

# ---- every compression, blocks cut at the end ------------------------------------------------
X, Y, Z = 37, 29, 23
u16 = rng.integers(0, 60000, (X, Y, Z)).astype(np.uint16)
comps = {"raw": {"type": "raw"}, "gzip": {"type": "gzip"},
         "zlib": {"type": "gzip", "useZlib": True},
         "bzip2": {"type": "bzip2", "blockSize": 9}, "xz": {"type": "xz", "preset": 6},
         "blosc": {"type": "blosc", "cname": "lz4", "clevel": 5, "shuffle": 1},
         "zstd": {"type": "zstd", "level": 3}}
for name, comp in comps.items():
    ds = n5_write(os.path.join(OUT, f"c_{name}.n5"), u16, (16, 8, 10), comp)
    got, _, _ = read_back(ds)
    check(same(got, u16), f"{name}: read voxel for voxel ({X} x {Y} x {Z}, blocks 16 x 8 x 10)")

# ---- every data type --------------------------------------------------------------------------
for dt in ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64", "int64",
           "uint64"):
    d = np.dtype(dt)
    if d.kind == "f":
        a = rng.normal(0, 1000, (X, Y, Z)).astype(d)
    else:
        info = np.iinfo(d)
        lo, hi = max(info.min, -(2 ** 40)), min(info.max, 2 ** 40)  # exact as doubles
        a = rng.integers(lo, hi, (X, Y, Z), dtype=d)
    ds = n5_write(os.path.join(OUT, f"t_{dt}.n5"), a, (20, 16, 12))
    got, _, _ = read_back(ds)
    check(same(got, a), f"{dt}: read voxel for voxel")

# ---- a 4-D dataset: x, y, z, c -----------------------------------------------------------------
a4 = rng.integers(0, 255, (X, Y, Z, 2)).astype(np.uint8)
d4 = n5_write(os.path.join(OUT, "xyzc.n5"), a4, (16, 16, 16, 1), axes=["x", "y", "z", "c"])
p = volvis("info", d4)
check(p.returncode == 0 and "channels:     2" in p.stdout.replace("channels:", "channels:"),
      f"xyzc: info names 2 channels: {p.stdout.strip()[:200]} {p.stderr.strip()}")
got, _, _ = read_back(d4, "--channel", "1")
check(same(got, a4[..., 1]), "xyzc: channel 1 read voxel for voxel")


# ---- a real CT as a multiscale group -----------------------------------------------------------
def mean2(a):
    """2x2x2 means (float, then rounded as n5-spark and BigDataViewer do) of A (x, y, z)."""
    s = [n - n % 2 for n in a.shape]
    b = a[:s[0], :s[1], :s[2]].astype(np.float64)
    b = b.reshape(s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(1, 3, 5))
    return np.round(b).astype(a.dtype)


ct, _, _ = read_nrrd(CT)  # z, y, x
ct = np.ascontiguousarray(ct.transpose(2, 1, 0))  # N5 order: x, y, z
levels = [ct, mean2(ct), mean2(mean2(ct))]
with open(CT, "rb") as f:  # its spacing: a "spacings" field (read_nrrd reads directions)
    head = f.read(4096).partition(b"\n\n")[0].decode(errors="replace")
RES = [round(float(v), 6) for ln in head.splitlines() if ln.startswith("spacings:")
       for v in ln.split(":", 1)[1].split()]
assert len(RES) == 3 and RES[2] == 1.5, RES


def ct_group(name, group_attrs, level_attrs):
    g = os.path.join(OUT, name)
    shutil.rmtree(g, ignore_errors=True)
    for i, lv in enumerate(levels):
        n5_write(os.path.join(g, f"s{i}"), lv, (64, 64, 32), extra=level_attrs(i))
    with open(os.path.join(g, "attributes.json"), "w") as f:
        json.dump(group_attrs, f)
    return g


g1 = ct_group("ct_viewer.n5",
              {"n5": "4.0.0", "scales": [[1, 1, 1], [2, 2, 2], [4, 4, 4]], "resolution": RES,
               "units": ["mm", "mm", "mm"], "axes": ["x", "y", "z"]},
              lambda i: {"downsamplingFactors": [2 ** i] * 3})
g2 = ct_group("ct_pixelres.n5",
              {"n5": "4.0.0", "pixelResolution": {"dimensions": RES, "unit": "mm"}},
              lambda i: {"downsamplingFactors": [2 ** i] * 3})
cosem = {"multiscales": [{"name": "ct", "datasets": [
    {"path": f"s{i}", "transform": {"axes": ["z", "y", "x"], "units": ["mm"] * 3,
                                    "scale": [RES[2] * 2 ** i, RES[1] * 2 ** i, RES[0] * 2 ** i],
                                    "translate": [(2 ** i - 1) / 2 * RES[2],
                                                  (2 ** i - 1) / 2 * RES[1],
                                                  (2 ** i - 1) / 2 * RES[0]]}}
    for i in range(3)]}]}
g3 = ct_group("ct_cosem.n5", cosem, lambda i: {})

p = volvis("info", g1)
txt = p.stdout
check(p.returncode == 0 and "format:       n5" in txt and "256 x 256 x 108" in txt,
      f"info: N5, 256 x 256 x 108: {txt[:300]} {p.stderr.strip()}")
check("3" in "".join(ln for ln in txt.splitlines() if "level" in ln.lower()),
      f"info: 3 levels: {[ln for ln in txt.splitlines() if 'level' in ln.lower()]}")
want_sp = [RES[0] * 2, RES[1] * 2, RES[2] * 2]
want_or = [RES[0] / 2, RES[1] / 2, RES[2] / 2]  # the centre of a 2x2x2 mean
for g in (g1, g2, g3):
    got, sp, org = read_back(g, "--level", "1")
    n = os.path.basename(g)
    check(same(got, levels[1]), f"{n}: --level 1 is s1 voxel for voxel")
    check(sp is not None and np.allclose(sp, want_sp, rtol=1e-4),
          f"{n}: level 1's spacing {sp}, want {want_sp}")
    check(org is not None and np.allclose(org, want_or, rtol=1e-4, atol=1e-6),
          f"{n}: level 1's origin {org}, want {want_or}")
    got, sp, _ = read_back(g)
    check(same(got, levels[0]) and sp is not None and np.allclose(sp, RES, rtol=1e-4),
          f"{n}: level 0 voxel for voxel, spacing {sp} (want {RES})")

mem = render("ct_mem", g1, "--level", "0", "--set", "refinement=off", "--tf", "100:1500")
orig = render("ct_nrrd", CT, "--set", "refinement=off", "--tf", "100:1500")
if mem and orig:
    d = psnr(mem, orig)
    check(d >= 60, f"ct: the N5 group's level 0 draws as the NRRD it came from ({d:.1f} dB; "
          f"its orientation and spacing)")
ooc = render("ct_ooc", g1, "--level", "0", "--memory-limit", "8M", "--tf", "100:1500")
if mem and ooc:
    d = psnr(mem, ooc)
    check(d >= 50, f"ct: out of core (--memory-limit 8M) {d:.1f} dB from in memory (>= 50)")

# ---- BigDataViewer's bdv.n5: setups as channels, timepoints as time steps ------------------------
# the layout BigDataViewer's N5 export writes (setup<S>/timepoint<T>/s<L>, the setup's
# downsamplingFactors and dataType; a timepoint group with Paintera's multiScale and
# resolution, or none at all), the datasets by tensorstore; two setups of the CT (the second
# its negative), three timepoints (shifted by 100 each), levels of 2x2x2 means
bdv = os.path.join(OUT, "bdv.n5")
shutil.rmtree(bdv, ignore_errors=True)
os.makedirs(bdv)
with open(os.path.join(bdv, "attributes.json"), "w") as f:
    json.dump({"n5": "4.0.0"}, f)
small = ct[::2, ::2, ::2].astype(np.int32)  # 128 x 128 x 54, x first


def bdv_volume(s, t):
    return (small * (1 if s == 0 else -1) + 100 * t).astype(np.int16)


for s in range(2):
    sd = os.path.join(bdv, f"setup{s}")
    os.makedirs(sd)
    with open(os.path.join(sd, "attributes.json"), "w") as f:
        json.dump({"downsamplingFactors": [[1, 1, 1], [2, 2, 2]], "dataType": "int16"}, f)
    for t in range(3):
        v = bdv_volume(s, t)
        for i, lv in enumerate((v, mean2(v))):
            n5_write(os.path.join(sd, f"timepoint{t}", f"s{i}"), lv, (32, 32, 16))
        if t != 1:  # timepoint 1 keeps no attributes (they are optional)
            with open(os.path.join(sd, f"timepoint{t}", "attributes.json"), "w") as f:
                json.dump({"multiScale": True, "resolution": [1.0, 1.0, 1.0]}, f)
p = volvis("info", bdv)
txt = p.stdout
check(p.returncode == 0 and "channels:     2" in txt and "time steps:   3" in txt
      and "levels:       2" in txt and '"setup1"' in txt,
      f"bdv.n5: info names 2 setups as channels, 3 time steps, 2 levels: {txt[:500]} "
      f"{p.stderr.strip()}")
for (c, t, lv) in ((0, 0, 0), (1, 2, 0), (1, 1, 1), (0, 2, 1)):
    want = bdv_volume(c, t) if lv == 0 else mean2(bdv_volume(c, t))
    got, _, _ = read_back(bdv, "--channel", str(c), "--time", str(t), "--level", str(lv))
    check(same(got, want), f"bdv.n5: setup {c} at timepoint {t}, level {lv} voxel for voxel")
got, _, _ = read_back(os.path.join(bdv, "setup1", "timepoint1"), "--level", "1")
check(same(got, mean2(bdv_volume(1, 1))),
      "bdv.n5: a timepoint group without attributes opened by itself, level 1")
p = volvis("convert", bdv, os.path.join(OUT, "bdv_bad.nrrd"), "--channel", "2", "--quiet")
check(p.returncode != 0 and len(p.stderr.strip().splitlines()) == 1 and "2 setups" in p.stderr
      and not os.path.exists(os.path.join(OUT, "bdv_bad.nrrd")),
      f"bdv.n5: a third setup asked: one line ({p.stderr.strip()})")
bm = render("bdv_mem", bdv, "--channels", "0,1", "--time", "2")
bo = render("bdv_ooc", bdv, "--channels", "0,1", "--time", "2", "--level", "0",
            "--memory-limit", "4M")
if bm and bo:
    d = psnr(bm, bo)
    check(d >= 50, f"bdv.n5: two setups at timepoint 2 out of core {d:.1f} dB from in memory")

# the same container named by a dataset XML (ImageLoader bdv.n5): its setups' names, its
# calibration as the spacing
CAL = [0.4, 0.4, 1.2]
views = "".join(f"""    <ViewRegistration timepoint="{t}" setup="{s}">
      <ViewTransform type="affine"><affine>{CAL[0]} 0 0 5 0 {CAL[1]} 0 6 0 0 {CAL[2]} 7</affine>
      </ViewTransform>
    </ViewRegistration>
""" for t in range(3) for s in range(2))
setups = "".join(f"""      <ViewSetup><id>{s}</id><name>{n}</name><size>128 128 54</size>
        <voxelSize><unit>µm</unit><size>{CAL[0]} {CAL[1]} {CAL[2]}</size></voxelSize>
      </ViewSetup>
""" for s, n in enumerate(("bone", "negative")))
bdv_xml = os.path.join(OUT, "bdv_n5.xml")
with open(bdv_xml, "w", encoding="utf-8") as f:
    f.write(f"""<?xml version="1.0" encoding="UTF-8"?>
<SpimData version="0.2">
  <BasePath type="relative">.</BasePath>
  <SequenceDescription>
    <ImageLoader format="bdv.n5" version="1.0">
      <n5 type="relative">bdv.n5</n5>
    </ImageLoader>
    <ViewSetups>
{setups}    </ViewSetups>
    <Timepoints type="range"><first>0</first><last>2</last></Timepoints>
  </SequenceDescription>
  <ViewRegistrations>
{views}  </ViewRegistrations>
</SpimData>
""")
p = volvis("info", bdv_xml)
check(p.returncode == 0 and '"negative"' in p.stdout and "time steps:   3" in p.stdout,
      f"bdv.n5 XML: info names the setups and 3 time steps: {p.stdout[:400]} {p.stderr.strip()}")
with open(bdv_xml, encoding="utf-8") as f:
    outside = f.read().replace('<n5 type="relative">bdv.n5', '<n5 type="relative">../bdv.n5')
bad_xml = os.path.join(OUT, "bdv_n5_outside.xml")
with open(bad_xml, "w", encoding="utf-8") as f:
    f.write(outside)
p = volvis("convert", bad_xml, os.path.join(OUT, "bdv_bad.nrrd"), "--quiet")
check(p.returncode != 0 and len(p.stderr.strip().splitlines()) == 1
      and "n5 container" in p.stderr and "bdv_n5_outside.xml" in p.stderr,
      f"bdv.n5 XML: a container outside the XML's folder is refused ({p.stderr.strip()})")
got, sp, org = read_back(bdv_xml, "--channel", "1", "--time", "2", "--level", "1")
check(same(got, mean2(bdv_volume(1, 2))) and sp is not None
      and np.allclose(sp, [2 * c for c in CAL], rtol=1e-4)
      and np.allclose(org, [5 + CAL[0] / 2, 6 + CAL[1] / 2, 7 + CAL[2] / 2], rtol=1e-4),
      f"bdv.n5 XML: setup 1 at timepoint 2, level 1 voxel for voxel, spacing {sp} and origin "
      f"{org} from the registration")

# ---- by URL: nginx on loopback -------------------------------------------------------------------
if nginx_path():
    nginx, port, _ = start_nginx(OUT, OUT, "n5_precomputed_cli")
    try:
        url = f"http://127.0.0.1:{port}"
        got, _, _ = read_back(f"{url}/c_gzip.n5")
        check(same(got, u16), "by URL: a gzip dataset voxel for voxel")
        got, sp, _ = read_back(f"{url}/ct_viewer.n5", "--level", "1")
        check(same(got, levels[1]) and sp is not None and np.allclose(sp, want_sp, rtol=1e-4),
              "by URL: the CT group's level 1 voxel for voxel, its spacing")
        rem = render("ct_url_ooc", f"{url}/ct_viewer.n5", "--level", "0", "--memory-limit", "8M",
                     "--tf", "100:1500")
        if rem and ooc:
            d = psnr(rem, ooc)
            check(d >= 99, f"by URL: the out-of-core render equals the local one ({d:.1f} dB)")
        p = volvis("info", f"{url}/ct_viewer.n5")
        check(p.returncode == 0 and "levels:       3" in p.stdout,
              f"by URL: info of the group: {p.stdout[:200]} {p.stderr.strip()}")
        p = volvis("info", f"n5://{url}/ct_viewer.n5")
        check(p.returncode == 0 and "format:       n5" in p.stdout,
              f"n5://URL: info names N5: {p.stdout[:200]} {p.stderr.strip()}")
        got, _, _ = read_back(f"n5://{url}/ct_viewer.n5", "--level", "2")
        check(same(got, levels[2]), "n5://URL: level 2 voxel for voxel")
    finally:
        stop_server(nginx)
else:
    check(False, "nginx is missing (apt-get install nginx-light): the URL checks cannot run")


# ---- hostile stores --------------------------------------------------------------------------------
def hostile(name, make, want):
    """A copy of the gzip dataset spoilt by MAKE(path): convert fails with one line naming
    the store (and WANT), a non-zero exit, no output."""
    d = os.path.join(OUT, f"bad_{name}.n5")
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(os.path.join(OUT, "c_gzip.n5"), d)
    make(d)
    out = os.path.join(OUT, f"bad_{name}.nrrd")
    p = volvis("convert", d, out, "--quiet")
    lines = p.stderr.strip().splitlines()
    check(p.returncode != 0 and len(lines) == 1 and f"bad_{name}.n5" in p.stderr and
          want in p.stderr and not os.path.exists(out),
          f"hostile {name}: exit {p.returncode}, {p.stderr.strip()!r} (wants {want!r})")


def block(d):
    return os.path.join(d, "0", "0", "0")


def rewrite_block(d, fn):
    with open(block(d), "rb") as f:
        b = bytearray(f.read())
    with open(block(d), "wb") as f:
        f.write(fn(b))


def attrs(d, **kw):
    f = os.path.join(d, "attributes.json")
    with open(f) as fh:
        at = json.load(fh)
    for k, v in kw.items():
        if v is None:
            at.pop(k, None)
        else:
            at[k] = v
    with open(f, "w") as fh:
        json.dump(at, fh)


hostile("short", lambda d: rewrite_block(d, lambda b: b[:10]), "header")
hostile("mode", lambda d: rewrite_block(d, lambda b: b"\x00\x02" + b[2:]), "mode 2")
hostile("ndim", lambda d: rewrite_block(d, lambda b: b[:2] + b"\x00\x02" + b[4:]),
        "2 dimensions")
hostile("bigblock", lambda d: rewrite_block(d, lambda b: b[:4] + b"\x00\x01\x00\x00" + b[8:]),
        "blockSize")
hostile("garbage", lambda d: rewrite_block(d, lambda b: b[:16] + bytes(len(b) - 16)),
        "does not decode")
hostile("dims", lambda d: attrs(d, dimensions=[-5, 29, 23]), "dimensions")
hostile("huge", lambda d: attrs(d, dimensions=[2 ** 50, 29, 23]), "dimensions")
hostile("zeroblock", lambda d: attrs(d, blockSize=[0, 8, 10]), "blockSize")
hostile("nodims", lambda d: attrs(d, dimensions=None), "attributes.json")
hostile("lz4", lambda d: attrs(d, compression={"type": "lz4"}), "lz4")
hostile("object", lambda d: attrs(d, dataType="object"), "object")


def missing_level(d):
    os.makedirs(os.path.join(d, "s0"))
    for e in os.listdir(d):
        if e != "s0":
            shutil.move(os.path.join(d, e), os.path.join(d, "s0", e))
    with open(os.path.join(d, "attributes.json"), "w") as f:
        json.dump({"n5": "4.0.0", "scales": [[1, 1, 1], [2, 2, 2]]}, f)


hostile("nolevel", missing_level, "no dataset s1")


# ---- Neuroglancer precomputed --------------------------------------------------------------------
def pc_write(path, arr, res, chunk, offset=(0, 0, 0), encoding="raw", mtype="image", create=True,
             **scale):
    """ARR (x, y, z, channel) as a scale of the precomputed volume at PATH (tensorstore)."""
    spec = {"driver": "neuroglancer_precomputed", "kvstore": {"driver": "file", "path": path},
            "scale_metadata": {"size": list(arr.shape[:3]), "resolution": list(res),
                               "encoding": encoding, "chunk_size": list(chunk),
                               "voxel_offset": list(offset), **scale},
            "create": True, "open": not create}
    if create:
        spec["multiscale_metadata"] = {"type": mtype, "data_type": str(arr.dtype),
                                       "num_channels": int(arr.shape[3])}
    t = ts.open(spec).result()
    t[...] = arr
    return t


PCR = (957.0, 957.0, 1500.0)
OFF = (7, 11, 3)
pc = os.path.join(OUT, "ct.precomputed")
shutil.rmtree(pc, ignore_errors=True)
pc_write(pc, levels[0][..., None], PCR, (64, 64, 20), OFF)
pc_write(pc, levels[1][..., None], (PCR[0] * 2, PCR[1] * 2, PCR[2] * 2), (64, 64, 20),
         (OFF[0] // 2, OFF[1] // 2, OFF[2] // 2), create=False)
p = volvis("info", pc)
check(p.returncode == 0 and "format:       precomputed" in p.stdout and "levels:       2" in p.stdout,
      f"precomputed: info names the format and 2 levels: {p.stdout[:300]} {p.stderr.strip()}")
check("unit:         nm" in p.stdout and "spacing:      957 x 957 x 1500 nm" in p.stdout,
      f"precomputed: the resolution's unit is nm: {p.stdout[:400]}")
for lv, sc in ((0, 1), (1, 2)):
    got, sp, org = read_back(pc, "--level", str(lv))
    r = [v * sc for v in PCR]
    o = [(OFF[k] // sc + 0.5) * r[k] - 0.5 * PCR[k] for k in range(3)]
    check(same(got, levels[lv]), f"precomputed: scale {lv} voxel for voxel (chunks cut at the end)")
    check(sp is not None and np.allclose(sp, r) and np.allclose(org, o),
          f"precomputed: scale {lv}: spacing {sp} origin {org} (want {r}, {o})")
pm = render("pc_mem", pc, "--level", "0", "--set", "refinement=off", "--tf", "100:1500")
po = render("pc_ooc", pc, "--level", "0", "--memory-limit", "8M", "--tf", "100:1500")
if pm and po:
    d = psnr(pm, po)
    check(d >= 50, f"precomputed: out of core {d:.1f} dB from in memory (>= 50)")

# three channels
a3 = rng.integers(0, 255, (X, Y, Z, 3)).astype(np.uint8)
pc3 = os.path.join(OUT, "c3.precomputed")
pc_write(pc3, a3, (4, 4, 4), (16, 16, 8))
for c in range(3):
    got, _, _ = read_back(pc3, "--channel", str(c))
    check(same(got, a3[..., c]), f"precomputed: channel {c} of 3 voxel for voxel")

# jpeg: >= 35 dB from the source, >= 45 dB from tensorstore's decoding
u8 = np.clip((ct.astype(np.float64) + 1024) / 8, 0, 255).astype(np.uint8)[:, :, :64, None]
pj = os.path.join(OUT, "jpeg.precomputed")
tj = pc_write(pj, u8, PCR, (64, 64, 16), encoding="jpeg", jpeg_quality=90)
ref = tj.read().result()[..., 0]
got, _, _ = read_back(pj)


def db(x, y):
    m = ((x - y.astype(np.float64)) ** 2).mean()
    return 99.0 if m == 0 else 10 * np.log10(255.0 ** 2 / m)


if got is not None:
    g = got.transpose(2, 1, 0).astype(np.float64)
    check(g.shape == u8[..., 0].shape and db(g, u8[..., 0]) >= 35,
          f"jpeg: {db(g, u8[..., 0]):.1f} dB from its source (>= 35)")
    check(db(g, ref) >= 45, f"jpeg: {db(g, ref):.1f} dB from tensorstore's decoding (>= 45)")

# a raw chunk stored gzip-compressed (as cloud-volume writes and servers send)
import gzip  # noqa: E402
pg = os.path.join(OUT, "gz.precomputed")
shutil.copytree(os.path.join(OUT, "c3.precomputed"), pg, dirs_exist_ok=True)
sd = os.path.join(pg, json.load(open(os.path.join(pg, "info")))["scales"][0]["key"])
for f in os.listdir(sd):
    with open(os.path.join(sd, f), "rb") as fh:
        b = fh.read()
    with open(os.path.join(sd, f), "wb") as fh:
        fh.write(gzip.compress(b))
got, _, _ = read_back(pg, "--channel", "2")
check(same(got, a3[..., 2]), "precomputed: gzip-compressed raw chunks voxel for voxel")

# a segmentation: a label image
seg = (np.arange(X * Y * Z).reshape(X, Y, Z) // 97 % 5).astype(np.uint32)[..., None]
ps = os.path.join(OUT, "seg.precomputed")
pc_write(ps, seg, (8, 8, 8), (16, 16, 16), mtype="segmentation")
got, _, _ = read_back(ps)
check(same(got, seg[..., 0]), "segmentation: voxel for voxel")
p = volvis("info", ps)
check(p.returncode == 0 and "label" in p.stdout.lower(),
      f"segmentation: info says it is a label image: {p.stdout[:400]}")



# sharded (neuroglancer_uint64_sharded_v1): the CT in both scales, murmurhash3_x86_128 with
# gzip indexes and data; three channels by the identity hash, raw; jpeg in shards
def sharding(h="murmurhash3_x86_128", enc="gzip", pre=1, mini=2, shard=2):
    return {"@type": "neuroglancer_uint64_sharded_v1", "preshift_bits": pre, "hash": h,
            "minishard_bits": mini, "shard_bits": shard, "minishard_index_encoding": enc,
            "data_encoding": enc}


psh = os.path.join(OUT, "ct_sharded.precomputed")
pc_write(psh, levels[0][..., None], PCR, (64, 64, 20), OFF, sharding=sharding())
pc_write(psh, levels[1][..., None], (PCR[0] * 2, PCR[1] * 2, PCR[2] * 2), (64, 64, 20),
         (OFF[0] // 2, OFF[1] // 2, OFF[2] // 2), create=False, sharding=sharding(shard=1))
check(any(f.endswith(".shard") for f in os.listdir(os.path.join(psh, os.listdir(psh)[0]))) or
      any(f.endswith(".shard") for f in os.listdir(os.path.join(psh, os.listdir(psh)[1]))),
      "sharded: tensorstore wrote .shard files")
for lv in (0, 1):
    got, _, _ = read_back(psh, "--level", str(lv))
    check(same(got, levels[lv]), f"sharded (murmurhash3_x86_128, gzip): scale {lv} voxel for "
          "voxel")
psr = render("pc_sharded_ooc", psh, "--level", "0", "--memory-limit", "8M", "--tf", "100:1500")
if psr and po:
    check(psnr(psr, po) >= 99, f"sharded: out of core the render of the unsharded scale "
          f"({psnr(psr, po):.1f} dB)")
psi = os.path.join(OUT, "c3_sharded.precomputed")
pc_write(psi, a3, (4, 4, 4), (16, 16, 8), sharding=sharding("identity", "raw", 0, 3, 1))
for c in (0, 2):
    got, _, _ = read_back(psi, "--channel", str(c))
    check(same(got, a3[..., c]), f"sharded (identity, raw): channel {c} of 3 voxel for voxel")
pjs = os.path.join(OUT, "jpeg_sharded.precomputed")
tjs = pc_write(pjs, u8, PCR, (64, 64, 16), encoding="jpeg", jpeg_quality=90,
               sharding=sharding(pre=0, mini=1, shard=1))
got, _, _ = read_back(pjs)
if got is not None:
    check(db(got.transpose(2, 1, 0).astype(np.float64), tjs.read().result()[..., 0]) >= 45,
          "sharded jpeg: >= 45 dB from tensorstore's decoding")

# by URL
if nginx_path():
    alog = os.path.join(OUT, "pc_access.log")
    nginx, port, _ = start_nginx(OUT, OUT, "n5_precomputed_cli", access_log=alog)
    try:
        got, _, _ = read_back(f"http://127.0.0.1:{port}/ct.precomputed", "--level", "1")
        check(same(got, levels[1]), "precomputed by URL: scale 1 voxel for voxel")
        pr = render("pc_url_ooc", f"http://127.0.0.1:{port}/ct.precomputed", "--level", "0",
                    "--memory-limit", "8M", "--tf", "100:1500")
        if pr and po:
            check(psnr(pr, po) >= 99, f"precomputed by URL: the render equals local's "
                  f"({psnr(pr, po):.1f} dB)")
        url = f"http://127.0.0.1:{port}/ct_sharded.precomputed"
        got, _, _ = read_back(url, "--level", "0")
        check(same(got, levels[0]), "sharded by URL: scale 0 voxel for voxel")
        pu = render("pc_sharded_url_ooc", url, "--level", "0", "--memory-limit", "8M",
                    "--tf", "100:1500")
        if pu and psr:
            check(psnr(pu, psr) >= 99, f"sharded by URL: the render equals local's "
                  f"({psnr(pu, psr):.1f} dB)")
        # a frame of level 1 alone (--lod 1) asks no byte of level 0's shards, and reads
        # level 1's by ranges
        keys = [sc["key"] for sc in json.load(open(os.path.join(psh, "info")))["scales"]]
        open(alog, "w").close()
        if render("pc_sharded_url_lod1", url, "--lod", "1"):
            reqs = open(alog).read().splitlines()
            fine = [r for r in reqs if f"/{keys[0]}/" in r]
            coarse = [r for r in reqs if f"/{keys[1]}/" in r and '"bytes=' in r]
            check(not fine and coarse, f"sharded by URL, --lod 1: {len(fine)} requests of level "
                  f"0 (want none), {len(coarse)} ranges of level 1 ({len(reqs)} requests)")
        # Neuroglancer's addresses: precomputed://URL; gs://BUCKET/PATH (anonymously at the
        # bucket's HTTPS address; here nginx stands in through STORAGE_EMULATOR_HOST)
        p = volvis("info", url)
        check(p.returncode == 0 and "levels:       2" in p.stdout,
              f"info by URL: {p.stdout[:200]} {p.stderr.strip()}")
        p = volvis("info", "precomputed://" + url)
        check(p.returncode == 0 and "format:       precomputed" in p.stdout,
              f"precomputed://URL: info names the format: {p.stdout[:200]} {p.stderr.strip()}")
        got, _, _ = read_back("precomputed://" + url, "--level", "1")
        check(same(got, levels[1]), "precomputed://URL: scale 1 voxel for voxel")
        os.environ["STORAGE_EMULATOR_HOST"] = f"http://127.0.0.1:{port}"
        try:
            got, _, _ = read_back("gs://ct_sharded.precomputed", "--level", "1")
            check(same(got, levels[1]), "gs://BUCKET: scale 1 voxel for voxel")
            pg = render("pc_gs_ooc", "precomputed://gs://ct_sharded.precomputed", "--level", "0",
                        "--memory-limit", "8M", "--tf", "100:1500")
            if pg and psr:
                check(psnr(pg, psr) >= 99, f"precomputed://gs://BUCKET: the render equals "
                      f"local's ({psnr(pg, psr):.1f} dB)")
        finally:
            del os.environ["STORAGE_EMULATOR_HOST"]
    finally:
        stop_server(nginx)


def refused(name, path, want):
    out = os.path.join(OUT, name + ".nrrd")
    p = volvis("convert", path, out, "--quiet")
    check(p.returncode != 0 and len(p.stderr.strip().splitlines()) == 1 and want in p.stderr and
          os.path.basename(path) in p.stderr and not os.path.exists(out),
          f"{name}: exit {p.returncode}, {p.stderr.strip()!r} (wants {want!r})")


# compressed_segmentation: uint32; uint64 in two channels with blocks that do not divide
# the chunk; uint64 in murmurhash3 shards with gzip
pcs = os.path.join(OUT, "cseg.precomputed")
pc_write(pcs, seg, (8, 8, 8), (16, 16, 16), encoding="compressed_segmentation",
         mtype="segmentation", compressed_segmentation_block_size=[8, 8, 8])
got, _, _ = read_back(pcs)
check(same(got, seg[..., 0]), "compressed_segmentation uint32: voxel for voxel")
seg2 = np.concatenate([seg.astype(np.uint64) + 2 ** 40, seg.astype(np.uint64) * 3], axis=3)
seg2[rng.random(seg2.shape) < 0.01] = 123456789
pcs2 = os.path.join(OUT, "cseg64.precomputed")
pc_write(pcs2, seg2, (8, 8, 8), (16, 16, 16), encoding="compressed_segmentation",
         mtype="segmentation", compressed_segmentation_block_size=[3, 5, 7])
for c in (0, 1):
    got, _, _ = read_back(pcs2, "--channel", str(c))
    check(same(got, seg2[..., c]), f"compressed_segmentation uint64, blocks 3 x 5 x 7: channel "
          f"{c} voxel for voxel")
pcs3 = os.path.join(OUT, "cseg_sharded.precomputed")
pc_write(pcs3, seg2[..., :1], (8, 8, 8), (16, 16, 16), encoding="compressed_segmentation",
         mtype="segmentation", compressed_segmentation_block_size=[4, 4, 4],
         sharding=sharding(pre=0, mini=1, shard=1))
got, _, _ = read_back(pcs3)
check(same(got, seg2[..., 0]), "compressed_segmentation in murmurhash3 shards: voxel for voxel")
p = volvis("info", pcs3)
check(p.returncode == 0 and "label" in p.stdout.lower(),
      f"compressed_segmentation: info says it is a label image: {p.stdout[:300]}")


def cseg_hostile(name, fn, want):
    d = os.path.join(OUT, f"badcseg_{name}.precomputed")
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(pcs, d)
    sd = os.path.join(d, "8_8_8")
    f = os.path.join(sd, sorted(os.listdir(sd))[0])
    with open(f, "rb") as fh:
        b = bytearray(fh.read())
    with open(f, "wb") as fh:
        fh.write(bytes(fn(b)))
    refused(f"badcseg_{name}", d, want)


def cseg_header(b, byte, v):
    at = 4 * int.from_bytes(b[0:4], "little") + byte  # the first block's header
    b[at] = v
    return b


cseg_hostile("offset", lambda b: b[:0] + (1 << 30).to_bytes(4, "little") + b[4:], "past the chunk")
cseg_hostile("bits", lambda b: cseg_header(b, 3, 3), "bits a value")
cseg_hostile("table", lambda b: cseg_header(cseg_header(cseg_header(b, 0, 255), 1, 255), 2, 255),
             "past the chunk")
cseg_hostile("ragged", lambda b: b[:-2], "32-bit words")


# hostile
def pc_hostile(name, make, want):
    d = os.path.join(OUT, f"badpc_{name}.precomputed")
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(os.path.join(OUT, "c3.precomputed"), d)
    make(d)
    refused(f"badpc_{name}", d, want)


def pc_info(d, fn):
    f = os.path.join(d, "info")
    with open(f) as fh:
        info = json.load(fh)
    fn(info)
    with open(f, "w") as fh:
        json.dump(info, fh)


def pc_chunk(d, fn):
    sd = os.path.join(d, "4_4_4")
    f = os.path.join(sd, sorted(os.listdir(sd))[0])
    with open(f, "rb") as fh:
        b = fh.read()
    with open(f, "wb") as fh:
        fh.write(fn(b))


pc_hostile("size", lambda d: pc_info(d, lambda i: i["scales"][0].update(size=[-1, 5, 5])),
           "size")
pc_hostile("huge", lambda d: pc_info(d, lambda i: i["scales"][0].update(size=[2 ** 50] * 3)),
           "size")
pc_hostile("chunk0", lambda d: pc_info(d, lambda i: i["scales"][0].update(
    chunk_sizes=[[0, 16, 8]])), "chunk_sizes")
pc_hostile("noscales", lambda d: pc_info(d, lambda i: i.update(scales=[])), "scales")
pc_hostile("dtype", lambda d: pc_info(d, lambda i: i.update(data_type="float16")), "float16")
pc_hostile("channels", lambda d: pc_info(d, lambda i: i.update(num_channels=0)), "num_channels")
pc_hostile("short", lambda d: pc_chunk(d, lambda b: b[:100]), "bytes")
pc_hostile("badgzip", lambda d: pc_chunk(d, lambda b: b"\x1f\x8b" + b[2:50]), "gzip")



# hostile shards: one shard of 4 minishards, raw indexes (identity hash)
def pc_shard_hostile(name, make, want):
    d = os.path.join(OUT, f"badshard_{name}.precomputed")
    shutil.rmtree(d, ignore_errors=True)
    pc_write(d, a3[..., :1], (4, 4, 4), (16, 16, 8), sharding=sharding("identity", "raw", 0, 2, 0))
    make(d)
    refused(f"badshard_{name}", d, want)


def shard_file(d, fn):
    f = os.path.join(d, "4_4_4", "0.shard")
    with open(f, "rb") as fh:
        b = bytearray(fh.read())
    with open(f, "wb") as fh:
        fh.write(bytes(fn(b)))


def set_u64(b, at, v):
    b[at:at + 8] = int(v).to_bytes(8, "little")
    return b


def sh_info(**kw):
    return lambda d: pc_info(d, lambda i: i["scales"][0]["sharding"].update(**kw))


pc_shard_hostile("bits", sh_info(shard_bits=65), "shard_bits")
pc_shard_hostile("sum", sh_info(minishard_bits=40, shard_bits=30), "over 64")
pc_shard_hostile("minibits", sh_info(minishard_bits=40, shard_bits=0), "minishard_bits")
pc_shard_hostile("hash", sh_info(hash="sha1"), "hash")
pc_shard_hostile("type", sh_info(**{"@type": "neuroglancer_uint64_sharded_v2"}), "sharding")
pc_shard_hostile("truncated", lambda d: shard_file(d, lambda b: b[:40]), "past its end")
# minishard 0's index ends past the shard; ends before it starts; two overlap
pc_shard_hostile("past", lambda d: shard_file(d, lambda b: set_u64(b, 56, len(b))),
                 "past its end")
pc_shard_hostile("backwards", lambda d: shard_file(
    d, lambda b: set_u64(set_u64(b, 0, 50), 8, 10)), "minishard 0")
pc_shard_hostile("overlap", lambda d: shard_file(
    d, lambda b: set_u64(b, 16, int.from_bytes(b[0:8], "little"))), "overlap")
# a minishard index of a size not 24 a chunk; a chunk whose bytes overlap its index, or
# run past the shard
pc_shard_hostile("ragged", lambda d: shard_file(
    d, lambda b: set_u64(b, 8, int.from_bytes(b[8:16], "little") - 5)), "24 a chunk")


def chunk_set(b, row, v):
    lo = 64 + int.from_bytes(b[0:8], "little")
    n = (int.from_bytes(b[8:16], "little") - int.from_bytes(b[0:8], "little")) // 24
    return set_u64(b, lo + 8 * row * n, v)  # chunk 0's offset (row 1) or size (row 2)


pc_shard_hostile("chunkbig", lambda d: shard_file(d, lambda b: chunk_set(b, 2, 1 << 40)),
                 "overlap the minishard index")
pc_shard_hostile("chunkpast", lambda d: shard_file(d, lambda b: chunk_set(b, 1, 1 << 40)),
                 "past its end")

check.finish("n5_precomputed_cli")
