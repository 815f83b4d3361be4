#!/usr/bin/env bash
# deepfield beside fractall-rust and Fraktaler-3 on formula families, side by side in one
# run: a Burning Ship location deeper than 1e100, a Mandelbar (tricorn) one deeper than
# 1e50 and a Mandelbrot power-3 one deeper than 1e50 (scenes/bench-burning-ship-e*.toml,
# bench-mandelbar-e*.toml, bench-mandelbrot3-e*.toml) are each rendered by the three
# programs in turn, ROUNDS times (alternating, since a shared machine's speed drifts),
# whole-process wall time, 800x600, one sample per pixel, the same iteration limit; the
# fastest and median of each program are printed, and each peer's median over deepfield's.
#
#   scripts/bench-formula-peers.sh FRACTALL_CLI FRAKTALER3 WISDOM [ROUNDS] [DEEPFIELD]
#
# SCENES="bench-mandelbrot3-e80 ..." (names in scenes/, without .toml) runs only those.
#
# Neither peer is built here; give "-" for one that is not at hand, and its rows say so.
# - fractall-rust (its `fractall-cli`): built from its source with `cargo build --release
#   --bin fractall-cli` in its own folder and its own target folder (Debian packages
#   libgmp-dev libmpfr-dev libmpc-dev; its `.cargo/config.toml` sets target-cpu=native).
#   It is run as its own harness runs it: `--toml` with a location in rust-fractal-core's
#   format (real, imag, zoom, iterations), `--width 800 --height 600 --bailout 25`, with
#   FRACTALL_NO_AUTO_ADJUST=1 FRACTALL_NO_PERIOD=1, and the family as `--type` (13 Burning
#   Ship, 14 Tricorn; power 3 as a `[[formula]]` block with `power = 3` in the location,
#   its perturbation route for powers other than 2: its `--type 23` Multibrot is not
#   perturbed at all, see docs/performance.md). Its zoom means the image WIDTH spans
#   4/zoom, so the location's zoom is deepfield's times height/width.
# - Fraktaler-3: its batch mode, built as scripts/bench-fraktaler3.sh says (version 2.1),
#   with its wisdom file. Its parameters carry the family as `[[formula]]` fields:
#   Burning Ship `abs_x = true, abs_y = true`, Mandelbar `neg_y = true`, power 3
#   `power = 3`; the per-pixel limits on perturbation iterations and BLA steps are the
#   iteration limit (as in bench-fraktaler3.sh). Its EXR is named as a save format with
#   raw channels only (`render.save_exr`, `render.exr_channels`): version 3.1 saves
#   nothing otherwise, and a build without its GUI cannot write colour channels.
# deepfield writes its PNG, fractall-rust its PNG, Fraktaler-3 its EXR (raw data only).
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 FRACTALL_CLI|- FRAKTALER3|- WISDOM|- [ROUNDS] [DEEPFIELD]" >&2
    exit 2
fi
fr=$1 f3=$2 wisdom=$3 rounds=${4:-3}
[ "$fr" = - ] || { fr=$(realpath "$fr"); [ -x "$fr" ] || { echo "no fractall-cli at $1" >&2; exit 2; }; }
if [ "$f3" != - ]; then
    f3=$(realpath "$f3") wisdom=$(realpath "$wisdom")
    [ -x "$f3" ] || { echo "no Fraktaler-3 binary at $2" >&2; exit 2; }
    [ -f "$wisdom" ] || { echo "no wisdom file at $3" >&2; exit 2; }
fi
here=$(cd "$(dirname "$0")/.." && pwd)
source "$here/scripts/common.sh"
peer_setup "$here" "${5:-}"
scenes=${SCENES:-}
[ -n "$scenes" ] || scenes=$(cd "$here/scenes" && ls bench-burning-ship-e*.toml bench-mandelbar-e*.toml bench-mandelbrot3-e*.toml 2> /dev/null | sed 's/\.toml$//' || true)
[ -n "$scenes" ] || { echo "no bench-burning-ship/mandelbar/mandelbrot3 scenes in $here/scenes" >&2; exit 2; }
for scene in $scenes; do
    # Writes $scene.fr.toml, $scene.fr.args (fractall-rust's flags) and $scene.f3.toml.
    python3 - "$here/scenes/$scene.toml" "$out/$scene" << 'EOF'
import sys, tomllib
from decimal import Decimal, getcontext
getcontext().prec = 60
s = tomllib.load(open(sys.argv[1], "rb"))
base = sys.argv[2]
re, im = s["view"]["center"]
zoom = s["view"]["zoom"]
w, h = s["view"]["width"], s["view"]["height"]
n = s["iteration"]["max"]
kind = s["formula"]["kind"]
power = s["formula"].get("power", 2)
# fractall-rust: --type and an optional [[formula]] block; Fraktaler-3: its phase fields.
fr_type, fr_formula, f3_fields = {
    ("burning-ship", 2): ("13", "", "abs_x = true\nabs_y = true\npower = 2"),
    ("mandelbar", 2): ("14", "", "neg_y = true\npower = 2"),
    ("mandelbrot", 3): ("3", "\n[[formula]]\npower = 3\n", "power = 3"),
}[(kind, power)]
fr_zoom = Decimal(zoom) * h / w
open(base + ".fr.toml", "w").write(
    f'real = "{re}"\nimag = "{im}"\nzoom = "{fr_zoom:.6E}"\niterations = {n}\nrotate = 0.0\n{fr_formula}')
open(base + ".fr.args", "w").write(f"--type {fr_type} --width {w} --height {h} --bailout 25\n")
open(base + ".f3.toml", "w").write(f'''program = "fraktaler-3"
location.real = "{re}"
location.imag = "{im}"
location.zoom = "{zoom}"
bailout.iterations = {n}
bailout.maximum_reference_iterations = {n}
bailout.maximum_perturb_iterations = {n}
bailout.maximum_bla_steps = {n}
image.width = {w}
image.height = {h}
image.subsampling = 1
image.subframes = 1
render.filename = "{base}"
render.save_exr = true
render.exr_channels = ["N0", "N1", "NF", "T", "DEX", "DEY"]

[[formula]]
{f3_fields}
''')
EOF
done
# run TAG COMMAND...: "TAG SECONDS" for a run that succeeds, "TAG failed" otherwise.
run() {
    local tag=$1
    shift
    timed "$tag" "$@" 2> "$out/err" || { echo "$tag failed"; sed 's/^/    /' "$out/err" | tail -n 3 >&2; }
}
printf '%-28s %-14s %10s %10s %8s\n' location program fastest median ratio
for scene in $scenes; do
    for _ in $(seq "$rounds"); do
        run d "$df" render "$here/scenes/$scene.toml" -o "$out/d.png" -q
        if [ "$fr" != - ]; then
            # shellcheck disable=SC2046 # the flags are words
            run fr env FRACTALL_NO_AUTO_ADJUST=1 FRACTALL_NO_PERIOD=1 "$fr" --toml "$out/$scene.fr.toml" \
                $(cat "$out/$scene.fr.args") --output "$out/fr.png"
        fi
        if [ "$f3" != - ]; then
            rm -f "$out/$scene.exr"
            run f3 "$f3" --batch --quiet --no-persistence --wisdom "$wisdom" "$out/$scene.f3.toml"
            [ -s "$out/$scene.exr" ] || echo "f3 failed"
        fi
    done | awk -v name="$scene" -v fr="$fr" -v f3="$f3" '
        $2 == "failed" { bad[$1] = 1; next }
        { t[$1] = t[$1] " " $2; n[$1]++ }
        function stats(tag,    a, k, i, j, x) {
            k = split(substr(t[tag], 2), a, " ")
            for (i = 2; i <= k; i++) { x = a[i]; for (j = i - 1; j >= 1 && a[j] > x; j--) a[j + 1] = a[j]; a[j + 1] = x }
            fast[tag] = a[1]; med[tag] = a[int((k + 1) / 2)]
        }
        function row(tag, label, given) {
            if (given == "-") { printf "%-28s %-14s %s\n", name, label, "not given"; return }
            if (bad[tag] || n[tag] == 0) { printf "%-28s %-14s %s\n", name, label, "FAILED (see above)"; return }
            stats(tag)
            printf "%-28s %-14s %9.2fs %9.2fs %8s\n", name, label, fast[tag], med[tag], \
                (tag == "d" || !med["d"]) ? "" : sprintf("%.2f", med[tag] / med["d"])
        }
        END { row("d", "deepfield", ""); row("fr", "fractall-rust", fr); row("f3", "Fraktaler-3", f3) }'
done
echo "ratio: the peer's median / deepfield's median (above 1: deepfield faster)"
