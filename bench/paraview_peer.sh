#!/usr/bin/env bash
# Issue 29's peer for big volumes: ParaView 5.11's pvbatch (Debian's
# `paraview`) must load a whole volume before it renders, where VolVis
# renders an OME-Zarr pyramid out of core. Same run, same machine: the
# synthetic SIDE^3 u8 volume of `bench_ooc --generate` (default 1024: 1 GiB,
# the largest of the issue's volumes that ParaView holds in this machine's
# memory with its gradients), 512^2 composite with the transfer-function
# ramp 60..255, an orbit of 10 degrees for the second frame:
#   - ParaView: an ImageReader of the raw file, volume representation
#     (VolumeRenderingMode, each of MODES, comma-separated: "Smart" (the
#     default: here the GPU mapper on Mesa's llvmpipe) and "Ray Cast Only"
#     (the CPU fixed-point ray caster)), the load, the first frame and the
#     next, peak resident set (GNU time);
#   - VolVis in memory: `volvis render RAW` (load and render, peak RSS);
#   - VolVis out of core: bench_pyramid on the OME-Zarr written by `volvis
#     convert` (128 MiB limit, --lod 1 and --level 0), peak RSS.
# python3-paraview replaces python3-vtk9 (the VTK the other anchors use):
# with --install the script installs paraview, and puts python3-vtk9 back
# when it ends. Needs xvfb-run (pvbatch renders through X here) and about
# 2 SIDE^3 bytes of free disk; the volumes are deleted after, the images
# kept in $VV_BENCH_OUT when that is set.
# usage: bench/paraview_peer.sh [BUILD_DIR] [SIDE] [MODES] [--install]
set -euo pipefail
build=${1:-build/release}
side=${2:-1024}
modes=${3:-Smart}
install=${4:-}
gen=$(readlink -f "$build/bench/bench_ooc")
bench=$(readlink -f "$build/bench/bench_pyramid")
volvis=$(readlink -f "$build/volvis")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/vv_pv.XXXXXX")
restore=0
cleanup() {
  if [ -n "${VV_BENCH_OUT:-}" ]; then
    mkdir -p "$VV_BENCH_OUT"
    cp "$tmp"/*.png "$VV_BENCH_OUT"/ 2>/dev/null || true
  fi
  rm -rf "$tmp"
  if [ "$restore" = 1 ]; then
    echo "# putting python3-vtk9 back"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q python3-vtk9 > /dev/null
  fi
}
trap cleanup EXIT
# pvbatch needs python3-paraview, which python3-vtk9 replaces
if ! command -v pvbatch > /dev/null ||
   ! dpkg-query -W -f '${Status}' python3-paraview 2>/dev/null | grep -q "ok installed"; then
  if [ "$install" = "--install" ]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q paraview python3-paraview > /dev/null
    restore=1
  else
    echo "paraview_peer.sh: pvbatch or python3-paraview is missing (Debian's paraview; --install installs them and" \
         "puts python3-vtk9 back after)" >&2
    exit 77
  fi
fi
timer=/usr/bin/time
[ -x "$timer" ] || { echo "paraview_peer.sh: GNU time (/usr/bin/time) is missing" >&2; exit 77; }
echo "# $(date -u +%FT%TZ) load: $(cut -d' ' -f1-3 /proc/loadavg); ${side}^3 u8 in $tmp;" \
     "$(pvbatch --version 2>/dev/null | head -1)"
"$gen" --generate "$side" "$tmp/big.raw"
IFS=, read -r -a mode_list <<< "$modes"
for mode in "${mode_list[@]}"; do
tag=$(echo "$mode" | tr -d ' ' | tr 'A-Z' 'a-z')
cat > "$tmp/pv.py" <<EOF
import time
t0 = time.time()
from paraview.simple import *
r = ImageReader(FileNames=["$tmp/big.raw"])
r.DataScalarType = "unsigned char"
r.DataByteOrder = "LittleEndian"
r.DataExtent = [0, $side - 1, 0, $side - 1, 0, $side - 1]
r.UpdatePipeline()
t_load = time.time() - t0
v = CreateRenderView()
v.ViewSize = [512, 512]
v.OrientationAxesVisibility = 0
d = Show(r, v)
d.SetRepresentationType("Volume")
d.VolumeRenderingMode = "$mode"
ColorBy(d, ("POINTS", "ImageFile"))
otf = GetOpacityTransferFunction("ImageFile")
otf.Points = [0, 0, 0.5, 0, 60, 0, 0.5, 0, 255, 1, 0.5, 0]
v.ResetCamera()
t1 = time.time()
Render(v)
t_first = time.time() - t1
v.GetActiveCamera().Azimuth(10)
t2 = time.time()
Render(v)
t_next = time.time() - t2
SaveScreenshot("$tmp/paraview_$tag.png", v)
for op, val in (("load", t_load), ("first_frame", t_first), ("next_frame", t_next)):
    print(f"anchor=paraview op=pvbatch_{op} dataset=synthetic_${side}_u8_$tag value={val:.3f} unit=s")
EOF
echo "# ParaView pvbatch (VolumeRenderingMode $mode)"
$timer -f "anchor=paraview op=pvbatch_peak_rss dataset=synthetic_${side}_u8_$tag value=%M unit=KiB" \
  xvfb-run -a -s "-screen 0 1024x768x24" pvbatch "$tmp/pv.py" 2>&1 | grep -E "^anchor|rror" || true
done
echo "# VolVis in memory (volvis render of the raw file: load, gradients and one frame)"
start=$(date +%s.%N)
# --max-memory: in memory even where the budget is smaller than the render
# needs (volvis render would switch to out of core and say so)
$timer -f "anchor=volvis op=memory_peak_rss dataset=synthetic_${side}_u8 value=%M unit=KiB" \
  "$volvis" --max-memory 1T render "$tmp/big.raw" --raw "${side}x${side}x${side}:u8" --size 512x512 --tf 60:255 \
  -o "$tmp/volvis.png" --quiet
echo "anchor=volvis op=memory_load_and_frame dataset=synthetic_${side}_u8 value=$(echo "$(date +%s.%N) - $start" | bc) unit=s"
echo "# VolVis out of core (OME-Zarr pyramid, 128 MiB)"
"$volvis" convert "$tmp/big.raw" --raw "${side}x${side}x${side}:u8" "$tmp/big.ome.zarr" --quiet
rm "$tmp/big.raw"
for m in "--lod 1" "--level 0"; do
  $timer -f "anchor=volvis op=pyramid_peak_rss dataset=synthetic_${side}_u8_$(echo "$m" | tr -d ' -') value=%M unit=KiB" \
    "$bench" "$tmp/big.ome.zarr" --memory-limit 128 --size 512 --frames 2 --tf 60:255 $m \
    --dataset "synthetic_${side}_u8_$(echo "$m" | tr -d ' -')" 2>&1 | grep -E "^anchor"
done
echo "# $(date -u +%FT%TZ) load: $(cut -d' ' -f1-3 /proc/loadavg)"
