#!/usr/bin/env bash
# Issue 65's memory bound: rendering a SIDE^3 u8 volume read whole must
# peak at no more than the volume + 4 bytes a voxel + 256 MiB (1024^3:
# 1,024 + 4,096 + 256 = 5,376 MiB). Generates the synthetic volume of
# `bench_ooc --generate` (SIDE^3 bytes of free disk), then runs
# `volvis render RAW` (load, the renderers' caches, one 512^2 composite
# frame with the ramp 60..255, THREADS threads) under GNU time and prints
#   anchor=volvis op=memory_peak_rss ... value=<MiB> unit=MiB
#   anchor=volvis op=memory_bound ...    value=<MiB> unit=MiB
#   anchor=volvis op=memory_load_and_frame ... value=<s> unit=s
# and whether the peak is within the bound. Each run passes --max-memory 1T
# so that the volume is read whole even where the memory budget is
# smaller than the render needs (volvis render would otherwise read it out
# of core, which this script does not measure). OLD_VOLVIS, when set, is
# run beside it on the same volume (a same-run A/B of two builds). The
# working folder (a mktemp -d under $TMPDIR) and the volume in it are
# deleted on exit.
# usage: bench/memory_peak.sh [BUILD_DIR] [SIDE] [THREADS]
set -euo pipefail
build=${1:-build/release}
side=${2:-1024}
threads=${3:-2}
gen=$(readlink -f "$build/bench/bench_ooc")
volvis=$(readlink -f "$build/volvis")
timer=/usr/bin/time
[ -x "$timer" ] || { echo "memory_peak.sh: GNU time (/usr/bin/time) is missing" >&2; exit 77; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/vv_mem.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
echo "# $(date -u +%FT%TZ) load: $(cut -d' ' -f1-3 /proc/loadavg); ${side}^3 u8 in $tmp"
"$gen" --generate "$side" "$tmp/big.raw"
ds="synthetic_${side}_u8"
run() { # label binary
  local start end kib
  start=$(date +%s.%N)
  "$timer" -o "$tmp/time.txt" -f "%M" "$2" --max-memory 1T render "$tmp/big.raw" --raw "${side}x${side}x${side}:u8" \
    --size 512x512 --tf 60:255 --threads "$threads" -o "$tmp/$1.png" --quiet
  end=$(date +%s.%N)
  kib=$(tail -1 "$tmp/time.txt")
  echo "anchor=$1 op=memory_peak_rss dataset=$ds value=$((kib / 1024)) unit=MiB"
  echo "anchor=$1 op=memory_load_and_frame dataset=$ds value=$(echo "$end - $start" | bc) unit=s"
  echo "$((kib / 1024))" >"$tmp/$1.mib"
}
if [ -n "${OLD_VOLVIS:-}" ]; then
  run volvis_old "$(readlink -f "$OLD_VOLVIS")"
fi
run volvis "$volvis"
bound=$(( side * side * side * 5 / 1048576 + 256 ))
echo "anchor=volvis op=memory_bound dataset=$ds value=$bound unit=MiB"
peak=$(cat "$tmp/volvis.mib")
if [ "$peak" -le "$bound" ]; then
  echo "# within the bound: $peak <= $bound MiB"
else
  echo "# OVER the bound: $peak > $bound MiB"
  exit 1
fi
