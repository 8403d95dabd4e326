//! How `upload` and `move-to` watch a run: a progress bar on stderr and,
//! when stdin is a terminal, the keys ([`Keys`]) for hold, resume, override
//! and stop.

use indicatif::{ProgressBar, ProgressStyle};
use triquint_link::{Feed, Progress};

use crate::cli::keys::Keys;
use crate::ops::run::RunWatch;

/// The progress bar of the run under way and the keys, kept from one run
/// to the next (an approach, then the plan) so an override chosen by key
/// carries over.
pub struct TerminalWatch {
    keys: Option<Keys>,
    bar: Option<ProgressBar>,
}

impl TerminalWatch {
    /// Keys if stdin is a terminal; the override starts at 100 %.
    pub fn open() -> Self {
        Self {
            keys: Keys::open(1000),
            bar: None,
        }
    }
}

impl RunWatch for TerminalWatch {
    fn initial_override_pm(&self) -> Option<u16> {
        self.keys.as_ref().map(|k| k.override_pm)
    }

    fn start(&mut self, segments: usize) {
        let bar = ProgressBar::new(segments as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} segments  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        self.bar = Some(bar);
    }

    fn feed(&mut self, progress: &Progress, cap_pm: u16) -> Vec<Feed> {
        let Some(k) = self.keys.as_mut() else {
            return Vec::new();
        };
        // `+`/`-` step from the override the drives hold (one set before
        // the upload is reported in their answer to Arm).
        k.learn(progress.override_permille);
        k.poll(cap_pm)
    }

    fn progress(&mut self, p: &Progress) {
        if let Some(bar) = &self.bar {
            bar.set_position(p.segments_acked as u64);
            bar.set_message(progress_message(p, self.keys.is_some()));
        }
    }

    fn abandon(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.abandon();
        }
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

/// The progress line's message: phase, hold, override, stop, keys.
fn progress_message(p: &Progress, keys: bool) -> String {
    let mut m = p.phase.to_string();
    if p.started {
        m += &format!(
            ", plan time {:.1}/{:.1} s",
            p.plan_time_us as f64 * 1e-6,
            p.plan_end_us as f64 * 1e-6
        );
    }
    if p.stopped {
        m += ", STOPPING";
    } else if p.held {
        m += ", HELD";
    }
    if let Some(pm) = p.override_permille.filter(|pm| *pm != 1000) {
        m += &format!(", override {} %", crate::ops::shown::percent(pm));
    }
    if keys {
        m += &format!("  [{}]", Keys::help());
    }
    m
}
