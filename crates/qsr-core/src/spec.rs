//! The serde form of a calculus: what a TOML or JSON spec file holds.
//!
//! A calculus is *data*. A spec names a frame kind and either
//! - a list of **constraints** (lines and circles in the normalised frame; each says which
//!   side its zero set joins) plus, per state, the **sign patterns** of the base cells it is
//!   the union of (one character per constraint: `+`, `-` or `*` for "either"), or
//! - a **raster** of state indices over a window of the normalised frame plus a rule for
//!   points outside the window (how learned calculi from SERGE are stored).
//!
//! ```toml
//! name = "left-right"
//! frame = "ternary"
//! description = "flip-flop: left or right of the directed line A→B"
//!
//! [[constraint]]
//! name = "AB"
//! kind = "line"      # f(x, y) = a·x + b·y + c
//! a = 1.0
//! b = 0.0
//! c = 0.0
//! zero = "positive"  # points on the line belong to the f > 0 side (right)
//!
//! [[state]]
//! label = "left"
//! cells = ["-"]
//!
//! [[state]]
//! label = "right"
//! cells = ["+"]
//! ```
//!
//! The built-in calculi are loaded from spec files of exactly this form (see `calculi/` in
//! the crate), through the same validation as user files.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{QsrError, Result, spec_error};
use crate::frame::FrameKind;

/// How far from the normalised frame (A = (0, 0), B = (0, 1)) a line, circle or raster window
/// may lie. The derived tables are sampled; the sampler's probe windows grow with the
/// features, and a feature at 1e308 makes them infinite.
pub const MAX_FEATURE_EXTENT: f64 = 1e6;

/// The smallest circle radius or raster window side (a subnormal window leaves the sampler
/// an empty range).
pub const MIN_FEATURE_SIZE: f64 = 1e-6;

/// Which side of a constraint its zero set (the curve itself) belongs to, so that every
/// point of the plane has exactly one state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Side {
    /// Points with `f = 0` count as `f > 0`.
    Positive,
    /// Points with `f = 0` count as `f < 0`.
    Negative,
}

/// The geometry of one constraint `f(x, y)` in normalised coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Shape {
    /// `f = a·x + b·y + c`.
    Line {
        /// Coefficient of x.
        a: f64,
        /// Coefficient of y.
        b: f64,
        /// Constant term.
        c: f64,
    },
    /// `f = (x − cx)² + (y − cy)² − r²` (negative inside).
    Circle {
        /// Centre `[cx, cy]`.
        center: [f64; 2],
        /// Radius `r > 0`.
        radius: f64,
    },
}

impl Shape {
    /// The value of `f` at `(x, y)`.
    #[inline(always)]
    #[must_use]
    pub fn value(&self, x: f64, y: f64) -> f64 {
        match *self {
            Self::Line { a, b, c } => a * x + b * y + c,
            Self::Circle { center, radius } => {
                let dx = x - center[0];
                let dy = y - center[1];
                dx * dx + dy * dy - radius * radius
            }
        }
    }
}

/// One constraint of a spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintSpec {
    /// A name for documentation and error messages (e.g. `"circle-A"`).
    #[serde(default)]
    pub name: String,
    /// The curve.
    #[serde(flatten)]
    pub shape: Shape,
    /// The side its zero set joins.
    pub zero: Side,
}

/// One state of a spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateSpec {
    /// Human label, unique within the calculus (for `edc`, `"1"`..`"20"`).
    pub label: String,
    /// For constraint calculi: the sign patterns of the base cells merged into this state.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cells: Vec<String>,
}

/// What a raster calculus answers for points outside its window.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "rule", rename_all = "kebab-case")]
pub enum OutsideRule {
    /// The state of the nearest window cell (coordinates clamped to the window): unbounded
    /// states continue straight outwards.
    Clamp,
    /// One fixed state everywhere outside.
    State {
        /// Its label.
        label: String,
    },
}

/// A label raster over an axis-aligned window of the normalised frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RasterSpec {
    /// `[x_min, x_max, y_min, y_max]`.
    pub window: [f64; 4],
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// `nx·ny` state indices (into the spec's `state` list), row-major, row 0 at `y_min`.
    pub cells: Vec<u16>,
    /// The rule outside the window.
    pub outside: OutsideRule,
}

/// A complete calculus description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalculusSpec {
    /// Name (e.g. `"edc"`).
    pub name: String,
    /// One line on what it is.
    #[serde(default)]
    pub description: String,
    /// The frame its partition is written in.
    pub frame: FrameKind,
    /// Constraints, for constraint calculi.
    #[serde(default, rename = "constraint", skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<ConstraintSpec>,
    /// The raster, for learned calculi.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raster: Option<RasterSpec>,
    /// The states in id order.
    #[serde(rename = "state")]
    pub states: Vec<StateSpec>,
}

/// Most constraints a spec may have (the base-cell table has 2^k entries).
pub const MAX_CONSTRAINTS: usize = 16;

impl CalculusSpec {
    /// Parses a TOML spec.
    ///
    /// # Errors
    /// [`QsrError::Spec`] with the parser's message.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        toml::from_str(text).map_err(|e| spec_error("<toml>", format!("TOML: {e}")))
    }

    /// Parses a JSON spec.
    ///
    /// # Errors
    /// [`QsrError::Spec`] with the parser's message.
    pub fn from_json_str(text: &str) -> Result<Self> {
        serde_json::from_str(text).map_err(|e| spec_error("<json>", format!("JSON: {e}")))
    }

    /// Reads a spec file; `.json` files are JSON, everything else TOML.
    ///
    /// # Errors
    /// [`QsrError::Io`] when the file cannot be read, [`QsrError::Spec`] when it does not parse.
    pub fn from_path(path: &Path) -> Result<Self> {
        let text = crate::text_file::read_text(path, crate::text_file::MAX_INPUT_BYTES).map_err(
            |source| QsrError::Io {
                path: path.to_path_buf(),
                source,
            },
        )?;
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let parsed = if is_json {
            Self::from_json_str(&text)
        } else {
            Self::from_toml_str(&text)
        };
        parsed.map_err(|e| match e {
            QsrError::Spec { reason, .. } => spec_error(&path.display().to_string(), reason),
            other => other,
        })
    }

    /// The spec as TOML.
    ///
    /// # Errors
    /// [`QsrError::Spec`] if serialisation fails (it does not for specs that validate).
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| spec_error(&self.name, format!("TOML: {e}")))
    }

    /// The spec as pretty JSON.
    ///
    /// # Errors
    /// [`QsrError::Spec`] if serialisation fails.
    pub fn to_json_string(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|e| spec_error(&self.name, format!("JSON: {e}")))
    }

    /// Checks everything that can be checked without sampling the plane: names, labels,
    /// constraint parameters, pattern syntax and overlaps, raster shape.
    pub(crate) fn check_static(&self) -> Result<()> {
        let name = if self.name.is_empty() {
            "<unnamed>"
        } else {
            &self.name
        };
        let err = |reason: String| spec_error(name, reason);
        if self.name.trim().is_empty() {
            return Err(err("the calculus needs a non-empty `name`".into()));
        }
        if self.states.is_empty() {
            return Err(err("no states".into()));
        }
        if self.states.len() >= usize::from(u16::MAX) {
            return Err(err(format!("{} states is too many", self.states.len())));
        }
        let mut seen = std::collections::BTreeSet::new();
        for s in &self.states {
            if s.label.trim().is_empty() {
                return Err(err("a state has an empty label".into()));
            }
            if !seen.insert(s.label.as_str()) {
                return Err(err(format!("duplicate state label `{}`", s.label)));
            }
        }
        match (&self.raster, self.constraints.is_empty()) {
            (Some(_), false) => Err(err("give either constraints or a raster, not both".into())),
            (None, true) => Err(err("give constraints or a raster".into())),
            (None, false) => self.check_constraints(name),
            (Some(r), true) => self.check_raster(name, r),
        }
    }

    fn check_constraints(&self, name: &str) -> Result<()> {
        let err = |reason: String| spec_error(name, reason);
        let k = self.constraints.len();
        if k > MAX_CONSTRAINTS {
            return Err(err(format!(
                "{k} constraints; at most {MAX_CONSTRAINTS} are supported"
            )));
        }
        for (i, c) in self.constraints.iter().enumerate() {
            let what = format!("constraint {i} `{}`", c.name);
            match c.shape {
                Shape::Line { a, b, c } => {
                    if ![a, b, c].iter().all(|v| v.is_finite()) {
                        return Err(err(format!("{what}: non-finite coefficient")));
                    }
                    if a == 0.0 && b == 0.0 {
                        return Err(err(format!("{what}: a line needs (a, b) != (0, 0)")));
                    }
                    let offset = c.abs() / a.hypot(b);
                    if offset.is_nan() || offset > MAX_FEATURE_EXTENT {
                        return Err(err(format!(
                            "{what}: the line lies {offset:e} from A; features must lie within \
                             {MAX_FEATURE_EXTENT:e} of the frame (A = (0, 0), B = (0, 1))"
                        )));
                    }
                }
                Shape::Circle { center, radius } => {
                    if !(center[0].is_finite() && center[1].is_finite() && radius.is_finite()) {
                        return Err(err(format!("{what}: non-finite centre or radius")));
                    }
                    if radius <= 0.0 {
                        return Err(err(format!("{what}: radius must be > 0, got {radius}")));
                    }
                    let far = center[0].hypot(center[1]);
                    if !(far <= MAX_FEATURE_EXTENT
                        && (MIN_FEATURE_SIZE..=MAX_FEATURE_EXTENT).contains(&radius))
                    {
                        return Err(err(format!(
                            "{what}: centre {center:?} and radius {radius:e} must lie within \
                             {MAX_FEATURE_EXTENT:e} of the frame and the radius be at least \
                             {MIN_FEATURE_SIZE:e} (A = (0, 0), B = (0, 1)): beyond that the \
                             sampler that derives the tables cannot reach the circle"
                        )));
                    }
                }
            }
        }
        let mut owner: Vec<Option<usize>> = vec![None; 1 << k];
        for (si, s) in self.states.iter().enumerate() {
            if s.cells.is_empty() {
                return Err(err(format!("state `{}` lists no cells", s.label)));
            }
            for pat in &s.cells {
                let vectors = expand_pattern(pat, k).map_err(|reason| {
                    err(format!("state `{}`, pattern `{pat}`: {reason}", s.label))
                })?;
                for v in vectors {
                    if let Some(other) = owner[v as usize]
                        && other != si
                    {
                        return Err(err(format!(
                            "sign vector `{}` is claimed by states `{}` and `{}`",
                            format_vector(v, k),
                            self.states[other].label,
                            s.label
                        )));
                    }
                    owner[v as usize] = Some(si);
                }
            }
        }
        Ok(())
    }

    fn check_raster(&self, name: &str, r: &RasterSpec) -> Result<()> {
        let err = |reason: String| spec_error(name, reason);
        if self.states.iter().any(|s| !s.cells.is_empty()) {
            return Err(err("raster calculi take no sign patterns".into()));
        }
        let [x0, x1, y0, y1] = r.window;
        if !r.window.iter().all(|v| v.is_finite()) || x1 <= x0 || y1 <= y0 {
            return Err(err(format!(
                "raster window {:?} must be finite with x_min < x_max, y_min < y_max",
                r.window
            )));
        }
        let extent = r.window.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if extent > MAX_FEATURE_EXTENT || x1 - x0 < MIN_FEATURE_SIZE || y1 - y0 < MIN_FEATURE_SIZE {
            return Err(err(format!(
                "raster window {:?} must lie within {MAX_FEATURE_EXTENT:e} of the frame and be at \
                 least {MIN_FEATURE_SIZE:e} wide and high",
                r.window
            )));
        }
        if r.nx == 0 || r.ny == 0 {
            return Err(err("raster needs nx, ny >= 1".into()));
        }
        let expected =
            r.nx.checked_mul(r.ny)
                .ok_or_else(|| err("raster too large".into()))?;
        if r.cells.len() != expected {
            return Err(err(format!(
                "raster has {} cells, expected nx·ny = {expected}",
                r.cells.len()
            )));
        }
        if let Some(bad) = r
            .cells
            .iter()
            .find(|&&c| usize::from(c) >= self.states.len())
        {
            return Err(err(format!(
                "raster cell value {bad} is not a state index (there are {} states)",
                self.states.len()
            )));
        }
        if let OutsideRule::State { label } = &r.outside
            && !self.states.iter().any(|s| &s.label == label)
        {
            return Err(err(format!("outside rule names unknown state `{label}`")));
        }
        Ok(())
    }
}

/// All sign vectors a pattern stands for (bit i = character i; `+` = 1).
fn expand_pattern(pat: &str, k: usize) -> std::result::Result<Vec<u32>, String> {
    let chars: Vec<char> = pat.chars().collect();
    if chars.len() != k {
        return Err(format!(
            "has {} characters, expected one per constraint ({k})",
            chars.len()
        ));
    }
    let mut out = vec![0u32];
    for (i, ch) in chars.iter().enumerate() {
        match ch {
            '+' => out.iter_mut().for_each(|v| *v |= 1 << i),
            '-' => {}
            '*' => {
                let with: Vec<u32> = out.iter().map(|v| v | (1 << i)).collect();
                out.extend(with);
            }
            other => return Err(format!("character `{other}` is not one of + - *")),
        }
    }
    Ok(out)
}

/// A sign vector written as a pattern string.
pub(crate) fn format_vector(v: u32, k: usize) -> String {
    (0..k)
        .map(|i| if v & (1 << i) != 0 { '+' } else { '-' })
        .collect()
}

/// Expands every state's patterns into a `2^k` table of state indices (`u16::MAX` = none).
pub(crate) fn pattern_table(spec: &CalculusSpec) -> Vec<u16> {
    let k = spec.constraints.len();
    let mut table = vec![u16::MAX; 1 << k];
    for (si, s) in spec.states.iter().enumerate() {
        for pat in &s.cells {
            // Patterns were checked by `check_static`.
            for v in expand_pattern(pat, k).unwrap_or_default() {
                table[v as usize] = si as u16;
            }
        }
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_expand_wildcards() {
        let mut v = expand_pattern("+*-", 3).expect("valid");
        v.sort_unstable();
        assert_eq!(v, vec![0b001, 0b011]);
        assert!(expand_pattern("+x", 2).is_err());
        assert!(expand_pattern("+", 2).is_err());
    }
}
