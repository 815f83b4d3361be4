#!/usr/bin/env bash
# Runs the libFuzzer targets in fuzz/ (cargo-fuzz) for SECONDS each (default 600): scene
# TOML, .kfr, every palette importer, the PNG scene chunk, the EXR reader behind recolor,
# reference files, and the work units `assemble` reads. Seeds come from fuzz/corpus/TARGET (small, in the repository);
# the growing corpus lives in fuzz/work/ and crashes in fuzz/artifacts/ (both ignored by
# git). cargo-fuzz needs nightly compiler flags: on a stable toolchain they are enabled
# with RUSTC_BOOTSTRAP=1, as here. Every crash found becomes a regression test.
#   scripts/fuzz.sh 3600            # an hour per target
#   scripts/fuzz.sh 60 palette exr  # a minute for two targets
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene kfr palette png_scene exr reference_file assemble)
command -v cargo-fuzz > /dev/null || cargo install cargo-fuzz --locked
export RUSTC_BOOTSTRAP=1
for t in "${targets[@]}"; do
    mkdir -p "fuzz/work/$t"
    cp -n fuzz/corpus/"$t"/* "fuzz/work/$t/" 2> /dev/null || true
    echo "== $t ($seconds s)"
    (cd fuzz && cargo fuzz run -O --sanitizer none "$t" "work/$t" -- \
        -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=20 -print_final_stats=1 2>&1) |
        grep -E "stat::number_of_executed_units|stat::peak_rss_mb|ERROR|panicked|deadly signal|Test unit written" || true
done
