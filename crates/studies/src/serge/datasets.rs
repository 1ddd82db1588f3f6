//! The three datasets of the thesis's SERGE study (§3.4.1), generated from a seed.
//!
//! - **well-separated**: 49 landmarks on a jittered 7 × 7 lattice 10 m apart, each measured
//!   40 times with anisotropic noise of 0.2–0.5 m standard deviation: beliefs never overlap
//!   (Fig 3.4), so every map has saliency 1.
//! - **hallway**: the sim2d `hallway` scenario (two walls of point landmarks, a robot driving
//!   down the middle, measurement variance 0.1 m²). 22 landmark triplets seen together in at
//!   least 10 frames are drawn at random; each observation gives one data point, F in the
//!   normalised frame of (D, E); a belief is 10,000 samples drawn around its observations
//!   with the same 0.1 m² variance and normalised (Fig 3.5).
//! - **lab**: we do not have the thesis's Kinect recording, so we generate a comparable one:
//!   a 10 m × 8 m room with the sensor in the middle, 55 objects on four tables and along the
//!   walls (centroids at least 0.15 m apart: objects on a table may touch), each tracked for
//!   30 frames. Each frame's bounding-box centroid has the Kinect's depth noise along the
//!   viewing ray, σ_z = 1.425·10⁻³ z² m (Khoshelham & Elberink, *Sensors* 2012), combined
//!   with segmentation jitter of 5 cm + 1 % of the range (box edges flicker by a few pixels
//!   from frame to frame), and a lateral noise of the jitter plus 1.5·10⁻³ z: anisotropic and
//!   growing with range, as in Fig 3.6. Neighbouring objects' beliefs overlap, as the
//!   thesis's did (its μ = 55 map has log saliency −28.1).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use serge::learn::{TripletObservation, normalise, triplet_beliefs};
use serge::selection::{Sighting, TripletSelection};
use serge::{Belief, BeliefSet};

use crate::error::{Result, StudyError};

/// Dataset names accepted by [`Dataset::generate`].
pub const DATASETS: [&str; 3] = ["well-separated", "hallway", "lab"];

/// One of the study's datasets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DatasetName {
    /// 49 landmarks on a lattice, beliefs that never overlap.
    WellSeparated,
    /// Landmark triplets of the simulated hallway, in the normalised frame.
    Hallway,
    /// 55 objects of a simulated Kinect recording of a lab.
    Lab,
}

impl DatasetName {
    /// Every dataset, in the study's order.
    pub const ALL: [Self; 3] = [Self::WellSeparated, Self::Hallway, Self::Lab];

    /// Its name in files and on the command line.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Self::WellSeparated => "well-separated",
            Self::Hallway => "hallway",
            Self::Lab => "lab",
        }
    }

    /// The dataset called `name`.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] listing the names there are.
    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|d| d.as_str() == name)
            .ok_or_else(|| {
                StudyError::InvalidParameter(format!(
                    "unknown dataset `{name}` (known: {})",
                    DATASETS.join(", ")
                ))
            })
    }
}

/// A dataset: data points grouped by belief, and how beliefs are made from them.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// Its name.
    pub name: String,
    /// Data points `Z_k` of each belief, in the frame the map is built in.
    pub points: Vec<Vec<[f64; 2]>>,
    /// For triplet data: the observation behind each point (same indices as `points`).
    pub observations: Option<Vec<Vec<TripletObservation>>>,
    /// Samples per triplet belief.
    pub samples_per_belief: usize,
    /// True landmark positions (world datasets), for plots.
    pub truth: Vec<[f64; 2]>,
}

impl Dataset {
    /// Generates a named dataset.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] for an unknown name; simulation errors (hallway).
    pub fn generate(name: &str, seed: u64) -> Result<Self> {
        Self::generate_named(DatasetName::parse(name)?, seed)
    }

    /// Generates dataset `name`.
    ///
    /// # Errors
    /// Simulation errors (hallway).
    pub fn generate_named(name: DatasetName, seed: u64) -> Result<Self> {
        match name {
            DatasetName::WellSeparated => Ok(well_separated(seed)),
            DatasetName::Hallway => hallway(seed, 10_000),
            DatasetName::Lab => Ok(lab(seed)),
        }
    }

    /// Number of beliefs K.
    #[must_use]
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there are no beliefs.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Beliefs from the points selected by `keep(k, i)` (e.g. the training folds): a fitted
    /// Gaussian, or samples around the selected triplet observations.
    ///
    /// # Errors
    /// [`serge::SergeError::Empty`] (as [`StudyError::Serge`]) when a belief has no selected point.
    pub fn beliefs(&self, keep: impl Fn(usize, usize) -> bool, seed: u64) -> Result<BeliefSet> {
        match &self.observations {
            None => Ok(BeliefSet::new(
                self.points
                    .iter()
                    .enumerate()
                    .map(|(k, pts)| {
                        let sel: Vec<[f64; 2]> = pts
                            .iter()
                            .enumerate()
                            .filter(|&(i, _)| keep(k, i))
                            .map(|(_, p)| *p)
                            .collect();
                        Belief::fit_gaussian(&sel, 1e-6)
                    })
                    .collect::<serge::Result<_>>()?,
            )?),
            Some(obs) => {
                let mut sel: Vec<TripletObservation> = Vec::new();
                for (k, list) in obs.iter().enumerate() {
                    sel.extend(
                        list.iter()
                            .enumerate()
                            .filter(|&(i, _)| keep(k, i))
                            .map(|(_, o)| *o),
                    );
                }
                Ok(triplet_beliefs(
                    &sel,
                    obs.len(),
                    self.samples_per_belief,
                    seed,
                )?)
            }
        }
    }

    /// The same dataset with `samples` per triplet belief (quick runs use fewer).
    #[must_use]
    pub fn with_samples(mut self, samples: usize) -> Self {
        self.samples_per_belief = samples.max(1);
        self
    }
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

fn well_separated(seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x3e11);
    let mut truth = Vec::new();
    let mut points = Vec::new();
    for i in 0..7 {
        for j in 0..7 {
            let c = [
                10.0 * f64::from(i) + rng.random_range(-1.5..1.5),
                10.0 * f64::from(j) + rng.random_range(-1.5..1.5),
            ];
            let (sx, sy) = (rng.random_range(0.2..0.5), rng.random_range(0.2..0.5));
            let rho: f64 = rng.random_range(-0.6..0.6);
            let pts = (0..40)
                .map(|_| {
                    let (a, b) = (gauss(&mut rng), gauss(&mut rng));
                    [
                        c[0] + sx * a,
                        c[1] + sy * (rho * a + (1.0 - rho * rho).sqrt() * b),
                    ]
                })
                .collect();
            truth.push(c);
            points.push(pts);
        }
    }
    Dataset {
        name: "well-separated".into(),
        points,
        observations: None,
        samples_per_belief: 0,
        truth,
    }
}

fn lab(seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x1ab);
    // tables: centre, half-size
    let tables = [
        ([-2.5, 1.5], [0.6, 0.4]),
        ([2.5, 1.5], [0.6, 0.4]),
        ([-2.5, -1.8], [0.6, 0.4]),
        ([2.0, -1.8], [0.8, 0.4]),
    ];
    let mut truth: Vec<[f64; 2]> = Vec::new();
    while truth.len() < 55 {
        let p = if rng.random_range(0.0..1.0) < 0.6 {
            let (c, h) = tables[rng.random_range(0..tables.len())];
            [
                c[0] + rng.random_range(-h[0]..h[0]),
                c[1] + rng.random_range(-h[1]..h[1]),
            ]
        } else {
            // benches along the walls, 0.3 m deep
            let along = rng.random_range(0.0..1.0);
            match rng.random_range(0..4) {
                0 => [-4.5 + 9.0 * along, 3.5 + rng.random_range(0.0..0.3)],
                1 => [-4.5 + 9.0 * along, -3.8 + rng.random_range(0.0..0.3)],
                2 => [4.5 + rng.random_range(0.0..0.3), -3.5 + 7.0 * along],
                _ => [-4.8 + rng.random_range(0.0..0.3), -3.5 + 7.0 * along],
            }
        };
        let near = f64::hypot(p[0], p[1]) < 1.0;
        if !near
            && truth
                .iter()
                .all(|q| (q[0] - p[0]).hypot(q[1] - p[1]) >= 0.15)
        {
            truth.push(p);
        }
    }
    let points = truth
        .iter()
        .map(|c| {
            let z = c[0].hypot(c[1]);
            let (ux, uy) = (c[0] / z, c[1] / z);
            // box-edge flicker of a few pixels moves the centroid by ~5 cm, more far away
            let jitter = 0.05 + 0.01 * z;
            let s_depth = (1.425e-3 * z * z).hypot(jitter);
            let s_lat = jitter + 1.5e-3 * z;
            (0..30)
                .map(|_| {
                    let (a, b) = (s_depth * gauss(&mut rng), s_lat * gauss(&mut rng));
                    [c[0] + a * ux - b * uy, c[1] + a * uy + b * ux]
                })
                .collect()
        })
        .collect();
    Dataset {
        name: "lab".into(),
        points,
        observations: None,
        samples_per_belief: 0,
        truth,
    }
}

/// Frames the hallway's landmark sets must be seen together in.
const HALLWAY_MIN_FRAMES: usize = 10;

/// Triplets of the hallway dataset (§3.4: 22).
const HALLWAY_TRIPLETS: usize = 22;

fn hallway(seed: u64, samples: usize) -> Result<Dataset> {
    let sim_err =
        |e: sim2d::SimError| StudyError::InvalidParameter(format!("hallway simulation: {e}"));
    let scenario = sim2d::scenario("hallway", seed, None).map_err(sim_err)?;
    let frames = scenario.run(seed, false).map_err(sim_err)?;
    // 22 landmark sets seen together in ≥ 10 frames, each in a random ordering
    let frames: Vec<Vec<Sighting>> = frames
        .iter()
        .map(|f| {
            f.detections
                .iter()
                .map(|d| Sighting {
                    id: d.id,
                    xy: d.xy,
                    cov: d.cov,
                })
                .collect()
        })
        .collect();
    let selection = TripletSelection {
        min_frames: HALLWAY_MIN_FRAMES,
        max_triplets: HALLWAY_TRIPLETS,
        seed: seed ^ 0x4a11,
    };
    let selected = selection
        .select(&frames)
        .map_err(|e| StudyError::InvalidParameter(format!("hallway: {e}")))?;
    if selected.triplets.len() < HALLWAY_TRIPLETS {
        return Err(StudyError::InvalidParameter(format!(
            "the hallway run saw only {} triplets in ≥ {HALLWAY_MIN_FRAMES} frames",
            selected.candidates
        )));
    }
    let chosen = &selected.triplets;
    let mut observations: Vec<Vec<TripletObservation>> = vec![Vec::new(); chosen.len()];
    let mut points: Vec<Vec<[f64; 2]>> = vec![Vec::new(); chosen.len()];
    for o in selected.observations {
        if let Some(p) = normalise(o.points[0], o.points[1], o.points[2]) {
            points[o.triplet].push(p);
            observations[o.triplet].push(o);
        }
    }
    let truth = scenario
        .world
        .spec()
        .landmarks
        .iter()
        .map(|l| l.pos)
        .collect();
    Ok(Dataset {
        name: "hallway".into(),
        points,
        observations: Some(observations),
        samples_per_belief: samples,
        truth,
    })
}
