//! `qrm.studies`: every thesis study through the `studies` crate's registry — the same
//! configs, runs and reports as `qrm study` on the command line.

use pyo3::prelude::*;

use crate::errors::invalid;
use crate::errors::study_err;

/// `[(name, about), ...]` of every study.
#[pyfunction]
pub(crate) fn studies_list() -> Vec<(&'static str, &'static str)> {
    studies::STUDIES
        .iter()
        .map(|s| (s.name(), s.about()))
        .collect()
}

/// The quick or full config of study `name` with `seed`, as JSON.
#[pyfunction]
#[pyo3(signature = (name, full, seed))]
pub(crate) fn studies_config(name: &str, full: bool, seed: u64) -> PyResult<String> {
    let study = studies::find(name).map_err(study_err)?;
    Ok(study.config(full, seed).to_string())
}

/// Runs study `name` with `config` (JSON; None: the quick or full built-in with `seed`) and
/// returns JSON `{"config": ..., "output": ..., "report": ...}`. Watched: Ctrl-C stops it,
/// `progress(done, total)` is called as its units of work finish.
#[pyfunction]
#[pyo3(signature = (name, config, quick, seed, progress = None))]
pub(crate) fn studies_run(
    py: Python<'_>,
    name: &str,
    config: Option<&str>,
    quick: bool,
    seed: u64,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let study = studies::find(name).map_err(study_err)?;
    let config: serde_json::Value = match config {
        Some(text) => serde_json::from_str(text)
            .map_err(|e| invalid(format!("config of `{name}` is not JSON: {e}")))?,
        None => study.config(!quick, seed),
    };
    study.check(&config).map_err(study_err)?;
    let ran = crate::pool::watched(py, progress, move |watch| study.run(&config, watch))?
        .map_err(study_err)?;
    ran_json(ran)
}

fn parse_config(name: &str, config: &str) -> PyResult<serde_json::Value> {
    serde_json::from_str(config)
        .map_err(|e| invalid(format!("config of `{name}` is not JSON: {e}")))
}

/// How many shards study `name`'s work under `config` (JSON) splits into.
#[pyfunction]
pub(crate) fn studies_shards(name: &str, config: &str) -> PyResult<usize> {
    let study = studies::find(name).map_err(study_err)?;
    study
        .shards(&parse_config(name, config)?)
        .map_err(study_err)
}

/// Runs shard `index` of study `name` under `config` (JSON) and returns it as JSON. Watched:
/// Ctrl-C stops it, `progress(done, total)` is called as its units finish.
#[pyfunction]
#[pyo3(signature = (name, config, index, progress = None))]
pub(crate) fn studies_run_shard(
    py: Python<'_>,
    name: &str,
    config: &str,
    index: usize,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let study = studies::find(name).map_err(study_err)?;
    let config = parse_config(name, config)?;
    study.check(&config).map_err(study_err)?;
    let shard = crate::pool::watched(py, progress, move |watch| {
        study.run_shard(&config, index, watch)
    })?
    .map_err(study_err)?;
    Ok(shard.to_string())
}

/// Merges shards `[(index, shard JSON), ...]` of study `name` under `config` (JSON), given in
/// any order and each exactly once, into the run's JSON `{"config", "output", "report"}`.
#[pyfunction]
pub(crate) fn studies_aggregate(
    name: &str,
    config: &str,
    shards: Vec<(usize, String)>,
) -> PyResult<String> {
    let study = studies::find(name).map_err(study_err)?;
    let config = parse_config(name, config)?;
    let shards = shards
        .into_iter()
        .map(|(i, text)| {
            serde_json::from_str(&text)
                .map(|v| (i, v))
                .map_err(|e| invalid(format!("shard {i} is not JSON: {e}")))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let ran = study.aggregate(&config, shards).map_err(study_err)?;
    ran_json(ran)
}

fn ran_json(ran: studies::Ran) -> PyResult<String> {
    let report = serde_json::to_value(&ran.report).map_err(|e| invalid(e.to_string()))?;
    Ok(
        serde_json::json!({"config": ran.config, "output": ran.output, "report": report})
            .to_string(),
    )
}
