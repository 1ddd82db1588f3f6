//! Example maps on all of a dataset's data (thesis Fig 3.8), and the dataset's use case:
//! the resolution-tree plan for the lab (Fig 3.9), the learned calculus for the hallway
//! (§3.3.2, Fig 3.10).

use serde::{Deserialize, Serialize};
use serge::{CellMasses, Grid, SalientRegionMap, Serge, SergeParams};

use super::cross_validation::StudyConfig;
use super::datasets::{Dataset, DatasetName};
use super::learned_calculus::{LearnedCalculus, learn_calculus};
use super::resolution_tree::{ResolutionTreeUse, resolution_tree_use};
use crate::error::Result;

/// A partition of a grid into regions, cell by cell (what a picture of a map needs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionGrid {
    /// `[x0, x1, y0, y1]`.
    pub window: [f64; 4],
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Region of every cell.
    pub cell_region: Vec<u32>,
}

impl RegionGrid {
    /// The grid of `map`.
    #[must_use]
    pub fn of(map: &SalientRegionMap) -> Self {
        Self {
            window: map.grid.window,
            nx: map.grid.nx,
            ny: map.grid.ny,
            cell_region: map.cell_region.clone(),
        }
    }
}

/// One example map on all data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExampleMap {
    /// File stem (`map_mu55_sigma0p01`).
    pub stem: String,
    /// μ.
    pub mu: usize,
    /// σ.
    pub sigma: f64,
    /// |R|.
    pub n_regions: usize,
    /// Log saliency on all data.
    pub log_saliency: f64,
    /// The map's regions.
    pub grid: RegionGrid,
    /// The map as `qrm serge run` writes it (`SalientRegionMap::to_json`).
    pub map: serde_json::Value,
}

/// A dataset's example maps and its use case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetExamples {
    /// Every data point (drawn over the maps).
    pub points: Vec<[f64; 2]>,
    /// Maps on all data.
    pub maps: Vec<ExampleMap>,
    /// The lab's resolution-tree plan.
    pub resolution_tree: Option<ResolutionTreeUse>,
    /// The hallway's learned calculus.
    pub learned_calculus: Option<LearnedCalculus>,
}

/// The (μ, σ) of the example maps the thesis shows for `name`.
fn settings(name: DatasetName) -> Vec<(usize, f64)> {
    match name {
        DatasetName::Lab => vec![(55, 0.01), (55, 2.0), (10, 2.0)],
        DatasetName::Hallway => vec![(18, 2.0), (10, 2.0)],
        DatasetName::WellSeparated => vec![(49, 2.0), (20, 2.0)],
    }
}

/// The example maps of `data` and its use case.
///
/// # Errors
/// SERGE's and the calculus's errors.
pub fn examples(
    data: &Dataset,
    name: DatasetName,
    config: &StudyConfig,
) -> Result<DatasetExamples> {
    let k = data.len();
    let beliefs = data.beliefs(|_, _| true, config.seed ^ 0xa11)?;
    let points: Vec<[f64; 2]> = data.points.iter().flatten().copied().collect();
    let trials = config.trials_per_belief * k;
    let grid = if name == DatasetName::Hallway {
        // the normalised frame: the bulk of the triplets, not the far tails
        Grid::new([-6.0, 6.0, -5.0, 7.0], config.grid, config.grid)?
    } else {
        Grid::around(&beliefs, config.grid, config.grid)?
    };
    let masses = CellMasses::compute(&beliefs, grid)?;
    let serge = Serge::new(&masses)?;
    let mut maps = Vec::new();
    let mut first: Option<SalientRegionMap> = None;
    for (mu, sigma) in settings(name) {
        let mu = mu.min(k);
        let map = serge.run(&SergeParams::new(mu, sigma).trials(trials).seed(config.seed))?;
        maps.push(ExampleMap {
            stem: format!("map_mu{mu}_sigma{}", sigma.to_string().replace('.', "p")),
            mu,
            sigma,
            n_regions: map.n_regions,
            log_saliency: map.log_saliency,
            grid: RegionGrid::of(&map),
            map: map.to_json(),
        });
        first.get_or_insert(map);
    }
    let resolution_tree = match name {
        DatasetName::Lab => Some(resolution_tree_use(&masses, config)?),
        _ => None,
    };
    let learned_calculus = match (name, &first) {
        (DatasetName::Hallway, Some(map)) => {
            Some(learn_calculus(data, map, maps[0].mu, maps[0].sigma)?)
        }
        _ => None,
    };
    Ok(DatasetExamples {
        points,
        maps,
        resolution_tree,
        learned_calculus,
    })
}
