//! The salient region (SR) map: what SERGE returns (thesis §3.2).
//!
//! Regions are unions of grid cells (eq. 3.3), numbered so that region 0 holds belief 0 and
//! each next region holds the lowest belief not yet placed; every belief is assigned to one
//! region (`L^B`), and its saliency is its mass on that region. The map answers which region
//! a point is in, which regions touch (a petgraph graph weighted by shared border length),
//! the outline of each region, how well it explains held-out data (test log likelihood and
//! error rate, §3.4.1), and exports itself as a qsr-core learned calculus (§3.3.2).

use petgraph::graph::UnGraph;
use qsr_core::{Calculus, CalculusSpec, FrameKind, OutsideRule, RasterSpec, StateSpec};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SergeError};
use crate::grid::{CellMasses, Grid};

/// Marks a cell that is not part of a (resolution-tree node's) map.
pub const OUTSIDE: u32 = u32::MAX;

/// A salient region map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SalientRegionMap {
    /// The grid the regions are made of.
    pub grid: Grid,
    /// Region of every grid cell ([`OUTSIDE`] for cells not in this map).
    pub cell_region: Vec<u32>,
    /// Global ids of the beliefs this map was built from (all of them for a full map).
    pub beliefs: Vec<usize>,
    /// `L^B`: region of each belief, in the order of `beliefs`.
    pub assignment: Vec<u32>,
    /// Saliency `S_k` of each belief on its region.
    pub saliency: Vec<f64>,
    /// Number of regions |R|.
    pub n_regions: usize,
    /// log ψ1 (eq. 3.5, with its normalisation β).
    pub log_psi1: f64,
    /// log ψ3 = Σ_k log S_k (eq. 3.7): the map's log saliency.
    pub log_saliency: f64,
    /// μ used.
    pub mu: usize,
    /// σ used.
    pub sigma: f64,
    /// Trials run.
    pub trials: usize,
    /// Seed used.
    pub seed: u64,
    /// The trial that produced this map.
    pub best_trial: usize,
}

/// `ln x`, with x floored at the smallest positive float: a belief with no mass in its region
/// scores very low but finite.
pub(crate) fn ln_floor(x: f64) -> f64 {
    x.max(f64::MIN_POSITIVE).ln()
}

impl SalientRegionMap {
    /// log φ = log ψ1 + log ψ3 (ψ2 = 1: every region is contiguous).
    #[must_use]
    pub fn log_phi(&self) -> f64 {
        self.log_psi1 + self.log_saliency
    }

    /// The region of a point (points outside the window: the nearest border cell's), or
    /// `None` when that cell is not part of this map.
    #[must_use]
    pub fn region_of(&self, p: [f64; 2]) -> Option<u32> {
        let r = self.cell_region[self.grid.cell_of(p)];
        (r != OUTSIDE).then_some(r)
    }

    /// The cells of region `r`.
    #[must_use]
    pub fn region_cells(&self, r: u32) -> Vec<usize> {
        (0..self.cell_region.len())
            .filter(|&c| self.cell_region[c] == r)
            .collect()
    }

    /// Beliefs (global ids) assigned to region `r`.
    #[must_use]
    pub fn region_beliefs(&self, r: u32) -> Vec<usize> {
        self.beliefs
            .iter()
            .zip(&self.assignment)
            .filter(|&(_, &a)| a == r)
            .map(|(&k, _)| k)
            .collect()
    }

    /// Whether this map covers every grid cell.
    #[must_use]
    pub fn is_complete(&self) -> bool {
        self.cell_region.iter().all(|&r| r != OUTSIDE)
    }

    /// Region adjacency: node `i` is region `i`, edge weight = shared border in cell edges.
    #[must_use]
    pub fn adjacency(&self) -> UnGraph<u32, u32> {
        let mut g = UnGraph::with_capacity(self.n_regions, 0);
        for r in 0..self.n_regions {
            g.add_node(r as u32);
        }
        let mut border: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
        for (c, &a) in self.cell_region.iter().enumerate() {
            if a == OUTSIDE {
                continue;
            }
            let (ix, iy) = (c % self.grid.nx, c / self.grid.nx);
            for nb in [
                (ix + 1 < self.grid.nx).then_some(c + 1),
                (iy + 1 < self.grid.ny).then_some(c + self.grid.nx),
            ]
            .into_iter()
            .flatten()
            {
                let b = self.cell_region[nb];
                if b != OUTSIDE && b != a {
                    *border.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
        }
        for ((a, b), len) in border {
            g.add_edge(a.into(), b.into(), len);
        }
        g
    }

    /// Outline of region `r` as closed rings of window coordinates (outer boundaries
    /// counter-clockwise, holes clockwise; the last point repeats the first).
    #[must_use]
    pub fn polygons(&self, r: u32) -> Vec<Vec<[f64; 2]>> {
        let (nx, ny) = (self.grid.nx, self.grid.ny);
        let inside = |ix: isize, iy: isize| {
            ix >= 0
                && iy >= 0
                && (ix as usize) < nx
                && (iy as usize) < ny
                && self.cell_region[iy as usize * nx + ix as usize] == r
        };
        // directed edges with the region on the left, keyed by start vertex
        let mut edges: std::collections::BTreeMap<(isize, isize), Vec<(isize, isize)>> =
            Default::default();
        for c in self.region_cells(r) {
            let (x, y) = ((c % nx) as isize, (c / nx) as isize);
            if !inside(x, y - 1) {
                edges.entry((x, y)).or_default().push((x + 1, y));
            }
            if !inside(x + 1, y) {
                edges.entry((x + 1, y)).or_default().push((x + 1, y + 1));
            }
            if !inside(x, y + 1) {
                edges.entry((x + 1, y + 1)).or_default().push((x, y + 1));
            }
            if !inside(x - 1, y) {
                edges.entry((x, y + 1)).or_default().push((x, y));
            }
        }
        let (dx, dy) = self.grid.cell_size();
        let to_xy = |(i, j): (isize, isize)| {
            [
                self.grid.window[0] + i as f64 * dx,
                self.grid.window[2] + j as f64 * dy,
            ]
        };
        let mut rings = Vec::new();
        while let Some((&start, _)) = edges.iter().find(|(_, v)| !v.is_empty()) {
            let mut ring = vec![start];
            let mut at = start;
            while let Some(next) = edges.get_mut(&at).and_then(Vec::pop) {
                at = next;
                ring.push(at);
                if at == start {
                    break;
                }
            }
            // drop collinear vertices
            let mut out: Vec<(isize, isize)> = Vec::with_capacity(ring.len());
            for &v in &ring {
                if out.len() >= 2 {
                    let (a, b) = (out[out.len() - 2], out[out.len() - 1]);
                    if (b.0 - a.0) * (v.1 - b.1) == (b.1 - a.1) * (v.0 - b.0) {
                        out.pop();
                    }
                }
                out.push(v);
            }
            rings.push(out.into_iter().map(to_xy).collect());
        }
        rings
    }

    /// Boundary segments between different regions (for drawing), window coordinates.
    #[must_use]
    pub fn boundary_segments(&self) -> Vec<[[f64; 2]; 2]> {
        let (nx, ny) = (self.grid.nx, self.grid.ny);
        let (dx, dy) = self.grid.cell_size();
        let [x0, _, y0, _] = self.grid.window;
        let mut out = Vec::new();
        for c in 0..nx * ny {
            let (ix, iy) = (c % nx, c / nx);
            let a = self.cell_region[c];
            if ix + 1 < nx && self.cell_region[c + 1] != a {
                let x = x0 + (ix + 1) as f64 * dx;
                out.push([[x, y0 + iy as f64 * dy], [x, y0 + (iy + 1) as f64 * dy]]);
            }
            if iy + 1 < ny && self.cell_region[c + nx] != a {
                let y = y0 + (iy + 1) as f64 * dy;
                out.push([[x0 + ix as f64 * dx, y], [x0 + (ix + 1) as f64 * dx, y]]);
            }
        }
        out
    }

    /// Number of connected components of region `r` (ψ2 needs 1 for every region).
    #[must_use]
    pub fn components(&self, r: u32) -> usize {
        let cells = self.region_cells(r);
        let mut seen = std::collections::HashSet::new();
        let mut count = 0;
        for &s in &cells {
            if !seen.insert(s) {
                continue;
            }
            count += 1;
            let mut stack = vec![s];
            while let Some(c) = stack.pop() {
                for nb in self.grid.neighbours(c) {
                    if self.cell_region[nb] == r && seen.insert(nb) {
                        stack.push(nb);
                    }
                }
            }
        }
        count
    }

    /// Test-data log likelihood `log ψ3(B_test, L^B, R)` (§3.4.1): `test` holds, for each
    /// of this map's beliefs in order, a held-out belief's masses on the same grid.
    ///
    /// # Errors
    /// [`SergeError::InvalidParameter`] when the grid or the number of beliefs differ.
    pub fn log_likelihood(&self, test: &CellMasses) -> Result<f64> {
        if *test.grid() != self.grid || test.n_beliefs() != self.beliefs.len() {
            return Err(SergeError::InvalidParameter(format!(
                "test masses ({} beliefs on {:?}) do not match the map ({} beliefs on {:?})",
                test.n_beliefs(),
                test.grid(),
                self.beliefs.len(),
                self.grid
            )));
        }
        let mut per_region: Vec<Vec<usize>> = vec![Vec::new(); self.n_regions];
        for (c, &r) in self.cell_region.iter().enumerate() {
            if r != OUTSIDE {
                per_region[r as usize].push(c);
            }
        }
        Ok(self
            .assignment
            .iter()
            .enumerate()
            .map(|(j, &r)| {
                ln_floor(
                    per_region[r as usize]
                        .iter()
                        .map(|&c| test.get(j, c))
                        .sum::<f64>(),
                )
            })
            .sum())
    }

    /// Error rate (§3.4.1): the fraction of held-out data points of each belief (in this
    /// map's belief order) that fall outside the belief's region. Returns `(errors, total)`.
    ///
    /// # Errors
    /// [`SergeError::InvalidParameter`] when the number of point lists differs.
    pub fn errors(&self, points: &[Vec<[f64; 2]>]) -> Result<(usize, usize)> {
        if points.len() != self.beliefs.len() {
            return Err(SergeError::InvalidParameter(format!(
                "{} point lists for {} beliefs",
                points.len(),
                self.beliefs.len()
            )));
        }
        let mut errors = 0;
        let mut total = 0;
        for (pts, &r) in points.iter().zip(&self.assignment) {
            for p in pts {
                total += 1;
                if self.region_of(*p) != Some(r) {
                    errors += 1;
                }
            }
        }
        Ok((errors, total))
    }

    /// The map as a learned ternary calculus (§3.3.2): the grid becomes the raster over the
    /// normalised frame, regions become states labelled `"1"`, `"2"`, …, and points outside
    /// the window take the nearest border cell's state (`clamp`, as the masses did). Only
    /// meaningful when the beliefs were in a normalised frame (see [`crate::learn`]).
    ///
    /// # Errors
    /// [`SergeError::InvalidParameter`] for an incomplete map or more than 65,535 regions;
    /// calculus validation errors.
    pub fn to_calculus(&self, name: &str, description: &str) -> Result<Calculus> {
        Ok(Calculus::from_spec(
            self.to_calculus_spec(name, description)?,
        )?)
    }

    /// The spec of [`SalientRegionMap::to_calculus`].
    ///
    /// # Errors
    /// As [`SalientRegionMap::to_calculus`].
    pub fn to_calculus_spec(&self, name: &str, description: &str) -> Result<CalculusSpec> {
        if !self.is_complete() {
            return Err(SergeError::InvalidParameter(
                "only a map covering the whole grid can become a calculus (export a full map \
                 or a resolution-tree cut)"
                    .into(),
            ));
        }
        if self.n_regions > usize::from(u16::MAX) {
            return Err(SergeError::InvalidParameter(format!(
                "{} regions do not fit a calculus (at most 65,535 states)",
                self.n_regions
            )));
        }
        Ok(CalculusSpec {
            name: name.to_owned(),
            description: description.to_owned(),
            frame: FrameKind::Ternary,
            constraints: Vec::new(),
            raster: Some(RasterSpec {
                window: self.grid.window,
                nx: self.grid.nx,
                ny: self.grid.ny,
                cells: self.cell_region.iter().map(|&r| r as u16).collect(),
                outside: OutsideRule::Clamp,
            }),
            states: (1..=self.n_regions)
                .map(|i| StateSpec {
                    label: i.to_string(),
                    cells: Vec::new(),
                })
                .collect(),
        })
    }

    /// The map as JSON: the fields above plus `n_regions`, `assignment`, `log_saliency`,
    /// `log_phi`, region adjacency and outlines.
    #[must_use]
    pub fn to_json(&self) -> serde_json::Value {
        let adj = self.adjacency();
        let edges: Vec<[u32; 3]> = adj
            .edge_indices()
            .filter_map(|e| {
                let (a, b) = adj.edge_endpoints(e)?;
                Some([a.index() as u32, b.index() as u32, adj[e]])
            })
            .collect();
        let regions: Vec<serde_json::Value> = (0..self.n_regions as u32)
            .map(|r| {
                serde_json::json!({
                    "id": r,
                    "beliefs": self.region_beliefs(r),
                    "n_cells": self.cell_region.iter().filter(|&&x| x == r).count(),
                    "polygons": self.polygons(r),
                })
            })
            .collect();
        serde_json::json!({
            "format": "qrm-serge-map",
            "version": 1,
            "n_regions": self.n_regions,
            "assignment": self.assignment,
            "saliency": self.saliency,
            "log_saliency": self.log_saliency,
            "log_psi1": self.log_psi1,
            "log_phi": self.log_phi(),
            "mu": self.mu,
            "sigma": self.sigma,
            "trials": self.trials,
            "seed": self.seed,
            "best_trial": self.best_trial,
            "beliefs": self.beliefs,
            "grid": self.grid,
            "cell_region": self.cell_region.iter().map(|&r| if r == OUTSIDE { -1 } else { i64::from(r) }).collect::<Vec<_>>(),
            "adjacency": edges,
            "regions": regions,
        })
    }
}
