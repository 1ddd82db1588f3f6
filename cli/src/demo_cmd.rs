//! `qrm demo`: the whole pipeline in one run (the `demo` study: lidar mapping, PQRM, a calculus
//! learned by SERGE, Q-Link across the field site, an MCAP log for Foxglove). An alias of
//! `qrm study run demo` that shows the run's three-line story instead of its tables.

use std::path::PathBuf;

use anyhow::Result;
use studies::demo::{Demo, DemoConfig};

use crate::study_cmd::Shown;

/// `qrm demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Seed of the world, the sensors and the sampler (default: the demo study's, as `qrm
    /// study run demo` and `qrm.studies.run("demo")`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Goal landmark (default: the one whose plan is the longest that succeeds; see
    /// `run_rule` in summary.json).
    #[arg(long)]
    pub goal: Option<u32>,
    /// Sensor range R' of the navigating robot (m); the mapping robot's lidar reaches
    /// R = 30 m, and arcs and search circles run at R as in the thesis.
    #[arg(long, default_value_t = 30.0)]
    pub nav_range: f64,
    /// Idealised navigating robot: true detections and exact driving (default: one that
    /// errs — the site's detection noise N(0, 0.7 m), missed detections, wheel slip).
    #[arg(long)]
    pub exact_robot: bool,
    /// Output directory.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
}

/// Runs the demo.
pub fn run(a: DemoArgs) -> Result<()> {
    let config = DemoConfig {
        seed: a.seed.unwrap_or(<Demo as studies::Study>::DEFAULT_SEED),
        goal: a.goal,
        nav_range: a.nav_range,
        exact_robot: a.exact_robot,
        ..DemoConfig::new(a.seed.unwrap_or(<Demo as studies::Study>::DEFAULT_SEED))
    };
    crate::study_cmd::run_study_shown::<Demo>(&config, &a.out, Shown::Story)
}
