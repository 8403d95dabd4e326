//! The search's side of observation: counters the observer reads, and the
//! cancel flag every linear program checks before it runs.

use std::cell::{Cell, RefCell};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::error::CancelReason;
use crate::options::{Progress, Stage};

thread_local! {
    /// Solves on this thread held back from the run's count ([`held_solves`]).
    static HELD: Cell<Option<u64>> = const { Cell::new(None) };
    /// Set once this thread's work is no longer wanted ([`abandonable`]).
    static ABANDONED: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// Runs `f` on this thread refusing every program once `abandoned` is
/// set (as a cancelled run does), for work whose result may not be wanted.
pub(crate) fn abandonable<R>(abandoned: Arc<AtomicBool>, f: impl FnOnce() -> R) -> R {
    let before = ABANDONED.with(|a| a.replace(Some(abandoned)));
    let r = f();
    ABANDONED.with(|a| a.replace(before));
    r
}

/// Runs `f` with the solves it makes on this thread held back from the
/// run's count, and returns them: work that may be thrown away (a trial
/// solved ahead) is counted only once it is used
/// ([`RunState::count_solves`]), so the plan's count is the search's own.
pub(crate) fn held_solves<R>(f: impl FnOnce() -> R) -> (R, u64) {
    let before = HELD.with(|held| held.replace(Some(0)));
    let r = f();
    let n = HELD.with(|held| held.replace(before)).unwrap_or(0);
    (r, n)
}

#[derive(Debug)]
pub(crate) struct RunState {
    started: Instant,
    deadline: Option<Instant>,
    cancelled: AtomicBool,
    by_budget: AtomicBool,
    lp_solves: AtomicU64,
    stage: AtomicU8,
    /// f64 bits of the best max jerk; +inf until a start finishes.
    best_jerk: AtomicU64,
}

const STAGES: [Stage; 4] = [
    Stage::Searching,
    Stage::LimitsBind,
    Stage::MinTime,
    Stage::Finishing,
];

impl RunState {
    pub(crate) fn new(budget: Option<Duration>) -> Self {
        let started = Instant::now();
        Self {
            started,
            deadline: budget.and_then(|b| started.checked_add(b)),
            cancelled: AtomicBool::new(false),
            by_budget: AtomicBool::new(false),
            lp_solves: AtomicU64::new(0),
            stage: AtomicU8::new(0),
            best_jerk: AtomicU64::new(f64::INFINITY.to_bits()),
        }
    }

    /// Called before every linear program: false once cancelled.
    pub(crate) fn proceed(&self) -> bool {
        let abandoned = ABANDONED.with(|a| {
            a.borrow()
                .as_ref()
                .is_some_and(|f| f.load(Ordering::Relaxed))
        });
        if abandoned || self.cancelled.load(Ordering::Relaxed) {
            return false;
        }
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            self.by_budget.store(true, Ordering::Relaxed);
            self.cancel();
            return false;
        }
        if !HELD.with(|held| held.get().map(|n| held.set(Some(n + 1))).is_some()) {
            self.lp_solves.fetch_add(1, Ordering::Relaxed);
        }
        true
    }

    /// Counts `n` solves held back by [`held_solves`].
    pub(crate) fn count_solves(&self, n: u64) {
        self.lp_solves.fetch_add(n, Ordering::Relaxed);
    }

    pub(crate) fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    pub(crate) fn cancelled(&self) -> Option<CancelReason> {
        self.cancelled.load(Ordering::Relaxed).then(|| {
            if self.by_budget.load(Ordering::Relaxed) {
                CancelReason::TimeBudget
            } else {
                CancelReason::Observer
            }
        })
    }

    pub(crate) fn set_stage(&self, stage: Stage) {
        let i = STAGES.iter().position(|s| *s == stage).unwrap_or(0);
        self.stage.store(i as u8, Ordering::Relaxed);
    }

    pub(crate) fn offer_jerk(&self, jerk: f64) {
        let _ = self
            .best_jerk
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |b| {
                (jerk < f64::from_bits(b)).then_some(jerk.to_bits())
            });
    }

    pub(crate) fn progress(&self) -> Progress {
        let best = f64::from_bits(self.best_jerk.load(Ordering::Relaxed));
        Progress {
            elapsed: self.started.elapsed(),
            stage: STAGES[usize::from(self.stage.load(Ordering::Relaxed)).min(3)],
            lp_solves: self.lp_solves.load(Ordering::Relaxed),
            best_max_jerk: best.is_finite().then_some(best),
        }
    }
}
