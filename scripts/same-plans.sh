#!/usr/bin/env bash
# Are two planner binaries' plans the same? Plans every job a refactor must
# not change (examples/, both paper cases as min-max-jerk and min-time, the
# no-regression jobs, the 10/40/100-point scaling curves) with BASE and NEW
# and compares the plan JSON with `solver.seconds` removed. A format 1 plan
# is first read as the loader reads it (docs/plan-format.md): the current
# format with the default machine's travel and ceilings, so a format bump
# alone is no difference.
#
#   scripts/same-plans.sh BASE_TRIQUINT NEW_TRIQUINT [WORKDIR]
#
# Exit 0 when every plan is identical; prints each job's verdict.
set -euo pipefail
cd "$(dirname "$0")/.."
base=$(realpath "$1")
new=$(realpath "$2")
work=${3:-$(mktemp -d)}
mkdir -p "$work/jobs" "$work/base" "$work/new"

cp examples/*.toml host/planner/tests/regression/*-*.toml "$work/jobs/"
for case in 1 2; do
    sed 's/^objective = "min-max-jerk"/objective = "min-time"/' \
        "examples/paper-case$case.toml" >"$work/jobs/paper-case$case-min-time.toml"
done
for n in 10 40 100; do
    cargo run --quiet --release --locked -p triquint-planner --example scaling_paths -- \
        "$work/jobs" 0.25 "$n" >/dev/null
done

strip() { python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
d.get("solver", {}).pop("seconds", None)
if d.get("format") in ("triquint-plan/1", "triquint-plan/2"):
    d["format"] = "triquint-plan/3"
    d.setdefault("travel", {"min": [0.05] * 3, "max": [0.415] * 3})
    d.setdefault("ceilings", {"velocity": 1e6, "acceleration": 1e6, "jerk": 1e6, "torque": 1e6})
print(json.dumps(d, sort_keys=True))' "$1"; }

fail=0
for job in "$work"/jobs/*.toml; do
    name=$(basename "$job" .toml)
    # A job that fails (the 10-point curve is an infeasible verdict) compares
    # by its exit status and message.
    for side in base new; do
        bin=$base; [ "$side" = new ] && bin=$new
        "$bin" plan "$job" -o "$work/$side/$name.json" --quiet >/dev/null 2>"$work/$side/$name.err" ||
            echo "exit $?: $(cat "$work/$side/$name.err")" >"$work/$side/$name.json"
    done
    if [ "$(strip "$work/base/$name.json" 2>/dev/null || cat "$work/base/$name.json")" = \
         "$(strip "$work/new/$name.json" 2>/dev/null || cat "$work/new/$name.json")" ]; then
        echo "same      $name"
    else
        echo "DIFFERENT $name"
        fail=1
    fi
done
exit $fail
