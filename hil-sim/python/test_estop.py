"""`triquint estop` over vcan: it waits for every addressed drive
to report the host's emergency (Fault or Stopping with HostEmergency), names
any that did not, and exits 4 if one did not; idle drives, moving drives,
drives on node ids 4, 5, 6, and a drive missing from the bus."""
import json
import re
import subprocess
import time

from conftest import IFACE, TRIQUINT, plan_path, plan_start_mm, run

DEVICE = 4
MOTION_FAULT = 5


def estop(*extra):
    t0 = time.monotonic()
    code, out, err = run([TRIQUINT, "estop", "--iface", IFACE, *extra])
    return code, out, err, time.monotonic() - t0


def node_lines(out):
    return dict(re.findall(r"^axis \d \(node (\d+)\): (.*)$", out, re.M))


def status(*extra):
    code, out, err = run([TRIQUINT, "status", "--iface", IFACE, "--json", *extra])
    return code, (json.loads(out) if out.strip() else None), err


def test_idle_drives_confirm_and_a_missing_one_is_named(make_sim, bus):
    sim = make_sim("estop-confirm", start=plan_start_mm(1))
    sim.wait_heartbeats(bus)
    code, out, err, took = estop()
    assert code == 0, err
    lines = node_lines(out)
    assert lines == {n: "Fault (HostEmergency)" for n in ("1", "2", "3")}, out
    # Each drive answers with its own Emergency frame: well inside the wait.
    assert took < 5.0, took
    # A second estop: the drives are already in Fault with the host's code.
    code, out, err, _ = estop()
    assert code == 0, err
    code, out, err = run([TRIQUINT, "clear", "--iface", IFACE])
    assert code == 0, err
    sim.stop()
    # Node 3 is not on the bus: nodes 1 and 2 confirm, node 3 is named, exit 4.
    sim = make_sim("estop-missing", nodes="1,2", start=plan_start_mm(1))
    sim.wait_heartbeats(bus, nodes=(1, 2))
    code, out, err, _ = estop()
    assert code == DEVICE, (out, err)
    lines = node_lines(out)
    assert lines["1"] == lines["2"] == "Fault (HostEmergency)", out
    assert lines["3"] == "no answer", out
    assert "axis 3 (node 3) did not confirm the emergency stop within 200 ms" in err, err
    sim.stop()


def test_node_ids_4_5_6(make_sim, bus):
    sim = make_sim("estop-456", nodes="4,5,6", start=plan_start_mm(1))
    sim.wait_heartbeats(bus, nodes=(4, 5, 6))
    # Addressed as 1, 2, 3: nobody confirms (the drives still stop: node 0).
    code, out, err, _ = estop()
    assert code == DEVICE, (out, err)
    assert "axis 1 (node 1), axis 2 (node 2), axis 3 (node 3) did not confirm" in err, err
    code, out, err, _ = estop("--nodes", "4,5,6")
    assert code == 0, err
    assert set(node_lines(out)) == {"4", "5", "6"}, out
    code, s, err = status("--nodes", "4,5,6")
    assert all(n["state"] == "Fault" and n["fault"]["name"] == "HostEmergency" for n in s["nodes"]), s
    sim.stop()


def test_moving_drives_confirm_while_stopping(make_sim, bus):
    sim = make_sim("estop-moving", start=plan_start_mm(2))
    sim.wait_heartbeats(bus)
    p = subprocess.Popen([TRIQUINT, "upload", plan_path(2), "--iface", IFACE],
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60:
        assert p.poll() is None, p.communicate()
        code, s, _ = status()
        if code == 0 and all(n["state"] == "Running" for n in s["nodes"]):
            break
        time.sleep(0.1)
    else:
        raise AssertionError("the upload never started")
    code, out, err, _ = estop()
    assert code == 0, err
    lines = node_lines(out)
    assert set(lines) == {"1", "2", "3"}, out
    # Moving: Stopping along the path (or already at rest in Fault).
    assert all(v in ("Stopping (HostEmergency)", "Fault (HostEmergency)") for v in lines.values()), out
    _, upload_err = p.communicate(timeout=60)
    assert p.returncode == MOTION_FAULT, upload_err
    report = sim.stop()
    assert not report["runs"][-1]["completed"]
