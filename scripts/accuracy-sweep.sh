#!/usr/bin/env bash
# Accuracy of the perturbation engines on every shipped deep scene and on the public
# locations of scenes/locations/ (rust-fractal-core's collection, which nothing here was
# tuned to), at full resolution: `deepfield compare --sample-only` on each scene with many
# sampled pixels, printed as one Markdown table (scene, engine, N mismatch, NF and DE
# errors, pixels compared, pixels whose N or NF is ill-conditioned).
#
#   scripts/accuracy-sweep.sh [SCALE] [EXTRA COMPARE FLAGS...]
#
# SCALE multiplies every scene's sample count (default 1: 4000 pixels where the big-float
# truth is cheap, down to 10 past zoom 1e1000). Extra flags go to every `deepfield compare`
# (default: --only bla, which leaves out the engines without BLA: at depth they take
# minutes). About an hour on 2 cores at SCALE 1. Set DEEPFIELD to use a prebuilt binary.
set -euo pipefail
cd "$(dirname "$0")/.."
scale="${1:-1}"
shift || true
if [ "$#" -eq 0 ]; then set -- --only bla; fi
bin="${DEEPFIELD:-}"
if [ -z "$bin" ]; then
    cargo build --release --quiet
    bin="${CARGO_TARGET_DIR:-target}/release/deepfield"
fi
echo "| scene | engine | N mismatch | pixels | ill-conditioned (N, NF) | NF p50 | NF p99 | DE p50 | DE p99 |"
echo "|---|---|---|---|---|---|---|---|---|"
while read -r scene samples; do
    n=$(awk -v s="$samples" -v k="$scale" 'BEGIN { printf "%d", s * k }')
    "$bin" compare "scenes/$scene.toml" --sample-only --samples "$n" --csv -q "$@" |
        tail -n +2 |
        awk -F, -v s="$scene" '
            # An error over no pixel is "-" in the CSV: keep it, not 0.
            function g(x) { return x == "-" ? "-" : sprintf("%.2g", x) }
            { row[NR] = $0; if ($1 ~ /^perturb-f64/) f64 = 1 }
            END {
                for (k = 1; k <= NR; k++) {
                    split(row[k], c, ",")
                    if (f64 && c[1] ~ /^perturb-floatexp/) continue
                    printf "| %s | %s | %.5f | %d | %d, %d | %s | %s | %s | %s |\n", s, c[1], c[4], c[9], c[12], c[13], g(c[5]), g(c[6]), g(c[7]), g(c[8])
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
floral-fantasy 1000
rug 200
spiral-deep 4000
lit-spiral 4000
locations/11-dimensions 100
locations/all-seeing-eye 400
locations/e401 100
locations/e1000 40
locations/e1121 20
locations/e1200 20
locations/flake 200
locations/glitch-test-1 100
locations/glitch-test-2 100
locations/glitch-test-3 200
locations/glitch-test-4 1000
locations/glitch-test-5 1000
locations/glitch-test-7 10
locations/golden-spider 100
locations/heaven 200
locations/leaded-glass 100
locations/line 2000
locations/mitosis 100
locations/mitosis2 200
locations/nr-fail 2000
locations/peanuts 2000
locations/spiral 2000
locations/test5 2000
locations/tick-tock 200
locations/uranium 200
locations/virus 100
locations/windmill 100
locations/x 100
SCENES
