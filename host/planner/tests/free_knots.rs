//! Free knots on point-to-point moves: every plan passes `check`, takes no
//! longer than at fixed knots, and comes within a few per cent of the
//! time-optimal jerk-limited duration of the joint that moves farthest
//! (the bound no plan can beat, computed here in closed form).

use triquint_planner::files::parse_plan;
use triquint_planner::{Job, KnotPlacement, Limits, Objective, Options, PlanError, check, plan};
use triquint_shared::protocol::streaming::QUEUE_CAPACITY;

const LIMITS: Limits = Limits {
    velocity: 0.5,
    acceleration: 1.2,
    jerk: 5.0,
    torque: 1e3,
    total_time: 100.0,
};

/// Rest-to-rest time-optimal duration over `d` under per-joint v, a, j,
/// when v·j ≥ a² (acceleration can be reached before velocity).
fn double_s_time(d: f64, l: &Limits) -> f64 {
    let (v, a, j) = (l.velocity, l.acceleration, l.jerk);
    assert!(v * j >= a * a);
    if d < 2.0 * a.powi(3) / (j * j) {
        4.0 * (d / (2.0 * j)).cbrt()
    } else if d < v * (a / j + v / a) {
        let tj = a / j;
        2.0 * (0.5 * tj + (0.25 * tj * tj + d / a).sqrt())
    } else {
        d / v + a / j + v / a
    }
}

/// Seeded moves inside the paper's workspace (x, y ±100 mm, z 540–680 mm).
fn moves(n: usize) -> Vec<[[f64; 3]; 2]> {
    let mut state: u64 = 37;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut point = || {
        [
            -100.0 + 200.0 * next(),
            -100.0 + 200.0 * next(),
            540.0 + 140.0 * next(),
        ]
    };
    (0..n).map(|_| [point(), point()]).collect()
}

fn job(m: [[f64; 3]; 2], knots: KnotPlacement) -> Result<Job, PlanError> {
    Job::builder()
        .objective(Objective::MinTime)
        .limits(LIMITS)
        .knots(knots)
        .points_mm(m)
        .build()
}

#[test]
fn free_knots_come_within_four_per_cent_of_the_jerk_limited_optimum() {
    let mut planned = 0;
    for m in moves(20) {
        let Ok(free_job) = job(m, KnotPlacement::Free) else {
            continue;
        };
        let free = plan(&free_job, &Options::default()).unwrap();
        let fixed = plan(&job(m, KnotPlacement::Fixed).unwrap(), &Options::default()).unwrap();
        let rows = check(&free).unwrap();
        assert!(rows.iter().all(|r| r.ok), "{m:?}: {rows:?}");
        planned += 1;
        if free.free_knots.is_empty() {
            // Too many short segments to stream to the drives' queue: the
            // planner wrote the fixed knots' plan instead.
            assert_eq!(free.segments, fixed.segments, "{m:?}");
            assert!(free.segments.len() <= QUEUE_CAPACITY, "{m:?}");
            continue;
        }
        let (a, b) = (free.knots_m[0], free.knots_m[free.knots_m.len() - 1]);
        let d = (0..3).map(|j| (b[j] - a[j]).abs()).fold(0.0, f64::max);
        let optimum = double_s_time(d, &LIMITS);
        let t = free.total_time_s;
        assert!(t >= optimum * (1.0 - 1e-9), "{m:?}: {t} below {optimum}");
        assert!(t <= optimum * 1.04, "{m:?}: {t} against {optimum}");
        assert!(
            t <= fixed.total_time_s,
            "{m:?}: {t} against {}",
            fixed.total_time_s
        );
        // Every interior knot is free, recorded in format 4, and read back.
        assert_eq!(free.format, "triquint-plan/4");
        assert_eq!(
            free.free_knots,
            (1..free.knots_m.len() - 1).collect::<Vec<_>>()
        );
        assert!(fixed.free_knots.is_empty() && fixed.format == "triquint-plan/3");
        let back = parse_plan(&serde_json::to_string(&free).unwrap()).unwrap();
        assert_eq!(back, free);
    }
    assert!(planned >= 15, "only {planned} of 20 moves in the workspace");
}

/// When torque binds, the free shape is only time-scaled for it; the plan
/// is then the shorter of it and the fixed knots' (reshaped by the
/// search), so free knots are never worse, and every plan passes check.
#[test]
fn where_torque_binds_free_knots_are_never_worse_than_fixed() {
    let m = [[-90.0, 90.0, 680.0], [40.0, -60.0, 600.0]];
    // A queue that cannot take the free shape's segments whole makes it
    // unstreamable (docs/protocol.md, Streamability): the fixed knots then.
    let free_streams = QUEUE_CAPACITY >= 15;
    let mut chose = [false; 2];
    for torque in [0.25, 0.12] {
        let with = |knots| {
            let job = Job::builder()
                .objective(Objective::MinTime)
                .limits(Limits { torque, ..LIMITS })
                .knots(knots)
                .points_mm(m)
                .build()
                .unwrap();
            plan(&job, &Options::default()).unwrap()
        };
        let (free, fixed) = (with(KnotPlacement::Free), with(KnotPlacement::Fixed));
        assert!(check(&free).unwrap().iter().all(|r| r.ok));
        assert!(free.total_time_s <= fixed.total_time_s, "torque {torque}");
        // Torque binds: the plan reaches it on some joint (the fixed
        // knots' plan written in the free shape's place need not).
        let reached = free.max_abs.torque.iter().fold(0.0, |a: f64, &b| a.max(b));
        if free_streams || torque < 0.2 {
            assert!(reached > torque * 0.999, "torque {torque}: {reached}");
        }
        chose[usize::from(free.free_knots.is_empty())] = true;
    }
    // At 0.25 N·m the scaled free shape wins; at 0.12 the fixed knots do.
    assert_eq!(chose, [free_streams, true]);
}

#[test]
fn free_knots_need_a_point_to_point_min_time_job_or_min_max_jerk() {
    let m = [[0.0, 0.0, 600.0], [20.0, 0.0, 600.0]];
    assert!(job(m, KnotPlacement::Free).is_ok());
    // Min-max-jerk takes free knots, but no segment count.
    let mmj = Job::builder().knots(KnotPlacement::Free).points_mm(m);
    assert!(mmj.clone().build().is_ok());
    let e = mmj.knot_segments(7).build().unwrap_err();
    assert!(
        matches!(&e, PlanError::InvalidJob { field, .. } if field == "knots.segments"),
        "{e:?}"
    );
    let e = Job::builder()
        .objective(Objective::MinTime)
        .knots(KnotPlacement::Free)
        .points_mm([m[0], m[1], [20.0, 20.0, 600.0]])
        .build()
        .unwrap_err();
    assert!(e.to_string().contains("exactly 2 via-points"), "{e}");
    // The job file's key.
    let text = "objective = \"min-time\"\nknots = \"free\"\n[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [20, 0, 600]]\n";
    assert_eq!(
        Job::from_toml(text).unwrap().knot_placement(),
        KnotPlacement::Free
    );
    let e = Job::from_toml(&text.replace("\"free\"", "\"loose\"")).unwrap_err();
    assert!(
        matches!(&e, PlanError::InvalidJob { field, .. } if field == "knots"),
        "{e:?}"
    );
    assert!(e.to_string().contains("unknown variant `loose`"), "{e}");
}

#[test]
fn the_loader_takes_free_knots_only_in_format_4() {
    let m = [[0.0, 0.0, 600.0], [20.0, 0.0, 600.0]];
    let p = plan(&job(m, KnotPlacement::Free).unwrap(), &Options::default()).unwrap();
    let mut v: serde_json::Value = serde_json::to_value(&p).unwrap();
    let load = |v: &serde_json::Value| parse_plan(&v.to_string());
    assert!(load(&v).is_ok());
    v["format"] = "triquint-plan/3".into();
    assert!(
        load(&v)
            .unwrap_err()
            .to_string()
            .contains("has no free knots")
    );
    v["format"] = "triquint-plan/4".into();
    v["free_knots"] = serde_json::json!([]);
    assert!(
        load(&v)
            .unwrap_err()
            .to_string()
            .contains("needs free knots")
    );
    let last = p.knots_m.len() - 1;
    for bad in [
        serde_json::json!([0]),
        serde_json::json!([last]),
        serde_json::json!([2, 1]),
    ] {
        v["free_knots"] = bad.clone();
        assert!(load(&v).is_err(), "{bad}");
    }
}

/// The reported deviation from the straight segment: its bound holds at
/// ten times the sampling density (an independent evaluation through
/// `Plan::at` and the closed-form FK), and the sampled maximum is reached
/// there; fixed knots stay within a fraction of a millimetre, free ones
/// leave the line.
#[test]
fn the_path_deviation_bounds_a_denser_sampling() {
    use nalgebra::Vector3;
    use triquint_planner::stats::path_deviation;
    use triquint_shared::kinematics::platform_position;
    let model = triquint_planner::Robot::default().model::<f64>();
    for (i, m) in moves(6).into_iter().enumerate() {
        for knots in [KnotPlacement::Free, KnotPlacement::Fixed] {
            let Ok(j) = job(m, knots) else { continue };
            let p = plan(&j, &Options::default()).unwrap();
            let d = path_deviation(&p).unwrap();
            let (a, b) = (
                Vector3::from(p.via_points_m[0]),
                Vector3::from(p.via_points_m[1]),
            );
            let n = (p.total_time_s / (d.step_s / 10.0)).ceil() as usize;
            let mut dense: f64 = 0.0;
            for k in 0..=n {
                let q = p.at(p.total_time_s * k as f64 / n as f64).unwrap().q;
                let r = platform_position(&model, q).unwrap();
                let u = ((r - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                dense = dense.max((r - (a + (b - a) * u)).norm());
            }
            assert!(
                dense <= d.bound_m,
                "move {i} {knots:?}: {dense} over {}",
                d.bound_m
            );
            assert!(dense >= d.max_m * (1.0 - 1e-6), "move {i} {knots:?}");
            if knots == KnotPlacement::Fixed {
                assert!(d.bound_m < 0.5e-3, "move {i}: {}", d.bound_m);
            }
        }
    }
}

/// `knots = { placement = "free", segments = N }`: more segments than the
/// shape's halve its segments and change nothing of the motion; fewer are
/// planned by the min-time search at the shape's knots; every plan passes
/// `check` and has N segments.
#[test]
fn a_segment_count_is_met_or_refused_with_the_most_there_can_be() {
    let m = [[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]];
    let auto = plan(&job(m, KnotPlacement::Free).unwrap(), &Options::default()).unwrap();
    let natural = auto.segments.len();
    // Beyond a queue's worth, a sub-second move's segments do not stream:
    // the count asked for is refused, not silently changed.
    let queue = QUEUE_CAPACITY;
    let too_many = Job::builder()
        .objective(Objective::MinTime)
        .limits(LIMITS)
        .knots(KnotPlacement::Free)
        .knot_segments(4 * queue)
        .points_mm(m)
        .build()
        .unwrap();
    assert!(
        matches!(
            plan(&too_many, &Options::default()),
            Err(PlanError::Unstreamable { .. })
        ),
        "{} segments",
        4 * queue
    );
    for n in [4, natural - 2, natural, natural + 3, queue] {
        let j = Job::builder()
            .objective(Objective::MinTime)
            .limits(LIMITS)
            .knots(KnotPlacement::Free)
            .knot_segments(n)
            .points_mm(m)
            .build()
            .unwrap();
        let p = plan(&j, &Options::default()).unwrap();
        assert_eq!(p.segments.len(), n, "asked {n}");
        assert!(check(&p).unwrap().iter().all(|r| r.ok), "asked {n}");
        assert_eq!(p.free_knots, (1..n).collect::<Vec<_>>());
        if n >= natural {
            // The same motion, cut finer.
            assert_eq!(p.total_time_s, auto.total_time_s, "asked {n}");
            for t in [0.1, 0.37, 0.8].map(|f| f * p.total_time_s) {
                let (a, b) = (p.at(t).unwrap(), auto.at(t).unwrap());
                let gap = |x: [f64; 3], y: [f64; 3]| {
                    (0..3).map(|j| (x[j] - y[j]).abs()).fold(0.0, f64::max)
                };
                assert!(
                    gap(a.q, b.q) < 1e-9 && gap(a.v, b.v) < 1e-6,
                    "asked {n} at {t}"
                );
            }
        } else {
            // Never below the time-optimal jerk-limited duration.
            let (a, b) = (p.knots_m[0], p.knots_m[n]);
            let d = (0..3).map(|j| (b[j] - a[j]).abs()).fold(0.0, f64::max);
            let optimum = double_s_time(d, &LIMITS);
            assert!(p.total_time_s >= optimum * (1.0 - 1e-9), "asked {n}");
        }
    }
    // More than 5 ms segments allow: refused with the most there can be.
    let short = [[0.0, 0.0, 600.0], [2.0, 0.0, 600.0]];
    let e = plan(
        &job(short, KnotPlacement::Free)
            .unwrap()
            .to_builder()
            .knot_segments(64)
            .build()
            .unwrap(),
        &Options::default(),
    )
    .unwrap_err();
    assert!(
        matches!(&e, PlanError::InvalidJob { field, .. } if field == "knots.segments"),
        "{e:?}"
    );
    assert!(e.to_string().contains("at most"), "{e}");
}

#[test]
fn bad_segment_counts_and_knot_tables_are_refused_naming_the_key() {
    let file = |knots: &str| {
        format!(
            "objective = \"min-time\"\nknots = {knots}\n[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [20, 0, 600]]\n"
        )
    };
    let ok = Job::from_toml(&file("{ placement = \"free\", segments = 9 }")).unwrap();
    assert_eq!(
        (ok.knot_placement(), ok.knot_segments()),
        (KnotPlacement::Free, Some(9))
    );
    let auto = Job::from_toml(&file("{ placement = \"free\" }")).unwrap();
    assert_eq!(auto.knot_segments(), None);
    for (knots, field, says) in [
        (
            "{ placement = \"free\", segments = 2 }",
            "knots.segments",
            "outside 3..64",
        ),
        (
            "{ placement = \"free\", segments = 65 }",
            "knots.segments",
            "outside 3..64",
        ),
        (
            "{ placement = \"free\", segments = -1 }",
            "knots.segments",
            "not a count",
        ),
        (
            "{ placement = \"fixed\", segments = 7 }",
            "knots.segments",
            "placement = \"free\"",
        ),
        (
            "{ placement = \"free\", segment = 7 }",
            "knots",
            "unknown field `segment`",
        ),
        (
            "{ placement = \"free\", segments = \"7\" }",
            "knots",
            "expected i64",
        ),
        ("{ segments = 7 }", "knots", "placement"),
        ("7", "knots", "neither"),
    ] {
        let e = Job::from_toml(&file(knots)).unwrap_err();
        assert!(
            matches!(&e, PlanError::InvalidJob { field: f, .. } if f == field),
            "{knots}: {e:?}"
        );
        assert!(e.to_string().contains(says), "{knots}: {e}");
    }
}

/// `path.max_deviation_mm`: on the seeded moves, every free-knot plan
/// bounded to 0.5 mm passes `check` and the deviation's own check, its
/// certificate is above a sampling ten times denser, and it is no longer
/// than at fixed knots.
#[test]
fn a_deviation_bound_is_met_and_proved() {
    use nalgebra::Vector3;
    use triquint_planner::check_deviation;
    use triquint_shared::kinematics::platform_position;
    let model = triquint_planner::Robot::default().model::<f64>();
    let mut bent = 0;
    for (i, m) in moves(10).into_iter().enumerate() {
        let Ok(free) = job(m, KnotPlacement::Free) else {
            continue;
        };
        let unbounded = plan(&free, &Options::default()).unwrap();
        let j = free.to_builder().max_deviation_mm(0.5).build().unwrap();
        let p = plan(&j, &Options::default()).unwrap();
        assert!(check(&p).unwrap().iter().all(|r| r.ok), "move {i}");
        let row = check_deviation(&p, 0.5e-3).unwrap();
        assert!(row.ok && row.value <= 0.5e-3, "move {i}: {row:?}");
        let fixed = plan(&job(m, KnotPlacement::Fixed).unwrap(), &Options::default()).unwrap();
        assert!(
            p.total_time_s <= fixed.total_time_s,
            "move {i}: {} against {}",
            p.total_time_s,
            fixed.total_time_s
        );
        let (a, b) = (
            Vector3::from(p.via_points_m[0]),
            Vector3::from(p.via_points_m[1]),
        );
        let n = (p.total_time_s / 2e-5).ceil() as usize;
        let mut dense: f64 = 0.0;
        for k in 0..=n {
            let q = p.at(p.total_time_s * k as f64 / n as f64).unwrap().q;
            let r = platform_position(&model, q).unwrap();
            let u = ((r - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
            dense = dense.max((r - (a + (b - a) * u)).norm());
        }
        assert!(dense <= row.value, "move {i}: {dense} over {}", row.value);
        if !check_deviation(&unbounded, 0.5e-3).unwrap().ok {
            bent += 1;
        }
    }
    assert!(bent >= 3, "only {bent} moves needed the bound");
}

/// A bound no plan meets is refused with the closest plan's figures.
#[test]
fn an_unmeetable_deviation_bound_says_how_close_the_plan_came() {
    let m = [[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]];
    for knots in [KnotPlacement::Free, KnotPlacement::Fixed] {
        let j = job(m, knots)
            .unwrap()
            .to_builder()
            .max_deviation_mm(1e-3)
            .build()
            .unwrap();
        match plan(&j, &Options::default()) {
            Err(PlanError::Deviation {
                limit_m,
                bound_m,
                reached_m,
                ..
            }) => {
                assert_eq!(limit_m, 1e-6);
                assert!(
                    bound_m > limit_m && bound_m >= reached_m,
                    "{bound_m} {reached_m}"
                );
            }
            other => panic!("{knots:?}: {other:?}"),
        }
    }
    let e = Job::from_toml(
        "[path]\nunits = \"mm\"\nmax_deviation_mm = -1\npoints = [[0, 0, 600], [20, 0, 600]]\n",
    )
    .unwrap_err();
    assert!(
        matches!(&e, PlanError::InvalidJob { field, .. } if field == "path.max_deviation_mm"),
        "{e:?}"
    );
}

/// A bounded job's plan records its bound (format 6), which `check` proves
/// without being told; a tampered bound fails the check (below the
/// certificate) or is refused by the loader (out of range, in another
/// format, missing).
#[test]
fn a_recorded_deviation_bound_is_proved_and_tampering_is_caught() {
    let m = [[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]];
    let j = job(m, KnotPlacement::Free)
        .unwrap()
        .to_builder()
        .max_deviation_mm(0.5)
        .build()
        .unwrap();
    let p = plan(&j, &Options::default()).unwrap();
    assert_eq!(p.format, "triquint-plan/6");
    assert_eq!(p.max_deviation_m, Some(0.5e-3));
    let rows = check(&p).unwrap();
    let row = |rows: &[triquint_planner::CheckRow]| {
        rows.iter()
            .find(|r| r.what.starts_with("path deviation"))
            .cloned()
            .expect("a deviation row")
    };
    let proved = row(&rows);
    assert!(
        rows.iter().all(|r| r.ok) && proved.bound == 0.5e-3,
        "{proved:?}"
    );
    let stats = triquint_planner::stats::plan_stats(&p).unwrap();
    assert_eq!(stats.path_deviation.limit_m, Some(0.5e-3));
    assert!(stats.path_deviation.bound_m <= 0.5e-3);

    let mut v: serde_json::Value = serde_json::to_value(&p).unwrap();
    let load = |v: &serde_json::Value| parse_plan(&v.to_string());
    assert_eq!(load(&v).unwrap(), p);
    // A bound below what the path certifies loads, and fails its row.
    let tight = proved.value * 0.5;
    v["max_deviation_m"] = tight.into();
    let tampered = load(&v).unwrap();
    let r = row(&check(&tampered).unwrap());
    assert!(!r.ok && r.bound == tight, "{r:?}");
    for (bad, says) in [
        (serde_json::json!(0.0), "not in"),
        (serde_json::json!(-1e-3), "not in"),
        (serde_json::json!(2.0), "not in"),
        (serde_json::Value::Null, "records its `max_deviation_m`"),
    ] {
        v["max_deviation_m"] = bad.clone();
        let e = load(&v).unwrap_err().to_string();
        assert!(e.contains(says), "{bad}: {e}");
    }
    v.as_object_mut().unwrap().remove("max_deviation_m");
    assert!(
        load(&v)
            .unwrap_err()
            .to_string()
            .contains("max_deviation_m")
    );
    // A bound in an earlier format is refused, not ignored.
    v["max_deviation_m"] = 0.5e-3.into();
    let knots_format = if p.free_knots.is_empty() {
        "triquint-plan/3"
    } else {
        "triquint-plan/4"
    };
    v["format"] = knots_format.into();
    let e = load(&v).unwrap_err().to_string();
    assert!(e.contains("has no `max_deviation_m`"), "{e}");
    // An unbounded job's plan records none.
    let free = plan(&job(m, KnotPlacement::Free).unwrap(), &Options::default()).unwrap();
    assert_eq!(free.max_deviation_m, None);
    assert!(
        check(&free)
            .unwrap()
            .iter()
            .all(|r| !r.what.starts_with("path deviation"))
    );
}
