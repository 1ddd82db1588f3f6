//! [`LogError`]: what can go wrong reading or writing a robot log, naming the file, the topic,
//! the message and the field.

use std::path::PathBuf;

/// Errors of this crate. Every variant names the file; those about one message name the topic,
/// the message's 1-based index on that topic and the field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LogError {
    /// The file could not be read or written.
    #[error("{path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The MCAP structure is broken: not an MCAP file, a truncated chunk, a bad record.
    #[error(
        "{path}: not a readable MCAP file after {messages} messages (truncated or damaged; topics seen: {present})"
    )]
    Damaged {
        /// The file.
        path: PathBuf,
        /// Messages read before the damage.
        messages: usize,
        /// Topics and schemas declared before the damage.
        present: String,
        /// The MCAP reader's error.
        #[source]
        source: mcap::McapError,
    },
    /// A topic asked for is not in the file.
    #[error("{path}: no topic {topic}; topics present: {present}")]
    MissingTopic {
        /// The file.
        path: PathBuf,
        /// The topic asked for.
        topic: String,
        /// Topics and schemas present.
        present: String,
    },
    /// A topic asked for carries a schema this crate cannot read.
    #[error(
        "{path}: topic {topic} has schema {schema}, which qrm cannot read; readable: {readable}; topics present: {present}"
    )]
    UnsupportedSchema {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// Its schema name and encodings, as `` `name` (schema/message encoding) ``.
        schema: String,
        /// What can be read.
        readable: &'static str,
        /// Topics and schemas present.
        present: String,
    },
    /// No topic was named and the choice is not clear.
    #[error("{path}: {reason}; topics present: {present}")]
    ChooseTopic {
        /// The file.
        path: PathBuf,
        /// Why no topic could be chosen (none readable, several scan topics, scans and detections mixed).
        reason: String,
        /// Topics and schemas present.
        present: String,
    },
    /// A message could not be decoded or holds an impossible value.
    #[error("{path}: topic {topic}, message {index}, field `{field}`: {reason}")]
    Message {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// 1-based index of the message on its topic.
        index: usize,
        /// The field (dotted path).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A message's observations are not valid PQRM input (bad covariance, repeated landmark).
    #[error("{path}: topic {topic}, message {index}")]
    Observation {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// 1-based index of the message on its topic.
        index: usize,
        /// The validation error (boxed: it is large and rare).
        #[source]
        source: Box<pqrm::PqrmError>,
    },
    /// Writing MCAP failed.
    #[error("{path}: writing MCAP")]
    Write {
        /// The file.
        path: PathBuf,
        /// The MCAP writer's error.
        #[source]
        source: mcap::McapError,
    },
    /// A value given to the writer or reader settings is out of range.
    #[error("invalid setting: {0}")]
    Invalid(String),
}

/// Shorthand for results of this crate.
pub type Result<T, E = LogError> = std::result::Result<T, E>;
