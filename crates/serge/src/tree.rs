//! The resolution tree (thesis §3.3.1) and planning over it (§3.4.3).
//!
//! The root (level 0) is one region holding every cell and belief. Splitting a node runs
//! SERGE on that node's cells and beliefs only (the selection potentials ψ_B, ψ_C of eqs.
//! 3.9–3.10), with μ = 2 by default; its regions become the node's children one level
//! down. A *cut* — any set of nodes whose cells partition the grid — is a map, so the tree
//! can be read at one level or at different levels in different branches.
//!
//! Planning refines only where it must: plan over the root's children, move into the child
//! holding the goal, split that child (if not yet split) and plan over its children, and so
//! on. Each level's plan is an A* search (petgraph) over the children's adjacency with
//! centroid distances as edge costs and straight-line distance as the (admissible)
//! heuristic. The planner reports how many regions it reasoned over at each level, which is
//! the point of the tree: a handful per level instead of the whole fine map.

use petgraph::algo::astar;
use petgraph::graph::{NodeIndex, UnGraph};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SergeError};
use crate::grid::CellMasses;
use crate::map::ln_floor;
use crate::map::{OUTSIDE, SalientRegionMap};
use crate::serge::{Serge, SergeParams};

/// One node of the tree: a region at some level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TreeNode {
    /// Parent node (`None` for the root).
    pub parent: Option<usize>,
    /// Depth (root = 0).
    pub level: usize,
    /// Global cell ids, sorted.
    pub cells: Vec<usize>,
    /// Global belief ids, sorted.
    pub beliefs: Vec<usize>,
    /// Children (empty until split).
    pub children: Vec<usize>,
}

/// A multi-resolution SR map.
#[derive(Debug, Clone)]
pub struct ResolutionTree<'a> {
    masses: &'a CellMasses,
    nodes: Vec<TreeNode>,
}

/// One level of a [`TreePlan`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LevelPlan {
    /// The node whose children were planned over.
    pub node: usize,
    /// Its children: the regions reasoned over at this level.
    pub regions: Vec<usize>,
    /// Node ids from the child holding the robot to the child holding the goal.
    pub path: Vec<usize>,
}

/// A coarse-to-fine plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TreePlan {
    /// One entry per level, coarse first.
    pub levels: Vec<LevelPlan>,
    /// The finest node reached (holds the goal).
    pub goal_node: usize,
}

impl TreePlan {
    /// Total regions reasoned over (the sum over levels).
    #[must_use]
    pub fn regions_considered(&self) -> usize {
        self.levels.iter().map(|l| l.regions.len()).sum()
    }
}

impl<'a> ResolutionTree<'a> {
    /// A tree with only the root.
    #[must_use]
    pub fn new(masses: &'a CellMasses) -> Self {
        Self {
            masses,
            nodes: vec![TreeNode {
                parent: None,
                level: 0,
                cells: (0..masses.grid().len()).collect(),
                beliefs: (0..masses.n_beliefs()).collect(),
                children: Vec::new(),
            }],
        }
    }

    /// All nodes (index = node id; 0 is the root).
    #[must_use]
    pub fn nodes(&self) -> &[TreeNode] {
        &self.nodes
    }

    /// One node.
    ///
    /// # Errors
    /// [`SergeError::Unknown`].
    pub fn node(&self, id: usize) -> Result<&TreeNode> {
        self.nodes.get(id).ok_or(SergeError::Unknown {
            kind: "node",
            index: id,
        })
    }

    /// Splits node `id` with SERGE (`params.mu` = 2 for the thesis's binary tree) and
    /// returns the new children. A node already split is returned as it is.
    ///
    /// # Errors
    /// [`SergeError::Unknown`]; SERGE's parameter errors (e.g. μ above the node's beliefs).
    pub fn split(&mut self, id: usize, params: &SergeParams) -> Result<Vec<usize>> {
        let node = self.node(id)?.clone();
        if !node.children.is_empty() {
            return Ok(node.children);
        }
        let serge = Serge::restricted(self.masses, node.cells.clone(), node.beliefs.clone())?;
        let map = serge.run(params)?;
        let mut children = Vec::with_capacity(map.n_regions);
        for r in 0..map.n_regions as u32 {
            let child = TreeNode {
                parent: Some(id),
                level: node.level + 1,
                cells: map.region_cells(r),
                beliefs: map.region_beliefs(r),
                children: Vec::new(),
            };
            children.push(self.nodes.len());
            self.nodes.push(child);
        }
        self.nodes[id].children.clone_from(&children);
        Ok(children)
    }

    /// Splits every node down to `depth` levels (breadth first), skipping nodes with a
    /// single belief.
    ///
    /// # Errors
    /// As [`ResolutionTree::split`].
    pub fn grow(&mut self, depth: usize, params: &SergeParams) -> Result<()> {
        let mut frontier = vec![0usize];
        for _ in 0..depth {
            let mut next = Vec::new();
            for id in frontier {
                let k = self.nodes[id].beliefs.len();
                if k < 2 {
                    continue;
                }
                let p = SergeParams {
                    mu: params.mu.min(k),
                    ..*params
                };
                next.extend(self.split(id, &p)?);
            }
            frontier = next;
        }
        Ok(())
    }

    /// The cut at `level`: for every branch, the node at that level or the deepest above.
    #[must_use]
    pub fn cut_at_level(&self, level: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![0usize];
        while let Some(id) = stack.pop() {
            let n = &self.nodes[id];
            if n.level == level || n.children.is_empty() {
                out.push(id);
            } else {
                stack.extend(n.children.iter().rev());
            }
        }
        out.sort_unstable();
        out
    }

    /// The map whose regions are the nodes of `cut` (mixed levels allowed).
    ///
    /// # Errors
    /// [`SergeError::Unknown`]; [`SergeError::InvalidParameter`] when the nodes do not
    /// partition the grid.
    pub fn map_of(&self, cut: &[usize]) -> Result<SalientRegionMap> {
        let grid = *self.masses.grid();
        let mut cell_region = vec![OUTSIDE; grid.len()];
        let mut assignment = vec![OUTSIDE; self.masses.n_beliefs()];
        for (r, &id) in cut.iter().enumerate() {
            let node = self.node(id)?;
            for &c in &node.cells {
                if cell_region[c] != OUTSIDE {
                    return Err(SergeError::InvalidParameter(format!(
                        "nodes of the cut overlap at cell {c}"
                    )));
                }
                cell_region[c] = r as u32;
            }
            for &k in &node.beliefs {
                assignment[k] = r as u32;
            }
        }
        if cell_region.contains(&OUTSIDE) || assignment.contains(&OUTSIDE) {
            return Err(SergeError::InvalidParameter(
                "the cut does not cover every cell and belief".into(),
            ));
        }
        let saliency: Vec<f64> = (0..self.masses.n_beliefs())
            .map(|k| {
                self.node(cut[assignment[k] as usize])
                    .map(|n| {
                        n.cells
                            .iter()
                            .map(|&c| self.masses.get(k, c))
                            .sum::<f64>()
                            .min(1.0)
                    })
                    .unwrap_or(0.0)
            })
            .collect();
        Ok(SalientRegionMap {
            grid,
            cell_region,
            beliefs: (0..self.masses.n_beliefs()).collect(),
            assignment,
            log_saliency: saliency.iter().map(|&s| ln_floor(s)).sum(),
            saliency,
            n_regions: cut.len(),
            log_psi1: 0.0,
            mu: cut.len(),
            sigma: 0.0,
            trials: 0,
            seed: 0,
            best_trial: 0,
        })
    }

    /// The node among `ids` whose cells contain `p`'s cell.
    fn containing(&self, ids: &[usize], p: [f64; 2]) -> Option<usize> {
        let c = self.masses.grid().cell_of(p);
        ids.iter()
            .copied()
            .find(|&id| self.nodes[id].cells.binary_search(&c).is_ok())
    }

    fn centroid(&self, id: usize) -> [f64; 2] {
        let g = self.masses.grid();
        let cells = &self.nodes[id].cells;
        let n = cells.len().max(1) as f64;
        let s = cells.iter().fold([0.0, 0.0], |a, &c| {
            let p = g.centre(c);
            [a[0] + p[0], a[1] + p[1]]
        });
        [s[0] / n, s[1] / n]
    }

    /// The children's adjacency graph (edges weighted by the distance between centroids),
    /// each child's node, and the centroids.
    fn children_graph(
        &self,
        children: &[usize],
    ) -> (UnGraph<usize, f64>, Vec<NodeIndex>, Vec<[f64; 2]>) {
        let grid = *self.masses.grid();
        let mut g: UnGraph<usize, f64> = UnGraph::default();
        let idx: Vec<NodeIndex> = children.iter().map(|&c| g.add_node(c)).collect();
        let mut owner = vec![usize::MAX; grid.len()];
        for (i, &c) in children.iter().enumerate() {
            for &cell in &self.nodes[c].cells {
                owner[cell] = i;
            }
        }
        let mut pairs = std::collections::BTreeSet::new();
        for &c in children {
            for &cell in &self.nodes[c].cells {
                for nb in grid.neighbours(cell) {
                    let (a, b) = (owner[cell], owner[nb]);
                    if a != usize::MAX && b != usize::MAX && a != b {
                        pairs.insert((a.min(b), a.max(b)));
                    }
                }
            }
        }
        let cent: Vec<[f64; 2]> = children.iter().map(|&c| self.centroid(c)).collect();
        let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        for (a, b) in pairs {
            g.add_edge(idx[a], idx[b], dist(cent[a], cent[b]));
        }
        (g, idx, cent)
    }

    /// Plans from `start` to `goal` coarse-to-fine (§3.4.3), splitting nodes on the way with
    /// `params` until the goal's node holds one belief or `max_levels` levels are used.
    ///
    /// # Errors
    /// SERGE's errors from the splits; [`SergeError::InvalidParameter`] when the regions of
    /// a level are not connected (cannot happen for maps SERGE builds).
    pub fn plan(
        &mut self,
        start: [f64; 2],
        goal: [f64; 2],
        params: &SergeParams,
        max_levels: usize,
    ) -> Result<TreePlan> {
        let mut levels = Vec::new();
        let mut current = 0usize;
        let mut pos = start;
        let grid = *self.masses.grid();
        for _ in 0..max_levels {
            let k = self.nodes[current].beliefs.len();
            if k < 2 {
                break;
            }
            let p = SergeParams {
                mu: params.mu.min(k),
                ..*params
            };
            let children = self.split(current, &p)?;
            if children.len() < 2 {
                break;
            }
            let from = self.containing(&children, pos).unwrap_or(children[0]);
            let to = self
                .containing(&children, goal)
                .ok_or_else(|| SergeError::InvalidParameter("goal outside the node".into()))?;
            let (g, idx, cent) = self.children_graph(&children);
            let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
            let ia = children.iter().position(|&c| c == from).unwrap_or(0);
            let ib = children.iter().position(|&c| c == to).unwrap_or(0);
            let goal_c = cent[ib];
            let (_, path) = astar(
                &g,
                idx[ia],
                |n| n == idx[ib],
                |e| *e.weight(),
                |n| dist(cent[n.index()], goal_c),
            )
            .ok_or_else(|| {
                SergeError::InvalidParameter("the regions of a level are not connected".into())
            })?;
            levels.push(LevelPlan {
                node: current,
                regions: children.clone(),
                path: path.iter().map(|n| g[*n]).collect(),
            });
            // the robot enters the goal's child at its cell nearest to where it was
            if let Some(&c) = self.nodes[to]
                .cells
                .iter()
                .min_by(|&&a, &&b| dist(grid.centre(a), pos).total_cmp(&dist(grid.centre(b), pos)))
            {
                pos = grid.centre(c);
            }
            current = to;
        }
        Ok(TreePlan {
            levels,
            goal_node: current,
        })
    }
}
