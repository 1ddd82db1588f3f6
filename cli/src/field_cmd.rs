//! `qrm qlink field`: the §4.4.2 field-site experiment in simulation — `qrm study run field`
//! with the study's common options as flags (the study is `studies::qlink::field`).

use crate::flags::StudyFlags;
use anyhow::Result;
use studies::qlink::field::FieldExperiment;

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
    /// Idealised: the navigating robot drives its waypoints exactly (default: with wheel
    /// slip; its detections are the lidar pipeline's either way).
    #[arg(long)]
    pub exact_robot: bool,
    /// --quick, --seed, --out.
    #[command(flatten)]
    pub run: StudyFlags,
}

/// Runs `qrm qlink field`.
pub fn run(a: FieldArgs) -> Result<()> {
    // stage two: the flags become the `field` study's config, run by `qrm study`'s runner
    let mut config = a.run.config::<FieldExperiment>();
    if let Some(n) = a.trials {
        config.trials = n;
    }
    if let Some(n) = a.worlds {
        config.worlds = n;
    }
    config.exact_robot |= a.exact_robot;
    crate::study_cmd::run_study::<FieldExperiment>(&config, &a.run.out)
}
