//! The simulation studies of thesis §4.4.1 (Table 4.1, Figs 4.6–4.7).
//!
//! Set-up (DESIGN §7): the sim2d `qlink-200` world (200 landmarks in 200 m × 200 m) mapped by
//! a robot with range R = 20 m and detection noise N(0, 0.3) into a PQRM with the `quadrant`
//! calculus; a Link Graph with β = 1 and unit costs; the arc controller; a horizon-4 search
//! POMDP. Every ordered (start, goal) landmark pair is navigated (39,800 of them) for sensor
//! ranges R'/R ∈ {1, 0.9, 0.8, 0.7, 0.6} without occlusion, and for landmark sizes
//! {0.1, 0.3, 0.5, 0.7} m with full occlusion at R' = R. A navigation fails when a transition
//! fails (no re-planning, as in the thesis); pairs without a path in the link graph are
//! counted apart. The sensor-range trial maps point landmarks without occlusion (one map for
//! its five settings); each occlusion setting maps its own world of discs, with occlusion
//! (the whole experiment happens in that environment).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::controller::{Controller, ControllerKind};
use crate::error::{QlinkError, Result};
use crate::graph::{DistanceField, LinkGraph};
use crate::map::QualitativeMap;
use crate::navigate::{
    Failure, NavConfig, NavOutcome, Navigator, Perception, RangePerception, WorldPerception,
};
use crate::pomdp::SearchPomdp;

/// The mapping robot's range R (m).
pub const MAP_RANGE: f64 = 20.0;

/// What the study runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyConfig {
    /// `sensor-range`, `occlusion` or `all`.
    pub trial: String,
    /// Ordered pairs per setting (`None`: all 39,800).
    pub pairs: Option<usize>,
    /// R'/R of the sensor-range trial.
    pub range_factors: Vec<f64>,
    /// Landmark sizes (radius, m) of the occlusion trial.
    pub sizes: Vec<f64>,
    /// Samples per landmark per frame of the PQRM.
    pub samples: usize,
    /// Perception check spacing along paths (m).
    pub step: f64,
    /// Seed (world, mapping noise, pair selection).
    pub seed: u64,
}

impl StudyConfig {
    /// The thesis's study: every pair, 9 settings.
    #[must_use]
    pub fn full(seed: u64) -> Self {
        Self {
            trial: "all".into(),
            pairs: None,
            range_factors: vec![1.0, 0.9, 0.8, 0.7, 0.6],
            sizes: vec![0.1, 0.3, 0.5, 0.7],
            samples: 200,
            step: 1.0,
            seed,
        }
    }

    /// A quick version: 400 random pairs per setting.
    #[must_use]
    pub fn quick(seed: u64) -> Self {
        Self {
            pairs: Some(400),
            samples: 100,
            ..Self::full(seed)
        }
    }

    /// The settings to run: `(trial, value)`.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for an unknown trial name, zero pairs (an empty table
    /// is not a result), no settings, or a non-positive/non-finite setting, sample count or
    /// step.
    pub fn settings(&self) -> Result<Vec<(String, f64)>> {
        let bad = |m: String| Err(QlinkError::InvalidParameter(m));
        if self.pairs == Some(0) {
            return bad("pairs must be >= 1 (or all)".into());
        }
        if self.samples == 0 || self.samples > 1_000_000 {
            return bad(format!(
                "samples must be in 1..=1000000, got {}",
                self.samples
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return bad(format!("step must be finite and > 0, got {}", self.step));
        }
        if let Some(v) = self
            .range_factors
            .iter()
            .chain(&self.sizes)
            .find(|v| !(v.is_finite() && **v > 0.0))
        {
            return bad(format!(
                "range factors and sizes must be finite and > 0, got {v}"
            ));
        }
        let range = self
            .range_factors
            .iter()
            .map(|&v| ("sensor-range".to_owned(), v));
        let occ = self.sizes.iter().map(|&v| ("occlusion".to_owned(), v));
        match self.trial.as_str() {
            "sensor-range" => Ok(range.collect()),
            "occlusion" => Ok(occ.collect()),
            "all" => Ok(range.chain(occ).collect()),
            t => Err(QlinkError::InvalidParameter(format!(
                "unknown trial `{t}` (sensor-range, occlusion, all)"
            ))),
        }
        .and_then(|v: Vec<(String, f64)>| {
            if v.is_empty() {
                bad(format!("trial `{}` has no settings to run", self.trial))
            } else {
                Ok(v)
            }
        })
    }
}

/// One navigation of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialRecord {
    /// `sensor-range` or `occlusion`.
    pub trial: String,
    /// R'/R or the landmark size.
    pub value: f64,
    /// Start landmark.
    pub start: u32,
    /// Goal landmark.
    pub goal: u32,
    /// |P| (0 when there was no path).
    pub plan_len: usize,
    /// Success.
    pub success: bool,
    /// Failure cause.
    pub failure: Option<Failure>,
    /// Trajectory length (m).
    pub length: f64,
    /// Length driven in transitions (what Proposition 2 bounds, m).
    pub transit_length: f64,
    /// Proposition 2's bound (m).
    pub bound: f64,
    /// Proposition 4's bound R·|P| (m; it applies only to maps meeting Assumption 3, which
    /// this one does not — reported for comparison).
    pub bound_direct: f64,
}

/// The mapped world the study navigates.
pub struct StudyWorld {
    /// The scenario (world with 0.3 m landmarks, mapping path).
    pub scenario: sim2d::Scenario,
    /// The PQRM map (quadrant).
    pub map: QualitativeMap,
    /// The unit-cost, β = 1 link graph.
    pub graph: LinkGraph,
    /// Landmark positions `(id, xy)`.
    pub landmarks: Vec<(u32, [f64; 2])>,
    /// Frames of the mapping drive.
    pub frames: usize,
}

/// Simulates the mapping drive and builds the PQRM and the Link Graph. With `size`, the
/// landmarks are discs of that radius and the mapping robot sees them with full occlusion
/// (the occlusion trial's environment); without, point landmarks and no occlusion.
///
/// # Errors
/// Simulation and mapping errors.
pub fn build_world(seed: u64, samples: usize, size: Option<f64>) -> Result<StudyWorld> {
    let mut scenario = sim2d::scenario("qlink-200", seed, None)?;
    match size {
        Some(r) => {
            scenario = scenario.with_landmark_radius(r)?;
            scenario.detector.full_occlusion = true;
        }
        None => scenario.detector.full_occlusion = false,
    }
    let frames = scenario.run(seed, false)?;
    let calculus = qsr_core::Calculus::builtin("quadrant")?;
    let mut pqrm = pqrm::Pqrm::new(
        calculus,
        pqrm::PqrmConfig {
            samples,
            seed,
            ..pqrm::PqrmConfig::default()
        },
    )?;
    for f in &frames {
        let obs = f
            .detections
            .iter()
            .map(|d| pqrm::Observation::new(pqrm::LandmarkId(d.id), d.xy, d.cov))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        if obs.len() >= 3 {
            pqrm.update(&pqrm::Scan::new(f.t, 0, obs)?)?;
        }
    }
    let map = QualitativeMap::from_pqrm(pqrm)?;
    let graph = LinkGraph::new(&map, 1, |_, _, _| 1.0)?;
    let landmarks = scenario
        .world
        .spec()
        .landmarks
        .iter()
        .map(|l| (l.id, l.pos))
        .collect();
    Ok(StudyWorld {
        frames: frames.len(),
        scenario,
        map,
        graph,
        landmarks,
    })
}

/// The study's navigation settings for a robot of range `range`.
///
/// # Errors
/// POMDP parameter errors (none for these values).
pub fn nav_config(range: f64, step: f64) -> Result<NavConfig> {
    let quadrant = qsr_core::Calculus::builtin("quadrant")?;
    Ok(NavConfig {
        controller: Controller::new(ControllerKind::Arc, range),
        pomdp: SearchPomdp::new(&quadrant, false, 1.0, 0.9, 4)?,
        step,
        replan: false,
        max_replans: 0,
        map_range: MAP_RANGE,
        find_goal: false,
    })
}

/// The ordered pairs navigated: all, or `n` drawn with the seed.
#[must_use]
pub fn pairs(landmarks: &[(u32, [f64; 2])], n: Option<usize>, seed: u64) -> Vec<(u32, u32)> {
    let mut all: Vec<(u32, u32)> = Vec::new();
    for &(a, _) in landmarks {
        for &(b, _) in landmarks {
            if a != b {
                all.push((a, b));
            }
        }
    }
    if let Some(n) = n
        && n < all.len()
    {
        use rand::SeedableRng;
        use rand::seq::SliceRandom;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x9a15);
        all.shuffle(&mut rng);
        all.truncate(n);
        all.sort_unstable();
    }
    all
}

/// Distance fields of every goal in `pairs` (unit costs), in parallel.
///
/// # Errors
/// [`QlinkError::UnknownLandmark`] for a goal not in the map.
pub fn fields(world: &StudyWorld, pairs: &[(u32, u32)]) -> Result<Vec<(u32, DistanceField)>> {
    let mut goals: Vec<u32> = pairs.iter().map(|p| p.1).collect();
    goals.sort_unstable();
    goals.dedup();
    goals
        .par_iter()
        .filter(|g| !world.map.elements_with(**g).is_empty())
        .map(|&g| Ok((g, world.graph.distance_field(&world.map, g)?)))
        .collect()
}

#[allow(clippy::too_many_arguments)] // private glue between run_setting's two perceptions
fn run_pairs<P: Perception>(
    world: &StudyWorld,
    perception: &P,
    config: &NavConfig,
    pairs: &[(u32, u32)],
    fields: &[(u32, DistanceField)],
    offset: f64,
    (trial, value): (&str, f64),
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<TrialRecord>> {
    let nav = Navigator::new(&world.map, &world.graph, perception, config)?;
    pairs
        .par_iter()
        .map(|&(s, g)| {
            let field = fields.iter().find(|f| f.0 == g).map(|f| &f.1);
            let p = perception
                .position(s)
                .ok_or(QlinkError::UnknownLandmark(s))?;
            let outcome: NavOutcome = if field.is_none() {
                // the goal was never mapped: no path
                NavOutcome::unfinished(Some(Failure::NoPath))
            } else {
                nav.navigate([p[0] + offset, p[1]], g, field, false)?
            };
            progress();
            Ok(TrialRecord {
                trial: trial.to_owned(),
                value,
                start: s,
                goal: g,
                plan_len: outcome.plan_len,
                success: outcome.success,
                failure: outcome.failure,
                length: outcome.length,
                transit_length: outcome.transit_length,
                bound: outcome.bound,
                bound_direct: outcome.bound_direct,
            })
        })
        .collect()
}

/// Runs one setting over `pairs` in `world` (for the occlusion trial, the world built with
/// that landmark size).
///
/// # Errors
/// Navigation errors; [`QlinkError::InvalidParameter`] for an unknown trial.
pub fn run_setting(
    world: &StudyWorld,
    config: &StudyConfig,
    pairs: &[(u32, u32)],
    fields: &[(u32, DistanceField)],
    (trial, value): (&str, f64),
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<TrialRecord>> {
    match trial {
        "sensor-range" => {
            let range = value * MAP_RANGE;
            let perception = RangePerception::new(&world.landmarks, range);
            let nav = nav_config(range, config.step)?;
            run_pairs(
                world,
                &perception,
                &nav,
                pairs,
                fields,
                0.5,
                (trial, value),
                progress,
            )
        }
        "occlusion" => {
            let perception = WorldPerception::new(&world.scenario.world, MAP_RANGE);
            let nav = nav_config(MAP_RANGE, config.step)?;
            run_pairs(
                world,
                &perception,
                &nav,
                pairs,
                fields,
                value + 0.5,
                (trial, value),
                progress,
            )
        }
        t => Err(QlinkError::InvalidParameter(format!("unknown trial `{t}`"))),
    }
}

/// One row of Table 4.1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableRow {
    /// Trial.
    pub trial: String,
    /// R'/R or size.
    pub value: f64,
    /// Pairs navigated.
    pub pairs: usize,
    /// Pairs without a path in the link graph.
    pub no_path: usize,
    /// Failed navigations (among pairs with a path).
    pub failures: usize,
    /// failures / (pairs − no_path).
    pub failure_rate: f64,
    /// Successful runs whose transitions were longer than Proposition 2's bound.
    pub over_bound: usize,
}

/// Table 4.1 from records.
#[must_use]
pub fn table(records: &[TrialRecord]) -> Vec<TableRow> {
    let mut keys: Vec<(String, u64)> = Vec::new();
    for r in records {
        let k = (r.trial.clone(), r.value.to_bits());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(trial, bits)| {
            let sel: Vec<&TrialRecord> = records
                .iter()
                .filter(|r| r.trial == trial && r.value.to_bits() == bits)
                .collect();
            let no_path = sel
                .iter()
                .filter(|r| r.failure == Some(Failure::NoPath))
                .count();
            let failures = sel
                .iter()
                .filter(|r| !r.success && r.failure != Some(Failure::NoPath))
                .count();
            let with_path = sel.len() - no_path;
            TableRow {
                trial,
                value: f64::from_bits(bits),
                pairs: sel.len(),
                no_path,
                failures,
                failure_rate: failures as f64 / with_path.max(1) as f64,
                over_bound: sel
                    .iter()
                    .filter(|r| r.success && r.transit_length > r.bound + 1e-9)
                    .count(),
            }
        })
        .collect()
}

/// A mapped world with its pairs and their goals' distance fields.
type Prepared = (StudyWorld, Vec<(u32, u32)>, Vec<(u32, DistanceField)>);

/// What one setting of a study run used and took.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettingInfo {
    /// Trial.
    pub trial: String,
    /// R'/R or size.
    pub value: f64,
    /// Mapping frames.
    pub frames: usize,
    /// Map elements.
    pub elements: usize,
    /// Directed link-graph edges.
    pub edges: usize,
    /// Seconds to build the map, graph and distance fields (0 when shared).
    pub build_seconds: f64,
    /// Seconds of navigation.
    pub navigate_seconds: f64,
}

/// Runs every setting of `config`: one point-landmark map for the sensor-range trial, one
/// map per landmark size for the occlusion trial. `progress` is called after every
/// navigation (`total` navigations are announced first through `start`).
///
/// # Errors
/// As [`build_world`] and [`run_setting`].
pub fn run_study(
    config: &StudyConfig,
    start: &dyn Fn(usize),
    progress: &(dyn Fn() + Sync),
) -> Result<(Vec<TrialRecord>, Vec<SettingInfo>)> {
    let settings = config.settings()?;
    let mut shared: Option<Prepared> = None;
    let mut records = Vec::new();
    let mut infos = Vec::new();
    for (trial, value) in settings {
        let t = std::time::Instant::now();
        let own;
        let (world, pairs, fields) = if trial == "occlusion" {
            let w = build_world(config.seed, config.samples, Some(value))?;
            let p = pairs(&w.landmarks, config.pairs, config.seed);
            let f = fields(&w, &p)?;
            own = (w, p, f);
            (&own.0, &own.1, &own.2)
        } else {
            if shared.is_none() {
                let w = build_world(config.seed, config.samples, None)?;
                let p = pairs(&w.landmarks, config.pairs, config.seed);
                let f = fields(&w, &p)?;
                shared = Some((w, p, f));
            }
            let sh = shared.as_ref().ok_or(QlinkError::EmptyMap)?;
            (&sh.0, &sh.1, &sh.2)
        };
        let build_seconds = t.elapsed().as_secs_f64();
        start(pairs.len());
        let tn = std::time::Instant::now();
        records.extend(run_setting(
            world,
            config,
            pairs,
            fields,
            (&trial, value),
            progress,
        )?);
        infos.push(SettingInfo {
            frames: world.frames,
            elements: world.map.elements().len(),
            edges: world.graph.n_edges(),
            build_seconds,
            navigate_seconds: tn.elapsed().as_secs_f64(),
            trial,
            value,
        });
    }
    Ok((records, infos))
}
