#!/usr/bin/env bash
# Instructions executed by `deepfield render` builds, counted by valgrind (cachegrind, no
# cache simulation), one thread: a measure of work that a noisy machine's load does not move,
# for changes too small for wall-clock A/B runs (scripts/ab-render.sh) to resolve. Needs
# valgrind (Debian: apt-get install valgrind); about 50x slower than a plain run, so use a
# small size.
#
#   cp target/release/deepfield /tmp/df-old    # build the other version, then
#   scripts/ab-instructions.sh scenes/minibrot-e102.toml 200x150 /tmp/df-old target/release/deepfield
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE WxH BINARY..." >&2
  exit 2
fi
command -v valgrind > /dev/null || { echo "$0: valgrind is not installed" >&2; exit 1; }
scene=$1 size=$2
shift 2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for b in "$@"; do
  refs=$(valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
    "$b" render "$scene" --size "$size" --threads 1 -o "$out/x.png" -q 2>&1 | sed -n 's/.*I *refs: *//p')
  echo "$b: $refs instructions ($(basename "$scene") at $size, one thread)"
done
