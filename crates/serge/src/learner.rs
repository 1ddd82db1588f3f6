//! A calculus learned from a recording, end to end (thesis §3.3.2): the triplets
//! [`TripletSelection`] chooses from the frames, their beliefs
//! ([`crate::learn::triplet_beliefs`]), SERGE over a grid of the normalised window, and the SR
//! map, which [`SalientRegionMap::to_calculus`] turns into a raster calculus. One learner for
//! `qrm serge learn`, the demo, and a robot that learns its own calculus.

use crate::error::Result;
use crate::grid::{CellMasses, Grid};
use crate::learn::triplet_beliefs;
use crate::selection::{Selected, Sighting, TripletSelection};
use crate::{SalientRegionMap, Serge, SergeParams};
use qsr_core::cost::{Budget, Cost};

/// How a calculus is learned. One seed (the selection's) draws the triplets, their belief
/// samples and SERGE's trials, so a learner and its frames give one calculus.
#[derive(Debug, Clone, PartialEq)]
#[must_use]
pub struct CalculusLearner {
    /// Which triplets, how many, and the seed.
    pub selection: TripletSelection,
    /// Samples per triplet belief.
    pub samples: usize,
    /// The normalised window `[x0, x1, y0, y1]` the grid covers.
    pub window: [f64; 4],
    /// Grid cells per side.
    pub cells: usize,
    /// Desired number of states μ (at most the triplets selected).
    pub mu: usize,
    /// Tolerance σ.
    pub sigma: f64,
    /// SERGE's trials (`None`: 100·K).
    pub trials: Option<usize>,
}

impl CalculusLearner {
    /// The normalised window the thesis's learned calculi cover: the frame's points at
    /// (0, 0) and (0, 1) with three units of margin.
    pub const WINDOW: [f64; 4] = [-3.0, 3.0, -2.5, 3.5];

    /// μ states within σ, with `seed`: 60 triplets seen together in 5 frames or more, 2,000
    /// samples per belief, a 64 × 64 grid over [`CalculusLearner::WINDOW`].
    pub fn new(mu: usize, sigma: f64, seed: u64) -> Self {
        Self {
            selection: TripletSelection {
                min_frames: 5,
                max_triplets: 60,
                seed,
            },
            samples: 2000,
            window: Self::WINDOW,
            cells: 64,
            mu,
            sigma,
            trials: None,
        }
    }

    /// Bytes the learner will hold at most: `samples` points (16 B) and `cells²` masses (8 B)
    /// per selected triplet, and SERGE's work arrays over the cells (a few per cell).
    pub fn estimated_cost(&self) -> Cost {
        let triplets = self.selection.max_triplets as f64;
        let cells = (self.cells as f64).powi(2);
        Cost::memory(triplets * (self.samples as f64 * 16.0 + cells * 8.0) + cells * 64.0)
    }

    /// Checks the sizes before any work: samples, cells and triplets of at least one, and
    /// the memory they ask for within [`Budget::RUN`] (issue 39: `--samples
    /// 18446744073709551615` panicked with a capacity overflow).
    ///
    /// # Errors
    /// [`crate::SergeError::InvalidParameter`] naming the field and the estimate.
    pub fn validate(&self) -> Result<()> {
        for (field, v) in [
            ("samples", self.samples),
            ("cells", self.cells),
            ("max_triplets", self.selection.max_triplets),
        ] {
            if v == 0 {
                return Err(crate::SergeError::InvalidParameter(format!(
                    "{field} = 0: at least 1"
                )));
            }
        }
        self.estimated_cost()
            .check(
                &Budget::RUN,
                format!(
                    "samples = {}, cells = {} and max_triplets = {}",
                    self.samples, self.cells, self.selection.max_triplets
                ),
            )
            .map_err(|e| {
                crate::SergeError::InvalidParameter(
                    e.hint("fewer samples, cells or triplets").to_string(),
                )
            })?;
        Ok(())
    }

    /// Selects triplets from `frames` (the landmarks each frame saw) and learns from them.
    ///
    /// # Errors
    /// [`crate::SergeError::InvalidParameter`] when no set was seen together often enough or
    /// for sizes [`CalculusLearner::validate`] refuses; as [`CalculusLearner::learn_from`].
    pub fn learn(&self, frames: &[Vec<Sighting>]) -> Result<(Selected, SalientRegionMap)> {
        self.validate()?;
        let selected = self.selection.select(frames)?;
        let map = self.learn_from(&selected)?;
        Ok((selected, map))
    }

    /// SERGE over the beliefs of triplets already selected.
    ///
    /// # Errors
    /// SERGE's: a window or grid that is not one, μ or σ out of range.
    pub fn learn_from(&self, selected: &Selected) -> Result<SalientRegionMap> {
        self.validate()?;
        let n = selected.triplets.len();
        let seed = self.selection.seed;
        let beliefs = triplet_beliefs(&selected.observations, n, self.samples, seed)?;
        let grid = Grid::new(self.window, self.cells, self.cells)?;
        let masses = CellMasses::compute(&beliefs, grid)?;
        let mut params = SergeParams::new(self.mu.min(n), self.sigma).seed(seed);
        if let Some(t) = self.trials {
            params = params.trials(t);
        }
        Serge::new(&masses)?.run(&params)
    }
}
