#!/usr/bin/env bash
# Which lines of our own parsers the fuzz corpora reach (issue 67;
# docs/security.md, "What the harnesses reach"): builds every harness with
# source-based coverage (the fuzz-coverage preset, build/fuzzcov), runs each
# once over its corpora (-runs=0: every input once, no mutation) under
# LLVM_PROFILE_FILE, and prints scripts/coverage.py's report: per file of
# our own parsers, the lines reached and every error message never formatted.
#
# The corpora: tests/fuzz/corpus/<format>/ (committed: seeds, every input
# that once failed, and the minimized corpora of long runs) and, when
# present, build/fuzz/corpus/<format>/ (what this machine's runs kept).
#
# usage: scripts/fuzz-coverage.sh [--markdown] [--committed-only] [FORMAT...]
set -euo pipefail
cd "$(dirname "$0")/.."
md=()
committed_only=0
formats=()
for a in "$@"; do
  case "$a" in
    --markdown) md=(--markdown) ;;
    --committed-only) committed_only=1 ;;
    *) formats+=("$a") ;;
  esac
done
cmake --preset fuzz-coverage >/dev/null
cmake --build --preset fuzz-coverage -j"${FUZZ_JOBS:-2}" --target fuzz_all >build/fuzzcov-build.log 2>&1 ||
  { tail -40 build/fuzzcov-build.log >&2; echo "fuzz-coverage: build failed" >&2; exit 1; }
if [ ${#formats[@]} -eq 0 ]; then
  for f in tests/fuzz/fuzz_*.c; do
    n="$(basename "$f" .c)"
    [ "$n" = fuzz_util ] && continue
    formats+=("${n#fuzz_}")
  done
fi
prof="build/fuzzcov/prof"
rm -rf "$prof"
mkdir -p "$prof"
export ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
objects=()
for fmt in "${formats[@]}"; do
  bin="build/fuzzcov/tests/fuzz/fuzz_$fmt"
  dirs=("tests/fuzz/corpus/$fmt")
  [ "$committed_only" = 0 ] && [ -d "build/fuzz/corpus/$fmt" ] && dirs+=("build/fuzz/corpus/$fmt")
  dict=()
  [ -f "tests/fuzz/dict/$fmt.dict" ] && dict=(-dict="tests/fuzz/dict/$fmt.dict")
  n=$(find "${dirs[@]}" -type f | wc -l)
  echo "== fuzz_$fmt: $n inputs" >&2
  LLVM_PROFILE_FILE="$prof/$fmt-%p.profraw" "$bin" -runs=0 -timeout=30 -rss_limit_mb=2048 \
    -malloc_limit_mb=1024 "${dict[@]}" "${dirs[@]}" >"build/fuzzcov/fuzz_$fmt.log" 2>&1 ||
    { tail -20 "build/fuzzcov/fuzz_$fmt.log" >&2; echo "fuzz_$fmt: failed on its corpus" >&2; exit 1; }
  objects+=("$bin")
done
python3 scripts/coverage.py profiles --build build/fuzzcov --profiles "$prof" \
  --objects "${objects[@]}" "${md[@]}"
