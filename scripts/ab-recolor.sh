#!/usr/bin/env bash
# Alternating wall-clock and peak-memory runs of `deepfield recolor DATA.exr` for several
# builds, ROUNDS rounds (this VM's speed drifts, so builds are compared within a round).
#
#   deepfield render scenes/seahorse-valley.toml --size 3840x2160 --aa 1 --exr /tmp/s4k.exr
#   scripts/ab-recolor.sh /tmp/s4k.exr 9 /tmp/df-old target/release/deepfield
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 DATA.exr ROUNDS BINARY..." >&2
  exit 2
fi
data=$1 rounds=$2
shift 2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for r in $(seq "$rounds"); do
  for b in "$@"; do
    /usr/bin/time -f "$b %e s %M KB" "$b" recolor "$data" -o "$out/x.png" 2>&1 | tail -1
  done
done | sort -k1,1 -k2,2n | awk '
  { n[$1]++; v[$1, n[$1]] = $2; m[$1] = $4 }
  END { for (b in n) printf "%s: median %.2f s (min %.2f, max %.2f, %d runs), peak %d MB\n", b, v[b, int((n[b] + 1) / 2)], v[b, 1], v[b, n[b]], n[b], m[b] / 1024 }'
