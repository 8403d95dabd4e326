"""Keys during `triquint upload` on a real terminal: the upload
runs under a pseudo-terminal, as on a user's console. Space holds and
resumes, '-' lowers the override by 10 %, both shown in the progress line;
the plan then completes with no fault. A second upload is stopped with 's'."""
import json
import os
import pty
import select
import time

from conftest import IFACE, TRIQUINT, plan_path, plan_start_mm, run

STOPPED = 7


def status():
    code, out, err = run([TRIQUINT, "status", "--iface", IFACE, "--json"])
    assert code == 0, err
    return json.loads(out)


class Terminal:
    """`triquint upload` of Case II with a pseudo-terminal as stdin and stdout."""

    def __init__(self):
        self.pid, self.fd = pty.fork()
        if self.pid == 0:
            os.execv(TRIQUINT, [TRIQUINT, "upload", plan_path(2), "--iface", IFACE])
        self.out = b""
        self.code = None

    def drain(self, seconds=0.0):
        """Reads what the upload wrote for `seconds`; False once it exited."""
        end = time.monotonic() + seconds
        while True:
            ready, _, _ = select.select([self.fd], [], [], max(0.0, end - time.monotonic()))
            if ready:
                try:
                    chunk = os.read(self.fd, 4096)
                except OSError:  # EIO: the upload exited and closed the terminal
                    chunk = b""
                if chunk:
                    self.out += chunk
                    continue
            if self.code is None:
                pid, st = os.waitpid(self.pid, os.WNOHANG)
                if pid:
                    self.code = os.waitstatus_to_exitcode(st)
            if self.code is not None or time.monotonic() >= end:
                return self.code is None

    def key(self, k):
        os.write(self.fd, k)

    def text(self):
        return self.out.decode(errors="replace")

    def why(self):
        """For a failure: the exit status and the last line the upload
        wrote first (a failure's summary shows one line), then its tail."""
        lines = [l.strip() for l in self.text().replace("\r", "\n").splitlines() if l.strip()]
        last = lines[-1] if lines else "(nothing written)"
        return f"exit {self.code}, last line: {last[-300:]}\n{self.text()[-2000:]}"

    def wait(self, timeout):
        end = time.monotonic() + timeout
        while self.drain(0.2):
            assert time.monotonic() < end, self.why()
        return self.code

    def until(self, cond, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            assert self.drain(0.1), f"the upload exited before {what}: {self.why()}"
            if cond(status()["nodes"]):
                return
        raise AssertionError(f"never {what}: {self.why()}")


def test_keys_on_a_terminal_hold_resume_override_and_stop(make_sim, bus):
    sim = make_sim("keys", start=plan_start_mm(2))
    sim.wait_heartbeats(bus)
    t = Terminal()
    t.until(lambda ns: all(n["state"] == "Running" for n in ns), 60, "running")
    assert "space hold/resume" in t.text(), t.why()
    t.drain(1.0)
    t.key(b" ")
    t.until(lambda ns: all(n["held"] for n in ns), 10, "held by the space key")
    # Held longer than the rest of the 5 s plan: not a timeout.
    t.drain(8.0)
    assert t.code is None, t.why()
    assert "HELD" in t.text(), t.why()
    t.key(b"-")
    t.until(lambda ns: all(n["override"] for n in ns), 10, "overridden by the - key")
    t.key(b" ")
    t.until(lambda ns: not any(n["held"] for n in ns), 10, "resumed by the space key")
    assert t.wait(120) == 0, t.why()
    assert "override 90 %" in t.text(), t.why()
    s = status()
    assert all(n["state"] == "Idle" and n["fault"]["code"] == 0 for n in s["nodes"]), s
    # Case II is closed: the next upload starts where this one ended; 's' stops it.
    t = Terminal()
    t.until(lambda ns: all(n["state"] == "Running" for n in ns), 60, "running")
    t.drain(0.5)
    t.key(b"s")
    assert t.wait(60) == STOPPED, t.why()
    assert "stopped on request" in t.text(), t.why()
    s = status()
    assert all(n["state"] == "Idle" and n["fault"]["code"] == 0 for n in s["nodes"]), s
    sim.stop()
