//! [`SplitSet`]: the relations a consistency search splits a constraint into — GQR's "cover
//! set" (`gqr consistency -c horn` reads `DATA/CALCULUS/calculus/hornalg`).
//!
//! ## Why
//! Searching over base relations decides a network by making every constraint atomic. For
//! calculi with a tractable subclass on which path consistency decides consistency — the Horn
//! relations of RCC-8 (Renz & Nebel 1999, 148 relations), the ORD-Horn relations of Allen's
//! interval algebra (Nebel & Bürckert 1995, 868) — the search can stop as soon as every
//! constraint lies in the subclass, and split a constraint into a few large subclass members
//! rather than into many base relations: far fewer decisions, and a smaller tree. The answer
//! is then a path-consistent network over the subclass, which *is* consistency for such a
//! subclass (and only for such a one: the file is the user's claim, as it is GQR's).
//!
//! ## The file
//! GQR's format: one relation per line, `( r1 r2 ... )`; blank lines and lines starting with
//! `#` are skipped. Every base relation must be a member on its own (otherwise some constraint
//! could not be split); the empty relation is dropped, as GQR drops it.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use super::algebra::BinaryAlgebra;
use crate::error::{QsrError, Result};
use crate::reason::StateSet;
use crate::text_file::shorten;

/// A set of relations to split constraints into during search (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitSet {
    /// Where it was read from (for messages).
    origin: String,
    /// The calculus it names relations of.
    calculus: String,
    members: Vec<StateSet>,
}

fn split_error(origin: &str, reason: impl Into<String>) -> QsrError {
    QsrError::Spec {
        calculus: origin.to_owned(),
        reason: reason.into(),
    }
}

impl SplitSet {
    /// Reads GQR's cover-set format (see the module docs) for `algebra`; `origin` names the
    /// text in messages.
    ///
    /// ```
    /// use qsr_core::binary::{BinaryAlgebra, SplitSet};
    /// let pa = BinaryAlgebra::from_gqr_tables(
    ///     "point",
    ///     "< :: >\n= :: =\n> :: <\n",
    ///     "< : < :: ( < )\n< : = :: ( < )\n< : > :: ( < = > )\n\
    ///      = : < :: ( < )\n= : = :: ( = )\n= : > :: ( > )\n\
    ///      > : < :: ( < = > )\n> : = :: ( > )\n> : > :: ( > )\n",
    ///     "=",
    ///     None,
    /// )?;
    /// let horn = SplitSet::from_gqr_str(&pa, "( < )\n( = )\n( > )\n( < = )\n", "pa-horn")?;
    /// assert_eq!(horn.len(), 4);
    /// assert!(SplitSet::from_gqr_str(&pa, "( < = )\n", "short").is_err(), "not exhaustive");
    /// # Ok::<(), qsr_core::QsrError>(())
    /// ```
    ///
    /// # Errors
    /// [`QsrError::Spec`] naming `origin` and the line: a line that is not `( r ... )`, a
    /// relation the calculus does not have; and a base relation that is not a member on its own.
    pub fn from_gqr_str(algebra: &BinaryAlgebra, text: &str, origin: &str) -> Result<Self> {
        let mut members = Vec::new();
        let mut seen = HashSet::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let inner = line
                .strip_prefix('(')
                .and_then(|rest| rest.split_once(')'))
                .filter(|(_, after)| after.trim().is_empty())
                .map(|(inside, _)| inside)
                .ok_or_else(|| {
                    split_error(
                        origin,
                        format!(
                            "line {}: expected a relation `( r1 r2 ... )`, got `{}`",
                            i + 1,
                            shorten(line)
                        ),
                    )
                })?;
            let mut set = StateSet::empty(algebra.n_states());
            for label in inner.split_whitespace() {
                let s = algebra.state(label).map_err(|_| {
                    split_error(
                        origin,
                        format!(
                            "line {}: calculus `{}` has no relation `{}`",
                            i + 1,
                            algebra.name(),
                            shorten(label)
                        ),
                    )
                })?;
                set.insert(s);
            }
            if !set.is_empty() && seen.insert(set.clone()) {
                members.push(set);
            }
        }
        for s in algebra.states() {
            if !seen.contains(&StateSet::single(algebra.n_states(), s)) {
                return Err(split_error(
                    origin,
                    format!(
                        "base relation `{}` is not a member on its own, so a constraint holding \
                         it could not be split (a split set must contain every base relation)",
                        algebra.label(s)
                    ),
                ));
            }
        }
        Ok(Self {
            origin: origin.to_owned(),
            calculus: algebra.name().to_owned(),
            members,
        })
    }

    /// Reads a cover-set file (see [`SplitSet::from_gqr_str`]).
    ///
    /// # Errors
    /// [`QsrError::Io`] when it cannot be read; as [`SplitSet::from_gqr_str`].
    pub fn from_gqr_file(algebra: &BinaryAlgebra, path: &Path) -> Result<Self> {
        let bytes = crate::text_file::read_bytes(path, crate::text_file::MAX_INPUT_BYTES).map_err(
            |source| QsrError::Io {
                path: path.to_owned(),
                source,
            },
        )?;
        Self::from_gqr_str(
            algebra,
            &String::from_utf8_lossy(&bytes),
            &path.display().to_string(),
        )
    }

    /// A split set by what a user types: a file path, or a name that GQR's `-c NAME` finds —
    /// `DIR/CALCULUS/calculus/NAMEalg`, where `DIR` is the directory of the calculus's `.spec`
    /// file (`spec_dir`), then `$GQR_DATA_DIR`, then `./data`.
    ///
    /// # Errors
    /// [`QsrError::Spec`] when no file is found (naming the places looked in); as
    /// [`SplitSet::from_gqr_file`].
    pub fn resolve(algebra: &BinaryAlgebra, name: &str, spec_dir: Option<&Path>) -> Result<Self> {
        let path = Path::new(name);
        if path.is_file() {
            return Self::from_gqr_file(algebra, path);
        }
        let mut tried = Vec::new();
        if !name.is_empty() && !name.contains(['/', '\\']) {
            let dirs = spec_dir
                .map(Path::to_path_buf)
                .into_iter()
                .chain(std::env::var_os("GQR_DATA_DIR").map(PathBuf::from))
                .chain([PathBuf::from("data")]);
            for dir in dirs {
                let candidate = dir
                    .join(algebra.name())
                    .join("calculus")
                    .join(format!("{name}alg"));
                if candidate.is_file() {
                    return Self::from_gqr_file(algebra, &candidate);
                }
                tried.push(candidate.display().to_string());
            }
        }
        Err(split_error(
            name,
            if tried.is_empty() {
                "no such file".to_owned()
            } else {
                format!("no such file, nor {}", tried.join(", "))
            },
        ))
    }

    /// The members (each a set of base relations).
    #[must_use]
    pub fn members(&self) -> &[StateSet] {
        &self.members
    }

    /// How many members.
    #[must_use]
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Whether it has no members (never, for one that was read: every base relation is one).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// Where it was read from.
    #[must_use]
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// The calculus whose relations it holds.
    #[must_use]
    pub fn calculus(&self) -> &str {
        &self.calculus
    }
}
