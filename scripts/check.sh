#!/usr/bin/env bash
# Runs exactly what CI runs (.ci/run calls this): formatting, lints (default and headless
# builds), documentation with warnings denied, the whole test suite.
# Needs only cargo to build; the viewer and GPU tests need a display server and a Vulkan
# adapter at run time (Xvfb, and Mesa's lavapipe software Vulkan), installed here when
# missing so this one command works on a fresh machine (as root, or with sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/common.sh
need=()
command -v xvfb-run > /dev/null || need+=(xvfb xauth)
ls /usr/share/vulkan/icd.d/lvp_icd*.json > /dev/null 2>&1 || need+=(mesa-vulkan-drivers libvulkan1)
apt_install "for the viewer and GPU tests" "${need[@]}"
# Tests run headless: no user session, so give the window system a runtime folder.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
# A fresh clone gains nothing from incremental compilation and pays for writing its state
# (a fifth of the time of each build of this crate); set CARGO_INCREMENTAL=1 to keep it.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

echo "== rustfmt"
cargo fmt --all -- --check

echo "== clippy"
cargo clippy --locked --all-targets -- -D warnings
# The headless build (no viewer, no wgpu) compiles and lints clean on its own.
cargo clippy --locked --no-default-features --lib --bins -- -D warnings

echo "== docs"
# With the examples, whose dev-dependencies then count, the dependencies' features resolve
# as for clippy's --all-targets run above, so rustdoc reuses its checked dependencies
# instead of checking most of them again with other features.
RUSTDOCFLAGS="-D warnings" cargo doc --locked --no-deps --lib --examples

echo "== tests"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# Unit, integration, bench (as tests) and example targets, then doc tests.
cargo test --locked --all-targets 2>&1 | tee "$log"
cargo test --locked --doc 2>&1 | tee -a "$log"
# One closing line for the whole run, summed over every test binary.
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "tests: %d passed, %d failed\n", p, f }' "$log"
