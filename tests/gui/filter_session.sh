#!/usr/bin/env bash
# The Filtering page with real input (run by test_gui.sh with
# VV_GUI_SCRIPT=filter_session.sh inside xvfb-run): the CT head opens; the
# chain "--threshold 300: --largest 1:26" typed on the page and applied
# gives a u8 mask (the log line the page writes says so) and a different,
# non-blank image without the head holder; undo restores the first image
# exactly; a chain built with "Add step" (--median 1) applies too; a bad
# chain shows an error dialog and the application keeps running; Ctrl+Q,
# Discard, exit 0.
set -euo pipefail
GUI=$1 OUT=$3
DATA=$(cd ../shared/data/volumes && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
export GDK_BACKEND=x11 NO_AT_BRIDGE=1 VOLVIS_FRAME_LOG=$OUT/frames.log VOLVIS_FRAME_DIR=$OUT
rm -f "$OUT"/*.png "$OUT"/frames.log
fail() { echo "FAIL: $*" >&2; exit 1; }
nfull() { local c; c=$(grep -c ' full ' "$OUT/frames.log" 2>/dev/null) || true; echo "${c:-0}"; }
wait_full() {
  for _ in $(seq 1 300); do
    [ "$(nfull)" -gt "$1" ] && { sleep 0.3; return 0; }
    sleep 0.1
  done
  fail "no full-quality frame after $2"
}
nfiltered() { local c; c=$(grep -c 'volvis-gui: filtered' "$OUT/gui.log" 2>/dev/null) || true; echo "${c:-0}"; }
wait_filtered() {
  for _ in $(seq 1 300); do
    [ "$(nfiltered)" -gt "$1" ] && return 0
    sleep 0.1
  done
  fail "no filter result after $2 ($(tail -3 "$OUT/gui.log"))"
}
same() { [ "$(compare -metric AE "$1" "$2" null: 2>&1 || true)" = "0" ]; }
# mean of the outer quarters of a frame (left and right), where the holder shows
edges_mean() {
  convert "$1" -crop "25%x100%" +repage "$OUT/q-%d.png"
  convert "$OUT/q-0.png" "$OUT/q-3.png" +append -format '%[fx:mean]' info:
}

"$GUI" "$DATA/ct_head.nrrd" > "$OUT/gui.log" 2>&1 &
pid=$!
wait_full 0 "opening"
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
sleep 1
n=$(nfull)
wait_full "$((n - 1))" "resizing"
cp "$OUT/full.png" "$OUT/full0.png"
import -window root "$OUT/open.png"
read -r sx sy < <(python3 "$HERE/locate.py" sidebar "$OUT/open.png" | sed -n 7p) ||
  fail "no Filtering entry in the side bar"
xdotool mousemove "$sx" "$sy" click 1
sleep 1
import -window root "$OUT/page.png"
# the page's controls at their places in a 1100x720 window (see page.png)
n=$(nfull)
f=$(nfiltered)
xdotool mousemove 877 49 click 1 type -- "--threshold 300: --largest 1:26"
xdotool mousemove 699 87 click 1 # Apply
wait_filtered "$f" "Apply"
wait_full "$n" "the filtered volume"
grep 'volvis-gui: filtered' "$OUT/gui.log" | tail -1
grep 'volvis-gui: filtered' "$OUT/gui.log" | tail -1 | grep -q '256 x 256 x 108 u8, values 0..1' ||
  fail "the result is not a u8 mask of the CT head"
for _ in $(seq 1 30); do same "$OUT/full.png" "$OUT/full0.png" || break; sleep 0.2; done
cp "$OUT/full.png" "$OUT/bone.png"
import -window root "$OUT/filtered.png"
same "$OUT/bone.png" "$OUT/full0.png" && fail "filtering did not change the image"
mean=$(convert "$OUT/bone.png" -format '%[fx:mean]' info:)
awk -v m="$mean" 'BEGIN { exit !(m > 0.02) }' || fail "the filtered volume looks blank (mean $mean)"
e0=$(edges_mean "$OUT/full0.png")
e1=$(edges_mean "$OUT/bone.png")
echo "filtered: mean $mean; outer quarters $e0 before, $e1 after"
awk -v a="$e0" -v b="$e1" 'BEGIN { exit !(b < 0.5 * a) }' || fail "the head holder is still there ($e0 -> $e1)"

# undo restores the first image exactly
n=$(nfull)
xdotool key ctrl+z
wait_full "$n" "undo"
for _ in $(seq 1 30); do same "$OUT/full.png" "$OUT/full0.png" && break; sleep 0.2; done
same "$OUT/full.png" "$OUT/full0.png" || fail "undo did not restore the image"
echo "undo: identical"

# a chain built with Add step: the filter list's median, argument 1
xdotool mousemove 855 87 click 1 # Clear
xdotool mousemove 912 201 click 1
sleep 0.5
xdotool key Down Return # median, the second filter
sleep 0.3
xdotool mousemove 912 238 click 1 type "1"
xdotool mousemove 877 345 click 1 # Add step
sleep 0.3
f=$(nfiltered)
xdotool mousemove 699 87 click 1 # Apply
wait_filtered "$f" "Apply (median)"
grep 'volvis-gui: filtered' "$OUT/gui.log" | tail -1 | grep -q -- '--median 1 -> 256 x 256 x 108 i16' ||
  fail "Add step did not build --median 1 ($(grep 'volvis-gui: filtered' "$OUT/gui.log" | tail -1))"
echo "add step: --median 1 applied"

# a bad chain: an error dialog, the application keeps running
xdotool mousemove 855 87 click 1 # Clear
xdotool mousemove 877 49 click 1 type -- "--median x"
xdotool mousemove 699 87 click 1
xdotool search --sync --name 'VolVis: error' > /dev/null
sleep 0.3
import -window root "$OUT/error.png"
kill -0 "$pid" || fail "the application died on a bad chain"
xdotool key Escape
sleep 0.3
echo "bad chain: error dialog, still running"
xdotool key ctrl+q
xdotool search --sync --name 'VolVis: unsaved changes' > /dev/null
xdotool key alt+d
st=0
wait "$pid" || st=$?
[ "$st" = 0 ] || fail "Ctrl+Q: exit status $st"
echo "1 passed, 0 failed"
