//! `triquint simulate --test-reference`: TEST REFERENCES, never a drive's
//! path. The plan, or a jerk-discontinuous 7-phase profile between its start
//! and end (which the drives refuse, rightly), run through the firmware's
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
use triquint_sim::test_reference::{self, SevenPhase};
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
    /// Holding the plan's start for as long as the plan: the noise floor.
    Still,
}

impl TestReference {
    pub fn name(self) -> &'static str {
        match self {
            Self::Plan => "plan",
            Self::SevenPhase => "seven-phase",
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
    let mut settings = opts.settings.clone();
    settings.control_rate = opts.rate_hz;
    settings.feedforward = opts.feedforward;
    let configs = DriveConfigs::for_plan(plan, &settings)?;
    let start = motion(plan, 0.0).q;
    let end = motion(plan, plan.total_time_s).q;
    let seven = SevenPhase::new(start, end, &plan.limits).ok_or_else(|| {
        SimulateError::Plan(
            "a 7-phase profile needs a move: the plan's start and end are the same (a closed path)"
                .into(),
        )
    })?;
    let (reference, duration): (Box<dyn Fn(f64) -> JointMotion<f64>>, f64) = match kind {
        TestReference::Plan => (Box::new(|t| motion(plan, t)), plan.total_time_s),
        TestReference::SevenPhase => (Box::new(|t| seven.at(t)), seven.duration()),
        TestReference::Still => (Box::new(|_| motion(plan, 0.0)), plan.total_time_s),
    };
    let plant = PlantModel::new(
        opts.plant,
        &plan.robot,
        opts.sim.plant.clone(),
        &opts.flex,
        start,
    )?;
    let run = test_reference::run(
        plant,
        &configs.nodes,
        &reference,
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

    /// The P2P move of docs/vibration.md on the flexible plant: at the
    /// lowest mode, the jerk-discontinuous 7-phase profile rings several
    /// times what the min-time and min-max-jerk plans of the same move leave,
    /// at the model's frequency, and the plans through the drives leave as
    /// little as through the law alone.
    #[test]
    fn a_seven_phase_profile_rings_where_the_plans_do_not() {
        let job = |objective, total| {
            Job::builder()
                .objective(objective)
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
}
