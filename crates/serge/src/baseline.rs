//! A straightforward, non-incremental SERGE: the same trials (same random merge orders and
//! the same acceptance rule) but every candidate merge is scored by recomputing the
//! potential from the grid — each belief's saliency as a sum over all cells of its region,
//! and contiguity (ψ2) by counting connected components — the way eq. 3.4 reads. It exists
//! to measure what incremental evaluation buys ([`crate::Serge`] docs) in
//! `benches/serge.rs`, and to cross-check the incremental scores in tests.

use crate::error::Result;
use crate::map::SalientRegionMap;
use crate::map::ln_floor;
use crate::serge::{Serge, SergeParams, TrialState, better, drive};

/// log ψ2·ψ3 of the partition in which initial region `r` belongs to `label[r]`, from
/// cells (−∞ when a region is not contiguous).
fn potential_from_cells(
    serge: &Serge<'_>,
    label_of_initial: &[u32],
    belief_label: &[u32],
    n_regions: usize,
) -> f64 {
    let masses = serge.masses();
    let grid = masses.grid();
    let init = serge.init();
    let mut cell_label = vec![u32::MAX; grid.len()];
    for (r, cells) in init.cells.iter().enumerate() {
        for &c in cells {
            cell_label[c] = label_of_initial[r];
        }
    }
    // ψ2: every label one 4-connected component
    let mut seen = vec![false; grid.len()];
    let mut components = 0usize;
    for &s in serge.cells() {
        if seen[s] {
            continue;
        }
        components += 1;
        seen[s] = true;
        let mut stack = vec![s];
        while let Some(c) = stack.pop() {
            for nb in grid.neighbours(c) {
                if !seen[nb] && cell_label[nb] == cell_label[c] {
                    seen[nb] = true;
                    stack.push(nb);
                }
            }
        }
    }
    if components != n_regions {
        return f64::NEG_INFINITY;
    }
    // ψ3: each belief's saliency summed over the cells of its region
    let mut log_psi3 = 0.0;
    for (j, &k) in serge.beliefs().iter().enumerate() {
        let s: f64 = serge
            .cells()
            .iter()
            .filter(|&&c| cell_label[c] == belief_label[j])
            .map(|&c| masses.get(k, c))
            .sum();
        log_psi3 += ln_floor(s);
    }
    log_psi3
}

/// Runs SERGE with every candidate scored from the cells. Same result as
/// [`Serge::run`] up to floating-point ties, orders of magnitude slower.
///
/// # Errors
/// As [`Serge::run`].
pub fn run_naive(serge: &Serge<'_>, params: &SergeParams) -> Result<SalientRegionMap> {
    let trials = serge.validate(params)?;
    let k = serge.n_beliefs();
    let mut best = None;
    for t in 0..trials {
        let mut state = TrialState::new(serge.init());
        let score = |s: &TrialState, n: usize, m: usize| {
            // labels after merging n into m, then φ(candidate) − φ(current) from scratch
            let roots = s.roots();
            let mut cand: Vec<u32> = roots.clone();
            for x in &mut cand {
                if *x as usize == n {
                    *x = m as u32;
                }
            }
            let belief_label = |labels: &[u32]| {
                let mut out = vec![0u32; k];
                for (r, bs) in serge.init().beliefs.iter().enumerate() {
                    for &j in bs {
                        out[j as usize] = labels[r];
                    }
                }
                out
            };
            let cur = potential_from_cells(serge, &roots, &belief_label(&roots), s.n_regions);
            let new = potential_from_cells(serge, &cand, &belief_label(&cand), s.n_regions - 1);
            // the driver adds the ψ1 change itself: hand it the ψ2·ψ3 change
            new - cur
        };
        drive(&mut state, params, k, t, None, score);
        let result = serge.finish(&state, params, t);
        best = Some(match best {
            None => result,
            Some(b) => better(b, result),
        });
    }
    let best = best
        .ok_or_else(|| crate::error::SergeError::InvalidParameter("trials must be ≥ 1".into()))?;
    Ok(serge.build_map(&best, &params.trials(trials)))
}
