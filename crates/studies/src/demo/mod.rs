//! The end-to-end demo (DESIGN §1): a simulated robot maps the field site with its lidar
//! (landmarks extracted from the scans and recognised by triangles, no ids given), builds the
//! probabilistic qualitative map, learns a calculus from the triplets it saw with SERGE, and
//! crosses the site with Q-Link using nothing but the qualitative map — the thesis's
//! navigator (β = 2 links, horizon-4 POMDP searches, arcs of the mapping range, references it
//! perceives). The run shown is picked by a stated rule ([`choice::RUN_RULE`]).
//!
//! It is a study like the others so that `qrm demo`, `qrm study run demo` and
//! `qrm.studies.run("demo")` give the same files: the log, the picture's data, the learned
//! calculus and the summary are the report's, and the front ends only write and draw them.
//! The pipeline is one run, so the demo is one shard.
//!
//! | module | what |
//! |---|---|
//! | [`pipeline`] | the mapping drive, the PQRM, the learned calculus, the map and its navigator |
//! | [`choice`] | which navigation is shown: the longest plan that succeeds |
//! | [`picture`] | the data of the picture: the plan's triangles, the links, the calculus's regions |
//! | [`log`] | the MCAP log for Foxglove |
//! | [`report`] | the summary, the run's tables, the picture and the files |

use qsr_core::progress::Progress;
use serde::{Deserialize, Serialize};

use crate::error::{Result, StudyError};
use crate::report::{Attachment, Report};
use crate::study::Study;
use crate::world_perception::WorldPerception;

pub mod choice;
pub mod log;
pub mod picture;
pub mod pipeline;
pub mod report;

pub use choice::{Chosen, RUN_RULE};
pub use picture::Picture;

/// What the demo runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemoConfig {
    /// Seed of the world, the sensors, the sampler and SERGE.
    pub seed: u64,
    /// Goal landmark (`None`: the one whose plan is the longest that succeeds).
    #[serde(default)]
    pub goal: Option<u32>,
    /// Sensor range R' of the navigating robot (m); the mapping robot's lidar reaches
    /// R = 30 m, and arcs and search circles run at R as in the thesis (§4.4.1).
    pub nav_range: f64,
    /// What the navigating robot's detector and wheels get wrong (seeded by `seed`): the
    /// site's detection noise N(0, 0.7), misses and wheeled motion noise.
    #[serde(default = "demo_robot")]
    pub robot: qlink::Robot,
    /// Idealised: true detections and exact driving (`robot` unused; labelled as such).
    #[serde(default)]
    pub exact_robot: bool,
}

/// The demo's navigating robot: the §4.4.2 site's detection noise N(0, 0.7) with the
/// default misses, wheeled motion noise.
#[must_use]
pub fn demo_robot() -> qlink::Robot {
    qlink::Robot::erring(0.7)
}

impl DemoConfig {
    /// The navigating robot: `robot` seeded with the demo's seed, or the exact one.
    #[must_use]
    pub fn navigating_robot(&self) -> qlink::Robot {
        self.robot.or_exact(self.exact_robot, self.seed)
    }

    /// The demo of `seed`: the goal by the run rule, R' = R = 30 m.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self {
            seed,
            goal: None,
            nav_range: 30.0,
            robot: demo_robot(),
            exact_robot: false,
        }
    }
}

/// The learned calculus: its size and its spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Learned {
    /// Its number of states.
    pub states: usize,
    /// `learned_calculus.json`: the spec, which `qrm calculus show` and `Calculus::from_spec`
    /// read.
    pub spec: Attachment,
}

/// What the demo produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemoOutput {
    /// The config it ran (a shard of another config is refused).
    pub config: DemoConfig,
    /// Frames of the mapping drive.
    pub frames: usize,
    /// Landmarks recognised by triangles and matched to the world's (clutter dropped).
    pub recognised_landmarks: usize,
    /// Elements of the qualitative map (landmark sets, over its layers).
    pub map_elements: usize,
    /// Links of the Link Graph.
    pub link_graph_edges: usize,
    /// What SERGE learned (`None` with fewer than two triplets to learn from).
    pub learned: Option<Learned>,
    /// The R the map was made with and the robot drives arcs of (m).
    pub map_range: f64,
    /// The run shown and how it was picked.
    pub run: Chosen,
    /// The picture's data.
    pub picture: Picture,
    /// `run.mcap`: the whole run for Foxglove.
    pub log: Attachment,
}

/// The demo's units of progress: mapping, the calculus and map, the navigation.
const UNITS: usize = 3;

/// Runs the demo of `config`.
///
/// # Errors
/// The crates' errors; [`StudyError::InvalidParameter`] when the seed's drive or the goal
/// leaves nothing to navigate; [`StudyError::Cancelled`] when `progress` asks.
fn run(config: &DemoConfig, progress: &dyn Progress) -> Result<DemoOutput> {
    progress.add_total(UNITS);
    let mapping = pipeline::map_by_lidar(config.seed)?;
    let (flip, entropy) = pipeline::flip_flop_map(&mapping.scans, config.seed)?;
    progress.tick();
    progress.check()?;
    let learned = pipeline::learn_calculus(&mapping.scans, config.seed)?;
    let map = pipeline::qualitative_map(flip, learned.as_ref(), &mapping.scans, config.seed)?;
    progress.tick();
    progress.check()?;
    let (graph, mut nav_config) = pipeline::navigator(&map, &mapping.scenario)?;
    nav_config.robot = config.navigating_robot();
    let perception = WorldPerception::new(&mapping.scenario.world, config.nav_range);
    let setting = choice::Setting {
        map: &map,
        graph: &graph,
        perception: &perception,
        config: &nav_config,
    };
    let run = choice::choose_run(&setting, &mapping.frames, config.goal, progress)?;
    progress.tick();
    let log = log::write(&log::Run {
        scenario: &mapping.scenario,
        frames: &mapping.frames,
        map: &map,
        entropy: &entropy,
        outcome: &run.outcome,
        goal: run.goal,
    })?;
    let picture = picture::Picture::new(&mapping, &map, &perception, &run, learned.as_ref());
    Ok(DemoOutput {
        config: config.clone(),
        frames: mapping.frames.len(),
        recognised_landmarks: mapping.recognised,
        map_elements: map.elements().len(),
        link_graph_edges: graph.n_edges(),
        learned: learned
            .map(|c| {
                Ok::<_, StudyError>(Learned {
                    states: c.n_states(),
                    spec: Attachment::text("learned_calculus.json", c.spec().to_json_string()?),
                })
            })
            .transpose()?,
        map_range: mapping.scenario.lidar.max_range,
        run,
        picture,
        log: Attachment::binary("run.mcap", log),
    })
}

/// The demo as a study.
#[derive(Debug, Clone, Copy)]
pub struct Demo;

impl Study for Demo {
    const NAME: &'static str = "demo";
    const ABOUT: &'static str = "DESIGN §1: the whole pipeline — lidar mapping, PQRM, a calculus learned by SERGE, \
         Q-Link across the field site, an MCAP log for Foxglove";
    /// Seed 1: its field world's map gives a three-transition run that reaches its goal on
    /// the first pair tried (220 m, under a second). Other seeds are shown the same way: every
    /// seed measured (0–14) has a pair that reaches its goal (seed 9 on its 30th of 103), and a
    /// seed without one is said to have none.
    const DEFAULT_SEED: u64 = 1;
    type Config = DemoConfig;
    type Output = DemoOutput;
    type Shard = DemoOutput;

    /// The demo takes a second: quick and full are the same.
    fn quick(seed: u64) -> DemoConfig {
        DemoConfig::new(seed)
    }
    fn full(seed: u64) -> DemoConfig {
        DemoConfig::new(seed)
    }
    fn check(config: &DemoConfig) -> Result<()> {
        // Beyond the field site (100 m across) a longer range sees nothing more.
        if !(config.nav_range.is_finite() && config.nav_range > 0.0 && config.nav_range <= 1e4) {
            return Err(StudyError::InvalidParameter(format!(
                "nav_range must be a positive number of metres, at most 1e4, not {:?}",
                config.nav_range
            )));
        }
        Ok(config.robot.check()?)
    }
    fn shards(config: &DemoConfig) -> Result<usize> {
        Self::check(config)?;
        Ok(1)
    }
    /// Mapping, the calculus and map, the navigation.
    fn shard_units(config: &DemoConfig, index: usize) -> Result<usize> {
        Self::shards(config)?;
        if index != 0 {
            return Err(StudyError::InvalidParameter(format!(
                "the demo is one shard, not shard {index}"
            )));
        }
        Ok(UNITS)
    }
    fn run_shard(config: &DemoConfig, index: usize, progress: &dyn Progress) -> Result<DemoOutput> {
        Self::check(config)?;
        if index != 0 {
            return Err(StudyError::InvalidParameter(format!(
                "the demo is one shard, not shard {index}"
            )));
        }
        run(config, progress)
    }
    fn aggregate(config: &DemoConfig, shards: Vec<(usize, DemoOutput)>) -> Result<DemoOutput> {
        crate::shard::check_indices(1, shards.iter().map(|(i, _)| *i))?;
        let output =
            shards.into_iter().next().map(|(_, s)| s).ok_or_else(|| {
                StudyError::InvalidParameter("the demo's shard is missing".into())
            })?;
        if output.config != *config {
            return Err(StudyError::InvalidParameter(format!(
                "shard 0 ran the demo of {:?}, not this config's {config:?}",
                output.config
            )));
        }
        Ok(output)
    }
    fn report(config: &DemoConfig, output: &DemoOutput) -> Report {
        report::report(config, output)
    }
}
