"""Hold, resume, feed override and stop over vcan: `triquint
upload` of Case II runs in one process, `triquint hold | resume | override |
stop` come from others at moments of their own (inside ramps too); each
exits 0, an override above the cap exits 8 with the cap, the plan completes
(or, stopped, the upload exits 7) with no fault."""
import json
import subprocess
import time

from conftest import IFACE, TRIQUINT, plan_path, plan_start_mm, run

REFUSED = 8
STOPPED = 7


def status():
    code, out, err = run([TRIQUINT, "status", "--iface", IFACE, "--json"])
    assert code == 0, err
    return json.loads(out)


def upload():
    return subprocess.Popen(
        [TRIQUINT, "upload", plan_path(2), "--iface", IFACE],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_running(p, timeout=60.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        assert p.poll() is None, p.communicate()
        if all(n["state"] == "Running" for n in status()["nodes"]):
            return time.monotonic()
        time.sleep(0.1)
    raise AssertionError("the upload never started")


def feed(*args):
    code, out, err = run([TRIQUINT, *args, "--iface", IFACE], timeout=30)
    return code, out, err


def test_feed_hold_resume_override_and_stop_from_another_process(make_sim, bus):
    sim = make_sim("feed", start=plan_start_mm(2))
    sim.wait_heartbeats(bus)
    p = upload()
    wait_running(p)
    # Well inside the 5 s plan, after the status poll above.
    time.sleep(1.2)
    code, out, err = feed("hold")
    assert code == 0, err
    assert "host time" in out, out
    # Held far longer than the plan: a hold has no time limit.
    time.sleep(12.0)
    assert p.poll() is None, p.communicate()
    s = status()
    assert all(n["state"] == "Running" and n["held"] for n in s["nodes"]), s
    # While held: an override is kept for the resume; above the cap refused.
    code, out, err = feed("override", "50")
    assert code == 0, err
    code, out, err = feed("override", "3000")
    assert code == REFUSED, err
    assert "the cap of the configured plan is" in err, err
    code, out, err = feed("resume")
    assert code == 0, err
    # Inside the resume ramp: back to 100 %.
    time.sleep(0.3)
    code, out, err = feed("override", "100")
    assert code == 0, err
    out, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    assert "axis 1 (node 1): Idle, fault None" in out, out
    s = status()
    assert all(n["state"] == "Idle" and n["fault"]["code"] == 0 for n in s["nodes"]), s
    # Case II is closed: the next upload starts where this one ended. Stop it.
    p = upload()
    wait_running(p)
    time.sleep(0.5)
    code, out, err = feed("stop")
    assert code == 0, err
    out, err = p.communicate(timeout=60)
    assert p.returncode == STOPPED, err
    assert "stopped on request" in err, err
    s = status()
    assert all(n["state"] == "Idle" and n["fault"]["code"] == 0 for n in s["nodes"]), s
    sim.stop()


def test_upload_approach_from_power_on_and_from_home(make_sim, bus):
    """`upload --approach` runs the min-time move to the plan's start, then
    the plan: from the simulator's default power-on pose, and from the pose
    `home` leaves the platform in."""
    sim = make_sim("approach")
    sim.wait_heartbeats(bus)
    code, out, err = run([TRIQUINT, "upload", plan_path(2), "--iface", IFACE, "--approach"],
                         timeout=180)
    assert code == 0, err
    assert "axis 1 (node 1): Idle, fault None" in out, out
    sim.stop()
    sim = make_sim("approach-home", extra=["--unhomed"])
    sim.wait_heartbeats(bus)
    code, out, err = run([TRIQUINT, "home", "--iface", IFACE], timeout=120)
    assert code == 0, err
    code, out, err = run([TRIQUINT, "upload", plan_path(2), "--iface", IFACE, "--approach"],
                         timeout=180)
    assert code == 0, err
    assert "axis 1 (node 1): Idle, fault None" in out, out
    code, out, err = run([TRIQUINT, "status", "--iface", IFACE, "--json"])
    assert code == 0, err
    s = json.loads(out)
    assert all(n["state"] == "Idle" and n["fault"]["code"] == 0 for n in s["nodes"]), s
    sim.stop()
