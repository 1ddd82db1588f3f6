//! # qrm-log — robot logs in and out of qrm
//!
//! A robot developer's recording is a ROS 2 bag (MCAP is `ros2 bag record`'s default storage)
//! or a Foxglove MCAP, not our CSV. This crate reads them into PQRM [`Scan`](pqrm::Scan)s and
//! writes qrm's own runs and converted recordings as MCAP that Foxglove opens.
//!
//! ## Why a crate of its own
//! Logs are I/O with their own failure modes (a truncated chunk, a schema nobody can read, a
//! topic that is not there) and their own dependencies (`mcap`, pure-Rust zstd/lz4 chunk
//! decoders ([`decompress`]), a CDR decoder for ROS 2 messages). Keeping them here lets the
//! mapper stay free of them and lets the CLI, the Python wheel and the fuzz targets share one
//! reader.
//!
//! ## What is read
//! | schema (encoding) | from | becomes |
//! |---|---|---|
//! | `sensor_msgs/msg/LaserScan` (`ros2msg`, CDR) | `ros2 bag record` | landmarks extracted from the returns and recognised by triangles (no ids needed) |
//! | `foxglove.LaserScan` (JSON) | `qrm sim`, Foxglove tools | the same |
//! | `qrm.LandmarkDetections` (JSON) | `qrm sim`, `qrm convert` | observations straight to the filter, with their ids and covariances |
//!
//! Scans are brought to one canonical form (`f32` ranges and angle increment, see [`decode`])
//! so the same scan from a ROS 2 bag and from a Foxglove log gives bit-identical landmarks.
//! Returns outside `[range_min, range_max]` (from the message, the channel metadata, or
//! [`ReadOptions`]) are no return. The scanner's mounting pose is ignored: qualitative
//! relations between landmarks do not change under a rigid motion of the sensor frame.
//!
//! ## Naming rule
//! `read_*` takes a file or bytes and returns a [`Recording`]; `write_*` and [`McapLog`] write
//! MCAP; [`Kind`] names what can be read; [`LogError`] says what went wrong, always naming the
//! file and, for one message, the topic, the message's index on it and the field.
//!
//! ## Errors
//! | variant | when |
//! |---|---|
//! | `Io` | the file cannot be read or created, is a directory or a device, is beyond [`MAX_LOG_BYTES`] |
//! | `Damaged` | not MCAP, a truncated or corrupt chunk (with the messages read before it and the topics seen) |
//! | (in `Damaged`) | a record longer than [`MAX_RECORD_BYTES`] (refused before allocating: a corrupt length is not an abort) |
//! | `MissingTopic` | a `--topic` that is not in the file (with the topics present) |
//! | `UnsupportedSchema` | a topic whose schema qrm cannot read (with what it can) |
//! | `ChooseTopic` | no readable topic, several scan topics, scans mixed with detections |
//! | `Message` | a message that does not decode or holds an impossible value (field named) |
//! | `Observation` | a detection that is not valid PQRM input (covariance, repeated landmark) |
//! | `Write`, `Invalid` | writing failed; a bad setting |
//!
//! ```
//! use qrm_log::{read_mcap_bytes, write_dataset, ReadOptions};
//! use pqrm::{loaders::Dataset, LandmarkId, Observation, Scan};
//!
//! let obs = |id, x, y| Observation::isotropic(LandmarkId(id), [x, y], 0.1);
//! let data = Dataset {
//!     scans: vec![Scan::new(0.5, 1, vec![obs(1, 2.0, 0.0)?, obs(2, 3.0, 1.0)?, obs(3, 1.0, -2.0)?])?],
//!     truth: None,
//!     skipped: 0,
//! };
//! let path = std::env::temp_dir().join(format!("qrm-log-doc-{}.mcap", std::process::id()));
//! write_dataset(&path, &data, "example")?;
//! let back = read_mcap_bytes(&std::fs::read(&path)?, &path, &ReadOptions::default())?;
//! assert_eq!(back.dataset.scans, data.scans);
//! std::fs::remove_file(&path)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod convert;
pub mod decode;
pub mod decompress;
mod error;
mod kind;
mod read;
mod simulated;
mod write;

pub use convert::write_dataset;
pub use error::{LogError, Result};
pub use kind::{Kind, READABLE};
pub use read::{
    LidarSettings, MAX_CANDIDATES, MAX_LOG_BYTES, MAX_RECORD_BYTES, ReadOptions, Recording,
    TRUTH_METADATA, TopicInfo, read_mcap, read_mcap_bytes,
};
pub use write::{DETECTIONS_SCHEMA, McapLog, stamp, yaw};
