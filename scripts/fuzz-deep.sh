#!/usr/bin/env bash
# The deep-view fuzzer for as long as asked: generated views (minibrot neighbourhoods and
# descents, Misiurewicz points to 1e2000, early-escaping references, the f64/FloatExp line,
# Julia sets), every engine configuration and instruction set against direct big-float
# iteration. Views that break the accuracy bar are written to OUT as scene files that
# reproduce them; the log goes to OUT/fuzz.log. Exit status 1 when any view failed.
#
#   scripts/fuzz-deep.sh [SECONDS] [OUT] [EXTRA FLAGS...]   # default 600 s, fuzz-failures/
#
# Extra flags go to the fuzzer (examples/deep_fuzz.rs): --seed S, --pixels K, --size WxH,
# --min-depth D, --max-depth D, --max-iter N, --kinds a,b, --count N.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
out="${2:-fuzz-failures}"
shift 2 || shift $# || true
mkdir -p "$out"
cargo build --release --quiet --example deep_fuzz
target/release/examples/deep_fuzz --seconds "$seconds" --out "$out" "$@" 2>&1 | tee "$out/fuzz.log"
exit "${PIPESTATUS[0]}"
