#!/usr/bin/env bash
# Runs ctest with the given arguments (e.g. --preset release -j2) and fails
# when ctest fails or when it reports any test skipped. A test that cannot
# run exits 77 (CTest's SKIP_RETURN_CODE; tests/testutil.h), which CTest
# counts as "Skipped", not as failed; CI installs every dependency and the
# shared data, so there a skip means a broken set-up and fails the suite.
# Exit status: ctest's, or 1 when it passed with skips.
set -uo pipefail
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
ctest "$@" 2>&1 | tee "$log"
rc=${PIPESTATUS[0]}
skipped="$(grep -E '^[[:space:]]*[0-9]+ - .* \(Skipped\)$' "$log" || true)"
if [ -n "$skipped" ]; then
  echo "== tests skipped (each says why above; in CI a skip fails the suite):" >&2
  echo "$skipped" >&2
  [ "$rc" -eq 0 ] && rc=1
fi
exit "$rc"
