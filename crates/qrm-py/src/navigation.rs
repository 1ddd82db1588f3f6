//! Q-Link from Python: navigate a qualitative map (a `qrm.Pqrm` or one built from surveyed
//! positions) in a range-only simulated world, and the §4.4.1 study. Thin wrappers of
//! `qlink`.

use std::collections::BTreeMap;

use pyo3::prelude::*;
use qlink::{
    Controller, ControllerKind, Layer, LinkGraph, NavConfig, Navigator, QlinkError, QualitativeMap,
    RangePerception, SearchPomdp,
};

use studies::StudyError;

use crate::calculus::Calculus;
use crate::errors::{invalid, qlink_err, study_err};
use crate::mapping::Pqrm;

/// Navigates from landmark `start` to landmark `goal` in a world of point landmarks
/// (`positions`: id → (x, y)) seen within `range`, with a map that is either `pqrm` or —
/// when it is None — the exact QRM of `calculus` a robot of range `map_range` would record.
/// The robot errs (`qlink::Robot::default()`: N(0, 0.3 m) detections, MRCLAM's miss rate,
/// wheel slip; draws from `seed`) unless `exact_robot`. Returns the outcome as a dict
/// (success, failure, plan_len, replans, length, transit_length, bound, trajectory,
/// transitions).
#[pyfunction]
#[pyo3(signature = (positions, start, goal, *, pqrm = None, calculus = None, range = 20.0, map_range = None, beta = 1, controller = "arc", horizon = 4, replan = true, exact_robot = false, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn navigate(
    py: Python<'_>,
    positions: BTreeMap<u32, (f64, f64)>,
    start: u32,
    goal: u32,
    pqrm: Option<PyRef<'_, Pqrm>>,
    calculus: Option<PyRef<'_, Calculus>>,
    range: f64,
    map_range: Option<f64>,
    beta: usize,
    controller: &str,
    horizon: usize,
    replan: bool,
    exact_robot: bool,
    seed: u64,
) -> PyResult<String> {
    if positions
        .values()
        .any(|p| !p.0.is_finite() || !p.1.is_finite())
    {
        return Err(invalid("a landmark position is not finite"));
    }
    let pos: BTreeMap<u32, [f64; 2]> = positions.iter().map(|(k, v)| (*k, [v.0, v.1])).collect();
    let map_range = map_range.unwrap_or(range);
    let layer = match (pqrm, calculus) {
        (Some(m), _) => Layer::Probabilistic(m.inner.clone()),
        (None, Some(c)) => {
            Layer::exact_from_positions(c.inner.clone(), &pos, map_range).map_err(qlink_err)?
        }
        (None, None) => {
            return Err(invalid(
                "give the map: pqrm=... or calculus=... (an exact map from the positions)",
            ));
        }
    };
    let kind: ControllerKind = controller.parse().map_err(qlink_err)?;
    let landmarks: Vec<(u32, [f64; 2])> = pos.into_iter().collect();
    let json = crate::pool::detach(py, move || -> Result<String, QlinkError> {
        let map = QualitativeMap::new(vec![layer])?;
        let calc = map.layers()[0].calculus().clone();
        let graph = LinkGraph::new(&map, beta, |_, _, _| 1.0)?;
        let config = NavConfig {
            step: 0.5,
            replan,
            max_replans: 3,
            map_range,
            robot: if exact_robot {
                qlink::Robot::EXACT
            } else {
                qlink::Robot::default().with_seed(seed)
            },
            ..NavConfig::thesis(
                Controller::new(kind, range),
                SearchPomdp::builder(&calc).horizon(horizon).build()?,
            )
        };
        let perception = RangePerception::new(&landmarks, range);
        let nav = Navigator::new(&map, &graph, &perception, &config)?;
        let out = nav.navigate_between(start, goal, 0.5)?;
        serde_json::to_string(&out).map_err(|e| QlinkError::InvalidParameter(e.to_string()))
    });
    json.map_err(qlink_err)
}

/// The §4.4.2 field experiment in one world (quick or full settings, `trials` per variant):
/// JSON `{"mapping": {...}, "draws": {...}, "variants": [...], "trials": [...]}` (trials
/// without their trajectories). Watched: Ctrl-C stops it, `progress(done, total)` is called
/// as trials finish.
#[pyfunction]
#[pyo3(signature = (quick, trials, seed, progress = None))]
pub(crate) fn qlink_field(
    py: Python<'_>,
    quick: bool,
    trials: Option<usize>,
    seed: u64,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    crate::pool::watched(py, progress, move |watch| -> Result<String, StudyError> {
        let mut params = if quick {
            studies::qlink::field::FieldParams::quick(seed)
        } else {
            studies::qlink::field::FieldParams::full(seed)
        };
        if let Some(n) = trials {
            params.trials = n;
        }
        let variants = studies::qlink::field::FieldVariant::ALL;
        let (field, draws, ts) = studies::qlink::field::run_field(&params, &variants, watch)?;
        let summaries = studies::qlink::field::summarise(&ts, &variants);
        let rows: Vec<serde_json::Value> = ts
            .iter()
            .map(|t| {
                serde_json::json!({
                    "variant": t.variant, "trial": t.task.trial, "start": t.task.start,
                    "goal": t.task.goal, "result": t.result, "plan_len": t.plan_len,
                    "replans": t.replans, "stranded": t.stranded, "length": t.length,
                    "final_distance": t.final_distance,
                    "transit_length": t.transit_length, "bounds": t.bounds,
                    "ground_share": t.ground_share,
                    "final_ground_share": t.final_ground_share,
                })
            })
            .collect();
        serde_json::to_string(&serde_json::json!({
            "mapping": field.stats, "draws": draws, "variants": summaries, "trials": rows,
        }))
        .map_err(|e| StudyError::InvalidParameter(e.to_string()))
    })?
    .map_err(study_err)
}

/// The §4.4.1 study (quick or full) for `trial` = sensor-range, occlusion or all; returns
/// JSON `{"table": [...], "records": [...]}`. Watched: Ctrl-C stops it,
/// `progress(done, total)` is called as navigations finish.
#[pyfunction]
#[pyo3(signature = (trial, quick, pairs, seed, progress = None, exact_robot = false))]
pub(crate) fn qlink_study(
    py: Python<'_>,
    trial: &str,
    quick: bool,
    pairs: Option<usize>,
    seed: u64,
    progress: Option<&Bound<'_, PyAny>>,
    exact_robot: bool,
) -> PyResult<String> {
    let trial: studies::qlink::table_4_1::Trials = trial.parse().map_err(study_err)?;
    crate::pool::watched(py, progress, move |watch| -> Result<String, StudyError> {
        let mut config = if quick {
            studies::qlink::table_4_1::StudyConfig::quick(seed)
        } else {
            studies::qlink::table_4_1::StudyConfig::full(seed)
        };
        config.trial = trial;
        config.exact_robot = exact_robot;
        if pairs.is_some() {
            // as `qrm qlink study --pairs`: the main rows' pairs, and at most as many in the
            // further schedules' and ablations' rows
            config.pairs = pairs;
            let at_most = |own: Option<usize>| pairs.map(|p| p.min(own.unwrap_or(p)));
            config.schedule_pairs = at_most(config.schedule_pairs);
            config.ablation_pairs = at_most(config.ablation_pairs);
        }
        let (records, _) = studies::qlink::table_4_1::run_study(&config, watch)?;
        let table = studies::qlink::table_4_1::table(&records);
        serde_json::to_string(&serde_json::json!({"table": table, "records": records}))
            .map_err(|e| StudyError::InvalidParameter(e.to_string()))
    })?
    .map_err(study_err)
}
