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

use std::collections::VecDeque;

use crate::error::{Result, SergeError};
use crate::grid::CellMasses;

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

/// Builds `C_init` over `cells` (global ids) for the beliefs `beliefs` (global ids).
pub(crate) fn initial_regions(
    masses: &CellMasses,
    cells: &[usize],
    beliefs: &[usize],
) -> Result<InitialRegions> {
    let grid = masses.grid();
    let n = grid.len();
    let kb = beliefs.len();
    // local index of each global cell in the problem (NONE outside)
    let mut local = vec![NONE; n];
    for (i, &c) in cells.iter().enumerate() {
        local[c] = i as u32;
    }
    // 1. argmax labels (ties: the lowest belief index)
    let mut label = vec![NONE; cells.len()];
    for (i, &c) in cells.iter().enumerate() {
        let mut best = 0.0;
        for (j, &k) in beliefs.iter().enumerate() {
            let m = masses.get(k, c);
            if m > best {
                best = m;
                label[i] = j as u32;
            }
        }
    }
    // 2. flood the unlabelled cells from the labelled ones
    let mut queue: VecDeque<usize> = (0..cells.len()).filter(|&i| label[i] != NONE).collect();
    if queue.is_empty() {
        return Err(SergeError::NoMass(format!(
            "none of the {} cells holds any mass of the {} beliefs",
            cells.len(),
            kb
        )));
    }
    while let Some(i) = queue.pop_front() {
        for nb in grid.neighbours(cells[i]) {
            let j = local[nb];
            if j != NONE && label[j as usize] == NONE {
                label[j as usize] = label[i];
                queue.push_back(j as usize);
            }
        }
    }
    // 3. connected components of equal label
    let mut comp = vec![NONE; cells.len()];
    let mut comp_label = Vec::new();
    for start in 0..cells.len() {
        if comp[start] != NONE {
            continue;
        }
        let id = comp_label.len() as u32;
        comp_label.push(label[start]);
        comp[start] = id;
        let mut stack = vec![start];
        while let Some(i) = stack.pop() {
            for nb in grid.neighbours(cells[i]) {
                let j = local[nb];
                if j != NONE && comp[j as usize] == NONE && label[j as usize] == label[start] {
                    comp[j as usize] = id;
                    stack.push(j as usize);
                }
            }
        }
    }
    let nc = comp_label.len();
    let mut cmass = vec![0.0; nc * kb];
    for (i, &c) in cells.iter().enumerate() {
        let row = comp[i] as usize * kb;
        for (j, &k) in beliefs.iter().enumerate() {
            cmass[row + j] += masses.get(k, c);
        }
    }
    // 4. beliefs to components
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
                "belief {} has no mass on any of the {} cells",
                beliefs[j],
                cells.len()
            )));
        }
        comp_beliefs[c].push(j as u32);
    }
    // 5. absorb belief-less components (union-find, one pass per layer of empties)
    let mut parent: Vec<u32> = (0..nc as u32).collect();
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let mut has_belief: Vec<bool> = comp_beliefs.iter().map(|b| !b.is_empty()).collect();
    loop {
        let roots: Vec<u32> = (0..nc as u32).map(|c| root(&mut parent, c)).collect();
        // shared border lengths between current roots, for empty roots only
        let mut border: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
        for (i, &c) in cells.iter().enumerate() {
            let a = roots[comp[i] as usize];
            for nb in grid.neighbours(c) {
                let j = local[nb];
                if j == NONE {
                    continue;
                }
                let b = roots[comp[j as usize] as usize];
                if a != b && !has_belief[a as usize] && has_belief[b as usize] {
                    *border.entry((a, b)).or_insert(0) += 1;
                }
            }
        }
        if border.is_empty() {
            break;
        }
        let mut choice: std::collections::BTreeMap<u32, (u32, u32)> = Default::default();
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
    // 6. compact the surviving roots into regions
    let mut region_of_root = vec![NONE; nc];
    let mut out = InitialRegions {
        cells: Vec::new(),
        beliefs: Vec::new(),
        masses: Vec::new(),
        adj: Vec::new(),
        kb,
    };
    let roots: Vec<u32> = (0..nc as u32).map(|c| root(&mut parent, c)).collect();
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
    let mut region_of_cell = vec![0u32; cells.len()];
    for (i, &c) in cells.iter().enumerate() {
        let reg = region_of_root[roots[comp[i] as usize] as usize];
        region_of_cell[i] = reg;
        out.cells[reg as usize].push(c);
    }
    let mut adj: Vec<std::collections::BTreeSet<u32>> = vec![Default::default(); out.cells.len()];
    for (i, &c) in cells.iter().enumerate() {
        for nb in grid.neighbours(c) {
            let j = local[nb];
            if j != NONE && region_of_cell[j as usize] != region_of_cell[i] {
                adj[region_of_cell[i] as usize].insert(region_of_cell[j as usize]);
            }
        }
    }
    out.adj = adj.into_iter().map(|s| s.into_iter().collect()).collect();
    for b in &mut out.beliefs {
        b.sort_unstable();
    }
    Ok(out)
}
