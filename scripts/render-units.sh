#!/usr/bin/env bash
# Renders SCENE as N work units and assembles them into OUT: with GNU parallel when it is
# installed (add `--sshloginfile FILE` through PARALLEL_OPTS to spread the units over
# machines that share this folder and have deepfield on their PATH), else with xargs -P
# on this machine.
# Usage: scripts/render-units.sh SCENE N OUT.png [extra render flags...]
#   PARALLEL_OPTS="--sshloginfile nodes.txt --workdir ." scripts/render-units.sh poster.toml 32 poster.png
set -euo pipefail
scene=$1 n=$2 out=$3
shift 3
bin="${DEEPFIELD:-deepfield}"
mkdir -p units
if command -v parallel > /dev/null; then
    # shellcheck disable=SC2086
    seq 0 $((n - 1)) | parallel ${PARALLEL_OPTS:-} --halt now,fail=1 \
        "$bin" render "$scene" --tile "{}/$n" --quiet -o "units/unit-{}.png" "$@"
else
    seq 0 $((n - 1)) | xargs -P "$(nproc)" -I{} "$bin" render "$scene" --tile "{}/$n" --threads 1 --quiet \
        -o "units/unit-{}.png" "$@"
fi
files=()
for ((k = 0; k < n; k++)); do files+=("units/unit-$k.png"); done
"$bin" assemble "${files[@]}" -o "$out"
