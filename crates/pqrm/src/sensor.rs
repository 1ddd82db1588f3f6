//! Inverse sensor models: how a detection's position is sampled (thesis eq. 2.9 uses a
//! Gaussian).
//!
//! A real sensor has gross outliers (a misread barcode, a reflection, another robot taken for
//! a landmark). Under a Gaussian, one such frame moves a triplet's belief by up to
//! ln((s + α)/α) nats — as much as many honest frames — so the filter locks onto states a
//! majority of frames would not pick. Heavy-tailed models spread a little probability over
//! far configurations, so one frame cannot rule a state out:
//!
//! | model | a sample is | reads as |
//! |---|---|---|
//! | [`SensorModel::Gaussian`] | `μ + L z`, `z ~ N(0, I)`, `L Lᵀ = Σ` | the thesis |
//! | [`SensorModel::StudentT`] | `μ + L z / √(w/ν)`, `w ~ χ²(ν)` | a multivariate t with scale Σ (covariance `ν/(ν−2) Σ` for ν > 2) |
//! | [`SensorModel::Outliers`] | with probability `rate` a point uniform in the disc of radius `spread` about the sensor, else Gaussian | a Gaussian plus an outlier anywhere in the field of view |
//!
//! The two differ against a *gross* outlier: a t tail at 20σ still puts nearly every sample
//! of that frame on the far side, so the frame moves the belief almost as much as under the
//! Gaussian (measured: 7.6 vs 8.3 nats), while the mixture bounds any frame's influence by
//! the share of samples it spreads over the field of view (1.9 nats at 10 %) — see
//! `tests/sensor_model.rs`.
//!
//! Like the Gaussian, each is sampled once per landmark per step and shared by every triplet
//! (see [`crate::sampler`]); the Gaussian's samples are unchanged bit for bit.

use rand::RngExt;
use rand_distr::{ChiSquared, Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};

/// How a detection's position is sampled.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum SensorModel {
    /// The thesis's Gaussian with the detection's covariance.
    #[default]
    Gaussian,
    /// A multivariate Student-t with `nu` degrees of freedom and the covariance as its scale.
    StudentT {
        /// Degrees of freedom (> 0; 3–5 for heavy tails, ∞ → Gaussian).
        nu: f64,
    },
    /// A Gaussian plus outliers uniform over a disc about the sensor.
    Outliers {
        /// Probability that a detection is an outlier, in `[0, 1)`.
        rate: f64,
        /// Radius (m) of the disc about the sensor the outliers fall in (the field of view).
        spread: f64,
    },
}

impl SensorModel {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] naming the parameter.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Self::Gaussian => Ok(()),
            Self::StudentT { nu } if nu.is_finite() && nu > 0.0 => Ok(()),
            Self::StudentT { nu } => Err(PqrmError::InvalidConfig(format!(
                "student-t degrees of freedom must be finite and > 0, got {nu}"
            ))),
            Self::Outliers { rate, spread }
                if (0.0..1.0).contains(&rate)
                    && spread.is_finite()
                    && spread > 0.0
                    && spread <= crate::observation::MAX_DISTANCE_M =>
            {
                Ok(())
            }
            Self::Outliers { rate, spread } => Err(PqrmError::InvalidConfig(format!(
                "outliers:{rate:?},{spread:?}: the outlier rate must be in [0, 1) and the spread \
                 finite, > 0 and at most {:e} m",
                crate::observation::MAX_DISTANCE_M
            ))),
        }
    }

    /// Parses `gaussian`, `student-t:NU` or `outliers:RATE,SPREAD` (the CLI's spelling).
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for anything else or out-of-range values.
    pub fn parse(text: &str) -> Result<Self> {
        let bad = || {
            PqrmError::InvalidConfig(format!(
                "sensor model `{text}`: expected gaussian, student-t:NU or outliers:RATE,SPREAD"
            ))
        };
        let num = |s: &str| s.trim().parse::<f64>().map_err(|_| bad());
        let model = match text.split_once(':') {
            None if text.trim() == "gaussian" => Self::Gaussian,
            Some(("student-t", nu)) => Self::StudentT { nu: num(nu)? },
            Some(("outliers", args)) => {
                let (rate, spread) = args.split_once(',').ok_or_else(bad)?;
                Self::Outliers {
                    rate: num(rate)?,
                    spread: num(spread)?,
                }
            }
            _ => return Err(bad()),
        };
        model.validate()?;
        Ok(model)
    }

    /// The CLI spelling ([`SensorModel::parse`] reads it back).
    #[must_use]
    pub fn label(&self) -> String {
        match *self {
            Self::Gaussian => "gaussian".into(),
            Self::StudentT { nu } => format!("student-t:{nu}"),
            Self::Outliers { rate, spread } => format!("outliers:{rate},{spread}"),
        }
    }

    /// One sample of a detection at `mean` with Cholesky factor `[l11, l21, l22]`.
    pub(crate) fn sample(
        &self,
        rng: &mut impl rand::Rng,
        mean: [f64; 2],
        [l11, l21, l22]: [f64; 3],
    ) -> [f64; 2] {
        // The same arithmetic, in the same order, as the sampler's Gaussian loop.
        let gaussian = |rng: &mut _| {
            let z1: f64 = StandardNormal.sample(rng);
            let z2: f64 = StandardNormal.sample(rng);
            [mean[0] + l11 * z1, mean[1] + l21 * z1 + l22 * z2]
        };
        match *self {
            Self::Gaussian => gaussian(rng),
            Self::StudentT { nu } => {
                let p = gaussian(rng);
                // ν > 0 is checked by validate(); a failed construction falls back to Gaussian.
                let w = ChiSquared::new(nu).map_or(nu, |c| c.sample(rng));
                let s = (nu / w.max(f64::MIN_POSITIVE)).sqrt();
                [
                    mean[0] + s * (p[0] - mean[0]),
                    mean[1] + s * (p[1] - mean[1]),
                ]
            }
            Self::Outliers { rate, spread } => {
                let u: f64 = rng.random();
                let p = gaussian(rng);
                if u < rate {
                    // Uniform in the disc: radius ∝ √U.
                    let r = spread * rng.random::<f64>().sqrt();
                    let a = std::f64::consts::TAU * rng.random::<f64>();
                    [r * a.cos(), r * a.sin()]
                } else {
                    p
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn draws(m: SensorModel, n: usize) -> Vec<[f64; 2]> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        (0..n)
            .map(|_| m.sample(&mut rng, [5.0, 0.0], [0.1, 0.0, 0.1]))
            .collect()
    }

    #[test]
    fn student_t_has_heavier_tails_than_the_gaussian_and_the_same_centre() {
        let far = |v: &[[f64; 2]]| v.iter().filter(|p| (p[0] - 5.0).abs() > 0.5).count();
        let g = draws(SensorModel::Gaussian, 20_000);
        let t = draws(SensorModel::StudentT { nu: 3.0 }, 20_000);
        // 5σ: ~0 for the Gaussian, ~1.5 % for t(3).
        assert!(far(&g) < 5, "{}", far(&g));
        assert!(far(&t) > 100, "{}", far(&t));
        let mut xs: Vec<f64> = t.iter().map(|p| p[0]).collect();
        xs.sort_by(f64::total_cmp);
        assert!((xs[xs.len() / 2] - 5.0).abs() < 0.01);
    }

    #[test]
    fn outliers_fall_in_the_disc_at_the_given_rate() {
        let o = draws(
            SensorModel::Outliers {
                rate: 0.1,
                spread: 30.0,
            },
            20_000,
        );
        let out = o.iter().filter(|p| (p[0] - 5.0).hypot(p[1]) > 1.0).count();
        // 10 % outliers, of which those within 1 m of the landmark (1/900 of the disc) look honest.
        assert!((out as f64 / 20_000.0 - 0.1).abs() < 0.01, "{out}");
        assert!(o.iter().all(|p| p[0].hypot(p[1]) <= 30.0 + 1.0));
    }

    #[test]
    fn the_cli_spelling_parses_and_bad_values_are_refused() {
        assert_eq!(
            SensorModel::parse("gaussian").unwrap(),
            SensorModel::Gaussian
        );
        assert_eq!(
            SensorModel::parse("student-t:4").unwrap(),
            SensorModel::StudentT { nu: 4.0 }
        );
        assert_eq!(
            SensorModel::parse("outliers:0.05,30").unwrap(),
            SensorModel::Outliers {
                rate: 0.05,
                spread: 30.0
            }
        );
        for m in [
            SensorModel::Gaussian,
            SensorModel::StudentT { nu: 4.5 },
            SensorModel::Outliers {
                rate: 0.05,
                spread: 30.0,
            },
        ] {
            assert_eq!(SensorModel::parse(&m.label()).unwrap(), m);
        }
        for bad in [
            "student-t:0",
            "student-t:nan",
            "outliers:1,30",
            "outliers:0.1",
            "cauchy",
        ] {
            assert!(SensorModel::parse(bad).is_err(), "{bad}");
        }
    }
}
