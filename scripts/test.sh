#!/usr/bin/env bash
# Quick start 2: install what is missing, build the release and the asan
# (AddressSanitizer + UndefinedBehaviorSanitizer) presets, run the whole
# test suite on both (a skipped test fails it: scripts/ctest-no-skips.sh),
# then every fuzz harness for 30 s on its corpus
# (scripts/fuzz.sh: the fuzz preset, clang + libFuzzer; every input ever
# found is replayed first; a finding fails the suite).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh build demo test
jobs="$(nproc)"
status=0
for preset in release asan; do
  echo "== $preset: build" >&2
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
  echo "== $preset: test" >&2
  # a skipped test fails the suite here: everything is installed
  bash scripts/ctest-no-skips.sh --preset "$preset" -j"$jobs" || status=1
done
echo "== fuzz: every harness for 30 s, one a core at a time" >&2
# Blocking: a crash, leak, hang or out-of-memory in any harness fails the
# suite (its input in build/fuzz/artifacts/). The harnesses of the formats
# read in the reader sandbox fuzz our own checks in-process (Teem, GDCM,
# libtiff, nifti_clib, Assimp, libxml2 and libnetcdf run in volvis-reader,
# whose parent side fuzz_sandbox fuzzes): docs/security.md, "Fuzzing".
if ! bash scripts/fuzz.sh 30; then
  echo "== fuzz: findings (inputs in build/fuzz/artifacts/)" >&2
  status=1
fi
exit $status
