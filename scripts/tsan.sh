#!/usr/bin/env bash
# The threads under ThreadSanitizer (docs/security.md, "Threads under
# ThreadSanitizer"). Run by hand; not part of CI (.ci/run), which has no time
# left for it. Builds what it needs in build/tsan (the tsan preset, with
# VOLVIS_TSAN: GLib's locks and hand-offs annotated in volvis-gui), then:
#   1. DICOM: test_io_dicom, its parallel header reads with 4 OpenMP threads
#      in this process (VOLVIS_SANDBOX=0) and in volvis-reader: no report;
#   2. the GUI session (tests/gui/tsan_session.py) with the annotations off
#      (VOLVIS_TSAN_GLIB=0): TSan must report the hand-offs it cannot see,
#      else the session did not exercise them and proves nothing;
#   3. the same session with the annotations on: no report;
#   4. a short session with a race injected (VOLVIS_TSAN_INJECT_RACE=1: the
#      render thread writes the preview policy without its lock): it must be
#      reported, in render_one.
# Exits 1 when any of these goes otherwise. Each GUI session starts its own
# Xvfb and session bus (tests/gui/atspi.py), as the GUI tests do.
#
# usage: scripts/tsan.sh [OUTDIR]      (default build/tsan/tsan-proof)
# environment: JOBS (parallel build jobs, default nproc)
#              TSAN_STEPS (default "dicom off on inject": which steps to run)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
jobs=${JOBS:-$(nproc)}
out=${1:-$root/build/tsan/tsan-proof}
steps=${TSAN_STEPS:-dicom off on inject}
bash scripts/install-deps.sh build test fuzz

cmake --preset tsan >/dev/null
cmake --build build/tsan -j"$jobs" --target volvis_gui volvis_reader volvis_cli test_io_dicom
mkdir -p "$out"

# LLVM's OpenMP runtime (clang) under TSan: Archer gives TSan OpenMP's
# synchronisation; thread binding off, which volvis-reader's system-call
# filter refuses (libomp treats the refusal as fatal)
export OMP_TOOL_LIBRARIES=/usr/lib/llvm-14/lib/libarcher.so
export KMP_AFFINITY=disabled
# GLib, GTK, Mesa and the other libraries are not instrumented: their own
# accesses are not checked (ignore_noninstrumented_modules)
export TSAN_OPTIONS="halt_on_error=0:second_deadlock_stack=1:ignore_noninstrumented_modules=1"

fail=0
reports() { grep -a -c -E '^(WARNING|ERROR): ThreadSanitizer' "$1" || true; }
say() { printf 'tsan.sh: %s\n' "$*"; }
bad() {
    say "FAILED: $*"
    fail=1
}

gui() { # gui NAME [short] -- runs tests/gui/tsan_session.py into $out/NAME
    local name=$1 mode=${2:-}
    rm -rf "${out:?}/$name"
    mkdir -p "$out/$name"
    local rc=0
    /usr/bin/python3 tests/gui/tsan_session.py build/tsan/apps/volvis-gui/volvis-gui \
        "$out/$name" $mode >"$out/$name/session.log" 2>&1 || rc=$?
    grep -a -E '^(frames shown|closed|FAIL)' "$out/$name/session.log" | sed "s/^/  $name: /" || true
    grep -a 'volvis-gui: render thread:' "$out/$name/gui.log" | sed "s/^/  $name: /" || true
    return $rc
}

for step in $steps; do
    case $step in
    dicom)
        rc=0
        VV_CLI=$root/build/tsan/volvis VV_TEST_OUT=$root/build/tsan/test-out \
            build/tsan/tests/test_io_dicom >"$out/dicom.log" 2>&1 || rc=$?
        n=$(reports "$out/dicom.log")
        say "DICOM (test_io_dicom, 4 threads in-process and in volvis-reader): exit $rc, $n reports"
        grep -a -E '^\[  (PASSED|FAILED)' "$out/dicom.log" | sed 's/^/  /' || true
        [ "$rc" -eq 0 ] || bad "test_io_dicom failed ($out/dicom.log)"
        [ "$n" -eq 0 ] || bad "ThreadSanitizer reported $n times on the DICOM reads ($out/dicom.log)"
        ;;
    off)
        rc=0
        VOLVIS_TSAN_GLIB=0 gui off || rc=$?
        n=$(reports "$out/off/gui.log")
        say "GUI session, GLib's synchronisation NOT annotated: $n reports (expected: some)"
        [ "$rc" -eq 0 ] || bad "the session failed ($out/off/session.log)"
        [ "$n" -gt 0 ] || bad "no report without the annotations: the session proves nothing"
        ;;
    on)
        rc=0
        gui on || rc=$?
        n=$(reports "$out/on/gui.log")
        say "GUI session, annotated: $n reports (expected: none)"
        [ "$rc" -eq 0 ] || bad "the session failed ($out/on/session.log)"
        [ "$n" -eq 0 ] || bad "ThreadSanitizer reported $n times in the GUI session ($out/on/gui.log)"
        ;;
    inject)
        rc=0
        VOLVIS_TSAN_INJECT_RACE=1 gui inject short || rc=$?
        n=$(reports "$out/inject/gui.log")
        found=$(grep -a -c -E '#0 render_one .*vvg-scene-render\.c' "$out/inject/gui.log" || true)
        say "GUI session, race injected: $n reports, $found in render_one (expected: at least 1)"
        [ "$rc" -eq 0 ] || bad "the session failed ($out/inject/session.log)"
        [ "$found" -gt 0 ] || bad "the injected race was not reported ($out/inject/gui.log)"
        ;;
    *)
        bad "unknown step $step (dicom, off, on, inject)"
        ;;
    esac
done
if [ "$fail" -ne 0 ]; then
    say "the proof FAILED (logs in $out)"
    exit 1
fi
say "the proof holds (logs in $out)"
