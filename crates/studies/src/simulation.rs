//! A simulated recording (`qrm sim`): a `sim2d` scenario run with its detector, and the files a
//! user maps and scores — the observations, the world, the surveyed truth, an MCAP log for
//! Foxglove and a picture of the run.
//!
//! ```no_run
//! use studies::simulation::{Detector, Simulation};
//! let sim = Simulation::new("hallway", 4).detector(Detector::Lidar);
//! let run = sim.run()?;
//! println!("{}", run.describe());
//! let files = run.products()?; // observations.csv, truth.csv, world.toml, run.mcap, scenario
//! # Ok::<(), studies::StudyError>(())
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use qrm_log::{McapLog, stamp};
use serde_json::json;
use sim2d::{Frame, LidarDetector, Scenario, WorldSpec};

use crate::error::{Result, StudyError};
use crate::report::{Attachment, Cell, Column, Figure, Plot, Products, Table};

/// Recognition tolerance (m) and position noise (m) of the lidar detector: the field trial's.
const LIDAR_DETECTOR: (f64, f64) = (0.3, 0.1);

/// How landmarks are detected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Detector {
    /// Ids known, full occlusion.
    #[default]
    Ideal,
    /// Extracted from the scan and recognised across frames by triangles, no ids (§4.4.2).
    Lidar,
}

/// What to simulate.
#[derive(Debug, Clone, PartialEq)]
#[must_use]
pub struct Simulation {
    /// The scenario (one of [`sim2d::SCENARIOS`]).
    pub scenario: String,
    /// Seed of the world generator and the sensor noise.
    pub seed: u64,
    /// A world replacing the scenario's generated one.
    pub world: Option<WorldSpec>,
    /// Every point landmark's radius (m), when set.
    pub landmark_radius: Option<f64>,
    /// The landmark detector.
    pub detector: Detector,
    /// Record the lidar (needed by [`Detector::Lidar`]; without it the log is much smaller).
    pub lidar: bool,
}

impl Simulation {
    /// `scenario` from `seed`, its own world, the ideal detector, with the lidar.
    pub fn new(scenario: &str, seed: u64) -> Self {
        Self {
            scenario: scenario.to_owned(),
            seed,
            world: None,
            landmark_radius: None,
            detector: Detector::Ideal,
            lidar: true,
        }
    }

    /// With this detector.
    pub fn detector(mut self, detector: Detector) -> Self {
        self.detector = detector;
        self
    }

    /// Checks the request before any work.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] for an unknown scenario or the lidar detector without
    /// the lidar.
    pub fn check(&self) -> Result<()> {
        if !sim2d::SCENARIOS.contains(&self.scenario.as_str()) {
            return Err(StudyError::InvalidParameter(format!(
                "unknown scenario `{}` ({})",
                self.scenario,
                sim2d::SCENARIOS.join(", ")
            )));
        }
        if self.detector == Detector::Lidar && !self.lidar {
            return Err(StudyError::InvalidParameter(
                "the lidar detector needs the lidar (drop --no-lidar)".to_owned(),
            ));
        }
        Ok(())
    }

    /// Runs the scenario and, with the lidar detector, replaces its detections by the
    /// recognised ones.
    ///
    /// # Errors
    /// As [`Simulation::check`]; [`StudyError::Sim`] for a world that cannot be built.
    pub fn run(&self) -> Result<Simulated> {
        self.check()?;
        let mut scenario = sim2d::scenario(&self.scenario, self.seed, self.world.clone())?;
        if let Some(r) = self.landmark_radius {
            scenario = scenario.with_landmark_radius(r)?;
        }
        let mut frames = scenario.run(self.seed, self.lidar)?;
        let truth = match self.detector {
            Detector::Ideal => scenario.world.landmark_positions().collect(),
            // Recognised ids are the detector's own; each is scored against the landmark it was
            // first recognised from (clutter has no truth and stays unscored). A landmark the
            // recogniser later took for a new one is scored under its first id only: two ids
            // at one surveyed position have no state to score.
            Detector::Lidar => {
                let (tolerance, sigma) = LIDAR_DETECTOR;
                // Frames of one drive: recognised by triangles and tracked from frame to frame,
                // as a bag's scans are mapped (`qrm map --format mcap`).
                let first = LidarDetector {
                    recognizer: sim2d::TriangleRecognizer::new(tolerance).tracking(),
                    ..LidarDetector::new(tolerance, sigma)
                }
                .detect_frames(&mut frames);
                let spec = scenario.world.spec();
                let mut scored = std::collections::BTreeSet::new();
                first
                    .into_iter()
                    .filter(|&(_, i)| scored.insert(i))
                    .map(|(id, i)| (id, spec.landmarks[i].pos))
                    .collect()
            }
        };
        Ok(Simulated {
            seed: self.seed,
            scenario,
            frames,
            truth,
        })
    }
}

/// Reads a TOML world file for [`Simulation::world`].
///
/// # Errors
/// [`StudyError::Sim`] (`world file: PATH: …`) naming the TOML error or why it cannot be read.
pub fn read_world(path: &Path) -> Result<WorldSpec> {
    let world = |e: String| sim2d::SimError::World(format!("{}: {e}", path.display()));
    let text = qsr_core::text_file::read_text(path, qsr_core::text_file::MAX_INPUT_BYTES)
        .map_err(|e| world(e.to_string()))?;
    Ok(WorldSpec::from_toml(&text).map_err(|e| match e {
        sim2d::SimError::World(why) => world(why),
        other => other,
    })?)
}

/// A simulated run.
#[derive(Debug)]
pub struct Simulated {
    /// The seed it ran with.
    pub seed: u64,
    /// The scenario, its world and sensors.
    pub scenario: Scenario,
    /// Every frame, with the detector's detections.
    pub frames: Vec<Frame>,
    /// Landmark id → true position, for scoring maps (the detector's ids with the lidar one).
    pub truth: BTreeMap<u32, [f64; 2]>,
}

impl Simulated {
    /// One line: frames, detections, landmarks and walls.
    #[must_use]
    pub fn describe(&self) -> String {
        let detections: usize = self.frames.iter().map(|f| f.detections.len()).sum();
        let spec = self.scenario.world.spec();
        format!(
            "{}: {} frames, {detections} detections, {} landmarks, {} walls",
            self.scenario.name,
            self.frames.len(),
            spec.landmarks.len(),
            spec.walls.len()
        )
    }

    /// The run's files: `observations.csv` (the mapper's input), `world.toml`, `truth.csv`,
    /// `run.mcap` and the picture `scenario`.
    ///
    /// # Errors
    /// [`StudyError::Log`] or [`StudyError::InvalidParameter`] when a file cannot be formed.
    pub fn products(&self) -> Result<Products> {
        let mut observations = Vec::new();
        // Writing into memory does not fail; the error stays typed all the same.
        sim2d::write_observations_csv(&self.frames, &mut observations).map_err(|e| {
            StudyError::InvalidParameter(format!("the observations cannot be written: {e}"))
        })?;
        let world = toml::to_string(self.scenario.world.spec()).map_err(|e| {
            StudyError::InvalidParameter(format!("the world cannot be written as TOML: {e}"))
        })?;
        let mut truth = Table::new(
            "truth",
            "Surveyed landmarks",
            vec![
                Column::new("landmark", "landmark"),
                Column::new("x", "x (m)"),
                Column::new("y", "y (m)"),
            ],
        );
        for (id, p) in &self.truth {
            truth.push(vec![
                Cell::int(*id),
                Cell::number(p[0], 3),
                Cell::number(p[1], 3),
            ]);
        }
        Ok(Products {
            tables: vec![truth],
            figures: vec![self.picture()],
            attachments: vec![
                Attachment::binary("observations.csv", observations),
                Attachment::text("world.toml", world),
                Attachment::binary("run.mcap", self.log()?),
            ],
        })
    }

    /// The world from above with the path and, at a dozen moments, rays to what was detected.
    fn picture(&self) -> Figure {
        let trajectory = self.frames.iter().map(|f| (f.pose.x, f.pose.y)).collect();
        let rays = self
            .frames
            .iter()
            .step_by((self.frames.len() / 12).max(1))
            .flat_map(|f| {
                let (s, c) = f.pose.theta.sin_cos();
                f.detections.iter().map(move |d| {
                    let to = (
                        f.pose.x + c * d.xy[0] - s * d.xy[1],
                        f.pose.y + s * d.xy[0] + c * d.xy[1],
                    );
                    ((f.pose.x, f.pose.y), to)
                })
            })
            .collect();
        Figure {
            name: "scenario".to_owned(),
            title: format!("{} (seed {})", self.scenario.name, self.seed),
            x_label: "x (m)".to_owned(),
            y_label: "y (m)".to_owned(),
            plot: Plot::Scenario {
                world: self.scenario.world.spec().clone(),
                trajectory,
                rays,
            },
        }
    }

    /// The MCAP log: the world, every frame, and the truth as metadata so that
    /// `qrm map --format mcap` scores itself.
    fn log(&self) -> Result<Vec<u8>> {
        let sc = &self.scenario;
        let mut log =
            McapLog::in_memory("run.mcap")?.with_robot_channels(Some((0.0, sc.lidar.max_range)))?;
        log.add_metadata(
            qrm_log::TRUTH_METADATA,
            self.truth
                .iter()
                .map(|(id, p)| (id.to_string(), format!("{},{}", p[0], p[1])))
                .collect(),
        )?;
        log.write_world(&sc.name, sc.world.spec())?;
        for f in &self.frames {
            log.write_frame(f)?;
        }
        let t_end = self.frames.last().map_or(0.0, |f| f.t);
        let message = format!("{} frames", self.frames.len());
        log.write(
            "/log",
            t_end,
            &json!({"timestamp": stamp(t_end), "level": 2, "message": message, "name": "qrm sim", "file": "", "line": 0}),
        )?;
        Ok(log.into_bytes()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lidar_detector_without_the_lidar_is_refused_before_any_work() {
        let mut sim = Simulation::new("hallway", 0).detector(Detector::Lidar);
        sim.lidar = false;
        assert!(matches!(sim.run(), Err(StudyError::InvalidParameter(m)) if m.contains("lidar")));
        let unknown = Simulation::new("moon", 0).check();
        assert!(matches!(unknown, Err(StudyError::InvalidParameter(m)) if m.contains("moon")));
    }

    #[test]
    fn truth_and_observations_name_the_same_landmarks() {
        let mut sim = Simulation::new("pqrm-100", 3);
        sim.lidar = false;
        let run = sim.run().unwrap();
        let products = run.products().unwrap();
        let names: Vec<&str> = products
            .attachments
            .iter()
            .map(|a| a.name.as_str())
            .collect();
        assert_eq!(names, ["observations.csv", "world.toml", "run.mcap"]);
        let csv = String::from_utf8(products.attachments[0].bytes().to_vec()).unwrap();
        let seen: std::collections::BTreeSet<u32> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
            .collect();
        assert!(!seen.is_empty());
        assert!(seen.iter().all(|id| run.truth.contains_key(id)));
        assert_eq!(products.tables[0].rows.len(), run.truth.len());
    }
}
