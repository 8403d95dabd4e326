//! Soak: seeded random fault schedules over both paper plans on the
//! in-process virtual hardware (1 kHz control); the last kind runs a
//! longer plan ([`late_plan`]) whose first segment above the velocity
//! ceiling arrives after Start. Prints a table per fault kind: trials,
//! outcome counts, worst stop time; fails (exit 1) on any corrupted
//! execution, unsafe ending or panic, or a late refusal before Start.
//!
//! `cargo run --release -p triquint-host --example fault_soak -- [SCHEDULES] [THREADS] [SEED]`

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_host::inprocess::fault_run::{AboveCeiling, BadSegment, Miswired, Scenario, run};
use triquint_shared::plan::Plan;
use triquint_shared::plan::figures::kinematics;
use triquint_shared::protocol::streaming::QUEUE_CAPACITY;
use triquint_sim::report::{Ending, RunReport};
use triquint_sim::{Fault, FaultWindow, testplan};

const MS: u64 = 1_000_000;

/// The fault kinds of the soak, with the range their parameter is drawn from.
const KINDS: [(&str, &str); 25] = [
    ("loss", "0.1-3 % of frames"),
    ("corrupt", "0.1-3 % of parts"),
    ("duplicate", "1-20 % of frames"),
    ("reorder", "0.1-2 % of frames"),
    ("delay", "0-5 ms service delay"),
    ("jitter", "0-100 µs timestamps"),
    ("late sync", "one sync 1-200 ms late"),
    ("sync lost", "from 0.5-4.5 s"),
    ("bus-off", "host/node, 10-600 ms"),
    ("babble", "0x001-0x01F, 10-600 ms"),
    ("burst", "12 segments, 0.3-4 s"),
    ("host killed", "at 0.1-4.5 s"),
    ("node reset", "at 0.5-4.5 s"),
    ("bad limits", "segment 1-8, jerk 2× the limit"),
    ("not C3", "segment 1-8 velocity step"),
    ("brakes, host killed", "at 0.1-4.5 s; torque off at rest"),
    ("push", "±3-8 N·m, 20-200 ms, 0.5-4.5 s"),
    ("push, brakes", "as push; torque off at rest"),
    ("miswired, brakes", "direction flipped or scale ×1/32"),
    ("scale ×32", "file counts ×32: open-loop hold"),
    ("above a ceiling", "v, a or j ceiling 0.5-0.98 × the plan's"),
    (
        "override above ceilings",
        "ceilings 1.0-1.1 × the plan's maxima",
    ),
    ("stop ramp short", "ceilings at the limits, ramps ×0.01-0.3"),
    (
        "above a ceiling while running",
        "48-segment move, v ceiling 0.92-0.98 × its peak",
    ),
    (
        "ceilings widened, locked",
        "commissioned v, a or j 0.5-0.98 × the plan's; top ones sent",
    ),
];

/// The kind whose refusal comes while Running, on [`late_plan`].
const LATE: usize = 23;
/// Its velocity ceiling's range, as a fraction of the plan's peak.
const LATE_RANGE: core::ops::Range<f64> = 0.92..0.98;

/// A rest-to-rest move of 100 mm in 48 segments over 6 s: its speed peaks
/// mid-plan, so the first segment above a velocity ceiling near the peak
/// is far past the first queue fill ([`first_above`]). Its velocity limit
/// is its peak: the override cap the host sizes from the limits is then
/// about 1, or every segment scaled to it would be above the ceiling and
/// refused before Start (the "override above ceilings" row).
fn late_plan() -> Plan {
    let mut p = testplan::point_to_point(48, 6.0, 0.1).expect("late plan");
    let peak = kinematics(&p.segments)
        .velocity
        .into_iter()
        .fold(0.0, f64::max);
    p.limits.velocity = peak * 1.001;
    p
}

/// The first segment of `plan` whose exact peak joint speed is above `f`
/// times the plan's.
fn first_above(plan: &Plan, f: f64) -> Option<usize> {
    let top = |x: [f64; 3]| x.into_iter().fold(0.0, f64::max);
    let peak = top(kinematics(&plan.segments).velocity);
    plan.segments
        .iter()
        .position(|s| top(kinematics(std::slice::from_ref(s)).velocity) > f * peak)
}

fn schedule(k: usize, rng: &mut ChaCha8Rng) -> Scenario {
    let t = |rng: &mut ChaCha8Rng, a: f64, b: f64| (rng.random_range(a..b) * 1e9) as u64;
    let all = |f: Fault| vec![FaultWindow::new(f, 0, u64::MAX)];
    let mut sc = Scenario {
        seed: rng.random(),
        fd: rng.random_range(0..4) == 0,
        ..Scenario::default()
    };
    match k {
        0 => {
            sc.windows = all(Fault::Loss {
                rate: rng.random_range(0.001..0.03),
            })
        }
        1 => {
            sc.windows = all(Fault::Corrupt {
                rate: rng.random_range(0.001..0.03),
            })
        }
        2 => {
            sc.windows = all(Fault::Duplicate {
                rate: rng.random_range(0.01..0.2),
            })
        }
        3 => {
            sc.windows = all(Fault::Reorder {
                rate: rng.random_range(0.001..0.02),
            })
        }
        4 => {
            sc.windows = all(Fault::Delay {
                max_ns: rng.random_range(0..5 * MS),
            })
        }
        5 => {
            sc.windows = all(Fault::Jitter {
                max_ns: rng.random_range(0..100_000),
            })
        }
        6 => {
            let from = t(rng, 0.5, 4.5);
            sc.windows = vec![
                FaultWindow::new(
                    Fault::Late {
                        ns: rng.random_range(MS..200 * MS),
                    },
                    from,
                    from + 100 * MS,
                )
                .on_ids(0x020..=0x020),
            ]
        }
        7 => {
            sc.windows = vec![
                FaultWindow::new(Fault::Loss { rate: 1.0 }, t(rng, 0.5, 4.5), u64::MAX)
                    .on_ids(0x020..=0x020),
            ]
        }
        8 => {
            let from = t(rng, 0.1, 4.5);
            let station = rng.random_range(0..4);
            sc.windows = vec![FaultWindow::new(
                Fault::BusOff { station },
                from,
                from + rng.random_range(10 * MS..600 * MS),
            )]
        }
        9 => {
            let from = t(rng, 0.1, 4.5);
            sc.windows = vec![FaultWindow::new(
                Fault::Babble {
                    id: rng.random_range(0x001..0x020),
                },
                from,
                from + rng.random_range(10 * MS..600 * MS),
            )]
        }
        10 => sc.burst_ns = Some(t(rng, 0.3, 4.0)),
        11 => sc.host_killed_ns = Some(t(rng, 0.1, 4.5)),
        12 => sc.node_reset = Some((rng.random_range(0..3), t(rng, 0.5, 4.5))),
        13 => sc.bad_segment = Some(BadSegment::Limits(rng.random_range(1..9))),
        14 => sc.bad_segment = Some(BadSegment::Kink(rng.random_range(1..9))),
        15 => {
            sc.brakes = true;
            sc.host_killed_ns = Some(t(rng, 0.1, 4.5));
        }
        16 | 17 => {
            let from = t(rng, 0.5, 4.5);
            let sign = if rng.random_range(0..2) == 0 {
                -1.0
            } else {
                1.0
            };
            sc.push = Some((
                rng.random_range(0..3),
                from,
                from + rng.random_range(20 * MS..200 * MS),
                sign * rng.random_range(3.0..8.0),
            ));
            sc.brakes = k == 17;
        }
        18 => {
            sc.brakes = true;
            let how = if rng.random_range(0..2) == 0 {
                Miswired::Direction
            } else {
                Miswired::Scale(1.0 / 32.0)
            };
            sc.miswired = Some((rng.random_range(0..3), how));
        }
        19 => sc.miswired = Some((rng.random_range(0..3), Miswired::Scale(32.0))),
        20 => {
            sc.above_ceiling = Some(AboveCeiling::Segment(
                rng.random_range(0..3),
                rng.random_range(0.5..0.98),
            ))
        }
        21 => sc.above_ceiling = Some(AboveCeiling::OverrideCap(rng.random_range(1.0..1.1))),
        22 => sc.above_ceiling = Some(AboveCeiling::StopRamp(rng.random_range(0.01..0.3))),
        LATE => sc.above_ceiling = Some(AboveCeiling::Segment(0, rng.random_range(LATE_RANGE))),
        _ => {
            sc.above_ceiling = Some(AboveCeiling::Locked(
                rng.random_range(0..3),
                rng.random_range(0.5..0.98),
            ))
        }
    }
    sc
}

#[derive(Default)]
struct Row {
    trials: u32,
    endings: BTreeMap<Ending, u32>,
    corrupted: usize,
    panics: u32,
    worst_stop_ns: u64,
    worst_e2s_ticks: f64,
    worst_lost_sync_ns: u64,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2).max(1);
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2026);
    let plans: [Plan; 2] = [
        testplan::paper_case1().expect("case I"),
        testplan::paper_case2().expect("case II"),
    ];
    let late = late_plan();
    // Every late ceiling refuses a segment the first queue fill does not hold.
    let late_first = [LATE_RANGE.start, LATE_RANGE.end].map(|f| first_above(&late, f));
    assert!(
        late_first
            .iter()
            .all(|k| k.is_some_and(|k| k >= QUEUE_CAPACITY)),
        "{late_first:?}"
    );
    let started = Instant::now();
    // Hide the panic messages of caught panics from the table.
    std::panic::set_hook(Box::new(|_| {}));
    let results: Vec<(usize, Option<RunReport>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|th| {
                let (plans, late) = (&plans, &late);
                s.spawn(move || {
                    let mut out = Vec::new();
                    for i in (th..n).step_by(threads) {
                        let mut rng = ChaCha8Rng::seed_from_u64(
                            seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
                        );
                        let k = i % KINDS.len();
                        let sc = schedule(k, &mut rng);
                        let plan = if k == LATE {
                            late
                        } else {
                            &plans[(i / KINDS.len()) % 2]
                        };
                        let r = catch_unwind(AssertUnwindSafe(|| run(plan, &sc))).ok();
                        match r.as_ref().and_then(|x| x.fault_run.as_ref()) {
                            Some(f) if f.ending != Ending::Unsafe => {}
                            _ => eprintln!("schedule {i} ({}): {sc:?}\n  -> {r:?}", KINDS[k].0),
                        }
                        out.push((k, r));
                    }
                    out
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let _ = std::panic::take_hook();
    let mut rows: Vec<Row> = (0..KINDS.len()).map(|_| Row::default()).collect();
    for (k, r) in &results {
        let row = &mut rows[*k];
        row.trials += 1;
        let Some((report, r)) = r.as_ref().and_then(|x| Some((x, x.fault_run.as_ref()?))) else {
            row.panics += 1;
            continue;
        };
        *row.endings.entry(r.ending).or_default() += 1;
        row.corrupted += r.corrupted_executions;
        if r.ending == Ending::Stopped {
            let stop_ns = report.stop_s.map_or(0, |t| (t * 1e9).round() as u64);
            row.worst_stop_ns = row.worst_stop_ns.max(stop_ns);
        }
        if let Some(t) = r.emergency_to_stop_ticks {
            row.worst_e2s_ticks = row.worst_e2s_ticks.max(t);
        }
        if let (Some(a), Some(b)) = (r.last_sync_ns, r.lost_sync_ns)
            && *k == 7
        {
            row.worst_lost_sync_ns = row.worst_lost_sync_ns.max(b.saturating_sub(a));
        }
    }
    let secs = started.elapsed().as_secs_f64();
    println!(
        "fault soak: {n} seeded schedules (seed {seed}) over paper cases I and II, 1 kHz control, {threads} threads, {secs:.1} s\n"
    );
    println!(
        "| fault | rate / parameter | trials | completed | stopped | not started | unsafe | panics | corrupted executions | worst stop (ms) | worst emergency→stop (ticks) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut bad = 0;
    for (k, row) in rows.iter().enumerate() {
        let e = |x: Ending| row.endings.get(&x).copied().unwrap_or(0);
        bad += e(Ending::Unsafe) as usize + row.panics as usize + row.corrupted;
        // The late refusal is the point of its row: it must come while Running.
        if k == LATE {
            bad += (e(Ending::NotStarted) + e(Ending::Completed)) as usize;
        }
        let mut name = KINDS[k].0.to_string();
        if k == 7 && row.worst_lost_sync_ns > 0 {
            name = format!(
                "{name} (detected ≤ {:.0} ms after the last sync)",
                row.worst_lost_sync_ns as f64 * 1e-6
            );
        }
        println!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            KINDS[k].1,
            row.trials,
            e(Ending::Completed),
            e(Ending::Stopped),
            e(Ending::NotStarted),
            e(Ending::Unsafe),
            row.panics,
            row.corrupted,
            if row.worst_stop_ns > 0 {
                format!("{:.0}", row.worst_stop_ns as f64 * 1e-6)
            } else {
                "–".into()
            },
            if row.worst_e2s_ticks > 0.0 {
                format!("{:.2}", row.worst_e2s_ticks)
            } else {
                "–".into()
            },
        );
    }
    println!(
        "\n{}: first segment above the ceiling {}–{} of {} (queue {QUEUE_CAPACITY}), from the exact maxima",
        KINDS[LATE].0,
        late_first[0].map_or(0, |k| k + 1),
        late_first[1].map_or(0, |k| k + 1),
        late.segments.len()
    );
    if bad > 0 {
        eprintln!("fault soak: {bad} unsafe endings, panics or corrupted executions");
        std::process::exit(1);
    }
}
