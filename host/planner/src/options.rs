//! How hard to search, and how to watch or stop a search.

use std::time::Duration;

/// The most starts a caller should ask for (the CLI's `--starts`, the
/// Python `plan(starts=)`): each start keeps an interval set per segment
/// and the search stops taking them once two agree, so the default 8 is
/// usually plenty; a thousand is far past any use.
pub const MAX_STARTS: usize = 1000;

/// Search settings. The same job, `starts` and `seed` give the same plan
/// byte for byte (apart from `solver.seconds`), whatever `threads` is.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Starting interval sets of the global search at most (the first three
    /// are deterministic shapes, the rest seeded random); the search stops
    /// taking them once two reach the same best point.
    pub starts: usize,
    /// Seed of the random starts.
    pub seed: u64,
    /// Worker threads (results do not depend on it).
    pub threads: usize,
    /// Give up with [`crate::error::PlanError::Cancelled`] after this long.
    pub time_budget: Option<Duration>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            starts: 8,
            seed: 1,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get().min(4)),
            time_budget: None,
        }
    }
}

/// What the search is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// Multistart on the jerk-only relaxation.
    Searching,
    /// Multistart with every limit (the relaxation's optimum broke one).
    LimitsBind,
    /// Looking for the shortest total time.
    MinTime,
    /// Rounding to whole microseconds and the final exact solve.
    Finishing,
}

/// A snapshot of a running search, given to an [`Observer`].
#[derive(Clone, Debug, PartialEq)]
pub struct Progress {
    pub elapsed: Duration,
    pub stage: Stage,
    /// Linear programs solved so far.
    pub lp_solves: u64,
    /// Best max |jerk| (m/s³) of any start so far, once there is one.
    pub best_max_jerk: Option<f64>,
}

/// What an observer wants next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    Continue,
    Cancel,
}

/// Watches a search: `plan_with` calls it on the calling thread at
/// least every 50 ms while the search runs on another. Returning
/// [`Control::Cancel`] stops the search within one linear program.
///
/// Any `FnMut(&Progress) -> Control` is an observer.
pub trait Observer {
    fn progress(&mut self, progress: &Progress) -> Control;
}

impl<F: FnMut(&Progress) -> Control> Observer for F {
    fn progress(&mut self, progress: &Progress) -> Control {
        self(progress)
    }
}
