#!/usr/bin/env bash
# The Animator page of the real volvis-gui under Xvfb, driven by real X input
# from xdotool (run by test_gui.sh inside xvfb-run). On a small scene (the
# neghip volume, 128x128 view): the page opens from its side-bar entry; an
# orbit is added with the default values; Play shows new frames while it
# runs and Stop gives back the first image bit for bit, with no unsaved
# change; a final render to the default output (animation.mp4 in the
# current folder) has the frame count set on the page; a PNG sequence has
# frame k equal to `volvis render --azimuth 360*k/N` bit for bit; Save…
# writes a file that `volvis animate` renders to the same frames, and New
# then Open… bring it back; camera keys before and after a drag, and a
# recorded flight of that drag, go from the first view (exactly) to the
# dragged one; Cancel stops a long render early; Ctrl+Q exits 0.
set -euo pipefail
GUI=$1 CLI=$2 OUT=$3
DATA=$(cd ../shared/data/volumes && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
export GDK_BACKEND=x11 NO_AT_BRIDGE=1 VOLVIS_FRAME_LOG=$OUT/frames.log VOLVIS_FRAME_DIR=$OUT
rm -rf "$OUT"/*.png "$OUT"/frames.log "$OUT"/*.json "$OUT"/*.mp4 "$OUT"/png "$OUT"/png2 "$OUT"/cli_png "$OUT"/cancel "$OUT"/keys "$OUT"/flight
pid=
fail() {
    echo "FAIL: $*" >&2
    [ -n "$pid" ] && kill "$pid" 2>/dev/null
    exit 1
}
cat > "$OUT/session.json" <<JSON
{
  "view": {"eye": [0, -220, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 30,
           "width": 128, "height": 128, "background": [0, 0, 0]},
  "lights": [{"type": "directional", "direction": [0, 1, 0], "color": [1, 1, 1], "intensity": 1.0}],
  "objects": [{
    "name": "neghip", "type": "volume", "file": "$DATA/neghip.slc",
    "origin": [-32.5, -32.5, -32.5], "mode": "composite", "step": 0.5,
    "transfer_function": {
      "opacity": [[20, 0.0], [60, 0.3], [255, 0.8]],
      "color": [[20, [0.2, 0.4, 1.0]], [120, [1, 0.8, 0.3]], [255, [1, 1, 1]]],
      "opacity_unit_distance": 1.0}
  }]
}
JSON
nlines() { local c; c=$(wc -l < "$OUT/frames.log" 2>/dev/null) || true; echo "${c:-0}"; }
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
# a drag of 96 pixels to the left in the scene view: 180 degrees a view
# height of 128 pixels, azimuth 135 (as gui_session.sh checks)
drag_left() {
    xdotool mousemove 300 400 mousedown 1
    for x in $(seq 292 -8 204); do xdotool mousemove "$x" 400; sleep 0.02; done
    xdotool mouseup 1
}
# renders to the PNG pattern $1 (folder made) and waits until no frame comes for 1.5 s
render_png() {
    mkdir -p "$(dirname "$1")"
    enter "$output_x" "$output_y" "$1"
    click "$render_x" "$render_y"
    local last=-1 n stable=0
    for _ in $(seq 1 300); do
        n=$(ls "$(dirname "$1")" | grep -c '\.png$') || true
        if [ "$n" = "$last" ] && [ "$n" -gt 0 ]; then
            stable=$((stable + 1))
            [ "$stable" -ge 8 ] && return 0
        else
            stable=0
        fi
        last=$n
        sleep 0.2
    done
    fail "the render to $1 did not finish"
}
shot() { import -window root "$OUT/$1"; }
click() { xdotool mousemove "$1" "$2" click 1; sleep 0.3; }
# types $3 into the entry at $1,$2 in place of its text
enter() {
    click "$1" "$2"
    xdotool key ctrl+a
    xdotool type --delay 5 "$3"
    sleep 0.2
}

# the default output of the page is animation.mp4 in the current folder
(cd "$OUT" && exec "$GUI" "$OUT/session.json") > "$OUT/gui.log" 2>&1 &
pid=$!
wait_full 0 "opening"
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 800
sleep 0.5
shot open.png
cp "$OUT/full.png" "$OUT/full0.png"

# the Animator's side-bar entry: try the entries from the last one up until
# the page's timeline is on screen
found=
while read -r x y; do
    click "$x" "$y"
    sleep 0.3
    shot page.png
    if box=$(python3 "$HERE/locate.py" timeline "$OUT/page.png"); then
        found="$x $y"
        break
    fi
done < <(python3 "$HERE/locate.py" sidebar "$OUT/open.png" | tac)
[ -n "$found" ] || fail "no side-bar entry shows the Animator page"
read -r L T R B <<< "$box"
W=$((R - L))
echo "Animator page: side-bar entry at $found, timeline at $L,$T-$R,$B"
# the controls, from the timeline (rows of equal-width buttons span it)
new_x=$((L + W / 6)) open_x=$((L + W / 2)) save_x=$((L + W * 5 / 6)) file_y=$((T - 21))
play_x=$((L + W / 6)) stop_x=$((L + W / 2)) ctl_y=$((B + 22))
frames_x=$((L + W / 2)) frames_y=$((B + 137))
output_x=$((L + W * 6 / 10)) output_y=$((B + 230))
render_x=$((L + W / 4)) cancel_x=$((L + W * 3 / 4)) render_y=$((B + 315))
addseq_x=$((L + W / 2)) addseq_y=$((B + 572))
record_x=$((L + W * 5 / 6)) addkey_x=$((L + W / 2)) addkey_y=$((B + 676))

# sequences are drawn as green lanes on the timeline
lanes() {
    shot lanes.png
    python3 "$HERE/locate.py" count 115,191,115 "$OUT/lanes.png" "$L" "$T" "$R" "$B"
}
[ "$(lanes)" = 0 ] || fail "the new animation is not empty"

# an orbit with the default values: 360 degrees over the animation's 60 frames
click "$addseq_x" "$addseq_y"
shot orbit.png
[ "$(lanes)" -gt 100 ] || fail "Add sequence: no sequence on the timeline"

# Play: new frames (Navigator previews) while it runs, no undo step
n=$(nlines)
click "$play_x" "$ctl_y"
sleep 2
shot playing.png
played=$(($(nlines) - n))
previews=$(tail -n "$played" "$OUT/frames.log" | grep -vc " full ") || true
echo "Play: $played frames in 2 s ($previews previews)"
[ "$played" -ge 10 ] || fail "Play showed $played frames in 2 s"
[ "$previews" -ge 5 ] || fail "Play showed $previews preview frames in 2 s"
# Stop: the World as it was at Play, exactly
n=$(nfull)
click "$stop_x" "$ctl_y"
wait_full "$n" "Stop"
for _ in $(seq 1 50); do
    same "$OUT/full.png" "$OUT/full0.png" && break
    sleep 0.2
done
same "$OUT/full.png" "$OUT/full0.png" || fail "Stop did not restore the first image"
xdotool search --name '^VolVis — session.json$' > /dev/null || fail "Play/Stop left an unsaved change"
echo "Stop: the first image again, bit for bit; nothing unsaved"

# the final render to the default output, 8 frames
enter "$frames_x" "$frames_y" 8
xdotool key Return
sleep 0.3
click "$render_x" "$render_y"
for _ in $(seq 1 600); do [ -f "$OUT/animation.mp4" ] && break; sleep 0.1; done
[ -f "$OUT/animation.mp4" ] || fail "no animation.mp4 from Render"
sleep 0.5
shot rendered.png
nf=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames \
    -of csv=p=0 "$OUT/animation.mp4")
[ "$nf" = 8 ] || fail "animation.mp4 has $nf frames, not 8"
"$CLI" render "$OUT/session.json" --azimuth 135 -q -o "$OUT/cli_135.png"
ffmpeg -v error -y -i "$OUT/animation.mp4" -vf 'select=eq(n\,3)' -vframes 1 "$OUT/mp4_3.png"
p=$(compare -metric PSNR "$OUT/mp4_3.png" "$OUT/cli_135.png" null: 2>&1 || true)
awk -v p="$p" 'BEGIN { exit !(p == "inf" || p > 30) }' ||
    fail "frame 3 of animation.mp4: PSNR $p against volvis render --azimuth 135"
echo "Render: animation.mp4 with 8 frames, frame 3 at $p dB against volvis render --azimuth 135"

# a PNG sequence: frame k is `volvis render --azimuth 360*k/8`
mkdir -p "$OUT/png"
enter "$output_x" "$output_y" "$OUT/png/f_%03d.png"
click "$render_x" "$render_y"
for _ in $(seq 1 600); do [ -f "$OUT/png/f_007.png" ] && break; sleep 0.1; done
[ -f "$OUT/png/f_007.png" ] || fail "no PNG sequence from Render"
[ "$(ls "$OUT/png" | grep -c '^f_...\.png$')" = 8 ] || fail "the PNG sequence has not 8 frames"
same "$OUT/png/f_003.png" "$OUT/cli_135.png" || fail "frame 3 differs from volvis render --azimuth 135"
same "$OUT/png/f_000.png" "$OUT/full0.png" || fail "frame 0 differs from the GUI's first image"
echo "Render: PNG frame 3 = volvis render --azimuth 135, frame 0 = the GUI's image"

# Save…: an animation file naming the session's scene beside it, which
# `volvis animate` renders to the GUI's frames
click "$save_x" "$file_y"
timeout 10 xdotool search --sync --name '^Save animation' > /dev/null || fail "Save… shows no dialog"
sleep 0.5
shot save_dialog.png
xdotool key ctrl+a
xdotool type --delay 5 "$OUT/saved.json"
xdotool key Return
for _ in $(seq 1 50); do [ -f "$OUT/saved.json" ] && break; sleep 0.1; done
[ -f "$OUT/saved.json" ] || fail "Save… wrote no animation file"
grep -q '"scene": "session.json"' "$OUT/saved.json" || fail "the saved animation does not name session.json"
mkdir -p "$OUT/cli_png"
"$CLI" animate --animation "$OUT/saved.json" -q -o "$OUT/cli_png/f_%03d.png"
for k in 0 1 2 3 4 5 6 7; do
    same "$OUT/cli_png/f_00$k.png" "$OUT/png/f_00$k.png" || fail "volvis animate of the saved file: frame $k differs"
done
echo "Save…: volvis animate of the saved animation gives the GUI's 8 frames"

# New empties the animation; Open… brings the saved one back
click "$new_x" "$file_y"
[ "$(lanes)" = 0 ] || fail "New did not empty the animation"
click "$open_x" "$file_y"
timeout 10 xdotool search --sync --name '^Open animation' > /dev/null || fail "Open… shows no dialog"
sleep 0.5
xdotool type --delay 5 "$OUT/saved.json"
sleep 0.3
xdotool key Return
for _ in $(seq 1 25); do [ "$(lanes)" -gt 100 ] && break; sleep 0.2; done
[ "$(lanes)" -gt 100 ] || fail "Open…: no sequence on the timeline"
mkdir -p "$OUT/png2"
enter "$output_x" "$output_y" "$OUT/png2/f_%03d.png"
click "$render_x" "$render_y"
for _ in $(seq 1 600); do [ -f "$OUT/png2/f_007.png" ] && break; sleep 0.1; done
shot reopened.png
[ "$(ls "$OUT/png2" | grep -c '^f_...\.png$')" = 8 ] || fail "no 8 frames after New and Open…"
same "$OUT/png2/f_005.png" "$OUT/png/f_005.png" || fail "the reopened animation renders differently"
echo "New, Open…: the reopened animation renders the same frames"

# camera keys: one at 0 s from the view, one at 1 s after a drag; frame 0 is
# the first view exactly and frame 30 (1 s at 30 fps) the dragged view
click "$new_x" "$file_y"
click "$addkey_x" "$addkey_y"
drag_left
sleep 0.3
click "$addkey_x" "$addkey_y"
xdotool key ctrl+z
shot keys.png
[ "$(python3 "$HERE/locate.py" count 242,209,77 "$OUT/keys.png" "$L" "$T" "$R" "$B")" -gt 10 ] ||
    fail "Add camera key: no keys on the timeline"
render_png "$OUT/keys/f_%03d.png"
[ "$(ls "$OUT/keys" | wc -l)" = 31 ] || fail "camera keys at 0 and 1 s: $(ls "$OUT/keys" | wc -l) frames, not 31"
same "$OUT/keys/f_000.png" "$OUT/full0.png" || fail "camera keys: frame 0 is not the first view"
p=$(psnr "$OUT/keys/f_030.png" "$OUT/cli_135.png")
awk -v p="$p" 'BEGIN { exit !(p == "inf" || p > 40) }' ||
    fail "camera keys: frame 30 at PSNR $p against volvis render --azimuth 135"
echo "Add camera key: 31 frames from the first view (exactly) to the dragged one ($p dB)"

# a recorded flight: the same drag, recorded at 30 Hz, becomes the animation
click "$record_x" "$ctl_y"
drag_left
sleep 0.5
click "$record_x" "$ctl_y"
xdotool key ctrl+z
render_png "$OUT/flight/f_%03d.png"
nf=$(ls "$OUT/flight" | wc -l)
last=$(ls "$OUT/flight" | tail -1)
same "$OUT/flight/f_000.png" "$OUT/full0.png" || fail "flight: frame 0 is not the first view"
p=$(psnr "$OUT/flight/$last" "$OUT/cli_135.png")
awk -v p="$p" 'BEGIN { exit !(p == "inf" || p > 40) }' ||
    fail "flight: the last frame at PSNR $p against volvis render --azimuth 135"
echo "Record flight: $nf frames from the first view (exactly) to the dragged one ($p dB)"

# Cancel stops a long render early
mkdir -p "$OUT/cancel"
enter "$frames_x" "$frames_y" 3000
xdotool key Return
enter "$output_x" "$output_y" "$OUT/cancel/f_%04d.png"
click "$render_x" "$render_y"
sleep 1
click "$cancel_x" "$render_y"
sleep 1
shot cancelled.png
c1=$(ls "$OUT/cancel" | wc -l)
sleep 1
c2=$(ls "$OUT/cancel" | wc -l)
[ "$c1" -ge 1 ] && [ "$c1" -lt 3000 ] && [ "$c1" = "$c2" ] ||
    fail "Cancel: $c1 then $c2 frames of 3000"
echo "Cancel: stopped after $c1 of 3000 frames"

# Ctrl+Q exits 0 (saved first: the drags were edits, undone)
xdotool key ctrl+s
sleep 0.5
xdotool key ctrl+q
st=0
wait "$pid" || st=$?
pid=
[ "$st" = 0 ] || fail "Ctrl+Q: exit status $st"
echo "1 passed, 0 failed"
