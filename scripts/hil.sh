#!/usr/bin/env bash
# Hardware-in-the-loop suite on a real SocketCAN interface: installs what it
# needs, builds the release binaries, plans both paper cases on the host, then
# boots one small VM (virtme-ng, the distribution kernel, emulated CPU) that
# loads vcan, brings up vcan0 and vcan1 (MTU 72, CAN-FD) and runs the pytest suite in
# hil-sim/python/ once. Exit status: the suite's (124 when the VM timed out).
#
# Needs root (apt-get, pip). Output: target/hil/ (vm.log, reports, candump
# logs) and a table of the measured figures, over vcan against in process.
# HIL_PYTEST_ARGS passes pytest options (e.g. "-k upload" for the demo only).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
OUT="$ROOT/target/hil"
step() { printf '\n==> hil: %s\n' "$*"; }

step "packages"
need=()
for p in qemu-system-x86 linux-image-amd64 can-utils busybox-static; do
    dpkg -s "$p" >/dev/null 2>&1 || need+=("$p")
done
if [ ${#need[@]} -gt 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
PY=$(python3 -c 'import sys; print(sys.executable)')
if ! "$PY" -c 'import can, cantools, pytest, virtme_ng' 2>/dev/null; then
    pkgs=(virtme-ng python-can cantools pytest)
    "$PY" -m pip install -q "${pkgs[@]}" 2>/dev/null \
        || "$PY" -m pip install -q --break-system-packages "${pkgs[@]}"
fi
# vng runs virtme-run by name: pip's script folder on PATH (a pyenv shim
# exists only after a rehash, which an earlier install may not have had).
export PATH="$(dirname "$PY"):$PATH"
VNG=$(command -v vng || echo "$(dirname "$PY")/vng")

step "release binaries"
nice cargo build --release --locked -p triquint-host -p triquint-sim
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release"
BIN=$(cd "$BIN" && pwd)

rm -rf "$OUT"
mkdir -p "$OUT/plans"
step "plans (on the host: the guest computes ~11x slower)"
for c in 1 2; do
    "$BIN/triquint" plan "examples/paper-case$c.toml" -o "$OUT/plans/paper-case$c.json" --quiet
done
# Issue 35's streaming fixtures (test_streaming.py), each through `check`.
# With triquint-host selected too, the example's features are the fault
# soak's (scripts/soak.sh), whose build it reuses; alone it needs its own.
nice cargo build --release --locked -q -p triquint-host -p triquint-sim --example streaming_fixtures
"$BIN/examples/streaming_fixtures" "$OUT/plans"
for f in "$OUT"/plans/stream-*.json; do
    "$BIN/triquint" check "$f" >/dev/null
done

# The guest sees the host's root file system read-only, with PATH reset:
# everything by absolute path; only $OUT is written back.
cat > "$OUT/in-vm.sh" <<VM
#!/bin/sh
cd "$ROOT"
modprobe vcan || exit 90
# vcan1: the drives' side of the fault-injecting proxy (test_faults.py).
for i in vcan0 vcan1; do
    ip link add dev \$i type vcan && ip link set \$i mtu 72 && ip link set up \$i || exit 91
done
export TRIQUINT="$BIN/triquint" TRIQUINT_SIM="$BIN/triquint-sim" HIL_OUT="$OUT" \
    HIL_PLANS="$OUT/plans" HIL_ROOT="$ROOT" HIL_IFACE=vcan0 HIL_IFACE_B=vcan1 PYTHONDONTWRITEBYTECODE=1 \
    PATH="\$PATH:/usr/bin:/sbin"
"$PY" -m pytest -p no:cacheprovider -v -rfE --durations=12 \
    --junitxml="$OUT/junit.xml" hil-sim/python ${HIL_PYTEST_ARGS:-}
status=\$?
# The guest kernel's log (clocksource changes, stalls), kept beside the
# simulator's own, which logs when its ticks ran late (docs/vcan.md).
dmesg > "$OUT/dmesg.log" 2>&1
echo "\$status" > "$OUT/status"
exit \$status
VM
chmod +x "$OUT/in-vm.sh"

step "VM: boot, vcan0, pytest (emulated CPU: 1-5 min)"
kernel=/boot/vmlinuz-$(ls /lib/modules | sort -V | tail -1)
set +e
# No '> file' redirection: QEMU reopens stdout/stderr; pipe instead.
timeout "${HIL_TIMEOUT:-900}" "$VNG" --force-9p --run "$kernel" --user root --disable-kvm \
    --memory 2G --cpus 2 --rwdir "$OUT" --exec "$OUT/in-vm.sh" 2>&1 | tee "$OUT/vm.log"
status=${PIPESTATUS[0]}
set -e
if [ "$status" -eq 0 ] && [ "$(cat "$OUT/status" 2>/dev/null)" != 0 ]; then
    echo "hil: the suite did not report a status (VM failure)" >&2
    status=1
fi
step "figures: over vcan (VM, real time) against in process (host)"
for c in 1 2; do
    for fd in "" --fd; do
        "$BIN/triquint" simulate "$OUT/plans/paper-case$c.json" $fd --json \
            > "$OUT/inproc-case$c${fd:+-fd}.json" || true
    done
done
for f in "$OUT"/plans/stream-*.json; do
    for fd in "" --fd; do
        "$BIN/triquint" simulate "$f" $fd --json \
            > "$OUT/inproc-$(basename "$f" .json)${fd:+-fd}.json" || true
    done
done
"$PY" scripts/hil_figures.py "$OUT" || true
if [ "$status" -ne 0 ]; then
    step "failures (the suite's report of each, and its simulators' logs)"
    "$PY" scripts/hil_failures.py "$OUT" || true
fi
step "HIL suite exit status $status"
exit "$status"
