//! `qrm sim`: a simulated recording (`studies::simulation`) written as `run.mcap`,
//! `observations.csv` (the mapper's input), `truth.csv`, `world.toml` and a picture.

use std::path::PathBuf;

use anyhow::Result;
use studies::simulation::{Detector, Simulation, read_world};

/// Raw flags of `qrm sim`.
#[derive(Debug, clap::Args)]
pub struct SimArgs {
    /// Scenario.
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(sim2d::SCENARIOS))]
    pub scenario: String,
    /// A TOML world file replacing the scenario's generated world.
    #[arg(long)]
    pub world: Option<PathBuf>,
    /// Seed of the world generator and the sensor noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Set every point landmark's radius (m), e.g. the occlusion study's 0.1–0.7 m sizes.
    #[arg(long)]
    pub landmark_radius: Option<f64>,
    /// Landmark detector.
    #[arg(long, value_enum, default_value_t = DetectorArg::Ideal)]
    pub detector: DetectorArg,
    /// Skip the lidar (detections only; much smaller logs).
    #[arg(long)]
    pub no_lidar: bool,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// How `qrm sim` detects landmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DetectorArg {
    /// Ids known, full occlusion.
    Ideal,
    /// Extracted from the scan and recognised across frames by triangles, no ids (§4.4.2).
    Lidar,
}

/// Runs `qrm sim`.
pub fn run(a: SimArgs) -> Result<()> {
    // stage two: the flags become a checked `Simulation`
    let sim = Simulation {
        scenario: a.scenario.clone(),
        seed: a.seed,
        world: a.world.as_deref().map(read_world).transpose()?,
        landmark_radius: a.landmark_radius,
        detector: match a.detector {
            DetectorArg::Ideal => Detector::Ideal,
            DetectorArg::Lidar => Detector::Lidar,
        },
        lidar: !a.no_lidar,
    };
    sim.check()?;
    let pb = crate::progress::bar(1, &format!("simulating {}", a.scenario));
    let run = sim.run()?;
    pb.finish_and_clear();
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = crate::output::stage(&a.out)?;
    qrm_files::write_products(stage.path(), &run.products()?)?;
    outln!("{}; wrote {}", run.describe(), a.out.display())?;
    stage.commit()?;
    Ok(())
}
