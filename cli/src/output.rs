//! Writing result files: whole or not at all (the writers are `qrm_files`'s, shared with the
//! Python wheel); here, what Ctrl-C does to an unfinished output.

pub use qrm_files::{Staging, write_atomic};

/// Ctrl-C: say so, remove the staging directories of unfinished outputs, exit 130 (the shell
/// convention for SIGINT) — within a second, whatever the computation is doing.
pub fn install_interrupt_handler() {
    let _ = ctrlc::set_handler(|| {
        if qrm_files::remove_unfinished().is_empty() {
            eprintln!("interrupted");
        } else {
            eprintln!("interrupted: the unfinished output was removed, nothing was written");
        }
        std::process::exit(130);
    });
}
