#!/usr/bin/env bash
# Memory pressure is an error or a switch, never the OOM killer (issues 33
# and 65): volvis runs in a memory cgroup of its own limited to 1 GiB
# (version 1 or 2, made beside this process's cgroup). A 2 GiB raw NRRD
# volume, too big to render in memory (its voxels, the renderers' copy and
# gradients: 10 GiB), is rendered out of core, said in one line, within
# the limit; when --max-memory raises the budget past what rendering in
# memory needs, its load is refused with the cgroup's one-line error and
# exit 1; a 64 MiB volume renders in memory (its cached gradients sized by
# the memory left). Exit 77 (skipped) where no memory cgroup can be made.
# Usage: cgroup_memory.sh VOLVIS OUT_DIR
set -uo pipefail
volvis="$(realpath "$1")"
out="$2"
rm -rf "$out"
mkdir -p "$out"
cd "$out" || exit 1

skip() {
  echo "skipped: $*"
  exit 77
}

# this process's memory cgroup: version 1's memory hierarchy where it is
# mounted, else the unified hierarchy
v1_mnt="$(awk '$0 ~ / - cgroup / && $NF ~ /(^|,)memory(,|$)/ {print $5; exit}' /proc/self/mountinfo)"
v2_mnt="$(awk '$0 ~ / - cgroup2 / {print $5; exit}' /proc/self/mountinfo)"
if [ -n "$v1_mnt" ]; then
  version=1
  rel="$(awk -F: '$2 ~ /(^|,)memory(,|$)/ {print $3; exit}' /proc/self/cgroup)"
  parent="$v1_mnt$rel"
elif [ -n "$v2_mnt" ]; then
  version=2
  rel="$(awk -F: '$1 == "0" {print $3; exit}' /proc/self/cgroup)"
  parent="$v2_mnt$rel"
  # a version 2 cgroup with processes cannot hand the memory controller to
  # children: use the parent of ours
  parent="$(dirname "$parent")"
  grep -qw memory "$parent/cgroup.subtree_control" 2>/dev/null ||
    echo +memory >"$parent/cgroup.subtree_control" 2>/dev/null ||
    skip "the memory controller cannot be enabled under $parent"
else
  skip "no memory cgroup hierarchy is mounted"
fi
cg="$parent/volvis-test-$$"
mkdir "$cg" 2>/dev/null || skip "cannot make a cgroup under $parent (not root, or read-only)"
trap 'rmdir "$cg" 2>/dev/null' EXIT
limit=$((1 << 30))
if [ "$version" = 1 ]; then
  echo "$limit" >"$cg/memory.limit_in_bytes" || skip "cannot set memory.limit_in_bytes"
else
  echo "$limit" >"$cg/memory.max" || skip "cannot set memory.max"
  echo 0 >"$cg/memory.swap.max" 2>/dev/null || true
fi

# sparse files: no disk, no page cache until read
truncate -s 2G big.raw
printf 'NRRD0004\ntype: uint8\ndimension: 3\nsizes: 1024 1024 2048\nencoding: raw\ndata file: big.raw\n' >big.nhdr
truncate -s 64M small.raw
# a slab of value 200 in the middle, so that the image shows something
head -c $((4 << 20)) /dev/zero | tr '\0' '\310' |
  dd of=small.raw bs=1M seek=30 conv=notrunc status=none
printf 'NRRD0004\ntype: uint8\ndimension: 3\nsizes: 256 256 1024\nencoding: raw\ndata file: small.raw\n' >small.nhdr

# runs "$@" inside the cgroup; prints its exit status
in_cgroup() {
  sh -c 'echo $$ >"$0/cgroup.procs" && exec "$@"' "$cg" "$@"
}

fail=0
check() {
  if ! eval "$1"; then
    echo "FAIL: $2"
    fail=1
  fi
}

in_cgroup "$volvis" render big.nhdr -o big.png --size 64x64 2>big.err
rc=$?
cat big.err
check '[ "$rc" = 0 ]' "a 2 GiB volume under a 1 GiB limit, out of core: exit $rc, not 0"
check 'grep -q "read out of core (--memory-limit" big.err' "the switch to out of core is not said"
check '[ "$(wc -l <big.err)" = 1 ]' "the note is not one line"
check '[ -s big.png ]' "no image of the 2 GiB volume"
rm -f big.png

in_cgroup "$volvis" --max-memory 16G render big.nhdr -o big.png --size 64x64 2>big16.err
rc=$?
cat big16.err
check '[ "$rc" = 1 ]' "--max-memory 16G past the cgroup's limit: exit $rc, not 1"
check 'grep -q "memory cgroup" big16.err' "the error does not name the cgroup's limit"
check '[ "$(wc -l <big16.err)" = 1 ]' "the error is not one line"
check '[ ! -e big.png ]' "an image was written for the refused volume"

in_cgroup "$volvis" render small.nhdr -o small.png --size 128x128
rc=$?
check '[ "$rc" = 0 ]' "a 64 MiB volume under a 1 GiB limit: exit $rc, not 0"
check '[ -s small.png ]' "no image of the 64 MiB volume"
if [ "$version" = 1 ]; then
  echo "peak usage in the cgroup: $(cat "$cg/memory.max_usage_in_bytes") bytes of $limit"
else
  echo "peak usage in the cgroup: $(cat "$cg/memory.peak" 2>/dev/null || echo unknown) bytes of $limit"
fi
[ "$fail" = 0 ] && echo "cgroup memory: refused with an error, never killed"
exit "$fail"
