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

/// "agree" when our trend is the thesis's, else "disagree".
#[must_use]
pub fn agreement(ours: Trend, theirs: Trend) -> &'static str {
    if ours == theirs { "agree" } else { "disagree" }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn agreement_needs_the_same_trend() {
        assert_eq!(agreement(Trend::Rises, Trend::Rises), "agree");
        assert_eq!(agreement(Trend::Flat, Trend::Rises), "disagree");
    }
}
