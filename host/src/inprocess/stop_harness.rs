//! What the stop tests share (`stop_tests`: the host's Stop,
//! `fault_stop_tests`: the host gone silent): a deterministic run of a
//! plan through the host's session on the in-process drives, branched at
//! seeded instants, and the measure of where a stopped run ended, against
//! the planned path.

use std::ops::Range;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_link::{DriveConfigs, Outcome, Session, SessionOptions};
use triquint_shared::plan::Plan;
use triquint_shared::plan::figures::kinematics;
use triquint_shared::protocol::config::SMOOTHSTEP_MAX_D1;
use triquint_sim::host_port::SimPort;
use triquint_sim::{Sim, SimConfig};

/// The bounds a stop keeps to (docs/protocol.md, "Stop ramp"): jerk within
/// the drives' own stop budget, min(C, max(J, j·cap³ + J/2)) for their
/// jerk limit J, ceiling C and override cap, acceleration within
/// max(A, a + 1.875·v/T_s), for the plan's exact maxima v, a, j.
#[derive(Clone, Copy, Debug)]
pub(super) struct Bounds {
    pub(super) jerk: f64,
    pub(super) accel: f64,
}

pub(super) fn bounds(plan: &Plan, configs: &DriveConfigs) -> Bounds {
    let [v, a, j] = kinematics(&plan.segments).largest();
    let l = &plan.limits;
    let c = &configs.nodes[0];
    let (jl, cap) = (c.max_jerk as f64, configs.override_cap);
    let stop_time_s = configs.stop_time_s;
    Bounds {
        jerk: (c.ceiling_jerk as f64).min(jl.max(j * cap.powi(3) + 0.5 * jl)),
        accel: l.acceleration.max(a + SMOOTHSTEP_MAX_D1 * v / stop_time_s),
    }
}

/// Largest distance of the plant from the planned joint path from the
/// stop on (m): the servo's cross-path error, not only the rest position.
pub(super) const OFF_PATH_M: f64 = 50e-6;
/// Largest distance of the rest position from the path (m).
pub(super) const REST_OFF_PATH_M: f64 = 10e-6;
/// At rest: joint speed over the last 100 ms below this (m/s).
pub(super) const REST_SPEED: f64 = 1e-4;
/// How long after every drive came to its end state the run goes on (ns).
pub(super) const SETTLE_NS: u64 = 300_000_000;

/// A run of a plan on the in-process drives. The simulation is
/// deterministic, so a clone taken at an instant goes on exactly as a run
/// started afresh would from there: one run to the last instant, branched
/// at each, replaces a run from the start per instant.
#[derive(Clone)]
pub(super) struct Run {
    pub(super) sim: Sim,
    pub(super) session: Session,
    pub(super) limit_ns: u64,
    /// When the Stop was sent (true time, ns).
    pub(super) sent_ns: Option<u64>,
    /// Largest |acceleration| of the reference from the Stop on.
    pub(super) accel: f32,
    /// The largest of any drive's own stop ramp for its queue (ns).
    pub(super) own_ramp_ns: i64,
}

impl Run {
    pub(super) fn new(plan: &Plan, configs: &DriveConfigs) -> Self {
        let q0 = plan.segments[0].quintic().eval(0.0).q;
        Self::on(
            Sim::new(&plan.robot, q0, SimConfig::default()),
            plan,
            configs,
        )
    }

    /// [`Run::new`] on the flexible machine (screw, coupling and strut
    /// compliance, an accelerometer on the platform).
    pub(super) fn flexible(plan: &Plan, configs: &DriveConfigs) -> Self {
        let q0 = Vector3::from(plan.segments[0].quintic().eval(0.0).q);
        let flex = triquint_sim::flex::FlexParams::default();
        let sim = Sim::flexible(&plan.robot, q0, SimConfig::default(), &flex).unwrap();
        Self::on(sim, plan, configs)
    }

    /// A run of `plan` on `sim`, before the session's first poll.
    fn on(sim: Sim, plan: &Plan, configs: &DriveConfigs) -> Self {
        Run {
            sim,
            session: Session::new(plan, configs.nodes, SessionOptions::default()).unwrap(),
            limit_ns: ((plan.total_time_s + 30.0) * 1e9) as u64,
            sent_ns: None,
            accel: 0.0,
            own_ramp_ns: 0,
        }
    }

    pub(super) fn track_ramps(&mut self) {
        for n in &self.sim.nodes {
            self.own_ramp_ns = self.own_ramp_ns.max(n.node.drive.queue_ramps_ns().0);
        }
    }

    /// Whether plan time `at_s` has come (the plan started).
    pub(super) fn reached(&self, at_s: f64) -> bool {
        let start_ns = self.session.start_us() * 1000;
        start_ns > 0 && self.sim.now_ns() as f64 >= start_ns as f64 + at_s * 1e9
    }

    /// The session polled, then 100 µs of simulation; the outcome once the
    /// session ended.
    pub(super) fn advance(&mut self) -> Option<Outcome> {
        if self.sent_ns.is_some() {
            self.accel = self
                .accel
                .max(self.sim.nodes[0].node.stats.reference.qdd.amax());
        }
        let mut port = SimPort {
            sim: &mut self.sim,
            tx_queue: 32,
        };
        if let Some(o) = self.session.poll(&mut port).unwrap() {
            return Some(o);
        }
        let t = self.sim.now_ns() + 100_000;
        assert!(t < self.limit_ns, "the run did not end");
        self.sim.run_until(t).unwrap();
        None
    }
}

/// Runs `plan` once and ends a branch of the run at each plan time of
/// `instants` with `end` (the branch, the instant): what each gave, in the
/// order given.
pub(super) fn branch_runs<R>(
    plan: &Plan,
    configs: &DriveConfigs,
    instants: &[f64],
    mut end: impl FnMut(Run, f64) -> R,
) -> Vec<R> {
    let mut order: Vec<usize> = (0..instants.len()).collect();
    order.sort_by(|&a, &b| instants[a].total_cmp(&instants[b]));
    let mut runs: Vec<Option<R>> = (0..instants.len()).map(|_| None).collect();
    let mut pending = order.into_iter().peekable();
    let mut main = Run::new(plan, configs);
    loop {
        main.track_ramps();
        while let Some(&k) = pending.peek() {
            if !main.reached(instants[k]) {
                break;
            }
            runs[k] = Some(end(main.clone(), instants[k]));
            pending.next();
        }
        if pending.peek().is_none() {
            break;
        }
        if main.advance().is_some() {
            panic!(
                "the session ended before the instant {} s",
                instants[pending.next().unwrap()]
            );
        }
    }
    runs.into_iter()
        .map(|r| r.expect("every instant branched"))
        .collect()
}

/// `n` plan times drawn uniformly from `range` by a generator seeded with `seed`.
pub(super) fn seeded_instants(seed: u64, n: usize, range: Range<f64>) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(range.clone())).collect()
}

/// A planned joint path as a polyline: [`Path::new`], a stretch of 0.5 ms
/// samples.
pub(super) struct Path(pub(super) Vec<Vector3<f64>>);

impl Path {
    /// The planned joint path over plan times [from, to], as a polyline of
    /// 0.5 ms samples.
    pub(super) fn new(plan: &Plan, from: f64, to: f64) -> Self {
        let (from, to) = (from.max(0.0), to.min(plan.total_time_s));
        let n = ((to - from) / 0.0005).ceil().max(1.0) as usize;
        Path(
            (0..=n)
                .filter_map(|i| plan.at(from + (to - from) * i as f64 / n as f64))
                .map(|s| Vector3::from(s.q))
                .collect(),
        )
    }

    /// The distance of `q` from the polyline (m).
    pub(super) fn distance(&self, q: &Vector3<f64>) -> f64 {
        self.0
            .windows(2)
            .map(|w| {
                let d = w[1] - w[0];
                let u = if d.norm_squared() > 0.0 {
                    ((q - w[0]).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (w[0] + d * u - q).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Where a stopped run ended, against the planned path.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ending {
    /// Worst distance of the plant from the path, from the stop on (m).
    pub(super) off_path_m: f64,
    /// Distance of the rest position from the path (m).
    pub(super) rest_off_path_m: f64,
    /// Joint speed over the last 100 ms (m/s).
    pub(super) rest_speed: f64,
}

impl Ending {
    /// The samples of `sim` from true time `from_ns` on (every fifth) and
    /// its last 100 ms, against `path`.
    pub(super) fn of(sim: &Sim, path: &Path, from_ns: u64) -> Self {
        let after: Vec<_> = sim.samples.iter().filter(|s| s.t_ns >= from_ns).collect();
        let off_path_m = after
            .iter()
            .step_by(5)
            .map(|s| path.distance(&Vector3::from(s.q)))
            .fold(0.0, f64::max);
        let last = after.last().expect("samples after the stop");
        let rest_off_path_m = path.distance(&Vector3::from(last.q));
        let before = after
            .iter()
            .rev()
            .find(|s| s.t_ns + 100_000_000 <= last.t_ns)
            .expect("100 ms of samples");
        let rest_speed = (Vector3::from(last.q) - Vector3::from(before.q)).amax()
            / ((last.t_ns - before.t_ns) as f64 * 1e-9);
        Ending {
            off_path_m,
            rest_off_path_m,
            rest_speed,
        }
    }

    /// Off the path, or not at rest on it.
    pub(super) fn is_unsafe(&self) -> bool {
        self.off_path_m > OFF_PATH_M
            || self.rest_off_path_m > REST_OFF_PATH_M
            || self.rest_speed > REST_SPEED
    }
}

/// A plan committed under testdata/protocol/plans/ (`case1-spline`,
/// `case2-spline`, `spiral-spline`).
pub(super) fn committed_plan(name: &str) -> Plan {
    let file = format!(
        "{}/../testdata/protocol/plans/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{file}: {e}"))
}
