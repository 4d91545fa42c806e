#!/bin/bash
# Packs what bench/device/run.sh needs on a lent GPU machine (an H100 or
# H200 with no network, no apt, its own Python; ../.library/device/README.md)
# into build/device/, to be carried there by the device tool:
#
#   build/device/volvis-gpu.tar.xz  bin/ (volvis, bench_gpu) and lib/: every
#                                   shared library they load that is not
#                                   glibc's, and the Vulkan loader
#                                   (libvulkan.so.1, opened at run time)
#   build/device/vtk-gpu.tar.xz     the part of the VTK wheel (the version
#                                   pinned in scripts/requirements-pypi.txt,
#                                   for the device's CPython, --python-tag)
#                                   that vtkGPUVolumeRayCastMapper and the
#                                   anchors' benchmark need (the modules
#                                   listed below and every library they load,
#                                   found from their ELF headers), a vtk.py
#                                   that imports only those, and glvnd's EGL
#                                   (libEGL.so.1, libGLdispatch.so.0,
#                                   libOpenGL.so.0) for a machine without it
#   build/device/data/              the CT head and the anchors' VTK
#                                   benchmark (bench_vtk.py, anchors_common.py)
#
# usage: bench/device/bundle.sh [--python-tag cp312] [--build build/release]
# Needs a built release tree, network for the wheel (cached in
# build/device/wheels), readelf and xz. Prints each file's size: the device
# tool carries 64 MiB in all a call.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
TAG=cp312
BUILD=$ROOT/build/release
while [ $# -gt 0 ]; do
    case $1 in
    --python-tag) TAG=$2; shift 2 ;;
    --build) BUILD=$2; shift 2 ;;
    *) echo "bundle.sh: unknown argument $1" >&2; exit 2 ;;
    esac
done
OUT=$ROOT/build/device
SHARED=$(cd "$ROOT/.." && pwd)/shared
for f in "$BUILD/volvis" "$BUILD/bench/bench_gpu" "$SHARED/data/volumes/ct_head.nrrd" \
    "$SHARED/anchors/bench_vtk.py" "$SHARED/anchors/anchors_common.py"; do
    [ -f "$f" ] || { echo "bundle.sh: $f: missing (build the release preset; ../shared beside the repository)" >&2; exit 1; }
done
mkdir -p "$OUT/data" "$OUT/wheels"
STAGE=$(mktemp -d)
trap 'rm -rf "$STAGE"' EXIT

# ---- VolVis: the binaries and their libraries, glibc's left to the machine
mkdir -p "$STAGE/vv/bin" "$STAGE/vv/lib"
cp "$BUILD/volvis" "$BUILD/bench/bench_gpu" "$STAGE/vv/bin/"
ldd "$BUILD/volvis" "$BUILD/bench/bench_gpu" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u |
    grep -Ev '/(libc|libm|libdl|libpthread|librt|libresolv|ld-linux-x86-64)\.so' |
    while read -r lib; do cp -L "$lib" "$STAGE/vv/lib/"; done
cp -L /lib/x86_64-linux-gnu/libvulkan.so.1 "$STAGE/vv/lib/"
tar -C "$STAGE/vv" -cJf "$OUT/volvis-gpu.tar.xz" bin lib

# ---- VTK: the wheel for the device's Python, cut to what the GPU mapper needs
VER=$(sed -n 's/^vtk==\([0-9.]*\).*/\1/p' "$ROOT/scripts/requirements-pypi.txt")
[ -n "$VER" ] || { echo "bundle.sh: no vtk pin in scripts/requirements-pypi.txt" >&2; exit 1; }
WHEEL=$(ls "$OUT/wheels"/vtk-"$VER"-"$TAG"-*.whl 2>/dev/null | head -1 || true)
if [ -z "$WHEEL" ]; then
    PY=$ROOT/.venv/bin/python
    [ -x "$PY" ] || PY=python3
    "$PY" -m pip download "vtk==$VER" --no-deps --only-binary=:all: \
        --python-version "${TAG#cp}" --platform manylinux_2_17_x86_64 -d "$OUT/wheels" >&2
    WHEEL=$(ls "$OUT/wheels"/vtk-"$VER"-"$TAG"-*.whl | head -1)
fi
mkdir -p "$STAGE/vtk"
(cd "$STAGE/vtk" && unzip -q "$WHEEL" 'vtkmodules/*')
# the modules the anchors' benchmark touches with the GPU mapper (vtk.* names
# resolve through these; bench/device/run.sh fails in one line if one is missing)
MODULES="vtkCommonCore vtkCommonDataModel vtkCommonExecutionModel vtkCommonMath
vtkCommonTransforms vtkIOImage vtkImagingCore vtkRenderingCore vtkRenderingOpenGL2
vtkRenderingVolume vtkRenderingVolumeOpenGL2 vtkRenderingUI vtkFiltersCore
vtkInteractionStyle"
python3 - "$STAGE/vtk/vtkmodules" $MODULES >"$STAGE/keep.txt" <<'EOF'
import os, re, subprocess, sys
d, mods = sys.argv[1], sys.argv[2:]
names = os.listdir(d)
todo = []
for m in mods:
    hit = [n for n in names if n.startswith(m + ".cpython") and n.endswith(".so")]
    if not hit:
        sys.exit("bundle.sh: the wheel has no module %s" % m)
    todo += hit
keep = set()
while todo:
    n = todo.pop()
    if n in keep:
        continue
    keep.add(n)
    out = subprocess.run(["readelf", "-d", os.path.join(d, n)], capture_output=True, text=True,
                         check=True).stdout
    libs = [x for x in re.findall(r"Shared library: \[(.*?)\]", out) if x in names]
    todo += libs
    # a module's Python part imports its dependencies' Python parts
    for x in libs:
        m = re.match(r"lib(vtk\w+?)(-[\d.]+)?\.so", x)
        if m:
            todo += [n for n in names if n.startswith(m.group(1) + ".cpython") and n.endswith(".so")]
print("\n".join(sorted(keep)))
EOF
mkdir -p "$STAGE/vtkb/vtkmodules/util" "$STAGE/vtkb/vtk/util" "$STAGE/vtkb/lib"
while read -r n; do cp "$STAGE/vtk/vtkmodules/$n" "$STAGE/vtkb/vtkmodules/"; done <"$STAGE/keep.txt"
cp "$STAGE/vtk/vtkmodules/__init__.py" "$STAGE/vtkb/vtkmodules/"
cp "$STAGE/vtk/vtkmodules/util/"*.py "$STAGE/vtkb/vtkmodules/util/"
# `import vtk` of the wheel loads all of its 180 modules; this one the listed
{
    echo '"""VTK cut to the GPU volume mapper (bench/device/bundle.sh)."""'
    for m in $MODULES; do echo "from vtkmodules.$m import *  # noqa: F401,F403"; done
    echo 'from vtkmodules.vtkCommonCore import vtkVersion, vtkObject  # noqa: F401'
} >"$STAGE/vtkb/vtk/__init__.py"
echo 'from vtkmodules.util.numpy_support import *  # noqa: F401,F403' >"$STAGE/vtkb/vtk/util/numpy_support.py"
touch "$STAGE/vtkb/vtk/util/__init__.py"
for l in libEGL.so.1 libGLdispatch.so.0 libOpenGL.so.0; do
    cp -L "/lib/x86_64-linux-gnu/$l" "$STAGE/vtkb/lib/"
done
tar -C "$STAGE/vtkb" -cJf "$OUT/vtk-gpu.tar.xz" vtk vtkmodules lib

# ---- data
cp "$SHARED/data/volumes/ct_head.nrrd" "$SHARED/anchors/bench_vtk.py" \
    "$SHARED/anchors/anchors_common.py" "$OUT/data/"

ls -l "$OUT/volvis-gpu.tar.xz" "$OUT/vtk-gpu.tar.xz" "$OUT/data"/* | awk '{printf "%8.1f MiB  %s\n", $5 / 1048576, $NF}'
du -cb "$OUT/volvis-gpu.tar.xz" "$OUT/vtk-gpu.tar.xz" "$OUT/data" | tail -1 | awk '{printf "%8.1f MiB  in all (the device tool carries 64 MiB a call)\n", $1 / 1048576}'
