//! `qrm demo`: the whole pipeline in one run — simulate a robot mapping the field site with
//! its lidar, build the probabilistic qualitative map, learn a calculus with SERGE, and
//! navigate to a goal with Q-Link; write an MCAP log for Foxglove, a summary and a picture.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qlink::{
    Controller, ControllerKind, Layer, LinkGraph, NavConfig, Navigator, QualitativeMap,
    SearchPomdp, WorldPerception,
};
use qsr_core::Calculus;
use serde_json::{Value, json};
use serge::learn::{TripletObservation, triplet_beliefs};
use serge::{CellMasses, Grid, Serge, SergeParams};

use crate::output::{Staging, write_atomic};
use qrm_log::{McapLog, stamp, yaw};

/// `qrm demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Seed of the world, the sensors and the sampler.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Goal landmark (default: the nearest mapped landmark that needs a transition).
    #[arg(long)]
    pub goal: Option<u32>,
    /// Sensor range of the navigating robot (m); the mapping robot's lidar reaches 60 m, a
    /// shorter range makes the navigation use more map elements.
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
    for s in &scans {
        flip.update(s)?;
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
        .map(|l| SearchPomdp::new(l.calculus(), true, 0.9, 0.9, 4))
        .collect::<std::result::Result<_, _>>()?;
    let cost = qlink::graph::pomdp_cost(&map, &pomdps, qlink::CostModel::NegLogSuccess);
    let graph = LinkGraph::new(&map, 1, cost)?;
    if a.nav_range.is_nan() || a.nav_range <= 0.0 {
        bail!("--nav-range must be positive");
    }
    let range = a.nav_range;
    let nav_config = NavConfig {
        replan: true,
        max_replans: 3,
        map_range: sc.detector.range,
        find_goal: true,
        ..NavConfig::thesis(
            Controller::new(ControllerKind::MidpointSweep, range),
            pomdps[0].clone(),
        )
    };
    let perception = WorldPerception::new(&sc.world, range);
    // start and goal: along the mapping drive (every frame that recognised three landmarks
    // at once, in order), the first start from which some reachable landmark needs at least
    // one transition — the nearest such landmark is the goal (a short run; `--goal` picks another). (From the corridor entrance
    // the posts and bollards frame elements holding almost every landmark.)
    let plan_len = |starts: &[usize], l: u32| {
        graph
            .plan(&map, starts, l, &Default::default())
            .ok()
            .map(|p| p.len())
    };
    let pos_of = |id: u32| {
        sc.world
            .spec()
            .landmarks
            .iter()
            .find(|l| l.id == id)
            .map(|l| l.pos)
    };
    let mut choice: Option<([f64; 2], u32)> = None;
    for f in frames.iter().filter(|f| f.detections.len() >= 3) {
        let start = [f.pose.x, f.pose.y];
        let starts = map.elements_in_view(&qlink::Perception::visible(&perception, start));
        if starts.is_empty() {
            continue;
        }
        let goal = match a.goal {
            Some(g) => plan_len(&starts, g).is_some_and(|n| n >= 1).then_some(g),
            None => map
                .landmarks()
                .into_iter()
                .filter(|&l| plan_len(&starts, l).is_some_and(|n| n >= 1))
                .filter_map(|l| {
                    let p = pos_of(l)?;
                    Some((l, (p[0] - start[0]).hypot(p[1] - start[1])))
                })
                .min_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)))
                .map(|x| x.0),
        };
        if let Some(g) = goal {
            choice = Some((start, g));
            break;
        }
    }
    let (start, goal) = match (choice, a.goal) {
        (Some(c), _) => c,
        // nothing needs a transition: start where the drive began, any goal
        (None, g) => (
            [sc.start.x, sc.start.y],
            g.or_else(|| map.landmarks().last().copied())
                .context("no landmark in the map")?,
        ),
    };
    let t2 = Instant::now();
    let nav = Navigator::new(&map, &graph, &perception, &nav_config)?;
    let outcome = nav.navigate(start, goal, None, true)?;
    let t_nav = t2.elapsed().as_secs_f64();
    // 5. outputs
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let t_end_map = frames.last().map_or(0.0, |f| f.t);
    write_log(&out_dir, &sc, &frames, &map, &outcome, goal, t_end_map)?;
    if let Some(c) = &learned {
        write_atomic(
            &out_dir.join("learned_calculus.json"),
            c.spec().to_json_string()?.as_bytes(),
        )?;
    }
    let traj: Vec<(f64, f64)> = outcome.trajectory.iter().map(|p| (p[0], p[1])).collect();
    // the plan's skeleton: start → each link landmark searched for → goal landmark
    let mut chain: Vec<[f64; 2]> = vec![start];
    chain.extend(
        outcome
            .transitions
            .iter()
            .filter(|t| t.success)
            .filter_map(|t| pos_of(t.link)),
    );
    chain.extend(pos_of(goal));
    let links: Vec<crate::plot::Segment> = chain
        .windows(2)
        .map(|w| ((w[0][0], w[0][1]), (w[1][0], w[1][1])))
        .collect();
    crate::plot::scenario_map(
        &out_dir.join("demo"),
        &format!(
            "Q-Link to landmark {goal}: {} ({} transitions, {:.0} m)",
            if outcome.success { "reached" } else { "failed" },
            outcome.transitions.len(),
            outcome.length
        ),
        sc.world.spec(),
        &traj,
        &links,
    )?;
    let summary = json!({
        "seed": a.seed,
        "scenario": "field",
        "frames": frames.len(),
        "recognised_landmarks": assoc.len(),
        "map_elements": map.elements().len(),
        "link_graph_edges": graph.n_edges(),
        "learned_calculus_states": learned.as_ref().map(Calculus::n_states),
        "goal": goal,
        "success": outcome.success,
        "failure": outcome.failure,
        "plan_len": outcome.plan_len,
        "replans": outcome.replans,
        "trajectory_length": outcome.length,
        "prop2_bound": outcome.bound,
        "prop4_bound": outcome.bound_direct,
        "transitions": outcome.transitions,
        "seconds": {"simulate": t_sim, "serge": t_serge, "navigate": t_nav, "total": t0.elapsed().as_secs_f64()},
    });
    write_atomic(
        &out_dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    outln!("qrm demo (seed {}):", a.seed)?;
    outln!(
        "  mapped the field site with the lidar: {} frames, {} landmarks recognised, {} map elements",
        frames.len(),
        assoc.len(),
        map.elements().len()
    )?;
    if let Some(c) = &learned {
        outln!(
            "  SERGE learned a calculus with {} states from {} triplets ({t_serge:.1} s)",
            c.n_states(),
            triplets.len()
        )?;
    }
    outln!(
        "  Q-Link to landmark {goal}: {} — |P| = {}, {} re-plans, {:.1} m driven (Prop. 2 bound {:.0} m)",
        if outcome.success {
            "reached"
        } else {
            "not reached"
        },
        outcome.plan_len,
        outcome.replans,
        outcome.length,
        outcome.bound
    )?;
    outln!(
        "  wrote {} (open run.mcap in Foxglove) in {:.1} s",
        a.out.display(),
        t0.elapsed().as_secs_f64()
    )?;
    stage.commit()?;
    Ok(())
}

fn write_log(
    out_dir: &Path,
    sc: &sim2d::Scenario,
    frames: &[sim2d::Frame],
    map: &QualitativeMap,
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
    crate::sim_cmd::write_world(&mut log, sc)?;
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
    let where_is: BTreeMap<u32, [f64; 2]> = sc
        .world
        .spec()
        .landmarks
        .iter()
        .map(|l| (l.id, l.pos))
        .collect();
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
