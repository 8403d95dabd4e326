//! The search's side of observation: counters the observer reads, and the
//! cancel flag every linear program checks before it runs.

use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::error::CancelReason;
use crate::options::{Progress, Stage};

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
        if self.cancelled.load(Ordering::Relaxed) {
            return false;
        }
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            self.by_budget.store(true, Ordering::Relaxed);
            self.cancel();
            return false;
        }
        self.lp_solves.fetch_add(1, Ordering::Relaxed);
        true
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
