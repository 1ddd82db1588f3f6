//! Progress bars on long work (hidden when stderr is not a terminal, e.g. in CI logs).

use indicatif::{ProgressBar, ProgressStyle};
use qsr_core::progress::Progress;

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
