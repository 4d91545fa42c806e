#!/usr/bin/env bash
# Quick start 2: install what is missing, build the release and the asan
# (AddressSanitizer + UndefinedBehaviorSanitizer) presets, run the whole
# test suite (a skipped test fails it: scripts/ctest-no-skips.sh), then
# every fuzz harness for 15 s on its corpus (scripts/fuzz.sh: the fuzz
# preset, clang + libFuzzer; every input ever found is replayed first; a
# finding fails the suite).
#
# Each test runs where it checks most. The unit tests (LABELS unit: the C
# programs of tests/*/test_*.c) run on both builds, the optimised and the
# sanitized one being different code. An end-to-end test (a program driven
# by a script: the CLI, the GUI sessions, the browser, Python) that the asan
# preset also defines runs there alone: the same behaviour is checked, and
# memory errors besides. It runs on the release build as well when it checks
# something there that it cannot under the sanitizers (LABELS
# release_checks: resident-set bounds, latencies). The tests that the asan
# preset leaves out (GUI sessions that measure memory, the wheel, napari,
# the Jupyter widget, the screenshots) run on the release build.
# `ctest --preset release` by hand still runs every test of that preset.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh build demo test
jobs="$(nproc)"
status=0
phase() { echo "== $* ($(date -u +%T), $((SECONDS / 60)) min in)" >&2; }
# the end-to-end tests that the asan preset runs in full (see above)
cmake --preset asan >/dev/null
list_tests() { ctest --preset "$@" -N | sed -n 's/^ *Test *#[0-9]*: //p' | sort; }
cmake --preset release >/dev/null
mapfile -t asan_only < <(comm -12 <(list_tests asan -LE unit) \
  <(list_tests release -LE 'unit|release_checks'))
for preset in release asan; do
  phase "$preset: build"
  cmake --preset "$preset" >/dev/null
  log="build/$preset-build.log"
  mkdir -p build
  if ! cmake --build --preset "$preset" -j"$jobs" >"$log" 2>&1; then
    cat "$log" >&2
    echo "== $preset: build failed" >&2
    exit 1
  fi
  if grep -q 'warning:' "$log"; then
    grep -A3 'warning:' "$log" >&2
    echo "== $preset: the build has warnings" >&2
    status=1
  fi
  skip=()
  if [ "$preset" = release ] && [ ${#asan_only[@]} -gt 0 ]; then
    skip=(-E "^($(IFS='|'; echo "${asan_only[*]}"))\$")
    echo "== release: ${#asan_only[@]} end-to-end tests run under asan alone:" \
      "${asan_only[*]}" >&2
  fi
  phase "$preset: test"
  # a skipped test fails the suite here: everything is installed
  bash scripts/ctest-no-skips.sh --preset "$preset" -j"$jobs" "${skip[@]}" || status=1
done
phase "fuzz: every harness for 15 s, one a core at a time"
# Blocking: a crash, leak, hang or out-of-memory in any harness fails the
# suite (its input in build/fuzz/artifacts/). The harnesses of the formats
# read in the reader sandbox fuzz our own checks in-process (Teem, GDCM,
# libtiff, nifti_clib, Assimp, libxml2 and libnetcdf run in volvis-reader,
# whose parent side fuzz_sandbox fuzzes): docs/security.md, "Fuzzing".
if ! bash scripts/fuzz.sh 15; then
  echo "== fuzz: findings (inputs in build/fuzz/artifacts/)" >&2
  status=1
fi
phase "done, status $status"
exit $status
