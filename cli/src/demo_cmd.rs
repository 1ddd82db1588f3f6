//! `qrm demo`: the whole pipeline in one run — simulate a robot mapping the field site with
//! its lidar, build the probabilistic qualitative map, learn a calculus with SERGE, and
//! navigate to a goal with Q-Link; write an MCAP log for Foxglove, a summary and a picture.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, bail};
use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qlink::{
    Controller, ControllerKind, Layer, LinkGraph, NavConfig, Navigator, QualitativeMap, SearchPomdp,
};
use qsr_core::Calculus;
use serde_json::{Value, json};
use serge::learn::{TripletObservation, triplet_beliefs};
use serge::{CellMasses, Grid, Serge, SergeParams};
use studies::world_perception::WorldPerception;

use crate::output::{Staging, write_atomic};
use qrm_log::{McapLog, stamp, yaw};

/// `qrm demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Seed of the world, the sensors and the sampler.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Goal landmark (default: the one whose plan is the longest that succeeds; see
    /// `run_rule` in summary.json).
    #[arg(long)]
    pub goal: Option<u32>,
    /// Sensor range R' of the navigating robot (m); the mapping robot's lidar reaches
    /// R = 30 m, and arcs and search circles run at R as in the thesis.
    #[arg(long, default_value_t = 30.0)]
    pub nav_range: f64,
    /// Output directory.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
}

const PLAN_SCHEMA: &str = r#"{"title": "qrm.Plan", "description": "A Q-Link plan: map elements (landmark triplets) from start to goal", "type": "object",
 "properties": {"timestamp": {"type": "object"}, "goal": {"type": "integer"}, "cost": {"type": "number"},
  "elements": {"type": "array", "items": {"type": "object", "properties": {"id": {"type": "integer"}, "landmarks": {"type": "array"}, "calculus": {"type": "string"}}}}}}"#;
const BELIEFS_SCHEMA: &str = r#"{"title": "qrm.MapBeliefs", "description": "PQRM beliefs: per map element, its calculus and the distribution over states of its first ordering", "type": "object",
 "properties": {"timestamp": {"type": "object"}, "elements": {"type": "array", "items": {"type": "object", "properties": {
  "landmarks": {"type": "array"}, "calculus": {"type": "string"}, "states": {"type": "array"}, "p": {"type": "array"}, "entropy": {"type": "number"}}}}}}"#;
const CONTROLLER_SCHEMA: &str = r#"{"title": "qrm.ControllerState", "description": "One Q-Link transition: the link searched for, the POMDP commands (target states) and the outcome", "type": "object",
 "properties": {"timestamp": {"type": "object"}, "from": {"type": "integer"}, "to": {"type": "integer"}, "link": {"type": "integer"},
  "commands": {"type": "array"}, "success": {"type": "boolean"}, "length": {"type": "number"}}}"#;

const ENTROPY_SCHEMA: &str = r#"{"title": "qrm.MapEntropy", "description": "Mean PQRM belief entropy over the map's triplets after a scan (nats, eq. 2.11)", "type": "object",
 "properties": {"timestamp": {"type": "object"}, "mean_entropy": {"type": "number"}, "triplets": {"type": "integer"}}}"#;

/// Runs the demo.
pub fn run(a: DemoArgs) -> Result<()> {
    let t0 = Instant::now();
    // 1. the mapping drive with the lidar; landmarks recognised by triangles, no ids given
    let sc = sim2d::scenario("field", a.seed, None)?;
    let mut frames = sc.run(a.seed, true)?;
    // recognised id → world landmark (first recognition), so the navigating robot can be
    // simulated; clutter recognised as a landmark is dropped
    let assoc: BTreeMap<u32, u32> = sim2d::LidarDetector::new(0.3, 0.7)
        .detect_frames(&mut frames)
        .into_iter()
        .map(|(id, i)| (id, sc.world.spec().landmarks[i].id))
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
    let t_sim = t0.elapsed().as_secs_f64();
    // 2. the PQRM (flip-flop calculus, N(0, 0.7) as in §4.4.2)
    let scans: Vec<Scan> = frames
        .iter()
        .filter(|f| f.detections.len() >= 3)
        .map(|f| {
            let mut seen = std::collections::BTreeSet::new();
            let obs = f
                .detections
                .iter()
                .filter(|d| seen.insert(d.id))
                .map(|d| Observation::new(LandmarkId(d.id), d.xy, [[0.49, 0.0], [0.0, 0.49]]))
                .collect::<std::result::Result<Vec<_>, _>>()?;
            Ok(Scan::new(f.t, 0, obs)?)
        })
        .collect::<Result<_>>()?;
    if scans.is_empty() {
        bail!("the mapping drive recognised no three landmarks at once");
    }
    let config = PqrmConfig {
        samples: 300,
        seed: a.seed,
        ..PqrmConfig::default()
    };
    let mut flip = Pqrm::new(Calculus::builtin("left-right")?, config)?;
    // mean belief entropy after each scan (eq. 2.11), for the log's entropy plot
    let mut entropy: Vec<(f64, f64, usize)> = Vec::with_capacity(scans.len());
    for s in &scans {
        flip.update(s)?;
        if let Some(h) = flip.mean_entropy() {
            entropy.push((s.t, h, flip.len()));
        }
    }
    // 3. SERGE learns a calculus from the triplets the robot saw
    let t1 = Instant::now();
    let mut count: BTreeMap<[u32; 3], usize> = BTreeMap::new();
    for s in &scans {
        let ids: Vec<u32> = s.observations.iter().map(|o| o.id.0).collect();
        for i in 0..ids.len() {
            for j in i + 1..ids.len() {
                for k in j + 1..ids.len() {
                    *count.entry([ids[i], ids[j], ids[k]]).or_insert(0) += 1;
                }
            }
        }
    }
    let mut triplets: Vec<[u32; 3]> = count
        .into_iter()
        .filter(|&(_, n)| n >= 4)
        .map(|(t, _)| t)
        .collect();
    triplets.truncate(30);
    let mut obs = Vec::new();
    for s in &scans {
        let get = |id: u32| s.observations.iter().find(|o| o.id.0 == id);
        for (k, t) in triplets.iter().enumerate() {
            if let (Some(d), Some(e), Some(f)) = (get(t[0]), get(t[1]), get(t[2])) {
                obs.push(TripletObservation {
                    triplet: k,
                    points: [d.mean, e.mean, f.mean],
                    cov: [d.cov, e.cov, f.cov],
                });
            }
        }
    }
    let learned = if triplets.len() >= 2 {
        let beliefs = triplet_beliefs(&obs, triplets.len(), 1000, a.seed)?;
        let masses = CellMasses::compute(&beliefs, Grid::new([-3.0, 3.0, -2.5, 3.5], 48, 48)?)?;
        let map =
            Serge::new(&masses)?.run(&SergeParams::new(6.min(triplets.len()), 2.0).seed(a.seed))?;
        Some(map.to_calculus(
            "demo-learned",
            "learned by SERGE from the demo's mapping drive",
        )?)
    } else {
        None
    };
    let t_serge = t1.elapsed().as_secs_f64();
    let mut layers = vec![Layer::Probabilistic(flip)];
    if let Some(c) = &learned {
        let mut m = Pqrm::new(c.clone(), config)?;
        for s in &scans {
            m.update(s)?;
        }
        layers.push(Layer::Probabilistic(m));
    }
    let map = QualitativeMap::new(layers)?;
    // 4. Q-Link: β = 2, −log P costs from the horizon-4 POMDP, midpoint-and-sweep, re-planning
    let pomdps: Vec<SearchPomdp> = map
        .layers()
        .iter()
        .map(|l| {
            SearchPomdp::builder(l.calculus())
                .moves(qlink::Moves::Direct)
                .p_move(0.9)
                .build()
        })
        .collect::<std::result::Result<_, _>>()?;
    let cost = qlink::graph::pomdp_cost(&map, &pomdps, qlink::CostModel::NegLogSuccess);
    let graph = LinkGraph::new(&map, BETA, cost)?;
    if a.nav_range.is_nan() || a.nav_range <= 0.0 {
        bail!("--nav-range must be positive");
    }
    // R: the range the map was made with (the lidar's); the robot drives arcs and circles
    // of R and senses with R' (thesis §4.4.1)
    let map_range = sc.lidar.max_range;
    let range = a.nav_range;
    let nav_config = NavConfig {
        replan: true,
        max_replans: 3,
        map_range,
        find_goal: true,
        ..NavConfig::thesis(
            Controller::new(ControllerKind::MidpointSweep, map_range),
            pomdps[0].clone(),
        )
    };
    let perception = WorldPerception::new(&sc.world, range);
    let t2 = Instant::now();
    let chosen = choose_run(&map, &graph, &perception, &nav_config, &frames, a.goal)?;
    let (start, goal, outcome) = (chosen.start, chosen.goal, chosen.outcome.clone());
    let t_nav = t2.elapsed().as_secs_f64();
    let pos_of = |id: u32| qlink::Perception::position(&perception, id);
    // 5. outputs
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let t_end_map = frames.last().map_or(0.0, |f| f.t);
    write_log(
        &out_dir, &sc, &frames, &map, &entropy, &outcome, goal, t_end_map,
    )?;
    if let Some(c) = &learned {
        write_atomic(
            &out_dir.join("learned_calculus.json"),
            c.spec().to_json_string()?.as_bytes(),
        )?;
    }
    let drive: Vec<[f64; 2]> = frames.iter().map(|f| [f.pose.x, f.pose.y]).collect();
    let plan: Vec<[[f64; 2]; 3]> = outcome
        .plan
        .iter()
        .filter_map(|&e| {
            let [x, y, z] = map.elements()[e].landmarks;
            Some([pos_of(x)?, pos_of(y)?, pos_of(z)?])
        })
        .collect();
    let links: Vec<[f64; 2]> = outcome
        .transitions
        .iter()
        .filter(|t| t.success)
        .filter_map(|t| pos_of(t.link))
        .collect();
    let regions = learned.as_ref().map(regions_of);
    let verdict = if outcome.success {
        "reached"
    } else {
        "not reached"
    };
    crate::plot::demo_picture(
        &out_dir.join("demo"),
        &crate::plot::DemoPicture {
            title: format!(
                "Q-Link to landmark {goal}: {verdict}, |P| = {}, {:.0} m",
                outcome.plan_len, outcome.length
            ),
            world: sc.world.spec(),
            drive: &drive,
            trajectory: &outcome.trajectory,
            searches: &outcome.searches,
            plan: &plan,
            links: &links,
            start,
            goal: pos_of(goal).unwrap_or(start),
            regions: match (&learned, &regions) {
                (Some(c), Some(r)) => Some((
                    format!("Learned calculus: {} regions of A→B", c.n_states()),
                    r.picture(),
                )),
                _ => None,
            },
        },
    )?;
    let summary = json!({
        "seed": a.seed,
        "scenario": "field",
        "frames": frames.len(),
        "recognised_landmarks": assoc.len(),
        "map_elements": map.elements().len(),
        "link_graph_edges": graph.n_edges(),
        "beta": BETA,
        "learned_calculus_states": learned.as_ref().map(Calculus::n_states),
        "run_rule": RUN_RULE,
        "runs_tried": chosen.tried,
        "pairs_with_a_plan": chosen.candidates,
        "start": start,
        "goal": goal,
        "success": outcome.success,
        "failure": outcome.failure,
        "plan_len": outcome.plan_len,
        "plan": outcome.plan,
        "replans": outcome.replans,
        "map_range": map_range,
        "sensor_range": range,
        "trajectory_length": outcome.length,
        "transit_length": outcome.transit_length,
        "prop2_bound": outcome.bound,
        "prop4_bound": outcome.bound_direct,
        "transitions": outcome.transitions,
        "seconds": {"simulate": t_sim, "serge": t_serge, "navigate": t_nav, "total": t0.elapsed().as_secs_f64()},
    });
    write_atomic(
        &out_dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    outln!(
        "qrm demo (seed {}): mapped the field site by lidar alone ({} scans, {} landmarks, {} map elements){}.",
        a.seed,
        frames.len(),
        assoc.len(),
        map.elements().len(),
        learned.as_ref().map_or(String::new(), |c| format!(
            "; SERGE learned a {}-state calculus",
            c.n_states()
        ))
    )?;
    outln!(
        "Q-Link to landmark {goal} with nothing but the qualitative map: {verdict}, {} \
         transitions planned, {} re-plan(s), {:.0} m driven (Prop. 2 bound {:.0} m); {}.",
        outcome.plan_len,
        outcome.replans,
        outcome.length,
        outcome.bound,
        if outcome.success {
            format!(
                "picked as the longest plan that succeeds ({} run(s) tried)",
                chosen.tried
            )
        } else {
            format!(
                "none of the {} runs tried reached its goal: this is the longest plan's run",
                chosen.tried
            )
        }
    )?;
    outln!(
        "Wrote {} in {:.1} s: demo.png (the run), run.mcap (Foxglove; layout \
         docs/foxglove/qrm-layout.json), summary.json.",
        a.out.display(),
        t0.elapsed().as_secs_f64()
    )?;
    stage.commit()?;
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn write_log(
    out_dir: &Path,
    sc: &sim2d::Scenario,
    frames: &[sim2d::Frame],
    map: &QualitativeMap,
    entropy: &[(f64, f64, usize)],
    outcome: &qlink::NavOutcome,
    goal: u32,
    t_map: f64,
) -> Result<()> {
    let mut log = McapLog::robot(&out_dir.join("run.mcap"), Some((0.0, sc.lidar.max_range)))?;
    log.add_channel("/navigation", "foxglove.SceneUpdate", None)?;
    log.add_channel("/plan", "qrm.Plan", Some(PLAN_SCHEMA))?;
    log.add_channel("/map/beliefs", "qrm.MapBeliefs", Some(BELIEFS_SCHEMA))?;
    log.add_channel(
        "/controller",
        "qrm.ControllerState",
        Some(CONTROLLER_SCHEMA),
    )?;
    log.add_channel("/map/entropy", "qrm.MapEntropy", Some(ENTROPY_SCHEMA))?;
    crate::sim_cmd::write_world(&mut log, sc)?;
    for &(t, h, n) in entropy {
        log.write(
            "/map/entropy",
            t,
            &json!({"timestamp": stamp(t), "mean_entropy": h, "triplets": n}),
        )?;
    }
    for f in frames {
        crate::sim_cmd::write_frame(&mut log, f)?;
    }
    // the map's beliefs at the end of the mapping drive
    let elements: Vec<Value> = map
        .elements()
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let [x, y, z] = e.landmarks;
            let p = map.belief(i, [x, y, z]).unwrap_or_default();
            let h: f64 = p.iter().filter(|&&q| q > 0.0).map(|q| -q * q.ln()).sum();
            json!({"landmarks": e.landmarks, "calculus": map.calculus(i).name(), "states": map.calculus(i).labels(), "p": p, "entropy": h})
        })
        .collect();
    log.write(
        "/map/beliefs",
        t_map,
        &json!({"timestamp": stamp(t_map), "elements": elements}),
    )?;
    // each step of the pipeline is an event on /log, so a Foxglove user reads the story in
    // the Log panel beside the 3D view
    let event = |log: &mut McapLog, t: f64, level: u8, message: String| -> Result<()> {
        Ok(log.write(
            "/log",
            t,
            &json!({"timestamp": stamp(t), "level": level, "message": message, "name": "qrm demo", "file": "", "line": 0}),
        )?)
    };
    event(
        &mut log,
        t_map,
        2,
        format!(
            "mapped by lidar: {} frames, {} map elements",
            frames.len(),
            map.elements().len()
        ),
    )?;
    // navigation: poses, transitions, the trajectory and the plan's landmarks
    let t_nav = t_map + 1.0;
    let plan: Vec<Value> = outcome
        .transitions
        .iter()
        .map(|t| json!({"id": t.to, "landmarks": map.elements()[t.to].landmarks, "calculus": map.calculus(t.to).name()}))
        .collect();
    log.write("/plan", t_nav, &json!({"timestamp": stamp(t_nav), "goal": goal, "cost": outcome.plan_len, "elements": plan}))?;
    event(
        &mut log,
        t_nav,
        2,
        format!(
            "plan to landmark {goal}: |P| = {} elements, {} re-plan(s) on the way",
            outcome.plan_len, outcome.replans
        ),
    )?;
    // the plan in 3D: each element's triangle of landmarks, in the world frame
    let where_is: BTreeMap<u32, [f64; 2]> = sc.world.landmark_positions().collect();
    let triangles: Vec<Value> = outcome
        .transitions
        .iter()
        .filter_map(|t| {
            let pts: Vec<[f64; 2]> = map.elements()[t.to]
                .landmarks
                .iter()
                .filter_map(|id| where_is.get(id).copied())
                .collect();
            (pts.len() == 3).then(|| {
                let loop_pts: Vec<Value> = pts
                    .iter()
                    .chain(std::iter::once(&pts[0]))
                    .map(|p| json!({"x": p[0], "y": p[1], "z": 0.3}))
                    .collect();
                json!({"type": 0, "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": yaw(0.0)}, "thickness": 0.25,
                       "scale_invariant": false, "points": loop_pts, "color": {"r": 0.0, "g": 0.45, "b": 0.7, "a": 1.0}})
            })
        })
        .collect();
    log.write(
        "/navigation",
        t_nav,
        &json!({"deletions": [], "entities": [{
            "timestamp": stamp(t_nav), "frame_id": "world", "id": "plan", "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [], "spheres": [], "texts": [], "lines": triangles}]}),
    )?;
    let speed = 1.0; // m/s along the trajectory
    let mut t = t_nav;
    let mut prev = outcome.trajectory.first().copied().unwrap_or([0.0, 0.0]);
    let mut driven = 0.0;
    let mut next_transition = 0usize;
    for p in &outcome.trajectory {
        let dl = (p[0] - prev[0]).hypot(p[1] - prev[1]);
        t += dl / speed;
        driven += dl;
        let heading = (p[1] - prev[1]).atan2(p[0] - prev[0]);
        log.write(
            "/tf",
            t,
            &json!({"timestamp": stamp(t), "parent_frame_id": "world", "child_frame_id": "base_link",
                    "translation": {"x": p[0], "y": p[1], "z": 0.0}, "rotation": yaw(heading)}),
        )?;
        // controller state when a transition ends
        let mut acc: f64 = outcome.transitions[..next_transition]
            .iter()
            .map(|x| x.length)
            .sum();
        while let Some(tr) = outcome.transitions.get(next_transition) {
            if driven + 1e-9 < acc + tr.length {
                break;
            }
            acc += tr.length;
            log.write(
                "/controller",
                t,
                &json!({"timestamp": stamp(t), "from": tr.from, "to": tr.to, "link": tr.link, "commands": tr.commands, "success": tr.success, "length": tr.length}),
            )?;
            event(
                &mut log,
                t,
                if tr.success { 2 } else { 3 },
                format!(
                    "transition {} → {}: {} after {:.1} m",
                    tr.from,
                    tr.to,
                    if tr.success { "link found" } else { "failed" },
                    tr.length
                ),
            )?;
            next_transition += 1;
        }
        prev = *p;
    }
    let points: Vec<Value> = outcome
        .trajectory
        .iter()
        .map(|p| json!({"x": p[0], "y": p[1], "z": 0.2}))
        .collect();
    log.write(
        "/navigation",
        t,
        &json!({"deletions": [], "entities": [{
            "timestamp": stamp(t), "frame_id": "world", "id": "trajectory", "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [], "texts": [],
            "lines": [{"type": 0, "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": yaw(0.0)}, "thickness": 0.4, "scale_invariant": false,
                       "points": points, "color": {"r": 0.9, "g": 0.2, "b": 0.2, "a": 1.0}}]}]}),
    )?;
    log.write(
        "/log",
        t,
        &json!({"timestamp": stamp(t), "level": 2, "message": format!("navigation to landmark {goal}: {}", if outcome.success { "reached" } else { "failed" }), "name": "qrm demo", "file": "", "line": 0}),
    )?;
    Ok(log.finish()?)
}

/// Landmarks two map elements share for a link: 2, as in the thesis's field experiment
/// (§4.4.2) — with one, elements spanning the site link far-apart places in one step.
const BETA: usize = 2;

/// Most navigations the demo tries before it shows the longest run it made.
const MAX_TRIES: usize = 24;

/// Poses of the mapping drive considered as starts: every this many frames that saw three
/// landmarks.
const START_EVERY: usize = 10;

/// The rule the demo picks its run by (printed in `summary.json`).
const RUN_RULE: &str = "starts: every 10th pose of the mapping drive that saw three landmarks; \
goals: every mapped landmark out of view there; pairs tried longest plan first (ties: the \
farthest goal), the first run that reaches its goal is shown (at most 24 runs, else the longest plan's run)";

/// The run the demo shows.
struct Chosen {
    start: [f64; 2],
    goal: u32,
    outcome: qlink::NavOutcome,
    /// Navigations run to find it.
    tried: usize,
    /// Start/goal pairs with a plan.
    candidates: usize,
}

/// Picks the run by [`RUN_RULE`]: the longest plan that succeeds for the seed. With
/// `goal`, only that goal is considered.
fn choose_run(
    map: &QualitativeMap,
    graph: &LinkGraph,
    perception: &WorldPerception<'_>,
    config: &NavConfig,
    frames: &[sim2d::Frame],
    goal: Option<u32>,
) -> Result<Chosen> {
    let landmarks = map.landmarks();
    let mut pairs: Vec<(usize, f64, [f64; 2], u32)> = Vec::new();
    for f in frames
        .iter()
        .filter(|f| f.detections.len() >= 3)
        .step_by(START_EVERY)
    {
        let start = [f.pose.x, f.pose.y];
        let visible = qlink::Perception::visible(perception, start);
        let starts = map.elements_in_view(&visible);
        if starts.is_empty() {
            continue;
        }
        for &l in &landmarks {
            if goal.is_some_and(|g| g != l) || visible.contains(&l) {
                continue;
            }
            let Ok(plan) = graph.plan(map, &starts, l, &Default::default()) else {
                continue;
            };
            let Some(p) = qlink::Perception::position(perception, l) else {
                continue;
            };
            pairs.push((
                plan.len(),
                (p[0] - start[0]).hypot(p[1] - start[1]),
                start,
                l,
            ));
        }
    }
    pairs.sort_by(|x, y| {
        y.0.cmp(&x.0)
            .then(y.1.total_cmp(&x.1))
            .then(x.3.cmp(&y.3))
            .then(x.2[0].total_cmp(&y.2[0]))
            .then(x.2[1].total_cmp(&y.2[1]))
    });
    let candidates = pairs.len();
    let nav = Navigator::new(map, graph, perception, config)?;
    let mut first: Option<Chosen> = None;
    for (k, &(_, _, start, l)) in pairs.iter().take(MAX_TRIES).enumerate() {
        let outcome = nav.navigate(start, l, None, true)?;
        let run = Chosen {
            start,
            goal: l,
            outcome,
            tried: k + 1,
            candidates,
        };
        if run.outcome.success {
            return Ok(run);
        }
        first.get_or_insert(run);
    }
    match first {
        Some(mut run) => {
            run.tried = MAX_TRIES.min(candidates);
            Ok(run)
        }
        None => match goal {
            Some(g) => bail!("no pose of the mapping drive has a plan to landmark {g}"),
            None => bail!("no start/goal pair along the mapping drive has a plan"),
        },
    }
}

/// A calculus's regions on a grid over its normalised frame (A = (0, 0), B = (1, 0)).
struct Regions {
    window: [f64; 4],
    nx: usize,
    ny: usize,
    cells: Vec<u32>,
    marks: Vec<([f64; 2], String)>,
}

impl Regions {
    fn picture(&self) -> crate::plot::RegionPicture<'_> {
        crate::plot::RegionPicture {
            window: self.window,
            nx: self.nx,
            ny: self.ny,
            cell_region: &self.cells,
            points: &[],
            highlight: &[],
            shade: None,
            marks: &self.marks,
            numbers: true,
        }
    }
}

fn regions_of(c: &Calculus) -> Regions {
    let window = match c.partition() {
        qsr_core::Partition::Raster(r) => r.window(),
        qsr_core::Partition::Constraints(_) => [-2.2, 2.2, -1.6, 2.6],
    };
    let [x0, x1, y0, y1] = window;
    let nx = 160;
    let cell = (x1 - x0) / nx as f64;
    let ny = ((y1 - y0) / cell).ceil() as usize;
    let cells = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| {
                let p = qsr_core::Point2::new(
                    x0 + (i as f64 + 0.5) * cell,
                    y0 + (j as f64 + 0.5) * cell,
                );
                u32::from(c.classify_normalised(&p).0)
            })
        })
        .collect();
    Regions {
        window: [x0, x1, y0, y0 + ny as f64 * cell],
        nx,
        ny,
        cells,
        marks: vec![([0.0, 0.0], "A".into()), ([1.0, 0.0], "B".into())],
    }
}
