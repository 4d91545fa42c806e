#!/usr/bin/python3
"""`volvis render --channels` on files written by tifffile (issue 30).

  channels_cli.py VOLVIS OUTDIR

Writes, with numpy and tifffile, an OME-TIFF of three channels (CZYX, a
ball per channel at a known place, named channels) and an ImageJ
hyperstack of two channels and two time points (TZCYX), then checks:

- the voxels of every channel read back through `volvis convert --channel C`
  to NIfTI equal tifffile's array (read with nibabel);
- every blend rule shows each channel's colour at its ball and only there
  (the balls' image centroids, in order along x);
- additive equals the sum of the one-channel images (PNG, within 8-bit
  rounding), maximum the sum of the one-channel MIPs;
- --label-channels: a label channel shows each label in the colour the
  one-channel `--labels` render gives it;
- bad input: a channel the file lacks, an unknown colour or rule, --channel
  with --channels, colours beyond the channels, --channels on a scene: one
  line naming the problem, a non-zero exit, no image written.

Exit 0 passed, 1 failed, 77 skipped (a module missing).
"""
import os
import subprocess
import sys

try:
    import numpy as np
    import nibabel as nib
    import tifffile
    from PIL import Image
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-numpy, python3-nibabel, python3-tifffile, python3-pil)")
    sys.exit(77)

VOLVIS, OUT = sys.argv[1], sys.argv[2]
os.makedirs(OUT, exist_ok=True)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def volvis(*args):
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True)


def render(name, *args):
    path = os.path.join(OUT, name + ".png")
    p = volvis("render", *args, "-o", path, "--size", "192x192", "--ortho", "-q")
    if p.returncode != 0:
        raise SystemExit(f"FAIL volvis render {' '.join(args)}: {p.stderr.strip()}")
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


Z, Y, X = 24, 32, 72
z, y, x = np.mgrid[0:Z, 0:Y, 0:X]
CENTRES = (14, 36, 58)


def ball(cx, r=8):
    inside = (x - cx) ** 2 + (y - 16) ** 2 + (z - 12) ** 2 <= r * r
    return (inside * 900 + 40 + (x % 3)).astype(np.uint16)  # a faint texture outside


ome = os.path.join(OUT, "cells.ome.tif")
cells = np.stack([ball(c) for c in CENTRES])  # CZYX
tifffile.imwrite(ome, cells, ome=True, metadata={
    "axes": "CZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 1.0,
    "Channel": {"Name": ["nuclei", "membrane", "protein"]}})
hyper = os.path.join(OUT, "hyper.tif")
stack = np.stack([np.stack([ball(CENTRES[0]), ball(CENTRES[2])], axis=1) + 7 * t
                  for t in range(2)])  # TZCYX
tifffile.imwrite(hyper, stack, imagej=True, metadata={"axes": "TZCYX"})

# the voxels of every channel, through NIfTI and nibabel
for path, arrays in ((ome, [cells[c] for c in range(3)]),
                     (hyper, [stack[0, :, c] for c in range(2)])):
    for c, want in enumerate(arrays):
        nii = os.path.join(OUT, f"{os.path.basename(path)}_{c}.nii")
        p = volvis("convert", path, nii, "--channel", str(c), "--quiet")
        if p.returncode != 0:
            check(False, f"convert {os.path.basename(path)} --channel {c}: {p.stderr.strip()}")
            continue
        got = np.asarray(nib.load(nii).dataobj).transpose(2, 1, 0)  # x, y, z -> z, y, x
        check(got.shape == want.shape and np.array_equal(got, want),
              f"{os.path.basename(path)} channel {c}: the voxels tifffile wrote")


def dominant(img, k):
    """Pixels where colour component k is bright and the others dark."""
    others = [j for j in range(3) if j != k]
    return (img[..., k] > 40) & (img[..., others[0]] < 8) & (img[..., others[1]] < 8)


for rule in ("composite", "additive", "maximum"):
    img = render(f"balls_{rule}", ome, "--channels", "0,1,2", "--colors", "red,green,blue",
                 "--blend", rule)
    xs = []
    for k in range(3):
        m = dominant(img, k)
        check(m.sum() > 50, f"{rule}: channel {k}'s colour shows ({m.sum()} pixels)")
        xs.append(np.nonzero(m)[1].mean() if m.sum() else np.nan)
    # the default view looks along +y from the front: x runs right to left
    check(xs[0] > xs[1] > xs[2], f"{rule}: the balls in order along x (centroids {xs})")
    # every lit pixel's strongest colour is the channel of the nearest ball
    # (a white highlight adds to every component alike)
    lit = np.nonzero(img.max(axis=2) > 40)
    nearest = np.argmin(np.abs(lit[1][:, None] - np.array(xs)[None, :]), axis=1)
    strongest = np.argmax(img[lit], axis=1)
    wrong = int((nearest != strongest).sum())
    check(wrong <= 0.02 * len(nearest),
          f"{rule}: a channel's colour only at its ball ({wrong} of {len(nearest)} lit pixels "
          "elsewhere)")

# additive = sum of the one-channel images; maximum = sum of the one-channel MIPs
colors = ["magenta", "green", "#00ffff"]
for rule in ("additive", "maximum"):
    both = render(f"sum_{rule}", ome, "--channels", "0,1,2", "--colors", ",".join(colors),
                  "--blend", rule, "--contrast", "40:600,40:600,40:600")
    total = sum(render(f"one_{rule}_{c}", ome, "--channels", str(c), "--colors", colors[c],
                       "--blend", rule, "--contrast", "40:600") for c in range(3))
    d = np.abs(both - np.minimum(total, 255)).max()
    check(d <= 2, f"{rule}: the sum of the one-channel images (largest difference {d} of 255)")

# the hyperstack: its two channels (the first time point)
img = render("hyper", hyper, "--channels", "0,1", "--colors", "magenta,green",
             "--blend", "maximum")
check((img[..., 1] > 40).sum() > 50 and ((img[..., 0] > 40) & (img[..., 2] > 40)).sum() > 50,
      "ImageJ hyperstack: both channels show")

# a label volume as a channel (--label-channels): each label's region in the
# colour the one-channel --labels render gives it, the other channel its own
lab = os.path.join(OUT, "labels.ome.tif")
labels = np.zeros((Z, Y, X), np.uint16)
labels[6:18, 8:24, 30:42] = 3
labels[6:18, 8:24, 50:62] = 7
tifffile.imwrite(lab, np.stack([ball(CENTRES[0]), labels]), ome=True,
                 metadata={"axes": "CZYX"})
both = render("label_channel", lab, "--channels", "0,1", "--label-channels", "1",
              "--colors", "red")
alone = render("label_alone", lab, "--channel", "1", "--labels")
box = alone.max(axis=2) > 40
d = np.abs(both[box] - alone[box]).max() if box.any() else 999
check(box.sum() > 200 and d <= 3,
      f"--label-channels: the labels' colours as --labels draws them ({box.sum()} pixels, "
      f"largest difference {d})")
check(dominant(both, 0).sum() > 50, "--label-channels: the other channel still in its colour")
two = {tuple(c) for c in alone[box][:, :3] // 16}
check(len(two) >= 2, f"--label-channels: two labels, two colours ({len(two)} seen)")

# colours alone (issue 66; napari's colormap=[...]): every channel of the file in order,
# the image of --channels 0,1,2 with the same colours; a blend rule alone too
alone = render("colors_alone", ome, "--colors", "red,green,blue", "--blend", "maximum")
listed = render("colors_listed", ome, "--channels", "0,1,2", "--colors", "red,green,blue",
                "--blend", "maximum")
check(np.array_equal(alone, listed) and all(dominant(alone, k).sum() > 50 for k in range(3)),
      "--colors without --channels: every channel, as --channels 0,1,2 draws them")
check(np.array_equal(render("blend_alone", ome, "--blend", "additive"),
                     render("blend_listed", ome, "--channels", "0,1,2", "--blend", "additive")),
      "--blend without --channels: every channel")

# bad input: one line, non-zero exit, no image
bad = [
    ([lab, "--channels", "0,1", "--label-channels", "5"], "not in --channels", 2),
    ([lab, "--label-channels", "1"], "only with --channels", 2),
    ([ome, "--channels", "0,5"], "channel 5", 1),
    ([ome, "--channels", "0,1", "--colors", "red,purple"], "purple", 2),
    ([ome, "--channels", "0,1", "--blend", "sum"], "sum", 2),
    ([ome, "--channel", "1", "--channels", "0,1"], "--channels", 2),
    ([ome, "--channels", "0,1", "--colors", "red,green,blue"], "3 given for 2 channels", 2),
    ([ome, "--colors", "red,green,blue,white"], "4 given for the file's 3 channels", 2),
    ([ome, "--colors", "red", "--channel", "1"], "not with --channel C", 2),
    ([ome, "--channels", "0,0"], "twice", 2),
    ([ome, "--channels", "0,1", "--mode", "mip"], "--blend", 2),
]
scene = os.path.join(OUT, "scene.json")
with open(scene, "w") as f:
    f.write('{"objects": []}')
bad.append(([scene, "--channels", "0,1"], "not a scene", 1))
bad.append(([scene, "--colors", "red"], "--colors is for a volume file's channels", 1))
for args, needle, code in bad:
    out = os.path.join(OUT, "bad.png")
    if os.path.exists(out):
        os.remove(out)
    p = volvis("render", *args, "-o", out, "-q")
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    check(p.returncode == code and needle in p.stderr and not os.path.exists(out)
          and len(lines) <= 2,
          f"render {' '.join(args[1:])}: exit {p.returncode}, {p.stderr.strip()!r}")

# the OME-TIFF's channels out of core together (its store, tile by tile,
# issue 91): as in memory
for name, args in (("max", ["--blend", "maximum"]), ("two", ["--channels", "0,1"])):
    a = render(f"ooc_{name}_mem", ome, *args)
    b = render(f"ooc_{name}", ome, *args, "--memory-limit", "1G", "--level", "0")
    mse = ((a - b) ** 2).mean()
    d = 99.0 if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)
    check(d >= 50, f"{' '.join(args)} --memory-limit 1G: {d:.1f} dB from in memory (>= 50)")

if failures:
    print(f"{len(failures)} failed")
    sys.exit(1)
print("all passed")
