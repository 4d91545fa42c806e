#!/usr/bin/env bash
# Stale frames (issue 11): input arrives while a slow final render (the ray
# tracer, supersampled) is running; the old final frame must never be shown
# after a frame of the new state, and the new state is refined in the end.
# Run by test_gui.sh (VV_GUI_SCRIPT=stale_session.sh) inside xvfb-run.
set -euo pipefail
GUI=$1 OUT=$3
DATA=$(cd ../shared/data/volumes && pwd)
export GDK_BACKEND=x11 NO_AT_BRIDGE=1 VOLVIS_FRAME_LOG=$OUT/frames.log
rm -f "$OUT"/frames.log
fail() { echo "FAIL: $*" >&2; exit 1; }
cat > "$OUT/slow.json" <<JSON
{
  "view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25, "width": 256, "height": 256},
  "lights": [{"type": "directional", "direction": [0, -1, 0]}],
  "render": {"renderer": "raytrace", "quality": 2, "options": {"samples": 4}},
  "objects": [{"name": "head", "type": "volume", "file": "$DATA/ct_head.nrrd",
               "origin": [-122.0, -122.0, -80.25]}]
}
JSON
"$GUI" "$OUT/slow.json" > "$OUT/gui.log" 2>&1 &
pid=$!
# the refinement has started when its 1/2 step is on screen: the slow final render runs now
for _ in $(seq 1 300); do grep -q 'raycast_1/2' "$OUT/frames.log" 2>/dev/null && break; sleep 0.05; done
grep -q 'raycast_1/2' "$OUT/frames.log" || fail "no refinement started"
before=$(tail -1 "$OUT/frames.log" | awk '{print $6}')
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
xdotool mousemove 300 360 mousedown 1
for x in $(seq 296 -4 240); do xdotool mousemove "$x" 360; sleep 0.02; done
xdotool mouseup 1
# the new state's final frame
for _ in $(seq 1 1800); do
  awk -v b="$before" '$2 == "full" && $6 > b { f = 1 } END { exit !f }' "$OUT/frames.log" && break
  sleep 0.1
done
awk -v b="$before" '$2 == "full" && $6 > b { f = 1 } END { exit !f }' "$OUT/frames.log" ||
  fail "the new state was not refined"
# the state never goes back down the log, and no final frame of the old state was shown
awk '{ if ($6 < last) { print "frame of state " $6 " after state " last; bad = 1 } last = $6 }
     END { exit bad }' "$OUT/frames.log" || fail "a stale frame was shown"
awk -v b="$before" '$2 == "full" && $6 <= b { bad = 1 } END { exit bad }' "$OUT/frames.log" ||
  fail "the old state's final frame was shown"
echo "stale frames: none; $(wc -l < "$OUT/frames.log") frames, old state $before"
# unsaved changes: Ctrl+Q asks first; Discard quits with 0
xdotool key ctrl+q
xdotool search --sync --name 'VolVis: unsaved changes' > /dev/null
kill -0 "$pid" || fail "quit without asking about the unsaved changes"
xdotool key alt+d
st=0
wait "$pid" || st=$?
[ "$st" = 0 ] || fail "Ctrl+Q: exit status $st"
echo "1 passed, 0 failed"
