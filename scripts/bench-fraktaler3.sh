#!/usr/bin/env bash
# deepfield beside Fraktaler-3 (Claude Heiland-Allen's deep zoom engine), side by side in one
# run: each benchmark location is rendered by both programs in turn, ROUNDS times
# (alternating, since a shared machine's speed drifts), whole-process wall time, and the
# fastest and median of each are printed.
#
# Fraktaler-3 is not built here. Build its batch mode yourself from its source (version 2.1
# was used: `make headers`, then its sources compiled with `-O3 -march=native
# -DHAVE_EXR=3 -DHAVE_FS`, with -DHAVE_CL for OpenCL; Debian packages libglm-dev
# libmpfr-dev libmpfrc++-dev libopenexr-dev libsdl2-dev libtoml11-dev), then give it
# hardware "wisdom" (`F3 --generate-wisdom --wisdom W`, then `F3 --benchmark-wisdom
# --wisdom W`), from which it picks its number type by the depth of each view.
#
#   scripts/bench-fraktaler3.sh ~/src/fraktaler-3/fraktaler-3 wisdom.toml 3
#
# Each location's parameters are written from deepfield's scene (the same centre strings,
# zoom with the same meaning: the image height spans 4/zoom, iteration limit, 800x600, one
# sample per pixel). Fraktaler-3's per-pixel limits on perturbation iterations and BLA steps
# are set to the iteration limit: at the "few thousand" its documentation suggests, pixels
# of bench-e50 and bench-e227 stop early and come out as interior (4815 and 44096 of them
# in version 2.1). Both write the same raw data, an EXR of N, NF, T, DEX and DEY (so both
# carry the derivative for the distance estimate), and deepfield its PNG as well. The
# parameters name the EXR and its raw channels (`render.save_exr`, `render.exr_channels`):
# version 3.1 saves nothing otherwise, and a build of it without GUI writes no colour.
set -euo pipefail
if [ $# -lt 2 ]; then
    echo "usage: $0 FRAKTALER3_BINARY WISDOM [ROUNDS] [DEEPFIELD]" >&2
    exit 2
fi
f3=$(realpath "$1") wisdom=$(realpath "$2") rounds=${3:-3}
[ -x "$f3" ] || { echo "no Fraktaler-3 binary at $1" >&2; exit 2; }
[ -f "$wisdom" ] || { echo "no wisdom file at $2" >&2; exit 2; }
here=$(cd "$(dirname "$0")/.." && pwd)
source "$here/scripts/common.sh"
peer_setup "$here" "${4:-}"
scenes="bench-e14 bench-e50 bench-e113 bench-e227 bench-e533 bench-e1086"
for scene in $scenes; do
    python3 - "$here/scenes/$scene.toml" "$out/$scene" > "$out/$scene.f3.toml" << 'EOF'
import sys, tomllib
s = tomllib.load(open(sys.argv[1], "rb"))
re, im = s["view"]["center"]
n = s["iteration"]["max"]
print(f'''program = "fraktaler-3"
location.real = "{re}"
location.imag = "{im}"
location.zoom = "{s["view"]["zoom"]}"
bailout.iterations = {n}
bailout.maximum_reference_iterations = {n}
bailout.maximum_perturb_iterations = {n}
bailout.maximum_bla_steps = {n}
image.width = {s["view"]["width"]}
image.height = {s["view"]["height"]}
image.subsampling = 1
image.subframes = 1
render.filename = "{sys.argv[2]}"
render.save_exr = true
render.exr_channels = ["N0", "N1", "NF", "T", "DEX", "DEY"]

[[formula]]
power = 2''')
EOF
done
printf '%-12s %22s %22s %8s\n' location "deepfield (fast/med)" "Fraktaler-3" ratio
for scene in $scenes; do
    for _ in $(seq "$rounds"); do
        timed d "$df" render "$here/scenes/$scene.toml" -o "$out/d.png" --exr "$out/d.exr" -q
        timed p "$f3" --batch --quiet --no-persistence --wisdom "$wisdom" "$out/$scene.f3.toml"
        [ -s "$out/$scene.exr" ] || { echo "Fraktaler-3 wrote no $scene.exr" >&2; exit 1; }
        rm -f "$out/$scene.exr"
    done | medians "$scene"
done
echo "ratio: deepfield median / Fraktaler-3 median (below 1: deepfield faster)"
