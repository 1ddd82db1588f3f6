//! # serge — salient region generation (thesis chapter 3)
//!
//! Given beliefs about where objects are (Gaussians or sample sets: a SLAM map, triplets in
//! a normalised frame, anything spatial), SERGE finds a *salient region map*: a partition of
//! the plane into μ-ish contiguous regions, each belief assigned to one region, that makes
//! the product of the beliefs' masses on their regions (the map's *saliency*) high.
//!
//! ```
//! use serge::{Belief, BeliefSet, CellMasses, Grid, Serge, SergeParams};
//!
//! // two objects far apart and two close together
//! let cov = [[0.04, 0.0], [0.0, 0.04]];
//! let beliefs = BeliefSet::new(vec![
//!     Belief::gaussian([0.0, 0.0], cov),
//!     Belief::gaussian([5.0, 0.0], cov),
//!     Belief::gaussian([5.0, 0.3], cov),
//! ])?;
//! let grid = Grid::around(&beliefs, 60, 30)?;
//! let masses = CellMasses::compute(&beliefs, grid)?;
//! // ask for two regions: the close pair shares one
//! let map = Serge::new(&masses)?.run(&SergeParams::new(2, 0.0).trials(50).seed(7))?;
//! assert_eq!(map.n_regions, 2);
//! assert_eq!(map.assignment, vec![0, 1, 1]);
//! assert!(map.log_saliency > -1e-6); // every belief fully inside its region
//! # Ok::<(), serge::SergeError>(())
//! ```
//!
//! ## Why it is built this way
//! - **Cells, then regions.** Regions are unions of grid cells (§3.2.2), so saliencies are
//!   sums of per-cell masses computed once ([`CellMasses`]: exact bivariate-normal
//!   rectangle probabilities for Gaussians, histograms for samples).
//! - **Incremental search.** A candidate merge changes the saliency of the beliefs of two
//!   regions only; [`Serge`] scores it from a region × belief mass table in time
//!   proportional to those beliefs. [`baseline::run_naive`] scores from the cells, as a
//!   cross-check and for the benchmark.
//! - **Deterministic parallel trials.** Trials are independent greedy ascents with their own
//!   seeded generators, run with rayon and reduced over a total order.
//! - **Calculi are qsr-core calculi.** A map in a normalised triplet frame exports as a raster
//!   calculus that `qrm calculus`, pqrm and qlink accept ([`SalientRegionMap::to_calculus`]);
//!   [`learn::compose_table`] gives its compose table by Algorithm 3 with interval bounds,
//!   sound by construction.
//!
//! ## Naming rule
//! Nouns are data (`Belief`, `Grid`, `SalientRegionMap`, `ResolutionTree`); `run`/`split`/
//! `plan` do the chapter's algorithms; `to_*` converts; `compose_*` are Algorithm 3.
//!
//! ## Errors
//! [`SergeError`]: `Empty` (no beliefs, no samples), `NonFinite`, `DegenerateCovariance`,
//! `InvalidParameter` (μ outside `1..=min(K, N)`, σ < 0, zero trials, bad grid),
//! `NoMass` (no cell holds any mass), `Unknown` (node/cell/belief ids), `Calculus`,
//! `Io`, `Parse`.

pub mod baseline;
mod belief;
pub mod bvn;
mod error;
mod grid;
mod init;
pub mod learn;
pub mod learner;
mod map;
pub mod selection;
#[allow(clippy::module_inception)]
mod serge;
mod tree;

pub use belief::{Belief, BeliefSet};
pub use error::{Result, SergeError};
pub use grid::{CellMasses, Grid, MAX_CELLS};
pub use map::{OUTSIDE, SalientRegionMap};
pub use serge::{Serge, SergeParams, log_psi1};
pub use tree::{LevelPlan, ResolutionTree, TreeNode, TreePlan};
