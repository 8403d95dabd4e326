//! Feed hold, resume, override and stop during an upload, end to end: the
//! host session's feed commands over the in-process bus to three firmware
//! nodes driving the plant. Each run traces, every millisecond, the drives'
//! time-scaling phases, the scaled reference (node 1 evaluates all three
//! axes) and the plant, so the tests check completion, the path, the limits
//! and measure the transitions.

use nalgebra::Vector3;
use triquint_firmware::scaling::Phase;
use triquint_link::{DriveConfigs, Feed, Outcome, Session, SessionOptions};
use triquint_shared::plan::Plan;
use triquint_shared::protocol::FaultCode;
use triquint_shared::protocol::config::{DriveSettings, SMOOTHSTEP_MAX_D1};
use triquint_shared::quintic::JointMotion;
use triquint_sim::host_port::SimPort;
use triquint_sim::{Sim, SimConfig, testplan};

use super::stop_harness::Path;

/// One millisecond of a run.
#[derive(Clone, Copy, Debug)]
struct Trace {
    /// Host time (s) since the start (negative before).
    t_s: f64,
    phases: [Phase; 3],
    reference: JointMotion<f32>,
    /// The plant's joint positions (m).
    q: Vector3<f64>,
}

struct Run {
    outcome: Outcome,
    trace: Vec<Trace>,
    configs: DriveConfigs,
    /// Commands sent: (time since the start (s), token, command).
    sent: Vec<(f64, u8, Feed)>,
    session_answers: Vec<[Option<(u8, u32)>; 3]>,
}

/// Runs `plan` from its start; `act(t_s, session)` is called every host
/// poll once started and may send feed commands (returned with their time).
fn run(plan: &Plan, act: impl FnMut(f64, &Session) -> Option<Feed>) -> Run {
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let mut sim = Sim::new(&plan.robot, q0, SimConfig::default());
    run_on(&mut sim, plan, SessionOptions::default(), act)
}

/// [`run`] on a machine as it is (a second plan after a first).
fn run_on(
    sim: &mut Sim,
    plan: &Plan,
    opts: SessionOptions,
    mut act: impl FnMut(f64, &Session) -> Option<Feed>,
) -> Run {
    let configs = DriveConfigs::for_plan(plan, &DriveSettings::default()).unwrap();
    let mut session = Session::new(plan, configs.nodes, opts).unwrap();
    let t_begin = sim.now_ns();
    let (mut trace, mut sent) = (Vec::new(), Vec::new());
    let mut polls = 0u64;
    let outcome = loop {
        let start_ns = session.start_us() * 1000;
        let t_s = (sim.now_ns() as f64 - start_ns as f64) * 1e-9;
        if start_ns > 0
            && let Some(f) = act(t_s, &session)
        {
            let token = session.feed(f);
            sent.push((t_s, token, f));
        }
        let mut port = SimPort {
            sim: &mut *sim,
            tx_queue: 32,
        };
        if let Some(o) = session.poll(&mut port).unwrap() {
            break o;
        }
        polls += 1;
        if polls.is_multiple_of(10) {
            trace.push(Trace {
                t_s,
                phases: [0, 1, 2].map(|i| sim.nodes[i].node.scaling_phase()),
                reference: sim.nodes[0].node.stats.reference,
                q: sim.plant.q(),
            });
        }
        let t = sim.now_ns() + 100_000;
        assert!(
            t - t_begin < 120_000_000_000,
            "the run did not end within 120 s"
        );
        sim.run_until(t).unwrap();
    };
    let session_answers = sent
        .iter()
        .map(|(_, token, _)| {
            session
                .answers(*token)
                .map(|a| a.map(|a| (a.result, a.value)))
        })
        .collect();
    Run {
        outcome,
        trace,
        configs,
        sent,
        session_answers,
    }
}

/// Plan maxima over the joints: velocity, acceleration, jerk.
fn maxima(plan: &Plan) -> [f64; 3] {
    let m = |x: [f64; 3]| x.iter().fold(0.0f64, |a, b| a.max(*b));
    [
        m(plan.max_abs.velocity),
        m(plan.max_abs.acceleration),
        m(plan.max_abs.jerk),
    ]
}

/// Peak |v|, |a|, |jerk| of the reference over `t_s` in [from, to).
fn peaks(trace: &[Trace], from: f64, to: f64) -> [f32; 3] {
    trace
        .iter()
        .filter(|t| t.t_s >= from && t.t_s < to)
        .fold([0.0f32; 3], |p, t| {
            [
                p[0].max(t.reference.qd.amax()),
                p[1].max(t.reference.qdd.amax()),
                p[2].max(t.reference.qddd.amax()),
            ]
        })
}

/// Checks the whole trace's reference against the limits, and a
/// transition's against the stop budget (docs/protocol.md): velocity
/// within the limit, acceleration within max(A, k²a + 1.875v/T_s), jerk
/// within max(J, k³j + J/2), with k the largest σ the run used.
fn assert_within_limits(plan: &Plan, r: &Run, k: f64, what: &str) {
    let [v, a, j] = maxima(plan);
    let l = &plan.limits;
    let ts = r.configs.stop_time_s;
    let tol = 1.0 + 1e-3;
    let budget = [
        l.velocity,
        l.acceleration.max(k * k * a + SMOOTHSTEP_MAX_D1 * v / ts),
        l.jerk.max(k.powi(3) * j + 0.5 * l.jerk),
    ];
    let p = peaks(&r.trace, f64::MIN, f64::MAX);
    // The plant itself, from its true joint positions at 1 ms: velocity
    // by 5 ms differences within 2 % of the limit, acceleration by 20 ms
    // second differences (the servo's torque ripple averaged out) within
    // 10 % of the reference's budget.
    let diff = |step: usize, k: usize| {
        let mut peak = 0.0f64;
        for w in r.trace.windows(2 * step + 1).step_by(step) {
            let (a0, b0, c0) = (&w[0], &w[step], &w[2 * step]);
            let h = b0.t_s - a0.t_s;
            if h <= 0.0 || (c0.t_s - b0.t_s - h).abs() > 1e-6 {
                continue;
            }
            let x = match k {
                1 => (b0.q - a0.q) / h,
                _ => (c0.q - 2.0 * b0.q + a0.q) / (h * h),
            };
            peak = peak.max(x.amax());
        }
        peak
    };
    let (pv, pa) = (diff(5, 1), diff(20, 2));
    eprintln!("{what}: plant peaks v {pv:.4} m/s, a {pa:.4} m/s²; reference {p:?}");
    assert!(pv <= budget[0] * 1.02, "{what}: plant velocity {pv}");
    assert!(pa <= budget[1] * 1.1, "{what}: plant acceleration {pa}");
    for i in 0..3 {
        assert!(
            p[i] as f64 <= budget[i] * tol,
            "{what}: peak {:?} against budget {:?}",
            p,
            budget
        );
    }
}

/// The time after `from` at which every drive is first in one of `phases`.
fn first_all(trace: &[Trace], from: f64, phases: &[Phase]) -> Option<f64> {
    trace
        .iter()
        .find(|t| t.t_s > from && t.phases.iter().all(|p| phases.contains(p)))
        .map(|t| t.t_s)
}

/// Largest distance (m) of the plant from the planned joint path (a
/// polyline of 0.5 ms samples) over `t_s` in [from, to).
fn off_path(plan: &Plan, trace: &[Trace], from: f64, to: f64) -> f64 {
    let path = Path(
        plan.sample(0.0005)
            .unwrap()
            .map(|(_, s)| Vector3::from(s.q))
            .collect(),
    );
    trace
        .iter()
        .filter(|t| t.t_s >= from && t.t_s < to)
        .step_by(5)
        .map(|t| path.distance(&t.q))
        .fold(0.0, f64::max)
}

fn assert_completed(r: &Run, what: &str) {
    assert!(
        r.outcome.completed && !r.outcome.stopped && r.outcome.faults.is_empty(),
        "{what}: {:?}",
        r.outcome
    );
}

/// Hold at 40 % of Case II for 8 s (longer than the old fixed deadline
/// allowed), resume: the plan completes, the platform stays on its path,
/// the reference within the limits (or the stop budget).
#[test]
fn hold_at_40_percent_of_case2_then_resume_completes_on_the_path() {
    let plan = testplan::paper_case2().unwrap();
    let t_hold = 0.4 * plan.total_time_s;
    let t_resume = t_hold + 8.0;
    let (mut held, mut resumed) = (false, false);
    let r = run(&plan, |t, _| {
        if !held && t >= t_hold {
            held = true;
            return Some(Feed::Hold);
        }
        if !resumed && t >= t_resume {
            resumed = true;
            return Some(Feed::Resume);
        }
        None
    });
    assert_completed(&r, "hold/resume");
    for a in &r.session_answers {
        assert!(
            a.iter().all(|x| x.is_some_and(|x| x.0 == 0)),
            "answers {a:?}"
        );
    }
    let (th, tr) = (r.sent[0].0, r.sent[1].0);
    // At rest within the hold ramp, and back to σ = 1 within the resume's.
    let rest = first_all(&r.trace, th, &[Phase::Rest]).expect("at rest") - th;
    let back = first_all(&r.trace, tr, &[Phase::Nominal]).expect("resumed") - tr;
    let ts = r.configs.stop_time_s;
    assert!(
        rest <= ts + 0.003 && back <= ts + 0.003,
        "{rest} {back} T_s {ts}"
    );
    // Held: the reference stands still.
    let still = peaks(&r.trace, th + rest + 0.01, tr);
    assert!(still[0] == 0.0, "moving while held: {still:?}");
    // On the path throughout the hold and the resume (position against
    // the path, not its timing): within the normal tracking error.
    let off = off_path(&plan, &r.trace, th - 0.2, tr + ts + 0.3);
    assert!(off < 50e-6, "{off} m off the path");
    assert_within_limits(&plan, &r, 1.0, "hold/resume");
    let [_, _, j] = maxima(&plan);
    eprintln!(
        "hold at {th:.3} s: at rest after {rest:.3} s, resumed to σ = 1 after {back:.3} s \
         (T_s {ts:.3} s); peak jerk in the hold ramp {:.3}, resume ramp {:.3} m/s³ \
         (plan {j:.3}, limit {}); {:.1} µm off the path at most",
        peaks(&r.trace, th, th + rest)[2],
        peaks(&r.trace, tr, tr + back)[2],
        plan.limits.jerk,
        off * 1e6
    );
}

/// Override to 50 % mid-plan and back to 100 %: completes, later by the
/// time run at half speed, within the limits.
#[test]
fn override_50_percent_and_back_to_100_completes() {
    let plan = testplan::paper_case2().unwrap();
    let (t1, t2) = (1.0, 3.0);
    let mut step = 0;
    let r = run(&plan, |t, _| match step {
        0 if t >= t1 => {
            step = 1;
            Some(Feed::Override(500))
        }
        1 if t >= t2 => {
            step = 2;
            Some(Feed::Override(1000))
        }
        _ => None,
    });
    assert_completed(&r, "override");
    for a in &r.session_answers {
        assert!(a.iter().all(|x| x.is_some_and(|x| x.0 == 0)), "{a:?}");
    }
    let down = first_all(&r.trace, t1 + 0.002, &[Phase::Nominal]).unwrap() - t1;
    let up = first_all(&r.trace, t2 + 0.002, &[Phase::Nominal]).unwrap() - t2;
    // 2 s at about half speed: the plan ends about 1 s late.
    let end = r.trace.last().unwrap().t_s;
    let late = end - plan.total_time_s;
    assert!((0.8..1.3).contains(&late), "ended {late} s late");
    assert_within_limits(&plan, &r, 1.0, "override");
    let off = off_path(&plan, &r.trace, t1, t2 + 0.5);
    assert!(off < 50e-6, "{off} m off the path");
    eprintln!(
        "override 100 → 50 %: {down:.3} s, peak jerk {:.3} m/s³; 50 → 100 %: {up:.3} s, \
         peak jerk {:.3} m/s³ (limit {}); ended {late:.3} s late",
        peaks(&r.trace, t1, t1 + down)[2],
        peaks(&r.trace, t2, t2 + up)[2],
        plan.limits.jerk
    );
}

/// Above the cap: every drive refuses with the cap in its answer, and the
/// plan runs on at 100 %; at the cap: accepted, and within the limits.
#[test]
fn override_above_the_cap_is_refused_with_the_cap() {
    let plan = testplan::paper_case2().unwrap();
    let cap_pm = DriveConfigs::for_plan(&plan, &DriveSettings::default())
        .unwrap()
        .override_cap_permille();
    assert!(cap_pm > 1000, "Case II leaves headroom: cap {cap_pm}");
    let mut step = 0;
    let r = run(&plan, |t, _| match step {
        0 if t >= 0.5 => {
            step = 1;
            Some(Feed::Override(cap_pm + 1))
        }
        1 if t >= 1.0 => {
            step = 2;
            Some(Feed::Override(cap_pm))
        }
        _ => None,
    });
    assert_completed(&r, "override at the cap");
    let refused = r.session_answers[0];
    for a in refused {
        assert_eq!(
            a,
            Some((FaultCode::OverrideAboveCap as u8, cap_pm as u32)),
            "{refused:?}"
        );
    }
    for a in r.session_answers[1] {
        assert_eq!(a, Some((0, cap_pm as u32)));
    }
    let k = cap_pm as f64 / 1000.0;
    assert_within_limits(&plan, &r, k, "at the cap");
    // At the cap the constant-σ reference meets the limits themselves.
    let p = peaks(&r.trace, 1.5, 2.5);
    let l = &plan.limits;
    assert!(p[0] as f64 <= l.velocity && p[1] as f64 <= l.acceleration * 1.001);
    assert!(p[2] as f64 <= l.jerk * 1.001, "{p:?}");
    eprintln!("cap {cap_pm} ‰: peaks at the cap {p:?}");
}

/// A stop mid-plan: at rest on the path, every drive Idle without a fault,
/// the session ends stopped (not completed, not a timeout).
#[test]
fn a_stop_mid_plan_ends_the_session_stopped() {
    let plan = testplan::paper_case2().unwrap();
    let mut sent = false;
    let r = run(&plan, |t, _| {
        if !sent && t >= 1.5 {
            sent = true;
            return Some(Feed::Stop);
        }
        None
    });
    assert!(r.outcome.stopped && !r.outcome.completed, "{:?}", r.outcome);
    assert!(r.outcome.faults.is_empty(), "{:?}", r.outcome.faults);
    let ts = r.configs.stop_time_s;
    let off = off_path(&plan, &r.trace, 1.4, 1.5 + ts + 0.2);
    assert!(off < 50e-6, "{off} m off the path");
    assert_within_limits(&plan, &r, 1.0, "stop");
}

/// `upload --approach` of Case II from the default power-on pose of
/// `triquint-sim` (-90, 90, 680) mm and from the pose `home` leaves (every
/// slider at the switch height less the back-off): the min-time approach
/// of `move-to` completes, then the plan, both at the override set during
/// the approach (50 %, carried as `upload` does).
#[test]
fn approach_then_case2_completes_from_the_power_on_and_home_poses() {
    use triquint_shared::kinematics::Pose;
    use triquint_shared::protocol::config::HomingSettings;
    let plan = testplan::paper_case2().unwrap();
    let m = plan.robot.model::<f64>();
    let h = HomingSettings::default();
    let homed = Vector3::from(h.switch_height).add_scalar(-h.backoff);
    let power_on = Pose::from_cartesian(&m, Vector3::new(-0.09, 0.09, 0.68))
        .unwrap()
        .q;
    for (name, q0) in [("power-on", power_on), ("homed", homed)] {
        let start = Vector3::from(plan.via_points_m[0]);
        let approach = crate::ops::plan_move::plan_move(
            &triquint_shared::machine::Machine::default(),
            q0,
            start,
        )
        .unwrap()
        .expect("not at the start");
        let mut sim = Sim::new(&plan.robot, q0, SimConfig::default());
        let mut sent = false;
        let a = run_on(&mut sim, &approach, SessionOptions::default(), |_, _| {
            (!std::mem::replace(&mut sent, true)).then_some(Feed::Override(500))
        });
        assert_completed(&a, name);
        let slow = a.trace.last().unwrap().t_s;
        assert!(
            slow > 1.8 * approach.total_time_s,
            "{name}: approach at 50 % took {slow} s of {} s",
            approach.total_time_s
        );
        let opts = SessionOptions {
            feed_override: Some(500),
            ..SessionOptions::default()
        };
        let r = run_on(&mut sim, &plan, opts, |_, _| None);
        assert_completed(&r, name);
        let took = r.trace.last().unwrap().t_s;
        assert!(
            (1.9..2.2).contains(&(took / plan.total_time_s)),
            "{name}: the plan at 50 % took {took} s"
        );
        eprintln!(
            "{name}: approach {:.3} s planned ({slow:.3} s at 50 %), Case II {took:.3} s at 50 %",
            approach.total_time_s
        );
    }
}

/// Commands at seeded random moments (inside ramps too): hold, resume and
/// overrides up to the cap, then a resume and 100 %: every drive takes
/// every one, the plan completes with no fault, on its path, within the
/// limits or the stop budget.
#[test]
fn commands_at_random_moments_each_taken_and_the_plan_completes() {
    use rand::{RngExt, SeedableRng};
    let plan = testplan::paper_case2().unwrap();
    let cap_pm = DriveConfigs::for_plan(&plan, &DriveSettings::default())
        .unwrap()
        .override_cap_permille();
    for seed in [1u64, 2, 3] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut times: Vec<f64> = (0..6).map(|_| rng.random_range(0.1..4.0)).collect();
        times.sort_by(f64::total_cmp);
        let mut cmds: Vec<(f64, Feed)> = times
            .iter()
            .map(|t| {
                let f = match rng.random_range(0..3) {
                    0 => Feed::Hold,
                    1 => Feed::Resume,
                    _ => Feed::Override(rng.random_range(300..=cap_pm)),
                };
                (*t, f)
            })
            .collect();
        cmds.push((4.5, Feed::Resume));
        cmds.push((4.6, Feed::Override(1000)));
        let mut next = 0;
        let r = run(&plan, |t, _| {
            let c = cmds.get(next).filter(|c| t >= c.0)?;
            next += 1;
            Some(c.1)
        });
        let what = format!("seed {seed}: {cmds:?}");
        assert_completed(&r, &what);
        for a in &r.session_answers {
            assert!(
                a.iter().all(|x| x.is_some_and(|x| x.0 == 0)),
                "{what}: {a:?}"
            );
        }
        let end = r.trace.last().unwrap().t_s;
        assert!(off_path(&plan, &r.trace, 0.0, end) < 50e-6, "{what}");
        assert_within_limits(&plan, &r, cap_pm as f64 / 1000.0, &what);
    }
}

/// A session for `plan` on a new machine at the plan's start (for tests
/// that drive the loop themselves, with [`step`]).
fn session_at_start(plan: &Plan) -> (Sim, Session) {
    let configs = DriveConfigs::for_plan(plan, &DriveSettings::default()).unwrap();
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let sim = Sim::new(&plan.robot, q0, SimConfig::default());
    let session = Session::new(plan, configs.nodes, SessionOptions::default()).unwrap();
    (sim, session)
}

/// One host poll, then 100 µs of the machine; the outcome once the session
/// ends. Panics past `limit_ns` of machine time.
fn step(sim: &mut Sim, session: &mut Session, limit_ns: u64) -> Option<Outcome> {
    let mut port = SimPort {
        sim: &mut *sim,
        tx_queue: 32,
    };
    if let Some(o) = session.poll(&mut port).unwrap() {
        return Some(o);
    }
    let t = sim.now_ns() + 100_000;
    assert!(t < limit_ns, "did not end");
    sim.run_until(t).unwrap();
    None
}

/// A stop asked for before Start (a key during the configuration): the
/// session resets the drives and ends stopped; nothing moved.
#[test]
fn a_stop_before_start_ends_the_session_stopped_and_nothing_moves() {
    let plan = testplan::paper_case2().unwrap();
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let (mut sim, mut session) = session_at_start(&plan);
    let mut polls = 0;
    let outcome = loop {
        polls += 1;
        if polls == 2000 {
            // 0.2 s in: configured, segments loading.
            session.feed(Feed::Stop);
        }
        if let Some(o) = step(&mut sim, &mut session, 10_000_000_000) {
            break o;
        }
    };
    assert!(outcome.stopped && !outcome.completed && outcome.start_us == 0);
    sim.run_until(sim.now_ns() + 300_000_000).unwrap();
    assert!((sim.plant.q() - q0).amax() < 20e-6, "moved");
    for n in &sim.nodes {
        assert_eq!(n.node.state(), triquint_shared::protocol::State::Idle);
        assert_eq!(n.node.fault(), FaultCode::None);
    }
}

/// A hold while segments are still streaming: the queues fill and wait, nothing is
/// retransmitted to exhaustion, no underrun on the resume; completes.
/// (The spiral of the stress test, several times the queue.)
#[test]
fn a_hold_while_streaming_waits_with_full_queues_and_completes() {
    let plan = testplan::spiral(
        testplan::SPIRAL_POINTS,
        testplan::SPIRAL_TURNS,
        testplan::SPIRAL_TIME,
    )
    .unwrap();
    let n = plan.segments.len();
    assert!(n >= 3 * triquint_firmware::QUEUE_CAPACITY);
    let (th, tr) = (0.3 * plan.total_time_s, 0.3 * plan.total_time_s + 6.0);
    let mut step = 0;
    let r = run(&plan, |t, s| match step {
        0 if t >= th => {
            step = 1;
            assert!(s.progress().segments_acked < n, "still streaming");
            Some(Feed::Hold)
        }
        1 if t >= tr => {
            step = 2;
            Some(Feed::Resume)
        }
        _ => None,
    });
    assert_completed(&r, "hold while streaming");
    let late = r.trace.last().unwrap().t_s - plan.total_time_s;
    assert!(late > tr - th, "ended {late} s late");
    assert!(off_path(&plan, &r.trace, th, tr + 3.0) < 50e-6);
    assert_within_limits(&plan, &r, 1.0, "spiral hold");
}

/// A stop and an override not sent by the session (`triquint stop` in a
/// second process, the web page): the session learns of the stop from the
/// drives' answers and ends stopped; the override persists on the drives.
#[test]
fn a_stop_from_another_station_ends_the_session_stopped() {
    use triquint_shared::protocol::{Command, CommandCode};
    let plan = testplan::paper_case2().unwrap();
    let (mut sim, mut session) = session_at_start(&plan);
    let other = |code: CommandCode, arg2: u16| {
        Command {
            command: code as u8,
            token: 0xC7,
            arg: 0,
            arg2,
        }
        .to_frame(0)
    };
    let (mut overridden, mut stopped) = (false, false);
    let outcome = loop {
        let start = session.start_us() * 1000;
        let t = sim.now_ns();
        if start > 0 && !overridden && t > start + 1_000_000_000 {
            overridden = true;
            sim.host_send(other(CommandCode::Override, 700));
        }
        if start > 0 && !stopped && t > start + 2_000_000_000 {
            stopped = true;
            sim.host_send(other(CommandCode::Stop, 0));
        }
        if let Some(o) = step(&mut sim, &mut session, 20_000_000_000) {
            break o;
        }
    };
    assert!(outcome.stopped && !outcome.completed, "{outcome:?}");
    assert!(outcome.faults.is_empty(), "{outcome:?}");
    for n in &sim.nodes {
        assert_eq!(n.node.state(), triquint_shared::protocol::State::Idle);
        assert_eq!(n.node.override_permille(), 700);
    }
}

/// An override set before the upload (`triquint override 70` from another
/// process) is learnt from the drives' answers to Arm: the session's plan
/// time, which its deadline follows, advances at 70 %, not at the slowest
/// override (0.1 %), and the progress line (and the `+`/`-` keys) have it.
#[test]
fn an_override_set_before_the_upload_is_learnt_from_the_answer_to_arm() {
    use triquint_shared::protocol::{Command, CommandCode};
    let plan = testplan::paper_case2().unwrap();
    let (mut sim, mut session) = session_at_start(&plan);
    let before = Command {
        command: CommandCode::Override as u8,
        token: 0xC9,
        arg: 0,
        arg2: 700,
    };
    sim.host_send(before.to_frame(0));
    sim.run_until(sim.now_ns() + 5_000_000).unwrap();
    for n in &sim.nodes {
        assert_eq!(n.node.override_permille(), 700, "not set before the upload");
    }
    let mut checked = 0;
    let outcome = loop {
        let start = session.start_us() * 1000;
        let t = sim.now_ns();
        if start > 0 && t > start + (1 + checked) * 1_000_000_000 && checked < 3 {
            checked += 1;
            let p = session.progress();
            assert_eq!(p.override_permille, Some(700), "not learnt");
            let drives_us = sim.nodes[0].node.plan_ns() / 1000;
            let host_us = p.plan_time_us as i64;
            assert!(
                (host_us - drives_us).abs() < 20_000,
                "host's plan time {host_us} µs, the drives' {drives_us} µs"
            );
        }
        if let Some(o) = step(&mut sim, &mut session, 120_000_000_000) {
            break o;
        }
    };
    assert_eq!(checked, 3);
    assert!(
        outcome.completed && outcome.faults.is_empty(),
        "{outcome:?}"
    );
}
