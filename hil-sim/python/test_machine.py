"""Operating a machine over vcan: an unhomed simulator, status,
refusals (NotHomed, faulted, too far from the start), home, clear, estop,
stuck and dead switches, drives on node ids 4, 5, 6."""
import json
import re

from conftest import IFACE, PROTOCOL_VERSION, TRIQUINT, plan_path, plan_start_mm, run

REFUSED = 8


def status(*extra):
    code, out, err = run([TRIQUINT, "status", "--iface", IFACE, "--json", *extra])
    return code, (json.loads(out) if out.strip() else None), err


def test_unhomed_machine_refuses_then_homes_and_runs(make_sim, bus):
    sim = make_sim("unhomed", start=plan_start_mm(1), extra=["--unhomed"])
    sim.wait_heartbeats(bus)
    code, s, err = status()
    assert code == 0, err
    assert [n["id"] for n in s["nodes"]] == [1, 2, 3]
    assert all(n["homed"] is False and n["homing"] == "not homed" for n in s["nodes"])
    assert all(n["joint_position_mm"] is None for n in s["nodes"])
    assert s["platform_mm"] is None
    assert all(n["protocol_version"] == PROTOCOL_VERSION for n in s["nodes"])
    # Upload refused before anything moves; the nodes stay Idle, no fault.
    code, out, err = run([TRIQUINT, "upload", plan_path(1), "--iface", IFACE])
    assert code == REFUSED, err
    assert "NotHomed" in err and "triquint home --iface" in err, err
    code, s, err = status()
    assert all(n["state"] == "Idle" and n["fault"]["code"] == 0 for n in s["nodes"]), s
    # Home: all three, a line per axis.
    code, out, err = run([TRIQUINT, "home", "--iface", IFACE], timeout=120)
    assert code == 0, err
    for axis in (1, 2, 3):
        assert re.search(rf"axis {axis} \(node {axis}\): homed after [0-9.]+ s", err), err
    took = float(re.search(r"all axes homed in ([0-9.]+) s", out).group(1))
    assert took < 30.0, out
    code, s, err = status()
    assert all(n["homed"] is True for n in s["nodes"]), s
    assert s["platform_mm"] is not None
    # Not at the plan's start: refused, with the distances and the move.
    code, out, err = run([TRIQUINT, "upload", plan_path(1), "--iface", IFACE])
    assert code == REFUSED, err
    assert "ArmTooFar" in err and "axis 1" in err, err
    move = re.search(r"`(triquint move-to [^`]+)`", err).group(1).split()
    assert move[2:5] == ["-90", "90", "680"], move
    code, out, err = run([TRIQUINT, *move[1:]], timeout=120)
    assert code == 0, err
    code, out, err = run([TRIQUINT, "upload", plan_path(1), "--iface", IFACE], timeout=120)
    assert code == 0, err
    sim.stop()


def test_faulted_nodes_are_refused_until_cleared(make_sim, bus):
    sim = make_sim("estop", start=plan_start_mm(1))
    sim.wait_heartbeats(bus)
    code, out, err = run([TRIQUINT, "estop", "--iface", IFACE])
    assert code == 0, err
    code, s, err = status()
    assert code == 0, err
    assert all(n["state"] == "Fault" and n["fault"]["name"] == "HostEmergency" for n in s["nodes"]), s
    assert all(n["fault"]["hint"] for n in s["nodes"])
    code, out, err = run([TRIQUINT, "upload", plan_path(1), "--iface", IFACE])
    assert code == REFUSED, err
    assert "triquint status --iface" in err and "triquint clear --iface" in err and "--clear" in err, err
    code, out, err = run([TRIQUINT, "clear", "--iface", IFACE])
    assert code == 0, err
    code, s, err = status()
    assert all(n["state"] == "Idle" for n in s["nodes"]), s
    # Faulted again: --clear clears and runs.
    run([TRIQUINT, "estop", "--iface", IFACE])
    code, out, err = run([TRIQUINT, "upload", plan_path(1), "--iface", IFACE, "--clear"], timeout=120)
    assert code == 0, err
    sim.stop()


def test_status_of_a_silent_node_is_exit_4(make_sim, bus):
    sim = make_sim("status-silent", nodes="1,2", start=plan_start_mm(1))
    sim.wait_heartbeats(bus, nodes=(1, 2))
    code, s, err = status()
    assert code == 4, err
    assert [n["heard"] for n in s["nodes"]] == [True, True, False]
    sim.stop()


def test_nodes_4_5_6(make_sim, bus):
    sim = make_sim("nodes456", nodes="4,5,6", start=plan_start_mm(1))
    sim.wait_heartbeats(bus, nodes=(4, 5, 6))
    code, s, err = status("--nodes", "4,5,6")
    assert code == 0, err
    assert [(n["id"], n["axis"]) for n in s["nodes"]] == [(4, 1), (5, 2), (6, 3)]
    # Nodes 1-3 are silent here.
    code, _, err = status()
    assert code == 4, err
    code, out, err = run([TRIQUINT, "upload", plan_path(1), "--iface", IFACE, "--nodes", "4,5,6", "--json"], timeout=120)
    assert code == 0, err
    summary = json.loads(out)
    assert [n["node"] for n in summary["nodes"]] == [4, 5, 6]
    assert summary["completed"]
    report = sim.stop()
    assert report["completed"], report["faults"]


def test_stuck_and_dead_switches_fault(make_sim, bus):
    for name, opt, axis, code_name in [
        ("stuck", "--stuck-switch", 2, "HomeSwitchActive"),
        ("dead", "--dead-switch", 3, "HomeSwitchNeverTriggered"),
    ]:
        sim = make_sim(f"switch-{name}", start=plan_start_mm(1), extra=["--unhomed", opt, str(axis)])
        sim.wait_heartbeats(bus)
        code, out, err = run([TRIQUINT, "home", "--iface", IFACE], timeout=120)
        assert code == 5, err
        assert code_name in err, err
        code, s, err = status()
        assert s["nodes"][axis - 1]["fault"]["name"] == code_name, s
        assert s["nodes"][axis - 1]["homing"] == "failed", s
        code, out, err = run([TRIQUINT, "clear", "--iface", IFACE])
        assert code == 0, err
        sim.stop()
