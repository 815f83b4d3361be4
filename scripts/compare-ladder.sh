#!/usr/bin/env bash
# The speed/accuracy ladder of docs/engine-notes.md: `deepfield compare` at zooms 1e0 ... 1e320 around the
# liiiines location's centre (-2 + 1.6e-102 + 1.4e-211 i, given to 340 digits) and at 1e1000
# next to -2 (-2 + 3e-1000 + 1e-1000 i; beyond its digits the liiiines centre is a generic
# point whose neighbourhood is featureless), printed as one Markdown table.
#
#   scripts/compare-ladder.sh [SIZE] [SAMPLES]      (default 400x300, 100)
#
# Each depth renders the full SIZE image with every engine that can address it and
# compares SAMPLES pixels with direct big-float iteration. Takes a few minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-400x300}"
samples="${2:-100}"
cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/deepfield"
center="$(sed -n 's/^center = \["\([^"]*\)", "\([^"]*\)"\]/\1,\2/p' scenes/liiiines.toml)"
echo "| zoom | engine | seconds | iterations/s | N mismatch | NF p50 | NF p99 | DE p50 | DE p99 |"
echo "|---|---|---|---|---|---|---|---|---|"
near_minus_two="-1.$(printf '9%.0s' $(seq 1 999))7,1e-1000"
for zoom in 1 1e10 1e14 1e16 1e50 1e300 1e320 1e1000; do
    c="$center"
    if [ "$zoom" = 1e1000 ]; then c="$near_minus_two"; fi
    "$bin" compare --center "$c" --zoom "$zoom" --size "$size" --max-iter 20000 \
        --samples "$samples" --csv -q |
        tail -n +2 |
        awk -F, -v z="$zoom" '
            # An error over no pixel is "-" in the CSV: keep it, not 0.
            function g(x) { return x == "-" ? "-" : sprintf("%.2g", x) }
            { printf "| %s | %s | %.3f | %.3g | %.4f | %s | %s | %s | %s |\n", z, $1, $2, $3, $4, g($5), g($6), g($7), g($8) }'
done
