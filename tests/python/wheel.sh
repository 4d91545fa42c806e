#!/usr/bin/env bash
# test_python_wheel (CTest, the release preset): the pip wheel, built and
# used the way a user would, without the build tree.
#
# Usage: tests/python/wheel.sh SOURCE_DIR OUT_DIR
#
#  1. `pip wheel SOURCE_DIR --no-build-isolation` with .venv-wheel's pinned
#     scikit-build-core, cffi, pycparser and numpy (scripts/requirements-wheel.txt,
#     made by scripts/install-deps.sh test), its CMake build kept in
#     OUT_DIR/skbuild so that a re-run rebuilds only what changed;
#  2. the wheel's contents: the package, libvolvis, volvis-reader, volvis, the
#     browser client; no absolute build path in its programs (strings), the
#     extension's RPATH $ORIGIN-relative; `auditwheel show` printed;
#  3. a fresh environment (/usr/bin/python3 -m venv, no system site packages)
#     in OUT_DIR/venv, the wheel installed with cffi, numpy, pytest and tifffile from
#     .venv-wheel/wheelhouse (no network);
#  4. from a folder outside the source tree, with no PYTHONPATH:
#     tests/python/wheel_check.py (NIfTI and TIFF rendered, the TIFF through
#     volvis-reader; the `volvis` command's --help, render and serve), then
#     the Python tests of WHEEL_TESTS below against the installed package.
# Exit 77 (skipped) only when a prerequisite is missing: .venv-wheel, the
# shared data, /usr/bin/python3 with venv.
set -euo pipefail
src="$(cd "$1" && pwd)"
out="$2"
tools="$src/.venv-wheel"
data="$src/../shared/data"
skip() {
  echo "test_python_wheel: skipped: $*"
  exit 77
}
[ -x "$tools/bin/python" ] && [ -d "$tools/wheelhouse" ] ||
  skip ".venv-wheel is missing (bash scripts/install-deps.sh test makes it)"
[ -f "$data/volumes/avg152T1_RL_nifti.nii.gz" ] || skip "no ../shared/data/volumes/avg152T1_RL_nifti.nii.gz"
/usr/bin/python3 -c "import ensurepip, venv" 2>/dev/null || skip "/usr/bin/python3 has no venv (python3-venv)"

# the Python tests run against the installed wheel (about 15 s; the others
# need more of the system's Python packages, or take long, and run in
# test_python); the environment has pytest and tifffile besides the wheel's
# cffi and numpy, so the ipywidgets view is left out
WHEEL_TESTS=(test_errors.py test_roundtrip.py test_world.py test_zero_copy.py test_slices.py
             test_cli_match.py)
WHEEL_DESELECT=(-k "not test_viewer_widget")

unset PYTHONPATH PYTHONHOME VOLVIS_READER VOLVIS_SANDBOX VOLVIS_WEB_DIR VOLVIS_DEVICE_DIR VV_CLI
mkdir -p "$out"
out="$(cd "$out" && pwd)"
t0=$(date +%s)

# 1. the wheel
rm -rf "$out/dist"
# Make, not Ninja, whether or not ninja-build is installed: the same build
# everywhere, and the kept build folder never meets another generator
if ! SKBUILD_BUILD_DIR="$out/skbuild" CMAKE_GENERATOR="Unix Makefiles" \
  CMAKE_BUILD_PARALLEL_LEVEL="${VV_WHEEL_JOBS:-2}" \
  "$tools/bin/python" -m pip wheel --disable-pip-version-check --no-build-isolation --no-deps \
  --no-index -w "$out/dist" "$src" >"$out/build.log" 2>&1; then
  tail -n 60 "$out/build.log"
  echo "test_python_wheel: FAIL: pip wheel (the whole log: $out/build.log)"
  exit 1
fi
if grep -q 'warning:' "$out/build.log"; then
  grep -A3 'warning:' "$out/build.log"
  echo "test_python_wheel: FAIL: the wheel's build has warnings"
  exit 1
fi
whls=("$out"/dist/volvis-*-linux_x86_64.whl)
[ -f "${whls[0]}" ] || { ls "$out/dist"; echo "test_python_wheel: FAIL: no volvis-*-linux_x86_64.whl"; exit 1; }
whl="${whls[0]}"
echo "built $(basename "$whl") ($(du -k "$whl" | cut -f1) KiB) in $(($(date +%s) - t0)) s"

# 2. its contents
rm -rf "$out/unpacked"
"$tools/bin/python" -c "import sys, zipfile; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])" \
  "$whl" "$out/unpacked"
u="$out/unpacked/volvis"
for f in __init__.py _cli.py widgets.py _widget.js _widget.css lib/libvolvis.so.0 bin/volvis libexec/volvis-reader \
  share/volvis/web/index.html share/volvis/devices/keyboard.json; do
  [ -f "$u/$f" ] || { echo "test_python_wheel: FAIL: volvis/$f is not in the wheel"; exit 1; }
done
ext=("$u"/_volvis.*.so)
[ -f "${ext[0]}" ] || { echo "test_python_wheel: FAIL: no extension volvis/_volvis.*.so"; exit 1; }
for f in "${ext[0]}" "$u/lib/libvolvis.so.0" "$u/bin/volvis" "$u/libexec/volvis-reader"; do
  if strings -a "$f" | grep -F -e "$src" -e "$out" -e "/usr/local"; then
    echo "test_python_wheel: FAIL: $(basename "$f") holds an absolute build or install path"
    exit 1
  fi
  rp="$(readelf -d "$f" | sed -n 's/.*(R\(UN\)\{0,1\}PATH).*\[\(.*\)\]/\2/p')"
  case "$rp" in
  "" | '$ORIGIN'*) ;;
  *) echo "test_python_wheel: FAIL: $(basename "$f") has the RPATH $rp"; exit 1 ;;
  esac
done
readelf -d "${ext[0]}" | grep -q 'R.*PATH.*\[\$ORIGIN/lib\]' ||
  { echo "test_python_wheel: FAIL: the extension's RPATH is not \$ORIGIN/lib"; exit 1; }
echo "== auditwheel show (informational: the wheel links Debian's libraries, docs/python.md)"
"$tools/bin/auditwheel" show "$whl" 2>&1 | grep -v '^INFO' | sed -n '1,4p'

# 3. a fresh environment
rm -rf "$out/venv"
/usr/bin/python3 -m venv "$out/venv"
"$out/venv/bin/python" -m pip install -q --disable-pip-version-check --no-input --no-index \
  --find-links "$tools/wheelhouse" "$whl" pytest tifffile
if "$out/venv/bin/python" -c "import sys; sys.exit(any('dist-packages' in p for p in sys.path))"; then :; else
  echo "test_python_wheel: FAIL: the fresh environment sees the system's packages"
  exit 1
fi

# 4. outside the source tree
work="$(mktemp -d /tmp/volvis-wheel-XXXXXX)"
trap 'rm -rf "$work"' EXIT
cd "$work"
"$out/venv/bin/python" "$src/tests/python/wheel_check.py" "$data"
tests=()
for t in "${WHEEL_TESTS[@]}"; do tests+=("$src/tests/python/$t"); done
VV_CLI="$out/venv/bin/volvis" VV_EXPECT_PREFIX="$out/venv" VV_TEST_OUT="$work/test-out" \
  PYTHONDONTWRITEBYTECODE=1 "$out/venv/bin/python" "$src/tests/python/run_pytest.py" "${tests[@]}" \
  "${WHEEL_DESELECT[@]}"
echo "test_python_wheel: ok in $(($(date +%s) - t0)) s"
