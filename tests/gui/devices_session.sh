#!/usr/bin/env bash
# Input devices driving the real volvis-gui under Xvfb (run by test_gui.sh
# inside xvfb-run with VV_GUI_SCRIPT=devices_session.sh). The GUI listens on
# a socket (VOLVIS_INPUT_SOCKET) and a python3 client speaks the network
# protocol of docs/input.md as a 3-D mouse. Checks: 6-DOF rotation events
# turn the view (a new full-quality frame, different from the first); the
# button bound to "view.reset" gives exactly what the window's own
# win.view-reset (Ctrl+0) gives; the motion is one undo step (Ctrl+Z
# restores the first image bit for bit); the GUI never answers the client
# with an error; closing the client's socket leaves the GUI running and
# Ctrl+Q exits 0. A recording replayed at start (VOLVIS_INPUT_REPLAY) turns
# the view through the manager's timeouts alone (a replay has no
# descriptor), as one undo step; a malformed recording shows an error
# dialog and the application keeps running. (The Input devices page itself
# is shown by scripts/gui-screenshots.sh, which finds it by name.)
set -euo pipefail
GUI=$1 OUT=$3
DATA=$(cd ../shared/data/volumes && pwd)
SOCKDIR=$(mktemp -d /tmp/volvis-devtest.XXXXXX) # socket paths are limited to 107 bytes
SOCK=$SOCKDIR/input.sock
trap 'rm -rf "$SOCKDIR"' EXIT
export GDK_BACKEND=x11 NO_AT_BRIDGE=1 VOLVIS_FRAME_LOG=$OUT/frames.log VOLVIS_FRAME_DIR=$OUT
export VOLVIS_AUTOSAVE_DELAY=1 # an autosave stands before the save and quit below
export VOLVIS_DEVICE_DIR=$PWD/share/devices # the source tree's information base
rm -f "$OUT"/*.png "$OUT"/frames.log "$OUT"/*.json "$OUT"/*.vvin "$OUT"/c.* "$OUT"/go.*
# the autosaves of an earlier failed run (its GUI was killed) would be
# offered for restoring in a dialog that takes the keys sent below
rm -rf "${XDG_STATE_HOME:?}/volvis"
autosaves() { ls "$XDG_STATE_HOME/volvis" 2> /dev/null | tr '\n' ' '; }
fail() { echo "FAIL: $*" >&2; exit 1; }
# the CT head at 256x256 (quick full-quality frames), ray caster
cat > "$OUT/scene.json" <<JSON
{
  "view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
           "width": 256, "height": 256, "background": [0, 0, 0]},
  "lights": [{"type": "directional", "direction": [0, -1, 0], "color": [1, 1, 1], "intensity": 1.0}],
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
cp "$OUT/scene.json" "$OUT/session.json"
nfull() { local c; c=$(grep -c " full " "$OUT/frames.log" 2>/dev/null) || true; echo "${c:-0}"; }
nlines() { local c; c=$(wc -l < "$OUT/frames.log" 2>/dev/null) || true; echo "${c:-0}"; }
# more than $1 full frames, the last frame full, and no new frame for 0.6 s;
# within 120 s (a full frame under ASan beside another test takes seconds)
wait_settled() {
  local last=-1 cur end=$((SECONDS + 120))
  while [ "$SECONDS" -lt "$end" ]; do
    if [ "$(nfull)" -gt "$1" ] && tail -1 "$OUT/frames.log" | grep -q " full "; then
      cur=$(nlines)
      [ "$cur" = "$last" ] && return 0
      last=$cur
      sleep 0.6
    else
      last=-1
      sleep 0.1
    fi
  done
  import -window root "$OUT/unsettled.png" 2> /dev/null || true
  echo "the last frames: $(tail -3 "$OUT/frames.log" 2> /dev/null | tr '\n' ';')" >&2
  echo "focus: $(xdotool getwindowfocus getwindowname 2>&1 | tr '\n' ' ')" >&2
  fail "no settled full-quality frame after $2"
}
# gives window $1 the keyboard (no window manager does); a window not yet
# mapped refuses the focus (BadMatch), so this tries again for 30 s
focus_window() {
  for _ in $(seq 1 300); do
    xdotool windowfocus "$1" 2> /dev/null && return 0
    sleep 0.1
  done
  fail "cannot give window $1 the keyboard"
}
wait_file() { for _ in $(seq 1 600); do [ -e "$1" ] && return 0; sleep 0.1; done; fail "$2"; }
same() { [ "$(compare -metric AE "$1" "$2" null: 2>&1 || true)" = "0" ]; }
ae() { compare -metric AE "$1" "$2" null: 2>&1 || true; }
quit_saved() { # Ctrl+S (the session's own file), Ctrl+Q: exit status 0
  xdotool key ctrl+s
  sleep 0.5
  xdotool key ctrl+q
  local st=0
  wait "$1" || st=$?
  [ "$st" = 0 ] || fail "Ctrl+Q $2: exit status $st"
}

# the client: a 3-D mouse over the socket, stepped by files in OUT
cat > "$OUT/client.py" <<'PY'
import os, socket, sys, time
out, path = sys.argv[1], sys.argv[2]
def wait_for(name):
    # the session's steps between two marks wait for settled frames (each up
    # to 120 s under ASan beside another test): ten minutes, then give up
    end = time.monotonic() + 600
    while time.monotonic() < end:
        if os.path.exists(os.path.join(out, name)):
            return
        time.sleep(0.05)
    sys.exit("client: no " + name)
def mark(name):
    open(os.path.join(out, name), "w").close()
s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
s.connect(path)
send = lambda line: s.sendall((line + "\n").encode())
send("# a 3-D mouse: six axes in counts of +-350, button 0 bound to view.reset")
send("device 1 spaceball test-puck")
mark("c.declared")
wait_for("go.rotate")
for _ in range(30):  # half a second of full twist about the vertical axis, 60 Hz
    send("motion6 1 0 0 0 0 0 350 0 16")
    time.sleep(1 / 60)
send("motion6 1 0 0 0 0 0 0 0 16")
mark("c.rotated")
wait_for("go.command")
send("button 1 0 1")
send("button 1 0 0")
mark("c.commanded")
wait_for("go.close")
s.setblocking(False)
try:
    answer = s.recv(4096)
except BlockingIOError:
    answer = b""
s.close()
if answer:
    sys.exit("client: the GUI answered: " + answer.decode(errors="replace"))
mark("c.closed")
PY

# ---- 1. a live client --------------------------------------------------------------
VOLVIS_INPUT_SOCKET=$SOCK "$GUI" "$OUT/session.json" > "$OUT/gui.log" 2>&1 &
pid=$!
wait_settled 0 "opening"
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
focus_window "$wid"
wait_file "$SOCK" "the GUI does not listen on $SOCK"
cp "$OUT/full.png" "$OUT/full0.png"
python3 "$OUT/client.py" "$OUT" "$SOCK" > "$OUT/client.log" 2>&1 &
client=$!
wait_file "$OUT/c.declared" "the client did not connect"
sleep 0.5
import -window root "$OUT/open.png"


# 6-DOF rotation: the view turns
n=$(nfull)
touch "$OUT/go.rotate"
wait_file "$OUT/c.rotated" "the client did not send its rotation"
wait_settled "$n" "the rotation"
cp "$OUT/full.png" "$OUT/full_rot.png"
d=$(ae "$OUT/full_rot.png" "$OUT/full0.png")
awk -v d="$d" 'BEGIN { exit !(d ~ /^[0-9][0-9.e+]*$/ && d + 0 > 1000) }' || fail "6-DOF rotation did not turn the view ($d pixels differ)"
echo "rotation: $d pixels differ from the first frame"

# the button bound to view.reset == the window's own win.view-reset (Ctrl+0)
n=$(nfull)
touch "$OUT/go.command"
wait_file "$OUT/c.commanded" "the client did not press its button"
wait_settled "$n" "the view.reset command"
cp "$OUT/full.png" "$OUT/full_cmd.png"
same "$OUT/full_cmd.png" "$OUT/full_rot.png" && fail "the view.reset command did nothing"
n=$(nfull)
xdotool key ctrl+z
wait_settled "$n" "undoing the command"
same "$OUT/full.png" "$OUT/full_rot.png" || fail "undo after the command: not the rotated view"
n=$(nfull)
xdotool key ctrl+0
wait_settled "$n" "Ctrl+0"
same "$OUT/full.png" "$OUT/full_cmd.png" || fail "view.reset from the device differs from Ctrl+0"
echo "command: the device's view.reset gives the pixels of Ctrl+0"

# the motion was one undo step: two Ctrl+Z (Ctrl+0, the motion) give the first image
n=$(nfull)
xdotool key ctrl+z
sleep 0.3
xdotool key ctrl+z
wait_settled "$n" "undo"
same "$OUT/full.png" "$OUT/full0.png" || fail "undo did not restore the first image ($(ae "$OUT/full.png" "$OUT/full0.png") pixels)"
echo "undo: identical to the first frame"
# undone back to the opened state: not "changed" (issue 66: the undo stack's clean state)
for _ in $(seq 1 50); do case "$(xdotool getwindowname "$wid")" in *' *') sleep 0.1 ;; *) break ;; esac; done
case "$(xdotool getwindowname "$wid")" in *' *') fail "undone to the opened state, the title still says changed: $(xdotool getwindowname "$wid")" ;; esac
echo "undo to the opened state: the title shows no change"
# an edit again (redo the motion), so that the session has something to autosave
n=$(nfull)
xdotool key ctrl+shift+z
wait_settled "$n" "redoing the motion"
same "$OUT/full.png" "$OUT/full_rot.png" || fail "redo: not the rotated view"

# the client closes its socket: the GUI runs on, its device leaves the list
touch "$OUT/go.close"
st=0
wait "$client" || st=$?
[ "$st" = 0 ] || fail "client: $(cat "$OUT/client.log")"
sleep 0.5
kill -0 "$pid" || fail "the GUI died when the client closed its socket"
import -window root "$OUT/devices_closed.png"
for _ in $(seq 1 300); do [ -n "$(autosaves)" ] && break; sleep 0.1; done
[ -n "$(autosaves)" ] || fail "no autosave of the edited session within 30 s"
# back to the opened state, which the save below writes (the next launches start from it)
n=$(nfull)
xdotool key ctrl+z
wait_settled "$n" "undoing the motion again"
same "$OUT/full.png" "$OUT/full0.png" || fail "undo again: not the first image"
quit_saved "$pid" "after the client"
# saved, then quit: no autosave is left to be offered as a crashed session
# (the next launch below would show that offer and the keys would go to it)
[ -z "$(autosaves)" ] || fail "a saved session left autosaves: $(autosaves)"
[ -e "$SOCK" ] && fail "the socket was left behind"
echo "client closed: the GUI ran on, Ctrl+Q exit 0, no autosave left"

# ---- 2. a replayed recording (no descriptor: the manager's timeouts) ------------------
python3 - "$OUT/turn.vvin" <<'PY'
import sys
with open(sys.argv[1], "w") as f:
    f.write("volvis-input 1\ndevice 1 spaceball replayed-puck\n")
    f.write("0 motion6 1 0 0 0 0 0 0 0 16\n")
    for i in range(30):  # from 3 s on (a slow start under the sanitizers): half a second of tilt
        f.write("%.17g motion6 1 0 0 0 0 -350 0 0 16\n" % (3 + i / 60))
    f.write("3.5 motion6 1 0 0 0 0 0 0 0 16\n")
PY
cp "$OUT/scene.json" "$OUT/session.json"
rm -f "$OUT/frames.log"
VOLVIS_INPUT_REPLAY=$OUT/turn.vvin "$GUI" "$OUT/session.json" > "$OUT/gui_replay.log" 2>&1 &
pid=$!
# the same window size as the first run: the view renders at the window's size
wid=$(xdotool search --sync --name '^VolVis — ' | head -1)
xdotool windowmove "$wid" 0 0 windowsize "$wid" 1100 720
focus_window "$wid"
# the motion comes 3 s after the replay starts, which is after the window is
# up: under load, well after the first frames
for _ in $(seq 1 300); do
  [ "$(awk '$6 > m { m = $6 } END { print m + 0 }' "$OUT/frames.log" 2>/dev/null)" -gt 4 ] && break
  sleep 0.1
done
wait_settled 0 "the replay"
d=$(ae "$OUT/full.png" "$OUT/full0.png")
awk -v d="$d" 'BEGIN { exit !(d ~ /^[0-9][0-9.e+]*$/ && d + 0 > 1000) }' || fail "the replay did not turn the view ($d pixels differ)"
n=$(nfull)
xdotool key ctrl+z
wait_settled "$n" "undoing the replay"
same "$OUT/full.png" "$OUT/full0.png" || fail "undo after the replay: not the first image"
quit_saved "$pid" "after the replay"
echo "replay: $d pixels differ, one undo step"

# ---- 3. a malformed recording: an error dialog, the GUI runs on ----------------------
printf 'volvis-input 1\ndevice 1 spaceball p\n0 motion6 1 0 1 2\n' > "$OUT/bad.vvin"
VOLVIS_INPUT_REPLAY=$OUT/bad.vvin "$GUI" > "$OUT/gui_bad.log" 2>&1 &
pid=$!
errwid=$(xdotool search --sync --name 'VolVis: error' | head -1)
focus_window "$errwid"
sleep 0.5
import -window root "$OUT/replay_error.png"
kill -0 "$pid" || fail "the GUI died on a malformed recording"
grep -q "replay: .*bad.vvin: line 3: " "$OUT/gui_bad.log" ||
  fail "the error does not carry the library's message: $(cat "$OUT/gui_bad.log")"
xdotool key Escape
sleep 0.3
wid=$(xdotool search --name '^VolVis — untitled' | head -1)
[ -n "$wid" ] || fail "the main window is gone"
focus_window "$wid"
sleep 0.2
xdotool key ctrl+q
st=0
wait "$pid" || st=$?
[ "$st" = 0 ] || fail "Ctrl+Q after the replay error: exit status $st"
echo "malformed recording: error dialog, still running, exit 0"
echo "1 passed, 0 failed"
