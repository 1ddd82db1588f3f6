//! Writing MCAP logs that open in Foxglove: well-known Foxglove schemas in JSON encoding where
//! one fits, and our own documented JSON schemas for the rest.
//!
//! | topic | schema | what |
//! |---|---|---|
//! | `/scan` | `foxglove.LaserScan` | lidar scans in the robot frame `base_link`; channel metadata `range_min`/`range_max` |
//! | `/world` | `foxglove.SceneUpdate` | landmarks (cylinders), walls (lines), clutter, once at t = 0 |
//! | `/tf` | `foxglove.FrameTransform` | the true robot pose, `world` → `base_link` |
//! | `/log` | `foxglove.Log` | events |
//! | `/detections` | `qrm.LandmarkDetections` | detections: id, x, y, covariance (robot frame), exact time `t` |
//! | `/detections/scene` | `foxglove.SceneUpdate` | the same detections drawn in 3D: a sphere per landmark (2σ wide) and its id, in `base_link` |
//!
//! Time stamps are simulated (or recorded) time. The writer emits chunks of at most 256 KiB as
//! it goes, so a run killed midway leaves a file readable up to its last finished chunk
//! ([`crate::ReadOptions::allowing_truncated`]).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Cursor, Seek, Write};
use std::path::Path;

use crate::error::{LogError, Result};
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
    }}},
    "t": {"type": "number", "description": "exact time (s), when the timestamp would round it"}
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
                   // null: a beam without return (JSON has no infinity); the schema says so
                   // (issue 40: it declared numbers, and every /scan message broke it)
                   "ranges": {"type": "array", "items": {"type": ["number", "null"]},
                              "description": "m; null: no return"},
                   "intensities": {"type": "array", "items": {"type": ["number", "null"]}}}),
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
                "cylinders": {"type": "array"}, "spheres": {"type": "array"}, "lines": {"type": "array"}, "texts": {"type": "array"}}}}}),
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

/// An MCAP log being written: to a file ([`McapLog::create`], the default sink) or to memory
/// ([`McapLog::in_memory`], for a library that hands the bytes to a front end to save).
pub struct McapLog<W: Write + Seek = BufWriter<File>> {
    writer: mcap::Writer<W>,
    /// The file, or what the bytes are, for error messages.
    path: std::path::PathBuf,
    channels: BTreeMap<String, u16>,
    sequence: u32,
}

impl McapLog {
    /// Creates an empty log at `path` (channels are added with [`McapLog::add_channel`]).
    ///
    /// # Errors
    /// [`LogError::Io`] when the file cannot be created, [`LogError::Write`].
    pub fn create(path: &Path) -> Result<Self> {
        let file = File::create(path).map_err(|source| LogError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        McapLog::on(BufWriter::new(file), path)
    }

    /// Creates a log at `path` with the channels of a simulated robot (`/scan`, `/world`,
    /// `/tf`, `/log`, `/detections`). `lidar_range` (min, max, m) goes into the `/scan`
    /// channel's metadata (`range_min`, `range_max`), so a reader knows which ranges mean
    /// "no return".
    ///
    /// # Errors
    /// As [`McapLog::create`].
    pub fn robot(path: &Path, lidar_range: Option<(f64, f64)>) -> Result<Self> {
        Self::create(path)?.with_robot_channels(lidar_range)
    }
}

impl McapLog<Cursor<Vec<u8>>> {
    /// Creates an empty log in memory; `name` stands for it in error messages. The same
    /// messages give the same bytes as [`McapLog::create`] writes to a file.
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn in_memory(name: &str) -> Result<Self> {
        McapLog::on(Cursor::new(Vec::new()), Path::new(name))
    }

    /// Writes the summary and returns the log's bytes.
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn into_bytes(mut self) -> Result<Vec<u8>> {
        self.close()?;
        Ok(self.writer.into_inner().into_inner())
    }
}

impl<W: Write + Seek> McapLog<W> {
    /// A log written to `sink` (uncompressed chunks of at most 256 KiB).
    fn on(sink: W, path: &Path) -> Result<Self> {
        let writer = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(256 * 1024))
            .profile("")
            .create(sink)
            .map_err(|source| LogError::Write {
                path: path.to_path_buf(),
                source,
            })?;
        Ok(Self {
            writer,
            path: path.to_path_buf(),
            channels: BTreeMap::new(),
            sequence: 0,
        })
    }

    /// Adds the channels of a simulated robot (see [`McapLog::robot`]).
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn with_robot_channels(self, lidar_range: Option<(f64, f64)>) -> Result<Self> {
        let mut log = self;
        let mut scan_meta = BTreeMap::new();
        if let Some((lo, hi)) = lidar_range {
            scan_meta.insert("range_min".to_owned(), lo.to_string());
            scan_meta.insert("range_max".to_owned(), hi.to_string());
        }
        log.add_channel_with_metadata("/scan", "foxglove.LaserScan", None, &scan_meta)?;
        for (topic, schema_name) in [
            ("/world", "foxglove.SceneUpdate"),
            ("/tf", "foxglove.FrameTransform"),
            ("/log", "foxglove.Log"),
        ] {
            log.add_channel(topic, schema_name, None)?;
        }
        log.add_channel(
            "/detections",
            "qrm.LandmarkDetections",
            Some(DETECTIONS_SCHEMA),
        )?;
        log.add_channel("/detections/scene", "foxglove.SceneUpdate", None)?;
        Ok(log)
    }

    /// Registers a channel: `schema_name` is a Foxglove well-known schema
    /// (`foxglove.SceneUpdate`, …) when `schema` is `None`, else our own JSON Schema text.
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn add_channel(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema: Option<&str>,
    ) -> Result<()> {
        self.add_channel_with_metadata(topic, schema_name, schema, &BTreeMap::new())
    }

    /// As [`McapLog::add_channel`], with channel metadata (e.g. `robot`, `range_max`).
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn add_channel_with_metadata(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema: Option<&str>,
        metadata: &BTreeMap<String, String>,
    ) -> Result<()> {
        let text = schema.map_or_else(|| foxglove_schema(schema_name), str::to_owned);
        let path = &self.path;
        let err = |source| LogError::Write {
            path: path.clone(),
            source,
        };
        let sid = self
            .writer
            .add_schema(schema_name, "jsonschema", text.as_bytes())
            .map_err(err)?;
        let cid = self
            .writer
            .add_channel(sid, topic, "json", metadata)
            .map_err(err)?;
        self.channels.insert(topic.to_owned(), cid);
        Ok(())
    }

    /// Writes a metadata record (e.g. [`crate::TRUTH_METADATA`]).
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn add_metadata(&mut self, name: &str, metadata: BTreeMap<String, String>) -> Result<()> {
        self.writer
            .write_metadata(&mcap::records::Metadata {
                name: name.to_owned(),
                metadata,
            })
            .map_err(|source| LogError::Write {
                path: self.path.clone(),
                source,
            })
    }

    /// Writes one JSON message at time `t` (s).
    ///
    /// # Errors
    /// [`LogError::Invalid`] for a topic without a channel, [`LogError::Write`].
    pub fn write(&mut self, topic: &str, t: f64, message: &Value) -> Result<()> {
        let channel_id = *self
            .channels
            .get(topic)
            .ok_or_else(|| LogError::Invalid(format!("no channel {topic}")))?;
        let ns = (t.max(0.0) * 1e9).round() as u64;
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: ns,
            publish_time: ns,
        };
        self.writer
            .write_to_known_channel(&header, message.to_string().as_bytes())
            .map_err(|source| LogError::Write {
                path: self.path.clone(),
                source,
            })
    }

    /// Writes the summary and closes the file.
    ///
    /// # Errors
    /// [`LogError::Write`].
    pub fn finish(mut self) -> Result<()> {
        self.close()
    }

    fn close(&mut self) -> Result<()> {
        self.writer.finish().map_err(|source| LogError::Write {
            path: self.path.clone(),
            source,
        })?;
        Ok(())
    }
}
