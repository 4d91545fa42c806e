#!/usr/bin/python3
"""Same-run pairs of VTK's CPU ray casters and VolVis's ray caster.

The machines these benchmarks run on are shared and their speed drifts over
seconds, so a ratio is only meaningful between two measurements taken back
to back. This script alternates ../shared/anchors/bench_vtk.py (through
bench/vtk_peer.py: vtkFixedPointVolumeRayCastMapper, and with --mappers
fixedpoint,smart also vtkSmartVolumeMapper held to its CPU path) and
build/release/bench/bench_raycast on the same volume and view (the shared
view of ../shared/BENCHMARKS.md), N times, and prints every pair's frame
times and VTK/VolVis ratio for composite and MIP, the iso frame beside
them, the medians, the load average before each pair and the CPU seconds
per frame of both sides (their cpu_per_wall times the frame).

usage: bench/pairs_vtk.py VOLUME [--pairs N] [--runs N] [--threads N]
                          [--iso V] [--tf-lo A] [--tf-hi B]
                          [--quality Q] [--option KEY=VALUE]...
                          [--vtk venv|debian|PYTHON] [--mappers LIST]
                          [--bench PATH] [--bench-b PATH] [--anchors DIR]

--bench-b names a second bench_raycast (another build, e.g. main's) that
runs right after the first in every pair, so that two builds are compared
with each other and with VTK in the same run ("B" in the output).
--vtk picks the VTK: `venv` (the default) is VTK 9.7 from PyPI in the
repository's .venv (scripts/install-deps.sh bench), rendering offscreen
through EGL; `debian` is Debian's VTK 9.1 (/usr/bin/python3, python3-vtk9,
under xvfb-run without $DISPLAY); anything else is the Python to use. The
script itself needs only the standard library. Output lines are the
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
    ap.add_argument("--vtk", default="venv",
                    help="venv (VTK 9.7, .venv), debian (VTK 9.1, /usr/bin/python3) or a Python")
    ap.add_argument("--mappers", default="fixedpoint",
                    help="VTK mappers, comma-separated: fixedpoint, smart (its CPU path)")
    ap.add_argument("--bench", default=os.path.join(ROOT, "build/release/bench/bench_raycast"))
    ap.add_argument("--bench-b", default=None, help="a second bench_raycast, run in every pair")
    ap.add_argument("--anchors", default=os.path.join(os.path.dirname(ROOT), "shared/anchors"))
    return ap.parse_args()


def vtk_python(choice):
    """The interpreter whose VTK is measured (--vtk)."""
    py = {"venv": os.path.join(ROOT, ".venv/bin/python"), "debian": "/usr/bin/python3"}.get(
        choice, choice)
    if not os.path.exists(py):
        sys.exit("pairs_vtk: %s: no such Python for --vtk %s (scripts/install-deps.sh bench "
                 "makes .venv)" % (py, choice))
    return py


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
    mappers = [m for m in a.mappers.split(",") if m]
    for m in mappers:
        if m not in ("fixedpoint", "smart"):
            sys.exit("pairs_vtk: --mappers: unknown mapper '%s' (fixedpoint, smart)" % m)
    vtk_cmd = [vtk_python(a.vtk), os.path.join(HERE, "vtk_peer.py"), a.anchors, a.volume,
               "--mappers", ",".join(mappers), "--threads", str(a.threads), "--no-iso",
               "--runs", str(a.runs)] + common
    vv_cmd = [a.bench, a.volume, "--threads", str(a.threads), "--runs", str(a.runs),
              "--modes", "composite,mip,iso", "--outdir", out_dir,
              "--quality", str(a.quality)] + common
    for o in a.option:
        vv_cmd += ["--option", o]
    ratios = {(mp, m): [] for mp in mappers for m in ("composite", "mip", "composite_first")}
    cpu = {}
    iso = []
    version = "?"
    for i in range(a.pairs):
        load = open("/proc/loadavg").read().split()[0]
        vt = run(vtk_cmd, cwd=out_dir)  # it writes anchors_out/ where it runs
        vv = run(vv_cmd)
        sys.stdout.write(vt + vv)
        v, w = values(vt), values(vv)
        if a.bench_b:
            vb = run([a.bench_b] + vv_cmd[1:])
            wb = values(vb)
            line = "# pair %d, B (%s):" % (i + 1, a.bench_b)
            for m in ("composite", "mip"):
                t_b = wb["dvr_%s_frame" % m]
                c_b = t_b * wb.get("dvr_%s_cpu_per_wall" % m, float("nan"))
                cpu.setdefault(("B", m), []).append(c_b)
                ratios.setdefault(("B", m), []).append(t_b / w["dvr_%s_frame" % m])
                for mp in mappers:
                    ratios.setdefault((mp, m, "B"), []).append(
                        v["dvr_%s_%s_frame" % (mp, m)] / t_b)
                line += " %s B %.4f s (cpu %.3f s), B/VolVis %.2fx;" % (
                    m, t_b, c_b, t_b / w["dvr_%s_frame" % m])
            print(line, flush=True)
        for line in vt.splitlines():
            if line.startswith("anchor=vtk-"):
                version = line.split()[0][len("anchor=vtk-"):]
        line = "# pair %d (load %s):" % (i + 1, load)
        for m in ("composite", "mip"):
            t_vv = w["dvr_%s_frame" % m]
            c_vv = t_vv * w.get("dvr_%s_cpu_per_wall" % m, float("nan"))
            cpu.setdefault(("volvis", m), []).append(c_vv)
            line += " %s VolVis %.4f s (cpu %.3f s)" % (m, t_vv, c_vv)
            for mp in mappers:
                t_vtk = v["dvr_%s_%s_frame" % (mp, m)]
                c_vtk = t_vtk * v.get("dvr_%s_%s_cpu_per_wall" % (mp, m), float("nan"))
                cpu.setdefault((mp, m), []).append(c_vtk)
                ratios[(mp, m)].append(t_vtk / t_vv)
                line += ", %s %.4f s (cpu %.3f s) = %.2fx" % (mp, t_vtk, c_vtk, t_vtk / t_vv)
            line += ";"
        for mp in mappers:
            ratios[(mp, "composite_first")].append(v["dvr_%s_composite_first_frame" % mp] /
                                                   w["dvr_composite_first_frame"])
            line += " %s composite first frame %.2fx;" % (mp, ratios[(mp, "composite_first")][-1])
        iso.append(w["dvr_iso_frame"])
        line += " iso %.4f s" % iso[-1]
        print(line, flush=True)
    for mp in mappers:
        print("# %s, VTK %s %s, %d pairs, %d threads: median VTK/VolVis composite %.2fx, "
              "first frame %.2fx, MIP %.2fx; CPU s a frame, VTK/VolVis: composite %.3f/%.3f, "
              "MIP %.3f/%.3f" %
              (os.path.basename(a.volume), version, mp, a.pairs, a.threads,
               statistics.median(ratios[(mp, "composite")]),
               statistics.median(ratios[(mp, "composite_first")]),
               statistics.median(ratios[(mp, "mip")]),
               statistics.median(cpu[(mp, "composite")]), statistics.median(cpu[("volvis", "composite")]),
               statistics.median(cpu[(mp, "mip")]), statistics.median(cpu[("volvis", "mip")])))
    if a.bench_b:
        for mp in mappers:
            print("# B: median VTK/B (%s) composite %.2fx, MIP %.2fx; B/VolVis composite %.2fx, "
                  "MIP %.2fx; B's CPU s a frame composite %.3f, MIP %.3f" %
                  (mp, statistics.median(ratios[(mp, "composite", "B")]),
                   statistics.median(ratios[(mp, "mip", "B")]),
                   statistics.median(ratios[("B", "composite")]),
                   statistics.median(ratios[("B", "mip")]),
                   statistics.median(cpu[("B", "composite")]), statistics.median(cpu[("B", "mip")])))
    print("# VolVis iso frame median %.4f s" % statistics.median(iso))


if __name__ == "__main__":
    main()
