//! Learning a qualitative calculus from triplet data (thesis §3.3.2).
//!
//! A triplet observation `(D, E, F)` — three landmark positions with covariances, in any
//! common frame — becomes a point of F in the normalised frame of (D, E) (D at the origin,
//! E at (0, 1); qsr-core's proper-rotation convention, so x < 0 is left of D→E). A triplet's
//! belief (eq. 3.11) is represented by samples: each draws D, E and F from their Gaussians
//! around one of the triplet's observations and normalises. SERGE over these beliefs gives
//! an SR map in the normalised frame, which [`crate::SalientRegionMap::to_calculus`] turns
//! into a qsr-core learned (raster) calculus.
//!
//! ## The compose table (Algorithm 3)
//! Algorithm 3 maps every cell of `{DE:F}` and every cell of `{EF:G}` into frame DE and
//! records the states the mapped cell lands in. [`compose_table`] does exactly this with
//! *interval arithmetic*: for a cell box of F (C in qsr-core's naming) and a cell box of G's
//! position P in frame EF, the position of G in frame DE, `D = E + p_y·e + p_x·(e_y, −e_x)`
//! with `e = F − E`, is enclosed in a box computed from the interval bounds of each term,
//! and every state with a cell in that box (clamped to the window, which is what the clamp
//! outside rule does to points beyond it) is added. Every real configuration has its F in
//! one cell and its P in one cell, so its `{DE:G}` lies in the table: the table is **sound
//! by construction** for every configuration, boundaries included (cells are closed boxes,
//! and border cells extend to infinity). The price is some extra entries where the interval
//! box over-covers; the sampled table of qsr-core ([`qsr_core::Calculus::compose_table`]),
//! whose entries are all witnessed by real configurations, is always a subset (checked in
//! the tests). Cost: `N²` cell pairs and `O(Q)` summed-area lookups each — about 1 s for a
//! 64 × 64 raster on two cores.

use qsr_core::progress::Progress;
use qsr_core::{Calculus, ComposeTable, OutsideRule, Point2, StateId, TernaryFrame};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use crate::belief::{Belief, BeliefSet};
use crate::error::{Result, SergeError};

/// One observation of a landmark triplet `(D, E, F)` (positions and covariances in one
/// frame, e.g. the robot's at one time step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TripletObservation {
    /// Which triplet (belief index).
    pub triplet: usize,
    /// Measured D, E, F.
    pub points: [[f64; 2]; 3],
    /// Their covariances `[[a, b], [b, c]]`.
    pub cov: [[[f64; 2]; 2]; 3],
}

/// F in the normalised frame of (D, E); `None` when D and E coincide.
#[must_use]
pub fn normalise(d: [f64; 2], e: [f64; 2], f: [f64; 2]) -> Option<[f64; 2]> {
    let frame = TernaryFrame::new(Point2::new(d[0], d[1]), Point2::new(e[0], e[1])).ok()?;
    let p = frame.to_normalised(&Point2::new(f[0], f[1]));
    Some([p.x, p.y])
}

fn cholesky(c: &[[f64; 2]; 2]) -> Result<[f64; 3]> {
    let l00 = c[0][0].sqrt();
    if l00.is_nan() || l00 <= 0.0 {
        // PSD with a zero variance: a point measurement on that axis
        if c[0][0] == 0.0 && c[0][1] == 0.0 && c[1][1] >= 0.0 {
            return Ok([0.0, 0.0, c[1][1].sqrt()]);
        }
        return Err(SergeError::NonFinite(format!(
            "covariance {c:?} is not PSD"
        )));
    }
    let l10 = c[0][1] / l00;
    let r = c[1][1] - l10 * l10;
    if r < -1e-12 * c[1][1].abs().max(1.0) || !r.is_finite() {
        return Err(SergeError::NonFinite(format!(
            "covariance {c:?} is not PSD"
        )));
    }
    Ok([l00, l10, r.max(0.0).sqrt()])
}

/// The normalised data points of each triplet (one per observation whose D and E differ).
///
/// # Errors
/// [`SergeError::Empty`] when a triplet in `0..n_triplets` has no usable observation.
pub fn triplet_points(obs: &[TripletObservation], n_triplets: usize) -> Result<Vec<Vec<[f64; 2]>>> {
    let mut out = vec![Vec::new(); n_triplets];
    for o in obs {
        if o.triplet >= n_triplets {
            return Err(SergeError::Unknown {
                kind: "triplet",
                index: o.triplet,
            });
        }
        if let Some(p) = normalise(o.points[0], o.points[1], o.points[2]) {
            out[o.triplet].push(p);
        }
    }
    if let Some(k) = out.iter().position(Vec::is_empty) {
        return Err(SergeError::Empty(format!(
            "triplet {k} has no usable observation"
        )));
    }
    Ok(out)
}

/// Sample beliefs of F in the (D, E) frame (eq. 3.11): `samples` per triplet, drawn
/// round-robin over the triplet's observations. Deterministic for a seed, whatever the
/// thread count (one generator per triplet).
///
/// # Errors
/// [`SergeError::Empty`] for a triplet without observations or `samples = 0`;
/// [`SergeError::NonFinite`] for bad covariances; [`SergeError::Unknown`] for a triplet
/// index ≥ `n_triplets`.
pub fn triplet_beliefs(
    obs: &[TripletObservation],
    n_triplets: usize,
    samples: usize,
    seed: u64,
) -> Result<BeliefSet> {
    if samples == 0 {
        return Err(SergeError::Empty("samples per belief must be ≥ 1".into()));
    }
    let mut by_triplet: Vec<Vec<&TripletObservation>> = vec![Vec::new(); n_triplets];
    for o in obs {
        if o.triplet >= n_triplets {
            return Err(SergeError::Unknown {
                kind: "triplet",
                index: o.triplet,
            });
        }
        if o.points
            .iter()
            .flatten()
            .chain(o.cov.iter().flatten().flatten())
            .any(|v| !v.is_finite())
        {
            return Err(SergeError::NonFinite(format!(
                "an observation of triplet {} is not finite",
                o.triplet
            )));
        }
        by_triplet[o.triplet].push(o);
    }
    let beliefs: Vec<Belief> = by_triplet
        .par_iter()
        .enumerate()
        .map(|(k, list)| {
            if list.is_empty() {
                return Err(SergeError::Empty(format!("triplet {k} has no observation")));
            }
            let chol: Vec<[[f64; 3]; 3]> = list
                .iter()
                .map(|o| {
                    Ok([
                        cholesky(&o.cov[0])?,
                        cholesky(&o.cov[1])?,
                        cholesky(&o.cov[2])?,
                    ])
                })
                .collect::<Result<_>>()?;
            let mut rng =
                ChaCha8Rng::seed_from_u64(seed ^ (k as u64).wrapping_mul(0xa076_1d64_78bd_642f));
            let mut out = Vec::with_capacity(samples);
            let mut attempts = 0usize;
            while out.len() < samples {
                attempts += 1;
                if attempts > 100 * samples {
                    return Err(SergeError::Empty(format!(
                        "triplet {k}: D and E coincide in almost every sample"
                    )));
                }
                let i = out.len() % list.len();
                let o = list[i];
                let mut pts = [[0.0; 2]; 3];
                for (j, p) in pts.iter_mut().enumerate() {
                    let z0: f64 = StandardNormal.sample(&mut rng);
                    let z1: f64 = StandardNormal.sample(&mut rng);
                    let l = chol[i][j];
                    *p = [
                        o.points[j][0] + l[0] * z0,
                        o.points[j][1] + l[1] * z0 + l[2] * z1,
                    ];
                }
                if let Some(f) = normalise(pts[0], pts[1], pts[2]) {
                    out.push(f);
                }
            }
            Ok(Belief::samples(out))
        })
        .collect::<Result<_>>()?;
    BeliefSet::new(beliefs)
}

/// An interval `[lo, hi]` (possibly unbounded).
#[derive(Debug, Clone, Copy)]
struct Iv(f64, f64);

impl Iv {
    fn add(self, o: Iv) -> Iv {
        Iv(self.0 + o.0, self.1 + o.1)
    }
    fn neg(self) -> Iv {
        Iv(-self.1, -self.0)
    }
    fn mul(self, o: Iv) -> Iv {
        // 0·∞ = 0 at endpoints: the interval's product set is still enclosed
        let m = |a: f64, b: f64| if a == 0.0 || b == 0.0 { 0.0 } else { a * b };
        let p = [
            m(self.0, o.0),
            m(self.0, o.1),
            m(self.1, o.0),
            m(self.1, o.1),
        ];
        Iv(
            p.iter().copied().fold(f64::INFINITY, f64::min),
            p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    }
}

/// The raster geometry of a learned calculus, with per-state summed-area tables.
struct RasterIndex {
    window: [f64; 4],
    nx: usize,
    ny: usize,
    cells: Vec<u16>,
    n_states: usize,
    /// `sat[q][(j)*(nx+1) + i]`: cells of state q in `[0, i) × [0, j)`.
    sat: Vec<Vec<u32>>,
    /// The fixed outside state (outside rule `state`), if any.
    outside: Option<usize>,
}

impl RasterIndex {
    fn new(calculus: &Calculus) -> Result<Self> {
        let spec = calculus.spec();
        let raster = spec.raster.as_ref().ok_or_else(|| {
            SergeError::InvalidParameter(format!(
                "calculus `{}` is not a learned (raster) calculus: Algorithm 3 works on cells",
                calculus.name()
            ))
        })?;
        if calculus.frame() != qsr_core::FrameKind::Ternary {
            return Err(SergeError::InvalidParameter(format!(
                "calculus `{}` is not ternary: composition needs two reference points",
                calculus.name()
            )));
        }
        let (nx, ny) = (raster.nx, raster.ny);
        let n_states = calculus.n_states();
        let mut sat = vec![vec![0u32; (nx + 1) * (ny + 1)]; n_states];
        for (q, table) in sat.iter_mut().enumerate() {
            for j in 0..ny {
                let mut row = 0u32;
                for i in 0..nx {
                    row += u32::from(usize::from(raster.cells[j * nx + i]) == q);
                    table[(j + 1) * (nx + 1) + i + 1] = table[j * (nx + 1) + i + 1] + row;
                }
            }
        }
        let outside = match &raster.outside {
            OutsideRule::Clamp => None,
            OutsideRule::State { label } => Some(calculus.state(label)?.index()),
        };
        Ok(Self {
            window: raster.window,
            nx,
            ny,
            cells: raster.cells.clone(),
            n_states,
            sat,
            outside,
        })
    }

    fn size(&self) -> (f64, f64) {
        (
            (self.window[1] - self.window[0]) / self.nx as f64,
            (self.window[3] - self.window[2]) / self.ny as f64,
        )
    }

    /// Index range of the cells an interval touches along x (`axis = 0`) or y, clamped to
    /// the window.
    fn range(&self, v: Iv, axis: usize) -> (usize, usize) {
        let (d, origin, n) = if axis == 0 {
            (self.size().0, self.window[0], self.nx)
        } else {
            (self.size().1, self.window[2], self.ny)
        };
        let idx = |x: f64| {
            let k = ((x - origin) / d).floor();
            if k.is_nan() {
                0
            } else {
                k.clamp(0.0, (n - 1) as f64) as usize
            }
        };
        (idx(v.0), idx(v.1))
    }

    /// Closed box of cell `c`; with the clamp rule border cells reach to infinity.
    fn cell_box(&self, c: usize) -> (Iv, Iv) {
        let (dx, dy) = self.size();
        let (i, j) = (c % self.nx, c / self.nx);
        let clamp = self.outside.is_none();
        let lo = |k: usize, origin: f64, d: f64| {
            if clamp && k == 0 {
                f64::NEG_INFINITY
            } else {
                origin + k as f64 * d
            }
        };
        let hi = |k: usize, n: usize, origin: f64, d: f64| {
            if clamp && k + 1 == n {
                f64::INFINITY
            } else {
                origin + (k + 1) as f64 * d
            }
        };
        (
            Iv(
                lo(i, self.window[0], dx),
                hi(i, self.nx, self.window[0], dx),
            ),
            Iv(
                lo(j, self.window[2], dy),
                hi(j, self.ny, self.window[2], dy),
            ),
        )
    }

    /// Marks in `out` every state with a point in the box `(x, y)`.
    fn states_in(&self, x: Iv, y: Iv, out: &mut [bool]) {
        let beyond = x.0 < self.window[0]
            || x.1 > self.window[1]
            || y.0 < self.window[2]
            || y.1 > self.window[3];
        if let (Some(q), true) = (self.outside, beyond) {
            out[q] = true;
        }
        if self.outside.is_some()
            && (x.1 < self.window[0]
                || x.0 > self.window[1]
                || y.1 < self.window[2]
                || y.0 > self.window[3])
        {
            return; // entirely outside: only the outside state
        }
        let (i0, i1) = self.range(x, 0);
        let (j0, j1) = self.range(y, 1);
        let w = self.nx + 1;
        for (q, t) in self.sat.iter().enumerate() {
            if out[q] {
                continue;
            }
            let n = t[(j1 + 1) * w + i1 + 1] + t[j0 * w + i0]
                - t[j0 * w + i1 + 1]
                - t[(j1 + 1) * w + i0];
            if n > 0 {
                out[q] = true;
            }
        }
    }

    /// Box of G in frame DE for F in box `c` and G's position P in frame EF in box `p`.
    fn place(c: (Iv, Iv), p: (Iv, Iv)) -> (Iv, Iv) {
        // E = (0, 1); e = F − E
        let ex = c.0;
        let ey = c.1.add(Iv(-1.0, -1.0));
        let x = p.1.mul(ex).add(p.0.mul(ey));
        let y = Iv(1.0, 1.0).add(p.1.mul(ey)).add(p.0.mul(ex).neg());
        (x, y)
    }
}

/// The compose table of a learned calculus by Algorithm 3 over cells (see the module docs):
/// sound for every configuration. `progress` is told the number of cells (the outside counts
/// as one when its state is fixed), ticks after each and is checked before each: a fine
/// raster takes seconds to tens of seconds.
///
/// # Errors
/// [`SergeError::InvalidParameter`] for a calculus that is not a ternary raster calculus;
/// [`SergeError::Cancelled`] when `progress` asks to stop.
pub fn compose_table(calculus: &Calculus, progress: &dyn Progress) -> Result<ComposeTable> {
    let index = RasterIndex::new(calculus)?;
    let q = index.n_states;
    let n = index.cells.len();
    let boxes: Vec<(Iv, Iv)> = (0..n).map(|c| index.cell_box(c)).collect();
    // With a fixed outside state, the outside is one more (unbounded) "cell".
    let extra: Vec<(usize, (Iv, Iv))> = index
        .outside
        .map(|s| {
            (
                s,
                (
                    Iv(f64::NEG_INFINITY, f64::INFINITY),
                    Iv(f64::NEG_INFINITY, f64::INFINITY),
                ),
            )
        })
        .into_iter()
        .collect();
    let all: Vec<(usize, (Iv, Iv))> = (0..n)
        .map(|c| (usize::from(index.cells[c]), boxes[c]))
        .chain(extra)
        .collect();
    progress.add_total(all.len());
    // rows[r][s][t]
    let rows: Vec<Vec<Vec<bool>>> = (0..q)
        .into_par_iter()
        .map(|r| {
            let mut row = vec![vec![false; q]; q];
            for &(_, cb) in all.iter().filter(|(s, _)| *s == r) {
                progress.check()?;
                for &(s, pb) in &all {
                    if row[s].iter().all(|&b| b) {
                        continue;
                    }
                    let (x, y) = RasterIndex::place(cb, pb);
                    index.states_in(x, y, &mut row[s]);
                }
                progress.tick();
            }
            Ok(row)
        })
        .collect::<Result<_>>()?;
    let table = rows
        .into_iter()
        .map(|row| {
            row.into_iter()
                .map(|hits| {
                    hits.iter()
                        .enumerate()
                        .filter(|&(_, &h)| h)
                        .map(|(t, _)| StateId(t as u16))
                        .collect()
                })
                .collect()
        })
        .collect();
    Ok(ComposeTable::from_rows(table)?)
}

/// The Fig 3.10 picture for `{DE:F} = r`, `{EF:G} = s`: which raster cells of frame DE the
/// union of Algorithm 3's boxes covers (window cells only), and the resulting states.
///
/// # Errors
/// As [`compose_table`].
pub fn compose_coverage(
    calculus: &Calculus,
    r: StateId,
    s: StateId,
) -> Result<(Vec<bool>, Vec<StateId>)> {
    let index = RasterIndex::new(calculus)?;
    let n = index.cells.len();
    // 2-D difference array of the boxes, summed at the end: O(1) per cell pair
    let w = index.nx + 1;
    let mut diff = vec![0i64; w * (index.ny + 1)];
    let mut states = vec![false; index.n_states];
    for c in (0..n).filter(|&c| usize::from(index.cells[c]) == r.index()) {
        for p in (0..n).filter(|&p| usize::from(index.cells[p]) == s.index()) {
            let (x, y) = RasterIndex::place(index.cell_box(c), index.cell_box(p));
            index.states_in(x, y, &mut states);
            let (i0, i1) = index.range(x, 0);
            let (j0, j1) = index.range(y, 1);
            diff[j0 * w + i0] += 1;
            diff[j0 * w + i1 + 1] -= 1;
            diff[(j1 + 1) * w + i0] -= 1;
            diff[(j1 + 1) * w + i1 + 1] += 1;
        }
    }
    let mut covered = vec![false; n];
    let mut acc = vec![0i64; w * (index.ny + 1)];
    for j in 0..index.ny {
        for i in 0..index.nx {
            let up = if j > 0 { acc[(j - 1) * w + i] } else { 0 };
            let left = if i > 0 { acc[j * w + i - 1] } else { 0 };
            let diag = if i > 0 && j > 0 {
                acc[(j - 1) * w + i - 1]
            } else {
                0
            };
            acc[j * w + i] = diff[j * w + i] + up + left - diag;
            covered[j * index.nx + i] = acc[j * w + i] > 0;
        }
    }
    let states = states
        .iter()
        .enumerate()
        .filter(|&(_, &h)| h)
        .map(|(t, _)| StateId(t as u16))
        .collect();
    Ok((covered, states))
}
