//! The `frames` fuzz target's inputs as a normal test on stable Rust: its
//! seed corpus, every committed regression input, and 3,000 seeded random
//! streams and mutations (the long libFuzzer run is documented in docs/verification.md);
//! and that the harness does reach Running: a whole plan in an input runs.

include!("../../fuzz/harness/frames.rs");
include!("../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    replay("frames", 3, |d| {
        fuzz_frames(d);
    });
}

#[test]
fn seeded_random_streams_and_mutations_pass() {
    streams_and_flips("frames", 0x9E37_79B9_7F4A_7C15, 3000, 600, |d| {
        fuzz_frames(d);
    });
}

/// Rest-to-rest segments of equal joint steps (C3 at every knot), `h` s each.
fn plan(n: usize, h: f64) -> Vec<triquint_shared::protocol::WireSegment> {
    use triquint_shared::kinematics::Pose;
    use triquint_shared::protocol::segment::{FLAG_FIRST, FLAG_LAST};
    use triquint_shared::quintic::Quintic;
    let m = triquint_shared::Robot::default().model::<f64>();
    let q = |z: f64, x: f64| {
        Pose::from_cartesian(&m, nalgebra::Vector3::new(x, -x, z))
            .unwrap()
            .q
    };
    let q0 = q(0.62, 0.0);
    let step = q(0.63, 0.01) - q0;
    (0..n)
        .map(|i| {
            let a = q0 + step * i as f64;
            let mut coeffs = [[0.0; 6]; 3];
            for j in 0..3 {
                let d = step[j];
                coeffs[j] = [
                    a[j],
                    0.0,
                    0.0,
                    10.0 * d / h.powi(3),
                    -15.0 * d / h.powi(4),
                    6.0 * d / h.powi(5),
                ];
            }
            let flags =
                if i == 0 { FLAG_FIRST } else { 0 } | if i + 1 == n { FLAG_LAST } else { 0 };
            triquint_shared::protocol::WireSegment::from_quintic(
                i as u16,
                &Quintic {
                    coeffs,
                    duration: h,
                },
                flags,
            )
            .unwrap()
        })
        .collect()
}

/// An input that uploads a plan, arms and starts it, and waits for its end.
fn plan_input(segs: &[triquint_shared::protocol::WireSegment]) -> Vec<u8> {
    use triquint_shared::protocol::{Command, CommandCode};
    let mut frames: Vec<_> = segs.iter().flat_map(|s| s.frames(false)).collect();
    let cmd = |c: CommandCode, token: u8, arg: u32| {
        Command {
            command: c as u8,
            token,
            arg,
            arg2: 0,
        }
        .to_frame(2)
    };
    frames.push(cmd(CommandCode::Arm, 1, 0));
    // The Start frame arrives FRAME_US after the Arm: start 20 ms later.
    let start_at = FIRST_FRAME_US + frames.len() as u64 * FRAME_US + 20_000;
    frames.push(cmd(CommandCode::Start, 2, start_at as u32));
    frames.extend((0..6).map(|_| pause(255)));
    encode_frames(&frames)
}

#[test]
fn a_plan_in_an_input_is_armed_started_and_executed_to_its_end() {
    let segs = plan(4, 0.3);
    let [raw, configured] = fuzz_frames(&plan_input(&segs));
    // Unconfigured, every segment is refused.
    assert_eq!((raw.accepted, raw.running_ticks), (0, 0));
    assert_eq!(configured.accepted, 4, "{configured:?}");
    // 1.2 s of plan at 1 kHz, every tick on an accepted segment.
    assert!(configured.running_ticks >= 1190, "{configured:?}");
}

#[test]
fn a_segment_beyond_the_limits_is_never_accepted_nor_run() {
    // Four times faster: jerk 4⁴ = 256 × higher, beyond the configured 50 m/s³.
    let segs = plan(4, 0.075);
    let [_, configured] = fuzz_frames(&plan_input(&segs));
    assert_eq!(configured.accepted, 0, "{configured:?}");
    assert!(configured.refused_checked >= 1, "{configured:?}");
    assert_eq!(configured.running_ticks, 0);
}

/// The plan input is part of the committed seed corpus, so libFuzzer
/// mutates a run that reaches Running from its first second.
#[test]
fn the_running_plan_is_in_the_seed_corpus() {
    let want = plan_input(&plan(4, 0.3));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus/frames/plan-arm-start-run");
    if std::env::var_os("TRIQUINT_BLESS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    assert_eq!(
        std::fs::read(&path).ok().as_ref(),
        Some(&want),
        "TRIQUINT_BLESS=1 rewrites {}",
        path.display()
    );
}
