//! Constraint networks from Python: algebraic closure and scenarios (`qsr_core::reason`).
//! Networks travel as the JSON of `qrm reason close`; the typed wrapper is `qrm/reason.py`.

use pyo3::prelude::*;
use qsr_core::reason::{
    Algebra, Network, ScenarioOptions, ScenarioOutcome, TableScope, close, find_scenario,
};

use crate::calculus::Calculus;
use crate::errors::{QrmError, qsr};

fn load(
    calculus: &Calculus,
    network: &str,
    general_position: bool,
) -> PyResult<(Network, Algebra)> {
    let c = &calculus.inner;
    let net = Network::from_json_str(c, network).map_err(qsr)?;
    let scope = if general_position {
        TableScope::GeneralPosition
    } else {
        // The sound tables from the disk cache (derived and written on the first use).
        c.load_or_derive_cached().map_err(qsr)?;
        TableScope::Sound
    };
    let alg = Algebra::of(c, scope).map_err(qsr)?;
    Ok((net, alg))
}

/// Closes a network given as JSON `{"constraints": [[A, B, C, [labels]], ...]}`; returns
/// JSON `{"consistent", "constraints", "explanation"}`.
#[pyfunction]
#[pyo3(signature = (calculus, network, *, general_position = false))]
pub(crate) fn reason_close(
    py: Python<'_>,
    calculus: &Calculus,
    network: &str,
    general_position: bool,
) -> PyResult<String> {
    let (net, alg) = load(calculus, network, general_position)?;
    let closed = crate::pool::detach(py, || close(net, &alg)).map_err(qsr)?;
    let explanation = closed
        .contradiction
        .as_ref()
        .map(|c| c.describe(&closed.network));
    Ok(serde_json::json!({
        "consistent": closed.is_consistent(),
        "constraints": closed.network.constraints_json(),
        "explanation": explanation,
    })
    .to_string())
}

/// One algebraically closed scenario of a JSON network: JSON `{"consistent", "constraints"}`
/// (constraints null when there is none).
#[pyfunction]
#[pyo3(signature = (calculus, network, *, general_position = false, max_nodes = 100_000))]
pub(crate) fn reason_scenario(
    py: Python<'_>,
    calculus: &Calculus,
    network: &str,
    general_position: bool,
    max_nodes: usize,
) -> PyResult<String> {
    let (net, alg) = load(calculus, network, general_position)?;
    let outcome = crate::pool::detach(py, || {
        find_scenario(net, &alg, &ScenarioOptions { max_nodes })
    })
    .map_err(qsr)?;
    match outcome {
        ScenarioOutcome::Found(s) => Ok(serde_json::json!({
            "consistent": true,
            "constraints": s.constraints_json(),
        })
        .to_string()),
        ScenarioOutcome::None => {
            Ok(serde_json::json!({"consistent": false, "constraints": null}).to_string())
        }
        ScenarioOutcome::GaveUp { nodes } => Err(QrmError::new_err(format!(
            "no answer within {nodes} search nodes (raise max_nodes)"
        ))),
    }
}
