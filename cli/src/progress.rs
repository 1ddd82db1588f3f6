//! Long work: what it is expected to take, said before it starts, and progress bars while it
//! runs (hidden when stderr is not a terminal, e.g. in CI logs).

use indicatif::{ProgressBar, ProgressStyle};
use qsr_core::cost::{Budget, Cost};
use qsr_core::progress::Progress;

/// Work the user should be told of before it starts (core-seconds).
const ANNOUNCE_SECONDS: f64 = 5.0;

/// Says on stderr, before work estimated at more than a few seconds starts, what it is expected
/// to take — the same [`Cost`] a refusal reports (issue 39: `calculus compose opra-8` ran for
/// 40 s, and a 400-point network's closure for minutes, without a word). Work beyond `budget`
/// is not announced: it is refused, with the estimate.
pub fn announce_cost(what: &str, cost: Cost, budget: &Budget, note: &str) {
    if cost.core_seconds() >= ANNOUNCE_SECONDS && cost.fits(budget) {
        eprintln!("{what}: {cost} (estimated; {note})");
    }
}

/// A bar of `len` steps with a message.
pub fn bar(len: u64, message: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(message.to_owned());
    pb
}

/// A bar that long library work drives through [`Progress`]: the work announces its units
/// (`add_total` grows the bar) and ticks them off.
pub struct Bar(ProgressBar);

impl Bar {
    /// A bar of `len` steps (more as the work announces them) with a message.
    pub fn new(len: u64, message: &str) -> Self {
        Self(bar(len, message))
    }
}

impl std::ops::Deref for Bar {
    type Target = ProgressBar;
    fn deref(&self) -> &ProgressBar {
        &self.0
    }
}

impl Progress for Bar {
    fn tick(&self) {
        self.0.inc(1);
    }

    fn add_total(&self, units: usize) {
        self.0.inc_length(units as u64);
    }
}
