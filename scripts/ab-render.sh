#!/usr/bin/env bash
# A/B wall time of `deepfield render` builds (alternating rounds, `scripts/ab-run.sh`).
#
#   cp target/release/deepfield /tmp/df-old    # build the other version, then
#   scripts/ab-render.sh scenes/liiiines.toml 5 /tmp/df-old target/release/deepfield
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 SCENE ROUNDS BINARY..." >&2; exit 2; }
exec "$(dirname "$0")/ab-run.sh" "$2" "${@:3}" -- render "$1" -q
