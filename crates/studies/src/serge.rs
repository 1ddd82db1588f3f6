//! The experiments of thesis chapter 3 (SERGE).

pub mod cross_validation;
pub mod datasets;
