#!/usr/bin/env python3
"""triquint against Ruckig on seeded point-to-point moves.

Each move: two points drawn (seed 37) in x, y ±100 mm, z 540–680 mm, limits
v 0.5 m/s, a 1.2 m/s², j 5 m/s³ per joint, torque 1000 N·m (never binding).
triquint plans it as a min-time job with `knots = "free"` and `"fixed"`
(whole `triquint plan` processes); Ruckig 0.19 plans the same joint
positions from rest to rest with Synchronization.Time (its default: every
joint ends together, each on its own profile) and with
Synchronization.Phase (one profile, the straight line in joint space).
Printed per move and as medians: durations and their ratios to Ruckig
(time sync), the platform's largest distance from the straight Cartesian
segment (samples every 1 ms through the closed-form FK, by the
`path_deviation` example), triquint's whole-process time and Ruckig's
in-process calculate() time, and whether every triquint plan passes
`triquint check`.

    scripts/ruckig_bench.py [--triquint BIN] [--moves N]

Needs `ruckig` and `numpy` (a venv: python3 -m venv target/venv37 &&
target/venv37/bin/pip install ruckig numpy) and release builds of
`triquint` and the example (cargo build --release -p triquint-host;
cargo build --release -p triquint-planner --example path_deviation).
Not part of CI.
"""

import argparse
import json
import random
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from ruckig import InputParameter, Result, Ruckig, Synchronization, Trajectory

ROOT = Path(__file__).resolve().parent.parent
V, A, J = 0.5, 1.2, 5.0


def moves(n, seed=37):
    rng = random.Random(seed)
    point = lambda: [rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(540, 680)]
    return [(point(), point()) for _ in range(n)]


def job_text(a, b, knots):
    return (
        f'objective = "min-time"\nknots = "{knots}"\n'
        f"[limits]\nvelocity = {V}\nacceleration = {A}\njerk = {J}\n"
        "torque = 1000.0\ntotal_time = 100.0\n"
        f'[path]\nunits = "mm"\npoints = [{a}, {b}]\n'
    )


def plan(binary, work, name, text):
    job, out = work / f"{name}.toml", work / f"{name}.json"
    job.write_text(text)
    t0 = time.perf_counter()
    r = subprocess.run([binary, "plan", job, "-o", out, "--quiet"], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        return None, wall, False
    ok = subprocess.run([binary, "check", out], capture_output=True).returncode == 0
    return json.loads(out.read_text()), wall, ok


def plan_samples(p, dt=1e-3):
    """Joint positions every dt (and at the end) from the plan's segments."""
    qs = []
    for seg in p["segments"]:
        h = seg["duration_s"]
        ts = np.append(np.arange(0.0, h, dt), h)
        c = np.array(seg["coeffs"])  # (3, 6), ascending powers
        powers = np.vander(ts, 6, increasing=True)  # (n, 6)
        qs.extend((powers @ c.T).tolist())
    return qs


def ruckig(q0, q1, sync):
    inp = InputParameter(3)
    inp.current_position, inp.target_position = list(q0), list(q1)
    inp.current_velocity = inp.current_acceleration = [0.0] * 3
    inp.target_velocity = inp.target_acceleration = [0.0] * 3
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [V] * 3, [A] * 3, [J] * 3
    inp.synchronization = sync
    traj = Trajectory(3)
    t0 = time.perf_counter()
    res = Ruckig(3).calculate(inp, traj)
    took = time.perf_counter() - t0
    assert res == Result.Working, res
    ts = np.append(np.arange(0.0, traj.duration, 1e-3), traj.duration)
    return traj.duration, took, [traj.at_time(t)[0] for t in ts]


def deviations(example, rows):
    text = "".join(json.dumps(r) + "\n" for r in rows)
    out = subprocess.run([example], input=text, capture_output=True, text=True, check=True)
    return [float(x) for x in out.stdout.split()]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--triquint", default=ROOT / "target/release/triquint")
    ap.add_argument("--example", default=ROOT / "target/release/examples/path_deviation")
    ap.add_argument("--moves", type=int, default=20)
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="ruckig-bench-"))
    rows, dev_in = [], []
    for i, (a, b) in enumerate(moves(args.moves)):
        free, free_wall, free_ok = plan(args.triquint, work, f"free-{i}", job_text(a, b, "free"))
        fixed, fixed_wall, fixed_ok = plan(args.triquint, work, f"fixed-{i}", job_text(a, b, "fixed"))
        if free is None or fixed is None:
            print(f"move {i}: {a} -> {b} not planned (outside the workspace or travel)")
            continue
        q0, q1 = free["knots_m"][0], free["knots_m"][-1]
        via = [[x * 1e-3 for x in a], [x * 1e-3 for x in b]]
        rt, rt_took, rt_q = ruckig(q0, q1, Synchronization.Time)
        rp, _, rp_q = ruckig(q0, q1, Synchronization.Phase)
        for q in (plan_samples(free), plan_samples(fixed), rt_q, rp_q):
            dev_in.append({"via": via, "q": q})
        rows.append(dict(
            i=i, free=free["total_time_s"], fixed=fixed["total_time_s"], rt=rt, rp=rp,
            free_wall=free_wall, fixed_wall=fixed_wall, rt_took=rt_took,
            ok=free_ok and fixed_ok, knots=len(free["knots_m"]),
        ))
    devs = deviations(args.example, dev_in)
    for k, r in enumerate(rows):
        r["dev_free"], r["dev_fixed"], r["dev_rt"], r["dev_rp"] = devs[4 * k:4 * k + 4]

    print(f"{len(rows)} moves; Ruckig 0.19 from rest to rest; ratios to Ruckig's Synchronization.Time")
    print(f"{'move':>4} {'free s':>8} {'fixed s':>8} {'ruckig s':>8} {'free/R':>7} {'fixed/R':>7} "
          f"{'phase/R':>7} {'dev free':>8} {'dev fixed':>9} {'dev R':>6} {'dev Rph':>7} "
          f"{'free ms':>7} {'fixed ms':>8} {'R µs':>6} check")
    for r in rows:
        print(f"{r['i']:>4} {r['free']:8.4f} {r['fixed']:8.4f} {r['rt']:8.4f} {r['free']/r['rt']:7.4f} "
              f"{r['fixed']/r['rt']:7.4f} {r['rp']/r['rt']:7.4f} {r['dev_free']:8.3f} {r['dev_fixed']:9.3f} "
              f"{r['dev_rt']:6.3f} {r['dev_rp']:7.3f} {r['free_wall']*1e3:7.1f} {r['fixed_wall']*1e3:8.1f} "
              f"{r['rt_took']*1e6:6.0f} {'ok' if r['ok'] else 'FAIL'}")
    med = lambda key: statistics.median(key(r) for r in rows)
    print("median: free/Ruckig {:.4f} (max {:.4f}), fixed/Ruckig {:.4f}, free/fixed {:.4f}".format(
        med(lambda r: r["free"] / r["rt"]), max(r["free"] / r["rt"] for r in rows),
        med(lambda r: r["fixed"] / r["rt"]), med(lambda r: r["free"] / r["fixed"])))
    print("median deviation (mm): free {:.3f} (max {:.3f}), fixed {:.3f}, Ruckig time {:.3f} (max {:.3f}), "
          "Ruckig phase {:.3f}".format(
              med(lambda r: r["dev_free"]), max(r["dev_free"] for r in rows), med(lambda r: r["dev_fixed"]),
              med(lambda r: r["dev_rt"]), max(r["dev_rt"] for r in rows), med(lambda r: r["dev_rp"])))
    print("median compute: triquint free {:.1f} ms, fixed {:.1f} ms (whole process, once each), "
          "Ruckig {:.0f} µs (calculate)".format(
              med(lambda r: r["free_wall"]) * 1e3, med(lambda r: r["fixed_wall"]) * 1e3,
              med(lambda r: r["rt_took"]) * 1e6))
    print("every plan passes check:", all(r["ok"] for r in rows))


if __name__ == "__main__":
    main()
