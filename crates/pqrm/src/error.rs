//! The error type of the crate.

use std::path::PathBuf;

use qsr_core::QsrError;

/// Everything that can go wrong in `pqrm`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PqrmError {
    /// A coordinate, covariance entry or time was NaN or infinite.
    #[error("non-finite input: {0}")]
    NonFinite(String),
    /// A covariance is not symmetric positive semi-definite.
    #[error("landmark {id}: covariance {cov:?} is not symmetric positive semi-definite ({reason})")]
    BadCovariance {
        /// The landmark.
        id: u32,
        /// The matrix.
        cov: [[f64; 2]; 2],
        /// What is wrong.
        reason: &'static str,
    },
    /// A landmark appears twice in one scan.
    #[error("landmark {0} appears twice in one scan")]
    DuplicateLandmark(u32),
    /// A configuration value is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// Two landmarks of a set coincide in (almost) every sample.
    #[error("landmarks {set:?} coincide: {reason}")]
    CoincidentLandmarks {
        /// The landmark set.
        set: [u32; 3],
        /// The underlying frame error.
        reason: String,
    },
    /// The caller asked the work to stop (Ctrl-C, a progress callback that raised).
    #[error(transparent)]
    Cancelled(#[from] qsr_core::progress::Cancelled),
    /// An error from the calculus layer.
    #[error(transparent)]
    Calculus(#[from] QsrError),
    /// A file could not be read or written.
    #[error("{path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A line of an input file could not be parsed.
    #[error("{path}:{line}: {reason}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0 for whole-file problems).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A saved map is malformed or from an unsupported format version.
    #[error("map format: {0}")]
    Format(String),
    /// Two maps or a map and a truth do not fit together.
    #[error("mismatch: {0}")]
    Mismatch(String),
}

/// Shorthand for results of this crate.
pub type Result<T, E = PqrmError> = std::result::Result<T, E>;

pub(crate) fn finite(what: impl FnOnce() -> String, values: &[f64]) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(PqrmError::NonFinite(what()))
    }
}
