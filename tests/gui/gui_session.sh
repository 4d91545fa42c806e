#!/usr/bin/env bash
# The real volvis-gui under Xvfb, driven by real X input from xdotool
# (run by test_gui.sh inside xvfb-run). Checks: a volume opens and shows a
# non-blank image; a drag to the left turns the head left (the view equals
# `volvis render --azimuth` of the same scene); dragging a transfer-function
# point changes the image; undo restores it exactly; a saved session renders
# through the CLI to the same pixels as the GUI's final frame; a bad file
# shows an error dialog and the application keeps running; Ctrl+Q exits 0.
set -euo pipefail
GUI=$1 CLI=$2 OUT=$3
DATA=$(cd ../shared/data/volumes && pwd)
export GDK_BACKEND=x11 NO_AT_BRIDGE=1 VOLVIS_FRAME_LOG=$OUT/frames.log VOLVIS_FRAME_DIR=$OUT
rm -f "$OUT"/*.png "$OUT"/frames.log "$OUT"/*.json
fail() { echo "FAIL: $*" >&2; exit 1; }
# a session: the CT head, 512x512 view, ray caster
cat > "$OUT/session.json" <<JSON
{
  "view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
           "width": 512, "height": 512, "background": [0, 0, 0]},
  "lights": [{"type": "directional", "direction": [0, -1, 0], "color": [1, 1, 1], "intensity": 1.0}],
  "cut_planes": [{"point": [0, 0, 50], "normal": [0, 0, -1]}],
  "objects": [{
    "name": "head", "type": "volume", "file": "$DATA/ct_head.nrrd",
    "origin": [-122.0, -122.0, -80.25], "mode": "composite", "step": 0.5,
    "transfer_function": {
      "opacity": [[-600, 0.0], [-300, 0.015], [-150, 0.0], [250, 0.0], [500, 0.3], [1500, 0.8]],
      "color": [[-600, [0.9, 0.6, 0.5]], [250, [1, 0.93, 0.8]], [1500, [1, 1, 1]]],
      "opacity_unit_distance": 0.957}
  }]
}
JSON
nfull() { local c; c=$(grep -c " full " "$OUT/frames.log" 2>/dev/null) || true; echo "${c:-0}"; }
wait_full() { # wait for more than $1 full frames
  for _ in $(seq 1 300); do
    [ "$(nfull)" -gt "$1" ] && { sleep 0.3; return 0; }
    sleep 0.1
  done
  fail "no full-quality frame after $2"
}
same() { [ "$(compare -metric AE "$1" "$2" null: 2>&1 || true)" = "0" ]; }
psnr() { compare -metric PSNR "$1" "$2" null: 2>&1 || true; }

"$GUI" "$OUT/session.json" > "$OUT/gui.log" 2>&1 &
pid=$!
wait_full 0 "opening"
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
sleep 0.5
import -window root "$OUT/open.png"
mean=$(convert "$OUT/full.png" -format '%[fx:mean]' info:)
awk -v m="$mean" 'BEGIN { exit !(m > 0.02) }' || fail "the opened volume looks blank (mean $mean)"
cp "$OUT/full.png" "$OUT/full0.png"
echo "opened: mean $mean"

# a drag to the left in the view: 96 pixels = 96 * 180 / 512 degrees of azimuth
n=$(nfull)
xdotool mousemove 300 360 mousedown 1
for x in $(seq 292 -8 204); do xdotool mousemove "$x" 360; sleep 0.02; done
xdotool mouseup 1
wait_full "$n" "the drag"
cp "$OUT/full.png" "$OUT/full_drag.png"
import -window root "$OUT/drag.png"
"$CLI" render "$OUT/session.json" --azimuth 33.75 -q -o "$OUT/cli_azimuth.png"
p=$(psnr "$OUT/full_drag.png" "$OUT/cli_azimuth.png")
awk -v p="$p" 'BEGIN { exit !(p == "inf" || p > 40) }' || fail "drag left: PSNR $p against --azimuth 33.75"
"$CLI" render "$OUT/session.json" --azimuth -33.75 -q -o "$OUT/cli_wrong.png"
pw=$(psnr "$OUT/full_drag.png" "$OUT/cli_wrong.png")
echo "drag: PSNR $p against the CLI at azimuth 33.75, $pw against -33.75"

# undo restores the image exactly
n=$(nfull)
xdotool key ctrl+z
wait_full "$n" "undo"
same "$OUT/full.png" "$OUT/full0.png" || fail "undo did not restore the image"
echo "undo: identical"

# drag a transfer-function point: press on the editor (adds a point), drag it up
read -r ex ey < <(python3 - "$OUT/open.png" <<'PY'
import sys, subprocess
# the editor is the dark (30,30,36) area in the side panel: find its box
out = subprocess.run(["convert", sys.argv[1], "-crop", "600x720+500+0", "txt:-"],
                     capture_output=True, text=True).stdout.splitlines()[1:]
xs, ys = [], []
for line in out:
    pos, rest = line.split(":", 1)
    x, y = map(int, pos.split(","))
    if "#1E1E23" in rest or "#1E1E24" in rest:
        xs.append(x + 500); ys.append(y)
if not xs:
    sys.exit("no editor found")
print((min(xs) + max(xs)) // 2, max(ys) - 10)
PY
) || fail "no transfer-function editor on screen"
n=$(nfull)
xdotool mousemove "$ex" "$ey" mousedown 1
for d in $(seq 5 5 80); do xdotool mousemove "$ex" $((ey - d)); sleep 0.02; done
xdotool mouseup 1
wait_full "$n" "the transfer-function drag"
import -window root "$OUT/tf.png"
same "$OUT/full.png" "$OUT/full0.png" && fail "dragging a transfer-function point did not change the image"
cp "$OUT/full.png" "$OUT/full_tf.png"
echo "transfer-function drag at $ex,$ey: PSNR $(psnr "$OUT/full_tf.png" "$OUT/full0.png") against before"

# save (Ctrl+S: the session's own file) and render it with the CLI: the same pixels
xdotool key ctrl+s
sleep 1
"$CLI" render "$OUT/session.json" -q -o "$OUT/cli_saved.png"
same "$OUT/cli_saved.png" "$OUT/full_tf.png" || fail "the CLI render of the saved session differs from the GUI ($(psnr "$OUT/cli_saved.png" "$OUT/full_tf.png") dB)"
echo "saved session: the CLI gives the GUI's pixels"

# a drag on the light (Alt+3) moves the highlight; a drag on the cut-plane
# handle (Alt+4) moves the plane; the saved session still gives the GUI's pixels
drag_in_view() { # x0 y0 dx dy
  xdotool mousemove "$1" "$2" mousedown 1
  for k in 1 2 3 4 5 6 7 8; do xdotool mousemove $(($1 + $3 * k / 8)) $(($2 + $4 * k / 8)); sleep 0.03; done
  xdotool mouseup 1
}
n=$(nfull)
xdotool key alt+3
drag_in_view 300 360 120 0
wait_full "$n" "the light drag"
import -window root "$OUT/light.png"
same "$OUT/full.png" "$OUT/full_tf.png" && fail "dragging the light did not change the image"
cp "$OUT/full.png" "$OUT/full_light.png"
echo "light drag: PSNR $(psnr "$OUT/full_light.png" "$OUT/full_tf.png") against before"
n=$(nfull)
xdotool key alt+4
drag_in_view 300 200 0 60
wait_full "$n" "the cut-plane drag"
import -window root "$OUT/cut.png"
same "$OUT/full.png" "$OUT/full_light.png" && fail "dragging the cut plane did not change the image"
cp "$OUT/full.png" "$OUT/full_cut.png"
xdotool key alt+1
xdotool key ctrl+s
sleep 1
"$CLI" render "$OUT/session.json" -q -o "$OUT/cli_saved2.png"
same "$OUT/cli_saved2.png" "$OUT/full_cut.png" || fail "after the light and cut-plane drags the CLI differs from the GUI"
echo "light and cut-plane drags: saved and rendered by the CLI to the GUI's pixels"

# a final render in its own window (Ctrl+R), and quitting while it runs:
# the render is cancelled and the application exits 0 at once
xdotool key ctrl+r
xdotool search --sync --name 'VolVis — render' > /dev/null
sleep 1.5
import -window root "$OUT/render_window.png"
xdotool key ctrl+r # a second one, quit while it renders
sleep 0.05
t0=$(date +%s.%N)
xdotool key ctrl+q
st=0
wait "$pid" || st=$?
t1=$(date +%s.%N)
[ "$st" = 0 ] || fail "Ctrl+Q during a render: exit status $st"
awk -v a="$t0" -v b="$t1" 'BEGIN { exit !(b - a < 5) }' || fail "quitting during a render took $(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }') s"
echo "quit during a final render: exit 0"

# a bad file: an error dialog, the application keeps running, the World empty
printf 'NRRD0004\ntype: short\ndimension: 3\nsizes: 100000 100000 100000\nencoding: raw\n\n' > "$OUT/bad.nrrd"
"$GUI" "$OUT/bad.nrrd" > "$OUT/gui_bad.log" 2>&1 &
pid=$!
xdotool search --sync --name 'VolVis: error' > /dev/null
sleep 0.5
import -window root "$OUT/error.png"
kill -0 "$pid" || fail "the application died on a bad file"
xdotool key Escape
sleep 0.3
xdotool search --name '^VolVis — untitled' > /dev/null || fail "the main window is gone or not empty"
xdotool key ctrl+q
st=0
wait "$pid" || st=$?
[ "$st" = 0 ] || fail "Ctrl+Q after the error: exit status $st"
echo "bad file: error dialog, still running, exit 0"
echo "1 passed, 0 failed"
