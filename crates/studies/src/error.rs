//! The error type of the crate.

/// Everything that can go wrong in a study.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyError {
    /// A configuration value is out of range (said before any work starts).
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// The caller asked the work to stop (Ctrl-C, a progress callback that raised).
    #[error(transparent)]
    Cancelled(#[from] qsr_core::progress::Cancelled),
    /// An error from navigation.
    #[error(transparent)]
    Qlink(#[from] qlink::QlinkError),
    /// An error from salient region generation.
    #[error(transparent)]
    Serge(#[from] serge::SergeError),
    /// An error from the mapper.
    #[error(transparent)]
    Pqrm(#[from] pqrm::PqrmError),
    /// An error from the calculus layer.
    #[error(transparent)]
    Calculus(#[from] qsr_core::QsrError),
    /// An error from the simulator.
    #[error(transparent)]
    Sim(#[from] sim2d::SimError),
    /// An error writing a log (the demo's MCAP).
    #[error(transparent)]
    Log(#[from] qrm_log::LogError),
}

impl StudyError {
    /// Whether the work stopped because the caller asked it to (at any depth).
    #[must_use]
    pub fn is_cancelled(&self) -> bool {
        matches!(
            self,
            Self::Cancelled(_)
                | Self::Qlink(qlink::QlinkError::Cancelled(_))
                | Self::Serge(serge::SergeError::Cancelled(_))
                | Self::Pqrm(pqrm::PqrmError::Cancelled(_))
        )
    }
}

/// Shorthand for `Result<T, StudyError>`.
pub type Result<T> = std::result::Result<T, StudyError>;
