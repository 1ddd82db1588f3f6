//! The experiments of thesis chapter 3 (SERGE).

pub mod calculus_learning;
pub mod cross_validation;
pub mod datasets;
pub mod examples;
pub mod learned_calculus;
mod output;
pub mod region_map;
mod report;
pub mod resolution_tree;
pub mod study;

pub use report::{
    HALLWAY_TOLERANCE, THESIS_HALLWAY_MAPS, THESIS_LAB_ERROR, THESIS_LAB_MAPS, THESIS_WORST_ERROR,
    report,
};
pub use study::SergeStudy;
