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
