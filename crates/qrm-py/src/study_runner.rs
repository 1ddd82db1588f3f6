//! `qrm.studies`: every thesis study through the `studies` crate's registry — the same
//! configs, runs and reports as `qrm study` on the command line.

use pyo3::prelude::*;

use crate::errors::{files_err, invalid, study_err};

/// `[(name, about), ...]` of every study.
#[pyfunction]
pub(crate) fn studies_list() -> Vec<(&'static str, &'static str)> {
    studies::STUDIES
        .iter()
        .map(|s| (s.name(), s.about()))
        .collect()
}

/// The quick or full config of study `name` with `seed` (None: the study's default seed, as
/// the command line's), as JSON.
#[pyfunction]
#[pyo3(signature = (name, full, seed = None))]
pub(crate) fn studies_config(name: &str, full: bool, seed: Option<u64>) -> PyResult<String> {
    let study = studies::find(name).map_err(study_err)?;
    Ok(study
        .config(full, seed.unwrap_or(study.default_seed()))
        .to_string())
}

/// Runs study `name` with `config` (JSON; None: the quick or full built-in with `seed`) and
/// returns JSON `{"config": ..., "output": ..., "report": ...}`. Watched: Ctrl-C stops it,
/// `progress(done, total)` is called as its units of work finish.
#[pyfunction]
#[pyo3(signature = (name, config, quick, seed = None, progress = None))]
pub(crate) fn studies_run(
    py: Python<'_>,
    name: &str,
    config: Option<&str>,
    quick: bool,
    seed: Option<u64>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let study = studies::find(name).map_err(study_err)?;
    let config: serde_json::Value = match config {
        Some(text) => serde_json::from_str(text)
            .map_err(|e| invalid(format!("config of `{name}` is not JSON: {e}")))?,
        None => study.config(!quick, seed.unwrap_or(study.default_seed())),
    };
    study.check(&config).map_err(study_err)?;
    let ran = crate::pool::watched(py, progress, move |watch| study.run(&config, watch))?
        .map_err(study_err)?;
    ran_json(name, ran)
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
    ran_json(name, ran)
}

fn ran_json(name: &str, ran: studies::Ran) -> PyResult<String> {
    let report = serde_json::to_value(&ran.report).map_err(|e| invalid(e.to_string()))?;
    Ok(serde_json::json!({
        "study": name,
        "config": ran.config,
        "output": ran.output,
        "report": report,
    })
    .to_string())
}

/// Saves a run of study `name` — its `config` and `output` (JSON), the report made again
/// from them — into directory `out` as `qrm study run` writes it (tables as CSV, figures as
/// SVG and PNG, attachments, report.md, config.toml), whole or not at all. Returns the
/// paths written, relative to `out`.
#[pyfunction]
pub(crate) fn studies_save(
    py: Python<'_>,
    name: &str,
    config: &str,
    output: &str,
    out: std::path::PathBuf,
) -> PyResult<Vec<String>> {
    let study = studies::find(name).map_err(study_err)?;
    let config = parse_config(name, config)?;
    let output: serde_json::Value = serde_json::from_str(output)
        .map_err(|e| invalid(format!("output of `{name}` is not JSON: {e}")))?;
    crate::pool::detach(py, || {
        let ran = study.rebuild(&config, output).map_err(study_err)?;
        let stage = qrm_files::Staging::new(&out).map_err(files_err)?;
        qrm_files::write_run(stage.path(), &ran, None).map_err(files_err)?;
        let written = files_under(stage.path());
        stage.commit().map_err(files_err)?;
        Ok(written)
    })
}

/// Every file under `dir`, relative to it, sorted.
pub(crate) fn files_under(dir: &std::path::Path) -> Vec<String> {
    let mut stack = vec![dir.to_path_buf()];
    let mut files = Vec::new();
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if let Ok(rel) = path.strip_prefix(dir) {
                files.push(rel.to_string_lossy().into_owned());
            }
        }
    }
    files.sort();
    files
}
