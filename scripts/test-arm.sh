#!/usr/bin/env bash
# The aarch64 build, NEON lanes included, run on this x86-64 machine under QEMU's user-mode
# emulation: clippy for the target (its cfg(target_arch) code is linted nowhere else), the
# library's whole test suite (every SIMD test runs each level the CPU has,
# here scalar and NEON, against the scalar loop, bit for bit), then shipped scenes rendered
# by the aarch64 binary with --simd neon and --simd scalar, whose PNG bytes must equal each
# other and the native x86-64 build's.
#
# Not part of CI: the cross build takes about ten minutes on two cores and the emulated
# suite several more. Installs what it needs where it is missing (the Rust target, QEMU,
# the cross linker; apt as root or with sudo).
#
#   scripts/test-arm.sh            # everything
#   scripts/test-arm.sh simd lanes # only the library tests whose names contain these
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/common.sh
target=aarch64-unknown-linux-gnu
sysroot=/usr/aarch64-linux-gnu

rustup target list --installed | grep -qx "$target" || rustup target add "$target"
need=()
command -v qemu-aarch64 > /dev/null || need+=(qemu-user)
command -v aarch64-linux-gnu-gcc > /dev/null || need+=(gcc-aarch64-linux-gnu)
[ -d "$sysroot/lib" ] || need+=(libc6-dev-arm64-cross)
apt_install "to build for aarch64 and run it here" "${need[@]}"
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L $sysroot"
# The headless build: the viewer's window system has nothing to show under emulation.
flags=(--locked --release --target "$target" --no-default-features)

if [ $# -eq 0 ]; then
    # The code behind cfg(target_arch = "aarch64") is linted nowhere else.
    echo "== clippy for $target"
    cargo clippy --locked --target "$target" --all-targets -- -D warnings
fi

echo "== library tests on $target (emulated)"
cargo test "${flags[@]}" --lib -- --test-threads 2 "$@"
[ $# -eq 0 ] || exit 0

echo "== the aarch64 binary beside the native one"
cargo build "${flags[@]}" --bin deepfield
cargo build --locked --release --bin deepfield
dir=${CARGO_TARGET_DIR:-target}
arm=(qemu-aarch64 -L "$sysroot" "$dir/$target/release/deepfield")
native=$dir/release/deepfield
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "aarch64 levels: $("${arm[@]}" render scenes/seahorse-valley.toml --size 8x6 --simd neon -o "$out/s.png" --stats -q | awk '/^simd/ {$1=""; print substr($0, 2)}')"
failed=0
# Shallow (the vectorised f64 kernel), deep with f64 deltas, deep with FloatExp deltas, a
# nucleus-centred view with interior detection, a Julia set, a trap and distance layers.
for scene in seahorse-valley bench-e50 liiiines minibrot-e102 julia-deep-e310 julia-bitmap-trap lit-spiral; do
    [ -f "scenes/$scene.toml" ] || { echo "missing scene $scene" >&2; failed=1; continue; }
    "${arm[@]}" render "scenes/$scene.toml" --size 160x120 --simd neon -o "$out/neon.png" -q
    "${arm[@]}" render "scenes/$scene.toml" --size 160x120 --simd scalar -o "$out/scalar.png" -q
    "$native" render "scenes/$scene.toml" --size 160x120 -o "$out/x86.png" -q
    verdict=same
    cmp -s "$out/neon.png" "$out/scalar.png" || { verdict="NEON differs from scalar"; failed=1; }
    cmp -s "$out/neon.png" "$out/x86.png" || { verdict="$verdict; aarch64 differs from x86-64"; failed=1; }
    printf '%-20s %s\n' "$scene" "$verdict"
done
exit "$failed"
