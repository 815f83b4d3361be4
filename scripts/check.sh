#!/usr/bin/env bash
# Runs exactly what CI runs (.ci/run calls this): formatting, lints, the whole test suite.
# Needs only cargo; system packages that future window/GPU tests need are installed here
# when missing, so this one command works on a fresh machine.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== rustfmt"
cargo fmt --all -- --check

echo "== clippy"
cargo clippy --locked --all-targets -- -D warnings

echo "== tests"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# Unit, integration, bench (as tests) and example targets, then doc tests.
cargo test --locked --all-targets 2>&1 | tee "$log"
cargo test --locked --doc 2>&1 | tee -a "$log"
# One closing line for the whole run, summed over every test binary.
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "tests: %d passed, %d failed\n", p, f }' "$log"
