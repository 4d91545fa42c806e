#!/usr/bin/env bash
# Runs every libFuzzer harness (tests/fuzz/fuzz_<format>.c, built by the fuzz
# preset) for SECONDS each (default 30), one after the other, on its corpus
# tests/fuzz/corpus/<format>/. New inputs go to build/fuzz/corpus/<format>/
# (not committed); a crash, leak, timeout or out-of-memory stops that harness,
# leaves its input as build/fuzz/artifacts/<format>/crash-* (or leak-,
# timeout-, oom-) and makes the script fail. Copy such an input into
# tests/fuzz/corpus/<format>/ once fixed: every input ever found stays there
# as a regression test (the corpus is replayed first by each run).
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
status=0
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
for fmt in "${formats[@]}"; do
  bin="build/fuzz/tests/fuzz/fuzz_$fmt"
  seeds="tests/fuzz/corpus/$fmt"
  work="build/fuzz/corpus/$fmt"
  art="build/fuzz/artifacts/$fmt"
  mkdir -p "$work" "$art" "$seeds"
  log="build/fuzz/fuzz_$fmt.log"
  echo "== fuzz_$fmt: ${secs} s" >&2
  # -rss_limit_mb: the library's budget is 256 MiB (tests/fuzz/fuzz_util.h);
  # -timeout: a single input taking longer is a hang
  if "$bin" "$work" "$seeds" -max_total_time="$secs" -timeout=10 \
      -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$art/" >"$log" 2>&1; then
    grep -E '^stat::number_of_executed_units|^#[0-9]+.*DONE' "$log" | tail -2 >&2 || true
  else
    tail -60 "$log" >&2
    echo "== fuzz_$fmt: FAILED (input in $art/, log $log)" >&2
    status=1
  fi
done
exit $status
