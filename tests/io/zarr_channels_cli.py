#!/usr/bin/env python3
"""Every channel out of core: the channels of OME-Zarr pyramids drawn together by level of
detail, against the same channels drawn in memory.

  zarr_channels_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test). The stores are written
by the reference implementations, not by VolVis:

- zarr-python 3: an NGFF 0.5 pyramid of 3 u16 channels (c, z, y, x; 3 levels; shards of
  32^3 holding inner chunks of 16^3; zstd), once chunked one channel a chunk (c = 1, the
  NGFF default) and once with every channel in a chunk (c = 3); omero names, colours and
  windows;
- ome-zarr-py (NGFF 0.5, levels halving y and x only) and ngff-zarr (NGFF 0.5, sharded),
  3 channels each, without omero windows (the contrast then comes from the coarsest level);
- zarr-python 3: a t, c, z, y, x store of 2 time steps (step 1 moved along x).

Checks, each image looked at as the difference of two renders (PSNR):

- `--channels 0,1,2 --memory-limit 8M --level 0` (the level-of-detail driver, every
  channel of a node read once) against the in-memory frame of the same level, by blend
  rule: composite and additive >= 50 dB, maximum >= 60 dB, for every store;
- a store chunked c = 3 reads its chunks once for all channels: the bytes read within
  1.2x of the store's files of the levels read (3x when each channel decoded its own);
- without --channels a store of several channels draws them all in their colours, as
  --channels 0,1,2 does (in memory and out of core alike);
- `--lod` at a coarse level shows every channel's colour;
- a label channel beside an intensity channel: out of core as in memory;
- time step 1 of the t, c, z, y, x store out of core >= 50 dB from step 1 in memory (and
  not step 0);
- raytrace (shadows through every channel) >= 50 dB from itself in memory; the gpu
  renderer (lavapipe) out of core >= 45 dB from raycast in memory;
- mpirun -n 2: each rank reads its box of every channel from the pyramid, the additive
  and maximum rules a pass a channel composited over the ranks: >= 60 dB from one
  process in memory;
- omero "active": false hides a channel, as leaving it out of --channels does (>= 50 dB);
- bad input: more than 16 channels asked, a channel the store does not have, a channel
  axis chunked differently at two levels: one line naming the store, a non-zero exit, no
  output written and an existing output untouched; omero windows that are NaN, inverted
  or absurd: a warning naming the window, the image drawn with the defaults.
"""
import json
import os
import re
import shutil
import subprocess
import sys

try:
    import numpy as np
    import zarr
    from PIL import Image
    from zarr.codecs import ZstdCodec
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Checks, run  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
check = Checks()
SIZE = ["--size", "200x160"]
Z, Y, X = 48, 64, 80


def volvis(*args):
    return run(VOLVIS, *args)


def channels_data(rng):
    """3 u16 channels (c, z, y, x): a blob each, in different places and sizes, plus noise."""
    zz, yy, xx = np.mgrid[0:Z, 0:Y, 0:X].astype(np.float32)
    out = []
    for c, (cz, cy, cx) in enumerate([(16, 24, 24), (30, 40, 50), (24, 30, 62)]):
        b = 3000 * np.exp(-((zz - cz) ** 2 + (yy - cy) ** 2 + (xx - cx) ** 2) / (90 + 60 * c))
        out.append(b.astype(np.uint16) + rng.integers(0, 60, size=b.shape, dtype=np.uint16))
    return np.stack(out)


def halve(a):
    """2x2x2 means of the last three axes (floor), rounded."""
    s = [d // 2 * 2 for d in a.shape[-3:]]
    q = a[..., :s[0], :s[1], :s[2]].astype(np.float64).reshape(
        *a.shape[:-3], s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2)
    return np.rint(q.mean(axis=(-5, -3, -1))).astype(a.dtype)


OMERO = [{"label": "dapi", "color": "0000FF", "active": True,
          "window": {"min": 0, "max": 4000, "start": 80, "end": 2600}},
         {"label": "gfp", "color": "00FF00", "active": True,
          "window": {"min": 0, "max": 4000, "start": 80, "end": 2600}},
         {"label": "rfp", "color": "FF0000", "active": True,
          "window": {"min": 0, "max": 4000, "start": 80, "end": 2600}}]


def zp_store(name, arr, cchunk, omero=OMERO, time=False, level_cchunks=None):
    """An NGFF 0.5 pyramid at OUT/name written by zarr-python 3: 3 levels of arr (c, z, y, x;
    with time t first), shards of 32^3 of inner chunks of 16^3 and cchunk channels, zstd;
    level_cchunks: the channel chunking of each level (a hostile store)."""
    path = os.path.join(OUT, name)
    g = zarr.open_group(path, mode="w")
    lv, ds = arr, []
    lead = (1,) if time else ()
    for k in range(3):
        cc = level_cchunks[k] if level_cchunks else cchunk
        a = g.create_array(str(k), shape=lv.shape, dtype=lv.dtype, chunks=lead + (cc, 16, 16, 16),
                           shards=lead + (cc, 32, 32, 32), compressors=ZstdCodec(level=3))
        a[:] = lv
        f = 2.0 ** k
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": list(lead) + [1.0, 0.5 * f, 0.5 * f, 0.5 * f]},
            {"type": "translation", "translation": [0.0] * len(lead) + [0.0] +
             [0.5 * (f - 1) / 2] * 3}]})
        lv = halve(lv)
    axes = ([{"name": "t", "type": "time", "unit": "second"}] if time else []) + \
        [{"name": "c", "type": "channel"}] + \
        [{"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"]
    ome = {"version": "0.5", "multiscales": [{"axes": axes, "datasets": ds}]}
    if omero is not None:
        ome["omero"] = {"channels": omero}
    g.attrs["ome"] = ome
    return path


def image(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.float64)


def psnr(a, b):
    m = ((image(a) - image(b)) ** 2).mean()
    return 99.0 if m == 0 else 10 * np.log10(255.0 ** 2 / m)


def render(name, store, *args):
    """volvis render STORE ARGS at SIZE into OUT/name.png; (path, its stdout + stderr) or
    (None, ...) when it failed (a failed check)."""
    out = os.path.join(OUT, name + ".png")
    p = volvis("render", store, "-o", out, *SIZE, *args)
    ok = p.returncode == 0 and os.path.exists(out)
    if not ok:
        check(False, f"render {name}: exit {p.returncode}: {p.stderr.strip()}")
    return (out if ok else None), p.stdout + p.stderr


def mib_read(text):
    m = re.search(r"([0-9.]+) MiB read", text)
    return float(m.group(1)) if m else None


def store_mib(path, levels):
    """MiB of the files of these levels of the store at path."""
    n = 0
    for lv in levels:
        for root, _, files in os.walk(os.path.join(path, str(lv))):
            n += sum(os.path.getsize(os.path.join(root, f)) for f in files)
    return n / 2 ** 20


def pair(name, store, blend, want, *extra):
    """In memory against out of core, --level 0, the blend rule; >= want dB."""
    args = ["--channels", "0,1,2", "--blend", blend, "--level", "0", *extra]
    mem, _ = render(f"{name}_{blend}_mem", store, *args, "--set", "refinement=off")
    ooc, text = render(f"{name}_{blend}_ooc", store, *args, "--memory-limit", "8M")
    if mem and ooc:
        d = psnr(mem, ooc)
        check(d >= want, f"{name}, {blend}: out of core {d:.1f} dB from in memory (>= {want})")
    return ooc, text


rng = np.random.default_rng(89)
data = channels_data(rng)

# ---- zarr-python 3: c = 1 and c = 3 ---------------------------------------------------------------
c1 = zp_store("c1.ome.zarr", data, 1)
c3 = zp_store("c3.ome.zarr", data, 3)
for name, store in (("c1", c1), ("c3", c3)):
    reads = {}
    for blend, want in (("composite", 50), ("additive", 50), ("maximum", 60)):
        ooc, text = pair(name, store, blend, want)
        reads[blend] = mib_read(text)
    # the frame reads level 0 and the proxy level 2: each chunk once for every channel
    files = store_mib(store, (0, 2))
    got = reads["composite"]
    check(got is not None and got <= 1.2 * files + 0.05,
          f"{name}: {got} MiB read for the frame, the store's levels 0 and 2 are {files:.2f} MiB "
          f"(<= 1.2x)")

# every channel by default, as --channels 0,1,2 draws them (composite)
for how, extra in (("in memory", []), ("out of core", ["--memory-limit", "8M", "--level", "0"])):
    dflt, _ = render(f"default_{how[:3]}", c1, *extra)
    listed, _ = render(f"listed_{how[:3]}", c1, "--channels", "0,1,2", *extra)
    check(dflt and listed and psnr(dflt, listed) >= 99,
          f"{how}: a store of 3 channels opened without --channels draws all of them")

# a label channel (segment ids) beside an intensity channel: its labels' colours over nodes
# out of core as in memory
zz, yy, xx = np.mgrid[0:Z, 0:Y, 0:X]
labels = np.zeros((Z, Y, X), np.uint16)
for k, (cz, cy, cx) in enumerate([(14, 20, 20), (30, 40, 48), (24, 28, 64)]):
    labels[(zz - cz) ** 2 + (yy - cy) ** 2 + (xx - cx) ** 2 < 64] = k + 1
lab = zp_store("labels.ome.zarr", np.stack([data[0], labels]), 1, omero=OMERO[:2])
args = ["--channels", "0,1", "--label-channels", "1", "--level", "0"]
mem, _ = render("labels_mem", lab, *args, "--set", "refinement=off")
ooc, _ = render("labels_ooc", lab, *args, "--memory-limit", "8M")
# the control: the label channel alone as a label volume (--labels), out of core against in
# memory; hard-edged labels render by regions at 35-40 dB even so (a sample's rounding moves a
# boundary by a step), where smooth channels give 65 dB
one_mem, _ = render("label_one_mem", lab, "--channel", "1", "--labels", "--level", "0",
                    "--set", "refinement=off")
one_ooc, _ = render("label_one_ooc", lab, "--channel", "1", "--labels", "--level", "0",
                    "--memory-limit", "8M")
if mem and ooc and one_mem and one_ooc:
    d, control = psnr(mem, ooc), psnr(one_mem, one_ooc)
    lit = image(ooc).max(axis=2) > 40
    check(d >= 35 and d >= control - 3 and lit.mean() > 0.01,
          f"a label channel out of core: {d:.1f} dB from in memory (>= 35, and >= the label "
          f"volume alone's {control:.1f} dB - 3), {100 * lit.mean():.1f} % of the pixels lit")

# a coarse level of detail: every channel in its colour (blue, green, red)
coarse, text = render("lod_coarse", c1, "--memory-limit", "8M", "--lod", "40")
if coarse:
    img = image(coarse)
    peak = img.reshape(-1, 3).max(axis=0)
    check(all(peak > 60) and re.search(r"2: [1-9]\d* nodes", text) is not None,
          f"--lod 40 draws level 2 with every channel's colour (peaks R, G, B {peak})")

# ---- ome-zarr-py and ngff-zarr ------------------------------------------------------------------
try:
    from ome_zarr.format import FormatV05
    from ome_zarr.writer import write_image
except ImportError as e:  # pragma: no cover
    write_image = None
    check(False, f"ome-zarr-py is importable ({e})")
if write_image:
    path = os.path.join(OUT, "omezarr.ome.zarr")
    g = zarr.open_group(path, mode="w")
    write_image(data, g, scale_factors=[2, 4], axes="czyx", fmt=FormatV05(),
                storage_options={"chunks": (1, 16, 16, 16)})
    check(json.load(open(os.path.join(path, "zarr.json")))["attributes"]["ome"]["version"]
          == "0.5", "ome-zarr-py wrote NGFF 0.5")
    for blend, want in (("composite", 50), ("additive", 50), ("maximum", 60)):
        pair("omezarr", path, blend, want)
try:
    import ngff_zarr as nz
except ImportError as e:  # pragma: no cover
    nz = None
    check(False, f"ngff-zarr is importable ({e})")
if nz:
    image_nz = nz.to_ngff_image(data, dims=["c", "z", "y", "x"],
                                scale={"z": 0.5, "y": 0.5, "x": 0.5})
    ms = nz.to_multiscales(image_nz, scale_factors=[2, 4], chunks=16)
    path = os.path.join(OUT, "ngff.ome.zarr")
    nz.to_ngff_zarr(path, ms, version="0.5", chunks_per_shard=2)
    for blend, want in (("composite", 50), ("additive", 50), ("maximum", 60)):
        pair("ngff", path, blend, want)

# ---- time: step 1 of a t, c, z, y, x store --------------------------------------------------------
tdata = np.stack([data, np.roll(data, 9, axis=3)])
tstore = zp_store("tczyx.ome.zarr", tdata, 1, time=True)
t1m, _ = render("t1_mem", tstore, "--time", "1", "--level", "0", "--set", "refinement=off")
t1o, _ = render("t1_ooc", tstore, "--time", "1", "--level", "0", "--memory-limit", "8M")
t0o, _ = render("t0_ooc", tstore, "--time", "0", "--level", "0", "--memory-limit", "8M")
if t1m and t1o and t0o:
    d1, d0 = psnr(t1m, t1o), psnr(t1m, t0o)
    check(d1 >= 50 and d0 < 40,
          f"time step 1 out of core {d1:.1f} dB from in memory (>= 50); step 0 {d0:.1f} dB (< 40)")

# ---- raytrace and gpu ---------------------------------------------------------------------------
rtm, _ = render("rt_mem", c1, "--renderer", "raytrace", "--level", "0")
rto, _ = render("rt_ooc", c1, "--renderer", "raytrace", "--level", "0", "--memory-limit", "8M")
if rtm and rto:
    d = psnr(rtm, rto)
    check(d >= 50, f"raytrace (shadows through the channels): out of core {d:.1f} dB from in "
          f"memory (>= 50)")
cpu, _ = render("gpu_ref", c1, "--level", "0", "--set", "refinement=off")
gpu, text = render("gpu_ooc", c1, "--renderer", "gpu", "--level", "0", "--memory-limit", "8M")
if cpu and gpu:
    d = psnr(cpu, gpu)
    check(d >= 45, f"gpu (lavapipe) out of core {d:.1f} dB from raycast in memory (>= 45)")

# ---- MPI: each rank's box with all its channels, read from the pyramid ----------------------------
mpirun = shutil.which("mpirun")
if mpirun:
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    env["HWLOC_COMPONENTS"] = "-gl"
    mpi = [mpirun, "--oversubscribe", "-n", "2", "-x", "ASAN_OPTIONS=detect_leaks=0:"
           "abort_on_error=1"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    for blend, want in (("composite", 60), ("additive", 60), ("maximum", 60)):
        ref, _ = render(f"mpi_ref_{blend}", c1, "--blend", blend, "--level", "0",
                        "--set", "refinement=off")
        out = os.path.join(OUT, f"mpi_{blend}.png")
        p = subprocess.run(mpi + [VOLVIS, "render", c1, "-o", out, *SIZE, "--blend", blend],
                           capture_output=True, text=True, env=env, timeout=300)
        ok = p.returncode == 0 and os.path.exists(out) and ref
        d = psnr(ref, out) if ok else 0
        check(ok and "2 ranks" in p.stdout and d >= want,
              f"mpirun -n 2, {blend}: each rank's box of every channel, {d:.1f} dB from one "
              f"process (>= {want}) {p.stderr.strip()[-300:]}")
else:
    check(False, "mpirun is installed (openmpi-bin)")

# ---- omero active: false ----------------------------------------------------------------------
inactive = [dict(c) for c in OMERO]
inactive[1]["active"] = False
istore = zp_store("inactive.ome.zarr", data, 1, omero=inactive)
hid, _ = render("inactive_ooc", istore, "--memory-limit", "8M", "--level", "0")
two, _ = render("two_ooc", c1, "--channels", "0,2", "--memory-limit", "8M", "--level", "0")
if hid and two:
    d = psnr(hid, two)
    check(d >= 50, f"omero active false hides the channel as --channels 0,2 leaves it out "
          f"({d:.1f} dB)")

# ---- bad input ------------------------------------------------------------------------------------
mixed = zp_store("mixed_c.ome.zarr", data, 1, level_cchunks=(3, 1, 1))
seventeen = ",".join(str(i) for i in range(17))
bad = [
    ([c1, "--channels", seventeen, "--memory-limit", "8M"], "16", "17 channels asked"),
    ([c1, "--channels", "0,5", "--memory-limit", "8M"], "channel 5", "a channel it does not have"),
    ([mixed, "--memory-limit", "8M"], "channel axis", "channel axes chunked differently"),
    ([mixed, "--channels", "0,1"], "channel axis", "channel axes chunked differently, in memory"),
]
target = os.path.join(OUT, "kept.png")
for args, needle, what in bad:
    with open(target, "wb") as f:
        f.write(b"not overwritten")
    p = volvis("render", *args, "-o", target, *SIZE)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    kept = open(target, "rb").read() == b"not overwritten"
    names = os.path.basename(args[0]) in p.stderr
    check(p.returncode != 0 and needle in p.stderr and len(lines) == 1 and kept and
          (names or needle == "16"),
          f"{what}: exit {p.returncode}, one line naming the store, output untouched "
          f"({p.stderr.strip()!r})")
leftovers = [f for f in os.listdir(OUT) if ".tmp-" in f]
check(not leftovers, f"no temporaries left behind ({leftovers})")

for label, window, needle in (
        ("nan", '{"min": 0, "max": 4000, "start": NaN, "end": 2600}', "not two finite numbers"),
        ("inverted", '{"min": 0, "max": 4000, "start": 2600, "end": 80}', "inverted"),
        ("absurd", '{"min": 0, "max": 4000, "start": 80, "end": 1e30}',
         "beyond what the voxel type holds")):
    path = zp_store(f"window_{label}.ome.zarr", data, 1)
    meta = os.path.join(path, "zarr.json")
    text = open(meta).read()
    root = json.loads(text)
    root["attributes"]["ome"]["omero"]["channels"][1]["window"] = "@@WINDOW@@"
    # Python's json writes NaN bare, as zarr-python writes user attributes
    open(meta, "w").write(json.dumps(root).replace('"@@WINDOW@@"', window))
    out = os.path.join(OUT, f"window_{label}.png")
    p = volvis("render", path, "-o", out, *SIZE, "--memory-limit", "8M")
    check(p.returncode == 0 and os.path.exists(out) and "warning" in p.stderr and
          needle in p.stderr and "channel 1" in p.stderr,
          f"omero window {label}: drawn, with a warning ({p.stderr.strip()!r})")

check.finish("zarr_channels_cli")
