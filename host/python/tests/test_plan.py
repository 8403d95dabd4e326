"""Planning from Python: the paper's optima, jobs, keywords, progress."""
import numpy as np
import pytest

import triquint
from conftest import CASE1, CASE2, EXAMPLES


def max_jerk(p):
    return float(np.max(p.max_abs["jerk"]))


def test_paper_optima_at_5_s(case1, case2):
    # docs/verification.md: 0.3325 and 1.5347 m/s³ (paper: 3.102 and 2.808).
    assert max_jerk(case1) == pytest.approx(0.33251, abs=1e-4)
    assert max_jerk(case2) == pytest.approx(1.53472, abs=1e-4)
    for p in (case1, case2):
        assert p.duration == pytest.approx(5.0, abs=1e-9)
        assert p.objective == "min-max-jerk"
        assert p.format == triquint.PLAN_FORMAT == "triquint-plan/3"


def test_points_and_job_file_give_the_same_plan(case1):
    p = triquint.plan(CASE1)
    assert p.segments.coeffs.tobytes() == case1.segments.coeffs.tobytes()
    assert p.segments.durations.tobytes() == case1.segments.durations.tobytes()
    # The same job in metres is the same plan.
    m = triquint.plan(np.array(CASE1) / 1000.0, units="m")
    np.testing.assert_allclose(m.segments.coeffs, p.segments.coeffs, rtol=0, atol=1e-12)


def test_job_properties():
    job = triquint.Job(CASE2, total_time=6.0, jerk=4.0)
    assert job.objective == "min-max-jerk"
    assert job.points.shape == (11, 3)
    np.testing.assert_allclose(job.points, np.array(CASE2) / 1000.0, rtol=0, atol=1e-15)
    assert job.limits == {"velocity": 0.5, "acceleration": 1.2, "jerk": 4.0, "torque": 10.0, "total_time": 6.0}
    assert job.robot == triquint.Robot()
    # Fewer than five via-points get straight-line knots.
    short = triquint.Job([[0, 0, 600], [20, 0, 600]])
    assert short.knots.shape == (5, 3)
    np.testing.assert_allclose(short.knots[2], [0.010, 0.0, 0.6], atol=1e-15)
    assert "2 via-points" in repr(short)


def test_plan_of_a_job_refuses_job_keywords():
    job = triquint.Job([[0, 0, 600], [20, 0, 600]])
    for kw in ({"velocity": 0.4}, {"units": "mm"}, {"objective": "min-time"}, {"robot": triquint.Robot()},
               {"total_time": 1.0}, {"jerk": 1.0}, {"acceleration": 1.0}, {"torque": 1.0}):
        with pytest.raises(TypeError, match=next(iter(kw))):
            triquint.plan(job, **kw)
    p = triquint.plan(job, starts=2, seed=3)
    assert p.solver["starts"] >= 1


def test_min_time_meets_every_limit():
    p = triquint.plan([[0, 0, 600], [40, 0, 600], [40, 40, 620]], objective="min-time", velocity=0.2)
    assert p.objective == "min-time"
    assert p.duration < 5.0
    assert all(row["ok"] for row in p.check())
    assert np.max(p.max_abs["velocity"]) <= 0.2 * (1 + 1e-9)


def test_limits_and_robot_reach_the_planner():
    pts = [[0, 0, 600], [60, 0, 600], [60, 60, 600]]
    slow = triquint.plan(pts, total_time=3.0)
    assert slow.limits["total_time"] == 3.0
    assert slow.duration == pytest.approx(3.0, abs=1e-9)
    heavy = triquint.plan(pts, total_time=3.0, robot=triquint.Robot(payload_mass=5.0))
    assert heavy.robot.payload_mass == 5.0
    # Same kinematics, same jerk-optimal joints; more mass, more torque.
    assert np.max(heavy.max_abs["torque"]) > 1.5 * np.max(slow.max_abs["torque"])


def test_seed_and_starts_are_deterministic():
    pts = CASE2[:6]
    a = triquint.plan(pts, starts=5, seed=7)
    b = triquint.plan(pts, starts=5, seed=7)
    assert a.segments.coeffs.tobytes() == b.segments.coeffs.tobytes()


def test_progress_is_called_with_a_snapshot():
    seen = []
    a = np.linspace(0, 2 * np.pi, 21)[:-1]
    pts = np.c_[100 * np.cos(a), 100 * np.sin(a), 600 + 0 * a]
    triquint.plan(pts, total_time=6.0, starts=3, progress=seen.append)
    assert seen, "a plan of 20 points takes more than 25 ms: the observer must run"
    assert all(isinstance(s, triquint.Progress) for s in seen)
    assert all(s.stage in ("searching", "limits-bind", "min-time", "finishing") for s in seen)
    assert [s.elapsed for s in seen] == sorted(s.elapsed for s in seen)
    assert seen[-1].lp_solves > 0


def test_progress_returning_false_cancels():
    calls = []

    def stop(p):
        calls.append(p)
        return False

    a = np.linspace(0, 2 * np.pi, 21)[:-1]
    pts = np.c_[100 * np.cos(a), 100 * np.sin(a), 600 + 0 * a]
    with pytest.raises(triquint.CancelledError) as e:
        triquint.plan(pts, total_time=6.0, progress=stop)
    assert e.value.reason == "observer"
    assert len(calls) == 1


def test_progress_exception_propagates():
    class Stop(Exception):
        pass

    def boom(p):
        raise Stop("from the callback")

    a = np.linspace(0, 2 * np.pi, 21)[:-1]
    pts = np.c_[100 * np.cos(a), 100 * np.sin(a), 600 + 0 * a]
    with pytest.raises(Stop, match="from the callback"):
        triquint.plan(pts, total_time=6.0, progress=boom)


def test_bad_search_settings():
    with pytest.raises(ValueError, match="starts"):
        triquint.plan(CASE1, starts=0)
    with pytest.raises(OverflowError):
        triquint.plan(CASE1, starts=-1)
    with pytest.raises(TypeError, match="progress"):
        triquint.plan(CASE1, progress=3)


def test_job_from_toml_reads_the_examples():
    job = triquint.Job.from_toml(str(EXAMPLES / "paper-case2.toml"))
    assert job.points.shape == (11, 3)
    assert job.limits["total_time"] == 5.0


def test_free_knots_and_the_path_deviation(tmp_path):
    move = 'objective = "min-time"\nknots = "{}"\n[path]\nunits = "mm"\npoints = [[-90, 90, 680], [40, -60, 600]]\n'
    plans = {}
    for knots in ("free", "fixed"):
        path = tmp_path / f"{knots}.toml"
        path.write_text(move.format(knots))
        plans[knots] = triquint.plan(triquint.Job.from_toml(str(path)))
    free, fixed = plans["free"], plans["fixed"]
    assert free.format == "triquint-plan/4" and fixed.format == "triquint-plan/3"
    assert free.free_knots == list(range(1, len(free.knots) - 1))
    assert fixed.free_knots == []
    assert free.duration < fixed.duration
    assert all(row["ok"] for row in free.check())
    d, f = free.path_deviation, fixed.path_deviation
    assert d["max"] <= d["bound"] and 0 < d["step"] <= 2e-4
    # The free knots leave the straight line; the fixed ones stay near it.
    assert f["bound"] < 0.5e-3 < d["max"]


def test_knots_keyword():
    move = [[-90, 90, 680], [40, -60, 600]]
    free = triquint.plan(move, objective="min-time", knots="free")
    job = triquint.Job(move, objective="min-time", knots="free")
    assert job.knot_placement == "free"
    assert triquint.plan(job).duration == free.duration
    fixed = triquint.plan(move, objective="min-time", knots="fixed")
    assert free.free_knots and free.duration < fixed.duration and not fixed.free_knots
    # Without `knots`, a point-to-point min-time move gets free knots.
    assert triquint.plan(move, objective="min-time").duration == free.duration
    assert "triquint-plan/4" in repr(free)
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.plan([*move, [0, 0, 600]], objective="min-time", knots="free")
    assert e.value.field == "knots"
    # Min-max-jerk: a knot added a segment, never a higher jerk than fixed.
    mmj, mmj_fixed = (triquint.plan(move, total_time=2.0, knots=k) for k in ("free", "fixed"))
    assert max(mmj.max_abs["jerk"]) <= max(mmj_fixed.max_abs["jerk"])
    assert all(row["ok"] for row in mmj.check())
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.Job(move, knots="loose")
    assert e.value.field == "knots"
    with pytest.raises(TypeError):
        triquint.plan(job, knots="free")


def test_knot_segments_and_the_deviation_bound():
    move = [[-90, 90, 680], [40, -60, 600]]
    p = triquint.plan(move, objective="min-time", knots="free", knot_segments=16)
    assert len(p.segments) == 16 and all(row["ok"] for row in p.check())
    # More than stream in under a second are refused, not changed.
    with pytest.raises(triquint.TriquintError) as e:
        triquint.plan(move, objective="min-time", knots="free", knot_segments=40)
    assert "unstreamable" in str(e.value)
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.plan(move, objective="min-time", knots="free", knot_segments=2)
    assert e.value.field == "knots.segments"
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.plan(move, objective="min-time", knots="fixed", knot_segments=7)
    assert e.value.field == "knots.segments"
    bounded = triquint.plan(move, objective="min-time", knots="free", max_deviation_mm=0.5)
    assert bounded.path_deviation["max"] <= 0.5e-3 < triquint.plan(move, objective="min-time", knots="free").path_deviation["max"]
    assert all(row["ok"] for row in bounded.check())
    # The bound is recorded (format 6), shown beside the deviation, proved by check.
    d = bounded.path_deviation
    assert bounded.format == "triquint-plan/6" and d["limit"] == 0.5e-3 and d["bound"] <= d["limit"]
    assert any(row["what"].startswith("path deviation") and row["ok"] for row in bounded.check())
    assert triquint.plan(move, objective="min-time", knots="free").path_deviation["limit"] is None
    with pytest.raises(triquint.InfeasibleError) as e:
        triquint.plan(move, objective="min-time", knots="free", max_deviation_mm=1e-3)
    assert e.value.limit == "max_deviation_mm" and e.value.reached > 1e-3
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.plan(move, objective="min-time", max_deviation_mm=float("nan"))
    assert e.value.field == "path.max_deviation_mm"


P2P = [[-60, 40, 560], [60, -40, 640]]


def test_a_shaped_plan_records_its_shaper_and_its_cost():
    # docs/input-shaping.md: EI at 25.6 Hz adds one period of the mode.
    unshaped = triquint.plan(P2P, objective="min-time")
    p = triquint.plan(P2P, objective="min-time", shaper="ei:25.6:0.062")
    assert unshaped.shaper is None
    s = p.shaper
    assert (s["type"], s["frequency_hz"], s["damping"]) == ("ei", 25.6, 0.062)
    assert s["duration_s"] == pytest.approx(1 / 25.6, abs=2e-3)
    # The shaper's duration longer than the unshaped move, give or take 5 %
    # of it: to keep the streaming rule the planner shapes this move taken
    # in fewer segments (docs/input-shaping.md), which can be a little
    # shorter or longer than the default count's.
    assert abs(p.duration - s["duration_s"] - unshaped.duration) <= 0.05 * unshaped.duration
    # Every row holds, streaming too.
    failed = [row["what"] for row in p.check() if not row["ok"]]
    assert not failed, failed
    # The dict form, as the job file's [shaper]; Klipper's damping 0.1 by default.
    j = triquint.Job(P2P, objective="min-time", shaper={"type": "zvd", "frequency_hz": 25.6})
    assert triquint.plan(j).shaper["damping"] == 0.1
    assert triquint.plan(P2P, objective="min-time", shaper="none").shaper is None


@pytest.mark.parametrize("bad", ["ei", "wobble:25", "ei:abc", "ei:25:0.1:9", "ei:0",
                                 {"type": "ei"}, {"frequency_hz": 25}, {"type": "ei",
                                 "frequency_hz": 25, "phase": 1}])
def test_a_bad_shaper_names_the_field(bad):
    with pytest.raises(triquint.InvalidJobError) as e:
        triquint.Job(P2P, objective="min-time", shaper=bad)
    assert e.value.field == "shaper"


def test_a_shaper_of_the_wrong_type_is_a_type_error():
    with pytest.raises(TypeError):
        triquint.Job(P2P, shaper=25.6)
