//! A salient region map of a user's own beliefs (`qrm serge run`): SERGE (thesis §3.2) over a
//! grid around them, the map as JSON and its picture.

use std::time::Instant;

use serde_json::json;
use serge::{BeliefSet, CellMasses, Grid, SalientRegionMap, Serge, SergeParams};

use crate::error::Result;
use crate::report::{Attachment, Figure, Plot, Products};

/// Region numbers are written on a picture of at most this many regions.
pub const NUMBERED_UP_TO: usize = 60;

/// SERGE over a user's beliefs.
#[derive(Debug, Clone)]
pub struct RegionMapJob {
    /// The beliefs.
    pub beliefs: BeliefSet,
    /// Grid window `[x0, x1, y0, y1]` (`None`: around the beliefs).
    pub window: Option<[f64; 4]>,
    /// Grid cells per side.
    pub cells: usize,
    /// μ, σ, trials and seed.
    pub params: SergeParams,
}

/// The map SERGE found, with what it started from and how long it took.
#[derive(Debug, Clone)]
pub struct RegionMapRun {
    /// The map.
    pub map: SalientRegionMap,
    /// Regions before merging (one per belief's support, split where they overlap).
    pub initial_regions: usize,
    /// Beliefs mapped.
    pub beliefs: usize,
    /// The beliefs' means, drawn over the map.
    pub means: Vec<[f64; 2]>,
    /// Time SERGE took (s).
    pub seconds: f64,
}

impl RegionMapJob {
    /// Runs SERGE.
    ///
    /// # Errors
    /// [`crate::StudyError::Serge`] for a window, grid or μ SERGE refuses.
    pub fn run(&self) -> Result<RegionMapRun> {
        let grid = match self.window {
            Some(w) => Grid::new(w, self.cells, self.cells)?,
            None => Grid::around(&self.beliefs, self.cells, self.cells)?,
        };
        let start = Instant::now();
        let masses = CellMasses::compute(&self.beliefs, grid)?;
        let serge = Serge::new(&masses)?;
        let map = serge.run(&self.params)?;
        Ok(RegionMapRun {
            map,
            initial_regions: serge.n_initial_regions(),
            beliefs: self.beliefs.len(),
            means: self
                .beliefs
                .as_slice()
                .iter()
                .map(serge::Belief::mean)
                .collect(),
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}

impl RegionMapRun {
    /// One line: beliefs, regions, saliency, trials and time.
    #[must_use]
    pub fn describe(&self) -> String {
        let m = &self.map;
        format!(
            "{} beliefs, {} initial regions → {} regions; log saliency {:.4}; log φ {:.4}; {} trials in {:.2} s",
            self.beliefs,
            self.initial_regions,
            m.n_regions,
            m.log_saliency,
            m.log_phi(),
            m.trials,
            self.seconds
        )
    }

    /// `map.json` (the map, its initial regions and time, indented) and the picture `map`.
    #[must_use]
    pub fn products(&self) -> Products {
        let mut doc = self.map.to_json();
        doc["initial_regions"] = json!(self.initial_regions);
        doc["seconds"] = json!(self.seconds);
        let m = &self.map;
        let title = format!(
            "SERGE: {} regions (μ = {}, σ = {}), log saliency {:.3}",
            m.n_regions, m.mu, m.sigma, m.log_saliency
        );
        Products {
            tables: Vec::new(),
            figures: vec![map_figure("map", title, m, self.means.clone())],
            attachments: vec![Attachment::text("map.json", format!("{doc:#}"))],
        }
    }
}

/// A salient region map drawn with data points over it.
#[must_use]
pub fn map_figure(
    name: &str,
    title: String,
    map: &SalientRegionMap,
    points: Vec<[f64; 2]>,
) -> Figure {
    Figure {
        name: name.to_owned(),
        title,
        x_label: "x".to_owned(),
        y_label: "y".to_owned(),
        plot: Plot::Regions {
            window: map.grid.window,
            nx: map.grid.nx,
            ny: map.grid.ny,
            cell_region: map.cell_region.clone(),
            points,
            shade: None,
            marks: Vec::new(),
            numbers: map.n_regions <= NUMBERED_UP_TO,
        },
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    #[test]
    fn two_far_apart_beliefs_make_two_regions_each_numbered_on_the_picture() {
        let text = r#"{"beliefs": [{"mean": [0, 0], "cov": [[0.1, 0], [0, 0.1]]},
                                  {"mean": [5, 0], "cov": [[0.1, 0], [0, 0.1]]}]}"#;
        let job = RegionMapJob {
            beliefs: BeliefSet::from_json_str(text, "test").unwrap(),
            window: None,
            cells: 40,
            params: SergeParams::new(2, 0.0).seed(1),
        };
        let run = job.run().unwrap();
        assert_eq!(run.map.n_regions, 2);
        assert_eq!(run.means, [[0.0, 0.0], [5.0, 0.0]]);
        let products = run.products();
        let doc: serde_json::Value = serde_json::from_str(&products.attachments[0].text).unwrap();
        assert_eq!(doc["initial_regions"], json!(run.initial_regions));
        assert!(matches!(
            products.figures[0].plot,
            Plot::Regions { numbers: true, .. }
        ));
    }
}
