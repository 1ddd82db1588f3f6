//! The conceptual-neighbourhood graph and the neighbour distance (thesis §2.3.1).
//!
//! Two states are **adjacent** when they share a boundary or a corner; the **neighbour
//! distance** between two states is the length of the shortest path between them in this
//! graph (0 for the same state; at most 4 in the EDC).
//!
//! How adjacency is found:
//! - constraint calculi: at points exactly on every boundary curve (lines followed out to
//!   10^6) the states on a ring of radius 1e-7·max(1, |p|) are collected (16 directions; 360
//!   at curve intersections, so wedges that meet only at a corner are caught); every pair met
//!   on one ring is adjacent. Two states closer than that ring without touching would be
//!   reported adjacent; no built-in calculus has such a pair.
//! - raster calculi: states that occur in a common 3×3 block of cells are adjacent, so that
//!   up to six wedges meeting at one point (the EDC's circle intersections) are all caught at
//!   any raster resolution; features narrower than two cells can add adjacencies.

use petgraph::graph::{NodeIndex, UnGraph};
use rayon::prelude::*;

use crate::partition::Partition;
use crate::sampled::{DERIVED_SEED, Sampled};
use crate::state::StateId;

/// Boundary points probed for constraint calculi.
const BOUNDARY_PROBES: usize = 60_000;

/// Adjacency of states plus all-pairs neighbour distances.
#[derive(Debug, Clone)]
pub struct NeighbourGraph {
    graph: UnGraph<StateId, ()>,
    distance: Vec<Vec<Option<u32>>>,
}

impl NeighbourGraph {
    pub(crate) fn compute(calculus: &impl Sampled) -> Self {
        let n = calculus.n_states();
        let adjacent = match calculus.partition() {
            Partition::Constraints(_) => ring_adjacency(calculus),
            Partition::Raster(_) => raster_adjacency(calculus),
        };
        Self::from_adjacency(n, &adjacent)
    }

    /// Builds the graph from an `n × n` symmetric adjacency matrix (diagonal ignored).
    #[must_use]
    pub fn from_adjacency(n: usize, adjacent: &[Vec<bool>]) -> Self {
        let mut graph = UnGraph::with_capacity(n, 4 * n);
        for i in 0..n {
            graph.add_node(StateId(i as u16));
        }
        for (i, row) in adjacent.iter().enumerate().take(n) {
            for (j, &adj) in row.iter().enumerate().take(n).skip(i + 1) {
                if adj || adjacent[j][i] {
                    graph.add_edge(NodeIndex::new(i), NodeIndex::new(j), ());
                }
            }
        }
        let distance = (0..n)
            .map(|i| {
                let d = petgraph::algo::dijkstra(&graph, NodeIndex::new(i), None, |_| 1u32);
                (0..n).map(|j| d.get(&NodeIndex::new(j)).copied()).collect()
            })
            .collect();
        Self { graph, distance }
    }

    /// Number of states.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.distance.len()
    }

    /// Whether two distinct states are adjacent.
    #[must_use]
    pub fn is_adjacent(&self, a: StateId, b: StateId) -> bool {
        a != b
            && self
                .graph
                .find_edge(NodeIndex::new(a.index()), NodeIndex::new(b.index()))
                .is_some()
    }

    /// Adjacent pairs `(a, b)` with `a < b`, sorted.
    #[must_use]
    pub fn edges(&self) -> Vec<(StateId, StateId)> {
        let mut e: Vec<_> = self
            .graph
            .edge_indices()
            .filter_map(|e| self.graph.edge_endpoints(e))
            .map(|(a, b)| {
                let (a, b) = (self.graph[a], self.graph[b]);
                if a < b { (a, b) } else { (b, a) }
            })
            .collect();
        e.sort_unstable();
        e
    }

    /// States adjacent to `s`, sorted.
    #[must_use]
    pub fn neighbours_of(&self, s: StateId) -> Vec<StateId> {
        let mut v: Vec<_> = self
            .graph
            .neighbors(NodeIndex::new(s.index()))
            .map(|n| self.graph[n])
            .collect();
        v.sort_unstable();
        v
    }

    /// Neighbour distance (hops), `None` if the states are not connected.
    #[must_use]
    pub fn distance(&self, a: StateId, b: StateId) -> Option<u32> {
        self.distance[a.index()][b.index()]
    }

    /// The full distance matrix in state order.
    #[must_use]
    pub fn distance_matrix(&self) -> &[Vec<Option<u32>>] {
        &self.distance
    }

    /// The largest neighbour distance, `None` if the graph is disconnected.
    #[must_use]
    pub fn diameter(&self) -> Option<u32> {
        let mut max = 0;
        for row in &self.distance {
            for d in row {
                max = max.max((*d)?);
            }
        }
        Some(max)
    }

    /// The underlying petgraph graph (nodes carry their [`StateId`]).
    #[must_use]
    pub fn graph(&self) -> &UnGraph<StateId, ()> {
        &self.graph
    }
}

fn ring_adjacency(calculus: &impl Sampled) -> Vec<Vec<bool>> {
    let n = calculus.n_states();
    let points = calculus
        .features()
        .boundary_points(BOUNDARY_PROBES, DERIVED_SEED ^ 0xb0d);
    let partition = calculus.partition();
    points
        .par_chunks(4096)
        .map(|chunk| {
            let mut adj = vec![vec![false; n]; n];
            let mut met: Vec<u16> = Vec::with_capacity(16);
            for &(p, is_vertex) in chunk {
                let dirs = if is_vertex { 360 } else { 16 };
                let rho = 1e-7 * p.coords.norm().max(1.0);
                met.clear();
                met.push(partition.classify(&p));
                for k in 0..dirs {
                    let th = std::f64::consts::TAU * (k as f64 + 0.5) / dirs as f64;
                    let q = p + nalgebra::Vector2::new(th.cos(), th.sin()) * rho;
                    met.push(partition.classify(&q));
                }
                met.sort_unstable();
                met.dedup();
                for (i, &a) in met.iter().enumerate() {
                    for &b in &met[i + 1..] {
                        adj[usize::from(a)][usize::from(b)] = true;
                    }
                }
            }
            adj
        })
        .reduce(
            || vec![vec![false; n]; n],
            |mut x, y| {
                for (rx, ry) in x.iter_mut().zip(y) {
                    for (a, b) in rx.iter_mut().zip(ry) {
                        *a |= b;
                    }
                }
                x
            },
        )
}

fn raster_adjacency(calculus: &impl Sampled) -> Vec<Vec<bool>> {
    let n = calculus.n_states();
    let mut adj = vec![vec![false; n]; n];
    let Partition::Raster(r) = calculus.partition() else {
        return adj;
    };
    let (nx, ny) = r.shape();
    let mut met: Vec<u16> = Vec::with_capacity(9);
    for iy in 0..ny {
        for ix in 0..nx {
            met.clear();
            for jy in iy.saturating_sub(1)..(iy + 2).min(ny) {
                for jx in ix.saturating_sub(1)..(ix + 2).min(nx) {
                    met.push(r.cell(jx, jy));
                }
            }
            let on_border = ix == 0 || iy == 0 || ix + 1 == nx || iy + 1 == ny;
            if on_border && let Some(o) = r.outside_state() {
                met.push(o);
            }
            met.sort_unstable();
            met.dedup();
            for (i, &a) in met.iter().enumerate() {
                for &b in &met[i + 1..] {
                    adj[usize::from(a)][usize::from(b)] = true;
                }
            }
        }
    }
    adj
}
