#!/usr/bin/env bash
# The main job: on a fresh machine with Rust, builds triquint, plans both of
# the paper's cases, verifies and reports them. Output goes to ./out/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p triquint-host -p triquint-sim
bin="${CARGO_TARGET_DIR:-target}/release"
mkdir -p out
# The machine: the paper's, written out as a machine file (every key at
# its default; docs/machine.md). A real robot has its own.
machine=examples/machines/paper.toml

for case in paper-case1 paper-case2; do
    echo "== $case: plan"
    $bin/triquint plan "examples/$case.toml" -o "out/$case.json" --plot "out/$case" --machine $machine
    echo "== $case: independent check"
    $bin/triquint check "out/$case.json" --machine $machine | tail -n 1
    echo "== $case: report (plots in out/$case/)"
    $bin/triquint report "out/$case.json"
    echo "== $case: run on the virtual hardware (3 drives + plant, in-process CAN bus)"
    $bin/triquint simulate "out/$case.json" --machine $machine --json --plot "out/$case/sim" > "out/$case.sim.json"
    $bin/triquint simulate "out/$case.json" --machine $machine --json --no-feedforward > "out/$case.sim-noff.json"
    $bin/triquint simulate "out/$case.json" --machine $machine --json --fd > "out/$case.sim-fd.json"
    echo "== $case: the same on the flexible plant (screw, coupling and platform modes)"
    $bin/triquint simulate "out/$case.json" --machine $machine --plant flexible --json > "out/$case.sim-flex.json"
done

# Vibration: a move fast enough to ring the flexible plant's lowest mode,
# unshaped and with a ZVD shaper at it (docs/vibration.md).
echo "== p2p-fast: plan, unshaped and ZVD-shaped at 25.6 Hz; run both on the flexible plant"
$bin/triquint plan examples/p2p-fast.toml -o out/p2p-fast.json --machine $machine --quiet
$bin/triquint plan examples/p2p-fast.toml -o out/p2p-fast-zvd.json --machine $machine --quiet \
    --shaper zvd:25.6:0.062
for p in p2p-fast p2p-fast-zvd; do
    $bin/triquint simulate "out/$p.json" --machine $machine --plant flexible --json > "out/$p.sim-flex.json"
done

echo
echo "max |jerk| (m/s³)      Case I   Case II"
echo "paper, as printed      3.102    2.808"
echo "paper's h, re-solved   1.054    2.661"
printf 'triquint               %.4f   %.4f\n' \
    "$(python3 -c 'import json,sys; print(max(json.load(open(sys.argv[1]))["max_abs"]["jerk"]))' out/paper-case1.json)" \
    "$(python3 -c 'import json,sys; print(max(json.load(open(sys.argv[1]))["max_abs"]["jerk"]))' out/paper-case2.json)"
python3 - <<'PY'
import json
def load(n): return json.load(open(n))
print()
print(f"{'virtual hardware':30} {'Case I':>12} {'Case II':>12}")
rows = [("RMS tracking error, FF (µm)", ".sim.json", lambda r: max(r["rms_error_m"]) * 1e6),
        ("RMS tracking error, no FF (µm)", ".sim-noff.json", lambda r: max(r["rms_error_m"]) * 1e6),
        ("bus load, classic 1 Mbit/s (%)", ".sim.json", lambda r: r["bus_load"] * 100),
        ("bus load, CAN-FD (%)", ".sim-fd.json", lambda r: r["bus_load"] * 100),
        ("completed without fault", ".sim.json", lambda r: r["completed"] and not r["faults"]),
        ("flexible plant: RMS error (µm)", ".sim-flex.json", lambda r: max(r["rms_error_m"]) * 1e6),
        ("  residual at the mode (mm/s²)", ".sim-flex.json", lambda r: r["vibration"]["lowest_mode_m_s2"] * 1e3),
        ("  completed without fault", ".sim-flex.json", lambda r: r["completed"] and not r["faults"])]
for name, suffix, f in rows:
    vals = [f(load(f"out/paper-case{c}{suffix}")) for c in (1, 2)]
    print(f"{name:30} " + " ".join(f"{v:>12.3f}" if not isinstance(v, bool) else f"{str(v):>12}" for v in vals))
print()
print("fast point-to-point move, flexible plant    unshaped   ZVD 25.6 Hz")
runs = [load(f"out/{p}.sim-flex.json") for p in ("p2p-fast", "p2p-fast-zvd")]
for name, f in [("duration (s)", lambda r: r["duration_s"]),
                ("residual at the mode (mm/s²)", lambda r: r["vibration"]["lowest_mode_m_s2"] * 1e3),
                ("residual RMS (mm/s²)", lambda r: r["vibration"]["rms_accel_m_s2"] * 1e3)]:
    print(f"{name:42} " + " ".join(f"{f(r):>10.3f}" for r in runs))
print(f"{'shaped residual / unshaped':42} {'':>10} {runs[1]['vibration']['lowest_mode_m_s2'] / runs[0]['vibration']['lowest_mode_m_s2']:>10.3f}")
PY
