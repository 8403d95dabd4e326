//! Global search over the intervals: deterministic multistart of the
//! trust-region step (coarse from the starts in batches until two agree on
//! the best point, then to convergence for the best few: to 1e-10; where
//! they can only be min-time's shapes, the coarse results are the shapes).

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use std::cell::Cell;

use crate::coarse_start::{coarse_starts, window_start};
use crate::inner::{Method, ROUNDS};
use crate::options::{Options, Stage};
use crate::problem::{Problem, Solution};
use crate::time_scaling::{scaled_shape, within_bounds};
use crate::workers::parallel;

/// The best solution and how it was found.
#[derive(Clone, Debug)]
pub(crate) struct SearchResult {
    pub(crate) best: Solution,
    /// The refined local optima, best first (`best` is the first).
    pub(crate) shapes: Vec<Solution>,
    pub(crate) starts: usize,
    pub(crate) lp_solves: u64,
    /// The starts ended at a refined agreement where the plan's rule
    /// ([`refined_agreement`]) runs on: the best may then be a local
    /// optimum a further start would better, not the global one.
    pub(crate) ended_early: bool,
    /// What [`relaxed_shapes`] gives for the problem (min-time descends
    /// from it; a search that ran further gives min-time other shapes).
    pub(crate) as_shapes: bool,
    /// Its shapes are only as far along as shapes need (the coarse
    /// results, [`SHAPE_TOL`]): the best then bounds nothing exactly.
    pub(crate) loose: bool,
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

/// Refined starts: the best few coarse results are driven to convergence
/// (to the multistart's refinement tolerance).
const REFINE: usize = 3;
/// Relative gain per step that ends a refinement.
pub(crate) const REFINE_TOL: f64 = 1e-10;
/// [`REFINE_TOL`] of a relaxation whose best can only be a shape: one that,
/// time-scaled to its jerk limit, still breaks another limit by
/// [`SHAPE_MARGIN`] is neither the plan nor min-time's answer, only where
/// the full search and min-time's descent start, and those do not need
/// it to the last digits. The coarse searches' own tolerance: such a
/// shape is the coarse result as it is.
const SHAPE_TOL: f64 = COARSE_TOL;
/// Relative gain per step that ends a coarse search.
const COARSE_TOL: f64 = 1e-5;
/// Relative violation of a limit other than jerk that makes a relaxation's
/// best a shape alone ([`SHAPE_TOL`]).
const SHAPE_MARGIN: f64 = 0.01;
/// Relative distance below which two coarse results are the same point.
const AGREE: f64 = 1e-4;
/// Coarse searches run in batches of this many starts.
const BATCH: usize = 2;
/// Starts that must agree on the best point before the rest are skipped.
const AGREEING: usize = 2;
/// Above this many knots (and on the full problem, at any size) two coarse
/// results that do not agree are refined and compared before more starts
/// run. Below it the jerk-only relaxation's starts are cheap, and where
/// its optimum is the plan they run until two coarse results agree (only
/// the shapes it gives min-time and the full search end at the first
/// refined agreement: docs/planner-speed.md).
const REFINED_AGREEMENT_KNOTS: usize = 64;

/// Multistart global search for min-max jerk at the problem's total time.
///
/// The jerk-only relaxation is searched first: its LPs are a fraction of the
/// size (no velocity, acceleration or torque rows) and exact in one solve.
/// Its global optimum bounds the problem's from below, so when it meets
/// every other limit it is the answer; otherwise the full problem is
/// searched, from the relaxation's optimum and the same starts.
#[cfg(any(test, feature = "evolution"))]
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
        // The relaxation's global optimum bounds the jerk from below: when
        // even it breaks the jerk limit no plan at this total time meets
        // it, and the full search would only confirm that. A search that
        // ended early bounds nothing.
        if !p.jerk_only && !r.ended_early && !r.loose && r.best.jerk > p.limits.jerk * (1.0 + 1e-9)
        {
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
pub(crate) const REFERENCE_S_PER_SEGMENT: f64 = 0.5;

/// How far the relaxation's multistart goes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Reach {
    /// Its starts end at the first refined agreement: it only starts a
    /// finer path's search or min-time's descent.
    Shapes,
    /// As [`Reach::Shapes`] while its best point breaks another limit of
    /// the problem (its shapes then only start the full problem's search
    /// and min-time); where it meets them it is the plan, and the starts
    /// run as [`refined_agreement`] has them (until two coarse results
    /// agree, on up to 64 knots).
    Answer,
}

/// The jerk-only relaxation's global optimum at the problem's total time T,
/// searched at a reference time (0.5 s a segment) and time-scaled to T.
/// Exact: a shape's jerk scales as T⁻³, so the relaxation's optimum at any
/// T is one shape; searched at T itself the search's absolute tolerances
/// would make it depend on T (docs/planner-speed.md). Searched at T when
/// the scaled intervals leave [h_min, h_max].
pub(crate) fn relaxed_global(p: &Problem, opts: &Options) -> Option<SearchResult> {
    relaxed_search(p, opts, Reach::Answer)
}

/// The relaxation's shapes for min-time: [`relaxed_global`] with its
/// starts ending at the first refined agreement (min-time descends from
/// its shapes; it is never the answer).
pub(crate) fn relaxed_shapes(p: &Problem, opts: &Options) -> Option<SearchResult> {
    relaxed_search(p, opts, Reach::Shapes)
}

fn relaxed_search(p: &Problem, opts: &Options, reach: Reach) -> Option<SearchResult> {
    let target = p.relaxed();
    let t_ref = REFERENCE_S_PER_SEGMENT * p.knots.segments() as f64;
    if (t_ref - p.total_time).abs() <= 1e-12 * p.total_time {
        return relaxed_at(p, &target, opts, reach, Some).flatten();
    }
    let reference = target.retimed(t_ref);
    match relaxed_at(p, &reference, opts, reach, |r| time_scaled(p, &target, r))? {
        Some(r) => Some(r),
        // Searched at T itself when the scaled intervals leave the bounds.
        None => relaxed_at(p, &target, opts, reach, Some).flatten(),
    }
}

/// The relaxation's search on `q` (the relaxation of `p` at some total
/// time), its result taken to `p`'s time by `to_p`. None when the search
/// found nothing, Some(None) when `to_p` refused its result.
fn relaxed_at(
    p: &Problem,
    q: &Problem,
    opts: &Options,
    reach: Reach,
    to_p: impl Fn(SearchResult) -> Option<SearchResult>,
) -> Option<Option<SearchResult>> {
    // Whether `s`, time-scaled to p's time, meets every limit of p: then
    // the relaxation is p's plan.
    let is_plan = |s: &Solution| {
        let (h, x) = scaled_shape(s, p.total_time);
        p.accept_relaxed(&Solution { h, x, ..s.clone() }).is_some()
    };
    // Whether `s` can only be a shape for min-time: time-scaled to its
    // jerk limit it breaks another limit by the margin (so no time meets
    // only the jerk limit's bound). It depends on the shape alone, not on
    // p's time, so min-time gets the same shapes whatever time a job asks.
    let only_shape = |s: &Solution| {
        let t_jerk = s.h.iter().sum::<f64>() * (s.jerk / p.limits.jerk).cbrt();
        let (h, x) = scaled_shape(s, t_jerk);
        p.evaluate(&h, &x).violation > SHAPE_MARGIN
    };
    // The refinement a batch whose best coarse point is `best` may end the
    // starts with at a refined agreement (None: it may not); a Shapes
    // search always may.
    let went_further = Cell::new(false);
    let may_end_early = |best: &Solution| {
        let may = reach == Reach::Shapes || refined_agreement(q) || !is_plan(best);
        went_further.set(went_further.get() || !may);
        may.then(|| {
            if only_shape(best) {
                SHAPE_TOL
            } else {
                REFINE_TOL
            }
        })
    };
    let mut search = searched(q, opts, &may_end_early);
    loop {
        let mut r = search.result()?;
        // A best refined for a shape that turns out more (within the
        // margin, or p's plan: the answer) is refined on.
        if r.loose && (!only_shape(&r.best) || (reach == Reach::Answer && is_plan(&r.best))) {
            search.tighten();
            continue;
        }
        // A best point the coarse results did not show to be the plan
        // may still be: then the rest of the starts run.
        if search.ended == Ended::RefinedAgreement && may_end_early(&r.best).is_none() {
            search.tighten();
            search.run(&|_| None);
            continue;
        }
        r.ended_early = search.ended == Ended::RefinedAgreement && !refined_agreement(q);
        r.as_shapes = !went_further.get();
        return Some(to_p(r));
    }
}

/// The reference time's result time-scaled to `p`'s total time (the shapes
/// evaluated, not re-solved: C3 and the rest ends are homogeneous in
/// time, so it is exact); None when a scaled interval leaves the bounds.
fn time_scaled(p: &Problem, target: &Problem, r: SearchResult) -> Option<SearchResult> {
    let within = |s: &Solution| s.h.iter().all(|&h| h >= p.h_min && h <= p.h_max);
    let shapes: Vec<Solution> = r
        .shapes
        .iter()
        .map(|s| {
            let (h, x) = scaled_shape(s, p.total_time);
            Solution {
                lp_solves: 0,
                ..target.evaluate(&h, &x)
            }
        })
        .collect();
    if !shapes.iter().all(within) {
        return None;
    }
    Some(SearchResult {
        best: shapes.first()?.clone(),
        shapes,
        ..r
    })
}

/// The jerk-only problem `p`'s multistart search: a long path from its
/// coarser path's optima ([`coarse_starts`], whose own search ends at the
/// first refined agreement), or where that path does not trace it from
/// its windows' ([`window_start`]), else from [`start_points`]; run until
/// `refined_agreement` of the best coarse point lets a refined agreement end it.
fn searched<'a>(
    p: &'a Problem,
    opts: &'a Options,
    refined_agreement: &dyn Fn(&Solution) -> Option<f64>,
) -> Multistart<'a> {
    let (starts, coarse_solves) = coarse_starts(p, |c| {
        relaxed_search(c, opts, Reach::Shapes).map(|r| (r.shapes, r.lp_solves))
    })
    .or_else(|| {
        window_start(p, |windows| {
            parallel(windows, opts.threads, |w| window_optimum(w, opts))
        })
    })
    .unwrap_or_else(|| (start_points(p, opts.starts, opts.seed), 0));
    let mut search = Multistart::new(p, starts, opts);
    search.extra_solves = coarse_solves;
    search.run(refined_agreement);
    search
}

/// Trust-region steps of a window's search, and the relative gain below
/// which it stops: the window's optimum only places the long path's start.
const WINDOW_STEPS: usize = 16;
const WINDOW_TOL: f64 = 1e-3;

/// A window's near-optimum for [`window_start`]: one search from the
/// travel-proportional start, a few steps long.
fn window_optimum(w: &Problem, opts: &Options) -> Option<Solution> {
    let h = start_points(w, 2, opts.seed).pop()?;
    let first = w.inner(&h, &w.zero_x(), Method::Direct, ROUNDS)?;
    Some(w.local_search(&first, WINDOW_STEPS, WINDOW_TOL))
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
    let mut search = Multistart::new(p, starts.to_vec(), opts);
    search.run(&|_| refined_agreement.then_some(REFINE_TOL));
    search.result()
}

/// What ended a multistart's batches.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Ended {
    /// Not run yet.
    NotRun,
    /// Two coarse results reached the best point: more starts would find it again.
    CoarseAgreement,
    /// Two refined results agreed in merit: further starts could still
    /// find a better point, and [`Multistart::run`] may go on.
    RefinedAgreement,
    /// Every start ran.
    Starts,
}

/// A multistart search of the trust-region step: coarse searches from the
/// starts in fixed batches (the plan must not depend on the thread count)
/// until two reach the best point so far, then the best few refined to
/// convergence (to 1e-10; where its caller asks only for shapes, the
/// coarse results as they are, [`Multistart::tighten`] taking them on).
/// It can stop early, at the first two refined results that agree, and go
/// on from there: it then runs the starts a search run on from the
/// beginning would, and keeps every shape refined so far, so its best is
/// at least as good as that search's.
pub(crate) struct Multistart<'a> {
    p: &'a Problem,
    opts: &'a Options,
    starts: Vec<Vec<f64>>,
    coarse: Vec<Option<Solution>>,
    refined: Vec<Option<Solution>>,
    ended: Ended,
    /// Solves spent before the starts (a coarser path's search).
    extra_solves: u64,
    /// Solves spent re-solving shapes, by every [`Multistart::result`].
    resolves: u64,
    /// The relative gain that ends a refinement.
    refine_tol: f64,
}

impl<'a> Multistart<'a> {
    pub(crate) fn new(p: &'a Problem, starts: Vec<Vec<f64>>, opts: &'a Options) -> Self {
        Multistart {
            p,
            opts,
            starts,
            coarse: Vec::new(),
            refined: Vec::new(),
            ended: Ended::NotRun,
            extra_solves: 0,
            resolves: 0,
            refine_tol: REFINE_TOL,
        }
    }

    fn merit(&self, s: &Solution) -> f64 {
        s.merit(self.p.weight)
    }

    fn same_merit(&self, a: &Solution, b: &Solution) -> bool {
        (self.merit(a) - self.merit(b)).abs() <= AGREE * self.merit(a).abs()
    }

    /// Starts that reached the same point (same intervals, same merit) are
    /// one basin: only the first of them is refined.
    fn same(&self, a: &Solution, b: &Solution) -> bool {
        self.same_merit(a, b)
            && a.h
                .iter()
                .zip(&b.h)
                .all(|(x, y)| (x - y).abs() <= AGREE * x.abs())
    }

    /// The coarse results' indices, best merit first (ties in start order).
    fn by_merit(&self) -> Vec<usize> {
        let c = &self.coarse;
        let mut order: Vec<usize> = (0..c.len()).filter(|&i| c[i].is_some()).collect();
        order.sort_by(|&a, &b| {
            let (ma, mb) = (
                c[a].as_ref().map_or(f64::INFINITY, |s| self.merit(s)),
                c[b].as_ref().map_or(f64::INFINITY, |s| self.merit(s)),
            );
            ma.total_cmp(&mb).then(a.cmp(&b))
        });
        order
    }

    fn refine_missing(&mut self, which: &[usize]) {
        self.refined.resize(self.coarse.len(), None);
        let todo: Vec<(usize, &Solution)> = which
            .iter()
            .copied()
            .filter(|&i| self.refined[i].is_none())
            .filter_map(|i| Some((i, self.coarse[i].as_ref()?)))
            .collect();
        for (i, r) in self.refine(&todo) {
            self.refined[i] = Some(r);
        }
    }

    /// Refinements from here on to [`REFINE_TOL`], and those already
    /// made to a looser one refined on to it.
    fn tighten(&mut self) {
        if self.refine_tol <= REFINE_TOL {
            return;
        }
        self.refine_tol = REFINE_TOL;
        let todo: Vec<(usize, &Solution)> = (self.refined.iter().enumerate())
            .filter_map(|(i, r)| Some((i, r.as_ref()?)))
            .collect();
        for (i, r) in self.refine(&todo) {
            self.refined[i] = Some(r);
        }
    }

    /// Each of `todo`'s points refined to the refinement tolerance, side
    /// by side, with its index; at the coarse searches' own tolerance or
    /// looser, the points as they are.
    fn refine(&self, todo: &[(usize, &Solution)]) -> Vec<(usize, Solution)> {
        let (p, tol) = (self.p, self.refine_tol);
        // The coarse searches ran to this tolerance (or to their step
        // cap): refining would mostly spend the region's shrinking again,
        // for a shape that only starts min-time's descent and the full
        // search.
        if tol >= COARSE_TOL {
            return todo.iter().map(|&(i, s)| (i, s.clone())).collect();
        }
        let done = parallel(todo, self.opts.threads, |(_, s)| {
            p.local_search(s, 400, tol)
        });
        todo.iter().map(|&(i, _)| i).zip(done).collect()
    }

    /// Runs the starts not yet run, batch by batch, until two coarse
    /// results reach the best point (or, where `refined_agreement` of the
    /// best coarse result gives a refinement tolerance, two results
    /// refined to it agree in merit). Coarse results a little apart may
    /// still reach one optimum (the
    /// `refined_agreement_keeps_the_optimum_of_every_start` test).
    pub(crate) fn run(&mut self, refined_agreement: &dyn Fn(&Solution) -> Option<f64>) {
        let p = self.p;
        // Two coarse results agreeing end the starts for good.
        if self.ended == Ended::CoarseAgreement {
            return;
        }
        self.ended = Ended::Starts;
        while self.coarse.len() < self.starts.len() {
            let from = self.coarse.len();
            let batch = &self.starts[from..(from + BATCH).min(self.starts.len())];
            let results = parallel(batch, self.opts.threads, |h| {
                let first = p.inner(h, &p.zero_x(), Method::Direct, ROUNDS)?;
                let sol = p.local_search(&first, 60, COARSE_TOL);
                if sol.violation == 0.0
                    && let Some(f) = p.shown_jerk
                {
                    p.run.offer_jerk(sol.jerk * f);
                }
                Some(sol)
            });
            self.coarse.extend(results);
            let order = self.by_merit();
            let Some(&best) = order.first() else {
                continue;
            };
            let Some(best_sol) = self.coarse[best].as_ref() else {
                continue;
            };
            let agreeing = order
                .iter()
                .filter(|&&i| {
                    self.coarse[i]
                        .as_ref()
                        .is_some_and(|s| self.same(best_sol, s))
                })
                .count();
            if agreeing >= AGREEING {
                self.ended = Ended::CoarseAgreement;
                return;
            }
            if let Some(tol) = refined_agreement(best_sol)
                && let [a, b, ..] = order[..]
            {
                if self.refined.iter().all(Option::is_none) {
                    self.refine_tol = tol;
                } else if tol < self.refine_tol {
                    self.tighten();
                }
                self.refine_missing(&[a, b]);
                // The merit alone: on long paths some intervals are nearly free
                // at the optimum, so refined results agree in merit long
                // before they agree in every interval.
                if let (Some(ra), Some(rb)) = (&self.refined[a], &self.refined[b])
                    && self.same_merit(ra, rb)
                {
                    self.ended = Ended::RefinedAgreement;
                    return;
                }
            }
        }
    }

    /// The best few distinct coarse results refined; every refined result
    /// is a shape, best first.
    pub(crate) fn result(&mut self) -> Option<SearchResult> {
        let p = self.p;
        let order = self.by_merit();
        if order.is_empty() {
            return None;
        }
        let mut chosen: Vec<usize> = Vec::with_capacity(REFINE);
        for &i in &order {
            let Some(s) = self.coarse[i].as_ref() else {
                continue;
            };
            if chosen.len() == REFINE {
                break;
            }
            if !chosen
                .iter()
                .any(|&c| self.coarse[c].as_ref().is_some_and(|t| self.same(s, t)))
            {
                chosen.push(i);
            }
        }
        self.refine_missing(&chosen);
        let mut lp_solves: u64 = self.extra_solves
            + self
                .coarse
                .iter()
                .flatten()
                .map(|s| s.lp_solves)
                .sum::<u64>();
        for (r, c) in self.refined.iter().zip(&self.coarse) {
            if let (Some(r), Some(c)) = (r, c) {
                lp_solves += r.lp_solves - c.lp_solves;
            }
        }
        // Every refined result is a shape (those refined for the agreement
        // check too), in the starts' order before the sort below.
        let refined: Vec<Solution> = self.refined.iter().flatten().cloned().collect();
        // The direct jerk-only solve puts every joint at its own optimum; the
        // shapes' knot derivatives are re-solved by the interior-point method,
        // whose non-binding joints sit central (their velocities and
        // accelerations decide what the full problem and min-time make of them).
        // Each shape's re-solve is independent of the others': they run
        // side by side.
        let refined: Vec<Solution> = if p.jerk_only {
            let resolved = parallel(&refined, self.opts.threads, |s| {
                p.inner(&s.h, &s.x, Method::CuttingPlanes, 1)
            });
            refined
                .into_iter()
                .zip(resolved)
                .map(|(s, c)| match c {
                    Some(c) => {
                        self.resolves += c.lp_solves;
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
        // An earlier result's re-solves count too (the search went on after it).
        lp_solves += self.resolves;
        // Best first; the sort is stable, so equal merits keep the starts' order.
        let mut shapes = refined;
        shapes.sort_by(|a, b| self.merit(a).total_cmp(&self.merit(b)));
        Some(SearchResult {
            best: shapes.first()?.clone(),
            shapes,
            starts: self.coarse.len(),
            lp_solves,
            ended_early: self.ended == Ended::RefinedAgreement,
            as_shapes: false,
            loose: self.refine_tol > REFINE_TOL,
        })
    }
}
