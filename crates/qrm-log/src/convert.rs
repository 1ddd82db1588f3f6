//! A recording (any [`Dataset`]: CSV, MRCLAM, g2o) written as MCAP: one
//! `qrm.LandmarkDetections` topic per robot (`/robot{N}/detections`, channel metadata
//! `robot = N`), the surveyed landmarks as a `foxglove.SceneUpdate` on `/world` and as the
//! [`TRUTH_METADATA`] record, and an event on `/log`. Read back with [`crate::read_mcap`], it
//! gives the same scans bit for bit (exact times in `t`, numbers in shortest round-trip form).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use pqrm::loaders::Dataset;
use serde_json::json;

use crate::error::Result;
use crate::read::TRUTH_METADATA;
use crate::write::{DETECTIONS_SCHEMA, McapLog, stamp, yaw};

/// Writes `data` to `path` as MCAP; `source` names the recording in the `/log` event.
///
/// # Errors
/// As [`McapLog`].
pub fn write_dataset(path: &Path, data: &Dataset, source: &str) -> Result<()> {
    let mut log = McapLog::create(path)?;
    let robots: BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
    for r in &robots {
        let meta = BTreeMap::from([("robot".to_owned(), r.to_string())]);
        log.add_channel_with_metadata(
            &format!("/robot{r}/detections"),
            "qrm.LandmarkDetections",
            Some(DETECTIONS_SCHEMA),
            &meta,
        )?;
    }
    log.add_channel("/world", "foxglove.SceneUpdate", None)?;
    log.add_channel("/log", "foxglove.Log", None)?;
    let t0 = data.scans.first().map_or(0.0, |s| s.t);
    if let Some(truth) = &data.truth {
        let meta = truth
            .positions
            .iter()
            .map(|(id, p)| (id.0.to_string(), format!("{},{}", p[0], p[1])))
            .collect();
        log.add_metadata(TRUTH_METADATA, meta)?;
        let entities: Vec<_> = truth.positions.iter().map(|(id, p)| json!({
            "timestamp": stamp(t0), "frame_id": "world", "id": format!("landmark-{}", id.0), "lifetime": stamp(0.0), "frame_locked": false,
            "cylinders": [{"pose": {"position": {"x": p[0], "y": p[1], "z": 0.5}, "orientation": yaw(0.0)},
                           "size": {"x": 0.3, "y": 0.3, "z": 1.0}, "bottom_scale": 1.0, "top_scale": 1.0,
                           "color": {"r": 0.1, "g": 0.5, "b": 0.2, "a": 1.0}}],
            "texts": [{"pose": {"position": {"x": p[0], "y": p[1], "z": 1.2}, "orientation": yaw(0.0)}, "billboard": true,
                       "font_size": 12.0, "scale_invariant": true, "color": {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0}, "text": id.0.to_string()}],
            "lines": []
        })).collect();
        log.write(
            "/world",
            t0,
            &json!({"deletions": [], "entities": entities}),
        )?;
    }
    for s in &data.scans {
        let dets: Vec<_> = s
            .observations
            .iter()
            .map(|o| json!({"id": o.id.0, "x": o.mean[0], "y": o.mean[1], "cov": [o.cov[0][0], o.cov[0][1], o.cov[1][1]]}))
            .collect();
        log.write(
            &format!("/robot{}/detections", s.robot),
            s.t,
            &json!({"timestamp": stamp(s.t), "t": s.t, "frame_id": format!("robot{}", s.robot), "detections": dets}),
        )?;
    }
    let t_end = data.scans.last().map_or(0.0, |s| s.t);
    log.write(
        "/log",
        t_end,
        &json!({"timestamp": stamp(t_end), "level": 2, "name": "qrm convert", "file": "", "line": 0,
                "message": format!("{source}: {} scans of {} robots", data.scans.len(), robots.len())}),
    )?;
    log.finish()
}
