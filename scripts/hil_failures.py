"""Prints, last in the HIL run's output, what each failed test said
(scripts/hil.sh): CI shows a run's tail, and the suite's own report of a
failure is far above it. Reads the suite's JUnit XML (OUT/junit.xml) and,
for each failure, prints the test, its message's last lines and the tail
of the simulator logs it left (OUT/sim-*.log written during the test)."""
import glob
import os
import sys
import xml.etree.ElementTree as ET

out = sys.argv[1]
MESSAGE_LINES = 25
LOG_LINES = 8


def tail(text, n):
    lines = [line.rstrip() for line in text.replace("\r", "\n").splitlines() if line.strip()]
    return lines[-n:]


try:
    root = ET.parse(os.path.join(out, "junit.xml")).getroot()
except (OSError, ET.ParseError) as e:
    print(f"no JUnit report ({e})")
    sys.exit(0)
failed = 0
for case in root.iter("testcase"):
    for bad in list(case.findall("failure")) + list(case.findall("error")):
        failed += 1
        name = f"{case.get('classname')}::{case.get('name')}"
        print(f"--- {name} ({bad.tag}, {case.get('time')} s)")
        for line in tail(bad.text or bad.get("message") or "", MESSAGE_LINES):
            print(f"    {line[:200]}")
        # A simulator's log is sim-NAME.log (or proxy-NAME.log): show those
        # whose NAME the test's module uses.
        module = case.get("classname", "").split(".")[-1]
        src = os.path.join(os.path.dirname(__file__), "..", "hil-sim", "python", f"{module}.py")
        try:
            with open(src, encoding="utf-8") as f:
                source = f.read()
        except OSError:
            continue
        logs = glob.glob(os.path.join(out, "sim-*.log")) + glob.glob(os.path.join(out, "proxy-*.log"))
        for log in sorted(logs):
            base = os.path.basename(log)
            stem = base.split("-", 1)[1].split(".")[0]
            if f'"{stem}"' not in source:
                continue
            with open(log, encoding="utf-8", errors="replace") as f:
                print(f"    {base}:")
                for line in tail(f.read(), LOG_LINES):
                    print(f"      {line[:200]}")
print(f"{failed} failed test(s) reported")
