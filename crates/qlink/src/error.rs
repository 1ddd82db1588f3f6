//! The error type of the crate.

/// Everything that can go wrong in `qlink`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum QlinkError {
    /// The map has no element.
    #[error("the map is empty: no landmark set to navigate with")]
    EmptyMap,
    /// A landmark id that no map element contains.
    #[error("landmark {0} is not in the map")]
    UnknownLandmark(u32),
    /// Start and goal are the same landmark.
    #[error("start and goal are the same landmark ({0}): nothing to navigate")]
    SameStartGoal(u32),
    /// No path in the link graph between the start elements and the goal.
    #[error("no path in the link graph to landmark {goal} (the graph is disconnected there)")]
    NoPath {
        /// The goal landmark.
        goal: u32,
    },
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// An operation a calculus or controller does not support.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The caller asked the work to stop (Ctrl-C, a progress callback that raised).
    #[error(transparent)]
    Cancelled(#[from] qsr_core::progress::Cancelled),
    /// An error from the calculus layer.
    #[error(transparent)]
    Calculus(#[from] qsr_core::QsrError),
    /// An error from the mapper.
    #[error(transparent)]
    Pqrm(#[from] pqrm::PqrmError),
}

/// Shorthand for `Result<T, QlinkError>`.
pub type Result<T> = std::result::Result<T, QlinkError>;
