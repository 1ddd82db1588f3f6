//! MCAP logs that open in Foxglove: well-known Foxglove schemas in JSON encoding where one
//! fits, and our own documented JSON schemas for the rest.
//!
//! | topic | schema | what |
//! |---|---|---|
//! | `/scan` | `foxglove.LaserScan` | lidar scans in the robot frame `base_link` |
//! | `/world` | `foxglove.SceneUpdate` | landmarks (cylinders), walls (lines), clutter, once at t = 0 |
//! | `/tf` | `foxglove.FrameTransform` | the true robot pose, `world` → `base_link` |
//! | `/log` | `foxglove.Log` | events |
//! | `/detections` | `qrm.LandmarkDetections` | ideal detections: id, x, y, covariance (robot frame) |
//!
//! Time stamps are simulated time. The writer emits chunks of at most 256 KiB as it goes, so
//! a run killed midway leaves a file readable up to its last finished chunk.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{Context, Result};
use serde_json::{Value, json};

/// JSON Schema of `qrm.LandmarkDetections` (documented here and in docs/logs.md).
pub const DETECTIONS_SCHEMA: &str = r#"{
  "title": "qrm.LandmarkDetections",
  "description": "Landmarks detected at one time step, in the robot frame (x forward, y left), with the detector's covariance",
  "type": "object",
  "properties": {
    "timestamp": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
    "frame_id": {"type": "string"},
    "detections": {"type": "array", "items": {"type": "object", "properties": {
      "id": {"type": "integer", "description": "landmark id"},
      "x": {"type": "number", "description": "m"},
      "y": {"type": "number", "description": "m"},
      "cov": {"type": "array", "items": {"type": "number"}, "description": "[cxx, cxy, cyy] in m²"}
    }}}
  }
}"#;

fn schema(title: &str, properties: Value) -> String {
    json!({"title": title, "type": "object", "properties": properties}).to_string()
}

fn time_props() -> Value {
    json!({"type": "object", "properties": {"sec": {"type": "integer", "minimum": 0}, "nsec": {"type": "integer", "minimum": 0}}})
}

fn vec3() -> Value {
    json!({"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}})
}

fn quat() -> Value {
    json!({"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}}})
}

fn pose() -> Value {
    json!({"type": "object", "properties": {"position": vec3(), "orientation": quat()}})
}

/// The JSON Schemas of the Foxglove messages we write (the fields we use).
fn foxglove_schema(name: &str) -> String {
    match name {
        "foxglove.LaserScan" => schema(
            name,
            json!({"timestamp": time_props(), "frame_id": {"type": "string"}, "pose": pose(),
                   "start_angle": {"type": "number"}, "end_angle": {"type": "number"},
                   "ranges": {"type": "array", "items": {"type": "number"}},
                   "intensities": {"type": "array", "items": {"type": "number"}}}),
        ),
        "foxglove.FrameTransform" => schema(
            name,
            json!({"timestamp": time_props(), "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
                   "translation": vec3(), "rotation": quat()}),
        ),
        "foxglove.Log" => schema(
            name,
            json!({"timestamp": time_props(), "level": {"type": "integer"}, "message": {"type": "string"},
                   "name": {"type": "string"}, "file": {"type": "string"}, "line": {"type": "integer"}}),
        ),
        _ => schema(
            name,
            json!({"deletions": {"type": "array"}, "entities": {"type": "array", "items": {"type": "object", "properties": {
                "timestamp": time_props(), "frame_id": {"type": "string"}, "id": {"type": "string"},
                "lifetime": time_props(), "frame_locked": {"type": "boolean"},
                "cylinders": {"type": "array"}, "lines": {"type": "array"}, "texts": {"type": "array"}}}}}),
        ),
    }
}

/// `{sec, nsec}` of a time in seconds.
pub fn stamp(t: f64) -> Value {
    let t = t.max(0.0);
    json!({"sec": t.floor() as u64, "nsec": ((t - t.floor()) * 1e9).round().min(999_999_999.0) as u64})
}

/// A quaternion for a rotation `theta` about z.
pub fn yaw(theta: f64) -> Value {
    json!({"x": 0.0, "y": 0.0, "z": (theta / 2.0).sin(), "w": (theta / 2.0).cos()})
}

/// An MCAP file being written.
pub struct McapLog {
    writer: mcap::Writer<BufWriter<File>>,
    channels: BTreeMap<String, u16>,
    sequence: u32,
}

impl McapLog {
    /// Creates the file and registers the channels.
    pub fn create(path: &Path) -> Result<Self> {
        let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let mut writer = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(256 * 1024))
            .profile("")
            .create(BufWriter::new(file))
            .context("starting the MCAP file")?;
        let mut channels = BTreeMap::new();
        for (topic, schema_name) in [
            ("/scan", "foxglove.LaserScan"),
            ("/world", "foxglove.SceneUpdate"),
            ("/tf", "foxglove.FrameTransform"),
            ("/log", "foxglove.Log"),
        ] {
            let sid = writer.add_schema(
                schema_name,
                "jsonschema",
                foxglove_schema(schema_name).as_bytes(),
            )?;
            channels.insert(
                topic.to_owned(),
                writer.add_channel(sid, topic, "json", &BTreeMap::new())?,
            );
        }
        let sid = writer.add_schema(
            "qrm.LandmarkDetections",
            "jsonschema",
            DETECTIONS_SCHEMA.as_bytes(),
        )?;
        channels.insert(
            "/detections".into(),
            writer.add_channel(sid, "/detections", "json", &BTreeMap::new())?,
        );
        Ok(Self {
            writer,
            channels,
            sequence: 0,
        })
    }

    /// Registers another channel: `schema_name` is a Foxglove well-known schema
    /// (`foxglove.SceneUpdate`, …) when `schema` is `None`, else our own JSON Schema text.
    pub fn add_channel(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema: Option<&str>,
    ) -> Result<()> {
        let text = schema.map_or_else(|| foxglove_schema(schema_name), str::to_owned);
        let sid = self
            .writer
            .add_schema(schema_name, "jsonschema", text.as_bytes())?;
        let cid = self
            .writer
            .add_channel(sid, topic, "json", &BTreeMap::new())?;
        self.channels.insert(topic.to_owned(), cid);
        Ok(())
    }

    /// Writes one JSON message at simulated time `t` (s).
    pub fn write(&mut self, topic: &str, t: f64, message: &Value) -> Result<()> {
        let channel_id = *self
            .channels
            .get(topic)
            .with_context(|| format!("no channel {topic}"))?;
        let ns = (t.max(0.0) * 1e9).round() as u64;
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: ns,
            publish_time: ns,
        };
        self.writer
            .write_to_known_channel(&header, message.to_string().as_bytes())?;
        Ok(())
    }

    /// Writes the summary and closes the file.
    pub fn finish(mut self) -> Result<()> {
        self.writer.finish().context("finishing the MCAP file")?;
        Ok(())
    }
}
