//! [`BinaryCalculus`]: a binary point calculus (OPRA-m, STAR-m) — names, relations,
//! classification, and its derived tables.

use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

use nalgebra::Point2;

use super::derive::{self, ConverseTable};
use super::direction::{DirectionPartition, TICKS_PER_UNIT};
pub use super::relations::BinaryFamily;
use super::relations::Relations;
use crate::calculus::StateId;
use crate::compose::ComposeTable;
use crate::cost::{Budget, Cost};
use crate::error::{QsrError, Result};
use crate::frame::DEGENERATE_TOLERANCE;
use crate::neighbours::NeighbourGraph;

/// Largest OPRA granularity: OPRA-63 has 63,756 relations, the most a 16-bit relation id
/// holds. Classification and converse work for all; composition and neighbours are refused
/// beyond [`DERIVATION_BUDGET`] with the estimate (OPRA-10 is the largest composition that
/// fits).
pub const MAX_OPRA_M: usize = 63;
/// The binary calculi `qrm calculus list` shows (any `opra-M` up to [`MAX_OPRA_M`] and every
/// even `star-m` work; `star-4` and `star-8` are listed with the spec calculi).
pub const BINARY_NAMES: [&str; 4] = ["opra-1", "opra-2", "opra-3", "opra-4"];

/// Largest STAR granularity (as the spec family `star-m`).
pub const MAX_STAR_M: usize = 32;

/// A binary calculus over points: relations, classification and derived tables (converse,
/// composition `{A:B} ∘ {B:C} → {A:C}`, conceptual neighbours), all computed exactly by
/// angle arithmetic (see [`crate::binary`]).
///
/// ```
/// use qsr_core::binary::BinaryCalculus;
/// let opra = BinaryCalculus::builtin("opra-1")?;
/// assert_eq!(opra.n_states(), 20);
/// let r = opra.state("1_3")?; // B on A's left, A on B's right
/// assert_eq!(opra.label(opra.converse().get(r)[0]), "3_1");
/// // A convoy: B straight ahead of A and A straight behind B, C likewise ahead of B ...
/// let ahead = opra.state("0_2")?;
/// // ... so C is straight ahead of A, A straight behind C.
/// assert_eq!(opra.compose_table()?.get(ahead, ahead), &[ahead]);
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
#[derive(Debug, Clone)]
pub struct BinaryCalculus {
    name: String,
    family: BinaryFamily,
    partition: DirectionPartition,
    labels: Vec<String>,
    pub(super) derived: Arc<Derived>,
}

#[derive(Debug, Default)]
pub(super) struct Derived {
    pub(super) converse: OnceLock<ConverseTable>,
    pub(super) compose: OnceLock<ComposeTable>,
    neighbours: OnceLock<NeighbourGraph>,
    /// The calculus's reasoning tables (shared by its clones and its networks).
    pub(super) algebra: OnceLock<super::algebra::BinaryAlgebra>,
}

/// CPU seconds per grid step of a derivation, measured: `qrm calculus compose opra-4` (64 M
/// steps) took 1.23 s of CPU and opra-6 (486 M) 8.9 s on the development machine — 18–19 ns
/// a step.
pub const SECONDS_PER_DERIVATION_STEP: f64 = 19e-9;

/// What a derivation may take: a table is derived inside a command the user waits on (and
/// cached afterwards), so an hour of one core and 4 GiB — OPRA-10's composition (about 2
/// core-minutes, 1.2 GiB) fits, OPRA-11's does not.
pub const DERIVATION_BUDGET: Budget = Budget::new(4.0 * (1u64 << 30) as f64, 3600.0);

fn cache() -> &'static Mutex<Vec<BinaryCalculus>> {
    static CACHE: OnceLock<Mutex<Vec<BinaryCalculus>>> = OnceLock::new();
    CACHE.get_or_init(Mutex::default)
}

/// Whether `name` names a binary calculus with composition (`opra-M`, `star-m`).
#[must_use]
pub fn is_binary_name(name: &str) -> bool {
    parse_name(name).is_some()
}

/// The error for a name of a binary family's shape (`opra-<digits>`, `star-<digits>`) whose
/// number is out of the family's range: told as such, not as an unknown name whose list omits
/// the family, nor (`qrm calculus permute opra-100`) as a ternary calculus (issue 39).
#[must_use]
pub fn name_out_of_range(name: &str) -> Option<QsrError> {
    if parse_name(name).is_some() {
        return None;
    }
    let number = |prefix: &str| {
        name.strip_prefix(prefix)
            .filter(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
    };
    let known = if let Some(m) = number("opra-") {
        format!("opra-M for 1 ≤ M ≤ {MAX_OPRA_M} (OPRA's granularity), not M = {m}")
    } else if let Some(m) = number("star-") {
        format!("star-m for even m, 2 ≤ m ≤ {MAX_STAR_M}, not m = {m}")
    } else {
        return None;
    };
    Some(QsrError::UnknownCalculus {
        name: name.to_owned(),
        known,
    })
}

fn parse_name(name: &str) -> Option<(BinaryFamily, usize)> {
    if let Some(m) = name
        .strip_prefix("opra-")
        .and_then(|m| m.parse::<usize>().ok())
        && (1..=MAX_OPRA_M).contains(&m)
    {
        return Some((BinaryFamily::Opra, m));
    }
    if let Some(m) = name
        .strip_prefix("star-")
        .and_then(|m| m.parse::<usize>().ok())
        && (2..=MAX_STAR_M).contains(&m)
        && m % 2 == 0
    {
        return Some((BinaryFamily::Star, m));
    }
    None
}

impl BinaryCalculus {
    /// A binary calculus by name: `opra-M` (1 ≤ M ≤ [`MAX_OPRA_M`]) or `star-m` (even m,
    /// 2 ≤ m ≤ [`MAX_STAR_M`]). Built once per process; clones share derived tables.
    ///
    /// # Errors
    /// [`QsrError::UnknownCalculus`].
    pub fn builtin(name: &str) -> Result<Self> {
        if let Ok(list) = cache().lock()
            && let Some(c) = list.iter().find(|c| c.name == name)
        {
            return Ok(c.clone());
        }
        if let Some(e) = name_out_of_range(name) {
            return Err(e);
        }
        let (family, m) = parse_name(name).ok_or_else(|| QsrError::UnknownCalculus {
            name: name.to_owned(),
            known: format!(
                "binary calculi: opra-M (1 ≤ M ≤ {MAX_OPRA_M}), star-m (even m, 2 ≤ m ≤ {MAX_STAR_M})"
            ),
        })?;
        let c = Self::new(family, m);
        if let Ok(mut list) = cache().lock() {
            list.push(c.clone());
        }
        Ok(c)
    }

    fn new(family: BinaryFamily, m: usize) -> Self {
        let (name, partition, labels) = match family {
            BinaryFamily::Opra => {
                let n = 4 * m;
                let mut labels: Vec<String> = (0..n)
                    .flat_map(|i| (0..n).map(move |j| format!("{i}_{j}")))
                    .collect();
                labels.extend((0..n).map(|k| format!("s_{k}")));
                (format!("opra-{m}"), DirectionPartition::Opra { m }, labels)
            }
            BinaryFamily::Star => {
                let mut labels = star_labels(m);
                labels.push("eq".to_owned());
                (
                    format!("star-{m}"),
                    DirectionPartition::HalfOpen { m },
                    labels,
                )
            }
        };
        Self {
            name,
            family,
            partition,
            labels,
            derived: Arc::default(),
        }
    }

    /// Name (`opra-2`, `star-8`).
    #[must_use]
    pub fn name(&self) -> &str {
        &self.name
    }

    /// One-line description.
    #[must_use]
    pub fn description(&self) -> String {
        let m = self.partition.m();
        match self.family {
            BinaryFamily::Opra => format!(
                "OPRA-{m}: two oriented points, each heading cutting the plane into {} sectors \
                 ({m} lines); relations i_j and s_k as SparQ and GQR name them",
                4 * m
            ),
            BinaryFamily::Star => format!(
                "STAR-{m}: direction between two points in {m} half-open sectors about a \
                 shared reference direction (SparQ's revised star), plus eq"
            ),
        }
    }

    /// The family.
    #[must_use]
    pub fn family(&self) -> BinaryFamily {
        self.family
    }

    /// The partition of directions.
    #[must_use]
    pub fn partition(&self) -> DirectionPartition {
        self.partition
    }

    /// Whether each point has its own heading (OPRA) rather than a shared one (STAR).
    #[must_use]
    pub fn is_oriented(&self) -> bool {
        self.family == BinaryFamily::Opra
    }

    /// Numbers per configuration row for [`BinaryCalculus::classify_row`].
    #[must_use]
    pub fn input_len(&self) -> usize {
        match self.family {
            BinaryFamily::Opra => 6,
            BinaryFamily::Star => 5,
        }
    }

    /// Number of base relations.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.labels.len()
    }

    /// Relation labels in id order.
    #[must_use]
    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    /// The label of a relation.
    ///
    /// # Panics
    /// If `s` is not a relation of this calculus.
    #[must_use]
    pub fn label(&self, s: StateId) -> &str {
        &self.labels[s.index()]
    }

    /// A relation by label (case-insensitive, as SparQ writes `S_0` and `s_0`).
    ///
    /// # Errors
    /// [`QsrError::UnknownState`].
    pub fn state(&self, label: &str) -> Result<StateId> {
        self.labels
            .iter()
            .position(|l| l.eq_ignore_ascii_case(label))
            .map(|i| StateId(u16::try_from(i).unwrap_or(u16::MAX)))
            .ok_or_else(|| QsrError::UnknownState {
                calculus: self.name.clone(),
                state: label.to_owned(),
            })
    }

    /// All relation ids.
    pub fn states(&self) -> impl ExactSizeIterator<Item = StateId> + '_ {
        (0..self.labels.len()).map(|i| StateId(u16::try_from(i).unwrap_or(u16::MAX)))
    }

    /// The relation arithmetic the derivations need, below the calculus.
    pub(crate) fn relations(&self) -> Relations {
        Relations {
            family: self.family,
            partition: self.partition,
            n_states: self.n_states(),
        }
    }

    /// The relation of `Y` as seen from `X`: positions and headings (radians, counter-clockwise
    /// from +x). STAR uses `x_heading` as the shared reference direction and ignores
    /// `y_heading`. Positions are the same when `|Y − X|² ≤ DEGENERATE_TOLERANCE² · (1 + |X|² + |Y|²)`.
    ///
    /// # Errors
    /// [`QsrError::NonFinite`] for NaN or infinite inputs.
    pub fn classify(
        &self,
        x: Point2<f64>,
        x_heading: f64,
        y: Point2<f64>,
        y_heading: f64,
    ) -> Result<StateId> {
        let values = [x.x, x.y, x_heading, y.x, y.y, y_heading];
        if values.iter().any(|v| !v.is_finite()) {
            return Err(QsrError::NonFinite {
                what: format!("{} configuration {values:?}", self.name),
            });
        }
        // Scale-free: compare the squared distance with the squared magnitudes, computed on
        // values divided by the largest so nothing overflows.
        let scale = values[..2]
            .iter()
            .chain(&values[3..5])
            .fold(1.0_f64, |a, v| a.max(v.abs()));
        let (dx, dy) = ((y.x - x.x) / scale, (y.y - x.y) / scale);
        let mag = 1.0 / (scale * scale)
            + (x.x / scale).powi(2)
            + (x.y / scale).powi(2)
            + (y.x / scale).powi(2)
            + (y.y / scale).powi(2);
        let same = dx * dx + dy * dy <= DEGENERATE_TOLERANCE * DEGENERATE_TOLERANCE * mag;
        let p = self.partition;
        let n = self.partition.n_sectors();
        let id = match (self.family, same) {
            (BinaryFamily::Opra, true) => n * n + p.sector_of_angle(y_heading - x_heading),
            (BinaryFamily::Star, true) => n,
            (BinaryFamily::Opra, false) => {
                let dir = dy.atan2(dx);
                p.sector_of_angle(dir - x_heading) * n + p.sector_of_angle(dir + PI - y_heading)
            }
            (BinaryFamily::Star, false) => p.sector_of_angle(dy.atan2(dx) - x_heading),
        };
        Ok(StateId(u16::try_from(id).unwrap_or(u16::MAX)))
    }

    /// Classifies one row: OPRA `xx xy xheading yx yy yheading`; STAR `ox oy ref yx yy`
    /// (the same row as the oriented spec calculus `star-m`).
    ///
    /// # Errors
    /// [`QsrError::Arity`] for a row of the wrong length, [`QsrError::NonFinite`].
    pub fn classify_row(&self, row: &[f64]) -> Result<StateId> {
        match (self.family, row) {
            (BinaryFamily::Opra, [ax, ay, ah, bx, by, bh]) => {
                self.classify(Point2::new(*ax, *ay), *ah, Point2::new(*bx, *by), *bh)
            }
            (BinaryFamily::Star, [ox, oy, r, yx, yy]) => {
                self.classify(Point2::new(*ox, *oy), *r, Point2::new(*yx, *yy), 0.0)
            }
            _ => Err(QsrError::Arity(format!(
                "{} classifies rows of {} numbers ({}), got {}",
                self.name,
                self.input_len(),
                match self.family {
                    BinaryFamily::Opra => "ax ay a_heading bx by b_heading",
                    BinaryFamily::Star => "ox oy reference_heading bx by",
                },
                row.len()
            ))),
        }
    }

    /// A text that determines the derived tables: what [`BinaryCalculus::table_hash`] hashes.
    #[must_use]
    pub fn definition(&self) -> String {
        format!(
            "{}|{:?}|{:?}|ticks-per-unit={TICKS_PER_UNIT}|derivation=v{}",
            self.name,
            self.family,
            self.partition,
            derive::DERIVATION_VERSION
        )
    }

    /// What deriving the composition table takes (checked by [`BinaryCalculus::compose_table`]
    /// against [`DERIVATION_BUDGET`]): a bitset table per part plus the merged one and the
    /// result's list headers; the grid steps at [`SECONDS_PER_DERIVATION_STEP`].
    pub fn compose_cost(&self) -> Cost {
        let n = self.n_states() as f64;
        let words = n / 64.0;
        let tables = (derive::PARTS + 1) as f64;
        let steps = derive::compose_steps(&self.relations(), TICKS_PER_UNIT) as f64;
        Cost::new(
            n * n * (8.0 * words.ceil() * tables + 24.0),
            steps * SECONDS_PER_DERIVATION_STEP,
        )
    }

    pub(super) fn check_compose(&self) -> Result<()> {
        self.compose_cost()
            .check(
                &DERIVATION_BUDGET,
                format!("its composition table ({} relations)", self.n_states()),
            )
            .map_err(|e| QsrError::TooLarge {
                operation: "compose".into(),
                calculus: self.name.clone(),
                reason: e.hint("classification and converse still work").to_string(),
            })?;
        Ok(())
    }

    /// The converse table: `X r Y ⇒ Y conv(r) X` (derived on first use, then cached).
    #[must_use]
    pub fn converse(&self) -> &ConverseTable {
        crate::derived::get_or_derive(&self.derived.converse, || {
            derive::derive_converse(&self.relations(), TICKS_PER_UNIT)
        })
    }

    /// The composition table `{A:B} ∘ {B:C} → {A:C}` (derived on first use, then cached).
    ///
    /// # Errors
    /// [`QsrError::TooLarge`] beyond [`DERIVATION_BUDGET`] (OPRA-11 and finer), with the
    /// estimate.
    pub fn compose_table(&self) -> Result<&ComposeTable> {
        if let Some(t) = self.derived.compose.get() {
            return Ok(t);
        }
        self.check_compose()?;
        Ok(crate::derived::get_or_derive(&self.derived.compose, || {
            derive::derive_compose(&self.relations(), TICKS_PER_UNIT)
        }))
    }

    /// Derives the tables on a grid of `per_unit` ticks per unit (not cached): tests use it
    /// to check that [`TICKS_PER_UNIT`] is fine enough.
    #[must_use]
    pub fn derive_tables_with(&self, per_unit: usize) -> (ConverseTable, ComposeTable) {
        let t = derive::derive_tables(&self.relations(), per_unit.max(1));
        (t.converse, t.compose)
    }

    /// The conceptual-neighbour graph: two relations are neighbours when a configuration of
    /// one is a limit of configurations of the other (a point moved, a heading turned).
    ///
    /// # Errors
    /// [`QsrError::TooLarge`] beyond [`DERIVATION_BUDGET`]: the graph keeps an `n × n`
    /// distance matrix (OPRA-32 and finer).
    pub fn neighbours(&self) -> Result<&NeighbourGraph> {
        if let Some(g) = self.derived.neighbours.get() {
            return Ok(g);
        }
        let n = self.n_states() as f64;
        // Adjacency (1 byte) and distances (8 bytes) per pair, and Dijkstra's maps.
        Cost::memory(n * n * 24.0)
            .check(
                &DERIVATION_BUDGET,
                format!("its neighbour graph and distance matrix ({n} relations)"),
            )
            .map_err(|e| QsrError::TooLarge {
                operation: "neighbours".into(),
                calculus: self.name.clone(),
                reason: e.to_string(),
            })?;
        Ok(crate::derived::get_or_derive(
            &self.derived.neighbours,
            || derive::derive_neighbours(&self.relations(), TICKS_PER_UNIT),
        ))
    }
}

impl PartialEq for BinaryCalculus {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

fn star_labels(m: usize) -> Vec<String> {
    (0..m).map(|j| crate::builtin::star_label(m, j)).collect()
}
