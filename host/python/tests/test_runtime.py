"""The module itself: version, signatures, docstrings and stubs; the GIL
released while planning; Ctrl-C as KeyboardInterrupt."""
import ast
import inspect
import pathlib
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import triquint
from conftest import CASE2

STUB = pathlib.Path(__file__).resolve().parents[1] / "triquint.pyi"


def test_version_and_format():
    assert triquint.__version__ == "0.1.0"
    assert triquint.PLAN_FORMAT == "triquint-plan/3"


def test_signatures_and_docstrings():
    sig = inspect.signature(triquint.plan)
    assert list(sig.parameters)[:2] == ["points", "units"]
    assert sig.parameters["units"].kind is inspect.Parameter.KEYWORD_ONLY
    assert sig.parameters["units"].default == "mm"
    assert sig.parameters["total_time"].default == 5.0
    assert sig.parameters["starts"].default == 8
    assert str(inspect.signature(triquint.Robot)).startswith("(*, platform_radius=0.07,")
    assert "millimetres" in triquint.plan.__doc__ and "m/s³" in triquint.plan.__doc__
    for name in triquint.__all__:
        obj = getattr(triquint, name)
        if callable(obj):
            assert obj.__doc__ and len(obj.__doc__) > 20, name
    for meth in ("at", "sample", "check", "to_json", "from_json", "load", "save"):
        assert getattr(triquint.Plan, meth).__doc__, meth


def test_stubs_cover_the_module():
    tree = ast.parse(STUB.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets)
    public = {n for n in names if not n.startswith("_") or n == "__version__"}
    assert public == set(triquint.__all__)
    # Every public method of each class is in its stub class.
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    for cname, node in classes.items():
        stubbed = {m.name for m in node.body if isinstance(m, ast.FunctionDef)}
        stubbed |= {m.target.id for m in node.body if isinstance(m, ast.AnnAssign)}
        cls = getattr(triquint, cname)
        if issubclass(cls, BaseException):
            continue
        real = {n for n in dir(cls) if not n.startswith("_")}
        assert real <= stubbed, (cname, real - stubbed)
    installed = pathlib.Path(triquint.__file__).with_name("__init__.pyi")
    assert installed.read_text() == STUB.read_text()
    assert installed.with_name("py.typed").exists()


def zigzag_circle():
    a = np.linspace(0, 2 * np.pi, 601)[:-1]
    r = 120 + 3 * (-1.0) ** np.arange(600)
    return np.c_[r * np.cos(a), r * np.sin(a), 600 + 0 * a]


def test_the_gil_is_released_while_planning():
    # A 600-point circle that zig-zags 3 mm in and out (so no coarser path
    # stands for it) plans for several seconds; the progress callable
    # cancels it after one, long enough to see the GIL released.
    circle = zigzag_circle()
    result = {}

    def work():
        t = time.perf_counter()
        try:
            triquint.plan(circle, total_time=300.0, progress=lambda p: p.elapsed < 1.0)
        except triquint.CancelledError:
            result["cancelled"] = True
        result["seconds"] = time.perf_counter() - t

    worker = threading.Thread(target=work)
    worker.start()
    gaps, last, ticks = [], time.perf_counter(), 0
    while worker.is_alive():
        sum(range(1000))  # Python work that needs the GIL
        now = time.perf_counter()
        gaps.append(now - last)
        last, ticks = now, ticks + 1
    worker.join()
    assert result.get("cancelled"), "the plan must still be running when cancelled"
    assert result["seconds"] >= 1.0, result
    assert ticks > 1000, ticks
    # Holding the GIL, the planner would stop this loop for the whole plan.
    assert max(gaps) < 0.25, max(gaps)


def test_ctrl_c_raises_keyboard_interrupt_within_a_second():
    script = textwrap.dedent("""
        import sys, time
        import numpy as np
        import triquint
        a = np.linspace(0, 2 * np.pi, 601)[:-1]
        r = 120 + 3 * (-1.0) ** np.arange(600)
        pts = np.c_[r * np.cos(a), r * np.sin(a), 600 + 0 * a]  # several seconds to plan
        print("planning", flush=True)
        t = time.perf_counter()
        try:
            triquint.plan(pts, total_time=300.0)
        except KeyboardInterrupt:
            print(f"interrupted after {time.perf_counter() - t:.3f} s", flush=True)
            sys.exit(42)
        sys.exit("finished without an interrupt")
    """)
    # SIGINT as at a terminal: a process started in the background by a
    # non-interactive shell (as CI may be) inherits SIGINT ignored, and
    # Python then keeps it ignored instead of raising KeyboardInterrupt.
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        assert child.stdout.readline().strip() == "planning"
        time.sleep(1.0)
        assert child.poll() is None, "the plan must still be running"
        sent = time.perf_counter()
        child.send_signal(signal.SIGINT)
        code = child.wait(timeout=10)
        took = time.perf_counter() - sent
    finally:
        if child.poll() is None:
            child.kill()
    out, err = child.communicate()
    assert code == 42, (code, out, err)
    assert took < 1.0, took
