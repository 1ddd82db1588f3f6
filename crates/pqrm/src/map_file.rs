//! The two files a [`crate::Pqrm`] is saved in: versioned JSON (small maps, interchange,
//! diffs) and a binary format for large maps.
//!
//! **Binary layout** (all integers little-endian; version 1):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `QRM-PQRM` |
//! | 8 | 4 | `version` (u32, = 1) |
//! | 12 | 4 | `header_len` (u32): bytes of the JSON header |
//! | 16 | 8 | `n_sets` (u64) |
//! | 24 | 4 | `n_states` (u32) |
//! | 28 | 4 | reserved, 0 |
//! | 32 | `header_len` | header: `{"calculus": spec, "config": …, "steps": …, "evidence": …}` as JSON |
//! | … | 12 · `n_sets` | sets: three u32 landmark ids each, in set order |
//! | … | 4 · `n_sets` | update counts (u32) |
//! | … | 4 · `n_sets` · `n_states` | log-probabilities (f32), one row per set |
//! | end − 4 | 4 | CRC-32 (IEEE) of every byte before it |
//!
//! **Why this and not Arrow or Parquet.** The map is three fixed-width tables and a small
//! header; a reader in any language is a dozen lines (`numpy.frombuffer` at the offsets
//! above), and the whole file is checked by one CRC before anything is believed. A columnar
//! container would add a large dependency for no query the map needs.
//!
//! A reader checks, in order, the magic, the version, that the sizes announced add up to the
//! file's length exactly (a truncated or padded file is refused before any table is
//! allocated), the checksum, then the header and every row ([`crate::Pqrm`]'s checks). Each
//! error names the field.

use std::path::Path;

use crate::evidence::EvidenceModel;

use serde::{Deserialize, Serialize, Serializer};

use crate::config::PqrmConfig;
use crate::error::{PqrmError, Result};

/// File format version of the JSON map ([`crate::Pqrm::to_json`]).
pub const FORMAT_VERSION: u32 = 1;

/// Magic bytes that open a binary map.
pub const BINARY_MAGIC: [u8; 8] = *b"QRM-PQRM";
/// Version of the binary layout above.
pub const BINARY_VERSION: u32 = 1;
/// File extension of binary maps.
pub const BINARY_EXTENSION: &str = "pqrm";
/// Bytes before the header.
const PREFIX: usize = 32;
/// Bytes of the trailing checksum.
const TRAILER: usize = 4;

/// The formats a map is saved in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFormat {
    /// Versioned JSON (`map.json`).
    Json,
    /// The binary layout of this module (`map.pqrm`).
    Binary,
}

impl MapFormat {
    /// The format a file name asks for: `.pqrm` is binary, anything else JSON.
    #[must_use]
    pub fn from_path(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case(BINARY_EXTENSION) => Self::Binary,
            _ => Self::Json,
        }
    }

    /// The file extension of the format.
    #[must_use]
    pub fn extension(self) -> &'static str {
        match self {
            Self::Json => "json",
            Self::Binary => BINARY_EXTENSION,
        }
    }
}

/// What both formats store beside the tables.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct MapHeader {
    pub calculus: qsr_core::CalculusSpec,
    pub config: PqrmConfig,
    pub steps: u64,
    /// How a belief is read from its row (files before it existed: eq. 2.10).
    #[serde(default)]
    pub evidence: EvidenceModel,
}

/// A map's contents in set order: the form both formats are written from and read into.
#[derive(Debug, Clone)]
pub(crate) struct MapParts {
    pub header: MapHeader,
    pub sets: Vec<[u32; 3]>,
    pub updates: Vec<u32>,
    /// `n_states` per set.
    pub log_p: Vec<f32>,
}

/// Whether bytes open like a binary map.
#[must_use]
pub fn is_binary(bytes: &[u8]) -> bool {
    bytes.starts_with(&BINARY_MAGIC)
}

// ---- JSON ----

#[derive(Deserialize)]
struct SavedMap {
    format: String,
    version: u32,
    calculus: qsr_core::CalculusSpec,
    config: PqrmConfig,
    steps: u64,
    #[serde(default)]
    evidence: EvidenceModel,
    sets: Vec<SavedSet>,
}

#[derive(Serialize, Deserialize)]
struct SavedSet {
    set: [u32; 3],
    updates: u32,
    log_p: Vec<f64>,
}

/// A map as the writers see it: the header and, in set order, each set's ids, update
/// count and stored row. Rows are read from the map in place (no copy of the tables).
pub(crate) struct MapSource<'a> {
    pub header: MapHeader,
    pub n_states: usize,
    /// Row `i` (in set order): `(ids, updates, log-probabilities)`.
    pub rows: Vec<([u32; 3], u32, &'a [f32])>,
}

/// The JSON document, serialised set by set.
struct JsonView<'a, 'b>(&'b MapSource<'a>);

impl Serialize for JsonView<'_, '_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let p = self.0;
        let mut st = s.serialize_struct("SavedMap", 7)?;
        st.serialize_field("format", "qrm-pqrm")?;
        st.serialize_field("version", &FORMAT_VERSION)?;
        st.serialize_field("calculus", &p.header.calculus)?;
        st.serialize_field("config", &p.header.config)?;
        st.serialize_field("steps", &p.header.steps)?;
        st.serialize_field("evidence", &p.header.evidence)?;
        st.serialize_field("sets", &Sets(p))?;
        st.end()
    }
}

struct Sets<'a, 'b>(&'b MapSource<'a>);

impl Serialize for Sets<'_, '_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(self.0.rows.iter().map(|(set, updates, row)| SavedSet {
            set: *set,
            updates: *updates,
            // JSON has no -inf: a ruled-out state is written as -1e300 (read back as -inf
            // in f32)
            log_p: row.iter().map(|&l| f64::from(l).max(-1e300)).collect(),
        }))
    }
}

/// Writes the JSON document.
pub(crate) fn write_json(map: &MapSource<'_>, out: &mut impl std::io::Write) -> Result<()> {
    serde_json::to_writer(out, &JsonView(map)).map_err(|e| PqrmError::Format(e.to_string()))
}

/// Reads the JSON document (rows are checked by the map).
pub(crate) fn read_json(text: &str) -> Result<MapParts> {
    let saved: SavedMap =
        serde_json::from_str(text).map_err(|e| PqrmError::Format(e.to_string()))?;
    if saved.format != "qrm-pqrm" || saved.version != FORMAT_VERSION {
        return Err(PqrmError::Format(format!(
            "expected qrm-pqrm version {FORMAT_VERSION}, found {} version {}",
            saved.format, saved.version
        )));
    }
    let q = saved.calculus.states.len();
    let mut log_p = Vec::with_capacity(saved.sets.len() * q);
    for s in &saved.sets {
        if s.log_p.len() != q {
            return Err(PqrmError::Format(format!(
                "set {:?}: {} log-probabilities for a {q}-state calculus",
                s.set,
                s.log_p.len()
            )));
        }
        log_p.extend(s.log_p.iter().map(|&v| v as f32));
    }
    Ok(MapParts {
        header: MapHeader {
            calculus: saved.calculus,
            config: saved.config,
            steps: saved.steps,
            evidence: saved.evidence,
        },
        sets: saved.sets.iter().map(|s| s.set).collect(),
        updates: saved.sets.iter().map(|s| s.updates).collect(),
        log_p,
    })
}

// ---- binary ----

/// A writer that feeds the CRC with every byte it passes on.
struct Checked<'w, W: std::io::Write> {
    out: &'w mut W,
    crc: crc32fast::Hasher,
}

impl<W: std::io::Write> Checked<'_, W> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.crc.update(bytes);
        self.out.write_all(bytes)
    }
}

/// Writes the binary layout, streaming the rows from the map (nothing but a small buffer is
/// allocated, so saving a million sets costs no memory beside the map).
pub(crate) fn write_binary(map: &MapSource<'_>, out: &mut impl std::io::Write) -> Result<()> {
    let header = serde_json::to_vec(&map.header).map_err(|e| PqrmError::Format(e.to_string()))?;
    let header_len =
        u32::try_from(header.len()).map_err(|_| PqrmError::Format("header over 4 GiB".into()))?;
    let q = map.n_states;
    let n_states = u32::try_from(q).map_err(|_| PqrmError::Format(format!("{q} states")))?;
    let mut w = Checked {
        out,
        crc: crc32fast::Hasher::new(),
    };
    let io = |e: std::io::Error| PqrmError::Format(format!("writing the binary map: {e}"));
    let mut prefix = Vec::with_capacity(PREFIX);
    prefix.extend_from_slice(&BINARY_MAGIC);
    prefix.extend_from_slice(&BINARY_VERSION.to_le_bytes());
    prefix.extend_from_slice(&header_len.to_le_bytes());
    prefix.extend_from_slice(&(map.rows.len() as u64).to_le_bytes());
    prefix.extend_from_slice(&n_states.to_le_bytes());
    prefix.extend_from_slice(&0u32.to_le_bytes());
    w.put(&prefix).map_err(io)?;
    w.put(&header).map_err(io)?;
    // the tables through one reused buffer of about 64 KiB
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let flush = |buf: &mut Vec<u8>, w: &mut Checked<'_, _>, force: bool| {
        if force || buf.len() >= 1 << 16 {
            w.put(buf).map_err(io)?;
            buf.clear();
        }
        Ok::<(), PqrmError>(())
    };
    for (set, _, _) in &map.rows {
        set.iter()
            .for_each(|id| buf.extend_from_slice(&id.to_le_bytes()));
        flush(&mut buf, &mut w, false)?;
    }
    for (_, updates, _) in &map.rows {
        buf.extend_from_slice(&updates.to_le_bytes());
        flush(&mut buf, &mut w, false)?;
    }
    for (_, _, row) in &map.rows {
        row.iter()
            .for_each(|v| buf.extend_from_slice(&v.to_le_bytes()));
        flush(&mut buf, &mut w, false)?;
    }
    flush(&mut buf, &mut w, true)?;
    let crc = w.crc.clone().finalize();
    w.out.write_all(&crc.to_le_bytes()).map_err(io)
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    let mut b = [0u8; 4];
    b.copy_from_slice(&bytes[at..at + 4]);
    u32::from_le_bytes(b)
}

fn bad(field: &str, why: impl std::fmt::Display) -> PqrmError {
    PqrmError::Format(format!("binary map, field `{field}`: {why}"))
}

/// The prefix's fields — header length, sets, states — checked: the magic, the version,
/// and the size they announce against the file's.
fn check_layout(bytes: &[u8]) -> Result<(usize, u64, u32)> {
    if bytes.len() < PREFIX + TRAILER {
        return Err(bad(
            "magic",
            format!(
                "{} bytes is shorter than the {} of an empty map (truncated?)",
                bytes.len(),
                PREFIX + TRAILER
            ),
        ));
    }
    if !is_binary(bytes) {
        return Err(bad("magic", "not a qrm binary map"));
    }
    let version = u32_at(bytes, 8);
    if version != BINARY_VERSION {
        return Err(bad(
            "version",
            format!("{version}; this build reads version {BINARY_VERSION}"),
        ));
    }
    let header_len = u32_at(bytes, 12) as usize;
    let mut n_bytes = [0u8; 8];
    n_bytes.copy_from_slice(&bytes[16..24]);
    let n_sets = u64::from_le_bytes(n_bytes);
    let n_states = u32_at(bytes, 24);
    // the size the fields announce, in u128 so that no value can overflow it
    let expected = PREFIX as u128
        + header_len as u128
        + u128::from(n_sets) * (16 + 4 * u128::from(n_states))
        + TRAILER as u128;
    if expected != bytes.len() as u128 {
        return Err(bad(
            "n_sets",
            format!(
                "{n_sets} sets of {n_states} states with a {header_len}-byte header take \
                 {expected} bytes, the file has {} (truncated or damaged)",
                bytes.len()
            ),
        ));
    }
    Ok((header_len, n_sets, n_states))
}

/// Decodes the binary layout, checking sizes and checksum before reading any table.
pub(crate) fn decode_binary(bytes: &[u8]) -> Result<MapParts> {
    let (header_len, n_sets, n_states) = check_layout(bytes)?;
    let body = bytes.len() - TRAILER;
    let stored = u32_at(bytes, body);
    let crc = crc32fast::hash(&bytes[..body]);
    if crc != stored {
        return Err(bad(
            "crc32",
            format!("checksum {crc:#010x} != stored {stored:#010x} (the file is damaged)"),
        ));
    }
    let header: MapHeader = serde_json::from_slice(&bytes[PREFIX..PREFIX + header_len])
        .map_err(|e| bad("header", e))?;
    let q = header.calculus.states.len();
    if q != n_states as usize {
        return Err(bad(
            "n_states",
            format!("{n_states}, but the calculus in the header has {q} states"),
        ));
    }
    // sizes checked against the file length above: these fit in memory already
    let n = n_sets as usize;
    let mut at = PREFIX + header_len;
    let sets = bytes[at..at + 12 * n]
        .chunks_exact(12)
        .map(|c| [u32_at(c, 0), u32_at(c, 4), u32_at(c, 8)])
        .collect();
    at += 12 * n;
    let updates = bytes[at..at + 4 * n]
        .chunks_exact(4)
        .map(|c| u32_at(c, 0))
        .collect();
    at += 4 * n;
    let log_p = bytes[at..at + 4 * n * q]
        .chunks_exact(4)
        .map(|c| f32::from_bits(u32_at(c, 0)))
        .collect();
    Ok(MapParts {
        header,
        sets,
        updates,
        log_p,
    })
}
