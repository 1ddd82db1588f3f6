//! # qrm-py — the native module `qrm._qrm` of the `qrm` Python package
//!
//! Thin by design: conversion (NumPy arrays in, NumPy arrays and plain Python data out) and
//! error mapping only; every algorithm lives in `qsr-core`, `pqrm`, `sim2d`, `serge` and `qlink`. The typed public
//! package (`qrm/__init__.py`, `_qrm.pyi`, `py.typed`) sits in `python/qrm`.
//!
//! Errors: each Rust error kind maps to one exception class under `qrm.QrmError` (see
//! `errors.rs`). Long calls release the interpreter and run in a fork-safe thread pool
//! (`pool.rs`). A Rust panic inside a
//! call becomes a Python `PanicException` (pyo3 catches it at the boundary), never a crash.
#![allow(unsafe_code)] // pyo3's #[pymodule]/#[pyclass]/#[pymethods] expand to unsafe FFI glue; this crate writes none itself.

mod arrays;
mod binary;
mod calculus;
mod errors;
mod mapping;
mod navigation;
mod picture;
mod pool;
mod reasoning;
mod regions;
mod simulation;
mod study_runner;

use pyo3::prelude::*;

/// The native module. Import `qrm`, not this.
#[pymodule]
fn _qrm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<calculus::Calculus>()?;
    m.add_class::<binary::BinaryCalculus>()?;
    m.add_function(wrap_pyfunction!(binary::reason_close_binary, m)?)?;
    m.add_class::<binary::BinaryAlgebra>()?;
    m.add_function(wrap_pyfunction!(binary::reason_solve_binary, m)?)?;
    m.add_function(wrap_pyfunction!(binary::reason_read_csp, m)?)?;
    m.add_class::<mapping::Pqrm>()?;
    m.add_function(wrap_pyfunction!(study_runner::studies_list, m)?)?;
    m.add_function(wrap_pyfunction!(study_runner::studies_config, m)?)?;
    m.add_function(wrap_pyfunction!(study_runner::studies_run, m)?)?;
    m.add_function(wrap_pyfunction!(study_runner::studies_shards, m)?)?;
    m.add_function(wrap_pyfunction!(study_runner::studies_run_shard, m)?)?;
    m.add_function(wrap_pyfunction!(study_runner::studies_aggregate, m)?)?;
    m.add_function(wrap_pyfunction!(study_runner::studies_save, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::read_observations, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::survey_agreement, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::layout_map, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::single_observation, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::monte_carlo_shard, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::monte_carlo_aggregate, m)?)?;
    m.add_function(wrap_pyfunction!(mapping::monte_carlo_config, m)?)?;
    m.add_function(wrap_pyfunction!(calculus::builtin_names, m)?)?;
    m.add_function(wrap_pyfunction!(simulation::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulation::sim_record, m)?)?;
    m.add_class::<regions::SalientRegionMap>()?;
    m.add_function(wrap_pyfunction!(regions::serge_run, m)?)?;
    m.add_function(wrap_pyfunction!(regions::serge_cross_validate, m)?)?;
    m.add_function(wrap_pyfunction!(regions::compose_cells, m)?)?;
    m.add_function(wrap_pyfunction!(navigation::navigate, m)?)?;
    m.add_function(wrap_pyfunction!(navigation::qlink_study, m)?)?;
    m.add_function(wrap_pyfunction!(navigation::qlink_field, m)?)?;
    m.add_function(wrap_pyfunction!(pool::worker_threads, m)?)?;
    m.add_function(wrap_pyfunction!(pool::_on_caller_thread, m)?)?;
    m.add_function(wrap_pyfunction!(reasoning::reason_close, m)?)?;
    m.add_function(wrap_pyfunction!(reasoning::reason_scenario, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
