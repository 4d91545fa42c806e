#!/usr/bin/env bash
# BigDataViewer HDF5 pyramids out of core (issue 29, docs/formats.md): the
# synthetic SIDE^3 u8 volume of bench_ooc --generate, written by h5py as a
# BigDataViewer file of three levels of 2x2x2 means in 64^3 gzip chunks into
# a temporary folder, rendered at 512^2 by bench_pyramid at full resolution
# (every node at level 0) within LIMIT_MIB, the chunks read by the sandboxed
# readers (libhdf5 in each) and then by libhdf5 in-process (one chunk at a
# time: libhdf5 is not thread-safe); the folder is deleted after.
# usage: bench/hdf5_pyramid.sh [BUILD_DIR] [SIDE] [LIMIT_MIB] [FRAMES]
#   (from the repo root; defaults 512, 128, 2; needs python3-h5py)
set -euo pipefail
build=${1:-build/release}
side=${2:-512}
limit=${3:-128}
frames=${4:-2}
gen=$(readlink -f "$build/bench/bench_ooc")
bin=$(readlink -f "$build/bench/bench_pyramid")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/vv_h5pyr.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
echo "# $(date -u +%FT%TZ) load: $(cut -d' ' -f1-3 /proc/loadavg); ${side}^3 u8 in $tmp"
"$gen" --generate "$side" "$tmp/big.raw"
/usr/bin/python3 - "$tmp/big.raw" "$side" "$tmp/big.h5" <<'PY'
import sys
import h5py
import numpy as np
raw, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
a = np.fromfile(raw, np.uint8).reshape(n, n, n)
with h5py.File(out, "w") as f:
    f["s00/resolutions"] = np.array([[2.0 ** k] * 3 for k in range(3)])
    f["s00/subdivisions"] = np.array([[64, 64, 64]] * 3, dtype=np.int32)
    for k in range(3):
        f.create_dataset(f"t00000/s00/{k}/cells", data=a, chunks=(64, 64, 64), compression="gzip",
                         compression_opts=1)
        z, y, x = [s // 2 * 2 for s in a.shape]
        a = np.rint(a[:z, :y, :x].astype(np.float32).reshape(z // 2, 2, y // 2, 2, x // 2, 2)
                    .mean(axis=(1, 3, 5))).astype(np.uint8)
PY
rm "$tmp/big.raw"
echo "# file: $(du -m "$tmp/big.h5" | cut -f1) MiB; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for sbx in 1 0; do
  echo "# --level 0 (VOLVIS_SANDBOX=$sbx)"
  VOLVIS_SANDBOX=$sbx "$bin" "$tmp/big.h5" --memory-limit "$limit" --size 512 --frames "$frames" \
    --tf 60:255 --level 0 --dataset "bdv_${side}_u8_level0$([ "$sbx" = 0 ] && echo _inprocess || true)"
done
