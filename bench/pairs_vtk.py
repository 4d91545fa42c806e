#!/usr/bin/python3
"""Same-run pairs of VTK's fixed-point ray caster and VolVis's ray caster.

The machines these benchmarks run on are shared and their speed drifts over
seconds, so a ratio is only meaningful between two measurements taken back
to back. This script alternates ../shared/anchors/bench_vtk.py (VTK 9.1,
vtkFixedPointVolumeRayCastMapper) and build/release/bench/bench_raycast on
the same volume and view (the shared view of ../shared/BENCHMARKS.md), N
times, and prints every pair's frame times and VTK/VolVis ratio for
composite and MIP, the iso frame beside them, the medians, and the load
average before each pair.

usage: bench/pairs_vtk.py VOLUME [--pairs N] [--runs N] [--threads N]
                          [--iso V] [--tf-lo A] [--tf-hi B]
                          [--quality Q] [--option KEY=VALUE]...
                          [--bench PATH] [--anchors DIR]

Use Debian's /usr/bin/python3 (it has vtk and numpy). Output lines are the
`anchor=... op=... value=...` lines of both programs (for
../shared/anchors/summarize.py) followed by lines starting with '#'.
"""
import argparse
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("volume")
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--runs", type=int, default=5, help="frames per median")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--iso", type=float)
    ap.add_argument("--tf-lo", type=float)
    ap.add_argument("--tf-hi", type=float)
    ap.add_argument("--quality", type=int, default=2, help="VolVis quality level (0..2)")
    ap.add_argument("--option", action="append", default=[],
                    help="VolVis renderer option KEY=VALUE (repeatable)")
    ap.add_argument("--bench", default=os.path.join(ROOT, "build/release/bench/bench_raycast"))
    ap.add_argument("--anchors", default=os.path.join(os.path.dirname(ROOT), "shared/anchors"))
    return ap.parse_args()


def values(text):
    """{op: value} of the anchor lines in text."""
    out = {}
    for line in text.splitlines():
        if not line.startswith("anchor="):
            continue
        f = dict(kv.split("=", 1) for kv in line.split())
        out[f["op"]] = float(f["value"])
    return out


def run(cmd, cwd=None):
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd)
    if p.returncode != 0:
        sys.exit("pairs_vtk: %s failed (%d): %s" % (cmd[0], p.returncode, p.stderr.strip()[-500:]))
    return p.stdout


def main():
    a = parse_args()
    a.volume = os.path.abspath(a.volume)
    out_dir = os.path.join(ROOT, "build/bench-out")
    os.makedirs(out_dir, exist_ok=True)
    if not a.volume.endswith(".nrrd"):
        # the VTK anchor reads NRRD only: convert once with volvis itself
        nrrd = os.path.join(out_dir, os.path.basename(a.volume).split(".")[0] + ".nrrd")
        run([os.path.join(ROOT, "build/release/volvis"), "convert", a.volume, nrrd])
        a.volume = nrrd
    common = []
    for opt, v in (("--iso", a.iso), ("--tf-lo", a.tf_lo), ("--tf-hi", a.tf_hi)):
        if v is not None:
            common += [opt, repr(v)]
    vtk_cmd = [sys.executable, os.path.join(a.anchors, "bench_vtk.py"), a.volume, "--mappers",
               "fixedpoint", "--threads", str(a.threads), "--no-iso", "--runs", str(a.runs)] + common
    vv_cmd = [a.bench, a.volume, "--threads", str(a.threads), "--runs", str(a.runs),
              "--modes", "composite,mip,iso", "--outdir", out_dir,
              "--quality", str(a.quality)] + common
    for o in a.option:
        vv_cmd += ["--option", o]
    ratios = {"composite": [], "mip": [], "composite_first": []}
    iso = []
    for i in range(a.pairs):
        load = open("/proc/loadavg").read().split()[0]
        vt = run(vtk_cmd, cwd=out_dir)  # it writes anchors_out/ where it runs
        vv = run(vv_cmd)
        sys.stdout.write(vt + vv)
        v, w = values(vt), values(vv)
        line = "# pair %d (load %s):" % (i + 1, load)
        for m in ("composite", "mip"):
            t_vtk = v["dvr_fixedpoint_%s_frame" % m]
            t_vv = w["dvr_%s_frame" % m]
            ratios[m].append(t_vtk / t_vv)
            line += " %s VTK %.4f s VolVis %.4f s = %.2fx;" % (m, t_vtk, t_vv, t_vtk / t_vv)
        ratios["composite_first"].append(v["dvr_fixedpoint_composite_first_frame"] /
                                         w["dvr_composite_first_frame"])
        iso.append(w["dvr_iso_frame"])
        line += " composite first frame %.2fx; iso %.4f s" % (ratios["composite_first"][-1], iso[-1])
        print(line, flush=True)
    print("# %s, %d pairs, %d threads: median VTK/VolVis composite %.2fx, first frame %.2fx, "
          "MIP %.2fx; VolVis iso frame median %.4f s" %
          (os.path.basename(a.volume), a.pairs, a.threads, statistics.median(ratios["composite"]),
           statistics.median(ratios["composite_first"]), statistics.median(ratios["mip"]),
           statistics.median(iso)))


if __name__ == "__main__":
    main()
