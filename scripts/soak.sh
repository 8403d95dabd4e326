#!/usr/bin/env bash
# Fault soak: 1,000 seeded random fault schedules over both paper plans on the
# in-process virtual hardware, release build, 1 kHz control, 2 threads.
# Prints the fault table; fails on any corrupted execution, unsafe ending or panic.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p triquint-host --example fault_soak
start=$(date +%s)
"${CARGO_TARGET_DIR:-target}/release/examples/fault_soak" "${SOAK_SCHEDULES:-1000}" "${SOAK_THREADS:-2}" "${SOAK_SEED:-2026}"
echo "fault soak: $(( $(date +%s) - start )) s"
