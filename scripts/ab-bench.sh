#!/usr/bin/env bash
# A/B timing of kernel bench binaries on a noisy machine: runs each binary's divan bench in
# turn, ROUNDS times, and prints per binary the "fastest" and "median" items/s of each round.
# Alternating matters: a shared machine's speed drifts by ±5% within minutes.
#
#   cargo bench --bench kernels --no-run      # then copy target/release/deps/kernels-<hash>
#   scripts/ab-bench.sh n_only 3 /tmp/kernels-old /tmp/kernels-new
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 BENCH ROUNDS BINARY..." >&2
  exit 2
fi
bench=$1 rounds=$2
shift 2
for _ in $(seq "$rounds"); do
  for b in "$@"; do
    line=$("$b" --bench "$bench" --sample-count 20 2>&1 | grep -A1 -- "─ $bench " | tail -1 | sed 's/[│╰├─]//g')
    echo "$b $(echo "$line" | awk '{print $1, $7}')"
  done
done | awk '{f[$1] = f[$1] " " $2; m[$1] = m[$1] " " $3}
  END {for (k in f) print k ": fastest" f[k] " | median" m[k]}'
