//! The experiments of thesis chapter 4 (Q-Link).

pub mod field;
pub mod table_4_1;
