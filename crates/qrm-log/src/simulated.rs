//! A simulated run in a log: the world once at t = 0, then every frame — what `qrm sim` and
//! the demo write, so the two logs read alike in Foxglove.

use std::io::{Seek, Write};

use serde_json::json;

use crate::error::Result;
use crate::write::{McapLog, stamp, yaw};

impl<W: Write + Seek> McapLog<W> {
    /// The world (landmarks, walls, clutter) on `/world` and a start event on `/log`, at t = 0.
    ///
    /// # Errors
    /// [`crate::LogError::Write`].
    pub fn write_world(&mut self, scenario: &str, spec: &sim2d::WorldSpec) -> Result<()> {
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
        self.write(
            "/world",
            0.0,
            &json!({"deletions": [], "entities": entities}),
        )?;
        self.write("/log", 0.0, &json!({"timestamp": stamp(0.0), "level": 2, "message": format!("scenario {scenario} started"), "name": "qrm sim", "file": "", "line": 0}))?;
        Ok(())
    }

    /// One frame: the pose on `/tf`, the detections, the scan.
    ///
    /// # Errors
    /// [`crate::LogError::Write`].
    pub fn write_frame(&mut self, f: &sim2d::Frame) -> Result<()> {
        {
            self.write(
                "/tf",
                f.t,
                &json!({"timestamp": stamp(f.t), "parent_frame_id": "world", "child_frame_id": "base_link",
                        "translation": {"x": f.pose.x, "y": f.pose.y, "z": 0.0}, "rotation": yaw(f.pose.theta)}),
            )?;
            let dets: Vec<_> = f.detections.iter().map(|d| json!({"id": d.id, "x": d.xy[0], "y": d.xy[1], "cov": [d.cov[0][0], d.cov[0][1], d.cov[1][1]]})).collect();
            self.write(
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
            self.write(
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
                self.write(
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
}
