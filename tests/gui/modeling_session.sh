#!/usr/bin/env bash
# The Modeling page with real input (run by test_gui.sh with
# VV_GUI_SCRIPT=modeling_session.sh inside xvfb-run): a voxelized sphere of
# size 100 at the origin, a box of size 100 at x = 50, then the CSG
# difference sphere - box. The box covers the right half of the view; after
# the difference (its operands hidden) only the left hemisphere is left, so
# the right half of the final frame turns to background.
set -euo pipefail
GUI=$1 OUT=$3
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
half_mean() { # mean of the left (0) or right (1) half of a PNG
  convert "$1" -crop "50%x100%" +repage "$OUT/half-%d.png"
  convert "$OUT/half-$2.png" -format '%[fx:mean]' info:
}
"$GUI" > "$OUT/gui.log" 2>&1 &
pid=$!
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
sleep 1.5
import -window root "$OUT/open.png"
read -r sx sy < <(python3 "$HERE/locate.py" sidebar "$OUT/open.png" | sed -n 4p) ||
  fail "no side bar"
xdotool mousemove "$sx" "$sy" click 1
sleep 1
import -window root "$OUT/page.png"
# the page's controls, at their places in a 1100x720 window (see page.png)
n=$(nfull)
xdotool mousemove 877 379 click 1 # Add (a sphere by default)
wait_full "$n" "adding a sphere"
cp "$OUT/full.png" "$OUT/sphere.png"
n=$(nfull)
xdotool mousemove 930 156 click 1 key ctrl+a type "50"
xdotool key Return
xdotool mousemove 965 45 click 1
sleep 0.5
xdotool key Down Return
sleep 0.3
xdotool mousemove 877 379 click 1 # Add the box
wait_full "$n" "adding a box"
cp "$OUT/full.png" "$OUT/both.png"
right_both=$(half_mean "$OUT/both.png" 1)
n=$(nfull)
xdotool mousemove 910 482 click 1
sleep 0.5
xdotool key Down Down Return # difference
sleep 0.3
xdotool mousemove 877 557 click 1 # Combine
wait_full "$n" "the CSG difference"
for _ in $(seq 1 50); do # the operands are hidden in a second change
  right_csg=$(half_mean "$OUT/full.png" 1)
  awk -v r="$right_csg" 'BEGIN { exit !(r < 0.02) }' && break
  sleep 0.2
done
import -window root "$OUT/csg.png"
left_csg=$(half_mean "$OUT/full.png" 0)
echo "right half: $right_both with the box, $right_csg after sphere - box; left half $left_csg"
awk -v r="$right_both" 'BEGIN { exit !(r > 0.2) }' || fail "the box does not show ($right_both)"
awk -v r="$right_csg" 'BEGIN { exit !(r < 0.02) }' || fail "the difference left the right half ($right_csg)"
awk -v l="$left_csg" 'BEGIN { exit !(l > 0.1) }' || fail "the hemisphere is missing ($left_csg)"
# unsaved changes: Ctrl+Q asks; Discard quits with 0
xdotool key ctrl+q
xdotool search --sync --name 'VolVis: unsaved changes' > /dev/null
xdotool key alt+d
st=0
wait "$pid" || st=$?
[ "$st" = 0 ] || fail "Ctrl+Q: exit status $st"
echo "1 passed, 0 failed"
