#!/usr/bin/env bash
# A/B wall time of `deepfield render` builds on a noisy machine: renders SCENE with each
# binary in turn, ROUNDS times (alternating, since this VM's speed drifts within minutes),
# and prints per binary the fastest and the median wall time.
#
#   cp target/release/deepfield /tmp/df-old    # build the other version, then
#   scripts/ab-render.sh scenes/liiiines.toml 5 /tmp/df-old target/release/deepfield
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 SCENE ROUNDS BINARY..." >&2
  exit 2
fi
scene=$1 rounds=$2
shift 2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq "$rounds"); do
  for b in "$@"; do
    start=$(date +%s.%N)
    "$b" render "$scene" -o "$out/x.png" -q
    end=$(date +%s.%N)
    echo "$b $(echo "$end - $start" | bc -l)"
  done
done | sort -k1,1 -k2,2n | awk '{t[$1] = t[$1] " " sprintf("%.2f", $2); n[$1]++}
  END {for (k in t) {split(substr(t[k], 2), v, " "); printf "%s: fastest %s median %s (all:%s)\n", k, v[1], v[int((n[k] + 1) / 2)], t[k]}}'
