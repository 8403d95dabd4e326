#!/usr/bin/env python3
"""Writes the no-regression jobs (10-40 via-points, four shapes) and, with
--baseline BIN, plans each with BIN (the b0eb6e5 release binary) and writes
baseline.toml: max jerk per job, the figure the planner must not get worse on.

    python3 generate.py                    # jobs only
    python3 generate.py --baseline /path/to/triquint-b0eb6e5
"""
import json, math, random, subprocess, sys, tempfile, os

HERE = os.path.dirname(os.path.abspath(__file__))
S_PER_SEGMENT = 1.0

def lissajous(n):
    ts = [2 * math.pi * i / (n - 1) for i in range(n)]
    return [(90 * math.sin(t), 70 * math.sin(2 * t), 600 + 60 * math.sin(3 * t + 0.3)) for t in ts]

def helix(n):
    ts = [4 * math.pi * i / (n - 1) for i in range(n)]
    return [(60 * math.cos(t), 60 * math.sin(t), 540 + 120 * t / (4 * math.pi)) for t in ts]

def zigzag(n):
    # A pick-and-place raster: across in x, a step in y, down and up in z.
    out = []
    for i in range(n):
        x = 60.0 if (i // 2) % 2 == 0 else -60.0
        y = -80 + 160 * i / (n - 1)
        z = 560.0 if i % 2 == 0 else 640.0
        out.append((x, y, z))
    return out

def walk(n, seed):
    rng = random.Random(seed)
    p = [0.0, 0.0, 600.0]
    out = [tuple(p)]
    while len(out) < n:
        p = [min(max(p[0] + rng.uniform(-40, 40), -90), 90),
             min(max(p[1] + rng.uniform(-40, 40), -90), 90),
             min(max(p[2] + rng.uniform(-40, 40), 530), 690)]
        out.append(tuple(p))
    return out

JOBS = {
    "lissajous-10": lissajous(10), "lissajous-20": lissajous(20), "lissajous-40": lissajous(40),
    "helix-15": helix(15), "helix-30": helix(30),
    "zigzag-12": zigzag(12), "zigzag-24": zigzag(24),
    "walk-10": walk(10, 1), "walk-25": walk(25, 2),
    # A quarter of the time: acceleration binds at the optimum.
    "lissajous-24-fast": lissajous(24),
}
S_PER_SEGMENT_OF = {"lissajous-24-fast": 0.25}

def write(name, pts):
    per_segment = S_PER_SEGMENT_OF.get(name, S_PER_SEGMENT)
    t = per_segment * (len(pts) - 1)
    rows = ",\n".join(f"  [{x:.4f}, {y:.4f}, {z:.4f}]" for x, y, z in pts)
    with open(os.path.join(HERE, name + ".toml"), "w") as f:
        f.write(f'# Written by generate.py: {len(pts)} via-points, {per_segment} s a segment.\n'
                f'objective = "min-max-jerk"\n[limits]\ntotal_time = {t:.3f}\n'
                f'[path]\nunits = "mm"\npoints = [\n{rows},\n]\n')

for name, pts in JOBS.items():
    write(name, pts)

if "--baseline" in sys.argv:
    binary = sys.argv[sys.argv.index("--baseline") + 1]
    lines = ["# Max jerk (m/s³) of each job as planned by the b0eb6e5 release binary",
             "# (python3 generate.py --baseline BIN); tests/no_regression.rs compares."]
    for name in JOBS:
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "p.json")
            subprocess.run([binary, "plan", os.path.join(HERE, name + ".toml"), "-o", out, "--quiet"], check=True)
            jerk = max(json.load(open(out))["max_abs"]["jerk"])
        lines.append(f'"{name}" = {jerk!r}')
        print(name, jerk, flush=True)
    open(os.path.join(HERE, "baseline.toml"), "w").write("\n".join(lines) + "\n")
