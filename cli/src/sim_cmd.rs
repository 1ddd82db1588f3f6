//! `qrm sim`: run a sim2d scenario, write `run.mcap`, `observations.csv` (the mapper's input),
//! `truth.csv` (surveyed landmark positions), `world.toml` and a picture of the run.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use serde_json::json;

use crate::output::{CsvTable, Staging, write_atomic};
use qrm_log::{McapLog, stamp, yaw};

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
    let out_dir = stage.path().to_path_buf();
    let mut csv = Vec::new();
    sim2d::write_observations_csv(&frames, &mut csv)?;
    write_atomic(&out_dir.join("observations.csv"), &csv)?;
    write_atomic(
        &out_dir.join("world.toml"),
        toml::to_string(sc.world.spec())?.as_bytes(),
    )?;
    let mut truth_csv = CsvTable::new(["landmark", "x", "y"])?;
    for (id, p) in &truth {
        truth_csv.row([id.to_string(), p[0].to_string(), p[1].to_string()])?;
    }
    truth_csv.write(&out_dir.join("truth.csv"))?;
    write_log(&out_dir.join("run.mcap"), &sc, &frames, &truth)?;
    let traj: Vec<(f64, f64)> = frames.iter().map(|f| (f.pose.x, f.pose.y)).collect();
    let rays: Vec<crate::plot::Segment> = frames
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
    crate::plot::scenario_map(
        &out_dir.join("scenario"),
        &format!("{} (seed {})", a.scenario, a.seed),
        sc.world.spec(),
        &traj,
        &rays,
    )?;
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
    write_world(&mut log, sc)?;
    for f in frames {
        write_frame(&mut log, f)?;
    }
    let t_end = frames.last().map_or(0.0, |f| f.t);
    log.write("/log", t_end, &json!({"timestamp": stamp(t_end), "level": 2, "message": format!("{} frames", frames.len()), "name": "qrm sim", "file": "", "line": 0}))?;
    Ok(log.finish()?)
}

/// The world (landmarks, walls, clutter) on `/world` and a start event on `/log`, at t = 0.
pub fn write_world(log: &mut McapLog, sc: &sim2d::Scenario) -> Result<()> {
    let spec = sc.world.spec();
    let mut entities = Vec::new();
    for l in &spec.landmarks {
        entities.push(json!({
            "timestamp": stamp(0.0), "frame_id": "world", "id": format!("landmark-{}", l.id), "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [{"pose": {"position": {"x": l.pos[0], "y": l.pos[1], "z": 0.5}, "orientation": yaw(0.0)},
                           "size": {"x": 2.0 * l.radius, "y": 2.0 * l.radius, "z": 1.0}, "bottom_scale": 1.0, "top_scale": 1.0,
                           "color": {"r": 0.1, "g": 0.5, "b": 0.2, "a": 1.0}}],
            "texts": [{"pose": {"position": {"x": l.pos[0], "y": l.pos[1], "z": 1.2}, "orientation": yaw(0.0)}, "billboard": true,
                       "font_size": 12.0, "scale_invariant": true, "color": {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0}, "text": l.id.to_string()}],
            "lines": []
        }));
    }
    for w in &spec.walls {
        entities.push(json!({
            "timestamp": stamp(0.0), "frame_id": "world", "id": format!("wall-{}", w.id), "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [], "texts": [],
            "lines": [{"type": 0, "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": yaw(0.0)}, "thickness": 0.3, "scale_invariant": false,
                       "points": [{"x": w.start[0], "y": w.start[1], "z": 0.5}, {"x": w.end[0], "y": w.end[1], "z": 0.5}],
                       "color": {"r": 0.6, "g": 0.6, "b": 0.6, "a": 1.0}}]
        }));
    }
    for (i, c) in spec.clutter.iter().enumerate() {
        entities.push(json!({
            "timestamp": stamp(0.0), "frame_id": "world", "id": format!("clutter-{i}"), "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [{"pose": {"position": {"x": c.pos[0], "y": c.pos[1], "z": 0.2}, "orientation": yaw(0.0)},
                           "size": {"x": 2.0 * c.radius, "y": 2.0 * c.radius, "z": 0.4}, "bottom_scale": 1.0, "top_scale": 1.0,
                           "color": {"r": 0.5, "g": 0.4, "b": 0.3, "a": 0.7}}],
            "texts": [], "lines": []
        }));
    }
    log.write(
        "/world",
        0.0,
        &json!({"deletions": [], "entities": entities}),
    )?;
    log.write("/log", 0.0, &json!({"timestamp": stamp(0.0), "level": 2, "message": format!("scenario {} started", sc.name), "name": "qrm sim", "file": "", "line": 0}))?;
    Ok(())
}

/// One frame: the pose on `/tf`, the detections, the scan.
pub fn write_frame(log: &mut McapLog, f: &sim2d::Frame) -> Result<()> {
    {
        log.write(
            "/tf",
            f.t,
            &json!({"timestamp": stamp(f.t), "parent_frame_id": "world", "child_frame_id": "base_link",
                    "translation": {"x": f.pose.x, "y": f.pose.y, "z": 0.0}, "rotation": yaw(f.pose.theta)}),
        )?;
        let dets: Vec<_> = f.detections.iter().map(|d| json!({"id": d.id, "x": d.xy[0], "y": d.xy[1], "cov": [d.cov[0][0], d.cov[0][1], d.cov[1][1]]})).collect();
        log.write(
            "/detections",
            f.t,
            &json!({"timestamp": stamp(f.t), "t": f.t, "frame_id": "base_link", "detections": dets}),
        )?;
        // The same detections for Foxglove's 3D panel (the custom schema above shows only in
        // Raw Messages): one entity, replaced every frame, a sphere 2σ wide per landmark.
        let pose = |x: f64, y: f64, z: f64| json!({"position": {"x": x, "y": y, "z": z}, "orientation": yaw(0.0)});
        let spheres: Vec<_> = f.detections.iter().map(|d| {
            let (sx, sy) = (2.0 * d.cov[0][0].max(0.0).sqrt(), 2.0 * d.cov[1][1].max(0.0).sqrt());
            json!({"pose": pose(d.xy[0], d.xy[1], 0.5), "size": {"x": sx.max(0.2), "y": sy.max(0.2), "z": 0.2},
                   "color": {"r": 0.95, "g": 0.6, "b": 0.1, "a": 0.8}})
        }).collect();
        let texts: Vec<_> = f.detections.iter().map(|d| {
            json!({"pose": pose(d.xy[0], d.xy[1], 1.2), "billboard": true, "font_size": 14.0, "scale_invariant": true,
                   "color": {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0}, "text": d.id.to_string()})
        }).collect();
        log.write(
            "/detections/scene",
            f.t,
            &json!({"deletions": [], "entities": [{"timestamp": stamp(f.t), "frame_id": "base_link", "id": "detections",
                    "lifetime": stamp(0.0), "frame_locked": true, "cylinders": [], "lines": [], "spheres": spheres, "texts": texts}]}),
        )?;
        if let Some(scan) = &f.scan {
            // No return is `null`. JSON has no infinity, and Foxglove draws a
            // `foxglove.LaserScan` with no range limits (it takes range_min/range_max as
            // ±∞), so any number past the sensor's range — the old max range + 1 — drew a
            // ring of phantom points around the robot. Foxglove reads `null` into its
            // Float32Array as 0: a zero-length beam at the sensor, no point anywhere else.
            // qrm's reader (and REP 117) read it as no return. Ranges are rounded to f32,
            // what ROS carries and a lidar resolves, so a ROS 2 bag of the same run holds
            // the same numbers.
            let ranges: Vec<Option<f64>> = scan
                .ranges
                .iter()
                .map(|r| r.is_finite().then(|| f64::from(*r as f32)))
                .collect();
            log.write(
                "/scan",
                f.t,
                &json!({"timestamp": stamp(f.t), "frame_id": "base_link", "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": yaw(0.0)},
                        "start_angle": scan.angles.first().copied().unwrap_or(0.0), "end_angle": scan.angles.last().copied().unwrap_or(0.0),
                        "ranges": ranges, "intensities": []}),
            )?;
        }
    }
    Ok(())
}
