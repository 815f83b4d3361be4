#!/usr/bin/env bash
# A zoom video's cost two ways, from the same deepest view: flat keyframes (each twice the
# video size, so that no frame magnifies a keyframe) and an exponential map for the video
# size. Prints `deepfield zoom --stats` of each (the reference once, the frames' time) and
# the time of `deepfield frames` making the video frames from each.
#   scripts/bench-zoom.sh [KEYFRAMES] [VIDEO_WxH] [SCENE] [ZOOM]
# Defaults: 100 keyframes, 640x360, scenes/liiiines.toml at zoom 1e300. DEEPFIELD=BIN runs
# that binary instead of building one.
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-100}
size=${2:-640x360}
scene=${3:-scenes/liiiines.toml}
zoom=${4:-1e300}
w=${size%x*}
h=${size#*x}
bin=${DEEPFIELD:-target/release/deepfield}
[ -n "${DEEPFIELD:-}" ] || cargo build --release --quiet --no-default-features
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "== flat keyframes, $((2 * w))x$((2 * h)) (twice the video), $n of them, from zoom $zoom"
/usr/bin/time -f "   process %e s, peak %M KB" "$bin" zoom "$scene" --zoom "$zoom" --size "$((2 * w))x$((2 * h))" \
    --aa 1 --frames "$n" -o "$out/flat" --stats -q
echo "== exponential map for $size, $n strips"
/usr/bin/time -f "   process %e s, peak %M KB" "$bin" zoom "$scene" --zoom "$zoom" --size "$size" --aa 1 \
    --frames "$n" --exponential-map 2 -o "$out/map" --stats -q
echo "== video frames at $size, 30 per second, one second per factor of 2"
/usr/bin/time -f "   from keyframes: %e s" "$bin" frames "$out/flat" --size "$size" -o "$out/f1" -q
/usr/bin/time -f "   from the map:   %e s" "$bin" frames "$out/map" --size "$size" -o "$out/f2" -q
