#!/usr/bin/env bash
# deepfield beside rust-fractal-core, side by side in one run: each benchmark location is
# rendered by both programs in turn, ROUNDS times (alternating, since a shared machine's
# speed drifts), whole process wall time, and the fastest and median of each are printed.
#
# rust-fractal-core is not built here: build it yourself (its README; it wants its own
# `target-cpu=native`) and give its checkout folder, where `target/release/main` and
# `benchmarks/` are, and a settings file there with `image_width = 800` and
# `image_height = 600` (its `default.toml` edited; the `output/` folder must exist).
#
#   scripts/bench-peers.sh ~/src/rust-fractal-core default.toml 5
set -euo pipefail
if [ $# -lt 2 ]; then
    echo "usage: $0 RFC_DIR RFC_SETTINGS [ROUNDS] [DEEPFIELD]" >&2
    exit 2
fi
rfc_dir=$(cd "$1" && pwd) settings=$2 rounds=${3:-3}
here=$(cd "$(dirname "$0")/.." && pwd)
source "$here/scripts/common.sh"
peer_setup "$here" "${4:-}"
# deepfield scene : rust-fractal-core benchmark file (the same location, 800x600).
pairs="bench-e14:1e14 bench-e50:1e50 bench-e113:5e113 bench-e227:5e227 bench-e533:4e533 bench-e1086:1e1086"
printf '%-12s %22s %22s %8s\n' location "deepfield (fast/med)" "rust-fractal-core" ratio
for pair in $pairs; do
    scene=${pair%%:*} bench=${pair##*:}
    for _ in $(seq "$rounds"); do
        timed d "$df" render "$here/scenes/$scene.toml" -o "$out/d.png" -q
        # rust-fractal-core reads its files relative to its own folder.
        timed p sh -c 'cd "$1" && ./target/release/main "benchmarks/$2.toml" -o "$3" 2> /dev/null' sh "$rfc_dir" "$bench" "$settings"
    done | medians "$scene"
done
echo "ratio: deepfield median / rust-fractal-core median (below 1: deepfield faster)"
