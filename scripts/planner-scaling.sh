#!/usr/bin/env bash
# The planner's scaling benchmark (issue 39): plans the closed curve at 0.25
# and at 0.8 s a segment and the seeded random walk at 0.25 s a segment
# (host/planner/examples/scaling_paths.rs) at each N via-points, one whole
# `triquint plan` process each, and prints wall and CPU time, peak memory,
# LP solves, the max jerk reached (or the exit and message), and the growth
# exponent of wall time, CPU time and memory from the N before.
#
#   scripts/planner-scaling.sh TRIQUINT [N ...]      (default N: 10 100 1000 2000)
#
# Not run by CI: at 1 000 and 2 000 via-points it takes tens of minutes.
# TIMEOUT (seconds, default 1800) bounds each plan. Figures and the run they
# came from: docs/planner-speed.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "$1")
shift
ns=("$@")
[ ${#ns[@]} -gt 0 ] || ns=(10 100 1000 2000)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

gen() { cargo run --quiet --release --locked -p triquint-planner --example scaling_paths -- "$@" >/dev/null; }
gen "$work/curve-0.25" 0.25 "${ns[@]}"
gen "$work/curve-0.8" 0.8 "${ns[@]}"
gen "$work/walk-0.25" --walk 0.25 "${ns[@]}"

echo "| path | N | wall s | CPU s | peak MiB | LP solves | max jerk m/s³ | wall ~ N^ | CPU ~ N^ | memory ~ N^ |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for dir in curve-0.25 curve-0.8 walk-0.25; do
    prev=""
    for n in "${ns[@]}"; do
        job=$(ls "$work/$dir"/*-"$n".toml)
        out="$work/$dir/$n.json"
        status=0
        /usr/bin/time -f "%e %U %S %M" -o "$work/time" \
            timeout "${TIMEOUT:-1800}" "$bin" plan "$job" -o "$out" --quiet \
            >/dev/null 2>"$work/err" || status=$?
        row=$(python3 - "$dir" "$n" "$status" "$out" "$work/time" "$work/err" "$prev" <<'PY'
import json, math, sys
path, n, status, out, timef, errf, prev = sys.argv[1:]
n = int(n)
line = open(timef).read().split()[-4:]
wall, user, sys_, kib = float(line[0]), float(line[1]), float(line[2]), int(line[3])
cpu, mib = user + sys_, kib / 1024
if status == "0":
    d = json.load(open(out))
    lps = d["solver"]["lp_solves"]
    jerk = f"{max(d['max_abs']['jerk']):.6g}"
else:
    lps = "—"
    jerk = f"exit {status}: " + " ".join(open(errf).read().split())[:80]
grow = ["", "", ""]
if prev:
    pn, pw, pc, pm = map(float, prev.split(","))
    r = math.log(n / pn)
    grow = [f"{math.log(a / b) / r:.2f}" for a, b in ((wall, pw), (cpu, pc), (mib, pm))]
print(f"| {path} | {n} | {wall:.2f} | {cpu:.2f} | {mib:.1f} | {lps} | {jerk} | " + " | ".join(grow) + " |")
print(f"{n},{wall},{cpu},{mib}")
PY
)
        echo "$row" | head -1
        prev=$(echo "$row" | tail -1)
    done
done
