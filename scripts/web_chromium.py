#!/usr/bin/env python3
"""Headless Chromium test of `triquint monitor --web` on a replayed log.

Starts the monitor on a free loopback port replaying a testdata/hil log,
loads the page in headless Chromium driven over the DevTools protocol
(--remote-debugging-pipe: NUL-separated JSON on fds 3 and 4, no extra
Python package), and checks: three axis cards "Axis 1..3" with protocol
state names in the DOM, the traces gain points over time, no console
errors or exceptions (DevTools events and the --enable-logging=stderr
log); writes a screenshot (PNG).

usage: web_chromium.py TRIQUINT_BIN LOG OUT.png [--at SECONDS]
"""

import base64
import json
import os
import re
import select
import subprocess
import sys
import tempfile
import time

STATES = {"Idle", "Loaded", "Armed", "Running", "Stopping", "Fault", "Homing"}


class Cdp:
    def __init__(self, args):
        # Chromium reads commands on fd 3 and writes answers on fd 4.
        to_r, self.to_w = os.pipe()
        self.from_r, from_w = os.pipe()
        self.log = tempfile.TemporaryFile()

        def fds():
            # Through fds above 4 first, so neither end lands on the other.
            a, b = os.dup2(to_r, 100), os.dup2(from_w, 101)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.proc = subprocess.Popen(
            args, stdin=subprocess.DEVNULL, stdout=self.log, stderr=self.log,
            preexec_fn=fds, pass_fds=(3, 4), close_fds=True)
        os.close(to_r)
        os.close(from_w)
        self.buf = b""
        self.next_id = 0
        self.events = []

    def _read(self, deadline):
        while b"\0" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no answer from Chromium")
            r, _, _ = select.select([self.from_r], [], [], left)
            if r:
                chunk = os.read(self.from_r, 1 << 20)
                if not chunk:
                    raise RuntimeError("Chromium closed the pipe")
                self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, session=None, timeout=30, **params):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params}
        if session:
            msg["sessionId"] = session
        os.write(self.to_w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            m = self._read(deadline)
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def stderr(self):
        self.log.seek(0)
        return self.log.read().decode(errors="replace")

    def close(self):
        try:
            self.call("Browser.close", timeout=5)
        except Exception:
            pass
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def console_errors(events):
    errs = []
    for e in events:
        m, p = e.get("method"), e.get("params", {})
        if m == "Runtime.exceptionThrown":
            errs.append(json.dumps(p.get("exceptionDetails", {}))[:500])
        elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            errs.append(json.dumps(p.get("args", []))[:500])
        elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            errs.append(json.dumps(p["entry"])[:500])
    return errs


def main():
    args = sys.argv[1:]
    at = 4.5
    if "--at" in args:
        i = args.index("--at")
        at = float(args[i + 1])
        del args[i:i + 2]
    binary, log, out = args
    browser = os.environ.get("CHROMIUM", "chromium")
    mon = subprocess.Popen(
        [binary, "monitor", "--web", "127.0.0.1:0", "--replay", log, "--duration", "120"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    failures = []
    cdp = None
    try:
        line = mon.stdout.readline()
        m = re.search(r"http://(127\.0\.0\.1:\d+)/", line)
        if not m:
            raise SystemExit(f"monitor did not start: {line!r} {mon.stderr.read()}")
        url = f"http://{m.group(1)}/"
        t_start = time.monotonic()
        profile = tempfile.mkdtemp(prefix="tq-chromium-")
        cdp = Cdp([browser, "--headless", "--no-sandbox", "--disable-gpu",
                   "--disable-dev-shm-usage", "--no-first-run", "--no-default-browser-check",
                   "--disable-extensions", "--disable-background-networking",
                   "--disable-component-update", "--disable-sync", "--mute-audio",
                   "--hide-scrollbars", f"--user-data-dir={profile}",
                   "--enable-logging=stderr", "--v=0",
                   "--remote-debugging-pipe", "--window-size=1400,860", "about:blank"])
        target = cdp.call("Target.createTarget", url="about:blank")["targetId"]
        s = cdp.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        for dom in ("Runtime.enable", "Log.enable", "Page.enable"):
            cdp.call(dom, session=s)
        cdp.call("Emulation.setDeviceMetricsOverride", session=s, width=1400, height=860,
                 deviceScaleFactor=1, mobile=False)
        cdp.call("Page.navigate", session=s, url=url)

        def js(expr):
            r = cdp.call("Runtime.evaluate", session=s, expression=expr, returnByValue=True)
            if "exceptionDetails" in r:
                raise RuntimeError(f"{expr}: {r['exceptionDetails']}")
            return r["result"].get("value")

        cards_js = ("JSON.stringify([...document.querySelectorAll('#nodes .node')].map(n => "
                    "[n.querySelector('h2').textContent, n.querySelector('.state').textContent]))")
        cards = []
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            try:
                cards = json.loads(js(cards_js) or "[]")
            except (RuntimeError, json.JSONDecodeError):
                cards = []
            if len(cards) == 3:
                break
            time.sleep(0.2)
        print(f"node cards: {cards}")
        if [c[0] for c in cards] != ["Axis 1", "Axis 2", "Axis 3"]:
            failures.append(f"cards {cards}, want Axis 1..3")
        if not all(c[1] in STATES for c in cards):
            failures.append(f"state names {cards} not all protocol states")
        pts = "window.triquintMonitor ? window.triquintMonitor.points() : -1"
        p0 = js(pts)
        time.sleep(1.5)
        p1 = js(pts)
        ev = js("window.triquintMonitor ? window.triquintMonitor.events() : -1")
        print(f"trace points: {p0} then {p1} 1.5 s later; {ev} events")
        if not (isinstance(p0, int) and isinstance(p1, int) and p1 > p0 >= 0):
            failures.append(f"traces did not gain points: {p0} → {p1}")
        # Events at the stream's rate (20 Hz): at least 10 Hz measured.
        e0, t0 = js("window.triquintMonitor.events()"), time.monotonic()
        time.sleep(1.0)
        e1, t1 = js("window.triquintMonitor.events()"), time.monotonic()
        rate = (e1 - e0) / (t1 - t0)
        print(f"event rate in the page: {rate:.1f} Hz")
        if rate < 10:
            failures.append(f"event rate {rate:.1f} Hz < 10 Hz")
        # The screenshot while the replayed plan runs (log time `at`).
        wait = at - (time.monotonic() - t_start)
        if wait > 0:
            time.sleep(wait)
        png = cdp.call("Page.captureScreenshot", session=s, format="png")["data"]
        with open(out, "wb") as f:
            f.write(base64.b64decode(png))
        print(f"screenshot: {out}")
        errs = console_errors(cdp.events)
        cdp.close()
        logged = [ln for ln in cdp.stderr().splitlines() if "CONSOLE" in ln and ":ERROR:" in ln
                  or re.search(r"Uncaught|console\.error", ln)]
        for e in errs + logged:
            failures.append(f"console: {e}")
        cdp = None
    finally:
        if cdp:
            cdp.close()
        mon.terminate()
        try:
            mon.wait(5)
        except subprocess.TimeoutExpired:
            mon.kill()
    if failures:
        for f in failures:
            print(f"FAIL {f}")
        print(f"0 passed, {len(failures)} failed")
        sys.exit(1)
    print("web_chromium: 1 passed, 0 failed")


if __name__ == "__main__":
    main()
