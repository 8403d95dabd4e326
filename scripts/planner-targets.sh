#!/usr/bin/env bash
# Issue 39's targets in one run: every target job planned by NEW and by BASE
# in turn (farm-bench, A B A B ...), and a table of the medians, the ratio
# NEW / BASE, and that ratio applied to the issue's figure for BASE (what NEW
# would take on the issue's machine) against the target. BASE is the
# issue's binary, e9db3ad:
#
#   git worktree add /tmp/e9 e9db3ad && (cd /tmp/e9 && cargo build --release -p triquint-host)
#   scripts/planner-targets.sh /tmp/e9/target/release/triquint target/release/triquint
#
# Then NEW alone on the min-max-jerk jobs with `knots = "free"` (the figures
# the issue asks for beside the targets). Not run by CI: about 15 minutes,
# most of it BASE on the 1 000-point paths. Figures: docs/planner-speed.md.
set -euo pipefail
cd "$(dirname "$0")/.."
base=$(realpath "$1")
new=$(realpath "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

gen() { cargo run --quiet --release --locked -p triquint-planner --example scaling_paths -- "$@" >/dev/null; }
gen "$work/verdict" 0.3 10 20
gen "$work/curve-0.25" 0.25 100 1000
gen "$work/curve-0.8" 0.8 100 1000
gen "$work/walk" --walk 0.25 100 1000
case2=examples/paper-case2.toml
sed 's/^objective = .*/objective = "min-time"/' "$case2" >"$work/case2-min-time.toml"
sed 's/^total_time = [0-9.]*/total_time = 3.0/' "$case2" >"$work/case2-at-3s.toml"
python3 - "$work/case2-min-time.toml" "$work/p2p.toml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
points = "points = [[-90, 90, 680], [-86, 83.66, 597.66]]"
text = re.sub(r"points = \[.*?\n\]", points, text, flags=re.S)
open(sys.argv[2], "w").write(text)
PY
sed 's/^objective = .*/objective = "min-time"\nknots = "fixed"/' "$work/p2p.toml" >"$work/p2p-fixed.toml"

# name | job | target s | BASE's figure on the issue's machine, s ("" if none)
# | pairs | BASE's job when not the same (e9db3ad knows no `knots` key: its
# knots are the fixed ones)
rows=(
    "Case II min-max-jerk|$case2|0.05|0.046|9"
    "Case II min-time|$work/case2-min-time.toml|0.3|0.593|9"
    "verdict, Case II at 3.0 s|$work/case2-at-3s.toml|0.5|0.577|9"
    "verdict, curve n = 10 at 2.7 s|$(ls "$work"/verdict/*-10.toml)|0.5|0.593|9"
    "verdict, curve n = 20 at 5.7 s|$(ls "$work"/verdict/*-20.toml)|0.5|3.84|5"
    "point-to-point min-time, knots fixed|$work/p2p-fixed.toml|0.005|0.015|9|$work/p2p.toml"
    "point-to-point min-time, free knots (default)|$work/p2p.toml|0.005||9"
    "closed curve, 100 via-points, 0.25 s a segment|$(ls "$work"/curve-0.25/*-100.toml)|1|2.02|5"
    "closed curve, 100 via-points, 0.8 s a segment|$(ls "$work"/curve-0.8/*-100.toml)|1||5"
    "random walk, 100 via-points|$(ls "$work"/walk/*-100.toml)|1||5"
    "closed curve, 1 000 via-points, 0.25 s a segment|$(ls "$work"/curve-0.25/*-1000.toml)|20|104|1"
    "closed curve, 1 000 via-points, 0.8 s a segment|$(ls "$work"/curve-0.8/*-1000.toml)|20|308|1"
    "random walk, 1 000 via-points|$(ls "$work"/walk/*-1000.toml)|20||1"
)

echo "| job | target | NEW: wall, peak | BASE: wall, peak | NEW / BASE, wall (CPU) | on the issue's figure | NEW's answer |"
echo "|---|---:|---|---|---:|---|---|"
for row in "${rows[@]}"; do
    IFS='|' read -r name job target issue pairs base_job <<<"$row"
    status=0
    "$new" plan "$job" -o "$work/new.json" >/dev/null 2>"$work/answer" || status=$?
    farm-bench -n "$pairs" --warmup "$([ "$pairs" -gt 1 ] && echo 1 || echo 0)" --timeout 3600 \
        --vs "$base plan ${base_job:-$job} -o $work/base.json --quiet" \
        -- "$new" plan "$job" -o "$work/new.json" --quiet >"$work/bench" 2>&1
    python3 - "$name" "$target" "$issue" "$work/bench" "$status" "$work/new.json" "$work/answer" <<'PY'
import json, re, sys
name, target, issue, bench, status, out, answer = sys.argv[1:]
med = {}
exits = {}
for line in open(bench):
    e = re.match(r"^(A|B) exit (\S+)", line)
    if e:
        exits[e.group(1)] = e.group(2)
    m = re.match(r"^(A|B|A/B) (wall s|cpu s|peak MiB|wall|cpu)\s+\S+\s+(\S+)", line)
    if m:
        med[(m.group(1), m.group(2))] = float(m.group(3))
# The plan file as scripts/planner-scaling.sh reads it; else the error.
if status == "0":
    d = json.load(open(out))
    said = f"T = {d['total_time_s']:.6f} s, max |jerk| {max(d['max_abs']['jerk']):.6g} m/s³"
else:
    text = " ".join(open(answer).read().split())
    short = re.search(r"shortest total time that meets every limit is ([0-9.]+ s)", text)
    said = f"infeasible, shortest {short.group(1)}" if short else f"exit {status}: {text[:60]}"
if exits.get("A") != exits.get("B"):
    said += f" (BASE exit {exits.get('B')})"
ratio = med.get(("A/B", "wall"))
t = float(target)
if issue and ratio is not None:
    there = ratio * float(issue)
    verdict = "met" if there <= t else f"{there / t:.2f}× over"
    on_issue = f"{there:.3g} s of {issue} s: {verdict}"
else:
    here = med.get(("A", "wall s"))
    verdict = "met here" if here is not None and here <= t else "over here"
    on_issue = f"(no figure in the issue) {verdict}"
fmt = lambda w: f"{med.get((w, 'wall s'), float('nan')):.3g} s, {med.get((w, 'peak MiB'), float('nan')):.0f} MiB"
print(f"| {name} | ≤ {target} s | {fmt('A')} | {fmt('B')} | "
      f"{ratio:.3f} ({med.get(('A/B', 'cpu'), float('nan')):.3f}) | {on_issue} | {said} |")
PY
done

echo
echo "With \`knots = \"free\"\` (NEW alone, min-max-jerk):"
echo
echo "| job | wall s | CPU s | peak MiB | NEW's answer |"
echo "|---|---:|---:|---:|---|"
for job in "$case2" "$(ls "$work"/curve-0.25/*-100.toml)" "$(ls "$work"/curve-0.8/*-100.toml)" \
    "$(ls "$work"/walk/*-100.toml)" "$(ls "$work"/curve-0.25/*-1000.toml)" \
    "$(ls "$work"/curve-0.8/*-1000.toml)" "$(ls "$work"/walk/*-1000.toml)"; do
    free="$work/free.toml"
    sed 's/^objective = .*/objective = "min-max-jerk"\nknots = "free"/' "$job" >"$free"
    status=0
    /usr/bin/time -f "%e %U %S %M" -o "$work/time" "$new" plan "$free" -o "$work/free.json" \
        >/dev/null 2>"$work/answer" || status=$?
    python3 - "$job" "$work/time" "$status" "$work/free.json" "$work/answer" <<'PY'
import json, os, sys
job, tfile, status, out, answer = sys.argv[1:]
wall, user, sys_, rss = open(tfile).read().split()[-4:]
if status == "0":
    d = json.load(open(out))
    said = f"{len(d['intervals_s'])} segments, max |jerk| {max(d['max_abs']['jerk']):.6g} m/s³"
else:
    said = f"exit {status}: " + " ".join(open(answer).read().split())[:80]
print(f"| {os.path.basename(os.path.dirname(job))}/{os.path.basename(job)} | {float(wall):.3g} | "
      f"{float(user) + float(sys_):.3g} | {int(rss) / 1024:.0f} | {said} |")
PY
done
