#!/usr/bin/env bash
# Runs every test of triquint on a fresh Debian machine with Rust and Python:
# installs what it needs, then formatting, lints, unit/integration tests,
# and the Cortex-M4F (thumbv7em-none-eabihf) builds of the no_std crates.
set -euo pipefail
cd "$(dirname "$0")/.."

# A fresh machine has no incremental caches to reuse: writing them only
# slows the from-scratch dev and test builds.
export CARGO_INCREMENTAL=0

start=$(date +%s)
last=$start
# Each step prints the time the one before it took (CI must stay under 30 min).
step() {
    local now
    now=$(date +%s)
    [ "$now" -gt "$start" ] && printf '(%d s)\n' $((now - last))
    last=$now
    printf '\n==> %s\n' "$*"
}

step "toolchain: rustfmt, clippy, thumbv7em-none-eabihf"
if command -v rustup >/dev/null; then
    rustup component add rustfmt clippy >/dev/null
    rustup target add thumbv7em-none-eabihf >/dev/null
fi

step "cargo fmt --check"
cargo fmt --all --check

step "cargo clippy -D warnings"
cargo clippy --workspace --all-targets --locked -- -D warnings

step "cargo doc -D warnings (no broken or private links in the API docs)"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --locked --quiet

step "cargo test"
# The fuzz targets' build (its own target directory and flags, niced) runs
# beside the tests, which leave part of the second core idle; the fuzz step
# below then only runs them.
fuzz_build_log="${CARGO_TARGET_DIR:-target}/fuzz-build.log"
FUZZ_BUILD_ONLY=1 ./scripts/fuzz.sh > "$fuzz_build_log" 2>&1 &
fuzz_build=$!
trap 'kill "$fuzz_build" 2>/dev/null || true' EXIT
# cargo-nextest (on the project's machines) runs every test binary's tests
# in one pool, so a long test no longer leaves the second core idle while
# its binary finishes; it does not run doctests, so they run after it.
if cargo nextest --version >/dev/null 2>&1; then
    cargo nextest run --workspace --locked --no-fail-fast --config-file scripts/nextest.toml \
        --status-level fail --final-status-level slow
    cargo test --workspace --locked --doc
else
    cargo test --workspace --locked
fi
if ! wait "$fuzz_build"; then
    cat "$fuzz_build_log"
    echo "the fuzz targets' build failed" >&2
    exit 1
fi
trap - EXIT

step "fault soak (release)"
# 200 schedules here (8 per fault kind, about a minute; `scripts/soak.sh`
# alone runs 1 000, docs/verification.md).
SOAK_SCHEDULES=${SOAK_SCHEDULES:-200} ./scripts/soak.sh
FUZZ_SECONDS=${FUZZ_SECONDS:-12} ./scripts/fuzz.sh   # short libFuzzer run of fuzz/ on stable (canary first)

step "Python package: abi3 wheel in a fresh venv (pip install ./host/python), pytest"
# The README's install command; the wheel reuses target/ (absolute: pip runs
# cargo from host/python). matplotlib for the figures example's test.
cargo build --release --locked -p triquint-host
target_dir="$(realpath "${CARGO_TARGET_DIR:-target}")"
venv="$target_dir/py-venv"
rm -rf "$venv"
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check pytest matplotlib
py_start=$(date +%s)
CARGO_TARGET_DIR="$target_dir" nice "$venv/bin/pip" install --quiet --disable-pip-version-check ./host/python
echo "wheel built and installed in $(( $(date +%s) - py_start )) s"
TRIQUINT_BIN="$target_dir/release/triquint" "$venv/bin/python" -m pytest -q host/python/tests

step "getting started: the README's tutorial, as written, in a fresh clone"
# Reuses the release build above for its `cargo install --path host`.
CARGO_TARGET_DIR="$target_dir" ./scripts/getting-started.sh

step "no_std crates for thumbv7em-none-eabihf"
cargo build --locked -p triquint-shared -p triquint-firmware --target thumbv7em-none-eabihf
# The plan file type with alloc and without std (a host-less user of plans).
cargo build --locked -p triquint-shared --features alloc --target thumbv7em-none-eabihf

step "on-target test (QEMU mps2-an386) and the board images"
./scripts/qemu-test.sh

step "web monitor in headless Chromium (replayed testdata/hil log)"
# Debian's chromium (after qemu-test.sh, whose apt-get update it reuses);
# the page, its stream and its console, and a screenshot as an artefact
# (target/web-monitor.png; docs/web-monitor.png is one).
if ! command -v chromium >/dev/null; then
    apt_chromium() {
        DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 install -y -qq \
            --no-install-recommends chromium >/dev/null
    }
    apt_chromium || { apt-get -o DPkg::Lock::Timeout=600 update -qq && apt_chromium; }
fi
timeout 120 python3 scripts/web_chromium.py "$target_dir/release/triquint" \
    testdata/hil/case1-classic.candump.log "$target_dir/web-monitor.png"

step "HIL suite: SocketCAN (vcan) in a virtme-ng VM"
./scripts/hil.sh

step "all tests passed in $(( $(date +%s) - start )) s"
