//! The experiments of thesis chapter 2 (PQRM).

pub mod monte_carlo;
pub mod real_data;
pub mod reasoning;
