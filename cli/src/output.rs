//! Writing result files: whole or not at all (the writers are `qrm_files`'s, shared with the
//! Python wheel); here, what Ctrl-C does to an unfinished output.

use std::path::Path;

pub use qrm_files::{StagedFile, Staging, write_atomic};

/// A staging directory for `out`, saying on stderr which leftovers of killed runs it removed.
///
/// # Errors
/// As [`Staging::new`].
pub fn stage(out: &Path) -> qrm_files::Result<Staging> {
    let stage = Staging::new(out)?;
    say_removed(stage.removed_stale());
    Ok(stage)
}

/// A staged single file for `path`, as [`stage`].
///
/// # Errors
/// As [`StagedFile::new`].
pub fn stage_file(path: &Path) -> qrm_files::Result<StagedFile> {
    let file = StagedFile::new(path)?;
    say_removed(file.removed_stale());
    Ok(file)
}

fn say_removed(stale: &[std::path::PathBuf]) {
    for p in stale {
        eprintln!(
            "removed {}: the unfinished output of a run that was killed",
            p.display()
        );
    }
}

/// Ctrl-C, SIGTERM and SIGHUP (what `timeout`, `kill`, systemd and job schedulers send): say
/// so, remove the staging directories of unfinished outputs, exit 130 (the shell convention
/// for SIGINT; one handler serves the three signals and cannot tell them apart) — within a
/// second, whatever the computation is doing. SIGKILL runs no handler: what it leaves is
/// removed by the next run that writes beside it ([`stage`]).
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
