#!/usr/bin/env bash
# Quick start 1: install what is missing, build VolVis (release), and render
# the real MRI head of Debian's mricron-data package to a PNG.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh build demo test
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)" >/dev/null
input=/usr/share/mricron/templates/ch2.nii.gz
mkdir -p out
./build/release/volvis info "$input"
./build/release/volvis render "$input" -o out/ch2.png --size 512x512 --azimuth 30 --elevation 15
# the library and the Python package, so /usr/bin/python3 -c "import volvis" works (docs/python.md)
cmake --install build/release --prefix /usr/local >/dev/null
ldconfig 2>/dev/null || true
echo "output: $(pwd)/out/ch2.png"
