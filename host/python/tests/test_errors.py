"""The exception hierarchy with its fields, and bad input that raises
(never crashes the interpreter, never a PanicException)."""
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import triquint
from conftest import CASE1


def test_hierarchy():
    base = triquint.TriquintError
    assert issubclass(base, Exception)
    for e in (triquint.InvalidJobError, triquint.JobFileError, triquint.OutsideWorkspaceError,
              triquint.InfeasibleError, triquint.UnstreamableError, triquint.CancelledError,
              triquint.SolverError, triquint.PlanFileError, triquint.InternalError):
        assert issubclass(e, base), e
        assert e.__module__ == "triquint"
        assert e.__doc__
    assert issubclass(triquint.InvalidJobError, ValueError)
    assert issubclass(triquint.OutsideWorkspaceError, ValueError)
    assert not issubclass(triquint.InfeasibleError, ValueError)
    assert not issubclass(triquint.UnstreamableError, (ValueError, triquint.InfeasibleError))


def test_invalid_job_names_the_field():
    cases = [
        ({"points": [[0, 0, 600], [float("nan"), 0, 600]]}, "path.points", "not finite"),
        ({"points": CASE1, "velocity": -1.0}, "limits.velocity", "-1"),
        ({"points": CASE1, "jerk": float("nan")}, "limits.jerk", "NaN"),
        ({"points": CASE1, "total_time": 1e300}, "limits.total_time", "1e300"),
        ({"points": CASE1, "objective": "fastest"}, "objective", "min-time"),
        ({"points": [[0, 0, 600]]}, "path.points", "at least 2"),
        ({"points": np.zeros((0, 3))}, "path.points", "at least 2"),
        ({"points": [[0, 0, 600], [0, 0, 600]]}, "path.points", "repeats"),
        ({"points": [[0, 0], [1, 1]]}, "path.points", "shape"),
        ({"points": []}, "path.points", "shape"),
    ]
    for kw, field, text in cases:
        with pytest.raises(triquint.InvalidJobError) as e:
            triquint.plan(**kw)
        assert e.value.field == field, kw
        assert text in str(e.value), (kw, str(e.value))
        assert isinstance(e.value, ValueError)
        # Jobs validate the same way when they are made.
        with pytest.raises(triquint.InvalidJobError):
            triquint.Job(**kw)
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.Robot(lead=0.0)
    assert e.value.field == "robot.lead" and "lead" in e.value.reason


def test_outside_workspace_has_index_and_point():
    with pytest.raises(triquint.OutsideWorkspaceError) as e:
        triquint.plan([[0, 0, 600], [10, 0, 600], [900, 0, 600]])
    assert e.value.index == 2 and e.value.kind == "via-point"
    assert e.value.point == (900.0, 0.0, 600.0)
    assert "point 3 (900, 0, 600) mm" in str(e.value)
    with pytest.raises(triquint.OutsideWorkspaceError) as e:
        triquint.plan([[0, 0, 0.6], [0.9, 0, 0.6]], units="m")
    assert e.value.index == 1 and e.value.point == (0.9, 0.0, 0.6)  # the caller's units


def test_unstreamable_is_its_own_error_with_the_run():
    # 20 points 2 mm apart as fast as the limits allow: 19 segments of a
    # few tens of ms, far less than a queue's worth of look-ahead.
    pts = [[2.0 * i, 0, 600] for i in range(20)]
    with pytest.raises(triquint.UnstreamableError) as e:
        triquint.plan(pts, objective="min-time")
    err = e.value
    assert type(err) is triquint.UnstreamableError
    assert err.capacity >= 2 and err.last - err.first + 1 == err.capacity - 1
    assert 0 < err.run_s < err.need_s
    assert str(err).startswith("unstreamable: segments "), str(err)
    assert f"segments {err.first + 1}–{err.last + 1}" in str(err)


def test_infeasible_has_limit_reached_and_shortest_time():
    pts = [[0, 0, 600], [60, 0, 600]]
    with pytest.raises(triquint.InfeasibleError) as e:
        triquint.plan(pts, total_time=0.2)
    err = e.value
    assert err.limit == "acceleration" and err.unit == "m/s²"
    assert err.limit_value == 1.2
    assert err.reached > err.limit_value
    assert err.shortest_total_time is not None and err.shortest_total_time > 0.2
    assert "acceleration limit 1.2 m/s² binds" in str(err)
    # The shortest time it names is feasible, and is the shortest.
    p = triquint.plan(pts, total_time=err.shortest_total_time * 1.001)
    assert all(row["ok"] for row in p.check())
    with pytest.raises(triquint.InfeasibleError):
        triquint.plan(pts, total_time=err.shortest_total_time * 0.99)


def test_a_torque_limit_below_the_holding_torque_names_it():
    with pytest.raises(triquint.InfeasibleError) as e:
        triquint.plan([[-90, 90, 680], [60, -40, 560]], torque=0.01)
    err = e.value
    assert err.limit == "torque" and err.limit_value == 0.01
    assert err.reached > 0.01 and err.shortest_total_time is None
    assert "hold the platform still at point 1" in str(err)
    # Just above the holding torque it names, the job is not refused for it.
    try:
        triquint.plan([[-90, 90, 680], [60, -40, 560]], torque=err.reached * 1.01)
    except triquint.InfeasibleError as other:
        assert "hold the platform still at point 1" not in str(other)


def test_job_file_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [10, 0, 600]]\nspeed = 3\n")
    with pytest.raises(triquint.JobFileError) as e:
        triquint.Job.from_toml(bad)
    assert e.value.origin == str(bad) and e.value.line == 4
    with pytest.raises(triquint.JobFileError) as e:
        triquint.Job.from_toml(tmp_path / "missing.toml")
    assert e.value.line is None
    far = tmp_path / "far.toml"
    far.write_text("[path]\nunits = \"m\"\npoints = [[0, 0, 0.6], [0.9, 0, 0.6]]\n")
    with pytest.raises(triquint.OutsideWorkspaceError) as e:
        triquint.Job.from_toml(far)
    assert e.value.index == 1 and e.value.point == pytest.approx((900.0, 0.0, 600.0))  # job files: mm


def test_wrong_types_and_keywords():
    with pytest.raises(TypeError):
        triquint.plan(CASE1, speed=0.4)
    with pytest.raises(TypeError):
        triquint.plan(CASE1, 0.4)  # keywords only
    with pytest.raises(ValueError, match="points"):
        triquint.plan("not points")
    with pytest.raises(ValueError, match="points"):
        triquint.plan([["a", "b", "c"], [1, 2, 3]])
    with pytest.raises(TypeError, match="points"):
        triquint.plan([[object()] * 3] * 2)
    with pytest.raises(TypeError):
        triquint.plan(CASE1, robot={"lead": 0.01})
    with pytest.raises(TypeError):
        triquint.Robot(leed=0.01)
    with pytest.raises(ValueError, match="points"):
        triquint.plan([[0, 0, 600], [10, 0]])  # ragged


def test_starts_are_bounded_as_on_the_command_line():
    pts = [[0, 0, 600], [20, 0, 600]]
    for starts in (0, 1001, 10**9):
        with pytest.raises(ValueError, match="1 to 1000"):
            triquint.plan(pts, starts=starts)
    job = triquint.Job(pts)
    with pytest.raises(ValueError, match="1 to 1000"):
        triquint.plan(job, starts=10**9)
    assert triquint.plan(pts, starts=1).solver["starts"] >= 1


def test_a_rust_panic_is_an_internal_error_not_a_panic_exception():
    with pytest.raises(triquint.InternalError, match="deliberate panic"):
        triquint.triquint._raise_rust_panic()
    try:
        triquint.triquint._raise_rust_panic()
    except Exception as e:  # a PanicException (BaseException) would escape this
        assert type(e).__name__ == "InternalError"


def test_bad_input_never_crashes_the_interpreter():
    # Every call must raise an Exception (not crash, not PanicException).
    script = textwrap.dedent("""
        import math, sys
        import numpy as np
        import triquint
        nan, inf = float("nan"), float("inf")
        p = triquint.plan([[0, 0, 600], [20, 0, 600]], starts=1)
        a = np.linspace(0, 2 * np.pi, 41)[:-1]
        circle = np.c_[120 * np.cos(a), 120 * np.sin(a), 600 + 0 * a]
        calls = [
            lambda: triquint.plan([[nan, nan, nan]] * 3),
            lambda: triquint.plan([[inf, 0, 600], [0, 0, 600]]),
            lambda: triquint.plan(np.zeros((0, 3))),
            lambda: triquint.plan(np.zeros((3, 0))),
            lambda: triquint.plan(np.zeros(())),
            lambda: triquint.plan(None),
            lambda: triquint.plan(object()),
            lambda: triquint.plan([[1e308, 1e308, 1e308], [0, 0, 600]]),
            lambda: triquint.plan([[0, 0, 600], [20, 0, 600]], total_time=-1),
            lambda: triquint.plan([[0, 0, 600], [20, 0, 600]], velocity=inf),
            lambda: triquint.plan([[0, 0, 600], [20, 0, 600]], seed=-1),
            lambda: triquint.plan([[0, 0, 600], [20, 0, 600]], starts=2**70),
            # A job long enough (about 1 s) that the callable is called at all.
            lambda: triquint.plan(circle, total_time=8.0, progress=lambda p: 1 / 0),
            lambda: triquint.ik(np.full((4, 3), nan)),
            lambda: triquint.ik(np.zeros((0, 3))).shape == (0, 3) and 1 / 0,
            lambda: triquint.fk([1e300, -1e300, 0]),
            lambda: triquint.torque([0.3] * 3, [nan] * 3, [0] * 3),
            lambda: triquint.torque([5.0, 0, 0], [0] * 3, [0] * 3),
            lambda: p.at(np.full(5, nan)),
            lambda: p.at(np.zeros((2, 2))),
            lambda: p.sample(1e-300),
            lambda: p.sample(nan),
            lambda: triquint.Plan.from_json(""),
            lambda: triquint.Plan.from_json("[]"),
            lambda: triquint.Plan.from_json("{" * 10000),
            lambda: triquint.Plan.from_json(p.to_json().replace('"segments": [', '"segments": [[], ')),
            lambda: triquint.Plan.from_json(p.to_json().replace("0.0", "1e999", 1)),
            lambda: triquint.Robot(gravity=nan),
            lambda: triquint.Robot(base_radius=0.1),
        ]
        for i, f in enumerate(calls):
            try:
                f()
            except Exception as e:
                assert type(e).__module__ in ("triquint", "builtins"), (i, type(e))
            else:
                sys.exit(f"call {i} did not raise")
        print("all raised")
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "all raised" in r.stdout
    assert "PanicException" not in r.stderr and "panicked" not in r.stderr, r.stderr
