//! A calculus learned by SERGE from the hallway's triplets (thesis §3.3.2, Fig 3.10): the map
//! becomes a raster calculus, which must load back and classify the data as the map does, and
//! whose compose table by Algorithm 3 must hold every composition a sampled table witnesses.

use qsr_core::{Calculus, ComposeOptions, ComposeTable, OutsideRule, Point2, StateId};
use serde::{Deserialize, Serialize};
use serge::SalientRegionMap;

use super::datasets::Dataset;
use crate::error::{Result, StudyError};

/// Cells per side of the raster Algorithm 3 runs on (its cost is quadratic in cells).
pub const COMPOSE_RASTER: usize = 48;
/// Configurations per state pair of the sampled table Algorithm 3 is checked against.
pub const SAMPLES_PER_PAIR: usize = 2_000;

/// One composition drawn (Fig 3.10): where G can be, given {DE:F} = r and {EF:G} = s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComposeExample {
    /// r's label.
    pub r: String,
    /// s's label.
    pub s: String,
    /// The states {DE:G} can be in.
    pub states: Vec<String>,
    /// The raster's window.
    pub window: [f64; 4],
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// State of every raster cell.
    pub cell_region: Vec<u32>,
    /// Cells where G can be.
    pub covered: Vec<bool>,
}

/// The learned calculus and the checks on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnedCalculus {
    /// Its spec (qsr-core's JSON).
    pub spec: String,
    /// States.
    pub n_states: usize,
    /// The map's raster (cells along x and y).
    pub raster: [usize; 2],
    /// Data points the loaded-back calculus classifies differently from the map (must be 0).
    pub mismatches: usize,
    /// Data points checked.
    pub points: usize,
    /// Entries of Algorithm 3's table on the coarse raster.
    pub algorithm3_entries: usize,
    /// Entries of the sampled, witnessed table.
    pub sampled_entries: usize,
    /// Sampled entries missing from Algorithm 3's (must be 0: it is sound by construction).
    pub missing: usize,
    /// Algorithm 3's table as JSON `{"states": [...], "table": {r: {s: [t, ...]}}}`.
    pub compose: serde_json::Value,
    /// The drawn composition: the state pair with the most data behind it whose entry is
    /// neither one state nor all.
    pub example: Option<ComposeExample>,
}

/// A compose table as JSON `{r: {s: [t, ...]}}` with state labels.
#[must_use]
pub fn compose_table_json(calc: &Calculus, table: &ComposeTable) -> serde_json::Value {
    let mut rows = serde_json::Map::new();
    for r in calc.states() {
        let mut row = serde_json::Map::new();
        for s in calc.states() {
            let labels: Vec<&str> = table.get(r, s).iter().map(|t| calc.label(*t)).collect();
            row.insert(calc.label(s).to_owned(), serde_json::json!(labels));
        }
        rows.insert(calc.label(r).to_owned(), serde_json::Value::Object(row));
    }
    serde_json::Value::Object(rows)
}

/// Learns the calculus of `map` (SERGE on `data`, μ and σ as named in its description),
/// loads it back, and checks Algorithm 3 against the sampled table.
///
/// # Errors
/// Calculus and SERGE errors.
pub fn learn_calculus(
    data: &Dataset,
    map: &SalientRegionMap,
    mu: usize,
    sigma: f64,
) -> Result<LearnedCalculus> {
    let calc = map.to_calculus(
        "hallway-learned",
        &format!("learned by SERGE from the hallway triplets (μ = {mu}, σ = {sigma})"),
    )?;
    let spec = calc.spec().to_json_string()?;
    // round trip: the spec loads back and classifies every data point as the map does
    let back = Calculus::from_json_str(&spec)?;
    let mut mismatches = 0usize;
    for p in data.points.iter().flatten() {
        let s = back.classify_normalised(&Point2::new(p[0], p[1]));
        if Some(u32::from(s.0)) != map.region_of(*p) {
            mismatches += 1;
        }
    }
    let coarse = back.rasterise(
        map.grid.window,
        COMPOSE_RASTER,
        COMPOSE_RASTER,
        OutsideRule::Clamp,
    )?;
    let cells = serge::learn::compose_table(&coarse, &|| {})?;
    let sampled = coarse.compose_table_with(&ComposeOptions {
        samples_per_pair: SAMPLES_PER_PAIR,
        ..ComposeOptions::default()
    })?;
    let mut missing = 0usize;
    for r in coarse.states() {
        for s in coarse.states() {
            missing += sampled
                .get(r, s)
                .iter()
                .filter(|t| !cells.get(r, s).contains(t))
                .count();
        }
    }
    let compose = serde_json::json!({
        "states": coarse.labels(),
        "table": compose_table_json(&coarse, &cells),
    });
    Ok(LearnedCalculus {
        spec,
        n_states: calc.n_states(),
        raster: [map.grid.nx, map.grid.ny],
        mismatches,
        points: data.points.iter().map(Vec::len).sum(),
        algorithm3_entries: cells.n_entries(),
        sampled_entries: sampled.n_entries(),
        missing,
        example: compose_example(&coarse, &cells)?,
        compose,
    })
}

fn compose_example(coarse: &Calculus, cells: &ComposeTable) -> Result<Option<ComposeExample>> {
    let q = coarse.n_states();
    let mut best: Option<(usize, usize, usize)> = None;
    for r in 0..q {
        for s in 0..q {
            let n = cells.get(state(r), state(s)).len();
            if n > 1 && n < q && best.is_none_or(|(_, _, m)| n < m) {
                best = Some((r, s, n));
            }
        }
    }
    let Some((r, s, _)) = best else {
        return Ok(None);
    };
    let (r, s) = (state(r), state(s));
    let (covered, states) = serge::learn::compose_coverage(coarse, r, s)?;
    let raster =
        coarse.spec().raster.as_ref().ok_or_else(|| {
            StudyError::InvalidParameter("a rasterised calculus has a raster".into())
        })?;
    Ok(Some(ComposeExample {
        r: coarse.label(r).to_owned(),
        s: coarse.label(s).to_owned(),
        states: states.iter().map(|t| coarse.label(*t).to_owned()).collect(),
        window: raster.window,
        nx: raster.nx,
        ny: raster.ny,
        cell_region: raster.cells.iter().map(|&c| u32::from(c)).collect(),
        covered,
    }))
}

fn state(i: usize) -> StateId {
    // a calculus has at most u16::MAX states (qsr-core's StateId)
    StateId(u16::try_from(i).unwrap_or(u16::MAX))
}
