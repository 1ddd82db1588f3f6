//! # qrm-files — result files written whole or not at all
//!
//! A result a user finds on disk must be a whole result: a run stopped by an error, a kill or
//! Ctrl-C leaves nothing that could be taken for one. Every front end (the `qrm` CLI, the
//! Python wheel) writes through this crate, so a study run saved from Python is the same
//! directory, byte for byte, as `qrm study run` writes.
//!
//! | item | what |
//! |---|---|
//! | [`write_atomic`] | one file through a temporary sibling and a rename |
//! | [`Staging`] | an output directory filled in a hidden sibling and moved into place by [`Staging::commit`] |
//! | [`StagedFile`] | one file a writer fills by path (an MCAP log), moved into place by [`StagedFile::commit`] |
//! | [`CsvTable`] | a CSV table through the `csv` crate (labels holding commas stay one field) |
//! | [`write_picture`] | a figure as `stem.svg` and `stem.png` |
//! | [`write_run`] | a study run: tables as CSV, figures, attachments, report.md, config.toml |
//! | [`write_products`] | a job's tables, figures and attachments (`qrm sim`, a calibration, a region map) |
//!
//! ## Naming rule
//! `write_*` writes one thing atomically; a type owns a directory or a table being built.
//!
//! ## Errors
//! [`FileError`]: `Io` (with the path and what was being done), `Csv`, `Plot` (a figure
//! that cannot be drawn), `Study` (a config that cannot be printed as TOML).
//!
//! ```
//! let dir = std::env::temp_dir().join(format!("qrm-files-doc-{}", std::process::id()));
//! let stage = qrm_files::Staging::new(&dir)?;
//! let mut t = qrm_files::CsvTable::new(["state", "p"])?;
//! t.row(["left, of", "0.5"])?; // one field: the csv crate quotes it
//! t.write(&stage.path().join("p.csv"))?;
//! stage.commit()?;
//! assert_eq!(std::fs::read_to_string(dir.join("p.csv"))?, "state,p\n\"left, of\",0.5\n");
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod atomic;
mod csv_table;
mod run;
mod staging;

pub use atomic::write_atomic;
pub use csv_table::CsvTable;
pub use run::{write_picture, write_products, write_run};
pub use staging::{StagedFile, Staging, remove_unfinished};

use std::path::PathBuf;

/// What can go wrong writing results.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FileError {
    /// The file system refused: `doing` says what was being done to `path`.
    #[error("{doing} {}: {source}", path.display())]
    Io {
        /// What was being done (`writing`, `creating`, `moving the result into`).
        doing: &'static str,
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A path that cannot be an output (`--out` naming a file, a path without a name).
    #[error("{0}")]
    Path(String),
    /// The csv writer failed (a row whose length is not the header's).
    #[error("CSV table: {0}")]
    Csv(#[from] csv::Error),
    /// A figure cannot be drawn.
    #[error(transparent)]
    Plot(#[from] qrm_plot::PlotError),
    /// A study's config cannot be written as TOML.
    #[error(transparent)]
    Study(#[from] studies::StudyError),
}

impl FileError {
    fn io(doing: &'static str, path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::Io {
            doing,
            path,
            source,
        }
    }
}

/// Shorthand for `Result<T, FileError>`.
pub type Result<T> = std::result::Result<T, FileError>;
