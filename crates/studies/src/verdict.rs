//! Verdicts a report states, computed: the direction of a series and whether ours agrees
//! with the thesis's. A report never types "grows" or "agree" by hand; it asks these.

use serde::{Deserialize, Serialize};

/// The direction of a series, as a report states it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Trend {
    /// Never falls, and rises overall by more than the tolerance.
    Rises,
    /// Never rises, and falls overall by more than the tolerance.
    Falls,
    /// Every value within the tolerance of the first.
    Flat,
    /// Rises and falls.
    Mixed,
}

impl Trend {
    /// The trend of `values` in order; steps within `tolerance` count as level.
    #[must_use]
    pub fn of(values: &[f64], tolerance: f64) -> Self {
        let first = values.first().copied().unwrap_or(0.0);
        if values.iter().all(|v| (v - first).abs() <= tolerance) {
            return Self::Flat;
        }
        let up = values.windows(2).any(|w| w[1] > w[0] + tolerance);
        let down = values.windows(2).any(|w| w[1] < w[0] - tolerance);
        match (up, down) {
            (true, false) => Self::Rises,
            (false, true) => Self::Falls,
            (false, false) => Self::Flat,
            (true, true) => Self::Mixed,
        }
    }

    /// The trend of sample means `(mean, standard error)` in order, read through their noise:
    /// a step — between neighbours, or from the first to the last — counts only where it
    /// exceeds `z` standard errors of the difference (1.96: the 5 % level). A dip within
    /// the noise of two means drawn from a rising series is not a fall; a rise within it is
    /// not a rise either.
    ///
    /// ```
    /// use studies::verdict::Trend;
    /// // 30 → 44 → 34 → 48 m, each ± 3 m: the dip 44 → 34 is beyond noise
    /// let dipped = [(30.0, 3.0), (44.0, 3.0), (34.0, 3.0), (48.0, 3.0)];
    /// assert_eq!(Trend::of_means(&dipped, 1.96), Trend::Mixed);
    /// // ± 6 m: it is not (1.96·√2·6 ≈ 16.6 m), and 30 → 48 is
    /// let noisy = [(30.0, 6.0), (44.0, 6.0), (34.0, 6.0), (48.0, 6.0)];
    /// assert_eq!(Trend::of_means(&noisy, 1.96), Trend::Rises);
    /// ```
    #[must_use]
    pub fn of_means(rows: &[(f64, f64)], z: f64) -> Self {
        let step = |a: (f64, f64), b: (f64, f64)| {
            let noise = z * a.1.hypot(b.1);
            if b.0 - a.0 > noise {
                1
            } else if a.0 - b.0 > noise {
                -1
            } else {
                0
            }
        };
        let mut steps: Vec<i32> = rows.windows(2).map(|w| step(w[0], w[1])).collect();
        if let (Some(&a), Some(&b)) = (rows.first(), rows.last()) {
            steps.push(step(a, b));
        }
        match (steps.contains(&1), steps.contains(&-1)) {
            (true, false) => Self::Rises,
            (false, true) => Self::Falls,
            (false, false) => Self::Flat,
            (true, true) => Self::Mixed,
        }
    }

    /// "rises", "falls", "is flat", "rises and falls".
    #[must_use]
    pub fn phrase(self) -> &'static str {
        match self {
            Self::Rises => "rises",
            Self::Falls => "falls",
            Self::Flat => "is flat",
            Self::Mixed => "rises and falls",
        }
    }
}

/// The Wilson score interval of a proportion `successes / n` at `z` standard errors (1.96:
/// 95 %): where the true rate lies, given the count. `[0, 1]` for `n = 0` (nothing known).
#[must_use]
pub fn wilson_interval(successes: usize, n: usize, z: f64) -> [f64; 2] {
    if n == 0 {
        return [0.0, 1.0];
    }
    let nf = n as f64;
    let p = successes.min(n) as f64 / nf;
    let z2 = z * z;
    let denominator = 1.0 + z2 / nf;
    let centre = (p + z2 / (2.0 * nf)) / denominator;
    let half = z * (p * (1.0 - p) / nf + z2 / (4.0 * nf * nf)).sqrt() / denominator;
    [(centre - half).max(0.0), (centre + half).min(1.0)]
}

/// The two-proportion z statistic of `k1 / n1` against `k0 / n0` (pooled standard error):
/// positive when the first is the higher rate; |z| > 1.96 is a difference at the 5 % level.
/// 0 when either count is empty or the pooled rate is 0 or 1 (no spread to judge by).
#[must_use]
pub fn two_proportion_z(k1: usize, n1: usize, k0: usize, n0: usize) -> f64 {
    if n1 == 0 || n0 == 0 {
        return 0.0;
    }
    let (n1f, n0f) = (n1 as f64, n0 as f64);
    let pooled = (k1 + k0) as f64 / (n1f + n0f);
    let se = (pooled * (1.0 - pooled) * (1.0 / n1f + 1.0 / n0f)).sqrt();
    if se == 0.0 {
        return 0.0;
    }
    (k1 as f64 / n1f - k0 as f64 / n0f) / se
}

/// "agree" when our trend is the thesis's, else "disagree".
#[must_use]
pub fn agreement(ours: Trend, theirs: Trend) -> &'static str {
    if ours == theirs { "agree" } else { "disagree" }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_within_the_noise_of_the_means_do_not_count() {
        // one point per mean, no spread: every step counts, as `of` with no tolerance
        let exact = [(1.0, 0.0), (2.0, 0.0), (1.5, 0.0)];
        assert_eq!(Trend::of_means(&exact, 1.96), Trend::Mixed);
        assert_eq!(
            Trend::of_means(&[(1.0, 0.0), (2.0, 0.0)], 1.96),
            Trend::Rises
        );
        assert_eq!(
            Trend::of_means(&[(2.0, 0.0), (1.0, 0.0)], 1.96),
            Trend::Falls
        );
        // a rise of 1.9 standard errors is no rise; of 2.0 it is
        let se = 1.0 / 2f64.sqrt();
        assert_eq!(Trend::of_means(&[(0.0, se), (1.9, se)], 2.0), Trend::Flat);
        assert_eq!(Trend::of_means(&[(0.0, se), (2.01, se)], 2.0), Trend::Rises);
        // small steps adding up beyond noise are a rise; one that falls beyond it is not
        let creep = [(0.0, 1.0), (2.0, 1.0), (4.0, 1.0), (6.0, 1.0)];
        assert_eq!(Trend::of_means(&creep, 1.96), Trend::Rises);
        let slump = [(0.0, 1.0), (2.0, 1.0), (-2.0, 1.0), (6.0, 1.0)];
        assert_eq!(Trend::of_means(&slump, 1.96), Trend::Mixed);
        assert_eq!(Trend::of_means(&[], 1.96), Trend::Flat);
        assert_eq!(Trend::of_means(&[(3.0, 1.0)], 1.96), Trend::Flat);
    }

    #[test]
    fn a_flat_series_is_flat_not_growing() {
        // issue 14/18: "0.0 % → 0.0 % → 0.0 % → 0.0 %" was reported as growing
        assert_eq!(Trend::of(&[0.0, 0.0, 0.0, 0.0], 1e-9), Trend::Flat);
        assert_eq!(Trend::of(&[0.0, 0.01, 0.01, 0.2], 1e-9), Trend::Rises);
        assert_eq!(Trend::of(&[0.3, 0.2, 0.2], 1e-9), Trend::Falls);
        assert_eq!(Trend::of(&[0.1, 0.3, 0.2], 1e-9), Trend::Mixed);
        assert_eq!(Trend::of(&[0.1, 0.1005, 0.1], 0.001), Trend::Flat);
    }

    #[test]
    fn wilson_intervals_of_known_counts() {
        // 13 of 18 (the thesis's field trials): 0.491..0.875 at 95 %
        let [lo, hi] = wilson_interval(13, 18, 1.96);
        assert!(
            (lo - 0.4912).abs() < 5e-4 && (hi - 0.8750).abs() < 5e-4,
            "{lo} {hi}"
        );
        // all or nothing still has a width; no trials says nothing
        let [lo, hi] = wilson_interval(0, 10, 1.96);
        assert!(lo == 0.0 && (hi - 0.2775).abs() < 5e-4, "{hi}");
        let [lo, hi] = wilson_interval(10, 10, 1.96);
        assert!((lo - 0.7225).abs() < 5e-4 && hi == 1.0, "{lo}");
        assert_eq!(wilson_interval(0, 0, 1.96), [0.0, 1.0]);
    }

    #[test]
    fn two_proportions_differ_only_beyond_their_noise() {
        // 90 of 100 against 70 of 100: z = 0.2 / sqrt(0.8 * 0.2 * 0.02) = 3.536
        let z = two_proportion_z(90, 100, 70, 100);
        assert!((z - 3.5355).abs() < 1e-3, "{z}");
        assert!((two_proportion_z(70, 100, 90, 100) + z).abs() < 1e-12);
        // 9 of 12 against 8 of 12 is noise
        assert!(two_proportion_z(9, 12, 8, 12).abs() < 1.96);
        assert_eq!(two_proportion_z(5, 5, 7, 7), 0.0);
        assert_eq!(two_proportion_z(1, 0, 7, 7), 0.0);
    }

    #[test]
    fn agreement_needs_the_same_trend() {
        assert_eq!(agreement(Trend::Rises, Trend::Rises), "agree");
        assert_eq!(agreement(Trend::Flat, Trend::Rises), "disagree");
    }
}
