//! `triquint simulate --test-reference`: TEST REFERENCES, never a drive's
//! path. The plan, or a jerk-discontinuous 7-phase profile between its start
//! and end or along its path (which the drives refuse, rightly), run through the firmware's
//! control law on the plant below the drives' segment checks
//! (`triquint_sim::test_reference`), with the drives' configuration for the
//! plan; on the flexible plant, the residual vibration after it.

use serde::Serialize;
use triquint_link::DriveConfigs;
use triquint_shared::plan::Plan;
use triquint_shared::quintic::JointMotion;
use triquint_sim::flex::AccelSample;
use triquint_sim::plant_model::PlantModel;
use triquint_sim::sim::SimError;
use triquint_sim::test_reference::{self, Retiming, SevenPhase};
use triquint_sim::vibration::{Residual, SETTLE_WINDOW_S};

use super::simulate::{SimulateError, SimulateOptions};

/// The test reference to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum TestReference {
    /// The plan itself.
    Plan,
    /// A 7-phase jerk-limited profile from the plan's start to its end along
    /// the straight joint-space line, within the plan's limits.
    SevenPhase,
    /// The plan's own path with its time driven by a 7-phase jerk-limited
    /// profile from rest to rest over the plan's duration: a 7-phase
    /// profile of a move that is not a straight line (a closed path).
    SevenPhasePath,
    /// Holding the plan's start for as long as the plan: the noise floor.
    Still,
}

impl TestReference {
    pub fn name(self) -> &'static str {
        match self {
            Self::Plan => "plan",
            Self::SevenPhase => "seven-phase",
            Self::SevenPhasePath => "seven-phase-path",
            Self::Still => "still",
        }
    }
}

/// Holding the start before the reference (s): the release from the brakes
/// rings the flexible machine, and this lets it die away.
const HOLD_S: f64 = 1.0;

/// What a test-reference run measured.
#[derive(Clone, Debug, Serialize)]
pub struct TestRun {
    pub test_reference: TestReference,
    pub duration_s: f64,
    /// Largest |reference − encoder| of any axis (m).
    pub max_error_m: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vibration: Option<Residual>,
    /// Plant time of the reference's start (s).
    #[serde(skip)]
    pub start_s: f64,
    #[serde(skip)]
    pub accel: Vec<AccelSample>,
}

fn motion(plan: &Plan, t: f64) -> JointMotion<f64> {
    let s = plan.at(t.clamp(0.0, plan.total_time_s)).unwrap_or_default();
    JointMotion {
        q: s.q.into(),
        qd: s.v.into(),
        qdd: s.a.into(),
        qddd: s.jerk.into(),
    }
}

/// Runs `kind` for `plan` with `opts`' plant, rate and feedforward.
pub fn run(
    plan: &Plan,
    opts: &SimulateOptions,
    kind: TestReference,
) -> Result<TestRun, SimulateError> {
    let start = motion(plan, 0.0).q;
    let end = motion(plan, plan.total_time_s).q;
    match kind {
        TestReference::Plan => {
            run_motion(plan, opts, kind, &|t| motion(plan, t), plan.total_time_s)
        }
        TestReference::SevenPhase => {
            let seven =
                SevenPhase::new(start, end, &plan.limits).ok_or(SimulateError::ClosedPath)?;
            run_motion(plan, opts, kind, &|t| seven.at(t), seven.duration())
        }
        TestReference::SevenPhasePath => {
            let retiming = Retiming::new(plan.total_time_s).ok_or(SimulateError::NoEnd)?;
            let path = |tau| motion(plan, tau);
            run_motion(
                plan,
                opts,
                kind,
                &|t| retiming.at(&path, t),
                retiming.duration(),
            )
        }
        TestReference::Still => {
            run_motion(plan, opts, kind, &|_| motion(plan, 0.0), plan.total_time_s)
        }
    }
}

/// Runs `reference` (`duration_s` long, labelled `kind`) with the drives'
/// configuration for `plan` and `opts`' plant, rate and feedforward.
pub fn run_motion(
    plan: &Plan,
    opts: &SimulateOptions,
    kind: TestReference,
    reference: &dyn Fn(f64) -> JointMotion<f64>,
    duration: f64,
) -> Result<TestRun, SimulateError> {
    let mut settings = opts.settings.clone();
    settings.control_rate = opts.rate_hz;
    settings.feedforward = opts.feedforward;
    let configs = DriveConfigs::for_plan(plan, &settings)?;
    let plant = PlantModel::new(
        opts.plant,
        &plan.robot,
        opts.sim.plant.clone(),
        &opts.flex,
        reference(0.0).q,
    )?;
    let run = test_reference::run(
        plant,
        &configs.nodes,
        reference,
        duration,
        HOLD_S,
        SETTLE_WINDOW_S,
    )
    .map_err(|source| SimError::Plant { t_s: 0.0, source })?;
    let (vibration, accel) = match run.plant.flexible() {
        Some(flex) => (
            flex.residual(run.end_s, SETTLE_WINDOW_S, reference(duration).q)
                .map_err(|source| SimError::Plant {
                    t_s: run.end_s,
                    source,
                })?,
            flex.accel.clone(),
        ),
        None => (None, Vec::new()),
    };
    Ok(TestRun {
        test_reference: kind,
        duration_s: duration,
        max_error_m: run.max_error_m,
        vibration,
        start_s: run.start_s,
        accel,
    })
}

#[cfg(test)]
mod tests {
    use triquint_planner::{Job, Objective, Options, plan};
    use triquint_sim::plant_model::PlantKind;

    use super::*;
    use crate::inprocess::simulate::simulate;
    use triquint_shared::Limits;

    /// Velocity, acceleration and jerk limits fast enough to ring the
    /// flexible plant, torque unbounded in effect (docs/vibration.md).
    fn fast_limits([velocity, acceleration, jerk]: [f64; 3]) -> Limits {
        Limits {
            velocity,
            acceleration,
            jerk,
            torque: 1000.0,
            total_time: 5.0,
        }
    }

    /// The residual at the lowest mode (m/s²) of `p` run with `kind` as the
    /// reference on the flexible plant.
    fn at_mode(p: &Plan, kind: TestReference) -> f64 {
        let opts = SimulateOptions {
            plant: PlantKind::Flexible,
            ..SimulateOptions::default()
        };
        let r = run(p, &opts, kind).unwrap();
        r.vibration.unwrap().lowest_mode_m_s2.unwrap()
    }

    /// A closed path has no move for a 7-phase profile: a typed refusal.
    #[test]
    fn a_seven_phase_profile_of_a_closed_path_is_refused() {
        let job = Job::builder()
            .total_time(4.0)
            .points_mm([
                [-60.0, 40.0, 560.0],
                [60.0, -40.0, 640.0],
                [-60.0, 40.0, 560.0],
            ])
            .build()
            .unwrap();
        let closed = plan(&job, &Options::default()).unwrap();
        let e = run(
            &closed,
            &SimulateOptions::default(),
            TestReference::SevenPhase,
        )
        .unwrap_err();
        assert!(matches!(e, SimulateError::ClosedPath), "{e}");
    }

    /// Case II's circle at limits near the machine's (docs/vibration.md),
    /// min-time: the 7-phase retiming of its own path (`seven-phase-path`)
    /// starts and ends where the plan does, at rest, in the plan's time; it is
    /// continuous in q, q̇ and q̈ (each changing no faster than the next
    /// says), its jerk steps where the path moves, by at most the velocity
    /// limit times the retiming's jerk; and it rings the lowest mode more
    /// than the plan shaped by ZVD at the mode.
    #[test]
    fn a_seven_phase_retiming_of_case_two_rings_above_the_shaped_plan() {
        use triquint_planner::shaping::{Shaper, ShaperSpec, shape};

        let limits = fast_limits([2.0, 30.0, 5000.0]);
        let job = Job::builder()
            .objective(Objective::MinTime)
            .limits(limits.clone())
            .points_mm(triquint_sim::testplan::PAPER_CASE2_MM.to_vec())
            .build()
            .unwrap();
        let p = plan(&job, &Options::default()).unwrap();
        let t_end = p.total_time_s;
        let retiming = Retiming::new(t_end).unwrap();
        let path = |tau| motion(&p, tau);
        let reference = |t| retiming.at(&path, t);
        let (start, end) = (reference(0.0), reference(t_end));
        assert!((start.q - motion(&p, 0.0).q).amax() < 1e-12);
        assert!((end.q - motion(&p, t_end).q).amax() < 1e-12);
        assert!(end.qd.amax() < 1e-9 && end.qdd.amax() < 1e-6);

        // Every phase boundary (multiples of T/12) on the grid.
        let (n, h) = (4800, 1e-6);
        let j_tau = 96.0 / (t_end * t_end);
        let (mut steps, mut largest_step, mut v_max, mut a_max) = (0, 0.0_f64, 0.0_f64, 0.0_f64);
        for k in 1..n {
            let t = t_end * k as f64 / n as f64;
            let (b, m, f) = (reference(t - h), reference(t), reference(t + h));
            let faster = |x: f64, y: f64| 2.0 * h * x.max(y) * 1.01 + 1e-12;
            assert!(
                (f.q - b.q).amax() <= faster(f.qd.amax(), b.qd.amax()),
                "q at {t}"
            );
            assert!(
                (f.qd - b.qd).amax() <= faster(f.qdd.amax(), b.qdd.amax()),
                "q̇ at {t}"
            );
            assert!(
                (f.qdd - b.qdd).amax() <= faster(f.qddd.amax(), b.qddd.amax()),
                "q̈ at {t}"
            );
            let step = (f.qddd - b.qddd).amax();
            if step > 0.02 * limits.velocity * j_tau {
                steps += 1;
                largest_step = largest_step.max(step);
            }
            v_max = v_max.max(m.qd.amax());
            a_max = a_max.max(m.qdd.amax());
        }
        eprintln!(
            "seven-phase-path: {steps} jerk steps, largest {largest_step:.1} m/s³, |q̇| {:.3} of the limit, |q̈| {:.3}",
            v_max / limits.velocity,
            a_max / limits.acceleration
        );
        assert!(steps >= 4, "{steps}");
        assert!(
            largest_step <= 1.01 * limits.velocity * j_tau,
            "{largest_step}"
        );
        // The same time with a slower start and end: τ̇ peaks at 4/3.
        assert!(
            v_max <= 4.0 / 3.0 * limits.velocity * (1.0 + 1e-6),
            "{v_max}"
        );

        let unshaped = at_mode(&p, TestReference::Plan);
        let seven = at_mode(&p, TestReference::SevenPhasePath);
        let zvd = shape(
            &p,
            &ShaperSpec {
                shaper: Shaper::Zvd,
                frequency_hz: 25.6,
                damping: 0.062,
            },
        )
        .unwrap();
        let shaped = at_mode(&zvd, TestReference::Plan);
        eprintln!(
            "at the lowest mode: seven-phase-path {seven:.4}, ZVD {shaped:.4}, unshaped {unshaped:.4} m/s²"
        );
        assert!(seven > 3.0 * shaped, "{seven} vs ZVD {shaped}");
        // And more than the jerk-continuous plan it retimes.
        assert!(seven > 3.0 * unshaped, "{seven} vs the plan's {unshaped}");
    }

    /// The P2P move of docs/vibration.md on the flexible plant: at the
    /// lowest mode, the jerk-discontinuous 7-phase profile rings several
    /// times what the min-time and min-max-jerk plans of the same move leave,
    /// at the model's frequency, and the plans through the drives leave as
    /// little as through the law alone.
    #[test]
    fn a_seven_phase_profile_rings_where_the_plans_do_not() {
        // The plans at the fixed knots: the shape that the seven-phase
        // profile is compared with.
        let job = |objective, total| {
            Job::builder()
                .objective(objective)
                .knots(triquint_planner::KnotPlacement::Fixed)
                .total_time(total)
                .points_mm([[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]])
                .build()
                .unwrap()
        };
        let min_time = plan(&job(Objective::MinTime, 5.0), &Options::default()).unwrap();
        let smooth = plan(&job(Objective::MinMaxJerk, 1.5), &Options::default()).unwrap();
        let opts = SimulateOptions {
            plant: PlantKind::Flexible,
            ..SimulateOptions::default()
        };
        let at_mode = |r: &TestRun| r.vibration.as_ref().unwrap().lowest_mode_m_s2.unwrap();
        let seven = run(&min_time, &opts, TestReference::SevenPhase).unwrap();
        let floor = run(&min_time, &opts, TestReference::Still).unwrap();
        let v7 = seven.vibration.as_ref().unwrap();
        for p in [&min_time, &smooth] {
            let law = run(p, &opts, TestReference::Plan).unwrap();
            assert!(
                at_mode(&seven) > 3.0 * at_mode(&law),
                "{seven:?} vs {law:?}"
            );
            assert!(v7.peak_position_m > 2.0 * law.vibration.as_ref().unwrap().peak_position_m);
            let drives = simulate(p, &opts).unwrap();
            assert!(drives.run.completed);
            let dv = drives.run.vibration.unwrap();
            assert!(
                at_mode(&seven) > 3.0 * dv.lowest_mode_m_s2.unwrap(),
                "{dv:?}"
            );
        }
        assert!(at_mode(&seven) > 10.0 * at_mode(&floor), "{floor:?}");
        let (hz, mode) = (v7.dominant_hz.unwrap(), v7.lowest_mode_hz.unwrap());
        assert!(
            (hz - mode).abs() < 0.05 * mode,
            "{hz} Hz vs the model's {mode} Hz"
        );
    }

    /// Input shaping on the flexible plant: the jerk-discontinuous 7-phase
    /// profile of the P2P move convolved with ZVD and EI impulses at the
    /// machine's lowest mode (and EI 20 % off it) rings that mode 3–4× less;
    /// and the min-time plan shaped by the planner (`shaping::shape`) is a
    /// C3 plan that `check` proves. (`shape` alone does not keep the
    /// streaming rule; the planner's shaped plans, which do, run through
    /// the drives below.)
    #[test]
    fn shaping_removes_the_ringing_of_the_jerk_steps() {
        use triquint_planner::shaping::{Impulses, Shaper, ShaperSpec, shape};
        use triquint_sim::flex::FlexPlant;
        use triquint_sim::plant::PlantConfig;

        let job = Job::builder()
            .objective(Objective::MinTime)
            .points_mm([[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]])
            .build()
            .unwrap();
        let p = plan(&job, &Options::default()).unwrap();
        let opts = SimulateOptions {
            plant: PlantKind::Flexible,
            ..SimulateOptions::default()
        };
        let end = motion(&p, p.total_time_s).q;
        let start = motion(&p, 0.0).q;
        let flex =
            FlexPlant::new(&p.robot, PlantConfig::default(), opts.flex.clone(), end).unwrap();
        let mode = flex.modes(flex.platform()).unwrap()[0];
        let seven = SevenPhase::new(start, end, &p.limits).unwrap();
        let at_mode = |r: &TestRun| r.vibration.as_ref().unwrap().lowest_mode_m_s2.unwrap();
        let unshaped = run(&p, &opts, TestReference::SevenPhase).unwrap();
        let mut shaped = Vec::new();
        for (shaper, hz) in [
            (Shaper::Zvd, mode.hz),
            (Shaper::Ei, mode.hz),
            (Shaper::Ei, 1.2 * mode.hz),
            (Shaper::Ei, 0.8 * mode.hz),
        ] {
            let imp = Impulses::new(shaper, hz, mode.damping).unwrap();
            let reference = |t: f64| {
                let mut m = JointMotion::<f64>::default();
                for (d, a) in imp.times_s.iter().zip(&imp.amplitudes) {
                    let c = seven.at(t - d);
                    m.q += c.q * *a;
                    m.qd += c.qd * *a;
                    m.qdd += c.qdd * *a;
                    m.qddd += c.qddd * *a;
                }
                m
            };
            let d = seven.duration() + imp.duration_s();
            let r = run_motion(&p, &opts, TestReference::SevenPhase, &reference, d).unwrap();
            eprintln!(
                "{shaper:?} at {hz:.2} Hz: {} vs {}",
                at_mode(&r),
                at_mode(&unshaped)
            );
            shaped.push(at_mode(&r));
        }
        let u = at_mode(&unshaped);
        // Down to what the smooth plans leave after a move (0.3–0.8 mm/s²:
        // the servo settling against the friction it mis-identifies), not
        // to the 6 % of holding still.
        assert!(
            shaped[0] < 0.35 * u && shaped[1] < 0.35 * u,
            "{shaped:?} vs {u}"
        );
        assert!(
            shaped[2] < 0.5 * u && shaped[3] < 0.5 * u,
            "{shaped:?} vs {u}"
        );

        // The planner's shaping of the plan itself: C3, checked, run by the drives.
        let s = shape(
            &p,
            &ShaperSpec {
                shaper: Shaper::Zvd,
                frequency_hz: mode.hz,
                damping: mode.damping,
            },
        )
        .unwrap();
        assert!(triquint_planner::check(&s).unwrap().iter().all(|r| r.ok));
        // Through the law it leaves no more than the floor after a move.
        let law = run(&s, &opts, TestReference::Plan).unwrap();
        assert!(at_mode(&law) < 0.35 * u, "{law:?}");
    }

    /// docs/vibration.md's residual-vibration targets, on moves at limits
    /// near the machine's ceilings whose unshaped residual stands far above
    /// the floor: the P2P move and Case II's circle, min-time, shaped as
    /// `triquint resonance` suggests measuring (25.6 Hz, damping 0.062).
    /// At the mode, ZVD and EI leave ≤ 5 % of the unshaped min-time plan's
    /// residual at the lowest mode; with the shaper 20 % off, EI or
    /// 2HUMP-EI leaves ≤ 10 %.
    #[test]
    fn shaped_at_the_mode_the_residual_meets_the_targets() {
        use triquint_planner::shaping::{Shaper, ShaperSpec, shape};

        let case2 = triquint_sim::testplan::PAPER_CASE2_MM.to_vec();
        for (points, [v, a, j]) in [
            (
                vec![[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]],
                [1.0, 10.0, 500.0],
            ),
            (case2, [2.0, 30.0, 5000.0]),
        ] {
            let job = Job::builder()
                .objective(Objective::MinTime)
                .limits(fast_limits([v, a, j]))
                .points_mm(points)
                .build()
                .unwrap();
            let p = plan(&job, &Options::default()).unwrap();
            let unshaped = at_mode(&p, TestReference::Plan);
            let floor = at_mode(&p, TestReference::Still);
            // Far above the floor (it adds under 0.5 % to any ratio below),
            // so that the ratios mean something.
            assert!(unshaped > 200.0 * floor, "{unshaped} vs floor {floor}");
            let shaped = |shaper, frequency_hz| {
                let s = shape(
                    &p,
                    &ShaperSpec {
                        shaper,
                        frequency_hz,
                        damping: 0.062,
                    },
                )
                .unwrap();
                at_mode(&s, TestReference::Plan) / unshaped
            };
            // ZVD cancels the mode; EI is built to leave up to 5 % at its
            // design frequency in exchange for its width, so it is held to
            // the 20 %-off target below and only reported here.
            let zvd = shaped(Shaper::Zvd, 25.6);
            let ei = shaped(Shaper::Ei, 25.6);
            eprintln!(
                "at the mode: ZVD {zvd:.4}, EI {ei:.4} of {unshaped:.4} m/s², floor {floor:.6}"
            );
            assert!(zvd <= 0.05, "ZVD at the mode: {zvd}");
            for hz in [0.8 * 25.6, 1.2 * 25.6] {
                let (ei, hump) = (shaped(Shaper::Ei, hz), shaped(Shaper::TwoHumpEi, hz));
                eprintln!("at {hz:.1} Hz: EI {ei:.4}, 2HUMP-EI {hump:.4}");
                let best = ei.min(hump);
                assert!(best <= 0.10, "EI / 2HUMP-EI at {hz} Hz: {best}");
            }
        }
    }

    /// The targets through the drives: the planner's shaped plans keep the
    /// streaming rule and run on the three simulated drives (bus, clocks,
    /// firmware) on the flexible plant. At the mode ZVD leaves ≤ 5 % of the
    /// unshaped min-time plan's residual at the lowest mode; 20 % off, the
    /// better of EI and 2HUMP-EI ≤ 10 % (on Case II 2HUMP-EI streams only
    /// with the plan slowed, which the planner does and records).
    #[test]
    fn shaped_plans_run_through_the_drives_and_meet_the_targets() {
        use triquint_planner::PlanError;
        use triquint_planner::shaping::{Shaper, ShaperSpec};

        let opts = SimulateOptions {
            plant: PlantKind::Flexible,
            ..SimulateOptions::default()
        };
        let at_mode = |p: &Plan| {
            let r = simulate(p, &opts).unwrap().run;
            assert!(r.completed, "{:?}", r.faults);
            r.vibration.unwrap().lowest_mode_m_s2.unwrap()
        };
        let case2 = triquint_sim::testplan::PAPER_CASE2_MM.to_vec();
        for (points, [v, a, j]) in [
            (
                vec![[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]],
                [1.0, 10.0, 500.0],
            ),
            (case2, [2.0, 30.0, 5000.0]),
        ] {
            let job = |shaper: Option<(Shaper, f64)>| {
                Job::builder()
                    .objective(Objective::MinTime)
                    .limits(fast_limits([v, a, j]))
                    .points_mm(points.clone())
                    .shaper(shaper.map(|(shaper, frequency_hz)| ShaperSpec {
                        shaper,
                        frequency_hz,
                        damping: 0.062,
                    }))
                    .build()
                    .unwrap()
            };
            let unshaped = at_mode(&plan(&job(None), &Options::default()).unwrap());
            let shaped = |shaper, hz| match plan(&job(Some((shaper, hz))), &Options::default()) {
                Ok(p) => {
                    let retimed = p.shaping.as_ref().and_then(|s| s.unshaped.retimed);
                    eprintln!("{shaper} at {hz:.2} Hz: slowed {retimed:?}");
                    Some(at_mode(&p) / unshaped)
                }
                Err(PlanError::Unstreamable {
                    shaper: Some(_), ..
                }) => None,
                Err(e) => panic!("{shaper} at {hz} Hz: {e}"),
            };
            let zvd = shaped(Shaper::Zvd, 25.6).unwrap();
            eprintln!("drives, at the mode: ZVD {zvd:.4} of {unshaped:.4} m/s²");
            assert!(zvd <= 0.05, "ZVD at the mode: {zvd}");
            for hz in [0.8 * 25.6, 1.2 * 25.6] {
                let (ei, hump) = (shaped(Shaper::Ei, hz), shaped(Shaper::TwoHumpEi, hz));
                eprintln!("drives, at {hz:.1} Hz: EI {ei:?}, 2HUMP-EI {hump:?}");
                let best = [ei, hump]
                    .into_iter()
                    .flatten()
                    .fold(f64::INFINITY, f64::min);
                assert!(best <= 0.10, "EI / 2HUMP-EI at {hz} Hz: {best}");
            }
        }
    }
}
