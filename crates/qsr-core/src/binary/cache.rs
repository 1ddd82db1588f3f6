//! The on-disk cache of derived binary tables, keyed by the calculus's hash.
//!
//! Deriving OPRA-4's 73,984 composition entries takes about a second on two cores; finer
//! granularities take longer, and a reasoning session reloads the same tables many times.
//! The cache stores converse and composition as JSON under
//! `<dir>/<name>-<hash>.json`. The hash covers everything that determines the tables
//! ([`BinaryCalculus::definition`]), so a changed derivation gets a new file, never a stale one;
//! a file that fails to parse or does not match is derived again and replaced. The tables carry
//! a checksum of their own text (FNV-1a, as the ternary cache's): one changed digit still parses
//! as JSON, and a cache that is believed unchecked gives wrong tables with exit 0 (issue 39).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::calculus::BinaryCalculus;
use super::derive::{self, BinaryTables, ConverseTable};
use super::direction::TICKS_PER_UNIT;
use crate::calculus::StateId;
use crate::compose::ComposeTable;

/// What [`BinaryCalculus::load_or_derive_tables`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CacheOutcome {
    /// The tables were already in memory.
    InMemory,
    /// Read from this file.
    Loaded(PathBuf),
    /// Derived and written to this file.
    Written(PathBuf),
    /// Derived; the cache file could not be used (why).
    Derived(String),
}

/// Where derived tables are cached unless told otherwise: `QRM_CACHE_DIR` (set but empty: no
/// cache), else `$XDG_CACHE_HOME/qrm`, else `~/.cache/qrm` (`None` without a home).
#[must_use]
pub fn default_cache_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("QRM_CACHE_DIR") {
        return (!dir.is_empty()).then(|| PathBuf::from(dir));
    }
    if let Some(x) = std::env::var_os("XDG_CACHE_HOME").filter(|x| !x.is_empty()) {
        return Some(PathBuf::from(x).join("qrm"));
    }
    std::env::var_os("HOME")
        .filter(|h| !h.is_empty())
        .map(|h| PathBuf::from(h).join(".cache").join("qrm"))
}

/// FNV-1a, 64 bit: stable across Rust versions and platforms (unlike `DefaultHasher`).
#[must_use]
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The tables as the file holds them.
#[derive(Serialize, Deserialize)]
struct Tables {
    labels: Vec<String>,
    converse: Vec<Vec<u16>>,
    compose: Vec<Vec<Vec<u16>>>,
}

#[derive(Serialize, Deserialize)]
struct CacheFile {
    format: String,
    definition: String,
    /// FNV-1a of `tables` as compact JSON.
    checksum: String,
    tables: Tables,
}

/// The checksum a file stores for its tables.
fn checksum(t: &Tables) -> Result<String, String> {
    let text = serde_json::to_string(t).map_err(|e| e.to_string())?;
    Ok(format!("{:016x}", fnv1a(text.as_bytes())))
}

/// Version 2 added the checksum; a version-1 file fails to parse and is derived again.
const FORMAT: &str = "qrm-binary-tables-2";

/// The cache file of `c` in `dir`.
#[must_use]
pub fn cache_path(c: &BinaryCalculus, dir: &Path) -> PathBuf {
    dir.join(format!("{}-{:016x}.json", c.name(), c.table_hash()))
}

pub(crate) fn load_or_derive(c: &BinaryCalculus, dir: &Path) -> (BinaryTables, CacheOutcome) {
    let path = cache_path(c, dir);
    let reason = match std::fs::read(&path) {
        Ok(bytes) => match read(c, &bytes) {
            Ok(t) => return (t, CacheOutcome::Loaded(path)),
            Err(why) => format!("{} was unusable ({why}); derived again", path.display()),
        },
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => format!("cannot read {}: {e}", path.display()),
    };
    let tables = derive::derive_tables(&c.relations(), TICKS_PER_UNIT);
    match write(c, &tables, &path) {
        Ok(()) if reason.is_empty() => (tables, CacheOutcome::Written(path)),
        Ok(()) => (tables, CacheOutcome::Derived(reason)),
        Err(e) => (
            tables,
            CacheOutcome::Derived(format!("cannot write {}: {e}", path.display())),
        ),
    }
}

fn read(c: &BinaryCalculus, bytes: &[u8]) -> Result<BinaryTables, String> {
    let file: CacheFile = serde_json::from_slice(bytes).map_err(|e| e.to_string())?;
    if file.format != FORMAT
        || file.definition != c.definition()
        || file.tables.labels != c.labels()
    {
        return Err("written for another calculus or derivation".into());
    }
    if checksum(&file.tables)? != file.checksum {
        return Err("its checksum does not verify (damaged on disk?)".into());
    }
    let f = file.tables;
    let n = c.n_states();
    if f.converse.len() != n || f.compose.len() != n {
        return Err(format!("tables are not {n} × {n}"));
    }
    let ids = |v: Vec<u16>| v.into_iter().map(StateId).collect::<Vec<_>>();
    let converse = ConverseTable::from_rows(f.converse.into_iter().map(ids).collect())
        .map_err(|e| e.to_string())?;
    let compose = ComposeTable::from_rows(
        f.compose
            .into_iter()
            .map(|row| row.into_iter().map(ids).collect())
            .collect(),
    )
    .map_err(|e| e.to_string())?;
    Ok(BinaryTables { converse, compose })
}

fn write(c: &BinaryCalculus, t: &BinaryTables, path: &Path) -> std::io::Result<()> {
    let ids = |v: &[StateId]| v.iter().map(|s| s.0).collect::<Vec<_>>();
    let tables = Tables {
        labels: c.labels().to_vec(),
        converse: t.converse.rows().iter().map(|r| ids(r)).collect(),
        compose: c
            .states()
            .map(|r| c.states().map(|s| ids(t.compose.get(r, s))).collect())
            .collect(),
    };
    let file = CacheFile {
        format: FORMAT.into(),
        definition: c.definition(),
        checksum: checksum(&tables).map_err(std::io::Error::other)?,
        tables,
    };
    let text = serde_json::to_vec(&file).map_err(std::io::Error::other)?;
    crate::text_file::write_whole(path, &text)
}

impl BinaryCalculus {
    /// A stable 64-bit hash (FNV-1a) of [`BinaryCalculus::definition`]: the on-disk table
    /// cache's key, so a changed derivation never reads stale tables.
    #[must_use]
    pub fn table_hash(&self) -> u64 {
        fnv1a(self.definition().as_bytes())
    }

    /// [`BinaryCalculus::load_or_derive_tables`] in [`default_cache_dir`]; without one the
    /// tables are derived and kept in memory.
    ///
    /// # Errors
    /// As [`BinaryCalculus::compose_table`] when the table is too large to derive.
    pub fn load_or_derive_cached(&self) -> crate::Result<CacheOutcome> {
        match default_cache_dir() {
            Some(dir) => self.load_or_derive_tables(&dir),
            None if self.derived.compose.get().is_some() => Ok(CacheOutcome::InMemory),
            None => {
                self.compose_table()?;
                Ok(CacheOutcome::Derived("no cache directory".into()))
            }
        }
    }

    /// Loads the tables from `dir` when a file with this calculus's hash is there and
    /// intact, else derives them and writes the file (atomically). A cache that cannot be
    /// written is not an error: the tables are kept in memory and the outcome says why.
    ///
    /// # Errors
    /// As [`BinaryCalculus::compose_table`] when the table is too large to derive.
    pub fn load_or_derive_tables(&self, dir: &Path) -> crate::Result<CacheOutcome> {
        if self.derived.compose.get().is_some() {
            return Ok(CacheOutcome::InMemory);
        }
        self.check_compose()?;
        let (tables, outcome) = load_or_derive(self, dir);
        let _ = self.derived.converse.set(tables.converse);
        let _ = self.derived.compose.set(tables.compose);
        Ok(outcome)
    }
}
