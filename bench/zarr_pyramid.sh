#!/usr/bin/env bash
# OME-Zarr pyramids out of core (issue 29, docs/parallel.md): the synthetic
# SIDE^3 u8 volume of bench_ooc --generate, written as an OME-Zarr pyramid
# (volvis convert: 64^3 zlib chunks, levels of 2x2x2 means) into a temporary
# folder, rendered at 512^2 by bench_pyramid inside a cgroup (v1) memory
# limit, once by level of detail (--lod 1) and once at full resolution
# (every node at level 0), the chunks decoded by the sandboxed readers, then
# at full resolution decoded in-process; the folder is deleted after. Needs root (cgroup)
# and about 2 SIDE^3 bytes of free disk. The conversion runs chunk by chunk
# (vv_volume_save_boxes to OME-Zarr) inside the same cgroup limit: its time and its
# peak resident set (GNU time) are printed, in a cgroup of its own: the page
# cache of the files it reads and writes stays charged to its cgroup.
# With TYPE u16 the volume holds 16 times the values as u16 (issue 29's
# 2048^3 u16 target: 16 GiB raw), the transfer function likewise.
# With FORMAT vvb the volume is written as a .vvb with pyramid levels
# instead (zstd bricks, levels of 64^3 zstd chunks), read in-process (a
# .vvb never goes through the sandboxed readers): --lod 1 and --level 0.
# usage: bench/zarr_pyramid.sh [BUILD_DIR] [SIDE] [LIMIT_MIB] [CGROUP_MIB] [FRAMES] [TYPE] [FORMAT]
#   (from the repo root; defaults 1024, 128, 256, 3, u8, zarr)
set -euo pipefail
build=${1:-build/release}
side=${2:-1024}
limit=${3:-128}
cgmib=${4:-256}
frames=${5:-3}
type=${6:-u8}
format=${7:-zarr}
case "$format" in
  zarr) store=big.ome.zarr runs="1 --lod 1|1 --level 0|0 --level 0" ;;
  vvb) store=big.vvb runs="0 --lod 1|0 --level 0" ;;
  *) echo "zarr_pyramid.sh: FORMAT is zarr or vvb" >&2; exit 2 ;;
esac
case "$type" in
  u8) tf=60:255 ;;
  u16) tf=960:4080 ;;
  *) echo "zarr_pyramid.sh: TYPE is u8 or u16" >&2; exit 2 ;;
esac
gen=$(readlink -f "$build/bench/bench_ooc")
bin=$(readlink -f "$build/bench/bench_pyramid")
volvis=$(readlink -f "$build/volvis")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/vv_pyr.XXXXXX")
cg=/sys/fs/cgroup/memory/vv_pyr_$$
cleanup() {
  rm -rf "$tmp"
  for d in "$cg" "$cg-convert"; do
    if [ -d "$d" ]; then rmdir "$d" 2>/dev/null || true; fi
  done
}
trap cleanup EXIT
echo "# $(date -u +%FT%TZ) load: $(cut -d' ' -f1-3 /proc/loadavg); ${side}^3 $type as $store in $tmp"
"$gen" --generate "$side" "$tmp/big.raw" "$type"
# the conversion in a cgroup of its own (the page cache of the files it
# reads and writes stays charged to it), with the same limit
mkdir "$cg" "$cg-convert"
echo $((cgmib * 1024 * 1024)) > "$cg/memory.limit_in_bytes"
echo $((cgmib * 1024 * 1024)) > "$cg-convert/memory.limit_in_bytes"
timer=""
[ -x /usr/bin/time ] && timer="/usr/bin/time -f '# convert (chunk by chunk): %e s, peak resident set %M KiB'"
sh -c "echo \$\$ > $cg-convert/cgroup.procs && exec $timer $volvis convert $tmp/big.raw \
  --raw ${side}x${side}x${side}:$type $tmp/$store --quiet"
rm "$tmp/big.raw"
echo "# store: $(du -sm "$tmp/$store" | cut -f1) MiB on disk; convert cgroup failcnt $(cat "$cg-convert/memory.failcnt"); load: $(cut -d' ' -f1-3 /proc/loadavg)"
# the chunks are decoded by the sandboxed readers (the default); the last
# run decodes them in-process (VOLVIS_SANDBOX=0), the sandbox's cost
IFS='|' read -r -a run_list <<< "$runs"
for run in "${run_list[@]}"; do
  sbx=${run%% *}
  mode=${run#* }
  name=synthetic_${side}_${type}_$(echo "$mode" | tr -d ' -')$([ "$format" = zarr ] && [ "$sbx" = 0 ] && echo _inprocess || true)$([ "$format" = vvb ] && echo _vvb || true)
  echo "# $mode (VOLVIS_SANDBOX=$sbx)"
  sh -c "echo \$\$ > $cg/cgroup.procs && VOLVIS_SANDBOX=$sbx exec $bin $tmp/$store \
    --memory-limit $limit --size 512 --frames $frames --tf $tf $mode --dataset $name"
done
echo "# cgroup: peak $(( $(cat "$cg/memory.max_usage_in_bytes") / 1048576 )) MiB of $cgmib, failcnt $(cat "$cg/memory.failcnt"); load: $(cut -d' ' -f1-3 /proc/loadavg)"
