//! `qrm sim`: run a sim2d scenario, write `run.mcap`, `observations.csv` (the mapper's input),
//! `truth.csv` (surveyed landmark positions), `world.toml` and a picture of the run.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use serde_json::json;

use crate::output::{CsvTable, Staging, write_atomic, write_picture};
use qrm_log::{McapLog, stamp};

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
    #[arg(long, value_enum, default_value_t = Detector::Ideal)]
    pub detector: Detector,
    /// Skip the lidar (detections only; much smaller logs).
    #[arg(long)]
    pub no_lidar: bool,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// How `qrm sim` detects landmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Detector {
    /// Ids known, full occlusion.
    Ideal,
    /// Extracted from the scan and recognised across frames by triangles, no ids (§4.4.2).
    Lidar,
}

/// Runs `qrm sim`.
pub fn run(a: SimArgs) -> Result<()> {
    if !sim2d::SCENARIOS.contains(&a.scenario.as_str()) {
        bail!(
            "unknown scenario `{}` ({})",
            a.scenario,
            sim2d::SCENARIOS.join(", ")
        );
    }
    let world = match &a.world {
        Some(p) => {
            let text = qsr_core::text_file::read_text(p, qsr_core::text_file::MAX_INPUT_BYTES)
                .with_context(|| format!("reading {}", p.display()))?;
            let spec: sim2d::WorldSpec = toml::from_str(&text)
                .with_context(|| format!("parsing world file {}", p.display()))?;
            Some(spec)
        }
        None => None,
    };
    let mut sc = sim2d::scenario(&a.scenario, a.seed, world)?;
    if let Some(r) = a.landmark_radius {
        sc = sc.with_landmark_radius(r)?;
    }
    let lidar_detector = match a.detector {
        Detector::Ideal => false,
        Detector::Lidar if a.no_lidar => {
            bail!("--detector lidar needs the lidar (drop --no-lidar)")
        }
        Detector::Lidar => true,
    };
    let pb = crate::progress::bar(1, &format!("simulating {}", a.scenario));
    let mut frames = sc.run(a.seed, !a.no_lidar)?;
    pb.finish_and_clear();
    // Landmark id → true position, written as truth.csv for scoring maps.
    let mut truth: std::collections::BTreeMap<u32, [f64; 2]> =
        sc.world.landmark_positions().collect();
    if lidar_detector {
        // Recognised ids are the detector's own; each is scored against the landmark it was
        // first recognised from (clutter has no truth and stays unscored).
        let first = sim2d::LidarDetector::new(0.3, 0.1).detect_frames(&mut frames);
        truth = first
            .into_iter()
            .map(|(id, i)| (id, sc.world.spec().landmarks[i].pos))
            .collect();
    }
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    write_outputs(stage.path(), &a, &sc, &frames, &truth)?;
    let detections: usize = frames.iter().map(|f| f.detections.len()).sum();
    outln!(
        "{}: {} frames, {} detections, {} landmarks, {} walls; wrote {}",
        a.scenario,
        frames.len(),
        detections,
        sc.world.spec().landmarks.len(),
        sc.world.spec().walls.len(),
        a.out.display()
    )?;
    stage.commit()?;
    Ok(())
}

/// The run's files in `dir`: observations, world, truth, the MCAP log and its picture.
fn write_outputs(
    dir: &std::path::Path,
    a: &SimArgs,
    sc: &sim2d::Scenario,
    frames: &[sim2d::Frame],
    truth: &std::collections::BTreeMap<u32, [f64; 2]>,
) -> Result<()> {
    let mut csv = Vec::new();
    sim2d::write_observations_csv(frames, &mut csv)?;
    write_atomic(&dir.join("observations.csv"), &csv)?;
    write_atomic(
        &dir.join("world.toml"),
        toml::to_string(sc.world.spec())?.as_bytes(),
    )?;
    let mut truth_csv = CsvTable::new(["landmark", "x", "y"])?;
    for (id, p) in truth {
        truth_csv.row([id.to_string(), p[0].to_string(), p[1].to_string()])?;
    }
    truth_csv.write(&dir.join("truth.csv"))?;
    write_log(&dir.join("run.mcap"), sc, frames, truth)?;
    let traj: Vec<(f64, f64)> = frames.iter().map(|f| (f.pose.x, f.pose.y)).collect();
    let rays: Vec<qrm_plot::Segment> = frames
        .iter()
        .step_by((frames.len() / 12).max(1))
        .flat_map(|f| {
            let (s, c) = f.pose.theta.sin_cos();
            f.detections.iter().map(move |d| {
                (
                    (f.pose.x, f.pose.y),
                    (
                        f.pose.x + c * d.xy[0] - s * d.xy[1],
                        f.pose.y + s * d.xy[0] + c * d.xy[1],
                    ),
                )
            })
        })
        .collect();
    write_picture(
        &dir.join("scenario"),
        &qrm_plot::scenario_map(
            &format!("{} (seed {})", a.scenario, a.seed),
            sc.world.spec(),
            &traj,
            &rays,
        )?,
    )?;
    Ok(())
}

fn write_log(
    path: &std::path::Path,
    sc: &sim2d::Scenario,
    frames: &[sim2d::Frame],
    truth: &std::collections::BTreeMap<u32, [f64; 2]>,
) -> Result<()> {
    let mut log = McapLog::robot(path, Some((0.0, sc.lidar.max_range)))?;
    // The surveyed positions of the detections' ids, so `qrm map --format mcap` scores itself.
    log.add_metadata(
        qrm_log::TRUTH_METADATA,
        truth
            .iter()
            .map(|(id, p)| (id.to_string(), format!("{},{}", p[0], p[1])))
            .collect(),
    )?;
    log.write_world(&sc.name, sc.world.spec())?;
    for f in frames {
        log.write_frame(f)?;
    }
    let t_end = frames.last().map_or(0.0, |f| f.t);
    log.write("/log", t_end, &json!({"timestamp": stamp(t_end), "level": 2, "message": format!("{} frames", frames.len()), "name": "qrm sim", "file": "", "line": 0}))?;
    Ok(log.finish()?)
}
