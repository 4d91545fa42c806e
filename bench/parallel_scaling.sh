#!/usr/bin/env bash
# Strong scaling of distributed ray casting (docs/parallel.md): the CT head
# resampled to 512^3, a 512^2 composite frame, one thread per rank, on 1 and
# 2 ranks (the 1.7x target on a 2-core machine), then 4 and 8 ranks
# oversubscribed for the compositing time and its share of the frame, by
# binary swap and radix-k. Prints the anchor lines of bench_parallel with
# the load average before each run (the machine is shared).
# usage: bench/parallel_scaling.sh [BUILD_DIR] [VOLUME]   (from the repo root)
set -euo pipefail
build=${1:-build/release}
vol=${2:-../shared/data/volumes/ct_head.nrrd}
bin=$build/bench/bench_parallel
# no X display for mpirun or the ranks (Open MPI's hwloc probes the X servers
# :0 to :9 for GPUs otherwise: docs/parallel.md)
mpirun=(env -u DISPLAY HWLOC_COMPONENTS=-gl mpirun --allow-run-as-root --oversubscribe)
echo "# $(date -u +%FT%TZ) $(nproc) cores; paraview: $(command -v pvbatch || echo 'not installed (no pvbatch comparison)')"
for np in 1 2 4 8; do
  for method in binary-swap radix-k; do
    # 1 rank: the methods are the same (no compositing)
    if [ "$np" = 1 ] && [ "$method" = radix-k ]; then continue; fi
    echo "# np=$np $method load: $(cut -d' ' -f1-3 /proc/loadavg)"
    timeout 1200 "${mpirun[@]}" -np "$np" "$bin" "$vol" --side 512 --size 512 --frames 3 \
      --threads 1 --compositing "$method"
  done
done
