#!/usr/bin/env bash
# Alternating A/B runs of deepfield builds on a noisy machine (its speed drifts within
# minutes, so builds are compared within a round): runs `BINARY ARGS... -o TMP.png` with each
# binary in turn, ROUNDS times, and prints per binary the median, fastest and slowest wall
# time and the peak memory. `ab-render.sh` and `ab-recolor.sh` are this with their command.
#
#   scripts/ab-run.sh 5 /tmp/df-old target/release/deepfield -- render scenes/liiiines.toml -q
set -euo pipefail
usage() {
  echo "usage: $0 ROUNDS BINARY... -- ARGS..." >&2
  exit 2
}
[ $# -ge 3 ] || usage
rounds=$1
shift
binaries=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
  binaries+=("$1")
  shift
done
[ $# -ge 2 ] && [ ${#binaries[@]} -ge 1 ] || usage
shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq "$rounds"); do
  for b in "${binaries[@]}"; do
    /usr/bin/time -f "$b %e s %M KB" "$b" "$@" -o "$out/x.png" 2>&1 | tail -1
  done
done | sort -k1,1 -k2,2n | awk '
  { n[$1]++; v[$1, n[$1]] = $2; if ($4 > m[$1]) m[$1] = $4 }
  END { for (b in n) printf "%s: median %.2f s (fastest %.2f, slowest %.2f, %d runs), peak %d MB\n", b, v[b, int((n[b] + 1) / 2)], v[b, 1], v[b, n[b]], n[b], m[b] / 1024 }'
