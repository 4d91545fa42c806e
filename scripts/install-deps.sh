#!/usr/bin/env bash
# Installs the Debian 12 packages VolVis needs, only those that are missing.
# Safe to run again. Usage: scripts/install-deps.sh [build|demo|test|fuzz|bench]...
#   build  compiler, CMake and the libraries (always included; Open MPI for src/parallel;
#          libwebsockets and libjpeg-turbo for `volvis serve`;
#          python3-dev, python3-cffi and python3-numpy for the Python package;
#          libvulkan-dev and glslc for the gpu renderer)
#   demo   mricron-data (the real MRI head used by the quick-start demo)
#   test   cmocka, ffmpeg (ffprobe checks the videos); Chromium, ChromeDriver, selenium and
#          websockets for the browser tests (tests/web); Xvfb, xdotool and ImageMagick for the GUI tests;
#          pytest, tqdm, ipywidgets, ipykernel and nbconvert (the Python package's tests and notebook);
#          pydicom (writes the DICOM test series, and its test files), nibabel (its Siemens MR
#          slices) and gdcmconv (compresses them); SciPy and Teem's unu (the filters' references);
#          Mesa's lavapipe (mesa-vulkan-drivers) and the Vulkan validation layers for the gpu renderer
#   fuzz   clang-14 with its sanitizer runtimes (libclang-rt-14-dev), libFuzzer and LLVM's OpenMP (the fuzz and tsan presets); Teem's tools,
#          ImageMagick, gdcm tools, VTK, numpy, pydicom (tests/fuzz/make_corpus.sh)
#   bench  VTK, numpy, pydicom, Xvfb, Teem's tools and the zfp CLI, to measure the peers side by side
#   test and bench also make .venv at the repository root: a virtual environment with the
#          PyPI packages of scripts/requirements-pypi.txt, pinned (zarr 3, tensorstore, ome-zarr,
#          ngff-zarr, ome-zarr-models: Zarr v3 / OME-Zarr 0.5 writers and readers to check ours
#          against; napari with PyQt5, pytest-qt for the napari plug-in under Xvfb, with Qt's
#          xcb libraries from Debian); remade when that file changes. Never installs into the
#          system Python.
#   test also makes .venv-wheel: scikit-build-core, cffi, numpy, pytest and auditwheel of
#          scripts/requirements-wheel.txt, pinned, with their wheels in .venv-wheel/wheelhouse
#          (the pip wheel's test, test_python_wheel, builds and installs offline from them)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv=0
wheelvenv=0

pkgs=(build-essential cmake pkg-config libwebsockets-dev libturbojpeg0-dev libteem-dev libnifti2-dev libjansson-dev libblosc-dev libzstd-dev libbz2-dev liblzma-dev
      libpng-dev zlib1g-dev libassimp-dev libfftw3-dev libcairo2-dev libgtk-4-dev
      libspnav-dev libsdl2-dev libxml2-dev libnetcdf-dev libavformat-dev libavcodec-dev
      libswscale-dev libavutil-dev libtiff-dev libgdcm-dev libseccomp-dev libhdf5-dev libopenmpi-dev openmpi-bin
      python3-dev python3-cffi python3-numpy libvulkan-dev glslc
      libcurl4-openssl-dev nginx-light openssl)
for what in "$@"; do
  case "$what" in
    build) ;;
    demo) pkgs+=(mricron-data) ;;
    test) pkgs+=(libcmocka-dev openssl chromium chromium-driver python3-selenium python3-websockets ffmpeg xvfb xauth xdotool imagemagick at-spi2-core python3-pyatspi dbus-x11 python3-pydicom python3-nibabel python3-tifffile python3-pil python3-zarr python3-numcodecs python3-h5py python3-vtk9 libgdcm-tools python3-scipy teem-apps
                 python3-pytest python3-tqdm python3-ipywidgets python3-ipykernel jupyter-nbconvert
                 mesa-vulkan-drivers vulkan-validationlayers graphviz python3-venv
                 libgl1-mesa-dri libegl1 libxkbcommon-x11-0 libxcb-icccm4 libxcb-image0 libxcb-keysyms1
                 libxcb-randr0 libxcb-render-util0 libxcb-xinerama0 libxcb-xkb1 libxcb-cursor0 libxcb-shape0)
          venv=1 wheelvenv=1 ;;
    fuzz) pkgs+=(clang-14 libclang-rt-14-dev libfuzzer-14-dev libomp-14-dev teem-apps imagemagick libgdcm-tools python3-vtk9 python3-numpy python3-pydicom) ;;
    bench) pkgs+=(python3-vtk9 python3-numpy python3-pydicom xvfb libgl1-mesa-dri libegl1 libegl-mesa0 teem-apps zfp mesa-vulkan-drivers python3-venv)
           venv=1 ;;
    *) echo "install-deps.sh: unknown group '$what' (build, demo, test, fuzz, bench)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps.sh: installing ${missing[*]}" >&2
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    sudo="sudo"
  fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The pinned PyPI packages, in .venv. Its stamp is written last: an
# interrupted install has none, and is made again from scratch next time.
if [ "$venv" = 1 ]; then
  req="$root/scripts/requirements-pypi.txt"
  want="$(sha256sum "$req" | cut -d' ' -f1)"
  if [ "$(cat "$root/.venv/requirements.sha256" 2>/dev/null)" != "$want" ]; then
    echo "install-deps.sh: making .venv from scripts/requirements-pypi.txt" >&2
    rm -rf "$root/.venv"
    /usr/bin/python3 -m venv "$root/.venv"
    "$root/.venv/bin/python" -m pip install -q --disable-pip-version-check --no-input -r "$req"
    echo "$want" >"$root/.venv/requirements.sha256"
  fi
fi

# The pip wheel's build and test tools, in .venv-wheel, and their wheels in
# .venv-wheel/wheelhouse (the fresh environment the test installs the wheel
# into takes cffi, numpy and pytest from there, without network).
if [ "$wheelvenv" = 1 ]; then
  req="$root/scripts/requirements-wheel.txt"
  want="$(sha256sum "$req" | cut -d' ' -f1)"
  if [ "$(cat "$root/.venv-wheel/requirements.sha256" 2>/dev/null)" != "$want" ]; then
    echo "install-deps.sh: making .venv-wheel from scripts/requirements-wheel.txt" >&2
    rm -rf "$root/.venv-wheel"
    /usr/bin/python3 -m venv "$root/.venv-wheel"
    "$root/.venv-wheel/bin/python" -m pip download -q --disable-pip-version-check --no-input \
      --no-deps --only-binary=:all: -d "$root/.venv-wheel/wheelhouse" -r "$req"
    "$root/.venv-wheel/bin/python" -m pip install -q --disable-pip-version-check --no-input \
      --no-index --find-links "$root/.venv-wheel/wheelhouse" -r "$req"
    echo "$want" >"$root/.venv-wheel/requirements.sha256"
  fi
fi
