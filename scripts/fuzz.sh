#!/usr/bin/env bash
# Runs every libFuzzer harness (tests/fuzz/fuzz_<format>.c, built by the fuzz
# preset) for SECONDS each (default 30), FUZZ_PARALLEL at a time (default
# one a core), on its corpus
# tests/fuzz/corpus/<format>/. New inputs go to build/fuzz/corpus/<format>/
# (not committed); a crash, leak, timeout or out-of-memory stops that harness,
# leaves its input as build/fuzz/artifacts/<format>/crash-* (or leak-,
# timeout-, oom-) and makes the script fail. Copy such an input into
# tests/fuzz/corpus/<format>/ once fixed: every input ever found stays there
# as a regression test (the corpus is replayed first by each run).
#
# A harness with a dictionary, tests/fuzz/dict/<format>.dict (the keys and
# magics its parser compares), runs with -dict=.
#
# usage: scripts/fuzz.sh [SECONDS] [FORMAT...]
#   FUZZ_BUILD=0 skips the build; FUZZ_JOBS (default 2) build jobs.
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-30}"
shift || true
bash scripts/install-deps.sh fuzz >/dev/null
if [ "${FUZZ_BUILD:-1}" != 0 ]; then
  cmake --preset fuzz >/dev/null
  cmake --build --preset fuzz -j"${FUZZ_JOBS:-2}" --target fuzz_all >build/fuzz-build.log 2>&1 ||
    { tail -40 build/fuzz-build.log >&2; echo "fuzz: build failed" >&2; exit 1; }
fi
formats=("$@")
if [ ${#formats[@]} -eq 0 ]; then
  for f in tests/fuzz/fuzz_*.c; do
    n="$(basename "$f" .c)"
    [ "$n" = fuzz_util ] && continue
    formats+=("${n#fuzz_}")
  done
fi
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
# one harness: its summary (or its failure) on stderr, exit 1 on a finding
run_one() {
  local fmt="$1"
  local bin="build/fuzz/tests/fuzz/fuzz_$fmt"
  local seeds="tests/fuzz/corpus/$fmt"
  local work="build/fuzz/corpus/$fmt"
  local art="build/fuzz/artifacts/$fmt"
  mkdir -p "$work" "$art" "$seeds"
  local log="build/fuzz/fuzz_$fmt.log"
  # the keys and magics the parser compares (tests/fuzz/dict/<format>.dict)
  local dict=()
  [ -f "tests/fuzz/dict/$fmt.dict" ] && dict=(-dict="tests/fuzz/dict/$fmt.dict")
  # -rss_limit_mb: the library's budget is 256 MiB (tests/fuzz/fuzz_util.h);
  # -timeout: a single input taking longer is a hang
  if "$bin" "$work" "$seeds" -max_total_time="$secs" -timeout=10 \
      -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$art/" "${dict[@]}" >"$log" 2>&1; then
    { echo "== fuzz_$fmt: ${secs} s"
      grep -E '^stat::number_of_executed_units|^#[0-9]+.*DONE' "$log" | tail -2 || true; } >&2
  else
    { echo "== fuzz_$fmt: ${secs} s"; tail -60 "$log"
      echo "== fuzz_$fmt: FAILED (input in $art/, log $log)"; } >&2
    return 1
  fi
}
# FUZZ_PARALLEL harnesses at a time (default: one a core; each is one
# process of one thread), each still gets its SECONDS of exploration
par="${FUZZ_PARALLEL:-$(nproc)}"
status=0
running=0
for fmt in "${formats[@]}"; do
  if [ "$running" -ge "$par" ]; then
    wait -n || status=1
    running=$((running - 1))
  fi
  run_one "$fmt" &
  running=$((running + 1))
done
while [ "$running" -gt 0 ]; do
  wait -n || status=1
  running=$((running - 1))
done
exit $status
