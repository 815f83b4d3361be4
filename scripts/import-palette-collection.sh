#!/usr/bin/env bash
# Imports every palette file under a folder (.map, .ugr, .ggr, .cpt, .kfp: Fractint maps,
# Ultra Fractal gradient collections, GIMP gradients, GMT tables, Kalles Fraktaler
# palettes) with `deepfield palettes import`, and prints each failure, the files imported
# and the palettes they held (a .ugr collection holds many).
# Usage: scripts/import-palette-collection.sh DIR [path/to/deepfield]
# Checked here on Fractint's 25 .map files (github.com/LegalizeAdulthood/fractint-legacy)
# and JWildfire's 6 Ultra Fractal .ugr collections (github.com/thargor6/JWildfire,
# resources/org/jwildfire/create/tina/io/scripts): every file imports.
set -euo pipefail
dir=$1
bin="${2:-$(dirname "$0")/../target/release/deepfield}"
[ -x "$bin" ] || (cd "$(dirname "$0")/.." && cargo build --release --locked)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ok=0
bad=0
palettes=0
while IFS= read -r -d '' f; do
    mkdir -p "$work/out"
    if out=$("$bin" palettes import "$f" -o "$work/out/" 2>&1); then
        ok=$((ok + 1))
        palettes=$((palettes + $(find "$work/out" -name '*.toml' | wc -l)))
    else
        bad=$((bad + 1))
        echo "FAIL ${f#"$dir/"}: $out"
    fi
    rm -rf "$work/out"
done < <(find "$dir" \( -iname '*.map' -o -iname '*.ugr' -o -iname '*.ggr' -o -iname '*.cpt' -o -iname '*.kfp' \) -print0 | sort -z)
echo "imported $ok of $((ok + bad)) files ($palettes palettes)"
[ "$bad" -eq 0 ]
