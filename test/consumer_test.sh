#!/usr/bin/env bash
# Builds example/consumer against hom twice: as a meson subproject and as an
# installed library found through pkg-config. Fails if either build or run fails.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# 1. Subproject.
mkdir -p "$work/sub/subprojects"
cp "$src"/example/consumer/* "$work/sub/"
ln -s "$src" "$work/sub/subprojects/hom"
meson setup "$work/sub/build" "$work/sub" --wrap-mode=forcefallback -Dhom:tests=false -Dhom:benchmarks=false -Dhom:tools=false >/dev/null
ninja -C "$work/sub/build" consumer >/dev/null
"$work/sub/build/consumer"

# 2. Installed library through pkg-config.
meson setup "$work/lib" "$src" --prefix="$work/prefix" -Dtests=false -Dbenchmarks=false -Dtools=false >/dev/null
meson install -C "$work/lib" --only-changed >/dev/null
pc=$(find "$work/prefix" -name hom.pc -printf '%h\n' | head -n1)
test -n "$pc"
mkdir -p "$work/inst"
cp "$src"/example/consumer/* "$work/inst/"
PKG_CONFIG_PATH="$pc" meson setup "$work/inst/build" "$work/inst" --wrap-mode=nofallback >/dev/null
ninja -C "$work/inst/build" consumer >/dev/null
"$work/inst/build/consumer"
