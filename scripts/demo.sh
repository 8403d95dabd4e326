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
print(f"{'virtual hardware':28} {'Case I':>12} {'Case II':>12}")
rows = [("RMS tracking error, FF (µm)", ".sim.json", lambda r: max(r["rms_error_m"]) * 1e6),
        ("RMS tracking error, no FF (µm)", ".sim-noff.json", lambda r: max(r["rms_error_m"]) * 1e6),
        ("bus load, classic 1 Mbit/s (%)", ".sim.json", lambda r: r["bus_load"] * 100),
        ("bus load, CAN-FD (%)", ".sim-fd.json", lambda r: r["bus_load"] * 100),
        ("completed without fault", ".sim.json", lambda r: r["completed"] and not r["faults"])]
for name, suffix, f in rows:
    vals = [f(load(f"out/paper-case{c}{suffix}")) for c in (1, 2)]
    print(f"{name:28} " + " ".join(f"{v:>12.3f}" if not isinstance(v, bool) else f"{str(v):>12}" for v in vals))
PY
