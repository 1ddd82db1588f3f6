//! The resolution-tree use case of thesis §3.4.3 (Fig 3.9): plan from a start to a goal on
//! the lab map, refining only the regions on the way.

use serde::{Deserialize, Serialize};
use serge::{CellMasses, ResolutionTree, SergeParams};

use super::cross_validation::StudyConfig;
use crate::error::Result;

/// One level of the plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TreeLevel {
    /// Regions reasoned over at this level.
    pub regions: usize,
    /// Regions on the path.
    pub path: usize,
    /// The map at this point (the cut of nodes planned over so far), cell by cell.
    pub cell_region: Vec<u32>,
    /// Cells of the path's regions.
    pub path_cells: Vec<bool>,
}

/// The plan and what it reasoned over.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResolutionTreeUse {
    /// Start (m).
    pub start: [f64; 2],
    /// Goal (m).
    pub goal: [f64; 2],
    /// The grid's window `[x0, x1, y0, y1]`.
    pub window: [f64; 4],
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// The levels, coarse to fine.
    pub levels: Vec<TreeLevel>,
    /// Regions reasoned over in all.
    pub regions_considered: usize,
    /// Beliefs of the finest map (what a flat plan reasons over).
    pub beliefs: usize,
}

/// Three regions at the top (μ = 3, σ = 1), then splits in two (μ = 2, σ = 1) along the
/// plan, from near the window's left edge to near its top right corner.
///
/// # Errors
/// SERGE's errors.
pub fn resolution_tree_use(masses: &CellMasses, config: &StudyConfig) -> Result<ResolutionTreeUse> {
    let trials = config.trials_per_belief * masses.n_beliefs();
    let mut tree = ResolutionTree::new(masses);
    tree.split(
        0,
        &SergeParams::new(3, 1.0).trials(trials).seed(config.seed),
    )?;
    let grid = *masses.grid();
    let start = [
        grid.window[0] + 0.15 * (grid.window[1] - grid.window[0]),
        0.0,
    ];
    let goal = [
        grid.window[1] - 0.12 * (grid.window[1] - grid.window[0]),
        grid.window[3] - 0.12 * (grid.window[3] - grid.window[2]),
    ];
    let plan = tree.plan(
        start,
        goal,
        &SergeParams::new(2, 1.0).trials(trials).seed(config.seed),
        10,
    )?;
    let mut levels = Vec::new();
    for (i, level) in plan.levels.iter().enumerate() {
        let mut cut: Vec<usize> = Vec::new();
        for l in &plan.levels[..=i] {
            cut.retain(|&n| n != l.node);
            cut.extend(&l.regions);
        }
        let map = tree.map_of(&cut)?;
        let path_cells: Vec<bool> = (0..grid.len())
            .map(|c| {
                level
                    .path
                    .iter()
                    .any(|&n| tree.nodes()[n].cells.binary_search(&c).is_ok())
            })
            .collect();
        levels.push(TreeLevel {
            regions: level.regions.len(),
            path: level.path.len(),
            cell_region: map.cell_region,
            path_cells,
        });
    }
    Ok(ResolutionTreeUse {
        start,
        goal,
        window: grid.window,
        nx: grid.nx,
        ny: grid.ny,
        levels,
        regions_considered: plan.regions_considered(),
        beliefs: masses.n_beliefs(),
    })
}
