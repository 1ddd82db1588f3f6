//! The error type of the crate.

/// Everything that can go wrong in `sim2d`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A parameter is out of range (negative radius, FOV > 2π, zero rays, ...).
    #[error("invalid parameter: {0}")]
    Invalid(String),
    /// A world file cannot be parsed or describes an impossible world.
    #[error("world file: {0}")]
    World(String),
    /// An unknown scenario name.
    #[error("unknown scenario `{0}` (pqrm-100, qlink-200, hallway, field)")]
    UnknownScenario(String),
}

/// Shorthand for results of this crate.
pub type Result<T, E = SimError> = std::result::Result<T, E>;

pub(crate) fn check(ok: bool, msg: impl FnOnce() -> String) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(SimError::Invalid(msg()))
    }
}
