#!/usr/bin/env bash
# The deep-view fuzzer for as long as asked: generated views (minibrot neighbourhoods and
# descents, Misiurewicz points to 1e2000, early-escaping references, the f64/FloatExp line,
# Julia sets, and for any formula boundary descents of its set, of its Julia sets, of the
# real axis, and Newton's periodic points), every engine configuration and instruction set
# against direct big-float iteration. Views that break the accuracy bar are written to OUT as
# scene files that reproduce them; the log goes to OUT/fuzz.log. Exit status 1 when any view
# failed.
#
#   scripts/fuzz-deep.sh [SECONDS] [OUT] [EXTRA FLAGS...]   # z² + c; default 600 s, fuzz-failures/
#   scripts/fuzz-deep.sh --formulas [SECONDS] [OUT] [EXTRA FLAGS...]
#       # every formula family at every power in turn, SECONDS each (default 120), the
#       # failures of each in OUT/NAME/
#   scripts/fuzz-deep.sh --formulas-short [OUT] [EXTRA FLAGS...]
#       # the short mode: every family at its smallest power, two small shallow views each
#
# Extra flags go to the fuzzer (examples/deep_fuzz.rs): --seed S, --pixels K, --size WxH,
# --min-depth D, --max-depth D, --max-iter N, --kinds a,b, --count N, --formula F.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=single
case "${1:-}" in
--formulas) mode=all; shift ;;
--formulas-short) mode=short; shift ;;
esac
if [ "$mode" = short ]; then
	seconds=120
else
	default=600
	[ "$mode" = all ] && default=120
	seconds="${1:-$default}"
	shift || true
fi
out="${1:-fuzz-failures}"
shift || true
mkdir -p "$out"
cargo build --release --quiet --example deep_fuzz
fuzz="${CARGO_TARGET_DIR:-target}/release/examples/deep_fuzz"
if [ "$mode" = single ]; then
	"$fuzz" --seconds "$seconds" --out "$out" "$@" 2>&1 | tee "$out/fuzz.log"
	exit "${PIPESTATUS[0]}"
fi
status=0
: >"$out/fuzz.log"
for formula in $("$fuzz" --list-formulas); do
	# The short mode takes each family once, at its smallest power (written without `^`).
	if [ "$mode" = short ] && [[ "$formula" == *^* ]]; then
		continue
	fi
	dir="$out/${formula//^/_}"
	extra=()
	if [ "$mode" = short ]; then
		extra=(--count 2 --size 32x24 --pixels 12 --min-depth 5 --max-depth 30 --max-iter 100000)
	fi
	echo "== $formula" | tee -a "$out/fuzz.log"
	if ! "$fuzz" --formula "$formula" --seconds "$seconds" --out "$dir" "${extra[@]}" "$@" 2>&1 | tee -a "$out/fuzz.log"; then
		status=1
	fi
done
exit "$status"
