"""Fixtures of the HIL suite: the binaries, the bus, the DBC, and a running
`triquint-sim` (three virtual drives + plant in real time on vcan0).

Paths come from the environment set by scripts/hil.sh (the VM sees the host's
file system read-only; only HIL_OUT is written back)."""
import json
import os
import re
import shutil
import signal
import subprocess
import time

import can
import cantools
import pytest

import stall_rerun

ROOT = os.environ.get("HIL_ROOT", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
IFACE = os.environ.get("HIL_IFACE", "vcan0")
# The drives' side of the fault-injecting proxy (host on IFACE, proxy between).
IFACE_B = os.environ.get("HIL_IFACE_B", "vcan1")
OUT = os.environ.get("HIL_OUT", "/tmp/triquint-hil")
PLANS = os.environ.get("HIL_PLANS", os.path.join(OUT, "plans"))
TRIQUINT = os.environ.get("TRIQUINT", os.path.join(ROOT, "target", "release", "triquint"))
TRIQUINT_SIM = os.environ.get("TRIQUINT_SIM", os.path.join(ROOT, "target", "release", "triquint-sim"))
# The emulated guest computes much slower than the host: 1 kHz control
# fits it (docs/measured-margins.md).
RATE = os.environ.get("HIL_RATE", "1000")
# The protocol version the drives report, read from its one declaration.
with open(os.path.join(ROOT, "shared", "src", "protocol", "messages.rs")) as _f:
    PROTOCOL_VERSION = int(re.search(r"pub const PROTOCOL_VERSION: u8 = (\d+);", _f.read()).group(1))
# The segment queue capacity the drives report, from its one declaration.
with open(os.path.join(ROOT, "shared", "src", "protocol", "streaming.rs")) as _f:
    QUEUE_CAPACITY = int(re.search(r"pub const QUEUE_CAPACITY: usize = (\d+);", _f.read()).group(1))


@pytest.fixture(scope="session")
def db():
    return cantools.database.load_file(os.path.join(ROOT, "docs", "triquint.dbc"))


@pytest.fixture
def bus():
    b = can.Bus(interface="socketcan", channel=IFACE, fd=True)
    yield b
    b.shutdown()


@pytest.fixture
def bus_b():
    b = can.Bus(interface="socketcan", channel=IFACE_B, fd=True)
    yield b
    b.shutdown()


def plan_path(case):
    return os.path.join(PLANS, f"paper-case{case}.json")


def plan_start_mm(case):
    with open(plan_path(case)) as f:
        p = json.load(f)
    return [1000.0 * c for c in p["via_points_m"][0]]


class Sim:
    """A running triquint-sim; `stop()` sends SIGTERM and returns its report."""

    def __init__(self, name, fd=False, nodes="1,2,3", start=None, extra=(), iface=IFACE):
        os.makedirs(OUT, exist_ok=True)
        self.report_path = os.path.join(OUT, f"sim-{name}.json")
        self.log_path = os.path.join(OUT, f"sim-{name}.log")
        args = [TRIQUINT_SIM, "--iface", iface, "--nodes", nodes, "--rate", RATE, "--report", self.report_path]
        if fd:
            args.append("--fd")
        if start is not None:
            args += ["--start", ",".join(f"{c:.6f}" for c in start)]
        args += list(extra)
        self.log = open(self.log_path, "w")
        # Frames stamped before this (kernel receive time, wall clock) come
        # from an earlier drive still queued on a test's open bus.
        self.started = time.time()
        self.proc = subprocess.Popen(args, stdout=self.log, stderr=subprocess.STDOUT)

    def wait_heartbeats(self, bus, nodes=(1, 2, 3), timeout=20.0):
        """Blocks until every node in `nodes` of this sim sent a heartbeat
        (a drive that sends one reads the bus too)."""
        seen = set()
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout and seen != set(nodes):
            assert self.proc.poll() is None, open(self.log_path).read()
            m = bus.recv(0.2)
            if m is not None and 0x701 <= m.arbitration_id <= 0x70F and m.timestamp >= self.started:
                seen.add(m.arbitration_id - 0x700)
        assert seen == set(nodes), f"heartbeats from {sorted(seen)} only"

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        code = self.proc.wait(timeout=30)
        self.log.close()
        assert code == 0, f"triquint-sim exit {code}: {open(self.log_path).read()}"
        with open(self.report_path) as f:
            return json.load(f)


class Proxy(Sim):
    """A running `triquint-sim proxy` between IFACE (A, host) and IFACE_B (B,
    drives) with the given fault options; `stop()` returns its counts."""

    def __init__(self, name, faults=(), fd=False):
        os.makedirs(OUT, exist_ok=True)
        self.report_path = os.path.join(OUT, f"proxy-{name}.json")
        self.log_path = os.path.join(OUT, f"proxy-{name}.log")
        args = [TRIQUINT_SIM, "proxy", "--a", IFACE, "--b", IFACE_B, "--report", self.report_path, *faults]
        if fd:
            args.append("--fd")
        # Real-time priority: in the emulated guest the drives' catch-up loop
        # takes whole CPUs, and every ms the proxy waits for one is a ms of
        # latency on the time sync (it moves the drives' time base).
        chrt = shutil.which("chrt") or "/usr/bin/chrt"
        if os.geteuid() == 0 and os.path.exists(chrt):
            args = [chrt, "-f", "50", *args]
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen(args, stdout=self.log, stderr=subprocess.STDOUT)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_protocol(item, nextitem):
    # A failure while the simulator was behind real time runs once more.
    return stall_rerun.protocol(item, nextitem, OUT)


@pytest.fixture
def make_sim(request):
    sims = []

    def make(*a, cls=Sim, **k):
        s = cls(*a, **k)
        sims.append(s)
        # Read by stall_rerun after the test.
        getattr(request.node, "sim_logs", []).append(s.log_path)
        return s

    yield make
    for s in sims:
        # SIGTERM, so a failed test still leaves the simulator's report.
        if s.proc.poll() is None:
            s.proc.send_signal(signal.SIGTERM)
            try:
                s.proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                s.proc.kill()
                s.proc.wait()


def run(args, timeout=120):
    """Runs a command; returns (exit status, stdout, stderr)."""
    p = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout, p.stderr
