//! Worker threads: items run side by side ([`parallel`]), and the cores
//! they leave idle lent to a search running alone ([`on_spare_core`]).
//! Neither changes a result, only when it is ready.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicIsize, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use crate::run_state::abandonable;

/// Cores that the outermost [`parallel`] call running leaves idle (more
/// threads than items, or workers out of items): a search running alone
/// spends one on a trial it may need next ([`on_spare_core`]).
static SPARE_CORES: AtomicIsize = AtomicIsize::new(0);

thread_local! {
    /// Whether this thread is a [`parallel`] worker: a nested call's cores
    /// are its caller's, none of them spare.
    static WORKER: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f` on every item with `threads` workers; results keep the items' order.
pub(crate) fn parallel<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let threads = threads.max(1);
    let workers = threads.min(items.len().max(1));
    let outermost = !WORKER.with(Cell::get);
    let spare = |n: usize| {
        if outermost {
            SPARE_CORES.fetch_add(n as isize, Ordering::SeqCst);
        }
    };
    spare(threads - workers);
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                WORKER.with(|w| w.set(true));
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    let r = f(item);
                    if let Ok(mut slot) = slots[i].lock() {
                        *slot = Some(r);
                    }
                }
                spare(1);
            });
        }
    });
    // Every worker has ended; a trial one started beside it, abandoned,
    // gives its core back within a program.
    if outermost {
        SPARE_CORES.fetch_sub(threads as isize, Ordering::SeqCst);
    }
    slots
        .into_iter()
        .filter_map(|m| m.into_inner().ok().flatten())
        .collect()
}

/// Work started on a spare core ([`on_spare_core`]): waited for when it
/// is needed, abandoned (its next program refused) when dropped unwaited.
pub(crate) struct Beside<R> {
    handle: Option<JoinHandle<R>>,
    abandoned: Arc<AtomicBool>,
}

impl<R> Beside<R> {
    /// Its result (None if it panicked).
    pub(crate) fn wait(mut self) -> Option<R> {
        self.handle.take()?.join().ok()
    }
}

impl<R> Drop for Beside<R> {
    fn drop(&mut self) {
        if self.handle.is_some() {
            self.abandoned.store(true, Ordering::SeqCst);
        }
    }
}

/// Starts `f` on another thread when a core is spare (None when none is):
/// the caller must not depend on which.
pub(crate) fn on_spare_core<R: Send + 'static>(
    f: impl FnOnce() -> R + Send + 'static,
) -> Option<Beside<R>> {
    SPARE_CORES
        .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n > 0).then(|| n - 1)
        })
        .ok()?;
    let abandoned = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&abandoned);
    let handle = std::thread::spawn(move || {
        let r = abandonable(flag, f);
        SPARE_CORES.fetch_add(1, Ordering::SeqCst);
        r
    });
    Some(Beside {
        handle: Some(handle),
        abandoned,
    })
}
