"""One more run for a failed test whose simulator fell behind real time.

In the emulated guest the simulator's loop can fall behind its 1 kHz
period (another process takes the CPU; a tick is dearer than on a real
host). Late ticks are caught up, so the run stays consistent, but every
drive then answers late, and the suite's shortest window is 200 ms (an
emergency stop's confirmation). A test that failed while its simulator
reported a tick more than `STALL_US` late runs once more; the rerun and
the late run's simulator logs are kept (OUT/reruns.txt,
sim-*.stalled.log). A failure without that, or a second failure, is
reported as it is."""
import os
import re

from _pytest.runner import runtestprotocol

STALL_US = 100_000


def stall_us(log_path):
    """The latest tick (µs) a simulator's log reports, 0 if none."""
    try:
        with open(log_path, encoding="utf-8") as f:
            m = re.search(r"max late (\d+) µs", f.read())
    except OSError:
        return 0
    return int(m.group(1)) if m else 0


def protocol(item, nextitem, out_dir):
    """`pytest_runtest_protocol` with the rerun (True: handled)."""
    item.ihook.pytest_runtest_logstart(nodeid=item.nodeid, location=item.location)
    for attempt in (1, 2):
        item.sim_logs = []
        reports = runtestprotocol(item, nextitem=nextitem, log=False)
        stalls = [(p, stall_us(p)) for p in item.sim_logs]
        stalls = [(p, us) for p, us in stalls if us > STALL_US]
        if attempt == 2 or not stalls or not any(r.failed for r in reports):
            break
        os.makedirs(out_dir, exist_ok=True)
        with open(os.path.join(out_dir, "reruns.txt"), "a", encoding="utf-8") as f:
            for p, us in stalls:
                f.write(f"{item.nodeid}: failed, its simulator {us / 1e3:.0f} ms late; run again\n")
                os.replace(p, p[: -len(".log")] + ".stalled.log")
        print(f"\n{item.nodeid}: failed with its simulator behind real time; run again")
        item._initrequest()
    for r in reports:
        item.ihook.pytest_runtest_logreport(report=r)
    item.ihook.pytest_runtest_logfinish(nodeid=item.nodeid, location=item.location)
    return True
