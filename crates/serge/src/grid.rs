//! The fine grid of cells `C` (thesis §3.2.2) and each belief's mass on every cell.
//!
//! SERGE searches over unions of cells, so the cells bound how finely region borders can
//! follow the data. We use a rectangular grid over a window chosen from the beliefs; the
//! outermost ring of cells extends to infinity (a border cell owns everything beyond it
//! that is closer to it than to any other border cell, as a learned calculus's `clamp`
//! rule does), so every belief's masses sum to exactly 1 and no probability is lost at the
//! window's edge.
//!
//! Masses (saliency of a cell for a belief, §3.2.1): exact for Gaussians through the
//! bivariate normal distribution function at the grid vertices ([`crate::bvn`], absolute
//! error ≲ 1e-15 per cell); for sample beliefs the fraction of samples in the cell (each
//! mass has the binomial standard error `√(m(1−m)/n)`, 0.005 at m = 0.5 for n = 10,000).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::belief::{Belief, BeliefSet};
use crate::bvn;
use crate::error::{Result, SergeError};
use qsr_core::cost::{Budget, Cost};

/// Most cells a grid may have (masses are stored densely, `K × N` f64).
pub const MAX_CELLS: usize = 4_000_000;

/// A rectangular grid: `nx × ny` cells over `window = [x0, x1, y0, y1]`, row-major, row 0 at
/// `y0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// `[x_min, x_max, y_min, y_max]`.
    pub window: [f64; 4],
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
}

impl Grid {
    /// A grid over `window`.
    ///
    /// # Errors
    /// [`SergeError::InvalidParameter`] for an empty or non-finite window or a cell count
    /// that is zero or above [`MAX_CELLS`].
    pub fn new(window: [f64; 4], nx: usize, ny: usize) -> Result<Self> {
        let [x0, x1, y0, y1] = window;
        // The extent too must be finite: [-1.7e308, 1.7e308] has finite ends and an infinite
        // width, which made every cell infinitely wide (issue 17).
        if !window.iter().all(|v| v.is_finite())
            || x1 <= x0
            || y1 <= y0
            || !(x1 - x0).is_finite()
            || !(y1 - y0).is_finite()
        {
            return Err(SergeError::InvalidParameter(format!(
                "grid window {window:?} must be finite with x_min < x_max and y_min < y_max"
            )));
        }
        if nx == 0 || ny == 0 || nx.saturating_mul(ny) > MAX_CELLS {
            return Err(SergeError::InvalidParameter(format!(
                "a {nx}×{ny} grid is impossible (1 to {MAX_CELLS} cells)"
            )));
        }
        Ok(Self { window, nx, ny })
    }

    /// A grid covering the bulk of every belief ([`BeliefSet::extent`]) plus a 5 % margin.
    ///
    /// # Errors
    /// As [`Grid::new`].
    pub fn around(beliefs: &BeliefSet, nx: usize, ny: usize) -> Result<Self> {
        let [x0, x1, y0, y1] = beliefs.extent();
        // A single tight belief would give a zero-size window: at least 1e-6 wide.
        let (w, h) = ((x1 - x0).max(1e-6), (y1 - y0).max(1e-6));
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        Self::new(
            [cx - 0.55 * w, cx + 0.55 * w, cy - 0.55 * h, cy + 0.55 * h],
            nx,
            ny,
        )
    }

    /// Number of cells `N`.
    #[must_use]
    pub fn len(&self) -> usize {
        self.nx * self.ny
    }

    /// True for a grid without cells (never, for a validated grid).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Cell size `(dx, dy)`.
    #[must_use]
    pub fn cell_size(&self) -> (f64, f64) {
        let [x0, x1, y0, y1] = self.window;
        ((x1 - x0) / self.nx as f64, (y1 - y0) / self.ny as f64)
    }

    /// The cell of a point; points outside the window go to the nearest border cell.
    #[must_use]
    pub fn cell_of(&self, p: [f64; 2]) -> usize {
        let (dx, dy) = self.cell_size();
        let ix = ((p[0] - self.window[0]) / dx).floor();
        let iy = ((p[1] - self.window[2]) / dy).floor();
        let ix = if ix.is_nan() {
            0.0
        } else {
            ix.clamp(0.0, (self.nx - 1) as f64)
        } as usize;
        let iy = if iy.is_nan() {
            0.0
        } else {
            iy.clamp(0.0, (self.ny - 1) as f64)
        } as usize;
        iy * self.nx + ix
    }

    /// The centre of a cell.
    #[must_use]
    pub fn centre(&self, cell: usize) -> [f64; 2] {
        let (dx, dy) = self.cell_size();
        let (ix, iy) = (cell % self.nx, cell / self.nx);
        [
            self.window[0] + (ix as f64 + 0.5) * dx,
            self.window[2] + (iy as f64 + 0.5) * dy,
        ]
    }

    /// The x coordinate of vertical grid line `i` (0..=nx); the outer lines are ∓∞ when
    /// `unbounded`.
    fn xline(&self, i: usize, unbounded: bool) -> f64 {
        if unbounded && i == 0 {
            f64::NEG_INFINITY
        } else if unbounded && i == self.nx {
            f64::INFINITY
        } else {
            self.window[0] + i as f64 * self.cell_size().0
        }
    }

    fn yline(&self, j: usize, unbounded: bool) -> f64 {
        if unbounded && j == 0 {
            f64::NEG_INFINITY
        } else if unbounded && j == self.ny {
            f64::INFINITY
        } else {
            self.window[2] + j as f64 * self.cell_size().1
        }
    }

    /// The 4-neighbours of a cell (edge-sharing; contiguity in ψ2 is 4-connectivity).
    pub fn neighbours(&self, cell: usize) -> impl Iterator<Item = usize> + '_ {
        let (ix, iy) = (cell % self.nx, cell / self.nx);
        let nx = self.nx;
        [
            (ix > 0).then(|| cell - 1),
            (ix + 1 < self.nx).then(|| cell + 1),
            (iy > 0).then(|| cell - nx),
            (iy + 1 < self.ny).then(|| cell + nx),
        ]
        .into_iter()
        .flatten()
    }
}

/// `mass(k, n)`: the probability of belief `k` on cell `n`, dense `K × N`.
#[derive(Debug, Clone, PartialEq)]
pub struct CellMasses {
    grid: Grid,
    k: usize,
    data: Vec<f64>,
}

impl CellMasses {
    /// Computes every belief's mass on every cell (beliefs in parallel).
    ///
    /// # Errors
    /// [`SergeError::InvalidParameter`] when `K × N` is too large to hold.
    pub fn compute(beliefs: &BeliefSet, grid: Grid) -> Result<Self> {
        let n = grid.len();
        let k = beliefs.len();
        // Estimated before allocating: 400 beliefs on a 2000×2000 grid are 12.8 GB of masses,
        // which the allocator would abort on rather than report (issue 17).
        Cost::memory(k as f64 * n as f64 * 8.0)
            .check(&Budget::RUN, format!("{k} beliefs × {n} cells of masses"))
            .map_err(|e| SergeError::InvalidParameter(e.hint("use a coarser grid").to_string()))?;
        // Written in place, one belief's row per task: no second copy at the peak.
        let mut data = vec![0.0; k * n];
        data.par_chunks_mut(n.max(1))
            .zip(beliefs.as_slice().par_iter())
            .for_each(|(row, b)| row.copy_from_slice(&belief_masses(b, &grid)));
        Ok(Self { grid, k, data })
    }

    /// The grid.
    #[must_use]
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Number of beliefs.
    #[must_use]
    pub fn n_beliefs(&self) -> usize {
        self.k
    }

    /// Masses of belief `k` on all cells.
    #[must_use]
    pub fn row(&self, k: usize) -> &[f64] {
        let n = self.grid.len();
        &self.data[k * n..(k + 1) * n]
    }

    /// Mass of belief `k` on cell `cell`.
    #[must_use]
    pub fn get(&self, k: usize, cell: usize) -> f64 {
        self.data[k * self.grid.len() + cell]
    }
}

fn belief_masses(belief: &Belief, grid: &Grid) -> Vec<f64> {
    let n = grid.len();
    match belief {
        Belief::Gaussian { mean, cov } => {
            let (sx, sy) = (cov[0][0].sqrt(), cov[1][1].sqrt());
            let r = (cov[0][1] / (sx * sy)).clamp(-1.0, 1.0);
            // F at every grid vertex, outer lines at infinity.
            let (vx, vy) = (grid.nx + 1, grid.ny + 1);
            let us: Vec<f64> = (0..vx)
                .map(|i| (grid.xline(i, true) - mean[0]) / sx)
                .collect();
            let vs: Vec<f64> = (0..vy)
                .map(|j| (grid.yline(j, true) - mean[1]) / sy)
                .collect();
            // Beyond 9 sd, Φ < 1.2e-19: F is 0, Φ(u) or Φ(v) to well below the 1e-15 noise
            // floor, so Genz's integral is skipped there.
            let mut f = vec![0.0; vx * vy];
            for (j, &v) in vs.iter().enumerate() {
                for (i, &u) in us.iter().enumerate() {
                    f[j * vx + i] = if u < -9.0 || v < -9.0 {
                        0.0
                    } else if u > 9.0 {
                        bvn::phi(v)
                    } else if v > 9.0 {
                        bvn::phi(u)
                    } else {
                        bvn::cdf(u, v, r)
                    };
                }
            }
            let mut out = vec![0.0; n];
            for iy in 0..grid.ny {
                for ix in 0..grid.nx {
                    let m = f[(iy + 1) * vx + ix + 1] - f[iy * vx + ix + 1] - f[(iy + 1) * vx + ix]
                        + f[iy * vx + ix];
                    // Differences of four values each within ~1e-15: below that is noise.
                    out[iy * grid.nx + ix] = if m > 1e-15 { m } else { 0.0 };
                }
            }
            out
        }
        Belief::Samples { samples } => {
            let mut out = vec![0.0; n];
            let w = 1.0 / samples.len() as f64;
            for p in samples {
                out[grid.cell_of(*p)] += w;
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_masses_sum_to_one_and_match_the_marginal() {
        let b = BeliefSet::new(vec![Belief::gaussian(
            [0.3, -0.2],
            [[1.0, 0.6], [0.6, 2.0]],
        )])
        .unwrap();
        let grid = Grid::new([-2.0, 2.0, -2.0, 2.0], 8, 8).unwrap();
        let m = CellMasses::compute(&b, grid).unwrap();
        let total: f64 = m.row(0).iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        // Column 0 holds x ≤ −1.5 (extended to −∞): Φ((−1.5 − 0.3)/1).
        let col0: f64 = (0..8).map(|iy| m.get(0, iy * 8)).sum();
        assert!((col0 - bvn::phi(-1.8)).abs() < 1e-12);
    }

    #[test]
    fn samples_outside_the_window_land_in_border_cells() {
        let b = BeliefSet::new(vec![Belief::samples(vec![[-100.0, 0.5], [0.5, 0.5]])]).unwrap();
        let grid = Grid::new([0.0, 1.0, 0.0, 1.0], 2, 2).unwrap();
        let m = CellMasses::compute(&b, grid).unwrap();
        assert_eq!(m.row(0), &[0.0, 0.0, 0.5, 0.5]);
    }
}
