//! A recording's noise fitted from the recording itself (`qrm pqrm calibrate`): the fit, how to
//! use it, and the normalised residuals a user looks at to judge it.

use std::path::{Path, PathBuf};

use pqrm::calibrate::NoiseFit;
use pqrm::loaders::RangeBearingNoise;
use serde_json::json;

use crate::error::Result;
use crate::recording::{RecordingFormat, read};
use crate::report::{Attachment, Figure, Plot, Products};

/// A residual further than this many fitted σ is drawn at the edge.
const CLAMP: f64 = 8.0;
/// How the fit works, in the summary.
const METHOD: &str = "spread of the distance between landmarks seen in one frame about its median over frames; IRLS on |z| <= 3; outlier rate = share beyond 3 sigma minus 0.27 %";

/// The noise fitted to a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The recording.
    pub input: PathBuf,
    /// Its form.
    pub format: RecordingFormat,
    /// The fit.
    pub fit: NoiseFit,
    /// Each residual over its fitted σ, clamped to ±8 (N(0, 1) if the model is right).
    pub normalised: Vec<f64>,
}

impl Calibration {
    /// Reads the recording and fits its noise ([`pqrm::calibrate::fit_noise`]).
    ///
    /// # Errors
    /// The reader's errors naming the file, line and field; [`crate::StudyError::Pqrm`] naming
    /// the file when too few landmark pairs are seen together to fit.
    pub fn of_recording(format: RecordingFormat, input: &Path) -> Result<Self> {
        let data = read(format, input, RangeBearingNoise::MRCLAM)?;
        let fit = pqrm::calibrate::fit_noise(&data).map_err(|e| match e {
            pqrm::PqrmError::Mismatch(m) => {
                pqrm::PqrmError::Mismatch(format!("fitting the noise of {}: {m}", input.display()))
            }
            other => other,
        })?;
        let normalised = pqrm::calibrate::residuals(&data, &fit)
            .iter()
            .filter(|r| r.sigma > 0.0)
            .map(|r| (r.residual / r.sigma).clamp(-CLAMP, CLAMP))
            .collect();
        Ok(Self {
            input: input.to_path_buf(),
            format,
            fit,
            normalised,
        })
    }

    /// The share of normalised residuals beyond ±3.
    #[must_use]
    pub fn beyond_three_sigma(&self) -> f64 {
        let n = self.normalised.iter().filter(|v| v.abs() > 3.0).count();
        n as f64 / self.normalised.len().max(1) as f64
    }

    /// The fit, how it was made and the `qrm map` flags that use it.
    #[must_use]
    pub fn summary(&self) -> serde_json::Value {
        let (fit, input) = (&self.fit, self.input.display());
        json!({
            "input": input.to_string(),
            "format": self.format.as_str(),
            "fit": fit,
            "method": METHOD,
            // Only a range-bearing format takes the fitted σs; the others carry their own
            // covariances, which this fit is a check of.
            "use": if self.format == RecordingFormat::Mrclam {
                format!("qrm map --format mrclam --input {input} --noise auto  (or --sigma-range {:.4} --sigma-bearing {:.5}; heavy tails: --sensor outliers:{:.3},{:.0})",
                    fit.sigma_range, fit.sigma_bearing, fit.outlier_rate, fit.max_range.ceil())
            } else {
                format!("{} files carry their own covariances: compare them with this fit; for heavy tails: qrm map --sensor outliers:{:.3},{:.0}",
                    self.format.as_str(), fit.outlier_rate, fit.max_range.ceil())
            },
        })
    }

    /// `calibration.json` (the summary, indented) and the histogram `residuals`.
    #[must_use]
    pub fn products(&self) -> Products {
        let summary = format!("{:#}", self.summary());
        let edges = (0..=32).map(|i| -CLAMP + 0.5 * f64::from(i)).collect();
        let residuals = Figure {
            name: "residuals".to_owned(),
            title: format!(
                "residual / fitted σ (N(0,1) if the model is right; {:.1} % beyond ±3)",
                100.0 * self.beyond_three_sigma()
            ),
            x_label: "normalised residual of a pairwise distance (clamped to ±8)".to_owned(),
            y_label: "residuals".to_owned(),
            plot: Plot::Histogram {
                edges,
                groups: vec![("residuals".to_owned(), self.normalised.clone())],
            },
        };
        Products {
            tables: Vec::new(),
            figures: vec![residuals],
            attachments: vec![Attachment::text("calibration.json", summary)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording whose distances are exact but for one frame that is far off.
    fn recording(dir: &Path) -> PathBuf {
        let path = dir.join("obs.csv");
        let mut csv = String::from("t,robot,landmark,x,y,cxx,cxy,cyy\n");
        for t in 0..40 {
            let wobble = if t == 7 { 3.0 } else { 0.01 * f64::from(t % 5) };
            for (id, x, y) in [(1, 2.0 + wobble, 0.0), (2, 0.0, 3.0), (3, -2.0, 1.0)] {
                csv.push_str(&format!("{t},0,{id},{x},{y},0.01,0,0.01\n"));
            }
        }
        std::fs::write(&path, csv).unwrap();
        path
    }

    #[test]
    fn the_outlying_frame_lands_beyond_three_sigma_and_only_it() {
        let dir = std::env::temp_dir().join(format!("qrm-calibration-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let c = Calibration::of_recording(RecordingFormat::Csv, &recording(&dir)).unwrap();
        let beyond = c.normalised.iter().filter(|v| v.abs() > 3.0).count();
        // the far frame moves two of the three distances
        assert!((1..=2).contains(&beyond), "{beyond} beyond 3σ");
        assert!(c.beyond_three_sigma() > 0.0 && c.beyond_three_sigma() < 0.1);
        let summary = c.summary();
        assert_eq!(summary["format"], "csv");
        assert!(
            summary["use"]
                .as_str()
                .unwrap()
                .starts_with("csv files carry")
        );
        let products = c.products();
        assert_eq!(products.attachments[0].name, "calibration.json");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
