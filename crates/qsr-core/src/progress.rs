//! How long work says how far it got, and stops when asked.
//!
//! Why this exists: a study or a learned compose table runs for seconds to minutes, and the
//! front ends want different things from it — the CLI draws a bar, Python calls a user's
//! callback (a tqdm bar) and must stop on Ctrl-C, a test wants nothing. The algorithms should
//! know none of that. So long work takes a `&dyn Progress`, calls [`Progress::tick`] after
//! each unit (a navigation, a trial, a SERGE run, a cell) and, between units, returns
//! [`Cancelled`] (through [`Progress::check`]) once the caller asked it to stop. Units are
//! short (milliseconds to a second), so a stop is prompt; work already done is dropped, never
//! half-returned.
//!
//! Any `Fn() + Sync` closure is a `Progress` that never cancels, so `&|| {}` means "no
//! report" and `&|| bar.inc(1)` drives an indicatif bar. [`Watch`] is the one to share with
//! another thread: it counts ticks, holds the total, and carries a stop flag.
//!
//! Cancelling never changes what a finished run returns: the checks read a flag and do no
//! other work, so results stay independent of the thread count and of who watches.
//!
//! ```
//! use qsr_core::progress::{Cancelled, Progress, Watch};
//!
//! fn count_to(n: usize, progress: &dyn Progress) -> Result<usize, Cancelled> {
//!     for _ in 0..n {
//!         progress.check()?;
//!         progress.tick();
//!     }
//!     Ok(n)
//! }
//! let watch = Watch::new();
//! assert_eq!(count_to(3, &watch), Ok(3));
//! assert_eq!(watch.done(), 3);
//! watch.stop();
//! assert_eq!(count_to(3, &watch), Err(Cancelled));
//! assert_eq!(count_to(3, &|| {}), Ok(3)); // a closure never cancels
//! ```

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Work's report channel: ticks out, a stop request in (see the module docs).
pub trait Progress: Sync {
    /// One more unit of work is done.
    fn tick(&self);

    /// The work announces `units` more units to come (it may announce in parts, e.g. per
    /// setting). The default ignores it.
    fn add_total(&self, units: usize) {
        let _ = units;
    }

    /// Whether the caller asked the work to stop. The default never does.
    fn cancelled(&self) -> bool {
        false
    }

    /// `Err(Cancelled)` once the caller asked the work to stop: call it between units.
    ///
    /// # Errors
    /// [`Cancelled`] when [`Progress::cancelled`] says so.
    fn check(&self) -> Result<(), Cancelled> {
        if self.cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }
}

impl<F: Fn() + Sync + ?Sized> Progress for F {
    fn tick(&self) {
        self();
    }
}

/// The work stopped because its caller asked it to (Ctrl-C, a callback that raised); what
/// it had done is dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cancelled: the caller asked the work to stop")]
pub struct Cancelled;

/// A [`Progress`] one thread works with while another watches it: ticks done, the total
/// when the work announces it, and a stop flag. All relaxed atomics — the counts are for
/// display, and a stop seen one unit late is still a stop.
#[derive(Debug, Default)]
pub struct Watch {
    done: AtomicUsize,
    total: AtomicUsize,
    stop: AtomicBool,
}

impl Watch {
    /// Nothing done, no total, not stopped.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Units done so far.
    #[must_use]
    pub fn done(&self) -> usize {
        self.done.load(Ordering::Relaxed)
    }

    /// Units the work announced (0 until it does).
    #[must_use]
    pub fn total(&self) -> usize {
        self.total.load(Ordering::Relaxed)
    }

    /// Asks the work to stop at its next check.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

impl Progress for Watch {
    fn tick(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }

    fn add_total(&self, units: usize) {
        self.total.fetch_add(units, Ordering::Relaxed);
    }

    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Runs a phase of work counted as exactly `units` units: the ticks `f` makes pass through
/// (at most `units` of them), and once it returns, the units it did not tick — a phase that
/// found less to do, skipped cached work or failed part-way — are ticked for it (unless the
/// caller asked the work to stop).
///
/// Why: a total announced before the work starts ([`FixedTotal`]) must be met exactly, or the
/// bar ends short of 100 % or runs past it; counting that holds by construction beats
/// counting every early exit by hand.
///
/// ```
/// use qsr_core::progress::{Progress, Watch, phase};
///
/// let watch = Watch::new();
/// let found = phase(&watch, 10, |p| {
///     for _ in 0..4 {
///         p.tick(); // only four of the ten units had work to do
///     }
///     "done early"
/// });
/// assert_eq!((found, watch.done()), ("done early", 10));
/// ```
pub fn phase<T>(progress: &dyn Progress, units: usize, f: impl FnOnce(&dyn Progress) -> T) -> T {
    struct Counted<'a> {
        inner: &'a dyn Progress,
        left: AtomicUsize,
    }
    impl Progress for Counted<'_> {
        fn tick(&self) {
            let had = self
                .left
                .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1));
            if had.is_ok() {
                self.inner.tick();
            }
        }
        fn cancelled(&self) -> bool {
            self.inner.cancelled()
        }
    }
    let counted = Counted {
        inner: progress,
        left: AtomicUsize::new(units),
    };
    let out = f(&counted);
    // a stopped run ends where it stopped: the bar does not jump to the phase's end
    if !progress.cancelled() {
        for _ in 0..counted.left.load(Ordering::Relaxed) {
            progress.tick();
        }
    }
    out
}

/// A [`Progress`] whose total was announced before the work started: it passes ticks and
/// stop requests through and drops the work's own [`Progress::add_total`] calls.
///
/// Why: work announces its units as it learns them (per setting, once tasks are drawn), so
/// a bar fed those grows while it runs. A caller that can count the units up front (every
/// study can: `Study::shard_units`) announces them once and wraps the progress in this, and
/// the bar's total is fixed from the first frame.
///
/// ```
/// use qsr_core::progress::{FixedTotal, Progress, Watch};
///
/// let watch = Watch::new();
/// watch.add_total(2);
/// let fixed = FixedTotal(&watch);
/// fixed.add_total(5); // the work's own announcement: dropped
/// fixed.tick();
/// assert_eq!((watch.done(), watch.total()), (1, 2));
/// ```
#[derive(Clone, Copy)]
pub struct FixedTotal<'a>(pub &'a dyn Progress);

impl Progress for FixedTotal<'_> {
    fn tick(&self) {
        self.0.tick();
    }

    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_watch_counts_ticks_and_totals_and_stops_only_when_asked() {
        let w = Watch::new();
        assert!(!w.cancelled());
        w.add_total(2);
        w.add_total(3);
        w.tick();
        assert_eq!((w.done(), w.total()), (1, 5));
        assert_eq!(w.check(), Ok(()));
        w.stop();
        assert_eq!(w.check(), Err(Cancelled));
    }

    #[test]
    fn a_closure_ticks_and_never_cancels() {
        let n = AtomicUsize::new(0);
        let f = || {
            n.fetch_add(1, Ordering::Relaxed);
        };
        let p: &dyn Progress = &f;
        p.tick();
        p.tick();
        assert_eq!(n.load(Ordering::Relaxed), 2);
        assert!(!p.cancelled());
    }
}
