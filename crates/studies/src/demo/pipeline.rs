//! The demo's pipeline, step by step: the mapping drive by lidar, the PQRM, the calculus SERGE
//! learns from it, the qualitative map of both and the thesis's navigator over it.

use std::collections::{BTreeMap, BTreeSet};

use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qlink::{Controller, ControllerKind, Layer, LinkGraph, NavConfig, QualitativeMap};
use qsr_core::Calculus;
use serge::learner::CalculusLearner;
use serge::selection::TripletSelection;

use crate::error::{Result, StudyError};

/// Landmarks two map elements share for a link: 2, as in the thesis's field experiment
/// (§4.4.2) — with one, elements spanning the site link far-apart places in one step.
pub const BETA: usize = 2;

/// Detection noise of the map, N(0, 0.7 m) per axis as in §4.4.2 (variance 0.49 m²).
const DETECTION_VARIANCE: f64 = 0.49;

/// Samples per landmark per step of the PQRM's sampler.
const SAMPLES: usize = 300;

/// The mapping drive: the field site, its frames with the detections renamed to the world's
/// landmark ids (clutter recognised as a landmark dropped), and the scans that saw three.
pub struct Mapping {
    /// The simulated site.
    pub scenario: sim2d::Scenario,
    /// Every frame of the drive.
    pub frames: Vec<sim2d::Frame>,
    /// Landmarks recognised and matched to the world's.
    pub recognised: usize,
    /// The frames that saw three landmarks or more, as PQRM scans.
    pub scans: Vec<Scan>,
}

/// Mean belief entropy after a scan (eq. 2.11): `(t, nats, landmark sets)`, for the log.
pub type EntropyPoint = (f64, f64, usize);

/// The mapping drive with the lidar; landmarks recognised by triangles, no ids given. The
/// recognised ids are matched to the world's (first recognition) so that the navigating
/// robot can be simulated.
///
/// # Errors
/// The simulator's; [`StudyError::InvalidParameter`] when no frame saw three landmarks.
pub fn map_by_lidar(seed: u64) -> Result<Mapping> {
    let scenario = sim2d::scenario("field", seed, None)?;
    let mut frames = scenario.run(seed, true)?;
    let assoc: BTreeMap<u32, u32> = sim2d::LidarDetector::new(0.3, 0.7)
        .detect_frames(&mut frames)
        .into_iter()
        .map(|(id, i)| (id, scenario.world.spec().landmarks[i].id))
        .collect();
    for f in &mut frames {
        f.detections.retain_mut(|d| match assoc.get(&d.id) {
            Some(&world) => {
                d.id = world;
                true
            }
            None => false,
        });
    }
    let scans: Vec<Scan> = frames
        .iter()
        .filter(|f| f.detections.len() >= 3)
        .map(|f| {
            let mut seen = BTreeSet::new();
            let cov = [[DETECTION_VARIANCE, 0.0], [0.0, DETECTION_VARIANCE]];
            let obs = f
                .detections
                .iter()
                .filter(|d| seen.insert(d.id))
                .map(|d| Observation::new(LandmarkId(d.id), d.xy, cov))
                .collect::<std::result::Result<Vec<_>, _>>()?;
            Ok(Scan::new(f.t, 0, obs)?)
        })
        .collect::<Result<_>>()?;
    if scans.is_empty() {
        return Err(StudyError::InvalidParameter(format!(
            "seed {seed}: the mapping drive recognised no three landmarks at once"
        )));
    }
    Ok(Mapping {
        recognised: assoc.len(),
        scenario,
        frames,
        scans,
    })
}

fn pqrm_config(seed: u64) -> PqrmConfig {
    PqrmConfig {
        samples: SAMPLES,
        seed,
        ..PqrmConfig::default()
    }
}

/// The PQRM of the flip-flop (left/right) calculus over the scans, and its mean entropy after
/// each scan.
///
/// # Errors
/// The mapper's.
pub fn flip_flop_map(scans: &[Scan], seed: u64) -> Result<(Pqrm, Vec<EntropyPoint>)> {
    let mut flip = Pqrm::new(Calculus::builtin("left-right")?, pqrm_config(seed))?;
    let mut entropy = Vec::with_capacity(scans.len());
    for s in scans {
        flip.update(s)?;
        if let Some(h) = flip.mean_entropy() {
            entropy.push((s.t, h, flip.len()));
        }
    }
    Ok((flip, entropy))
}

/// Frames a landmark set must be seen together in to be learned from.
const LEARN_MIN_FRAMES: usize = 4;

/// Most triplets the demo learns from.
const LEARN_TRIPLETS: usize = 30;

/// SERGE learns a calculus from the triplets the robot saw ([`serge::selection`]'s rule;
/// `None` with fewer than two).
///
/// # Errors
/// SERGE's.
pub fn learn_calculus(scans: &[Scan], seed: u64) -> Result<Option<Calculus>> {
    let learner = CalculusLearner {
        selection: TripletSelection {
            min_frames: LEARN_MIN_FRAMES,
            max_triplets: LEARN_TRIPLETS,
            seed,
        },
        samples: 1000,
        cells: 48,
        ..CalculusLearner::new(6, 2.0, seed)
    };
    let Ok(selected) = learner
        .selection
        .select(&crate::recording::sightings(scans))
    else {
        return Ok(None);
    };
    if selected.triplets.len() < 2 {
        return Ok(None);
    }
    let map = learner.learn_from(&selected)?;
    Ok(Some(map.to_calculus(
        "demo-learned",
        "learned by SERGE from the demo's mapping drive",
    )?))
}

/// The hybrid map: the flip-flop layer, and the learned calculus's layer over the same scans.
///
/// # Errors
/// The mapper's and Q-Link's.
pub fn qualitative_map(
    flip: Pqrm,
    learned: Option<&Calculus>,
    scans: &[Scan],
    seed: u64,
) -> Result<QualitativeMap> {
    let mut layers = vec![Layer::Probabilistic(flip)];
    if let Some(c) = learned {
        let mut m = Pqrm::new(c.clone(), pqrm_config(seed))?;
        for s in scans {
            m.update(s)?;
        }
        layers.push(Layer::Probabilistic(m));
    }
    Ok(QualitativeMap::new(layers)?)
}

/// The Link Graph (β = 2, −log P costs from the horizon-4 POMDP) and the thesis's navigator:
/// midpoint-and-sweep, arcs and circles of the lidar's range R, re-planning up to three times.
///
/// # Errors
/// Q-Link's.
pub fn navigator(
    map: &QualitativeMap,
    scenario: &sim2d::Scenario,
) -> Result<(LinkGraph, NavConfig)> {
    let pomdps = map.search_pomdps(|b| b.moves(qlink::Moves::Direct).p_move(0.9))?;
    let cost = qlink::graph::pomdp_cost(map, &pomdps, qlink::CostModel::NegLogSuccess);
    let graph = LinkGraph::new(map, BETA, cost)?;
    let map_range = scenario.lidar.max_range;
    let config = NavConfig {
        replan: true,
        max_replans: 3,
        map_range,
        find_goal: true,
        ..NavConfig::thesis(
            Controller::new(ControllerKind::MidpointSweep, map_range),
            pomdps[0].clone(),
        )
    };
    Ok((graph, config))
}
