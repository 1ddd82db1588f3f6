//! `qrm qlink field`: the §4.4.2 field-site experiment in simulation — `qrm study run field`
//! with the study's common options as flags (the study is `studies::qlink::field`).

use std::path::PathBuf;

use anyhow::Result;
use studies::qlink::field::{FieldExperiment, FieldParams};

/// `qrm qlink field`.
#[derive(Debug, clap::Args)]
pub struct FieldArgs {
    /// Trials per variant (default 200; quick: 12).
    #[arg(long)]
    pub trials: Option<usize>,
    /// Worlds (scenario seeds seed, seed + 1, …), each mapped and navigated on its own
    /// (default 5; quick: 1). Rates are reported per world and pooled.
    #[arg(long)]
    pub worlds: Option<usize>,
    /// Fewer trials, fewer samples and coarser checks: for tests.
    #[arg(long)]
    pub quick: bool,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `qrm qlink field`.
pub fn run(a: FieldArgs) -> Result<()> {
    // stage two: the flags become the `field` study's config, run by `qrm study`'s runner
    let mut config = if a.quick {
        FieldParams::quick(a.seed)
    } else {
        FieldParams::full(a.seed)
    };
    if let Some(n) = a.trials {
        config.trials = n;
    }
    if let Some(n) = a.worlds {
        config.worlds = n;
    }
    crate::study_cmd::run_study::<FieldExperiment>(&config, &a.out)
}
