//! Global search over the intervals: deterministic multistart of the
//! trust-region step (coarse from the starts in batches until two agree on
//! the best point, then to convergence for the best few).

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::coarse_start::coarse_starts;
use crate::inner::{Method, ROUNDS};
use crate::options::{Options, Stage};
use crate::problem::{Problem, Solution};
use crate::time_scaling::{scaled_x, within_bounds};

/// The best solution and how it was found.
#[derive(Clone, Debug)]
pub(crate) struct SearchResult {
    pub(crate) best: Solution,
    /// The refined local optima, best first (`best` is the first).
    pub(crate) shapes: Vec<Solution>,
    pub(crate) starts: usize,
    pub(crate) lp_solves: u64,
}

/// SplitMix64: a tiny, portable, seeded generator (the plan must not depend
/// on a library's stream changing between versions).
pub(crate) struct SplitMix(pub(crate) u64);

impl SplitMix {
    pub(crate) fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Interval sets summing to the total time: uniform, proportional to the
/// largest joint travel, to its square root, then seeded random (Dirichlet(1)).
pub(crate) fn start_points(p: &Problem, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let nseg = p.knots.segments();
    let travel: Vec<f64> = (0..nseg)
        .map(|k| {
            (0..3)
                .map(|j| (p.knots.q[k + 1][j] - p.knots.q[k][j]).abs())
                .fold(1e-6, f64::max)
        })
        .collect();
    let mut rng = SplitMix(seed);
    let mut out = vec![
        vec![1.0; nseg],
        travel.clone(),
        travel.iter().map(|t| t.sqrt()).collect(),
    ];
    while out.len() < n {
        out.push(
            (0..nseg)
                .map(|_| -(1.0 - rng.next_f64()).ln() + 0.05)
                .collect(),
        );
    }
    out.truncate(n.max(1));
    for h in &mut out {
        let sum: f64 = h.iter().sum();
        h.iter_mut().for_each(|x| *x *= p.total_time / sum);
        within_bounds(h, p.h_min, p.h_max);
    }
    out
}

/// Runs `f` on every item with `threads` workers; results keep the items' order.
pub(crate) fn parallel<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..threads.max(1).min(items.len().max(1)) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    let r = f(item);
                    if let Ok(mut slot) = slots[i].lock() {
                        *slot = Some(r);
                    }
                }
            });
        }
    });
    slots
        .into_iter()
        .filter_map(|m| m.into_inner().ok().flatten())
        .collect()
}

/// Refined starts: the best few coarse results are driven to convergence.
const REFINE: usize = 3;
/// Relative distance below which two coarse results are the same point.
const AGREE: f64 = 1e-4;
/// Coarse searches run in batches of this many starts.
const BATCH: usize = 2;
/// Starts that must agree on the best point before the rest are skipped.
const AGREEING: usize = 2;
/// Above this many knots (and on the full problem, at any size) two coarse
/// results that do not agree are refined and compared before more starts
/// run. Below it the jerk-only relaxation's starts are cheap and the
/// further starts' shapes help min-time (docs/planner-speed.md).
const REFINED_AGREEMENT_KNOTS: usize = 64;

/// Multistart global search for min-max jerk at the problem's total time.
///
/// The jerk-only relaxation is searched first: its LPs are a fraction of the
/// size (no velocity, acceleration or torque rows) and exact in one solve.
/// Its global optimum bounds the problem's from below, so when it meets
/// every other limit it is the answer; otherwise the full problem is
/// searched, from the relaxation's optimum and the same starts.
pub(crate) fn global(p: &Problem, opts: &Options) -> Option<SearchResult> {
    global_from(p, opts, relaxed_global(p, opts))
}

/// [`global`] from the relaxation's search result, already known.
pub(crate) fn global_from(
    p: &Problem,
    opts: &Options,
    relaxed: Option<SearchResult>,
) -> Option<SearchResult> {
    let mut starts = start_points(p, opts.starts, opts.seed);
    let mut lp_solves = 0;
    if let Some(r) = relaxed {
        if let Some(best) = p.accept_relaxed(&r.best) {
            return Some(SearchResult { best, ..r });
        }
        // The relaxation bounds the jerk from below: when even it breaks the
        // jerk limit no plan at this total time meets it, and the full
        // search would only confirm that.
        if !p.jerk_only && r.best.jerk > p.limits.jerk * (1.0 + 1e-9) {
            let best = Solution {
                lp_solves: r.best.lp_solves,
                ..p.evaluate(&r.best.h, &r.best.x)
            };
            return Some(SearchResult { best, ..r });
        }
        lp_solves = r.lp_solves;
        starts.insert(0, r.best.h);
    }
    if p.run.progress().stage == Stage::Searching {
        p.run.set_stage(Stage::LimitsBind);
    }
    let mut r = multistart(p, &starts, opts)?;
    r.lp_solves += lp_solves;
    Some(r)
}

/// Seconds per segment of the reference time at which the relaxation is searched.
const REFERENCE_S_PER_SEGMENT: f64 = 0.5;

/// The jerk-only relaxation's global optimum at the problem's total time T,
/// searched at a reference time (0.5 s a segment) and time-scaled to T.
/// Exact: a shape's jerk scales as T⁻³, so the relaxation's optimum at any
/// T is one shape; searched at T itself the search's absolute tolerances
/// would make it depend on T (docs/planner-speed.md). Searched at T when
/// the scaled intervals leave [h_min, h_max].
pub(crate) fn relaxed_global(p: &Problem, opts: &Options) -> Option<SearchResult> {
    relaxed_search(p, opts, false)
}

/// [`relaxed_global`]; `for_starts` when the result only starts a finer
/// path's search: then its starts end at the first refined agreement
/// whatever the path's length.
fn relaxed_search(p: &Problem, opts: &Options, for_starts: bool) -> Option<SearchResult> {
    let target = p.relaxed();
    let direct = || searched(&target, opts, for_starts);
    let t_ref = REFERENCE_S_PER_SEGMENT * p.knots.segments() as f64;
    if (t_ref - p.total_time).abs() <= 1e-12 * p.total_time {
        return direct();
    }
    let reference = target.retimed(t_ref);
    let r = searched(&reference, opts, for_starts)?;
    let within = |s: &Solution| s.h.iter().all(|&h| h >= p.h_min && h <= p.h_max);
    let shapes: Vec<Solution> = r
        .shapes
        .iter()
        .map(|s| {
            // The same shape in time-scaled form, evaluated, not re-solved:
            // C3 and the rest ends are homogeneous in time, so it is exact.
            let alpha = p.total_time / s.h.iter().sum::<f64>();
            let h: Vec<f64> = s.h.iter().map(|x| x * alpha).collect();
            Solution {
                lp_solves: 0,
                ..target.evaluate(&h, &scaled_x(&s.x, alpha))
            }
        })
        .collect();
    if !shapes.iter().all(within) {
        return direct();
    }
    let lp_solves = r.lp_solves;
    Some(SearchResult {
        best: shapes.first()?.clone(),
        shapes,
        lp_solves,
        starts: r.starts,
    })
}

/// The jerk-only problem `p`'s multistart search: a long path from its
/// coarser path's optima ([`coarse_starts`], whose own search ends at the
/// first refined agreement), else from [`start_points`].
fn searched(p: &Problem, opts: &Options, for_starts: bool) -> Option<SearchResult> {
    let (starts, coarse_solves) = coarse_starts(p, |c| {
        relaxed_search(c, opts, true).map(|r| (r.shapes, r.lp_solves))
    })
    .unwrap_or_else(|| (start_points(p, opts.starts, opts.seed), 0));
    let refined_agreement = for_starts || refined_agreement(p);
    let mut r = multistart_with(p, &starts, opts, refined_agreement)?;
    r.lp_solves += coarse_solves;
    Some(r)
}

fn multistart(p: &Problem, starts: &[Vec<f64>], opts: &Options) -> Option<SearchResult> {
    multistart_with(p, starts, opts, refined_agreement(p))
}

/// Where a limit other than jerk binds, a coarse search costs hundreds of
/// solves: the refined agreement spares the further starts
/// (docs/planner-speed.md has what it saves).
fn refined_agreement(p: &Problem) -> bool {
    p.knots.len() > REFINED_AGREEMENT_KNOTS || !p.jerk_only
}

/// [`multistart`]; `refined_agreement` lets two refined results that
/// agree end the starts.
pub(crate) fn multistart_with(
    p: &Problem,
    starts: &[Vec<f64>],
    opts: &Options,
    refined_agreement: bool,
) -> Option<SearchResult> {
    let merit = |s: &Solution| s.merit(p.weight);
    // Starts that reached the same point (same intervals, same merit) are
    // one basin: only the first of them is refined.
    let same_merit =
        |a: &Solution, b: &Solution| (merit(a) - merit(b)).abs() <= AGREE * merit(a).abs();
    let same = |a: &Solution, b: &Solution| {
        same_merit(a, b)
            && a.h
                .iter()
                .zip(&b.h)
                .all(|(x, y)| (x - y).abs() <= AGREE * x.abs())
    };
    let refine = |s: &Solution| p.local_search(s, 400, 1e-10);
    // Coarse searches in fixed batches (the plan must not depend on the
    // thread count), stopping once the best point so far has been reached
    // from enough starts: more starts would only find it again. Coarse
    // results a little apart may still reach one optimum (the
    // `refined_agreement_keeps_the_optimum_of_every_start` test), so on
    // large jobs the two best are refined and compared when they do not
    // agree: refined results of the same merit end the starts.
    let mut coarse: Vec<Option<Solution>> = Vec::with_capacity(starts.len());
    let mut refined: Vec<Option<Solution>> = Vec::with_capacity(starts.len());
    let by_merit = |coarse: &[Option<Solution>]| {
        let mut order: Vec<usize> = (0..coarse.len()).filter(|&i| coarse[i].is_some()).collect();
        order.sort_by(|&a, &b| {
            let (ma, mb) = (
                coarse[a].as_ref().map_or(f64::INFINITY, merit),
                coarse[b].as_ref().map_or(f64::INFINITY, merit),
            );
            ma.total_cmp(&mb).then(a.cmp(&b))
        });
        order
    };
    let refine_missing =
        |coarse: &[Option<Solution>], refined: &mut Vec<Option<Solution>>, which: &[usize]| {
            refined.resize(coarse.len(), None);
            let todo: Vec<usize> = which
                .iter()
                .copied()
                .filter(|&i| refined[i].is_none())
                .collect();
            let done = parallel(&todo, opts.threads, |&i| coarse[i].as_ref().map(refine));
            for (i, r) in todo.into_iter().zip(done) {
                refined[i] = r;
            }
        };
    for batch in starts.chunks(BATCH) {
        coarse.extend(parallel(batch, opts.threads, |h| {
            let first = p.inner(h, &p.zero_x(), Method::Direct, ROUNDS)?;
            let sol = p.local_search(&first, 60, 1e-5);
            if sol.violation == 0.0
                && let Some(f) = p.shown_jerk
            {
                p.run.offer_jerk(sol.jerk * f);
            }
            Some(sol)
        }));
        let order = by_merit(&coarse);
        let Some(&best) = order.first() else {
            continue;
        };
        let best_sol = coarse[best].as_ref()?;
        let agreeing = order
            .iter()
            .filter(|&&i| coarse[i].as_ref().is_some_and(|s| same(best_sol, s)))
            .count();
        if agreeing >= AGREEING {
            break;
        }
        if refined_agreement && let [a, b, ..] = order[..] {
            refine_missing(&coarse, &mut refined, &[a, b]);
            // The merit alone: on long paths some intervals are nearly free
            // at the optimum, so refined results agree in merit long
            // before they agree in every interval.
            if let (Some(ra), Some(rb)) = (&refined[a], &refined[b])
                && same_merit(ra, rb)
            {
                break;
            }
        }
    }
    let order = by_merit(&coarse);
    if order.is_empty() {
        return None;
    }
    let mut chosen: Vec<usize> = Vec::with_capacity(REFINE);
    for &i in &order {
        let Some(s) = coarse[i].as_ref() else {
            continue;
        };
        if chosen.len() == REFINE {
            break;
        }
        if !chosen
            .iter()
            .any(|&c| coarse[c].as_ref().is_some_and(|t| same(s, t)))
        {
            chosen.push(i);
        }
    }
    refine_missing(&coarse, &mut refined, &chosen);
    let mut lp_solves: u64 = coarse.iter().flatten().map(|s| s.lp_solves).sum();
    for (r, c) in refined.iter().zip(&coarse) {
        if let (Some(r), Some(c)) = (r, c) {
            lp_solves += r.lp_solves - c.lp_solves;
        }
    }
    // Every refined result is a shape (those refined for the agreement
    // check too), in the starts' order before the sort below.
    let refined: Vec<Solution> = refined.into_iter().flatten().collect();
    // The direct jerk-only solve puts every joint at its own optimum; the
    // shapes' knot derivatives are re-solved by the interior-point method,
    // whose non-binding joints sit central (their velocities and
    // accelerations decide what the full problem and min-time make of them).
    let refined: Vec<Solution> = if p.jerk_only {
        refined
            .into_iter()
            .map(|s| match p.inner(&s.h, &s.x, Method::CuttingPlanes, 1) {
                Some(c) => {
                    lp_solves += c.lp_solves;
                    Solution {
                        lp_solves: s.lp_solves + c.lp_solves,
                        ..c
                    }
                }
                None => s,
            })
            .collect()
    } else {
        refined
    };
    // Best first; the sort is stable, so equal merits keep the starts' order.
    let mut shapes = refined;
    shapes.sort_by(|a, b| merit(a).total_cmp(&merit(b)));
    Some(SearchResult {
        best: shapes.first()?.clone(),
        shapes,
        starts: coarse.len(),
        lp_solves,
    })
}
