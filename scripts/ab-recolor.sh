#!/usr/bin/env bash
# A/B wall time and peak memory of `deepfield recolor DATA.exr` builds (alternating
# rounds, `scripts/ab-run.sh`).
#
#   deepfield render scenes/seahorse-valley.toml --size 3840x2160 --aa 1 --exr /tmp/s4k.exr
#   scripts/ab-recolor.sh /tmp/s4k.exr 9 /tmp/df-old target/release/deepfield
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 DATA.exr ROUNDS BINARY..." >&2; exit 2; }
exec "$(dirname "$0")/ab-run.sh" "$2" "${@:3}" -- recolor "$1"
