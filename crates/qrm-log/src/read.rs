//! Reading an MCAP file (a ROS 2 bag, a Foxglove log, a `qrm sim` run) into PQRM scans.
//!
//! One pass over the messages keeps the raw bytes of every readable channel; the topics are
//! chosen (named ones, else every detection topic, else the one scan topic); then each message
//! is decoded. Detections become [`Scan`]s directly. Lidar scans go, in time order, through the
//! landmark extractor and the triangle recogniser of `sim2d` (no ids needed; the ids are the
//! recogniser's own, so a surveyed truth in the file does not apply to them). Scans that saw
//! nothing are dropped: they carry no evidence.

use std::collections::BTreeMap;
use std::path::Path;

use pqrm::loaders::Dataset;
use pqrm::{GroundTruth, LandmarkId, Observation, Scan};

use mcap::records::Record;

use crate::decode::{Decoded, decode};
use crate::error::{LogError, Result};
use crate::kind::{Kind, READABLE};

/// The largest log read into memory (8 GiB; a bag beyond that is split with `ros2 bag convert`).
pub const MAX_LOG_BYTES: u64 = 8 << 30;

/// The most landmark candidates one scan may give: the recogniser's work grows with the cube
/// of their number, and a scan with more is not a landmark scene.
pub const MAX_CANDIDATES: usize = 256;

/// The longest record read (256 MiB; a LaserScan is kilobytes, an image megabytes). The MCAP
/// reader allocates a record's declared length before reading it, so without this bound a
/// corrupt length field would abort the process.
pub const MAX_RECORD_BYTES: usize = 256 << 20;

/// Metadata record holding surveyed landmark positions (`id` → `"x,y"`), written by
/// `qrm convert` and `qrm sim`.
pub const TRUTH_METADATA: &str = "qrm.ground_truth";

/// How lidar scans become landmark detections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LidarSettings {
    /// Extraction of point-landmark candidates from the returns.
    pub extractor: sim2d::ExtractorConfig,
    /// Tolerance of the triangle recogniser (m): sorted triangle sides agreeing within it match.
    pub recognition_tolerance: f64,
    /// Position noise σ (m) given to each extracted landmark (isotropic).
    pub sigma: f64,
}

impl Default for LidarSettings {
    /// The settings `qrm sim --detector lidar` uses.
    fn default() -> Self {
        Self {
            extractor: sim2d::ExtractorConfig::default(),
            recognition_tolerance: 0.3,
            sigma: 0.1,
        }
    }
}

/// What to read and how.
#[derive(Debug, Clone, Default, PartialEq)]
#[must_use]
pub struct ReadOptions {
    /// Topics to read; empty = choose (every detection topic, else the one scan topic).
    pub topics: Vec<String>,
    /// Returns below this are no return (m), overriding the message's `range_min`.
    pub range_min: Option<f32>,
    /// Returns beyond this are no return (m), overriding the message's `range_max` (needed for
    /// Foxglove scans from writers that mark no return by a long range).
    pub range_max: Option<f32>,
    /// Lidar extraction and recognition.
    pub lidar: LidarSettings,
    /// Read a truncated or damaged file up to its last readable chunk instead of failing
    /// ([`Recording::damage`] says where it stopped).
    pub allow_truncated: bool,
}

impl ReadOptions {
    /// Reads `topic` (may be called several times).
    pub fn with_topic(mut self, topic: impl Into<String>) -> Self {
        self.topics.push(topic.into());
        self
    }

    /// Treats returns beyond `max` metres as no return.
    pub fn with_range_max(mut self, max: f32) -> Self {
        self.range_max = Some(max);
        self
    }

    /// Lidar extraction and recognition settings.
    pub fn with_lidar(mut self, lidar: LidarSettings) -> Self {
        self.lidar = lidar;
        self
    }

    /// Reads a truncated file up to its last readable chunk.
    pub fn allowing_truncated(mut self) -> Self {
        self.allow_truncated = true;
        self
    }

    fn validate(&self) -> Result<()> {
        // Bounded like every distance σ (pqrm's MAX_DISTANCE_M): `--lidar-sigma 1e308` was
        // blamed on a message of the log (issue 39).
        let max = pqrm::observation::MAX_DISTANCE_M;
        let ok = |x: f64| x.is_finite() && x > 0.0 && x <= max;
        for (name, v) in [
            ("lidar sigma (--lidar-sigma)", self.lidar.sigma),
            (
                "lidar recognition tolerance",
                self.lidar.recognition_tolerance,
            ),
        ] {
            if !ok(v) {
                return Err(LogError::Invalid(format!(
                    "{name} = {v:?} m: must be finite, > 0 and at most {max:e} m"
                )));
            }
        }
        if let Some(v) = self.range_min
            && !(v.is_finite() && v >= 0.0)
        {
            return Err(LogError::Invalid(format!(
                "range_min {v} must be finite and >= 0"
            )));
        }
        // A cap of 0 m makes every return "no return": an empty map, not a reading.
        if let Some(v) = self.range_max
            && !(v.is_finite() && v > 0.0)
        {
            return Err(LogError::Invalid(format!(
                "range_max (--range-max) {v} must be finite and > 0"
            )));
        }
        Ok(())
    }
}

/// One topic of the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// The topic.
    pub topic: String,
    /// Schema name (empty if none).
    pub schema: String,
    /// Schema encoding / message encoding.
    pub encoding: String,
    /// How qrm reads it, if it can.
    pub kind: Option<Kind>,
    /// Messages read on it.
    pub messages: usize,
    /// Whether it was read into the dataset.
    pub used: bool,
    /// The robot its scans are attributed to (channel metadata `robot`, else its position
    /// among the topics read).
    pub robot: u32,
}

/// What was read.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The scans (sorted by time, then robot) and the surveyed truth, if the file has one and
    /// the scans carry its ids.
    pub dataset: Dataset,
    /// Every topic seen.
    pub topics: Vec<TopicInfo>,
    /// Whether landmarks came from lidar scans (ids made by the recogniser).
    pub from_scans: bool,
    /// Where reading stopped early on a damaged file (only with `allow_truncated`).
    pub damage: Option<String>,
}

/// Reads an MCAP file.
///
/// # Errors
/// [`LogError::Io`] if the file cannot be read; otherwise as [`read_mcap_bytes`].
pub fn read_mcap(path: &Path, options: &ReadOptions) -> Result<Recording> {
    let bytes =
        qsr_core::text_file::read_bytes(path, MAX_LOG_BYTES).map_err(|source| LogError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    read_mcap_bytes(&bytes, path, options)
}

struct Channel {
    info: TopicInfo,
    metadata: BTreeMap<String, String>,
    raw: Vec<Vec<u8>>,
}

fn present(channels: &BTreeMap<u16, Channel>) -> String {
    if channels.is_empty() {
        return "none".into();
    }
    channels
        .values()
        .map(|c| {
            let s = if c.info.schema.is_empty() {
                "no schema"
            } else {
                &c.info.schema
            };
            format!("{} ({s}, {})", c.info.topic, c.info.encoding)
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn note_channel(
    channels: &mut BTreeMap<u16, Channel>,
    schemas: &BTreeMap<u16, (String, String)>,
    c: mcap::records::Channel,
) {
    channels.entry(c.id).or_insert_with(|| {
        let (schema, schema_encoding) = schemas.get(&c.schema_id).cloned().unwrap_or_default();
        let kind = Kind::of(&schema, &schema_encoding, &c.message_encoding);
        Channel {
            info: TopicInfo {
                topic: c.topic,
                encoding: format!("{schema_encoding}/{}", c.message_encoding),
                schema,
                kind,
                messages: 0,
                used: false,
                robot: 0,
            },
            metadata: c.metadata,
            raw: Vec::new(),
        }
    });
}

/// Checks that every record inside an uncompressed chunk ends within the chunk: `mcap` 0.26
/// subtracts a record's length from the chunk's remaining bytes unchecked (an overflow panic
/// in debug builds, a runaway read in release). A truncated file stops the check where it is
/// cut; the message pass reports that. Records are taken raw from the sans-I/O reader (its
/// own chunk-header checks bound every length), never parsed here.
fn check_plain_chunks(bytes: &[u8]) -> mcap::McapResult<()> {
    let mut reader = mcap::sans_io::LinearReader::new_with_options(
        mcap::sans_io::LinearReaderOptions::default()
            .with_record_length_limit(MAX_RECORD_BYTES)
            .with_emit_chunks(true),
    );
    crate::decompress::register(&mut reader, MAX_RECORD_BYTES)?;
    let mut buf = bytes;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(mcap::sans_io::LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(buf.len());
                reader.insert(n).copy_from_slice(&buf[..n]);
                reader.notify_read(n);
                buf = &buf[n..];
            }
            Ok(mcap::sans_io::LinearReadEvent::Record { data, opcode }) => {
                if opcode == mcap::records::op::CHUNK && !plain_chunk_fits(data) {
                    return Err(mcap::McapError::UnexpectedEoc);
                }
            }
            Err(_) => break,
        }
    }
    Ok(())
}

/// Whether a chunk is compressed or its records each end inside it. Layout: start and end
/// time, uncompressed size (u64 each), CRC (u32), compression (string), records (u64 length
/// and bytes).
fn plain_chunk_fits(chunk: &[u8]) -> bool {
    let mut r = Fields(chunk);
    let header = r.take(28).is_some();
    let Some(compression) = r.string() else {
        return false;
    };
    if !header {
        return false;
    }
    if !compression.is_empty() {
        return true;
    }
    let Some(mut records) = r.u64().and_then(|n| r.take(usize::try_from(n).ok()?)) else {
        return false;
    };
    while !records.is_empty() {
        let mut f = Fields(records);
        let Some(len) = f.take(1).and_then(|_| f.u64()) else {
            return false;
        };
        match usize::try_from(len).ok().and_then(|l| f.take(l)) {
            Some(_) => records = f.0,
            None => return false,
        }
    }
    true
}

/// Little-endian fields of an MCAP record, each length checked against what is left.
struct Fields<'a>(&'a [u8]);

impl<'a> Fields<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, tail) = self.0.split_at_checked(n)?;
        self.0 = tail;
        Some(head)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take(4)?.try_into().ok().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8)?.try_into().ok().map(u64::from_le_bytes)
    }
    /// A u32-length-prefixed string (or byte array).
    fn string(&mut self) -> Option<&'a [u8]> {
        let n = usize::try_from(self.u32()?).ok()?;
        self.take(n)
    }
    /// A u32-byte-length-prefixed map of strings.
    fn map(&mut self) -> Option<()> {
        let n = usize::try_from(self.u32()?).ok()?;
        let mut inner = Fields(self.take(n)?);
        while !inner.0.is_empty() {
            inner.string()?;
            inner.string()?;
        }
        Some(())
    }
}

/// Whether every length-prefixed field of a record qrm parses fits in the record: `mcap`'s
/// parser reserves a string's declared length before reading it, so a corrupt 4 GiB length
/// would be a 4 GiB allocation.
fn fields_fit(opcode: u8, data: &[u8]) -> bool {
    use mcap::records::op;
    let mut f = Fields(data);
    let ok = match opcode {
        op::SCHEMA => f
            .take(2)
            .and_then(|_| f.string())
            .and_then(|_| f.string())
            .and_then(|_| f.string()),
        op::CHANNEL => f
            .take(4)
            .and_then(|_| f.string())
            .and_then(|_| f.string())
            .and_then(|_| f.map().map(|()| &[][..])),
        op::METADATA => f.string().and_then(|_| f.map().map(|()| &[][..])),
        op::MESSAGE => f.take(22),
        _ => None,
    };
    ok.is_some()
}

/// The file's records in order, chunks decompressed, each record's length bounded by
/// [`MAX_RECORD_BYTES`] (`mcap`'s own `MessageStream` sets no bound inside chunks).
struct Records<'a> {
    buf: &'a [u8],
    reader: mcap::sans_io::LinearReader,
}

impl<'a> Records<'a> {
    fn new(buf: &'a [u8]) -> mcap::McapResult<Self> {
        let mut reader = mcap::sans_io::LinearReader::new_with_options(
            mcap::sans_io::LinearReaderOptions::default()
                .with_record_length_limit(MAX_RECORD_BYTES),
        );
        crate::decompress::register(&mut reader, MAX_RECORD_BYTES)?;
        Ok(Self { buf, reader })
    }
}

impl Iterator for Records<'_> {
    type Item = mcap::McapResult<Record<'static>>;

    fn next(&mut self) -> Option<Self::Item> {
        while let Some(event) = self.reader.next_event() {
            match event {
                Ok(mcap::sans_io::LinearReadEvent::ReadRequest(need)) => {
                    let n = need.min(self.buf.len());
                    self.reader.insert(n).copy_from_slice(&self.buf[..n]);
                    self.reader.notify_read(n);
                    self.buf = &self.buf[n..];
                }
                Ok(mcap::sans_io::LinearReadEvent::Record { data, opcode }) => {
                    use mcap::records::op;
                    // Only the records qrm reads are parsed, after their lengths are checked.
                    if !matches!(
                        opcode,
                        op::SCHEMA | op::CHANNEL | op::MESSAGE | op::METADATA
                    ) {
                        continue;
                    }
                    if !fields_fit(opcode, data) {
                        return Some(Err(mcap::McapError::RecordTooLarge {
                            opcode,
                            len: data.len() as u64,
                        }));
                    }
                    return Some(mcap::parse_record(opcode, data).map(Record::into_owned));
                }
                Err(e) => return Some(Err(e)),
            }
        }
        None
    }
}

/// Reads MCAP bytes; `path` names the file in errors.
///
/// # Errors
/// [`LogError::Damaged`] for a broken or truncated file (unless `allow_truncated`),
/// [`LogError::MissingTopic`], [`LogError::UnsupportedSchema`], [`LogError::ChooseTopic`] when
/// the topics cannot be read, [`LogError::Message`] / [`LogError::Observation`] for a message
/// that cannot be decoded or is not valid PQRM input, [`LogError::Invalid`] for bad options.
pub fn read_mcap_bytes(bytes: &[u8], path: &Path, options: &ReadOptions) -> Result<Recording> {
    options.validate()?;
    let Indexed {
        mut channels,
        truth,
        damage,
    } = index_records(bytes, path, options)?;
    let chosen = choose(&mut channels, path, options)?;
    let from_scans = chosen
        .iter()
        .any(|id| channels[id].info.kind.is_some_and(Kind::is_scan));
    let (mut scans, range_scans) = decode_chosen(&channels, &chosen, path, options)?;
    if from_scans {
        scans = recognise(range_scans, &channels, &chosen, path, options)?;
    }
    // A scan that saw nothing carries no evidence (and a CSV has no row for it).
    scans.retain(|s| !s.observations.is_empty());
    scans.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.robot.cmp(&b.robot)));
    let truth = match truth {
        Some(entries) if !from_scans => Some(parse_truth(&entries, path)?),
        _ => None,
    };
    for (order, id) in chosen.iter().enumerate() {
        if let Some(c) = channels.get_mut(id) {
            c.info.used = true;
            c.info.robot = c
                .metadata
                .get("robot")
                .and_then(|r| r.trim().parse().ok())
                .unwrap_or(u32::try_from(order).unwrap_or(u32::MAX));
        }
    }
    Ok(Recording {
        dataset: Dataset {
            scans,
            truth,
            skipped: 0,
        },
        topics: channels.into_values().map(|c| c.info).collect(),
        from_scans,
        damage,
    })
}

/// What one pass over a log's records gathers: its channels with their raw messages, the
/// surveyed landmarks' metadata, and where a damaged file stopped.
struct Indexed {
    channels: BTreeMap<u16, Channel>,
    truth: Option<BTreeMap<String, String>>,
    damage: Option<String>,
}

/// One pass over the records: schemas, channels, messages kept raw for the readable
/// channels, the truth metadata. A broken record stops the pass (with `allow_truncated`)
/// or fails it, saying how many messages came before.
fn index_records(bytes: &[u8], path: &Path, options: &ReadOptions) -> Result<Indexed> {
    let mut channels: BTreeMap<u16, Channel> = BTreeMap::new();
    check_plain_chunks(bytes).map_err(|source| LogError::Damaged {
        path: path.to_path_buf(),
        messages: 0,
        present: present(&channels),
        source,
    })?;
    let mut schemas: BTreeMap<u16, (String, String)> = BTreeMap::new();
    let mut truth = None;
    let mut count = 0usize;
    // A broken record: with `allow_truncated` the pass stops there (`said` messages
    // before it), else it fails (`read` messages read whole).
    let stopped = |source, said: usize, read: usize, channels: &BTreeMap<u16, Channel>| {
        if options.allow_truncated {
            Ok(format!("stopped after {said} messages: {source}"))
        } else {
            Err(LogError::Damaged {
                path: path.to_path_buf(),
                messages: read,
                present: present(channels),
                source,
            })
        }
    };
    let records = Records::new(bytes).map_err(|source| LogError::Damaged {
        path: path.to_path_buf(),
        messages: 0,
        present: present(&channels),
        source,
    })?;
    for record in records {
        let record = match record {
            Ok(r) => r,
            Err(source) => {
                let damage = Some(stopped(source, count, count, &channels)?);
                return Ok(Indexed {
                    channels,
                    truth,
                    damage,
                });
            }
        };
        match record {
            Record::Schema { header, .. } => {
                schemas.insert(header.id, (header.name, header.encoding));
            }
            Record::Channel(c) => note_channel(&mut channels, &schemas, c),
            Record::Message { header, data } => {
                count += 1;
                let Some(c) = channels.get_mut(&header.channel_id) else {
                    let source =
                        mcap::McapError::UnknownChannel(header.sequence, header.channel_id);
                    let damage = Some(stopped(source, count, count - 1, &channels)?);
                    return Ok(Indexed {
                        channels,
                        truth,
                        damage,
                    });
                };
                c.info.messages += 1;
                if c.info.kind.is_some() {
                    c.raw.push(data.into_owned());
                }
            }
            Record::Metadata(m) if m.name == TRUTH_METADATA => {
                truth = Some(m.metadata);
            }
            _ => {}
        }
    }
    Ok(Indexed {
        channels,
        truth,
        damage: None,
    })
}

/// The chosen channels' messages decoded: detections as scans, lidar scans kept for the
/// recogniser (with their robot, channel order and index).
#[allow(clippy::type_complexity)] // the recogniser's input, named where it is consumed
fn decode_chosen(
    channels: &BTreeMap<u16, Channel>,
    chosen: &[u16],
    path: &Path,
    options: &ReadOptions,
) -> Result<(
    Vec<Scan>,
    Vec<(crate::decode::RangeScan, u32, usize, usize)>,
)> {
    let limits = (options.range_min, options.range_max);
    let mut scans = Vec::new();
    let mut range_scans = Vec::new();
    for (order, id) in chosen.iter().enumerate() {
        let c = &channels[id];
        let robot = match c.metadata.get("robot") {
            Some(r) => r.trim().parse::<u32>().map_err(|_| LogError::Message {
                path: path.to_path_buf(),
                topic: c.info.topic.clone(),
                index: 0,
                field: "channel metadata `robot`".into(),
                reason: format!("{r:?} is not a robot number"),
            })?,
            None => u32::try_from(order).unwrap_or(u32::MAX),
        };
        let kind = c
            .info
            .kind
            .ok_or_else(|| LogError::Invalid("unreadable topic chosen".into()))?;
        // A channel's own range limits (qrm sim writes them) complete what the messages lack.
        let meta = |k: &str| c.metadata.get(k).and_then(|v| v.parse::<f32>().ok());
        let limits = (
            limits.0.or(meta("range_min")),
            limits.1.or(meta("range_max")),
        );
        for (i, raw) in c.raw.iter().enumerate() {
            let at = |field: String, reason: String| LogError::Message {
                path: path.to_path_buf(),
                topic: c.info.topic.clone(),
                index: i + 1,
                field,
                reason,
            };
            match decode(kind, raw, limits).map_err(|e| at(e.field, e.reason))? {
                Decoded::Detections(d) => {
                    let obs = d
                        .detections
                        .iter()
                        .map(|d| {
                            Observation::new(
                                LandmarkId(d.id),
                                d.xy,
                                [[d.cov[0], d.cov[1]], [d.cov[1], d.cov[2]]],
                            )
                        })
                        .collect::<pqrm::Result<Vec<_>>>()
                        .and_then(|obs| Scan::new(d.t, robot, obs))
                        .map_err(|source| LogError::Observation {
                            path: path.to_path_buf(),
                            topic: c.info.topic.clone(),
                            index: i + 1,
                            source: Box::new(source),
                        })?;
                    scans.push(obs);
                }
                Decoded::Scan(s) => range_scans.push((s, robot, order, i)),
            }
        }
    }
    Ok((scans, range_scans))
}

/// With no topic named: every detection topic with messages, else the one scan topic;
/// `Err(why)` when there is none or several scan topics.
fn readable_topics(channels: &BTreeMap<u16, Channel>) -> std::result::Result<Vec<u16>, String> {
    let of = |pred: &dyn Fn(Kind) -> bool| -> Vec<u16> {
        channels
            .iter()
            .filter(|(_, c)| c.info.kind.is_some_and(pred) && c.info.messages > 0)
            .map(|(id, _)| *id)
            .collect()
    };
    let mut chosen = of(&|k| k == Kind::Detections);
    if chosen.is_empty() {
        chosen = of(&Kind::is_scan);
        if chosen.len() > 1 {
            let names: Vec<&str> = chosen
                .iter()
                .map(|id| channels[id].info.topic.as_str())
                .collect();
            return Err(format!(
                "several scan topics ({}): name the ones to read with --topic",
                names.join(", ")
            ));
        }
    }
    if chosen.is_empty() {
        return Err(format!("no topic with messages qrm can read ({READABLE})"));
    }
    Ok(chosen)
}

/// The topics named, each present and readable, and some with messages.
fn named_topics(
    channels: &BTreeMap<u16, Channel>,
    path: &Path,
    options: &ReadOptions,
    listed: &str,
) -> Result<Vec<u16>> {
    let mut chosen: Vec<u16> = Vec::new();
    for topic in &options.topics {
        let ids: Vec<u16> = channels
            .iter()
            .filter(|(_, c)| &c.info.topic == topic)
            .map(|(id, _)| *id)
            .collect();
        if ids.is_empty() {
            return Err(LogError::MissingTopic {
                path: path.to_path_buf(),
                topic: topic.clone(),
                present: listed.to_owned(),
            });
        }
        for id in ids {
            let c = &channels[&id];
            if c.info.kind.is_none() {
                return Err(LogError::UnsupportedSchema {
                    path: path.to_path_buf(),
                    topic: topic.clone(),
                    schema: format!("`{}` ({})", c.info.schema, c.info.encoding),
                    readable: READABLE,
                    present: listed.to_owned(),
                });
            }
            if !chosen.contains(&id) {
                chosen.push(id);
            }
        }
    }
    if chosen.iter().all(|id| channels[id].info.messages == 0) {
        return Err(LogError::ChooseTopic {
            path: path.to_path_buf(),
            reason: format!("topic(s) {} have no messages", options.topics.join(", ")),
            present: listed.to_owned(),
        });
    }
    Ok(chosen)
}

/// The channels to read, in topic order.
fn choose(
    channels: &mut BTreeMap<u16, Channel>,
    path: &Path,
    options: &ReadOptions,
) -> Result<Vec<u16>> {
    let listed = present(channels);
    let choose_err = |reason: String| LogError::ChooseTopic {
        path: path.to_path_buf(),
        reason,
        present: listed.clone(),
    };
    let chosen = if options.topics.is_empty() {
        readable_topics(channels).map_err(choose_err)?
    } else {
        named_topics(channels, path, options, &listed)?
    };
    let scans = chosen
        .iter()
        .filter(|id| channels[id].info.kind.is_some_and(Kind::is_scan))
        .count();
    if scans > 0 && scans < chosen.len() {
        return Err(choose_err(
            "scans and detections cannot be read together (their landmark ids differ): name topics of one kind"
                .into(),
        ));
    }
    Ok(chosen)
}

/// Lidar scans in time order → landmark candidates → ids from one recogniser shared by all
/// scan topics (one catalogue of landmarks for every robot).
fn recognise(
    mut range_scans: Vec<(crate::decode::RangeScan, u32, usize, usize)>,
    channels: &BTreeMap<u16, Channel>,
    chosen: &[u16],
    path: &Path,
    options: &ReadOptions,
) -> Result<Vec<Scan>> {
    range_scans.sort_by(|a, b| {
        a.0.t
            .total_cmp(&b.0.t)
            .then(a.1.cmp(&b.1))
            .then(a.2.cmp(&b.2))
            .then(a.3.cmp(&b.3))
    });
    // Mapping needs triplets: a scan of fewer than three candidates is not recognised (it
    // would only make new ids for known landmarks, issue 40).
    let tolerance = options.lidar.recognition_tolerance;
    let mut detector = sim2d::LidarDetector {
        extractor: options.lidar.extractor,
        recognizer: sim2d::TriangleRecognizer::new(tolerance).tracking(),
        ..sim2d::LidarDetector::new(tolerance, options.lidar.sigma)
    }
    .with_min_candidates(sim2d::MAPPING_MIN_CANDIDATES);
    let mut scans = Vec::with_capacity(range_scans.len());
    for (s, robot, order, i) in range_scans {
        let topic = || channels[&chosen[order]].info.topic.clone();
        let points = sim2d::points_of(&s.to_laser_scan(), &options.lidar.extractor);
        if points.len() > MAX_CANDIDATES {
            return Err(LogError::Message {
                path: path.to_path_buf(),
                topic: topic(),
                index: i + 1,
                field: "ranges".into(),
                reason: format!(
                    "{} landmark candidates in one scan, more than {MAX_CANDIDATES}",
                    points.len()
                ),
            });
        }
        let obs = detector
            .recognise(points)
            .into_iter()
            .map(|(d, _)| Observation::isotropic(LandmarkId(d.id), d.xy, options.lidar.sigma))
            .collect::<pqrm::Result<Vec<_>>>()
            .and_then(|obs| Scan::new(s.t, robot, obs))
            .map_err(|source| LogError::Observation {
                path: path.to_path_buf(),
                topic: topic(),
                index: i + 1,
                source: Box::new(source),
            })?;
        scans.push(obs);
    }
    Ok(scans)
}

/// The surveyed truth of the [`TRUTH_METADATA`] record: landmark id → `x,y`.
fn parse_truth(entries: &BTreeMap<String, String>, path: &Path) -> Result<GroundTruth> {
    let mut positions = BTreeMap::new();
    for (k, v) in entries {
        let bad = |reason: String| LogError::Message {
            path: path.to_path_buf(),
            topic: format!("(metadata {TRUTH_METADATA})"),
            index: 0,
            field: k.clone(),
            reason,
        };
        let id: u32 = k
            .trim()
            .parse()
            .map_err(|_| bad("the key is not a landmark id".into()))?;
        let xy: Vec<f64> = v
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad(format!("{v:?} is not `x,y`")))?;
        match xy[..] {
            [x, y] if x.is_finite() && y.is_finite() => {
                positions.insert(LandmarkId(id), [x, y]);
            }
            _ => return Err(bad(format!("{v:?} is not `x,y` with finite numbers"))),
        }
    }
    Ok(GroundTruth { positions })
}
