//! The on-disk cache of a ternary calculus's derived reasoning tables (the sound composition
//! table and the five permutation tables).
//!
//! Deriving EDC's tables by sampling takes about 3.3 s of CPU, and every `qrm reason close
//! --calculus edc` needs them; binary calculi have had a cache ([`crate::binary`]) from the
//! start. The file is `<dir>/ternary-<name>-<hash>.json`, the hash (FNV-1a) over the spec as
//! JSON and [`DERIVATION_VERSION`], so a changed spec or sampler gets a new file, never a stale
//! one. The tables carry a checksum of their own text: a file damaged on disk (a flipped digit
//! still parses) is derived again and replaced, never trusted.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::binary::{CacheOutcome, default_cache_dir};
use crate::calculus::{Calculus, StateId};
use crate::compose::ComposeTable;
use crate::permute::{Permutation, PermutationTable};

/// Bumped whenever sampling changes what the tables hold: part of the cache key.
pub const DERIVATION_VERSION: u32 = 1;

const FORMAT: &str = "qrm-ternary-tables";

/// The tables as the file holds them.
#[derive(Serialize, Deserialize)]
struct Tables {
    labels: Vec<String>,
    compose: Vec<Vec<Vec<u16>>>,
    /// One table per operation, in [`Permutation::ALL`] order.
    permutations: Vec<Vec<Vec<u16>>>,
}

#[derive(Serialize, Deserialize)]
struct CacheFile {
    format: String,
    key: String,
    /// FNV-1a of `tables` as compact JSON.
    checksum: String,
    tables: Tables,
}

impl Calculus {
    /// What the derived tables depend on: the spec and the sampler's version.
    fn table_key(&self) -> crate::Result<String> {
        let spec = serde_json::to_string(self.spec()).map_err(|e| crate::QsrError::Spec {
            calculus: self.name().to_owned(),
            reason: format!("cannot be written as JSON for the cache key: {e}"),
        })?;
        Ok(format!(
            "{:016x}-v{DERIVATION_VERSION}",
            crate::binary::fnv1a(spec.as_bytes())
        ))
    }

    /// The cache file of this calculus's tables in `dir`.
    ///
    /// # Errors
    /// As [`Calculus::load_or_derive_tables`].
    pub fn table_cache_path(&self, dir: &Path) -> crate::Result<PathBuf> {
        let name: String = self
            .name()
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .take(64)
            .collect();
        Ok(dir.join(format!("ternary-{name}-{}.json", self.table_key()?)))
    }

    /// [`Calculus::load_or_derive_tables`] in [`default_cache_dir`]; without one the tables
    /// are derived and kept in memory.
    ///
    /// # Errors
    /// As [`Calculus::load_or_derive_tables`].
    pub fn load_or_derive_cached(&self) -> crate::Result<CacheOutcome> {
        match default_cache_dir() {
            Some(dir) => self.load_or_derive_tables(&dir),
            None => {
                self.compose_table()?;
                Ok(CacheOutcome::Derived("no cache directory".into()))
            }
        }
    }

    /// The sound composition and permutation tables: already in memory, read from `dir` when
    /// a file with this calculus's key is there and its checksum verifies, else derived and
    /// written there (atomically). A cache that cannot be read or written is not an error:
    /// the tables are derived and the outcome says why.
    ///
    /// # Errors
    /// [`crate::QsrError::Unsupported`] for a calculus that is not ternary.
    pub fn load_or_derive_tables(&self, dir: &Path) -> crate::Result<CacheOutcome> {
        self.require_ternary("reasoning tables")?;
        if self.has_reasoning_tables() {
            return Ok(CacheOutcome::InMemory);
        }
        let path = self.table_cache_path(dir)?;
        let key = self.table_key()?;
        let reason = match std::fs::read(&path) {
            Ok(bytes) => match self.read_cache(&bytes, &key) {
                Ok(()) => return Ok(CacheOutcome::Loaded(path)),
                Err(why) => format!("{} was unusable ({why}); derived again", path.display()),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => format!("cannot read {}: {e}", path.display()),
        };
        let tables = self.tables_for_cache()?;
        match write_cache(&tables, &key, &path) {
            Ok(()) if reason.is_empty() => Ok(CacheOutcome::Written(path)),
            Ok(()) => Ok(CacheOutcome::Derived(reason)),
            Err(e) => Ok(CacheOutcome::Derived(format!(
                "cannot write {}: {e}",
                path.display()
            ))),
        }
    }

    fn tables_for_cache(&self) -> crate::Result<Tables> {
        let ids = |v: &[StateId]| v.iter().map(|s| s.0).collect::<Vec<_>>();
        let compose = self.compose_table()?;
        let mut permutations = Vec::new();
        for op in Permutation::ALL {
            permutations.push(
                self.permutation(op)?
                    .rows()
                    .iter()
                    .map(|r| ids(r))
                    .collect(),
            );
        }
        Ok(Tables {
            labels: self.labels().to_vec(),
            compose: self
                .states()
                .map(|r| self.states().map(|s| ids(compose.get(r, s))).collect())
                .collect(),
            permutations,
        })
    }

    fn read_cache(&self, bytes: &[u8], key: &str) -> Result<(), String> {
        let file: CacheFile = serde_json::from_slice(bytes).map_err(|e| e.to_string())?;
        if file.format != FORMAT || file.key != key || file.tables.labels != self.labels() {
            return Err("written for another calculus or derivation".into());
        }
        let text = serde_json::to_string(&file.tables).map_err(|e| e.to_string())?;
        if format!("{:016x}", crate::binary::fnv1a(text.as_bytes())) != file.checksum {
            return Err("its checksum does not verify (damaged on disk?)".into());
        }
        let n = self.n_states();
        let t = file.tables;
        if t.compose.len() != n || t.permutations.len() != Permutation::ALL.len() {
            return Err(format!("tables are not {n} × {n} with five permutations"));
        }
        let ids = |v: Vec<u16>| v.into_iter().map(StateId).collect::<Vec<_>>();
        let compose = ComposeTable::from_rows(
            t.compose
                .into_iter()
                .map(|row| row.into_iter().map(ids).collect())
                .collect(),
        )
        .map_err(|e| e.to_string())?;
        if compose.n_states() != n {
            return Err(format!("the composition table is not {n} × {n}"));
        }
        let mut perms = Vec::new();
        for (op, rows) in Permutation::ALL.into_iter().zip(t.permutations) {
            let table = PermutationTable::from_rows(op, rows.into_iter().map(ids).collect())
                .map_err(|e| e.to_string())?;
            if table.n_states() != n {
                return Err(format!("the `{op}` table has {} states", table.n_states()));
            }
            perms.push(table);
        }
        self.seed_reasoning_tables(compose, perms);
        Ok(())
    }
}

fn write_cache(tables: &Tables, key: &str, path: &Path) -> std::io::Result<()> {
    let text = serde_json::to_string(tables).map_err(std::io::Error::other)?;
    let file = CacheFile {
        format: FORMAT.into(),
        key: key.into(),
        checksum: format!("{:016x}", crate::binary::fnv1a(text.as_bytes())),
        tables: serde_json::from_str(&text).map_err(std::io::Error::other)?,
    };
    let bytes = serde_json::to_vec(&file).map_err(std::io::Error::other)?;
    crate::text_file::write_whole(path, &bytes)
}
