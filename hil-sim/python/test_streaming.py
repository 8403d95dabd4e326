"""Issue 35's streaming fixtures through `triquint upload` against
`triquint-sim` on vcan0, classic CAN and CAN-FD: 15 segments in 0.9 s, a
2 ms segment every tenth, 2 000 segments of 27 ms. Each runs to
completion with no fault, every segment executed, and its bus load is
reported (OUT/streaming-*.json, the table of scripts/hil_figures.py). The
plan files come from `cargo run --example streaming_fixtures` (hil.sh)."""
import json
import os

import pytest

from conftest import IFACE, OUT, PLANS, TRIQUINT, run

FIXTURES = ["stream-15-segments", "stream-2ms-every-tenth", "stream-2000-segments"]


def fixture_path(name):
    return os.path.join(PLANS, f"{name}.json")


@pytest.mark.parametrize("fd", [False, True], ids=["classic", "fd"])
@pytest.mark.parametrize("name", FIXTURES)
def test_streaming_fixture_runs_to_completion(make_sim, bus, name, fd):
    with open(fixture_path(name)) as f:
        plan = json.load(f)
    n = len(plan["segments"])
    tag = f"{name}-{'fd' if fd else 'classic'}"
    sim = make_sim(tag, fd=fd, start=[1000.0 * c for c in plan["via_points_m"][0]])
    sim.wait_heartbeats(bus)
    args = [TRIQUINT, "upload", fixture_path(name), "--iface", IFACE, "--json"]
    if fd:
        args.append("--fd")
    code, out, err = run(args, timeout=60 + 3 * plan["total_time_s"])
    assert code == 0, err
    summary = json.loads(out)
    assert summary["completed"] and summary["faults"] == [], summary
    assert summary["segments"] == n
    assert [x["state"] for x in summary["nodes"]] == ["Idle"] * 3
    report = sim.stop()
    assert report["completed"] and report["faults"] == [], report["faults"]
    assert report["segments"] == n
    assert report["skipped_ticks"] == 0, report["skipped_ticks"]
    assert abs(report["plan_time_s"] - plan["total_time_s"]) < 1e-5
    assert 0 < report["bus_load"] < 0.5, report["bus_load"]
    figures = {
        "plan": name,
        "bus": "fd" if fd else "classic",
        "segments": n,
        "plan_s": plan["total_time_s"],
        "upload_s": summary["upload_s"],
        "segment_frames": summary["segment_frames"],
        "retransmits": summary["retransmits"],
        "bus_load": report["bus_load"],
        "segment_bus_load": report.get("segment_bus_load"),
        "max_error_m": report["max_error_m"],
        "missed_deadlines": report["missed_deadlines"],
        "ticks": report["ticks"],
    }
    with open(os.path.join(OUT, f"streaming-{tag}.json"), "w") as f:
        json.dump(figures, f, indent=1)
    print(f"{tag}: {n} segments, {plan['total_time_s']:.3f} s, bus load {100 * report['bus_load']:.2f} %")
