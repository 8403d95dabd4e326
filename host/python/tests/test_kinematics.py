"""ik, fk and torque: the paper's Tables 2 and 6, round trips, shapes."""
import numpy as np
import pytest

import triquint

# (x, y, z) → (q1, q2, q3), millimetres: paper Tables 2 and 6 (as decoded in
# shared/src/kinematics.rs, printed to 0.01 mm).
TABLES = [
    ([-90.0, 90.0, 680.0], [376.68, 244.16, 336.13]),
    ([-90.0, 90.0, 660.0], [356.68, 224.16, 316.13]),
    ([-90.0, 90.0, 640.0], [336.68, 204.16, 296.13]),
    ([-60.0, 60.0, 620.0], [281.18, 195.62, 256.27]),
    ([-20.0, 20.0, 620.0], [246.37, 218.29, 238.64]),
    ([20.0, -20.0, 620.0], [222.51, 250.90, 229.91]),
    ([60.0, -60.0, 620.0], [207.69, 296.43, 229.48]),
    ([90.0, -90.0, 640.0], [221.91, 362.79, 254.57]),
    ([90.0, -90.0, 660.0], [241.91, 382.79, 274.57]),
    ([90.0, -90.0, 680.0], [261.91, 402.79, 294.57]),
    ([-86.0, 83.66, 597.66], [288.39, 163.71, 248.87]),
    ([-43.0, 97.74, 654.74], [310.62, 222.28, 324.36]),
    ([0.0, 84.85, 684.85], [307.49, 265.09, 355.31]),
    ([43.0, 54.74, 697.74], [292.11, 301.92, 361.50]),
    ([86.0, -2.34, 683.66], [257.33, 335.11, 332.45]),
    ([86.0, -83.66, 602.34], [184.29, 315.81, 216.66]),
    ([43.0, -97.74, 545.26], [147.80, 246.31, 136.30]),
    ([0.0, -84.85, 515.15], [137.79, 185.61, 95.39]),
    ([-43.0, -54.74, 502.26], [148.74, 137.79, 82.20]),
    ([-86.0, 2.34, 516.34], [195.97, 112.72, 115.03]),
    ([-86.0, 83.66, 597.66], [288.39, 163.71, 248.87]),
]
P = np.array([r for r, _ in TABLES])
Q = np.array([q for _, q in TABLES])


def test_ik_matches_the_paper_tables():
    q = triquint.ik(P)
    assert q.shape == (21, 3)
    # Printed to 0.01 mm: rounding leaves at most 0.005 mm.
    assert np.max(np.abs(q - Q)) <= 0.0051
    # Three numbers, and one (3,) row, give the same (3,) answer.
    for k in (0, 10, 20):
        one = triquint.ik(*P[k])
        assert one.shape == (3,)
        np.testing.assert_array_equal(one, q[k])
        np.testing.assert_array_equal(triquint.ik(P[k]), q[k])
        np.testing.assert_array_equal(triquint.ik(list(P[k])), q[k])


def test_fk_inverts_ik():
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 2 * np.pi, 500)
    r = rng.uniform(0, 120, 500)
    p = np.c_[r * np.cos(a), r * np.sin(a), rng.uniform(500, 700, 500)]
    back = triquint.fk(triquint.ik(p))
    np.testing.assert_allclose(back, p, rtol=0, atol=1e-9)
    np.testing.assert_allclose(triquint.fk(Q), P, rtol=0, atol=0.02)
    one = triquint.fk(*Q[0])
    assert one.shape == (3,)


def test_units_m():
    q_m = triquint.ik(P / 1000.0, units="m")
    np.testing.assert_allclose(q_m * 1000.0, triquint.ik(P), rtol=0, atol=1e-9)
    np.testing.assert_allclose(triquint.fk(q_m, units="m") * 1000.0, P, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="units"):
        triquint.ik(P, units="inch")


def test_robot_changes_the_kinematics():
    longer = triquint.Robot(strut_length=0.5)
    assert not np.allclose(triquint.ik(P, robot=longer), triquint.ik(P))
    np.testing.assert_allclose(triquint.fk(triquint.ik(P, robot=longer), robot=longer), P, atol=1e-9)


def test_torque_static_and_shapes():
    # At rest the motors hold the weight: positive, equal by symmetry at the centre.
    q = triquint.ik(0, 0, 600, units="mm") / 1000.0
    tau = triquint.torque(q, [0, 0, 0], [0, 0, 0])
    assert tau.shape == (3,)
    assert np.all(tau > 0)
    assert np.ptp(tau) < 1e-9
    # Lighter under gravity 0, heavier with payload.
    assert np.all(triquint.torque(q, [0] * 3, [0] * 3, robot=triquint.Robot(gravity=0.0)) == 0.0)
    assert np.all(triquint.torque(q, [0] * 3, [0] * 3, robot=triquint.Robot(payload_mass=1.0)) > tau)
    qs = triquint.ik(P) / 1000.0
    zero = np.zeros_like(qs)
    many = triquint.torque(qs, zero, zero)
    assert many.shape == (21, 3)
    np.testing.assert_array_equal(many[4], triquint.torque(qs[4], zero[4], zero[4]))
    with pytest.raises(ValueError, match="same shape"):
        triquint.torque(qs, zero[:3], zero)


def test_outside_the_workspace():
    with pytest.raises(triquint.OutsideWorkspaceError) as e:
        triquint.ik([[0, 0, 600], [900, 0, 600]])
    assert e.value.index == 1
    assert e.value.point == (900.0, 0.0, 600.0)
    assert e.value.kind == "position"
    assert e.value.position_m == pytest.approx((0.9, 0.0, 0.6))
    assert isinstance(e.value, ValueError) and isinstance(e.value, triquint.TriquintError)
    with pytest.raises(triquint.OutsideWorkspaceError) as e:
        triquint.fk(0, 0, 1000)
    assert e.value.kind == "joints" and e.value.point == (0.0, 0.0, 1000.0)


def test_bad_kinematics_input():
    for bad in ([1, 2], [[1, 2, 3, 4]], [], np.zeros((2, 3, 1))):
        with pytest.raises(ValueError, match="shape"):
            triquint.ik(bad)
    with pytest.raises(triquint.InvalidJobError, match="not finite") as e:
        triquint.ik([0, float("nan"), 600])
    assert e.value.field == "points"
    with pytest.raises(triquint.InvalidJobError):
        triquint.fk(float("inf"), 0.3, 0.3)
    with pytest.raises(TypeError):
        triquint.ik(1.0, 2.0)
    with pytest.raises(ValueError):
        triquint.ik("a b c")
    with pytest.raises(TypeError):
        triquint.ik(P, unit="mm")
