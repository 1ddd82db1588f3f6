//! The error type of the crate.

use std::path::PathBuf;

use qsr_core::QsrError;

/// Everything that can go wrong in `serge`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SergeError {
    /// A coordinate, covariance entry or parameter was NaN or infinite.
    #[error("non-finite input: {0}")]
    NonFinite(String),
    /// The belief set is empty, or a sample belief has no samples.
    #[error("empty input: {0}")]
    Empty(String),
    /// A Gaussian belief's covariance is not symmetric positive definite.
    #[error("belief {index}: covariance {cov:?} is degenerate ({reason})")]
    DegenerateCovariance {
        /// The belief (input order).
        index: usize,
        /// The matrix.
        cov: [[f64; 2]; 2],
        /// What is wrong.
        reason: &'static str,
    },
    /// A parameter is out of range (μ < 1, μ > min(K, N), σ < 0, zero trials, bad grid).
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// No grid cell holds any probability mass of any belief.
    #[error("no mass: {0}")]
    NoMass(String),
    /// A region, node or cell index does not exist.
    #[error("unknown {kind} {index}")]
    Unknown {
        /// What was looked up ("node", "region", "cell").
        kind: &'static str,
        /// The index.
        index: usize,
    },
    /// The caller asked the work to stop (Ctrl-C, a progress callback that raised).
    #[error(transparent)]
    Cancelled(#[from] qsr_core::progress::Cancelled),
    /// An error from the calculus layer (export of a learned calculus).
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
    /// An input document is malformed.
    #[error("{context}: {reason}")]
    Parse {
        /// The file or document.
        context: String,
        /// What is wrong.
        reason: String,
    },
}

/// Shorthand for `Result<T, SergeError>`.
pub type Result<T> = std::result::Result<T, SergeError>;
