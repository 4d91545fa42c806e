#!/bin/bash
# The gpu renderer's figures on a lent GPU machine (issue 81's "where a GPU
# is available"), in one call of the device tool, from the repository root,
# with what bench/device/bundle.sh packed carried (build/device/...):
#
#   part volvis: the Vulkan devices; bench_gpu on the CT head (the peers'
#     view, composite and MIP, --sizes); the CT head drawn in memory and
#     through the brick cache (a .vvb within --memory-limit), alternated,
#     --repeat frames each while orbiting (`volvis render --orbit`, --orbit
#     degrees a frame; 0: the same frame), the median of frames 2.. of each
#     (ms, device ms, bytes uploaded, cache hits and misses), and their ratio
#   part vtk: vtkGPUVolumeRayCastMapper (VTK from the bundle, offscreen
#     through EGL on the GPU: the OpenGL renderer's name is printed and must
#     be the GPU's, not llvmpipe) in the anchors' benchmark, and bench_gpu on
#     the same volume, view, size and transfer function right after it: a
#     same-run pair
#
# usage: bash bench/device/run.sh [--part volvis|vtk|all] [--sizes WxH,...]
#                                 [--vtk-size N] [--repeat N] [--runs N]
#                                 [--memory-limit SIZE] [--orbit DEG] [--python PY]
# The bundles unpack once into $VV_DEVICE_DIR (default /tmp/vvdevice) and
# stay there while the machine is warm, so a later call may carry only the
# other bundle (64 MiB a call; with the cp312 wheel, 2026-11-28: VolVis 31.7
# MiB, VTK 40.7 MiB, the CT head 7.2 MiB, the tree 3.4 MiB). Two calls, the
# second at once (a machine idle for 30 s goes back):
#   carry [build/device/volvis-gpu.tar.xz, build/device/data]:
#       bash bench/device/run.sh --part volvis
#   carry [build/device/vtk-gpu.tar.xz, build/device/data]:
#       bash bench/device/run.sh --part vtk
# Tried on this 2-core machine with lavapipe and llvmpipe
# (VV_DEVICE_SOFTWARE=1, bundle.sh --python-tag cp311, --python
# .venv/bin/python): every step ran; VTK rendered through vtkEGLRenderWindow
# from the cut bundle. Every step prints its own time; a missing
# piece (no Vulkan ICD, no EGL vendor library) is said in one line and the
# step is skipped with "skipped:", never counted as measured.
# VV_DEVICE_SOFTWARE=1 lets VTK render with Mesa's llvmpipe (to try the
# script on a machine without a GPU, with lavapipe: the figures mean nothing).
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
PART=all SIZES=1024x1024,1920x1080 VTKSIZE=1024 REPEAT=20 RUNS=20 MEMLIM=4M PY=python3 ORBIT=6
while [ $# -gt 0 ]; do
    case $1 in
    --part) PART=$2; shift 2 ;;
    --sizes) SIZES=$2; shift 2 ;;
    --vtk-size) VTKSIZE=$2; shift 2 ;;
    --repeat) REPEAT=$2; shift 2 ;;
    --runs) RUNS=$2; shift 2 ;;
    --memory-limit) MEMLIM=$2; shift 2 ;;
    --orbit) ORBIT=$2; shift 2 ;;
    --python) PY=$2; shift 2 ;;
    *) echo "run.sh: unknown argument $1" >&2; exit 2 ;;
    esac
done
BUN=$ROOT/build/device
DEV=${VV_DEVICE_DIR:-/tmp/vvdevice}
DATA=$BUN/data
mkdir -p "$DEV"
step() { echo "== $(date +%T) $*"; }

# ---- unpack what came (a bundle already unpacked by an earlier call stays)
for b in volvis-gpu vtk-gpu; do
    d=$DEV/${b%-gpu}
    if [ -f "$BUN/$b.tar.xz" ] && [ ! -e "$d/.done" ]; then
        mkdir -p "$d" && tar -C "$d" -xJf "$BUN/$b.tar.xz" && touch "$d/.done"
    fi
done
[ -f "$DATA/ct_head.nrrd" ] && cp -n "$DATA"/* "$DEV/" 2>/dev/null
CT=$DEV/ct_head.nrrd

# ---- the NVIDIA Vulkan and EGL drivers where the image names none
find_lib() { for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64; do
    [ -e "$d/$1" ] && { echo "$d/$1"; return 0; }; done; return 1; }
if ! grep -ls nvidia /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1; then
    if lib=$(find_lib libGLX_nvidia.so.0); then
        printf '{"file_format_version": "1.0.1", "ICD": {"library_path": "%s", "api_version": "1.3.0"}}\n' \
            "$lib" >"$DEV/nvidia_icd.json"
        export VK_DRIVER_FILES=$DEV/nvidia_icd.json VK_ICD_FILENAMES=$DEV/nvidia_icd.json
        echo "# Vulkan: no NVIDIA ICD file in the image; one written for $lib"
    else
        echo "# Vulkan: no NVIDIA ICD file and no libGLX_nvidia.so.0 (the gpu renderer will find no GPU)"
    fi
fi
command -v nvidia-smi >/dev/null && nvidia-smi -L

if [ "$PART" != vtk ]; then
    if [ ! -x "$DEV/volvis/bin/volvis" ]; then
        echo "skipped: part volvis: no $BUN/volvis-gpu.tar.xz carried (bench/device/bundle.sh)"
    else
        export LD_LIBRARY_PATH=$DEV/volvis/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
        VV=$DEV/volvis/bin/volvis BG=$DEV/volvis/bin/bench_gpu
        step "devices"
        "$VV" renderers 2>&1 | sed -n '/gpu/,$p' | head -12
        step "bench_gpu, CT head, sizes $SIZES"
        "$BG" "$CT" --tf-lo 100 --tf-hi 1500 --sizes "$SIZES" --runs "$RUNS" --no-cpu --outdir "$DEV/out" 2>&1
        step "CT head in memory against through the brick cache (.vvb, --memory-limit $MEMLIM), orbiting $ORBIT degrees a frame"
        rm -f "$DEV/cache.txt"
        [ -f "$DEV/ct.vvb" ] || "$VV" convert "$CT" "$DEV/ct.vvb" >/dev/null
        W=${SIZES##*,}
        for i in 1 2 3; do
            for how in memory cache; do
                if [ $how = memory ]; then src=$CT lim=(); else src=$DEV/ct.vvb lim=(--memory-limit "$MEMLIM"); fi
                "$VV" render "$src" "${lim[@]}" --renderer gpu --size "$W" --tf 100:1500 --azimuth 30 \
                    --repeat "$REPEAT" --orbit "$ORBIT" --stats -o "$DEV/out/ct_$how.png" 2>&1 |
                    "$PY" -c '
import statistics, sys
how, run = sys.argv[1], sys.argv[2]
v = {}
for line in sys.stdin:
    if line.startswith("frame="):
        kv = dict(x.split("=", 1) for x in line.split())
        if int(kv["frame"]) > 1:
            for k, x in kv.items():
                v.setdefault(k, []).append(float(x))
print("%s run %s, median of frames 2..%d:" % (how, run, len(v.get("frame", [])) + 1),
      " ".join("%s=%g" % (k, statistics.median(x)) for k, x in v.items() if k != "frame"))
' $how $i | tee -a "$DEV/cache.txt"
            done
        done
        "$PY" - "$DEV/cache.txt" <<'EOF'
import re, statistics, sys
ms = {"memory": [], "cache": []}
for line in open(sys.argv[1]):
    m = re.match(r"(memory|cache) run .* ms=([0-9.e+-]+)", line)
    if m:
        ms[m.group(1)].append(float(m.group(2)))
if ms["memory"] and ms["cache"]:
    a, b = statistics.median(ms["memory"]), statistics.median(ms["cache"])
    print("# CT head through the brick cache: %.3f ms a frame against %.3f ms in memory: %.2fx "
          "(issue 81: within 10 %%)" % (b, a, b / a))
EOF
    fi
fi

if [ "$PART" != volvis ]; then
    if [ ! -d "$DEV/vtk/vtkmodules" ]; then
        echo "skipped: part vtk: no $BUN/vtk-gpu.tar.xz carried (bench/device/bundle.sh)"
    elif [ ! -x "$DEV/volvis/bin/bench_gpu" ]; then
        echo "skipped: part vtk: bench_gpu not unpacked (carry volvis-gpu.tar.xz in this call or an earlier one)"
    else
        export PYTHONPATH=$DEV/vtk${PYTHONPATH:+:$PYTHONPATH}
        export VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow ANCHORS_NO_XVFB=1
        export LD_LIBRARY_PATH=$DEV/volvis/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
        ldconfig -p 2>/dev/null | grep -q 'libEGL.so.1 ' || export LD_LIBRARY_PATH=$DEV/vtk/lib:$LD_LIBRARY_PATH
        if ! ls /usr/share/glvnd/egl_vendor.d/*nvidia* >/dev/null 2>&1 && lib=$(find_lib libEGL_nvidia.so.0); then
            printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "%s"}}\n' "$lib" >"$DEV/10_nvidia.json"
            export __EGL_VENDOR_LIBRARY_FILENAMES=$DEV/10_nvidia.json
            echo "# EGL: no NVIDIA vendor file in the image; one written for $lib"
        fi
        step "VTK's OpenGL renderer"
        GL=$("$PY" - <<'EOF' 2>&1
import vtk
rw = vtk.vtkRenderWindow()
rw.SetOffScreenRendering(1)
rw.SetSize(64, 64)
rw.AddRenderer(vtk.vtkRenderer())
rw.Render()
caps = rw.ReportCapabilities() or ""
print(vtk.vtkVersion.GetVTKVersion(), type(rw).__name__,
      " | ".join(l.strip() for l in caps.splitlines() if "renderer" in l.lower() or "vendor" in l.lower()))
EOF
        )
        echo "$GL"
        if echo "$GL" | grep -qi "Error\|Traceback" ||
            { [ -z "${VV_DEVICE_SOFTWARE:-}" ] && echo "$GL" | grep -qi "llvmpipe\|softpipe"; }; then
            echo "skipped: part vtk: VTK did not render on the GPU (above)"
        else
            for i in 1 2 3; do
                step "pair $i: vtkGPUVolumeRayCastMapper, ${VTKSIZE}x${VTKSIZE}"
                (cd "$DEV" && "$PY" "$DEV/bench_vtk.py" "$CT" --tf-lo 100 --tf-hi 1500 --mappers gpu \
                    --size "$VTKSIZE" --no-iso --runs "$RUNS" --outdir "$DEV/out/vtk" 2>&1 | grep -E "op=.*(composite|mip)|^#")
                step "pair $i: bench_gpu, ${VTKSIZE}x${VTKSIZE}"
                "$DEV/volvis/bin/bench_gpu" "$CT" --tf-lo 100 --tf-hi 1500 --sizes "${VTKSIZE}x${VTKSIZE}" \
                    --runs "$RUNS" --no-cpu --outdir "$DEV/out" 2>&1 | grep -E "op=|^#"
            done
        fi
    fi
fi
step "done"
