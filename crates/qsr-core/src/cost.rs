//! [`Cost`]: what a run will take before it starts — peak memory and single-core work — and
//! [`Budget`], the limits it is checked against.
//!
//! **Why one type.** Every knob that drives work (a study's trials and steps, a network's
//! points, a calculus's granularity, a grid's cells, a look-ahead's horizon) used to be checked
//! by its own rule in its own unit — bytes here, "grid steps" there, core-hours elsewhere —
//! and a knob no rule covered ran for hours or aborted on allocation (issue 39). Now every
//! estimate in qrm is a `Cost` built from the knobs that drive it at *measured* rates
//! (each site says where its rate comes from), and every refusal is [`Cost::check`]'s, in one
//! form that names the knobs, the estimate and the limits:
//!
//! ```text
//! levels × trials × steps × ordered triplets × samples = 23 × 1000000000 × 23 × 720 × 1000 =
//! 3.81e17 triplet-samples needs about 5.9e5 core-hours; the limits are 4 GiB and 48
//! core-hours: fewer trials, samples, landmarks or levels, or a coarser step_deg
//! ```
//!
//! Work is in *core-seconds* (one core's CPU time), so an estimate does not change with the
//! machine's thread count; what a refusal reports is the same on a laptop and on a cluster
//! node. A NaN anywhere in the knobs makes the estimate undefined, which is refused too (a NaN
//! compares false, so `cost > limit` alone would let it through).
//!
//! ```
//! use qsr_core::cost::{Budget, Cost};
//! let per_item = Cost::new(1024.0, 1e-6);
//! let run = per_item.times(1e6); // a million items: 1 GiB, one core-second
//! assert!(run.check(&Budget::RUN, "items = 1000000").is_ok());
//! let err = per_item.times(1e7).check(&Budget::RUN, "items = 10000000").unwrap_err();
//! assert_eq!(
//!     err.to_string(),
//!     "items = 10000000 needs about 9.54 GiB and 10 core-seconds; the limits are 4 GiB and \
//!      48 core-hours"
//! );
//! ```

use std::fmt;

/// Bytes in a GiB.
const GIB: f64 = (1u64 << 30) as f64;

/// An estimate of peak memory (bytes) and work (core-seconds), made before the work starts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[must_use]
pub struct Cost {
    bytes: f64,
    core_seconds: f64,
}

impl Cost {
    /// Nothing: the start of a sum.
    pub const ZERO: Self = Self::new(0.0, 0.0);

    /// A cost of `bytes` at the peak and `core_seconds` of one core's time.
    pub const fn new(bytes: f64, core_seconds: f64) -> Self {
        Self {
            bytes,
            core_seconds,
        }
    }

    /// Memory only (work too small to matter).
    pub const fn memory(bytes: f64) -> Self {
        Self::new(bytes, 0.0)
    }

    /// Work only: `units` of something measured at `seconds_per_unit` core-seconds each.
    pub fn work(units: f64, seconds_per_unit: f64) -> Self {
        Self::new(0.0, units * seconds_per_unit)
    }

    /// This cost `n` times over (memory and work both: `n` items held and processed).
    pub fn times(self, n: f64) -> Self {
        Self::new(self.bytes * n, self.core_seconds * n)
    }

    /// The same work with `bytes` more at the peak.
    pub fn and_memory(self, bytes: f64) -> Self {
        Self::new(self.bytes + bytes, self.core_seconds)
    }

    /// Peak memory in bytes.
    #[must_use]
    pub const fn bytes(&self) -> f64 {
        self.bytes
    }

    /// Work in core-seconds.
    #[must_use]
    pub const fn core_seconds(&self) -> f64 {
        self.core_seconds
    }

    /// Whether both parts are defined and within `budget`.
    #[must_use]
    pub fn fits(&self, budget: &Budget) -> bool {
        // Written so NaN fails: a comparison with NaN is false.
        self.bytes <= budget.bytes && self.core_seconds <= budget.core_seconds
    }

    /// Nothing when it [`fits`](Self::fits) `budget`; otherwise the refusal naming `what`
    /// (the knobs that drive it, with their values), the estimate and the limits.
    ///
    /// # Errors
    /// [`OverBudget`] when either part is over its limit or undefined (NaN).
    pub fn check(self, budget: &Budget, what: impl Into<String>) -> Result<(), OverBudget> {
        if self.fits(budget) {
            Ok(())
        } else {
            Err(OverBudget {
                what: what.into(),
                cost: self,
                budget: *budget,
                hint: None,
            })
        }
    }
}

impl std::ops::Add for Cost {
    type Output = Self;
    fn add(self, other: Self) -> Self {
        Self::new(
            self.bytes + other.bytes,
            self.core_seconds + other.core_seconds,
        )
    }
}

impl std::iter::Sum for Cost {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::ZERO, |a, b| a + b)
    }
}

/// "about 1.2 GiB and 3.4 core-minutes".
impl fmt::Display for Cost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.bytes.is_nan() || self.core_seconds.is_nan() {
            return f.write_str("an undefined amount (a knob is not a number)");
        }
        // A part that is nothing is left out: "about 0 B and 120 core-hours" says less.
        match (self.bytes > 0.0, self.core_seconds > 0.0) {
            (true, false) => write!(f, "about {}", Bytes(self.bytes)),
            (false, true) => write!(f, "about {}", CoreSeconds(self.core_seconds)),
            _ => write!(
                f,
                "about {} and {}",
                Bytes(self.bytes),
                CoreSeconds(self.core_seconds)
            ),
        }
    }
}

/// The most memory and work one run may ask for.
#[derive(Debug, Clone, Copy, PartialEq)]
#[must_use]
pub struct Budget {
    /// Peak bytes.
    pub bytes: f64,
    /// Core-seconds.
    pub core_seconds: f64,
}

impl Budget {
    /// A whole command or study: 4 GiB (what a laptop spares) and 48 core-hours (a weekend on
    /// two cores; the full-scale studies take hours). Every study, network and derived table
    /// is checked against it unless its site says why it needs a tighter one.
    pub const RUN: Self = Self::new(4.0 * GIB, 48.0 * 3600.0);

    /// A budget of `bytes` and `core_seconds`.
    pub const fn new(bytes: f64, core_seconds: f64) -> Self {
        Self {
            bytes,
            core_seconds,
        }
    }
}

/// "4 GiB and 48 core-hours".
impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} and {}",
            Bytes(self.bytes),
            CoreSeconds(self.core_seconds)
        )
    }
}

/// A run refused before it started: what drives it, its estimate and the limits.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct OverBudget {
    /// The knobs that drive the estimate, with their values (e.g. `"trials = 1e9, samples = 30"`).
    pub what: String,
    /// The estimate.
    pub cost: Cost,
    /// The limits it broke.
    pub budget: Budget,
    /// What to change (e.g. `"fewer trials or samples"`), if the site knows.
    pub hint: Option<String>,
}

impl OverBudget {
    /// The refusal with advice on what to lower.
    #[must_use]
    pub fn hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }
}

impl fmt::Display for OverBudget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} needs {}; the limits are {}",
            self.what, self.cost, self.budget
        )?;
        if let Some(hint) = &self.hint {
            write!(f, ": {hint}")?;
        }
        Ok(())
    }
}

/// Bytes for people: B, KiB, MiB, GiB; beyond a PiB in scientific GiB.
struct Bytes(f64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0;
        if !b.is_finite() {
            return f.write_str("unboundedly many bytes");
        }
        if b >= GIB * 1024.0 * 1024.0 {
            write!(f, "{:.1e} GiB", b / GIB)
        } else if b >= GIB {
            // whole limits print as "4 GiB", estimates with a decimal
            let g = b / GIB;
            if g.fract() == 0.0 && g < 1e4 {
                write!(f, "{g} GiB")
            } else if g < 10.0 {
                // two decimals near the limit: 4.01 GiB is over 4 GiB, "4.0" would not say so
                write!(f, "{g:.2} GiB")
            } else {
                write!(f, "{g:.1} GiB")
            }
        } else if b >= 1024.0 * 1024.0 {
            write!(f, "{:.0} MiB", b / (1024.0 * 1024.0))
        } else if b >= 1024.0 {
            write!(f, "{:.0} KiB", b / 1024.0)
        } else {
            write!(f, "{b:.0} B")
        }
    }
}

/// One core's time for people: core-seconds, -minutes, -hours; beyond a million hours in
/// scientific core-hours.
struct CoreSeconds(f64);

impl fmt::Display for CoreSeconds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.0;
        if !s.is_finite() {
            return f.write_str("unbounded work");
        }
        let h = s / 3600.0;
        let (value, unit) = if h >= 1e4 {
            return write!(f, "{h:.1e} core-hours");
        } else if s >= 3600.0 {
            (Sig(h).to_string(), "core-hour")
        } else if s >= 60.0 {
            (Sig(s / 60.0).to_string(), "core-minute")
        } else if s >= 0.1 {
            (Sig(s).to_string(), "core-second")
        } else {
            return f.write_str("under 0.1 core-seconds");
        };
        let plural = if value == "1" { "" } else { "s" };
        write!(f, "{value} {unit}{plural}")
    }
}

/// Two significant figures, no trailing zeros: 48, 2.1, 0.35.
struct Sig(f64);

impl fmt::Display for Sig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v >= 10.0 {
            write!(f, "{v:.0}")
        } else if v >= 1.0 {
            let s = format!("{v:.1}");
            f.write_str(s.strip_suffix(".0").unwrap_or(&s))
        } else {
            write!(f, "{v:.2}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cost_within_the_budget_passes_and_one_over_either_limit_is_refused() {
        let b = Budget::new(100.0, 10.0);
        assert!(Cost::new(100.0, 10.0).check(&b, "x").is_ok());
        assert!(Cost::new(101.0, 1.0).check(&b, "x").is_err());
        assert!(Cost::new(1.0, 10.5).check(&b, "x").is_err());
    }

    #[test]
    fn a_nan_or_infinite_knob_is_refused_and_said_to_be_undefined() {
        for c in [
            Cost::new(f64::NAN, 1.0),
            Cost::work(f64::NAN, 1e-9),
            Cost::memory(f64::INFINITY),
        ] {
            let e = c.check(&Budget::RUN, "trials = NaN").unwrap_err();
            let text = e.to_string();
            assert!(text.starts_with("trials = NaN needs"), "{text}");
            assert!(!text.contains("NaN GiB") && !text.contains("inf"), "{text}");
        }
        assert!(Cost::new(f64::NAN, 0.0).to_string().contains("undefined"));
    }

    #[test]
    fn estimates_print_in_the_unit_a_person_reads() {
        assert_eq!(
            Cost::new(5.3 * GIB, 7200.0).to_string(),
            "about 5.30 GiB and 2 core-hours"
        );
        assert_eq!(
            Budget::new(GIB, 3600.0).to_string(),
            "1 GiB and 1 core-hour"
        );
        assert_eq!(
            Cost::new(300.0 * 1024.0 * 1024.0, 90.0).to_string(),
            "about 300 MiB and 1.5 core-minutes"
        );
        assert_eq!(
            Cost::new(2048.0, 0.01).to_string(),
            "about 2 KiB and under 0.1 core-seconds"
        );
        assert_eq!(
            Cost::new(1e300, 1e300).to_string(),
            "about 9.3e290 GiB and 2.8e296 core-hours"
        );
        assert_eq!(Budget::RUN.to_string(), "4 GiB and 48 core-hours");
    }

    #[test]
    fn a_refusal_carries_its_hint_after_the_limits() {
        let e = Cost::work(1e12, 1.0)
            .check(&Budget::RUN, "trials = 1000000000000")
            .unwrap_err()
            .hint("fewer trials");
        assert!(
            e.to_string()
                .ends_with("the limits are 4 GiB and 48 core-hours: fewer trials"),
            "{e}"
        );
    }

    #[test]
    fn costs_add_and_scale() {
        assert_eq!(Cost::memory(2048.0).to_string(), "about 2 KiB");
        assert_eq!(Cost::work(90.0, 1.0).to_string(), "about 1.5 core-minutes");
        let c: Cost = [Cost::memory(10.0), Cost::work(2.0, 3.0)].into_iter().sum();
        assert_eq!(c, Cost::new(10.0, 6.0));
        assert_eq!(c.times(2.0).and_memory(1.0), Cost::new(21.0, 12.0));
    }
}
