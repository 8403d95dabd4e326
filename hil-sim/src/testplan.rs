//! Plans for tests and demos that do not need the planner: a piecewise
//! quintic (Hermite in position, velocity and acceleration at every knot)
//! through the IK images of Cartesian via-points, with spline knot
//! velocities and accelerations and rest at both ends. Not optimal; smooth,
//! realistic and cheap. The streaming fixtures ([`point_to_point`],
//! [`helix`]) are built with [`Ends::Still`] and pass `triquint check`, so
//! `triquint upload` takes them as files.

use crate::band_lu::Banded;
use nalgebra::Vector3;
use triquint_firmware::QUEUE_CAPACITY;
use triquint_shared::kinematics::{KinematicsError, Pose};
use triquint_shared::plan::figures::kinematics;
use triquint_shared::plan::{MaxAbs, Objective, PLAN_FORMAT, Plan, Segment, SolverStats};
use triquint_shared::{Limits, Robot, dynamics};

/// Coefficients of the quintic with q, q', q'' = (q0, v0, a0) at 0 and (q1, v1, a1) at h.
pub fn hermite5(q0: f64, v0: f64, a0: f64, q1: f64, v1: f64, a1: f64, h: f64) -> [f64; 6] {
    let d = q1 - q0;
    let (h2, h3) = (h * h, h * h * h);
    [
        q0,
        v0,
        a0 / 2.0,
        (20.0 * d - (8.0 * v1 + 12.0 * v0) * h - (3.0 * a0 - a1) * h2) / (2.0 * h3),
        (-30.0 * d + (14.0 * v1 + 16.0 * v0) * h + (3.0 * a0 - 2.0 * a1) * h2) / (2.0 * h3 * h),
        (12.0 * d - 6.0 * (v1 + v0) * h + (a1 - a0) * h2) / (2.0 * h3 * h2),
    ]
}

/// Jerk and snap at both ends of a Hermite quintic: (j(0), s(0), j(h), s(h)).
fn ends(c: &[f64; 6], h: f64) -> [f64; 4] {
    [
        6.0 * c[3],
        24.0 * c[4],
        6.0 * c[3] + 24.0 * c[4] * h + 60.0 * c[5] * h * h,
        24.0 * c[4] + 120.0 * c[5] * h,
    ]
}

/// End jerk/snap of a segment are linear in its inputs (q0, v0, a0, q1, v1, a1):
/// the response to each unit input.
fn basis(hs: f64) -> [[f64; 4]; 6] {
    let mut out = [[0.0; 4]; 6];
    for (k, row) in out.iter_mut().enumerate() {
        let mut x = [0.0; 6];
        x[k] = 1.0;
        *row = ends(&hermite5(x[0], x[1], x[2], x[3], x[4], x[5], hs), hs);
    }
    out
}

/// How a plan through points ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ends {
    /// v = a = 0 at both ends, jerk and snap continuous at every interior
    /// knot (C4); the end jerk is what it comes to.
    Rest,
    /// v = a = jerk = 0 at both ends (what `triquint check` asks of a
    /// plan): the snap continuity at the second and the second-to-last knot
    /// gives way to the end jerk, so the plan is C3. Needs four points or
    /// more (with fewer the end jerk stays as [`Ends::Rest`] leaves it).
    Still,
}

/// Knot velocities and accelerations of the quintic spline through `q`
/// (jerk and snap continuous at interior knots; rest at both ends, and with
/// [`Ends::Still`] zero end jerk instead of two snap continuities). One
/// dense solve per joint.
fn quintic_spline_derivatives(q: &[f64], h: &[f64], ends: Ends) -> (Vec<f64>, Vec<f64>) {
    let n = q.len();
    let mut v = vec![0.0; n];
    let mut a = vec![0.0; n];
    if n < 3 {
        return (v, a);
    }
    let m = 2 * (n - 2);
    // A row at knot i touches the knots i − 1, i and i + 1: a band of 3.
    let mut mat = Banded::zeros(m, 3, 3);
    let mut rhs = vec![0.0; m];
    let idx = |i: usize, k: usize| 2 * (i - 1) + k;
    // A segment's end jerk and snap depend on its knots' positions only
    // through their difference (b[0] = −b[3]): with `Ends::Still` taken as
    // such, so the 1/h³ and 1/h⁴ factors of a short segment do not cancel
    // large terms (`Ends::Rest` keeps the form its committed plans came from).
    let mut add = |row: usize, seg: usize, quantity: usize, sign: f64| {
        let b = basis(h[seg]);
        if ends == Ends::Still {
            rhs[row] -= sign * b[3][quantity] * (q[seg + 1] - q[seg]);
        } else {
            rhs[row] -= sign * b[0][quantity] * q[seg];
            rhs[row] -= sign * b[3][quantity] * q[seg + 1];
        }
        for (knot, base) in [(seg, 0usize), (seg + 1, 3)] {
            if knot > 0 && knot < n - 1 {
                mat.add(row, idx(knot, 0), sign * b[base + 1][quantity]);
                mat.add(row, idx(knot, 1), sign * b[base + 2][quantity]);
            }
        }
    };
    let still = ends == Ends::Still && n >= 4;
    for i in 1..n - 1 {
        // Segment i−1 ends at knot i (its end quantities 2, 3), segment i
        // starts there (0, 1): jerk (eq 0) and snap (eq 1) continuous.
        for (eq, le, re) in [(0, 2, 0), (1, 3, 1)] {
            let row = idx(i, eq);
            if still && eq == 1 && i == 1 {
                // Jerk at t = 0 of the first segment instead.
                add(row, 0, 0, 1.0);
            } else if still && eq == 1 && i == n - 2 {
                // Jerk at the end of the last segment instead.
                add(row, n - 2, 2, 1.0);
            } else {
                add(row, i - 1, le, 1.0);
                add(row, i, re, -1.0);
            }
        }
    }
    let sol = if ends == Ends::Still {
        // Rows scaled to unit size (a 2 ms segment's rows are 10⁵ times a
        // long one's), then the solution refined against its residual, for
        // the check's 10⁻⁹ on jerk continuity.
        for r in 0..m {
            let scale = mat.row_amax(r);
            if scale > 0.0 {
                mat.unscale_row(r, scale);
                rhs[r] /= scale;
            }
        }
        let lu = mat.clone().lu();
        lu.solve(&rhs).map(|mut x| {
            for _ in 0..2 {
                let ax = mat.mul(&x);
                let residual: Vec<f64> = rhs.iter().zip(&ax).map(|(b, y)| b - y).collect();
                if let Some(dx) = lu.solve(&residual) {
                    for (x, d) in x.iter_mut().zip(dx) {
                        *x += d;
                    }
                }
            }
            x
        })
    } else {
        mat.lu().solve(&rhs)
    };
    if let Some(sol) = sol {
        for i in 1..n - 1 {
            v[i] = sol[idx(i, 0)];
            a[i] = sol[idx(i, 1)];
        }
    }
    (v, a)
}

/// A plan through `points` (m) with the given intervals (s, rounded to
/// whole µs), C4 with rest at both ends ([`Ends::Rest`]); its `max_abs`
/// sampled.
pub fn plan_through(
    robot: &Robot,
    limits: &Limits,
    points: &[[f64; 3]],
    intervals: &[f64],
) -> Result<Plan, KinematicsError> {
    let mut plan = spline_through(robot, limits, points, intervals, Ends::Rest)?;
    plan.max_abs = sampled_max_abs(&plan)?;
    Ok(plan)
}

/// A plan through `points` (m) with the given intervals that passes
/// `triquint check` (four points or more): [`Ends::Still`], its `max_abs`
/// exact in v, a and jerk ([`kinematics`]), torque sampled on the check's grid.
pub fn checked_plan_through(
    robot: &Robot,
    limits: &Limits,
    points: &[[f64; 3]],
    intervals: &[f64],
) -> Result<Plan, KinematicsError> {
    let mut plan = spline_through(robot, limits, points, intervals, Ends::Still)?;
    let k = kinematics(&plan.segments);
    plan.max_abs = MaxAbs {
        velocity: k.velocity,
        acceleration: k.acceleration,
        jerk: k.jerk,
        torque: sampled_max_abs(&plan)?.torque,
    };
    Ok(plan)
}

fn spline_through(
    robot: &Robot,
    limits: &Limits,
    points: &[[f64; 3]],
    intervals: &[f64],
    ends: Ends,
) -> Result<Plan, KinematicsError> {
    let m = robot.model::<f64>();
    let knots: Vec<Vector3<f64>> = points
        .iter()
        .map(|p| Pose::from_cartesian(&m, Vector3::from(*p)).map(|x| x.q))
        .collect::<Result<_, _>>()?;
    let h: Vec<f64> = intervals
        .iter()
        .map(|x| (x * 1e6).round().max(1.0) * 1e-6)
        .collect();
    let n = knots.len();
    let mut v = vec![Vector3::zeros(); n];
    let mut a = vec![Vector3::zeros(); n];
    for j in 0..3 {
        let q: Vec<f64> = knots.iter().map(|k| k[j]).collect();
        let (vj, aj) = quintic_spline_derivatives(&q, &h, ends);
        for i in 0..n {
            v[i][j] = vj[i];
            a[i][j] = aj[i];
        }
    }
    let mut segments = Vec::new();
    let mut t0 = 0.0;
    for i in 0..n.saturating_sub(1) {
        let coeffs = [0, 1, 2].map(|j| {
            hermite5(
                knots[i][j],
                v[i][j],
                a[i][j],
                knots[i + 1][j],
                v[i + 1][j],
                a[i + 1][j],
                h[i],
            )
        });
        segments.push(Segment {
            t0_s: t0,
            duration_s: h[i],
            coeffs,
        });
        t0 += h[i];
    }
    Ok(Plan {
        format: PLAN_FORMAT.to_string(),
        objective: Objective::MinMaxJerk,
        robot: robot.clone(),
        limits: limits.clone(),
        travel: Default::default(),
        ceilings: Default::default(),
        via_points_m: points.to_vec(),
        knots_m: knots.iter().map(|k| [k[0], k[1], k[2]]).collect(),
        free_knots: Vec::new(),
        max_deviation_m: None,
        intervals_s: h.clone(),
        total_time_s: t0,
        segments,
        max_abs: MaxAbs::default(),
        solver: SolverStats::default(),
        shaping: None,
    })
}

/// Maxima of |v|, |a|, |jerk|, |τ| per joint, sampled (400 points per segment).
pub fn sampled_max_abs(plan: &Plan) -> Result<MaxAbs, KinematicsError> {
    let m = plan.robot.model::<f64>();
    let mut out = MaxAbs::default();
    for s in &plan.segments {
        let q = s.quintic();
        for k in 0..=400 {
            let jm = q.eval(s.duration_s * k as f64 / 400.0);
            let tau = dynamics::state_torque(&m, jm)?;
            for j in 0..3 {
                out.velocity[j] = out.velocity[j].max(jm.qd[j].abs());
                out.acceleration[j] = out.acceleration[j].max(jm.qdd[j].abs());
                out.jerk[j] = out.jerk[j].max(jm.qddd[j].abs());
                out.torque[j] = out.torque[j].max(tau[j].abs());
            }
        }
    }
    Ok(out)
}

fn mm(p: [f64; 3]) -> [f64; 3] {
    p.map(|x| x * 1e-3)
}

/// Paper Case I (inverted U) with the paper's intervals.
pub fn paper_case1() -> Result<Plan, KinematicsError> {
    let pts = [
        [-90.0, 90.0, 680.0],
        [-90.0, 90.0, 660.0],
        [-90.0, 90.0, 640.0],
        [-60.0, 60.0, 620.0],
        [-20.0, 20.0, 620.0],
        [20.0, -20.0, 620.0],
        [60.0, -60.0, 620.0],
        [90.0, -90.0, 640.0],
        [90.0, -90.0, 660.0],
        [90.0, -90.0, 680.0],
    ]
    .map(mm);
    let h = [
        0.738, 0.238, 0.588, 0.370, 0.388, 0.623, 0.799, 0.267, 0.756,
    ];
    plan_through(&Robot::default(), &Limits::default(), &pts, &h)
}

/// Paper Case II's via-points (mm): a closed circle of r = 120 mm.
pub const PAPER_CASE2_MM: [[f64; 3]; 11] = [
    [-86.0, 83.66, 597.66],
    [-43.0, 97.74, 654.74],
    [0.0, 84.85, 684.85],
    [43.0, 54.74, 697.74],
    [86.0, -2.34, 683.66],
    [86.0, -83.66, 602.34],
    [43.0, -97.74, 545.26],
    [0.0, -84.85, 515.15],
    [-43.0, -54.74, 502.26],
    [-86.0, 2.34, 516.34],
    [-86.0, 83.66, 597.66],
];

/// Paper Case II (closed circle, r = 120 mm) with the paper's intervals.
pub fn paper_case2() -> Result<Plan, KinematicsError> {
    let pts = PAPER_CASE2_MM.map(mm);
    let h = [
        1.027, 0.229, 0.225, 0.347, 0.583, 0.455, 0.255, 0.212, 0.307, 1.359,
    ];
    plan_through(&Robot::default(), &Limits::default(), &pts, &h)
}

/// Via-points (mm) of the stress spiral: `n` points on a helix of radius
/// 80 mm about the z axis, `turns` turns rising from 560 to 680 mm.
pub fn spiral_points_mm(n: usize, turns: f64) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let u = i as f64 / (n - 1).max(1) as f64;
            let th = 2.0 * std::f64::consts::PI * turns * u;
            let r = 80.0;
            let round = |x: f64| (x * 100.0).round() / 100.0;
            [
                round(r * th.cos()),
                round(r * th.sin()),
                round(560.0 + 120.0 * u),
            ]
        })
        .collect()
}

/// The stress spiral of `examples/spiral.toml`: points, turns, total time (s).
pub const SPIRAL_POINTS: usize = 97;
pub const SPIRAL_TURNS: f64 = 3.0;
pub const SPIRAL_TIME: f64 = 30.0;

/// The job file `examples/spiral.toml` for the planner .
pub fn spiral_job_toml() -> String {
    let mut o = format!(
        "# Stress example: a 3-turn helix of radius 80 mm rising from 560 to 680 mm,\n\
         # 97 via-points = 96 segments, several times the drives' queue capacity\n\
         # ({QUEUE_CAPACITY} segments), so streaming with flow control is exercised for real.\n\
         # Generated by hil-sim (testplan::spiral_job_toml); TRIQUINT_BLESS=1 rewrites it.\n\
         objective = \"min-max-jerk\"\n\n[limits]\nvelocity = 0.5\nacceleration = 1.2\njerk = 5.0\ntorque = 10.0\n",
    );
    o.push_str(&format!(
        "total_time = {SPIRAL_TIME:.1}\n\n[path]\nunits = \"mm\"\npoints = [\n"
    ));
    for p in spiral_points_mm(SPIRAL_POINTS, SPIRAL_TURNS) {
        o.push_str(&format!("  [{}, {}, {}],\n", p[0], p[1], p[2]));
    }
    o.push_str("]\n");
    o
}

/// The stress plan: a long spiral with equal intervals.
pub fn spiral(n: usize, turns: f64, total_time: f64) -> Result<Plan, KinematicsError> {
    let pts: Vec<[f64; 3]> = spiral_points_mm(n, turns).into_iter().map(mm).collect();
    // Slow in and out: longer first and last intervals so the rest-to-rest ends stay gentle.
    let mut h = vec![1.0; n - 1];
    h[0] = 3.0;
    h[n - 2] = 3.0;
    let sum: f64 = h.iter().sum();
    let h: Vec<f64> = h.iter().map(|x| x * total_time / sum).collect();
    let limits = Limits {
        total_time,
        ..Limits::default()
    };
    plan_through(&Robot::default(), &limits, &pts, &h)
}

/// The streaming fixtures (issue 35): a rest-to-rest move of `d` (m)
/// along x in `n` equal segments over `t` s, through the points of a
/// quintic smoothstep at the knots.
pub fn point_to_point(n: usize, t: f64, d: f64) -> Result<Plan, KinematicsError> {
    let pts: Vec<[f64; 3]> = (0..=n)
        .map(|i| {
            let u = i as f64 / n as f64;
            let s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
            [d * s, 0.0, 0.62]
        })
        .collect();
    let h = vec![t / n as f64; n];
    checked_plan_through(&Robot::default(), &Limits::default(), &pts, &h)
}

/// A 3-turn helix of radius 80 mm rising from 560 to 680 mm, rest to rest
/// (path parameter a smoothstep of time), in `n` segments over `t` s,
/// every tenth segment `short` s long (the others share the rest): with
/// `short` a stand-in for a shaped plan's millisecond segments.
pub fn helix(n: usize, t: f64, short: Option<f64>) -> Result<Plan, KinematicsError> {
    helix_turns(3.0, n, t, short)
}

/// [`helix`] of `turns` turns. A slow one passes `triquint check` with
/// 2 ms segments: their jerk at the ends is a sum of terms of size v/h²
/// (v the speed, h the duration), and the check holds its continuity to
/// 10⁻⁹ m/s³, near the rounding of those terms at 0.2 m/s.
pub fn helix_turns(
    turns: f64,
    n: usize,
    t: f64,
    short: Option<f64>,
) -> Result<Plan, KinematicsError> {
    let shorts = if short.is_some() { n / 10 } else { 0 };
    let s = short.unwrap_or(0.0);
    // Whole µs, as the plan holds them, so its total is the limit's.
    let long = ((t - s * shorts as f64) / (n - shorts) as f64 * 1e6).round() * 1e-6;
    let h: Vec<f64> = (0..n)
        .map(|i| {
            if short.is_some() && i % 10 == 9 {
                s
            } else {
                long
            }
        })
        .collect();
    let mut knot_t = vec![0.0];
    for x in &h {
        knot_t.push(knot_t.last().copied().unwrap_or(0.0) + x);
    }
    let pts: Vec<[f64; 3]> = knot_t
        .iter()
        .map(|&tk| {
            let v = (tk / knot_t[n]).clamp(0.0, 1.0);
            let u = v * v * v * (10.0 - 15.0 * v + 6.0 * v * v);
            let th = 2.0 * std::f64::consts::PI * turns * u;
            [0.08 * th.cos(), 0.08 * th.sin(), 0.56 + 0.12 * u]
        })
        .collect();
    let limits = Limits {
        total_time: knot_t[n],
        ..Limits::default()
    };
    checked_plan_through(&Robot::default(), &limits, &pts, &h)
}

/// Issue 35's fixtures as the VM suite runs them (hil-sim/python/
/// test_streaming.py, files written by the `streaming_fixtures` example),
/// by file stem: 15 segments in 0.9 s; a 2 ms segment every tenth (a slow
/// helix, [`helix_turns`]); 2 000 segments of 27 ms, near the shortest the
/// streaming rule allows at the default settings, so the emulated guest
/// runs it in 54 s.
pub fn streaming_fixtures() -> Result<Vec<(&'static str, Plan)>, KinematicsError> {
    Ok(vec![
        ("stream-15-segments", point_to_point(15, 0.9, 0.03)?),
        (
            "stream-2ms-every-tenth",
            helix_turns(1.0, 100, 12.0, Some(0.002))?,
        ),
        ("stream-2000-segments", helix(2000, 54.0, None)?),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Plans for `triquint simulate` without the planner, committed under
    /// testdata/protocol/plans/ (TRIQUINT_BLESS=1 rewrites them).
    #[test]
    fn committed_test_plans_are_current() {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata/protocol/plans");
        let job = dir.join("../../../examples/spiral.toml");
        if std::env::var_os("TRIQUINT_BLESS").is_some() {
            std::fs::write(&job, spiral_job_toml()).unwrap();
        } else {
            let committed = std::fs::read_to_string(&job).unwrap();
            assert!(
                committed == spiral_job_toml(),
                "examples/spiral.toml is stale"
            );
        }
        for (name, plan) in [
            ("case1-spline.json", paper_case1().unwrap()),
            ("case2-spline.json", paper_case2().unwrap()),
            (
                "spiral-spline.json",
                spiral(SPIRAL_POINTS, SPIRAL_TURNS, SPIRAL_TIME).unwrap(),
            ),
        ] {
            let text = serde_json::to_string_pretty(&plan).unwrap() + "\n";
            let path = dir.join(name);
            if std::env::var_os("TRIQUINT_BLESS").is_some() {
                std::fs::create_dir_all(&dir).unwrap();
                std::fs::write(&path, &text).unwrap();
            } else {
                let committed = std::fs::read_to_string(&path).unwrap();
                assert!(committed == text, "{name} is stale (TRIQUINT_BLESS=1)");
            }
        }
    }

    #[test]
    fn hermite_meets_its_end_conditions() {
        let c = hermite5(0.1, 0.2, -0.3, 0.25, -0.1, 0.4, 0.7);
        let k = [c[0], c[1], c[2], c[3], c[4], c[5]];
        let [p, v, a, _] = triquint_shared::quintic::eval_poly(&k, 0.7);
        assert!((p - 0.25).abs() < 1e-12 && (v + 0.1).abs() < 1e-12 && (a - 0.4).abs() < 1e-11);
    }

    #[test]
    fn paper_plans_are_c2_and_within_limits() {
        for plan in [paper_case1().unwrap(), paper_case2().unwrap()] {
            for w in plan.segments.windows(2) {
                let e = w[0].quintic().end();
                let s = w[1].quintic().eval(0.0);
                assert!((e.q - s.q).norm() < 1e-12);
                assert!((e.qd - s.qd).norm() < 1e-10);
                assert!((e.qdd - s.qdd).norm() < 1e-9);
                assert!((e.qddd - s.qddd).norm() < 1e-7, "jerk continuous");
            }
            for j in 0..3 {
                assert!(plan.max_abs.velocity[j] < plan.limits.velocity);
                assert!(
                    plan.max_abs.acceleration[j] < plan.limits.acceleration,
                    "{:?}",
                    plan.max_abs
                );
            }
            assert!((plan.total_time_s - plan.intervals_s.iter().sum::<f64>()).abs() < 1e-9);
        }
    }
}
