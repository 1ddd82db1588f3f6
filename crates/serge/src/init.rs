//! `C_init`: the initial regions SERGE merges (thesis §3.3, built as in §3.4.1).
//!
//! Each grid cell goes to the belief with the highest mass there; cells where no belief
//! has any mass (far from every Gaussian, or no sample fell there) take the label of the
//! nearest labelled cell (a breadth-first flood, i.e. a grid Voronoi fill). The labelled
//! cells are split into 4-connected components so that every initial region is contiguous
//! (ψ2 = 1 from the start, and merges of adjacent regions keep it so). Each belief goes to
//! the component of its own label holding most of its mass (or, for a belief that wins no
//! cell, to the component holding most of its mass). Components left without a belief —
//! the other pieces of a belief split by a neighbour, speckle of a noisy histogram — would
//! count in |R| while adding nothing to ψ3, so each is absorbed into the neighbouring region
//! it shares the longest border with. Every initial region therefore holds at least one
//! belief, as the thesis's K initial regions do.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use crate::error::{Result, SergeError};
use crate::grid::{CellMasses, Grid};

/// The initial regions of one SERGE problem (all cells, or one resolution-tree node's).
#[derive(Debug, Clone)]
pub(crate) struct InitialRegions {
    /// Global cell ids of each region.
    pub cells: Vec<Vec<usize>>,
    /// Local belief indices (into the problem's belief list) of each region.
    pub beliefs: Vec<Vec<u32>>,
    /// `masses[r * kb + j]`: mass of the problem's belief `j` on region `r`.
    pub masses: Vec<f64>,
    /// Sorted adjacency lists.
    pub adj: Vec<Vec<u32>>,
    /// Number of beliefs of the problem.
    pub kb: usize,
}

const NONE: u32 = u32::MAX;

/// The cells of one problem on the grid: global ids and each global cell's local index.
struct Cells<'a> {
    grid: &'a Grid,
    /// Global ids of the problem's cells.
    ids: &'a [usize],
    /// Local index of each global cell (NONE outside the problem).
    local: Vec<u32>,
}

impl Cells<'_> {
    /// Local indices of the problem's cells 4-adjacent to local cell `i`.
    fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.grid
            .neighbours(self.ids[i])
            .map(|nb| self.local[nb])
            .filter(|&j| j != NONE)
            .map(|j| j as usize)
    }
}

/// Builds `C_init` over `cells` (global ids) for the beliefs `beliefs` (global ids).
pub(crate) fn initial_regions(
    masses: &CellMasses,
    cells: &[usize],
    beliefs: &[usize],
) -> Result<InitialRegions> {
    let grid = masses.grid();
    let mut local = vec![NONE; grid.len()];
    for (i, &c) in cells.iter().enumerate() {
        local[c] = i as u32;
    }
    let problem = Cells {
        grid,
        ids: cells,
        local,
    };
    let label = flooded_labels(masses, &problem, beliefs)?;
    let (comp, comp_label) = components(&problem, &label);
    let kb = beliefs.len();
    let mut cmass = vec![0.0; comp_label.len() * kb];
    for (i, &c) in cells.iter().enumerate() {
        let row = comp[i] as usize * kb;
        for (j, &k) in beliefs.iter().enumerate() {
            cmass[row + j] += masses.get(k, c);
        }
    }
    let comp_beliefs = beliefs_to_components(&comp_label, &cmass, beliefs, cells.len())?;
    let roots = absorb_empty(&problem, &comp, &comp_beliefs);
    Ok(compact(&problem, &comp, &roots, &comp_beliefs, &cmass, kb))
}

/// Steps 1–2: each cell's belief of highest mass (ties: the lowest index), then the cells
/// without mass flooded from the labelled ones (a grid Voronoi fill).
fn flooded_labels(masses: &CellMasses, p: &Cells<'_>, beliefs: &[usize]) -> Result<Vec<u32>> {
    let mut label = vec![NONE; p.ids.len()];
    for (i, &c) in p.ids.iter().enumerate() {
        let mut best = 0.0;
        for (j, &k) in beliefs.iter().enumerate() {
            let m = masses.get(k, c);
            if m > best {
                best = m;
                label[i] = j as u32;
            }
        }
    }
    let mut queue: VecDeque<usize> = (0..p.ids.len()).filter(|&i| label[i] != NONE).collect();
    if queue.is_empty() {
        return Err(SergeError::NoMass(format!(
            "none of the {} cells holds any mass of the {} beliefs",
            p.ids.len(),
            beliefs.len()
        )));
    }
    while let Some(i) = queue.pop_front() {
        for j in p.neighbours(i) {
            if label[j] == NONE {
                label[j] = label[i];
                queue.push_back(j);
            }
        }
    }
    Ok(label)
}

/// Step 3: 4-connected components of equal label — each cell's component, each component's
/// label.
fn components(p: &Cells<'_>, label: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut comp = vec![NONE; p.ids.len()];
    let mut comp_label = Vec::new();
    for start in 0..p.ids.len() {
        if comp[start] != NONE {
            continue;
        }
        let id = comp_label.len() as u32;
        comp_label.push(label[start]);
        comp[start] = id;
        let mut stack = vec![start];
        while let Some(i) = stack.pop() {
            for j in p.neighbours(i) {
                if comp[j] == NONE && label[j] == label[start] {
                    comp[j] = id;
                    stack.push(j);
                }
            }
        }
    }
    (comp, comp_label)
}

/// Step 4: each belief to the component of its own label holding most of its mass (else the
/// component holding most of its mass).
fn beliefs_to_components(
    comp_label: &[u32],
    cmass: &[f64],
    beliefs: &[usize],
    n_cells: usize,
) -> Result<Vec<Vec<u32>>> {
    let (nc, kb) = (comp_label.len(), beliefs.len());
    let mut comp_beliefs: Vec<Vec<u32>> = vec![Vec::new(); nc];
    for j in 0..kb {
        let mut best: Option<(usize, f64)> = None;
        let mut best_any: Option<(usize, f64)> = None;
        for c in 0..nc {
            let m = cmass[c * kb + j];
            if comp_label[c] == j as u32 && best.is_none_or(|(_, b)| m > b) {
                best = Some((c, m));
            }
            if best_any.is_none_or(|(_, b)| m > b) {
                best_any = Some((c, m));
            }
        }
        let (c, m) = best.or(best_any).unwrap_or((0, 0.0));
        if m <= 0.0 {
            return Err(SergeError::NoMass(format!(
                "belief {} has no mass on any of the {n_cells} cells",
                beliefs[j]
            )));
        }
        comp_beliefs[c].push(j as u32);
    }
    Ok(comp_beliefs)
}

fn root(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

/// Step 5: belief-less components absorbed into the neighbour they share the longest border
/// with (union-find, one pass per layer of empties); each component's root.
fn absorb_empty(p: &Cells<'_>, comp: &[u32], comp_beliefs: &[Vec<u32>]) -> Vec<u32> {
    let nc = comp_beliefs.len();
    let mut parent: Vec<u32> = (0..nc as u32).collect();
    let mut has_belief: Vec<bool> = comp_beliefs.iter().map(|b| !b.is_empty()).collect();
    loop {
        let roots: Vec<u32> = (0..nc as u32).map(|c| root(&mut parent, c)).collect();
        // shared border lengths between current roots, for empty roots only
        let mut border: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        for i in 0..p.ids.len() {
            let a = roots[comp[i] as usize];
            for j in p.neighbours(i) {
                let b = roots[comp[j] as usize];
                if a != b && !has_belief[a as usize] && has_belief[b as usize] {
                    *border.entry((a, b)).or_insert(0) += 1;
                }
            }
        }
        if border.is_empty() {
            break;
        }
        let mut choice: BTreeMap<u32, (u32, u32)> = BTreeMap::new();
        for (&(a, b), &len) in &border {
            let e = choice.entry(a).or_insert((b, len));
            if len > e.1 {
                *e = (b, len);
            }
        }
        for (a, (b, _)) in choice {
            parent[a as usize] = b;
            has_belief[a as usize] = true;
        }
    }
    (0..nc as u32).map(|c| root(&mut parent, c)).collect()
}

/// Step 6: the surviving roots compacted into regions, with their cells, beliefs, masses and
/// adjacency.
fn compact(
    p: &Cells<'_>,
    comp: &[u32],
    roots: &[u32],
    comp_beliefs: &[Vec<u32>],
    cmass: &[f64],
    kb: usize,
) -> InitialRegions {
    let nc = comp_beliefs.len();
    let mut region_of_root = vec![NONE; nc];
    let mut out = InitialRegions {
        cells: Vec::new(),
        beliefs: Vec::new(),
        masses: Vec::new(),
        adj: Vec::new(),
        kb,
    };
    for c in 0..nc {
        let r = roots[c] as usize;
        if region_of_root[r] == NONE {
            region_of_root[r] = out.cells.len() as u32;
            out.cells.push(Vec::new());
            out.beliefs.push(Vec::new());
            out.masses.extend(std::iter::repeat_n(0.0, kb));
        }
        let reg = region_of_root[r] as usize;
        out.beliefs[reg].extend_from_slice(&comp_beliefs[c]);
        for j in 0..kb {
            out.masses[reg * kb + j] += cmass[c * kb + j];
        }
    }
    let mut region_of_cell = vec![0u32; p.ids.len()];
    for (i, &c) in p.ids.iter().enumerate() {
        let reg = region_of_root[roots[comp[i] as usize] as usize];
        region_of_cell[i] = reg;
        out.cells[reg as usize].push(c);
    }
    let mut adj: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); out.cells.len()];
    for i in 0..p.ids.len() {
        for j in p.neighbours(i) {
            if region_of_cell[j] != region_of_cell[i] {
                adj[region_of_cell[i] as usize].insert(region_of_cell[j]);
            }
        }
    }
    out.adj = adj.into_iter().map(|s| s.into_iter().collect()).collect();
    for b in &mut out.beliefs {
        b.sort_unstable();
    }
    out
}
