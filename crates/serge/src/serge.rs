//! The SERGE search (thesis Algorithm 2) over the initial regions of [`crate::init`].
//!
//! One *trial* repeatedly picks a region `C_n` at random, simulates merging it into each
//! neighbour `C_m`, and keeps the merge that raises the potential `ψ = ψ1·ψ2·ψ3` (eqs.
//! 3.5–3.7) most, until no merge raises it. `T` trials with different random orders run in
//! parallel; the best map is kept.
//!
//! ## Incremental evaluation
//! In log space `log ψ = log ψ1(|R|) + Σ_k log S_k` (ψ2 is 1 throughout: regions start
//! contiguous and only adjacent regions merge). Merging `n` into `m` changes `|R|` by one
//! and the saliency of exactly the beliefs of `n` and `m`, whose new saliency is the sum of
//! their masses on the two regions. With a `regions × K` mass table that is updated by one
//! row addition per accepted merge, a candidate costs `O(|beliefs of n and m|)` instead of
//! the `O(N·K)` of recomputing ψ from the cells ([`crate::baseline`] does that, for the
//! benchmark and as a cross-check).
//!
//! ## Convergence and the random order
//! A region whose best merge does not raise ψ stays that way until one of its neighbours
//! changes: ψ3-gains depend only on the pair, and the ψ1-gain of one more merge,
//! `(2(|R|−μ)−1)/(2σ²)`, only shrinks as `|R|` falls. So a trial keeps the set of regions
//! not yet found stuck, draws `C_n` uniformly from it, and re-opens the merged region and
//! its neighbours after each merge; it has converged when the set is empty. Drawing from
//! all regions and skipping stuck ones would give the same distribution of merges, just
//! slower.
//!
//! ## σ = 0
//! `ψ1` is then 0 unless `|R| = μ`: the limit σ → 0 is taken, i.e. merges are accepted while
//! `|R| > μ` (the best by ψ3) and never after, so every trial ends with exactly μ regions.
//!
//! ## Determinism
//! Trial `t` draws from `ChaCha8(seed, t)`; the best trial is the one with the highest
//! `log φ`, ties to the lowest `t`. The reduction is over a total order, so the result is
//! the same for any number of threads.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Core-seconds per candidate merge of the greedy search (trials × initial regions²),
/// measured: `qrm serge run` on 40 random beliefs (40 initial regions, 1,600 merges a trial),
/// `--trials 100000` took 4.4 s of CPU against 0.15 s at 100 trials. A run beyond [`Budget::RUN`] is refused with the estimate
/// (issue 17: `--trials 2^64-1` ran with no result, no progress and no end).
pub const SECONDS_PER_MERGE: f64 = 2.7e-8;

use crate::error::{Result, SergeError};
use crate::grid::CellMasses;
use crate::init::{InitialRegions, initial_regions};
use crate::map::{OUTSIDE, SalientRegionMap, ln_floor};
use qsr_core::cost::{Budget, Cost};

/// The user parameters of SERGE.
#[derive(Debug, Clone, Copy, PartialEq)]
#[must_use]
pub struct SergeParams {
    /// Desired number of regions μ (1 ≤ μ ≤ K).
    pub mu: usize,
    /// Tolerance σ ≥ 0: larger trades regions for saliency; 0 forces |R| = μ.
    pub sigma: f64,
    /// Trials T; `None` = 100·K (the thesis's suggestion, §3.3).
    pub trials: Option<usize>,
    /// Seed of the random merge orders.
    pub seed: u64,
}

impl SergeParams {
    /// μ and σ with the default trials (100·K) and seed 0.
    pub fn new(mu: usize, sigma: f64) -> Self {
        Self {
            mu,
            sigma,
            trials: None,
            seed: 0,
        }
    }

    /// Sets the number of trials.
    pub fn trials(mut self, trials: usize) -> Self {
        self.trials = Some(trials);
        self
    }

    /// Sets the seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
}

/// A prepared SERGE problem: cells, beliefs and their initial regions.
#[derive(Debug, Clone)]
pub struct Serge<'a> {
    masses: &'a CellMasses,
    cells: Vec<usize>,
    beliefs: Vec<usize>,
    init: InitialRegions,
}

/// What one trial ended with.
#[derive(Debug, Clone)]
pub(crate) struct TrialResult {
    pub log_phi: f64,
    pub trial: usize,
    /// Final region (an initial-region id acting as representative) of each initial region.
    pub root: Vec<u32>,
}

/// The mutable state of one trial (shared with the baseline evaluator).
#[derive(Debug, Clone)]
pub(crate) struct TrialState {
    pub masses: Vec<f64>,
    pub beliefs: Vec<Vec<u32>>,
    pub adj: Vec<Vec<u32>>,
    pub log_s: Vec<f64>,
    pub merged_into: Vec<u32>,
    pub n_regions: usize,
    pub kb: usize,
}

impl TrialState {
    pub fn new(init: &InitialRegions) -> Self {
        let kb = init.kb;
        let log_s = init
            .beliefs
            .iter()
            .enumerate()
            .map(|(r, bs)| {
                bs.iter()
                    .map(|&j| ln_floor(init.masses[r * kb + j as usize]))
                    .sum()
            })
            .collect();
        Self {
            masses: init.masses.clone(),
            beliefs: init.beliefs.clone(),
            adj: init.adj.clone(),
            log_s,
            merged_into: (0..init.cells.len() as u32).collect(),
            n_regions: init.cells.len(),
            kb,
        }
    }

    /// Change of log ψ3 when `n` merges into `m`.
    pub fn delta3(&self, n: usize, m: usize) -> f64 {
        let kb = self.kb;
        let (rn, rm) = (
            &self.masses[n * kb..(n + 1) * kb],
            &self.masses[m * kb..(m + 1) * kb],
        );
        let mut s = 0.0;
        for &j in self.beliefs[n].iter().chain(&self.beliefs[m]) {
            s += ln_floor(rn[j as usize] + rm[j as usize]);
        }
        s - self.log_s[n] - self.log_s[m]
    }

    /// Merges region `n` into region `m`.
    pub fn merge(&mut self, n: usize, m: usize) {
        let kb = self.kb;
        for j in 0..kb {
            self.masses[m * kb + j] += self.masses[n * kb + j];
        }
        let moved = std::mem::take(&mut self.beliefs[n]);
        self.beliefs[m].extend(moved);
        self.log_s[m] = self.beliefs[m]
            .iter()
            .map(|&j| ln_floor(self.masses[m * kb + j as usize]))
            .sum();
        self.log_s[n] = 0.0;
        let nbs = std::mem::take(&mut self.adj[n]);
        for &x in &nbs {
            let x = x as usize;
            if x == m {
                continue;
            }
            let list = &mut self.adj[x];
            list.retain(|&y| y as usize != n);
            if let Err(pos) = list.binary_search(&(m as u32)) {
                list.insert(pos, m as u32);
            }
            if let Err(pos) = self.adj[m].binary_search(&(x as u32)) {
                self.adj[m].insert(pos, x as u32);
            }
        }
        self.adj[m].retain(|&y| y as usize != n);
        self.merged_into[n] = m as u32;
        self.n_regions -= 1;
    }

    pub fn log_psi3(&self) -> f64 {
        (0..self.log_s.len())
            .filter(|&r| self.merged_into[r] as usize == r)
            .map(|r| self.log_s[r])
            .sum()
    }

    pub fn roots(&self) -> Vec<u32> {
        (0..self.merged_into.len())
            .map(|r| {
                let mut x = r;
                while self.merged_into[x] as usize != x {
                    x = self.merged_into[x] as usize;
                }
                x as u32
            })
            .collect()
    }
}

/// `log ψ1(|R|)` including the normalisation β of eq. 3.5 (`−∞` off μ when σ = 0).
#[must_use]
pub fn log_psi1(n_regions: usize, mu: usize, sigma: f64, k: usize) -> f64 {
    let two_var = 2.0 * sigma * sigma;
    // σ so small that 2σ² underflows behaves as σ = 0 (else 0/0 = NaN at r = μ).
    if sigma == 0.0 || two_var == 0.0 {
        return if n_regions == mu {
            0.0
        } else {
            f64::NEG_INFINITY
        };
    }
    let g = |r: usize| {
        let d = r as f64 - mu as f64;
        -d * d / two_var
    };
    // The Gaussian's normalising constant cancels between g(n) and the sum over r, so it is
    // left out: with σ = 1e300 it is infinite and gave log φ = −∞ (issue 17). Log-sum-exp
    // about the largest term (0, at r = μ when 1 ≤ μ ≤ K) keeps the sum finite.
    let top = (1..=k.max(1)).map(g).fold(f64::NEG_INFINITY, f64::max);
    let sum: f64 = (1..=k.max(1)).map(|r| (g(r) - top).exp()).sum();
    g(n_regions) - top - sum.ln()
}

/// Gain in log ψ1 of one more merge from `r` regions.
fn delta1(r: usize, mu: usize, sigma: f64) -> f64 {
    let a = r as f64 - mu as f64;
    let b = a - 1.0;
    (a * a - b * b) / (2.0 * sigma * sigma)
}

impl<'a> Serge<'a> {
    /// The problem over every cell and every belief of `masses`.
    ///
    /// # Errors
    /// [`SergeError::NoMass`] when no cell holds mass or a belief has none.
    pub fn new(masses: &'a CellMasses) -> Result<Self> {
        let cells: Vec<usize> = (0..masses.grid().len()).collect();
        let beliefs: Vec<usize> = (0..masses.n_beliefs()).collect();
        Self::restricted(masses, cells, beliefs)
    }

    /// The problem over some cells (global ids) and some beliefs (global ids): one
    /// resolution-tree node's.
    ///
    /// # Errors
    /// [`SergeError::Empty`], [`SergeError::Unknown`] for ids out of range,
    /// [`SergeError::NoMass`].
    pub fn restricted(
        masses: &'a CellMasses,
        mut cells: Vec<usize>,
        mut beliefs: Vec<usize>,
    ) -> Result<Self> {
        cells.sort_unstable();
        cells.dedup();
        beliefs.sort_unstable();
        beliefs.dedup();
        if cells.is_empty() || beliefs.is_empty() {
            return Err(SergeError::Empty(
                "a SERGE problem needs at least one cell and one belief".into(),
            ));
        }
        if let Some(&c) = cells.iter().find(|&&c| c >= masses.grid().len()) {
            return Err(SergeError::Unknown {
                kind: "cell",
                index: c,
            });
        }
        if let Some(&k) = beliefs.iter().find(|&&k| k >= masses.n_beliefs()) {
            return Err(SergeError::Unknown {
                kind: "belief",
                index: k,
            });
        }
        let init = initial_regions(masses, &cells, &beliefs)?;
        Ok(Self {
            masses,
            cells,
            beliefs,
            init,
        })
    }

    /// The masses.
    #[must_use]
    pub fn masses(&self) -> &'a CellMasses {
        self.masses
    }

    /// Number of initial regions `|C_init|`.
    #[must_use]
    pub fn n_initial_regions(&self) -> usize {
        self.init.cells.len()
    }

    /// Number of beliefs `K` of the problem.
    #[must_use]
    pub fn n_beliefs(&self) -> usize {
        self.beliefs.len()
    }

    /// The initial regions as a map (the `μ = K` end of the resolution tree).
    #[must_use]
    pub fn initial_map(&self) -> SalientRegionMap {
        let n0 = self.init.cells.len();
        let k = self.beliefs.len();
        let state = TrialState::new(&self.init);
        let result = TrialResult {
            log_phi: log_psi1(n0, n0.min(k), 0.0, k) + state.log_psi3(),
            trial: 0,
            root: (0..n0 as u32).collect(),
        };
        self.build_map(&result, &SergeParams::new(n0.min(k), 0.0).trials(0))
    }

    pub(crate) fn validate(&self, params: &SergeParams) -> Result<usize> {
        let k = self.beliefs.len();
        if !params.sigma.is_finite() || params.sigma < 0.0 {
            return Err(SergeError::InvalidParameter(format!(
                "sigma (σ) = {} must be finite and ≥ 0",
                params.sigma
            )));
        }
        let upper = k.min(self.cells.len());
        if params.mu < 1 || params.mu > upper {
            return Err(SergeError::InvalidParameter(format!(
                "μ = {} must be between 1 and min(K, N) = {upper}",
                params.mu
            )));
        }
        if params.sigma == 0.0 && params.mu > self.init.cells.len() {
            return Err(SergeError::InvalidParameter(format!(
                "σ = 0 asks for exactly μ = {} regions, but only {} initial regions exist \
                 (some beliefs win no cell of their own); use μ ≤ {} or σ > 0",
                params.mu,
                self.init.cells.len(),
                self.init.cells.len()
            )));
        }
        let trials = params.trials.unwrap_or(100 * k);
        if trials == 0 {
            return Err(SergeError::InvalidParameter("trials must be ≥ 1".into()));
        }
        // A trial merges regions greedily from the initial map: about (initial regions)²
        // candidate merges. Refuse what would run for hours instead of starting it.
        let per_trial = (self.init.cells.len() as f64).max(1.0).powi(2);
        Cost::work(trials as f64 * per_trial, SECONDS_PER_MERGE)
            .check(
                &Budget::RUN,
                format!("trials = {trials} × about {per_trial} candidate merges each"),
            )
            .map_err(|e| {
                SergeError::InvalidParameter(e.hint("ask for fewer trials").to_string())
            })?;
        Ok(trials)
    }

    /// Runs SERGE (Algorithm 2) and returns the best map of all trials.
    ///
    /// # Errors
    /// [`SergeError::InvalidParameter`] for μ outside `1..=min(K, N)`, σ < 0 or
    /// non-finite, zero trials, or σ = 0 with μ above the number of initial regions.
    pub fn run(&self, params: &SergeParams) -> Result<SalientRegionMap> {
        let trials = self.validate(params)?;
        let best = (0..trials)
            .into_par_iter()
            .map(|t| self.trial(params, t, None))
            .reduce_with(better)
            .ok_or_else(|| SergeError::InvalidParameter("trials must be ≥ 1".into()))?;
        Ok(self.build_map(&best, &params.trials(trials)))
    }

    /// Runs one trial and returns `log φ` after every accepted merge (the first entry is the
    /// initial map's): the trace of the greedy ascent, for tests and plots.
    ///
    /// # Errors
    /// As [`Serge::run`].
    pub fn trace(&self, params: &SergeParams, trial: usize) -> Result<Vec<f64>> {
        self.validate(params)?;
        let mut trace = Vec::new();
        self.trial(params, trial, Some(&mut trace));
        Ok(trace)
    }

    pub(crate) fn trial(
        &self,
        params: &SergeParams,
        t: usize,
        trace: Option<&mut Vec<f64>>,
    ) -> TrialResult {
        let mut state = TrialState::new(&self.init);
        let delta3 = |s: &TrialState, n: usize, m: usize| s.delta3(n, m);
        drive(&mut state, params, self.beliefs.len(), t, trace, delta3);
        self.finish(&state, params, t)
    }

    pub(crate) fn finish(&self, state: &TrialState, params: &SergeParams, t: usize) -> TrialResult {
        let log_psi3 = state.log_psi3();
        TrialResult {
            log_phi: log_psi1(state.n_regions, params.mu, params.sigma, self.beliefs.len())
                + log_psi3,
            trial: t,
            root: state.roots(),
        }
    }

    pub(crate) fn init(&self) -> &InitialRegions {
        &self.init
    }

    pub(crate) fn cells(&self) -> &[usize] {
        &self.cells
    }

    pub(crate) fn beliefs(&self) -> &[usize] {
        &self.beliefs
    }

    pub(crate) fn build_map(&self, best: &TrialResult, params: &SergeParams) -> SalientRegionMap {
        map_of_trial(self, best, params)
    }
}

/// The greedy ascent of one trial; `delta3(state, n, m)` evaluates a candidate merge.
pub(crate) fn drive(
    state: &mut TrialState,
    params: &SergeParams,
    k: usize,
    t: usize,
    mut trace: Option<&mut Vec<f64>>,
    mut delta3: impl FnMut(&TrialState, usize, usize) -> f64,
) {
    let mut rng =
        ChaCha8Rng::seed_from_u64(params.seed ^ (t as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let n0 = state.merged_into.len();
    let mut open: Vec<u32> = (0..n0 as u32).collect();
    let mut is_open = vec![true; n0];
    let mut phi = log_psi1(state.n_regions, params.mu, params.sigma, k) + state.log_psi3();
    if let Some(tr) = trace.as_deref_mut() {
        tr.push(phi);
    }
    while !open.is_empty() {
        let i = rng.random_range(0..open.len());
        let n = open.swap_remove(i) as usize;
        is_open[n] = false;
        let mut best: Option<(usize, f64)> = None;
        for &m in &state.adj[n] {
            let d = delta3(state, n, m as usize);
            if best.is_none_or(|(_, b)| d > b) {
                best = Some((m as usize, d));
            }
        }
        let Some((m, d3)) = best else { continue };
        let accept = if params.sigma == 0.0 {
            state.n_regions > params.mu
        } else {
            delta1(state.n_regions, params.mu, params.sigma) + d3 > 0.0
        };
        if !accept {
            continue;
        }
        state.merge(n, m);
        for x in std::iter::once(m as u32).chain(state.adj[m].iter().copied()) {
            if !is_open[x as usize] {
                is_open[x as usize] = true;
                open.push(x);
            }
        }
        if let Some(tr) = trace.as_deref_mut() {
            phi = log_psi1(state.n_regions, params.mu, params.sigma, k) + state.log_psi3();
            tr.push(phi);
        }
    }
}

/// The better of two trials: higher log φ, ties to the lower trial index (a total order, so
/// any reduction tree gives the same answer).
pub(crate) fn better(a: TrialResult, b: TrialResult) -> TrialResult {
    match a.log_phi.total_cmp(&b.log_phi) {
        std::cmp::Ordering::Greater => a,
        std::cmp::Ordering::Less => b,
        std::cmp::Ordering::Equal => {
            if a.trial <= b.trial {
                a
            } else {
                b
            }
        }
    }
}

/// The map a trial's regions make: compact region ids in belief order, the cells of each
/// region, the saliencies and the likelihood's parts.
fn map_of_trial(serge: &Serge<'_>, best: &TrialResult, params: &SergeParams) -> SalientRegionMap {
    let init = serge.init();
    let masses = serge.masses();
    let kb = init.kb;
    // representative initial region of each belief → compact region ids in belief order
    let mut belief_root = vec![0u32; kb];
    for (r, bs) in init.beliefs.iter().enumerate() {
        for &j in bs {
            belief_root[j as usize] = best.root[r];
        }
    }
    let mut id_of_root = vec![OUTSIDE; init.cells.len()];
    let mut next = 0u32;
    for &root in &belief_root {
        if id_of_root[root as usize] == OUTSIDE {
            id_of_root[root as usize] = next;
            next += 1;
        }
    }
    let mut cell_region = vec![OUTSIDE; masses.grid().len()];
    for (r, cells) in init.cells.iter().enumerate() {
        let id = id_of_root[best.root[r] as usize];
        for &c in cells {
            cell_region[c] = id;
        }
    }
    let assignment: Vec<u32> = belief_root
        .iter()
        .map(|&r| id_of_root[r as usize])
        .collect();
    let beliefs = serge.beliefs().to_vec();
    let saliency: Vec<f64> = beliefs
        .iter()
        .zip(&assignment)
        .map(|(&k, &region)| {
            serge
                .cells()
                .iter()
                .filter(|&&c| cell_region[c] == region)
                .map(|&c| masses.get(k, c))
                .sum::<f64>()
                .min(1.0)
        })
        .collect();
    let n_regions = next as usize;
    SalientRegionMap {
        grid: *masses.grid(),
        cell_region,
        assignment,
        log_saliency: saliency.iter().map(|&s| ln_floor(s)).sum(),
        saliency,
        n_regions,
        log_psi1: log_psi1(n_regions, params.mu, params.sigma, beliefs.len()),
        beliefs,
        mu: params.mu,
        sigma: params.sigma,
        trials: params.trials.unwrap_or(0),
        seed: params.seed,
        best_trial: best.trial,
    }
}
