"""Evaluating a plan: `at`, `sample`, `segments`, `max_abs` against an
independent numpy evaluation of the plan file's coefficients."""
import json

import numpy as np
import pytest

import triquint


def numpy_eval(plan_json: str, times: np.ndarray):
    """q, v, a, jerk (m, 3) from the plan file's text with numpy alone."""
    doc = json.loads(plan_json)
    segs = doc["segments"]
    t0 = np.array([s["t0_s"] for s in segs])
    out = np.zeros((4, len(times), 3))
    for n, t in enumerate(times):
        i = max(int(np.searchsorted(t0, t, side="right")) - 1, 0)
        u = t - segs[i]["t0_s"]
        for j in range(3):
            c = np.array(segs[i]["coeffs"][j])[::-1]  # np.polyval: highest power first
            for d in range(4):
                out[d, n, j] = np.polyval(c, u)
                c = np.polyder(c)
    return out


@pytest.mark.parametrize("name", ["case1", "case2"])
def test_at_matches_numpy_at_1000_random_times(name, request):
    p = request.getfixturevalue(name)
    rng = np.random.default_rng(20200312)
    times = rng.uniform(0.0, p.duration, 1000)
    ref = numpy_eval(p.to_json(), times)
    s = p.at(times)
    assert s.q.shape == s.v.shape == s.a.shape == s.jerk.shape == (1000, 3)
    np.testing.assert_allclose(s.q, ref[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.v, ref[1], rtol=0, atol=1e-11)
    np.testing.assert_allclose(s.a, ref[2], rtol=0, atol=1e-10)
    np.testing.assert_allclose(s.jerk, ref[3], rtol=0, atol=1e-9)
    # One time at a time gives (3,) arrays, the same numbers.
    for k in (0, 17, 999):
        one = p.at(float(times[k]))
        assert one.q.shape == (3,)
        np.testing.assert_array_equal(one.q, s.q[k])
        np.testing.assert_array_equal(one.jerk, s.jerk[k])


def test_at_rests_outside_the_plan(case1):
    start, end = case1.at(0.0), case1.at(case1.duration)
    before, after = case1.at(-1.0), case1.at(case1.duration + 1.0)
    np.testing.assert_array_equal(before.q, start.q)
    np.testing.assert_allclose(after.q, end.q, rtol=0, atol=1e-12)
    for s in (before, after):
        assert not s.v.any() and not s.a.any() and not s.jerk.any()
    # The plan starts and ends at the first and last via-point (joint space).
    np.testing.assert_allclose(start.q, triquint.ik(case1.via_points[0], units="m"), atol=1e-12)
    np.testing.assert_allclose(end.q, triquint.ik(case1.via_points[-1], units="m"), atol=1e-9)


def test_sample_agrees_with_at(case2):
    s = case2.sample(0.001)
    n = len(s)
    assert n == 5001
    assert s.t.shape == (n,)
    assert s.t[0] == 0.0 and s.t[-1] == case2.duration
    np.testing.assert_allclose(np.diff(s.t), 0.001, rtol=0, atol=1e-12)
    for name in ("q", "v", "a", "jerk", "torque", "platform"):
        assert getattr(s, name).shape == (n, 3), name
    a = case2.at(s.t)
    for name in ("q", "v", "a", "jerk"):
        np.testing.assert_array_equal(getattr(s, name), getattr(a, name), err_msg=name)
    # Torque: the inverse dynamics of the same state; platform: FK of q.
    np.testing.assert_allclose(s.torque, triquint.torque(s.q, s.v, s.a), rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.platform, triquint.fk(s.q, units="m"), rtol=0, atol=1e-12)
    # The joints pass through the knots, so the platform through every
    # via-point (Case II has 11 via-points, 10 segments: no added knots).
    knots_t = np.concatenate([[0.0], np.cumsum(case2.segments.durations)])
    at_knots = case2.at(knots_t).q
    np.testing.assert_allclose(at_knots, case2.knots, rtol=0, atol=1e-12)
    np.testing.assert_allclose(triquint.fk(at_knots, units="m"), case2.via_points, rtol=0, atol=1e-9)


def test_sampled_peaks_stay_within_the_exact_maxima(case2):
    s = case2.sample(0.0005)
    m = case2.max_abs
    for name, key in (("v", "velocity"), ("a", "acceleration"), ("jerk", "jerk"), ("torque", "torque")):
        sampled = np.max(np.abs(getattr(s, name)), axis=0)
        assert m[key].shape == (3,)
        assert np.all(sampled <= m[key] * (1 + 1e-3) + 1e-12), (name, sampled, m[key])
        assert np.all(sampled >= m[key] * 0.99), (name, sampled, m[key])


def test_segments(case1):
    seg = case1.segments
    k = len(seg)
    assert k == 9
    assert seg.durations.shape == (k,) and seg.t0.shape == (k,) and seg.coeffs.shape == (k, 3, 6)
    assert seg.durations.sum() == pytest.approx(case1.duration, abs=1e-12)
    np.testing.assert_allclose(seg.t0[1:], np.cumsum(seg.durations)[:-1], rtol=0, atol=1e-12)
    # Whole microseconds (what the drives run).
    us = seg.durations * 1e6
    np.testing.assert_allclose(us, np.round(us), rtol=0, atol=1e-6)
    # coeffs[i, j, 0] is joint j's position at the start of segment i.
    np.testing.assert_allclose(seg.coeffs[:, :, 0], case1.at(seg.t0).q, rtol=0, atol=1e-12)
    assert case1.knots.shape == (k + 1, 3) and case1.via_points.shape == (10, 3)


def test_arrays_are_writable_copies(case1):
    s = case1.at([0.5, 1.5])
    s.q[0, 0] = 123.0  # numpy arrays the caller owns
    assert case1.at([0.5, 1.5]).q[0, 0] != 123.0
    seg = case1.segments
    seg.coeffs[:] = 0.0
    assert case1.segments.coeffs.any()


def test_bad_times(case1):
    with pytest.raises(ValueError, match="NaN"):
        case1.at(float("nan"))
    with pytest.raises(ValueError, match="NaN"):
        case1.at([0.1, float("nan")])
    with pytest.raises(ValueError, match="shape"):
        case1.at([[0.1, 0.2]])
    with pytest.raises(ValueError):
        case1.at("soon")
    for dt in (0.0, -0.1, float("nan"), float("inf"), 1e-12):
        with pytest.raises(ValueError):
            case1.sample(dt)
