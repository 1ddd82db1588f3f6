//! The demo's MCAP log for Foxglove: the mapping drive as `qrm sim` logs a run (world, poses,
//! detections, scans), the map's entropy as it mapped and its beliefs at the end, then the
//! navigation — the plan in 3D, the pose along the trajectory, each transition on
//! `/controller` — with every step of the pipeline an event on `/log`, so a Foxglove user
//! reads the story in the Log panel beside the 3D view (layout: `docs/foxglove/qrm-layout.json`).

use std::collections::BTreeMap;
use std::io::Cursor;

use qlink::{NavOutcome, QualitativeMap};
use qrm_log::{McapLog, stamp, yaw};
use serde_json::{Value, json};

use super::pipeline::EntropyPoint;
use crate::error::Result;

/// What the log tells.
pub struct Run<'a> {
    /// The simulated site.
    pub scenario: &'a sim2d::Scenario,
    /// The mapping drive.
    pub frames: &'a [sim2d::Frame],
    /// The map at the end of the drive.
    pub map: &'a QualitativeMap,
    /// Mean entropy after each scan.
    pub entropy: &'a [EntropyPoint],
    /// The navigation shown.
    pub outcome: &'a NavOutcome,
    /// Its goal.
    pub goal: u32,
}

type Log = McapLog<Cursor<Vec<u8>>>;

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

/// Speed the trajectory is replayed at (m/s).
const SPEED: f64 = 1.0;

/// The log's bytes.
///
/// # Errors
/// [`crate::StudyError::Log`] (writing to memory fails only on a bad channel).
pub fn write(run: &Run<'_>) -> Result<Vec<u8>> {
    let sc = run.scenario;
    let mut log =
        McapLog::in_memory("run.mcap")?.with_robot_channels(Some((0.0, sc.lidar.max_range)))?;
    log.add_channel("/navigation", "foxglove.SceneUpdate", None)?;
    log.add_channel("/plan", "qrm.Plan", Some(PLAN_SCHEMA))?;
    log.add_channel("/map/beliefs", "qrm.MapBeliefs", Some(BELIEFS_SCHEMA))?;
    log.add_channel(
        "/controller",
        "qrm.ControllerState",
        Some(CONTROLLER_SCHEMA),
    )?;
    log.add_channel("/map/entropy", "qrm.MapEntropy", Some(ENTROPY_SCHEMA))?;
    let t_map = run.frames.last().map_or(0.0, |f| f.t);
    write_mapping(&mut log, run, t_map)?;
    let t_nav = t_map + 1.0;
    write_plan(&mut log, run, t_nav)?;
    let t_end = write_drive(&mut log, run.outcome, t_nav)?;
    event(
        &mut log,
        t_end,
        2,
        format!(
            "navigation to landmark {}: {}",
            run.goal,
            if run.outcome.success {
                "reached"
            } else {
                "failed"
            }
        ),
    )?;
    Ok(log.into_bytes()?)
}

/// An event on `/log`.
fn event(log: &mut Log, t: f64, level: u8, message: String) -> Result<()> {
    Ok(log.write(
        "/log",
        t,
        &json!({"timestamp": stamp(t), "level": level, "message": message, "name": "qrm demo", "file": "", "line": 0}),
    )?)
}

/// The world, the entropy as it mapped, every frame, and the beliefs at the end of the drive.
fn write_mapping(log: &mut Log, run: &Run<'_>, t_map: f64) -> Result<()> {
    log.write_world(&run.scenario.name, run.scenario.world.spec())?;
    for &(t, h, n) in run.entropy {
        log.write(
            "/map/entropy",
            t,
            &json!({"timestamp": stamp(t), "mean_entropy": h, "triplets": n}),
        )?;
    }
    for f in run.frames {
        log.write_frame(f)?;
    }
    let map = run.map;
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
    event(
        log,
        t_map,
        2,
        format!(
            "mapped by lidar: {} frames, {} map elements",
            run.frames.len(),
            map.elements().len()
        ),
    )
}

/// The plan on `/plan`, an event, and its elements' triangles of landmarks in 3D.
fn write_plan(log: &mut Log, run: &Run<'_>, t_nav: f64) -> Result<()> {
    let (map, outcome) = (run.map, run.outcome);
    let plan: Vec<Value> = outcome
        .transitions
        .iter()
        .map(|t| json!({"id": t.to, "landmarks": map.elements()[t.to].landmarks, "calculus": map.calculus(t.to).name()}))
        .collect();
    log.write(
        "/plan",
        t_nav,
        &json!({"timestamp": stamp(t_nav), "goal": run.goal, "cost": outcome.plan_len, "elements": plan}),
    )?;
    event(
        log,
        t_nav,
        2,
        format!(
            "plan to landmark {}: |P| = {} elements, {} re-plan(s) on the way",
            run.goal, outcome.plan_len, outcome.replans
        ),
    )?;
    let where_is: BTreeMap<u32, [f64; 2]> = run.scenario.world.landmark_positions().collect();
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
    Ok(log.write(
        "/navigation",
        t_nav,
        &json!({"deletions": [], "entities": [{
            "timestamp": stamp(t_nav), "frame_id": "world", "id": "plan", "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [], "spheres": [], "texts": [], "lines": triangles}]}),
    )?)
}

/// The pose along the trajectory at [`SPEED`], each transition on `/controller` (and an
/// event) when the distance driven reaches its end, then the whole trajectory in 3D. Returns
/// the time the drive ends.
fn write_drive(log: &mut Log, outcome: &NavOutcome, t_nav: f64) -> Result<f64> {
    let mut t = t_nav;
    let mut prev = outcome.trajectory.first().copied().unwrap_or([0.0, 0.0]);
    let mut driven = 0.0;
    let mut next_transition = 0usize;
    for p in &outcome.trajectory {
        let dl = (p[0] - prev[0]).hypot(p[1] - prev[1]);
        t += dl / SPEED;
        driven += dl;
        let heading = (p[1] - prev[1]).atan2(p[0] - prev[0]);
        log.write(
            "/tf",
            t,
            &json!({"timestamp": stamp(t), "parent_frame_id": "world", "child_frame_id": "base_link",
                    "translation": {"x": p[0], "y": p[1], "z": 0.0}, "rotation": yaw(heading)}),
        )?;
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
                log,
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
    Ok(t)
}
