//! A Stop at seeded instants of the three streaming fixtures (issue 35):
//! a 15-segment point-to-point move under 1 s, a helix with a 2 ms
//! segment every tenth, and a 2 000-segment helix, each streamed to the
//! in-process drives and stopped with the host's Stop at instants drawn
//! from a seeded generator. Every run must end at rest, every drive Idle
//! without a fault, the platform on the planned path throughout, the
//! reference within the stop budget (docs/protocol.md, "Stop ramp"). The
//! figures are printed (`--nocapture`) for docs/protocol.md.

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_link::{DriveConfigs, Feed, Outcome, Session, SessionOptions};
use triquint_shared::plan::Plan;
use triquint_shared::plan::figures::kinematics;
use triquint_shared::protocol::State;
use triquint_shared::protocol::config::{DriveSettings, SMOOTHSTEP_MAX_D1};
use triquint_sim::host_port::SimPort;
use triquint_sim::{Sim, SimConfig, testplan};

/// Largest distance of the plant from the planned joint path from the
/// Stop on (m): the servo's cross-path error, not only the rest position.
const OFF_PATH_M: f64 = 50e-6;
/// Largest distance of the rest position from the path (m).
const REST_OFF_PATH_M: f64 = 10e-6;
/// At rest: joint speed over the last 100 ms below this (m/s).
const REST_SPEED: f64 = 1e-4;
/// How long after every drive is Idle the run goes on (ns).
const SETTLE_NS: u64 = 300_000_000;

/// One stopped run.
#[derive(Clone, Copy, Debug)]
struct StopRun {
    /// Plan time at which the Stop was sent (s).
    at_s: f64,
    /// From the Stop to every drive Idle (s).
    stop_s: f64,
    /// Worst distance of the plant from the path, from the Stop on (m).
    off_path_m: f64,
    /// Distance of the rest position from the path (m).
    rest_off_path_m: f64,
    /// Joint speed over the last 100 ms (m/s).
    rest_speed: f64,
    /// Largest |jerk| of any drive's reference while Stopping (m/s³).
    jerk: f64,
    /// Largest |acceleration| of the reference from the Stop on (m/s²).
    accel: f64,
    /// The largest of any drive's own stop ramp for its queue (ns).
    own_ramp_ns: i64,
    /// Every drive Idle, no fault on any node or reported to the host, and
    /// the session ended stopped (or completed: the plan ended first).
    clean: bool,
}

/// The bounds a stop keeps to (docs/protocol.md, "Stop ramp"): jerk within
/// the drives' own stop budget, min(C, max(J, j·cap³ + J/2)) for their
/// jerk limit J, ceiling C and override cap, acceleration within
/// max(A, a + 1.875·v/T_s), for the plan's exact maxima v, a, j.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    jerk: f64,
    accel: f64,
}

fn bounds(plan: &Plan, configs: &DriveConfigs) -> Bounds {
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

/// A run of a plan on the in-process drives. The simulation is
/// deterministic, so a clone taken at an instant goes on exactly as a run
/// started afresh would from there: one run to the last instant, branched
/// at each, replaces a run from the start per instant.
#[derive(Clone)]
struct Run {
    sim: Sim,
    session: Session,
    limit_ns: u64,
    /// When the Stop was sent (true time, ns).
    sent_ns: Option<u64>,
    /// Largest |acceleration| of the reference from the Stop on.
    accel: f32,
    /// The largest of any drive's own stop ramp for its queue (ns).
    own_ramp_ns: i64,
}

impl Run {
    fn new(plan: &Plan, configs: &DriveConfigs) -> Self {
        let q0 = plan.segments[0].quintic().eval(0.0).q;
        Run {
            sim: Sim::new(&plan.robot, q0, SimConfig::default()),
            session: Session::new(plan, configs.nodes, SessionOptions::default()).unwrap(),
            limit_ns: ((plan.total_time_s + 30.0) * 1e9) as u64,
            sent_ns: None,
            accel: 0.0,
            own_ramp_ns: 0,
        }
    }

    fn track_ramps(&mut self) {
        for n in &self.sim.nodes {
            self.own_ramp_ns = self.own_ramp_ns.max(n.node.drive.queue_ramps_ns().0);
        }
    }

    /// Whether plan time `at_s` has come (the plan started).
    fn reached(&self, at_s: f64) -> bool {
        let start_ns = self.session.start_us() * 1000;
        start_ns > 0 && self.sim.now_ns() as f64 >= start_ns as f64 + at_s * 1e9
    }

    /// The session polled, then 100 µs of simulation; the outcome once the
    /// session ended.
    fn advance(&mut self) -> Option<Outcome> {
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

    /// Sends Stop now and runs to the end: the stopped run's figures.
    fn stop(mut self, plan: &Plan, configs: &DriveConfigs, at_s: f64) -> StopRun {
        self.session.feed(Feed::Stop);
        let sent = self.sim.now_ns();
        self.sent_ns = Some(sent);
        let outcome = loop {
            if let Some(o) = self.advance() {
                break o;
            }
            self.track_ramps();
        };
        let Run {
            mut sim,
            accel,
            own_ramp_ns,
            ..
        } = self;
        sim.run_until(sim.now_ns() + SETTLE_NS).unwrap();
        let idle_at = sim
            .nodes
            .iter()
            .map(|n| {
                n.states
                    .iter()
                    .filter(|(t, _)| *t >= sent)
                    .find(|(_, s)| *s == State::Idle)
                    .map_or(u64::MAX, |x| x.0)
            })
            .max()
            .unwrap_or(u64::MAX);
        // Drives that were already Idle (the plan ended first) stopped at once.
        let idle_at =
            if idle_at == u64::MAX && sim.nodes.iter().all(|n| n.node.state() == State::Idle) {
                sent
            } else {
                idle_at
            };
        let clean = sim.nodes.iter().all(|n| n.node.state() == State::Idle)
            && sim.faults().is_empty()
            && outcome.faults.is_empty()
            && (outcome.stopped || outcome.completed);
        let stop_s = configs.stop_time_s;
        let path = Path::new(plan, at_s - 0.1, at_s + stop_s + 0.1);
        let after: Vec<_> = sim.samples.iter().filter(|s| s.t_ns >= sent).collect();
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
        StopRun {
            at_s,
            stop_s: idle_at.saturating_sub(sent) as f64 * 1e-9,
            off_path_m,
            rest_off_path_m,
            rest_speed,
            jerk: sim
                .nodes
                .iter()
                .map(|n| n.max_stop_jerk as f64)
                .fold(0.0, f64::max),
            accel: accel as f64,
            own_ramp_ns,
            clean,
        }
    }
}

/// Runs `plan` once and stops a branch of the run at each plan time of
/// `instants`: the figures of each stopped run, in the order given.
fn stop_runs(plan: &Plan, configs: &DriveConfigs, instants: &[f64]) -> Vec<StopRun> {
    let mut order: Vec<usize> = (0..instants.len()).collect();
    order.sort_by(|&a, &b| instants[a].total_cmp(&instants[b]));
    let mut runs: Vec<Option<StopRun>> = vec![None; instants.len()];
    let mut pending = order.into_iter().peekable();
    let mut main = Run::new(plan, configs);
    loop {
        main.track_ramps();
        while let Some(&k) = pending.peek() {
            if !main.reached(instants[k]) {
                break;
            }
            runs[k] = Some(main.clone().stop(plan, configs, instants[k]));
            pending.next();
        }
        if pending.peek().is_none() {
            break;
        }
        if main.advance().is_some() {
            panic!(
                "the session ended before the Stop at {} s",
                instants[pending.next().unwrap()]
            );
        }
    }
    runs.into_iter()
        .map(|r| r.expect("every instant stopped"))
        .collect()
}

/// The planned joint path over plan times [from, to], as a polyline of
/// 0.5 ms samples.
struct Path(Vec<Vector3<f64>>);

impl Path {
    fn new(plan: &Plan, from: f64, to: f64) -> Self {
        let (from, to) = (from.max(0.0), to.min(plan.total_time_s));
        let n = ((to - from) / 0.0005).ceil().max(1.0) as usize;
        Path(
            (0..=n)
                .filter_map(|i| plan.at(from + (to - from) * i as f64 / n as f64))
                .map(|s| Vector3::from(s.q))
                .collect(),
        )
    }

    fn distance(&self, q: &Vector3<f64>) -> f64 {
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

/// Stops `plan` at `n` seeded instants in [0, T); asserts each and
/// prints the worst figures.
fn stops_end_on_the_path(name: &str, plan: &Plan, n: usize, seed: u64) {
    stops_end_on_the_path_with(name, plan, n, seed, &DriveSettings::default());
}

/// [`stops_end_on_the_path`] on drives with `settings`.
fn stops_end_on_the_path_with(
    name: &str,
    plan: &Plan,
    n: usize,
    seed: u64,
    settings: &DriveSettings,
) {
    let configs = DriveConfigs::for_plan(plan, settings).unwrap();
    let b = bounds(plan, &configs);
    // The drives' own ramp for what they hold never exceeds the host's
    // (as the drive rounds it: whole µs).
    let host_ns = (configs.nodes[0].stop_time * 1e6) as i64 * 1000;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let instants: Vec<f64> = (0..n)
        .map(|_| rng.random_range(0.0..plan.total_time_s))
        .collect();
    let runs = stop_runs(plan, &configs, &instants);
    let unsafe_endings: Vec<&StopRun> = runs
        .iter()
        .filter(|r| {
            !r.clean
                || r.off_path_m > OFF_PATH_M
                || r.rest_off_path_m > REST_OFF_PATH_M
                || r.rest_speed > REST_SPEED
                || r.jerk > b.jerk * 1.001
                || r.accel > b.accel * 1.001
                || r.stop_s > configs.stop_time_s + 0.01
                || r.own_ramp_ns > host_ns
                || r.own_ramp_ns == 0
        })
        .collect();
    let worst = |f: fn(&StopRun) -> f64| runs.iter().map(f).fold(0.0, f64::max);
    let worst_at = runs
        .iter()
        .max_by(|a, b| a.off_path_m.total_cmp(&b.off_path_m))
        .map_or(0.0, |r| r.at_s);
    // Stops the host dated with a ramp for the path ahead are shorter.
    let mean_stop = runs.iter().map(|r| r.stop_s).sum::<f64>() / runs.len().max(1) as f64;
    eprintln!(
        "{name}: {n} stops, T_s {:.3} s: worst off path {:.2} µm (Stop at {worst_at:.3} s; at rest {:.2} µm), \
         mean stop {mean_stop:.3} s (×{:.3} of T_s), worst stop {:.3} s, worst jerk {:.3} m/s³ of {:.3}, worst acceleration {:.3} m/s² of {:.3}, \
         rest speed {:.1e} m/s, drives' own ramp up to {:.3} s; {} unsafe",
        configs.stop_time_s,
        worst(|r| r.off_path_m) * 1e6,
        worst(|r| r.rest_off_path_m) * 1e6,
        mean_stop / configs.stop_time_s,
        worst(|r| r.stop_s),
        worst(|r| r.jerk),
        b.jerk,
        worst(|r| r.accel),
        b.accel,
        worst(|r| r.rest_speed),
        worst(|r| r.own_ramp_ns as f64 * 1e-9),
        unsafe_endings.len()
    );
    assert!(unsafe_endings.is_empty(), "{name}: {unsafe_endings:#?}");
}

#[test]
fn a_stop_at_100_instants_of_the_15_segment_move_ends_on_the_path() {
    let plan = testplan::point_to_point(15, 0.9, 0.03).unwrap();
    stops_end_on_the_path("15 segments in 0.9 s", &plan, 100, 35);
}

/// The same move on drives whose jerk ceiling is below the plan's own
/// stop budget (j + J/4 < j + J/2): every stop stays within the ceiling.
#[test]
fn a_stop_at_50_instants_stays_within_the_drives_jerk_ceiling() {
    let plan = testplan::point_to_point(15, 0.9, 0.03).unwrap();
    let [_, _, j] = kinematics(&plan.segments).largest();
    let mut s = DriveSettings::default();
    s.ceilings.jerk = j + 0.25 * plan.limits.jerk;
    stops_end_on_the_path_with("15 segments, ceiling j + J/4", &plan, 50, 38, &s);
}

#[test]
fn a_stop_at_100_instants_of_the_2_ms_every_tenth_plan_ends_on_the_path() {
    let plan = testplan::helix(100, 20.0, Some(0.002)).unwrap();
    stops_end_on_the_path("2 ms every tenth", &plan, 100, 36);
}

/// 100 instants of the 100 s plan: one run to the last, branched at each.
#[test]
fn a_stop_at_100_instants_of_the_2000_segment_plan_ends_on_the_path() {
    let plan = testplan::helix(2000, 100.0, None).unwrap();
    stops_end_on_the_path("2000 segments", &plan, 100, 37);
}
