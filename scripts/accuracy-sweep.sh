#!/usr/bin/env bash
# Accuracy of the perturbation engines on the shipped deep scenes, at full resolution:
# `deepfield compare --sample-only` on each scene with many sampled pixels, printed as one
# Markdown table (scene, engine, N mismatch, NF and DE errors, pixels compared).
#
#   scripts/accuracy-sweep.sh [SCALE] [EXTRA COMPARE FLAGS...]
#
# SCALE multiplies every scene's sample count (default 1: 4000 pixels where the big-float
# truth is cheap, down to 20 at bench-e1086). Extra flags go to every `deepfield compare`
# (default: --only bla, which leaves out the engines without BLA: at depth they take
# minutes). About 30 minutes on 2 cores at SCALE 1. Set DEEPFIELD to use a prebuilt binary.
set -euo pipefail
cd "$(dirname "$0")/.."
scale="${1:-1}"
shift || true
if [ "$#" -eq 0 ]; then set -- --only bla; fi
bin="${DEEPFIELD:-}"
if [ -z "$bin" ]; then
    cargo build --release --quiet
    bin=target/release/deepfield
fi
echo "| scene | engine | N mismatch | pixels | ill-conditioned | NF p50 | NF p99 | DE p50 | DE p99 |"
echo "|---|---|---|---|---|---|---|---|---|"
while read -r scene samples; do
    n=$(awk -v s="$samples" -v k="$scale" 'BEGIN { printf "%d", s * k }')
    "$bin" compare "scenes/$scene.toml" --sample-only --samples "$n" --csv -q "$@" |
        tail -n +2 |
        awk -F, -v s="$scene" '
            { row[NR] = $0; if ($1 ~ /^perturb-f64/) f64 = 1 }
            END {
                for (k = 1; k <= NR; k++) {
                    split(row[k], c, ",")
                    if (f64 && c[1] ~ /^perturb-floatexp/) continue
                    printf "| %s | %s | %.5f | %d | %d | %.2g | %.2g | %.2g | %.2g |\n", s, c[1], c[4], c[9], c[10], c[5], c[6], c[7], c[8]
                }
            }'
done <<'SCENES'
bench-e14 4000
bench-e50 1000
bench-e113 2000
liiiines 4000
julia-deep-e40 4000
julia-deep-e310 4000
bench-e533 100
deep-e318 100
bench-e227 40
bench-e1086 20
SCENES
