#!/usr/bin/env python3
"""Plans both cases of Lu, Ding & Li (2020) and draws the paper's Figures 10
(Case I, inverted-U pick-and-place) and 12 (Case II, closed circle): joint
position, velocity, acceleration and jerk against time, plus the motor
torques, three joints per panel, knots dotted, limits dashed where they are
within reach.

    python host/python/examples/paper_figures.py [--out DIR]

Writes DIR/figure10_case1.png and DIR/figure12_case2.png (DIR defaults to
out/python-figures). matplotlib is optional: without it the script still
plans and prints the figures' numbers, and says that it drew nothing.
"""
import argparse
import pathlib
import sys

import numpy as np

import triquint

CASES = {
    # Paper Table 2 and Table 6 via-points (mm); limits of Table 3 (the defaults).
    "figure10_case1": (
        "Figure 10 - Case I: inverted-U path (Table 2), T = 5 s",
        [[-90, 90, 680], [-90, 90, 660], [-90, 90, 640], [-60, 60, 620], [-20, 20, 620],
         [20, -20, 620], [60, -60, 620], [90, -90, 640], [90, -90, 660], [90, -90, 680]],
    ),
    "figure12_case2": (
        "Figure 12 - Case II: circle r = 120 mm (Table 6), T = 5 s",
        [[-86, 83.66, 597.66], [-43, 97.74, 654.74], [0, 84.85, 684.85], [43, 54.74, 697.74],
         [86, -2.34, 683.66], [86, -83.66, 602.34], [43, -97.74, 545.26], [0, -84.85, 515.15],
         [-43, -54.74, 502.26], [-86, 2.34, 516.34], [-86, 83.66, 597.66]],
    ),
}

# (Samples attribute, axis label, scale to the plotted unit, limit key or None)
PANELS = [
    ("q", "position q (mm)", 1e3, None),
    ("v", "velocity (m/s)", 1.0, "velocity"),
    ("a", "acceleration (m/s²)", 1.0, "acceleration"),
    ("jerk", "jerk (m/s³)", 1.0, "jerk"),
    ("torque", "torque (N·m)", 1.0, "torque"),
]
COLOURS = ["#1f77b4", "#d62728", "#2ca02c"]


def summary(name: str, plan: "triquint.Plan") -> str:
    m = plan.max_abs
    return (f"{name}: {len(plan.segments)} segments, T = {plan.duration:.3f} s, "
            f"max |jerk| {np.max(m['jerk']):.5f} m/s³, |a| {np.max(m['acceleration']):.4f} m/s², "
            f"|v| {np.max(m['velocity']):.4f} m/s, |τ| {np.max(m['torque']):.4f} N·m")


def draw(path: pathlib.Path, title: str, plan: "triquint.Plan") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = plan.sample(0.002)
    knots_t = np.concatenate([[0.0], np.cumsum(plan.segments.durations)])
    fig, axes = plt.subplots(len(PANELS), 1, figsize=(8.5, 12), sharex=True, constrained_layout=True)
    for ax, (attr, label, scale, limit) in zip(axes, PANELS):
        y = getattr(s, attr) * scale
        for j in range(3):
            ax.plot(s.t, y[:, j], color=COLOURS[j], lw=1.4, label=f"joint {j + 1}")
        for t in knots_t:
            ax.axvline(t, color="0.75", lw=0.6, ls=":", zorder=0)
        if limit is not None:
            bound = plan.limits[limit]
            peak = float(np.max(plan.max_abs[limit]))
            if peak >= 0.25 * bound:
                for sign in (1, -1):
                    ax.axhline(sign * bound, color="0.3", lw=0.9, ls="--")
            else:
                ax.text(0.99, 0.93, f"limit ±{bound:g} off scale (peak {peak:.3g})",
                        transform=ax.transAxes, ha="right", va="top", fontsize=8, color="0.35")
            ax.axhline(0.0, color="0.6", lw=0.6)
        ax.set_ylabel(label)
        ax.grid(alpha=0.25)
    axes[0].legend(loc="upper right", ncol=3, fontsize=8)
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"{title}\nmax |jerk| = {np.max(plan.max_abs['jerk']):.4f} m/s³ (triquint, exact)",
                 fontweight="bold")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/python-figures"),
                    help="directory for the PNG files (default: out/python-figures)")
    args = ap.parse_args()
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        matplotlib = None
    plans = {}
    for name, (title, points) in CASES.items():
        plans[name] = triquint.plan(points)
        print(summary(name, plans[name]))
    if matplotlib is None:
        print("matplotlib is not installed: planned both cases, drew nothing "
              "(pip install matplotlib, or pip install './host/python[figures]')", file=sys.stderr)
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    for name, (title, _) in CASES.items():
        path = args.out / f"{name}.png"
        draw(path, title, plans[name])
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
