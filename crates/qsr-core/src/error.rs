//! The error type of the crate.
//!
//! Every fallible operation returns [`QsrError`]; each variant names one kind of bad input or
//! one unsupported request, so callers (the CLI, the Python bindings) can map them one to one.

use std::path::PathBuf;

/// Everything that can go wrong in `qsr-core`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum QsrError {
    /// A coordinate or parameter was NaN or infinite.
    #[error("non-finite input: {what}")]
    NonFinite {
        /// Which input was not finite.
        what: String,
    },
    /// The reference entities do not define a frame (e.g. `A == B` within
    /// [`DEGENERATE_TOLERANCE`](crate::DEGENERATE_TOLERANCE)).
    #[error("degenerate frame: {reason}")]
    DegenerateFrame {
        /// Why the frame is degenerate.
        reason: String,
    },
    /// A calculus specification is malformed or does not partition the plane.
    #[error("invalid calculus spec `{calculus}`: {reason}")]
    Spec {
        /// Name of the calculus (or the file) being loaded.
        calculus: String,
        /// What is wrong with it.
        reason: String,
    },
    /// No built-in calculus has this name.
    #[error("unknown calculus `{name}` (built-in: {known})")]
    UnknownCalculus {
        /// The name asked for.
        name: String,
        /// Comma-separated built-in names.
        known: String,
    },
    /// A state label or id does not belong to the calculus.
    #[error("calculus `{calculus}` has no state `{state}`")]
    UnknownState {
        /// Name of the calculus.
        calculus: String,
        /// The label or id asked for.
        state: String,
    },
    /// A permutation operation name is not one of the five.
    #[error(
        "unknown operation `{name}` (expected inverse, shortcut, shortcut-inverse, homing, homing-inverse)"
    )]
    UnknownOperation {
        /// The name asked for.
        name: String,
    },
    /// The operation is not defined for this kind of calculus.
    #[error("`{operation}` is not defined for calculus `{calculus}`: {reason}")]
    Unsupported {
        /// The operation asked for.
        operation: String,
        /// Name of the calculus.
        calculus: String,
        /// Why it is not defined.
        reason: String,
    },
    /// The operation is defined but would need more memory or work than allowed; the
    /// reason carries the estimate and the limit.
    #[error("`{operation}` of calculus `{calculus}` is too large: {reason}")]
    TooLarge {
        /// The operation asked for.
        operation: String,
        /// Name of the calculus.
        calculus: String,
        /// The estimate against the limit.
        reason: String,
    },
    /// The input has the wrong shape for the calculus (e.g. 5 numbers for a ternary calculus).
    #[error("arity mismatch: {0}")]
    Arity(String),
    /// A merge from `fine` to `coarse` was asked for, but `fine` does not refine `coarse`.
    #[error(
        "`{fine}` does not refine `{coarse}`: its state `{fine_state}` meets coarse states {coarse_states:?}"
    )]
    NotARefinement {
        /// The finer calculus.
        fine: String,
        /// The coarser calculus.
        coarse: String,
        /// The fine state that straddles coarse states.
        fine_state: String,
        /// The coarse states it meets.
        coarse_states: Vec<String>,
    },
    /// A constraint network (JSON or SparQ text) is malformed.
    #[error("invalid constraint network at {at}: {reason}")]
    Network {
        /// Where: a line and column, or the constraint's position.
        at: String,
        /// What is wrong there.
        reason: String,
    },
    /// A spec file could not be read.
    #[error("cannot read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = QsrError> = std::result::Result<T, E>;

pub(crate) fn spec_error(calculus: &str, reason: impl Into<String>) -> QsrError {
    QsrError::Spec {
        calculus: calculus.to_owned(),
        reason: reason.into(),
    }
}

pub(crate) fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(QsrError::NonFinite {
            what: format!("{what} {values:?}"),
        })
    }
}
