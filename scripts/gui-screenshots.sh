#!/usr/bin/env bash
# Takes the screenshots of docs/gui.md: the real volvis-gui on the CT head
# under its own Xvfb and session bus, each page found by accessible name
# over AT-SPI (scripts/gui_screenshots.py, tests/gui/atspi.py; the system's
# python3 with python3-pyatspi).
# usage: scripts/gui-screenshots.sh [BUILD_DIR] [OUT_DIR]   (defaults: build/release docs/images)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
out=${2:-docs/images}
exec /usr/bin/python3 scripts/gui_screenshots.py "$build/apps/volvis-gui/volvis-gui" "$out"
