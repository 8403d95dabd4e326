"""The flexible plant over vcan: `triquint upload` of a fast point-to-point
move to `triquint-sim --plant flexible`, the residual vibration the simulator
reports (settle window after the plan's end, from the platform's
accelerometer) against the in-process figure for the same plan (`triquint
simulate --plant flexible`, run on the host by hil.sh), unshaped and shaped
by ZVD at the mode (docs/vibration.md)."""
import json
import os
import time

import pytest

from conftest import IFACE, PLANS, TRIQUINT, run

# The settle window (hil-sim/src/vibration.rs SETTLE_WINDOW_S) and the
# accelerometer's rate (flex.rs): the window holds this many samples.
SETTLE_S = 0.5
WINDOW_SAMPLES = SETTLE_S * 3200
# Over vcan the drives and the plant are the same discrete-time system as in
# process (late ticks are caught up at their own times: docs/verification.md),
# so the figures differ only by timing: the drives' start skew (their time
# sync over a jittery emulated bus) and where the window starts (the plan's
# end located within one 1 ms tick). A skew d adds d times the plan's
# derivative, d*w of the residual at the mode w = 2 pi 25.5 Hz: 0.8 % at
# 50 us; a 1 ms shift of the window changes a ring decaying at damping 0.06
# by 1 %. 10 % holds that with room for a skew of several hundred us.
TOLERANCE = 0.10
# The shaped plan's residual is a cancellation, so the same timing moves it
# by more of itself (the drives and the control law alone differ by 19 % on
# it in process): within 50 % of in process, and below the target
# of 5 % of the unshaped move's.
SHAPED_TOLERANCE = 0.50
TARGET = 0.05


def start_mm(plan):
    return [1000.0 * c for c in plan["via_points_m"][0]]


def run_flex(make_sim, bus, name):
    """Uploads PLANS/name.json to drives on the flexible plant; returns the
    simulator's report of the run and the in-process one."""
    path = os.path.join(PLANS, f"{name}.json")
    with open(path) as f:
        plan = json.load(f)
    with open(os.path.join(PLANS, f"{name}.inproc.json")) as f:
        inproc = json.load(f)
    sim = make_sim(name, start=start_mm(plan), extra=["--plant", "flexible"])
    sim.wait_heartbeats(bus)
    code, out, err = run([TRIQUINT, "upload", path, "--iface", IFACE, "--json"], timeout=120)
    assert code == 0, err
    assert json.loads(out)["completed"]
    # The run is reported once its settle window has passed in plant time
    # (real time, caught up when late): wait it out, with room for lateness.
    time.sleep(SETTLE_S + 2.5)
    report = sim.stop()
    assert report["skipped_ticks"] == 0, report["skipped_ticks"]
    assert report["completed"] and report["faults"] == [], report["faults"]
    assert abs(report["plan_time_s"] - plan["total_time_s"]) < 1e-5
    v = report.get("vibration")
    assert v is not None, "no residual vibration in the report"
    assert v["samples"] >= 0.95 * WINDOW_SAMPLES, v
    assert abs(v["window_s"] - SETTLE_S) < 1e-9, v
    with open(os.path.join(os.path.dirname(sim.report_path), f"flex-{name}.json"), "w") as f:
        json.dump({"vcan": v, "inproc": inproc["vibration"], "start_skew_us": report["start_skew_us"],
                   "missed_deadlines": report["missed_deadlines"], "ticks": report["ticks"]}, f, indent=1)
    return v, inproc["vibration"]


def close(a, b, tol):
    return abs(a - b) <= tol * abs(b)


@pytest.fixture(scope="module")
def figures():
    return {}


def test_flex_unshaped_rings_as_in_process(make_sim, bus, figures):
    v, ref = run_flex(make_sim, bus, "flex-p2p")
    figures["unshaped"] = v
    # The move rings: far above the floor (0.2 mm/s² at the mode).
    assert v["lowest_mode_m_s2"] > 0.1, v
    assert abs(v["lowest_mode_hz"] - ref["lowest_mode_hz"]) < 1e-6
    for k in ("lowest_mode_m_s2", "rms_accel_m_s2", "peak_accel_m_s2"):
        assert close(v[k], ref[k], TOLERANCE), (k, v[k], ref[k])
    assert abs(v["dominant_hz"] - ref["dominant_hz"]) < 0.5, (v["dominant_hz"], ref["dominant_hz"])


def test_flex_shaped_at_the_mode_lowers_it(make_sim, bus, figures):
    v, ref = run_flex(make_sim, bus, "flex-p2p-zvd")
    for k in ("lowest_mode_m_s2", "rms_accel_m_s2"):
        assert close(v[k], ref[k], SHAPED_TOLERANCE), (k, v[k], ref[k])
    unshaped = figures.get("unshaped")
    if unshaped is None:
        # Run alone (-k): against the in-process unshaped figure.
        with open(os.path.join(PLANS, "flex-p2p.inproc.json")) as f:
            unshaped = json.load(f)["vibration"]
    ratio = v["lowest_mode_m_s2"] / unshaped["lowest_mode_m_s2"]
    assert ratio <= TARGET, ratio
    assert v["rms_accel_m_s2"] < 0.2 * unshaped["rms_accel_m_s2"], (v, unshaped)
