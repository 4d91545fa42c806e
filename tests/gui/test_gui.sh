#!/usr/bin/env bash
# CTest entry: runs gui_session.sh inside a private Xvfb (xvfb-run -a).
set -euo pipefail
dir=$(dirname "$0")
mkdir -p "$3"
exec xvfb-run -a -s "-screen 0 1280x800x24" bash "$dir/gui_session.sh" "$@"
