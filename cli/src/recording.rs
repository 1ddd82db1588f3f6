//! Reading a user's recording for the commands that map one (`qrm map`, `pqrm calibrate`,
//! `convert`): its form, and the range-bearing noise given or fitted.

use std::path::Path;

use anyhow::{Result, ensure};
use pqrm::loaders::{Dataset, RangeBearingNoise};

use crate::flags::{InputFormat, NoiseArgs, NoiseMode};

/// Reads a recording (`studies::recording`).
pub fn load_dataset(
    format: InputFormat,
    input: &Path,
    noise: RangeBearingNoise,
) -> Result<Dataset> {
    Ok(studies::recording::read(format.into(), input, noise)?)
}

/// The range-bearing noise to load `input` with: `mode` `fixed` (the given sigmas, else
/// MRCLAM's defaults) or `auto` (fitted from the recording, `pqrm::calibrate`). Without a mode,
/// a given sigma means fixed — explicit values win — and otherwise MRCLAM is fitted.
pub fn resolve_noise(
    format: InputFormat,
    input: &Path,
    args: &NoiseArgs,
) -> Result<(RangeBearingNoise, Option<pqrm::calibrate::NoiseFit>)> {
    let (mode, sigma_range, sigma_bearing) = (args.mode, args.sigma_range, args.sigma_bearing);
    let fixed = RangeBearingNoise {
        sigma_range: sigma_range.unwrap_or(RangeBearingNoise::MRCLAM.sigma_range),
        sigma_bearing: sigma_bearing.unwrap_or(RangeBearingNoise::MRCLAM.sigma_bearing),
    };
    let given = sigma_range.is_some() || sigma_bearing.is_some();
    let chosen = mode.is_some();
    let mode = mode.unwrap_or(if given || format != InputFormat::Mrclam {
        NoiseMode::Fixed
    } else {
        NoiseMode::Auto
    });
    match mode {
        NoiseMode::Fixed => Ok((fixed, None)),
        NoiseMode::Auto => {
            ensure!(
                format == InputFormat::Mrclam,
                "--noise auto fits a range-bearing sensor: --format mrclam (the other formats carry their own covariances; `qrm pqrm calibrate` reports a fit for any)"
            );
            ensure!(
                !given,
                "--noise auto fits σ_r and σ_b; drop --sigma-range/--sigma-bearing or say --noise fixed"
            );
            let fit = match pqrm::calibrate::fit_noise(&load_dataset(format, input, fixed)?) {
                Ok(fit) => fit,
                // The default, not asked for: a recording too short to fit keeps the fixed
                // noise, with a word; `--noise auto` asked for it, so it is an error.
                Err(e) if !chosen => {
                    eprintln!(
                        "warning: {}: the noise cannot be fitted ({e}); using σ_r = {} m, σ_b = {} rad",
                        input.display(),
                        fixed.sigma_range,
                        fixed.sigma_bearing
                    );
                    return Ok((fixed, None));
                }
                Err(e) => {
                    return Err(anyhow::Error::new(e).context("fitting the noise (--noise auto)"));
                }
            };
            Ok((
                RangeBearingNoise {
                    sigma_range: fit.sigma_range,
                    sigma_bearing: fit.sigma_bearing,
                },
                Some(fit),
            ))
        }
    }
}
