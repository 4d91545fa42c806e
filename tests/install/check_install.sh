#!/usr/bin/env bash
# Installs the built project into a temporary prefix and builds a program
# against it three ways: find_package(VolVis) with the shared and the static
# library, and pkg-config. Usage: check_install.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1"
src="$2"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
cmake -S "$src/tests/install/consumer" -B "$tmp/b" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
      -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/b" >/dev/null
data="$src/../shared/data/volumes/nut.slc"
LD_LIBRARY_PATH="$tmp/prefix/lib" "$tmp/b/consumer" "$data"
"$tmp/b/consumer_static" "$data"
pc="$(find "$tmp/prefix" -name volvis.pc)"
flags="$(PKG_CONFIG_PATH="$(dirname "$pc")" pkg-config --cflags --libs volvis)"
# shellcheck disable=SC2086
cc "$src/tests/install/consumer/main.c" $flags -Wl,-rpath,"$tmp/prefix/lib" -o "$tmp/pc"
"$tmp/pc" "$data"
echo "install: find_package (shared, static) and pkg-config consumers work"

# `volvis serve` from the prefix serves the page installed beside it (share/volvis/web)
test -f "$tmp/prefix/share/volvis/web/index.html"
test -f "$tmp/prefix/share/volvis/web/js/main.js"
"$tmp/prefix/bin/volvis" serve --port 0 -v "$src/../shared/data/volumes/nut.slc" \
    >"$tmp/serve.out" 2>"$tmp/serve.err" &
pid=$!
for _ in $(seq 1 200); do
  grep -q '^http' "$tmp/serve.out" 2>/dev/null && grep -q "page's files" "$tmp/serve.err" && break
  sleep 0.1
done
url="$(head -1 "$tmp/serve.out")"
grep -q "page's files from $(realpath "$tmp/prefix")/share/volvis/web" "$tmp/serve.err" || {
  cat "$tmp/serve.err"; kill "$pid"; exit 1; }
python3 - "$url" <<'PY'
import sys, urllib.request
page = urllib.request.urlopen(sys.argv[1]).read().decode()
assert 'js/main.js' in page, page[:200]
PY
kill "$pid"
wait "$pid" || true
echo "install: volvis serve serves the installed page"
