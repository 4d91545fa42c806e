#!/usr/bin/env bash
# CTest entry: runs gui_session.sh (or $VV_GUI_SCRIPT, e.g. devices_session.sh)
# inside a private Xvfb (xvfb-run -a).
set -euo pipefail
dir=$(dirname "$0")
mkdir -p "$3"
# Under the asan preset: GTK, GLib and fontconfig keep caches until exit that
# LeakSanitizer reports as leaks; the GUI session checks behaviour, the unit
# tests check the library's leaks.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
# autosaves of the sessions killed here stay in the test's own folder: no
# restore question in another test or in the user's next session
export XDG_STATE_HOME="$3/state"
exec xvfb-run -a -s "-screen 0 1280x800x24" bash "$dir/${VV_GUI_SCRIPT:-gui_session.sh}" "$@"
