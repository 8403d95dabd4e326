#!/usr/bin/env bash
# Runs every test of triquint on a fresh Debian machine with Rust and Python:
# installs what it needs, then formatting, lints, unit/integration tests,
# and the Cortex-M4F (thumbv7em-none-eabihf) builds of the no_std crates.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }
start=$(date +%s)

step "toolchain: rustfmt, clippy, thumbv7em-none-eabihf"
if command -v rustup >/dev/null; then
    rustup component add rustfmt clippy >/dev/null
    rustup target add thumbv7em-none-eabihf >/dev/null
fi

step "cargo fmt --check"
cargo fmt --all --check

step "cargo clippy -D warnings"
cargo clippy --workspace --all-targets --locked -- -D warnings

step "cargo test"
cargo test --workspace --locked

step "fault soak (release)"
./scripts/soak.sh
./scripts/fuzz.sh   # short libFuzzer run of fuzz/ on stable (canary first)

step "no_std crates for thumbv7em-none-eabihf"
cargo build --locked -p triquint-shared -p triquint-firmware --target thumbv7em-none-eabihf

step "on-target test (QEMU mps2-an386) and the board images"
./scripts/qemu-test.sh

step "HIL suite: SocketCAN (vcan) in a virtme-ng VM"
./scripts/hil.sh

step "all tests passed in $(( $(date +%s) - start )) s"
