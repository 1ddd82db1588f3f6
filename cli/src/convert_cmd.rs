//! `qrm convert`: a recording (CSV, MRCLAM, g2o) written as MCAP that Foxglove opens and
//! `qrm map --format mcap` reads back into the same map.

use std::path::PathBuf;

use anyhow::{Result, bail};
use pqrm::loaders::read_truth_csv;

use crate::flags::InputFormat;

/// `qrm convert`.
#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// Input format (not mcap: that is the output).
    #[arg(long, value_enum)]
    pub from: InputFormat,
    /// Input file (csv, g2o) or directory (mrclam).
    #[arg(long)]
    pub input: PathBuf,
    /// Ground truth `landmark,x,y` CSV (MRCLAM brings its own); written into the log.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Range-bearing noise (MRCLAM), resolved as `qrm map` does, so the log maps as the
    /// recording does.
    #[command(flatten)]
    pub noise: crate::flags::NoiseArgs,
    /// Drop gross outliers frame by frame before writing, as `qrm map` does (default: where the
    /// noise is fitted from the recording; `--gate false` keeps every detection).
    #[arg(long, num_args = 0..=1, default_missing_value = "true", action = clap::ArgAction::Set)]
    pub gate: Option<bool>,
    /// The MCAP file to write.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `qrm convert`.
pub fn run(a: ConvertArgs) -> Result<()> {
    if a.from == InputFormat::Mcap {
        bail!("--from mcap: the input is MCAP already");
    }
    let warn = |w: String| eprintln!("warning: {w}");
    let noise = a.noise.request().resolve(a.from.into(), &a.input, &warn)?;
    let mut data = studies::recording::read(a.from.into(), &a.input, noise.noise)?;
    if let Some(t) = &a.truth {
        data.truth = Some(read_truth_csv(t)?);
    }
    let gated = studies::mapping::gate(&mut data, a.gate, noise.fit.as_ref())?;
    // Written beside the target and renamed when finished: a failure or Ctrl-C never leaves a
    // half-written file under the final name.
    let file = crate::output::stage_file(&a.out)?;
    qrm_log::write_dataset(file.path(), &data, &a.input.display().to_string())?;
    file.commit()?;
    let robots: std::collections::BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
    outln!(
        "{}: {} scans of {} robot(s){}{}; wrote {}",
        a.input.display(),
        data.scans.len(),
        robots.len(),
        if data.truth.is_some() {
            " with surveyed landmarks"
        } else {
            ""
        },
        gated.map_or(String::new(), |g| format!(
            " ({} of {} detections gated as gross outliers)",
            g.detections, g.of
        )),
        a.out.display()
    )?;
    Ok(())
}
