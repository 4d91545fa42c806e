#!/usr/bin/env bash
# Out-of-core target (issue 20, docs/parallel.md): a 2048^3 u8 volume (8 GiB)
# generated into a temporary folder, rendered at 512^2 with a 1 GiB memory
# limit by bench_ooc, the whole run inside a cgroup (v1) memory limit of
# 1.5 GiB (by default) so that going over is caught from outside (the kernel would
# reclaim the page cache, then kill the process). The folder is deleted
# after. Needs about 8.5 GiB of free disk, root (cgroup), and a long run
# (the generation and the streaming scan each read or write 8 GiB).
# usage: bench/ooc_2048.sh [BUILD_DIR] [SIDE] [LIMIT_MIB] [CGROUP_MIB] [FRAMES]
#   (from the repo root; defaults 2048, 1024, 1536, 4: the issue's target)
set -euo pipefail
build=${1:-build/release}
side=${2:-2048}
limit=${3:-1024}
cgmib=${4:-1536}
frames=${5:-4}
bin=$(readlink -f "$build/bench/bench_ooc")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/vv_ooc.XXXXXX")
cg=/sys/fs/cgroup/memory/vv_ooc_$$
cleanup() {
  rm -rf "$tmp"
  if [ -d "$cg" ]; then rmdir "$cg" 2>/dev/null || true; fi
}
trap cleanup EXIT
need=$((side * side * side / 1024 / 1024 + 512))
avail=$(df -Pm "$tmp" | awk 'NR==2 {print $4}')
if [ "$avail" -lt "$need" ]; then
  echo "ooc_2048.sh: $avail MiB free in $tmp, need $need" >&2
  exit 1
fi
echo "# $(date -u +%FT%TZ) load: $(cut -d' ' -f1-3 /proc/loadavg); ${side}^3 u8 in $tmp"
# a sphere of tissue with a shell of bone and ripples, air around (bricks
# outside are skipped unread), written one slice at a time
"$bin" --generate "$side" "$tmp/big.raw"
echo "# generated: $(du -m "$tmp/big.raw" | cut -f1) MiB; load: $(cut -d' ' -f1-3 /proc/loadavg)"
mkdir "$cg"
echo $((cgmib * 1024 * 1024)) > "$cg/memory.limit_in_bytes"
# the bench in the cgroup; its page cache is charged there too
sh -c "echo \$\$ > $cg/cgroup.procs && exec $bin $tmp/big.raw --raw ${side}x${side}x${side}:u8 \
  --memory-limit $limit --size 512 --frames $frames --tf 60:255 --dataset synthetic_${side}_u8"
echo "# cgroup: peak $(( $(cat "$cg/memory.max_usage_in_bytes") / 1048576 )) MiB of $cgmib, failcnt $(cat "$cg/memory.failcnt"); load: $(cut -d' ' -f1-3 /proc/loadavg)"
