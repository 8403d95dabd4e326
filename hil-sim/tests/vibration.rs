//! Residual vibration on the flexible plant, through the firmware's control
//! law (test references, below the drives' segment checks): a
//! jerk-discontinuous 7-phase profile rings the machine more than a
//! jerk-continuous move of the same length, the ringing is at a mode of the
//! linearised model, and both stand above the noise floor of holding still.

use nalgebra::Vector3;
use triquint_link::DriveConfigs;
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::quintic::JointMotion;
use triquint_shared::{Limits, Robot};
use triquint_sim::flex::FlexParams;
use triquint_sim::plant::PlantConfig;
use triquint_sim::plant_model::{PlantKind, PlantModel};
use triquint_sim::test_reference::{self, SevenPhase};
use triquint_sim::vibration::{Residual, SETTLE_WINDOW_S};

/// A C3 rest-to-rest move along the same line: s(τ) = 35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷.
fn septic(q0: Vector3<f64>, q1: Vector3<f64>, t_total: f64) -> impl Fn(f64) -> JointMotion<f64> {
    move |t: f64| {
        let u = (t / t_total).clamp(0.0, 1.0);
        let s = u.powi(4) * (35.0 - 84.0 * u + 70.0 * u * u - 20.0 * u.powi(3));
        let v = u.powi(3) * (140.0 - 420.0 * u + 420.0 * u * u - 140.0 * u.powi(3)) / t_total;
        let a = u * u * (420.0 - 1680.0 * u + 2100.0 * u * u - 840.0 * u.powi(3)) / t_total.powi(2);
        let j = u * (840.0 - 5040.0 * u + 8400.0 * u * u - 4200.0 * u.powi(3)) / t_total.powi(3);
        let d = q1 - q0;
        JointMotion {
            q: q0 + d * s,
            qd: d * v,
            qdd: d * a,
            qddd: d * j,
        }
    }
}

struct Case {
    q0: Vector3<f64>,
    q1: Vector3<f64>,
    limits: Limits,
    configs: DriveConfigs,
    robot: Robot,
}

fn case() -> Case {
    let robot = Robot::default();
    let m = robot.model::<f64>();
    let ik = |r: [f64; 3]| Pose::from_cartesian(&m, Vector3::from(r)).unwrap().q;
    let limits = Limits::default();
    Case {
        q0: ik([-0.06, 0.04, 0.56]),
        q1: ik([0.06, -0.04, 0.64]),
        configs: DriveConfigs::for_limits(&robot, &limits, &DriveSettings::default()),
        limits,
        robot,
    }
}

/// The residual of a move, and its amplitude at the machine's lowest mode.
fn residual_of(
    c: &Case,
    reference: &dyn Fn(f64) -> JointMotion<f64>,
    duration: f64,
) -> (Residual, f64) {
    let plant = PlantModel::new(
        PlantKind::Flexible,
        &c.robot,
        PlantConfig::default(),
        &FlexParams::default(),
        reference(0.0).q,
    )
    .unwrap();
    let run = test_reference::run(
        plant,
        &c.configs.nodes,
        reference,
        duration,
        1.0,
        SETTLE_WINDOW_S,
    )
    .unwrap();
    let flex = run.plant.flexible().unwrap();
    let r = flex
        .residual(run.end_s, SETTLE_WINDOW_S, reference(duration).q)
        .unwrap()
        .unwrap();
    let at_mode = r.lowest_mode_m_s2.unwrap();
    (r, at_mode)
}

#[test]
fn a_jerk_step_rings_the_flexible_machine_more_than_a_smooth_move() {
    let c = case();
    let seven = SevenPhase::new(c.q0, c.q1, &c.limits).unwrap();
    let t7 = seven.duration();
    let (r7, m7) = residual_of(&c, &|t| seven.at(t), t7);
    // A second first: the release from the brakes rings for a while.
    // The C3 move of the same length (its peaks are above the limits: only
    // the shape differs).
    let smooth = septic(c.q0, c.q1, t7);
    let (rs, ms) = residual_of(&c, &smooth, t7);
    let q0 = c.q0;
    let (floor, mf) = residual_of(
        &c,
        &move |_| JointMotion {
            q: q0,
            ..JointMotion::default()
        },
        t7,
    );
    eprintln!("7-phase {r7:?} {m7}\nC3 {rs:?} {ms}\nfloor {floor:?} {mf}");
    // Over all frequencies the encoder's quantisation, through the
    // derivative term, keeps the slider modes ringing at rest: the floor.
    assert!(
        r7.rms_accel_m_s2 > 1.3 * rs.rms_accel_m_s2,
        "{r7:?} vs {rs:?}"
    );
    assert!(
        r7.rms_accel_m_s2 > 1.3 * floor.rms_accel_m_s2,
        "{r7:?} vs {floor:?}"
    );
    assert!(r7.peak_position_m > rs.peak_position_m, "{r7:?} vs {rs:?}");
    // At the lowest (platform) mode the jerk steps stand far out.
    assert!(m7 > 2.5 * ms && m7 > 10.0 * mf, "{m7} vs {ms}, floor {mf}");

    // The ringing is at a mode of the linearised machine at the end pose.
    let plant = FlexParams::default();
    let m = c.robot.model::<f64>();
    let end = Pose::from_joints(&m, c.q1).unwrap().r;
    let model = PlantModel::new(
        PlantKind::Flexible,
        &c.robot,
        PlantConfig::default(),
        &plant,
        c.q1,
    )
    .unwrap();
    let modes = model.flexible().unwrap().modes(end).unwrap();
    let hz = r7.dominant_hz.unwrap();
    let nearest = modes
        .iter()
        .map(|m| (m.hz - hz).abs() / m.hz)
        .fold(f64::INFINITY, f64::min);
    assert!(nearest < 0.05, "measured {hz} Hz, modes {modes:?}");
}
