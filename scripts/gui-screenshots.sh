#!/usr/bin/env bash
# Takes the screenshots of docs/gui.md: the real volvis-gui on the CT head
# under Xvfb, one picture per page, driven with xdotool.
# usage: scripts/gui-screenshots.sh [BUILD_DIR] [OUT_DIR]   (defaults: build/release docs/images)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
out=${2:-docs/images}
if [ -z "${DISPLAY:-}" ]; then
  exec xvfb-run -a -s "-screen 0 1280x800x24" bash "$0" "$build" "$out"
fi
mkdir -p "$out"
export GDK_BACKEND=x11 NO_AT_BRIDGE=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export VOLVIS_FRAME_LOG=$tmp/frames.log
"$build/apps/volvis-gui/volvis-gui" ../shared/data/volumes/ct_head.nrrd > "$tmp/gui.log" 2>&1 &
pid=$!
wait_full() {
  local n=$1
  for _ in $(seq 1 300); do
    local c
    c=$(grep -c ' full ' "$tmp/frames.log" 2>/dev/null) || true
    [ "${c:-0}" -gt "$n" ] && { sleep 0.5; return 0; }
    sleep 0.1
  done
  echo "gui-screenshots: no full frame" >&2
  return 1
}
wait_full 0
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
sleep 1
shot() { import -window "$wid" "$out/gui_$1.png"; echo "wrote $out/gui_$1.png"; }
import -window "$wid" "$tmp/open.png"
mapfile -t entries < <(python3 tests/gui/locate.py sidebar "$tmp/open.png")
page() { xdotool mousemove ${entries[$1]} click 1; sleep 0.7; }
shot manipulation
# the 2-D transfer function and textures: scroll the side bar down (over the labels)
read -r ex _ <<< "${entries[0]}"
xdotool mousemove $((ex + 130)) 400
for _ in $(seq 1 8); do xdotool click 5; sleep 0.05; done
sleep 0.5
shot manipulation_tf2d
page 1
shot rendering
page 2
shot measurement
page 3
shot modeling
page 4
shot devices
page 5
shot animator
kill "$pid"
wait "$pid" 2>/dev/null || true
