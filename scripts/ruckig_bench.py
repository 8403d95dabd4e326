#!/usr/bin/env python3
"""triquint against Ruckig on seeded point-to-point moves.

Each move: two points drawn (seed 37) in x, y ±100 mm, z 540–680 mm, limits
v 0.5 m/s, a 1.2 m/s², j 5 m/s³ per joint, torque 1000 N·m (never binding).
triquint plans it as a min-time job with `knots = "free"`, with free knots
bounded to 0.5 mm off the straight Cartesian segment (`path.max_deviation_mm`)
and with `"fixed"` (whole `triquint plan` processes); Ruckig 0.19 plans the same joint
positions from rest to rest with Synchronization.Time (its default: every
joint ends together, each on its own profile) and with
Synchronization.Phase (one profile, the straight line in joint space).
Printed per move and as medians: durations and their ratios to Ruckig
(time sync), the platform's largest distance from the straight Cartesian
segment (samples every 1 ms through the closed-form FK, by the
`path_deviation` example), triquint's whole-process time and Ruckig's
in-process calculate() time, the largest |jerk| and |snap| (Ruckig's jerk
steps: unbounded snap), whether every triquint plan passes `triquint check`,
and which of `check`'s rows Ruckig's own output fails: its pieces are
cubics, written as a plan (the phase switches rounded to whole µs, each
piece Ruckig's own cubic of the phase it lies in) and checked exactly.

With --paper, the paper's via-points (examples/paper-case1.toml and
paper-case2.toml) too: triquint min-time against Ruckig stopping at every
via-point, and Ruckig through the states (q, q̇, q̈) triquint's min-time plan
has at its knots (Ruckig's community version has no intermediate waypoints).

    scripts/ruckig_bench.py [--triquint BIN] [--moves N] [--paper]

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


BOUND_MM = 0.5


def job_text(a, b, knots, bound=None):
    return (
        f'objective = "min-time"\nknots = "{knots}"\n'
        f"[limits]\nvelocity = {V}\nacceleration = {A}\njerk = {J}\n"
        "torque = 1000.0\ntotal_time = 100.0\n"
        f'[path]\nunits = "mm"\npoints = [{a}, {b}]\n'
        + (f"max_deviation_mm = {bound}\n" if bound else "")
    )


def peaks(p):
    """Largest |jerk| and |snap| of a plan: snap is linear in each segment."""
    jerk = max(p["max_abs"]["jerk"])
    snap = 0.0
    for seg in p["segments"]:
        h = seg["duration_s"]
        for c in seg["coeffs"]:
            snap = max(snap, abs(24 * c[4]), abs(24 * c[4] + 120 * c[5] * h))
    return jerk, snap


def ruckig_pieces(traj, dofs=3):
    """Ruckig's trajectory as cubic pieces: (start, duration, coeffs per joint)
    between the union of every joint's phase switches rounded to whole µs."""
    phases = []
    for d in range(dofs):
        pr = traj.profiles[0][d]
        t0, ph = 0.0, []
        for k in range(7):
            ph.append((t0, pr.t[k], pr.j[k], pr.p[k], pr.v[k], pr.a[k]))
            t0 += pr.t[k]
        phases.append((ph, pr.p[7]))
    edges = {0, round(traj.duration * 1e6)}
    for ph, _ in phases:
        edges.update(round((t0 + h) * 1e6) for t0, h, *_ in ph if h > 0)
    edges = sorted(e for e in edges if 0 <= e <= round(traj.duration * 1e6))
    pieces = []
    for e0, e1 in zip(edges, edges[1:]):
        if e1 == e0:
            continue
        t, mid = e0 * 1e-6, 0.5 * (e0 + e1) * 1e-6
        coeffs = []
        for ph, pf in phases:
            live = [x for x in ph if x[1] > 0 and x[0] <= mid]
            if not live or mid >= live[-1][0] + live[-1][1]:
                coeffs.append([pf, 0, 0, 0, 0, 0])
                continue
            t0, _, j, p, v, a = live[-1]
            dt = t - t0
            coeffs.append([p + v * dt + a * dt**2 / 2 + j * dt**3 / 6,
                           v + a * dt + j * dt**2 / 2, (a + j * dt) / 2, j / 6, 0.0, 0.0])
        pieces.append((t, (e1 - e0) * 1e-6, coeffs))
    return pieces


def check_ruckig(binary, work, name, like, traj):
    """The rows of `triquint check` that Ruckig's trajectory fails, written
    as a plan with `like`'s robot, limits and via-points."""
    pieces = ruckig_pieces(traj)
    plan = dict(like)
    plan.update(format="triquint-plan/3", free_knots=[],
                knots_m=[[c[0] for c in p[2]] for p in pieces] + [like["knots_m"][-1]],
                intervals_s=[p[1] for p in pieces], total_time_s=sum(p[1] for p in pieces),
                segments=[dict(t0_s=p[0], duration_s=p[1], coeffs=p[2]) for p in pieces])
    plan.pop("free_knots")
    plan.pop("max_deviation_m", None)
    out = work / f"{name}.json"
    rows = None
    for _ in range(2):  # the second pass with the maxima `check` found recorded
        out.write_text(json.dumps(plan))
        r = subprocess.run([binary, "check", out, "--json"], capture_output=True, text=True)
        if not r.stdout:
            return [("not a plan: " + r.stderr.strip(), float("nan"))]
        rows = json.loads(r.stdout)["checks"]
        for key, label in [("velocity", "velocity (m/s)"), ("acceleration", "acceleration (m/s²)"),
                           ("jerk", "jerk (m/s³)"), ("torque", "torque (N·m)")]:
            plan["max_abs"][key] = [next(x["value"] for x in rows
                                         if x["check"] == f"max |{label}| joint {j + 1}") for j in range(3)]
    return [(x["check"], x["value"]) for x in rows if not x["ok"]]


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


def ruckig(q0, q1, sync, start=None, end=None):
    inp = InputParameter(3)
    inp.current_position, inp.target_position = list(q0), list(q1)
    inp.current_velocity, inp.current_acceleration = start or ([0.0] * 3, [0.0] * 3)
    inp.target_velocity, inp.target_acceleration = end or ([0.0] * 3, [0.0] * 3)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [V] * 3, [A] * 3, [J] * 3
    inp.synchronization = sync
    traj = Trajectory(3)
    t0 = time.perf_counter()
    res = Ruckig(3).calculate(inp, traj)
    took = time.perf_counter() - t0
    assert res == Result.Working, res
    ts = np.append(np.arange(0.0, traj.duration, 1e-3), traj.duration)
    return traj.duration, took, [traj.at_time(t)[0] for t in ts], traj


def paper(binary, work):
    """Case I and II: triquint min-time against Ruckig stopping at every
    via-point and Ruckig through triquint's knot states."""
    print("\npaper via-points: triquint min-time against Ruckig 0.19 (time sync)")
    print(f"{'case':>6} {'knots':>5} {'triquint s':>10} {'stop s':>8} {'through s':>9} "
          f"{'tq/stop':>7} {'tq/thru':>7} {'jerk tq':>7} {'snap tq':>8}")
    for case in (1, 2):
        text = (ROOT / f"examples/paper-case{case}.toml").read_text()
        text = text.replace('objective = "min-max-jerk"', 'objective = "min-time"')
        p, _, ok = plan(binary, work, f"paper{case}", text)
        lim = p["limits"]
        global V, A, J
        V, A, J = lim["velocity"], lim["acceleration"], lim["jerk"]
        q = p["knots_m"]
        states = [([c[1] for c in s["coeffs"]], [2 * c[2] for c in s["coeffs"]]) for s in p["segments"]]
        states.append(([0.0] * 3, [0.0] * 3))
        stop = sum(ruckig(q[k], q[k + 1], Synchronization.Time)[0] for k in range(len(q) - 1))
        through = sum(ruckig(q[k], q[k + 1], Synchronization.Time, states[k], states[k + 1])[0]
                      for k in range(len(q) - 1))
        jerk, snap = peaks(p)
        t = p["total_time_s"]
        print(f"{case:>6} {len(q):>5} {t:10.4f} {stop:8.4f} {through:9.4f} {t / stop:7.4f} "
              f"{t / through:7.4f} {jerk:7.3f} {snap:8.1f}  check {'ok' if ok else 'FAIL'}")
    V, A, J = 0.5, 1.2, 5.0


def deviations(example, rows):
    text = "".join(json.dumps(r) + "\n" for r in rows)
    out = subprocess.run([example], input=text, capture_output=True, text=True, check=True)
    return [float(x) for x in out.stdout.split()]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--triquint", default=ROOT / "target/release/triquint")
    ap.add_argument("--example", default=ROOT / "target/release/examples/path_deviation")
    ap.add_argument("--moves", type=int, default=20)
    ap.add_argument("--paper", action="store_true", help="the paper's via-points too")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="ruckig-bench-"))
    rows, dev_in = [], []
    for i, (a, b) in enumerate(moves(args.moves)):
        free, free_wall, free_ok = plan(args.triquint, work, f"free-{i}", job_text(a, b, "free"))
        fixed, fixed_wall, fixed_ok = plan(args.triquint, work, f"fixed-{i}", job_text(a, b, "fixed"))
        bounded, _, bounded_ok = plan(args.triquint, work, f"bounded-{i}",
                                      job_text(a, b, "free", BOUND_MM))
        if free is None or fixed is None or bounded is None:
            print(f"move {i}: {a} -> {b} not planned (outside the workspace or travel)")
            continue
        q0, q1 = free["knots_m"][0], free["knots_m"][-1]
        via = [[x * 1e-3 for x in a], [x * 1e-3 for x in b]]
        rt, rt_took, rt_q, rt_traj = ruckig(q0, q1, Synchronization.Time)
        rp, _, rp_q, _ = ruckig(q0, q1, Synchronization.Phase)
        for q in (plan_samples(free), plan_samples(fixed), rt_q, rp_q, plan_samples(bounded)):
            dev_in.append({"via": via, "q": q})
        rows.append(dict(
            i=i, free=free["total_time_s"], fixed=fixed["total_time_s"], rt=rt, rp=rp,
            bounded=bounded["total_time_s"],
            free_wall=free_wall, fixed_wall=fixed_wall, rt_took=rt_took,
            ok=free_ok and fixed_ok and bounded_ok, knots=len(free["knots_m"]),
            jerk_free=peaks(free)[0], snap_free=peaks(free)[1],
            jerk_fixed=peaks(fixed)[0], snap_fixed=peaks(fixed)[1],
            jerk_rt=max(abs(j) for d in range(3) for j in rt_traj.profiles[0][d].j),
            ruckig_fails=check_ruckig(args.triquint, work, f"ruckig-{i}", fixed, rt_traj),
        ))
    devs = deviations(args.example, dev_in)
    for k, r in enumerate(rows):
        r["dev_free"], r["dev_fixed"], r["dev_rt"], r["dev_rp"], r["dev_bounded"] = devs[5 * k:5 * k + 5]

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
    print("median bounded to {} mm: bounded/Ruckig {:.4f} (max {:.4f}), deviation {:.3f} mm (max {:.3f})".format(
        BOUND_MM, med(lambda r: r["bounded"] / r["rt"]), max(r["bounded"] / r["rt"] for r in rows),
        med(lambda r: r["dev_bounded"]), max(r["dev_bounded"] for r in rows)))
    print("largest |jerk| (m/s³), median: free {:.3f}, fixed {:.3f}, Ruckig {:.3f}; largest |snap| (m/s⁴): "
          "free {:.1f}, fixed {:.1f}, Ruckig unbounded (jerk steps)".format(
              med(lambda r: r["jerk_free"]), med(lambda r: r["jerk_fixed"]), med(lambda r: r["jerk_rt"]),
              med(lambda r: r["snap_free"]), med(lambda r: r["snap_fixed"])))
    fails = {}
    for r in rows:
        for what, value in r["ruckig_fails"]:
            name = what if isinstance(what, str) else str(what)
            fails.setdefault(name, []).append(value)
    print(f"`triquint check` on Ruckig's time-sync output, rows failed in {len(rows)} moves:")
    for name, values in sorted(fails.items()):
        print(f"  {name}: {len(values)} moves, largest {max(values):.3g}")
    print("every plan passes check:", all(r["ok"] for r in rows))
    if args.paper:
        paper(args.triquint, work)


if __name__ == "__main__":
    main()
