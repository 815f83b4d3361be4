#!/usr/bin/env bash
# Imports every .ggr and .cpt palette Debian ships (gimp-data: GIMP gradients; gmt-common:
# GMT colour tables) with `deepfield palettes import`, and prints each failure and a count.
# Downloads the two packages with apt-get (no install), unpacks them in a temporary folder.
# Usage: scripts/import-debian-palettes.sh [path/to/deepfield]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/release/deepfield}"
[ -x "$bin" ] || cargo build --release --locked
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && apt-get download gimp-data gmt-common > /dev/null)
for deb in "$work"/*.deb; do dpkg-deb -x "$deb" "$work/root"; done
ok=0
bad=0
while IFS= read -r -d '' f; do
    if out=$("$bin" palettes import "$f" -o "$work/out.toml" 2>&1); then
        ok=$((ok + 1))
    else
        bad=$((bad + 1))
        echo "FAIL ${f#"$work/root/"}: $out"
    fi
    rm -f "$work/out.toml"
    rm -rf "$work/out"
done < <(find "$work/root" \( -name '*.ggr' -o -name '*.cpt' \) -print0 | sort -z)
echo "imported $ok of $((ok + bad)) palette files"
[ "$bad" -eq 0 ]
