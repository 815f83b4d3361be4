#!/usr/bin/env bash
# The speed/accuracy trade along an ordinary descent into seahorse valley (the centre
# -0.7436438870371587... + 0.1318259042053119... i, to 33 digits), zoom 1e3 to 1e20, as one
# Markdown table: the engine `auto` picks, its wall time and direct f64's (where f64 still
# addresses the view) for a SIZE render of N only, and `deepfield compare`'s N mismatch and
# NF p99 against direct big-float iteration for f64 and for the perturbation engine with
# BLA (auto's choice past f64) on a 400x300 render of the same view.
#
#   scripts/descent-trade.sh [SIZE] [SAMPLES] [MAX_ITER]   (default 1024x768, 200, 5000)
#
# Set DEEPFIELD to use a prebuilt binary. About five minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1024x768}"
samples="${2:-200}"
max_iter="${3:-5000}"
bin="${DEEPFIELD:-}"
if [ -z "$bin" ]; then
    cargo build --release --quiet
    bin="${CARGO_TARGET_DIR:-target}/release/deepfield"
fi
center="-0.743643887037158704752191506114774,0.131825904205311970493132056385139"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
wall() { awk '/^wall time/ { print $3 }'; }
echo "| zoom | auto picks | auto s | f64 s | auto / f64 | f64 N mismatch | f64 NF p99 | perturb-f64 bla N mismatch | perturb-f64 bla NF p99 |"
echo "|---|---|---|---|---|---|---|---|---|"
for e in $(seq 3 20); do
    zoom="1e$e"
    common=(--center "$center" --zoom "$zoom" --max-iter "$max_iter")
    stats="$("$bin" render "${common[@]}" --size "$size" --channels N -o "$out/auto.exr" --stats -q 2>&1)"
    engine="$(awk '/^engine/ { print $2; exit }' <<< "$stats")"
    auto_s="$(wall <<< "$stats")"
    if f64="$("$bin" render "${common[@]}" --size "$size" --channels N -o "$out/f64.exr" --engine f64 --stats -q 2>&1)"; then
        f64_s="$(wall <<< "$f64")"
        ratio="$(awk -v a="$auto_s" -v f="$f64_s" 'BEGIN { printf "%.1f", a / f }')"
    else
        f64_s="refused"
        ratio="-"
    fi
    rows="$("$bin" compare "${common[@]}" --size 400x300 --samples "$samples" --only f64 --csv -q 2>/dev/null | tail -n +2)"
    pick() { awk -F, -v e="$1" '$1 == e { printf "%.4f | %s", $4, ($6 == "-" ? "-" : sprintf("%.2g", $6)) }' <<< "$rows"; }
    f64_acc="$(pick f64)"
    bla_acc="$(pick "perturb-f64 bla 1e-14")"
    echo "| $zoom | $engine | $auto_s | $f64_s | $ratio | ${f64_acc:-- | -} | ${bla_acc:-- | -} |"
done
