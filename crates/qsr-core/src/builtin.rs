//! The built-in calculi (DESIGN §3). Each is a spec loaded through [`Calculus::from_spec`]
//! exactly like a user file: the point calculi from the TOML files in `calculi/`, `star-m`
//! from a generated spec.

use std::collections::BTreeMap;
use std::f64::consts::TAU;
use std::sync::{Mutex, OnceLock};

use crate::calculus::Calculus;
use crate::error::{QsrError, Result};
use crate::frame::FrameKind;
use crate::spec::{CalculusSpec, ConstraintSpec, Shape, Side, StateSpec};

/// Spec files shipped with the crate, by name.
pub const BUILTIN_SPECS: [(&str, &str); 10] = [
    ("edc", include_str!("../calculi/edc.toml")),
    ("edc-lune", include_str!("../calculi/edc-lune.toml")),
    ("triple-cross", include_str!("../calculi/triple-cross.toml")),
    ("double-cross", include_str!("../calculi/double-cross.toml")),
    ("quadrant", include_str!("../calculi/quadrant.toml")),
    ("left-right", include_str!("../calculi/left-right.toml")),
    ("single-cross", include_str!("../calculi/single-cross.toml")),
    (
        "relative-distance",
        include_str!("../calculi/relative-distance.toml"),
    ),
    ("tpcc", include_str!("../calculi/tpcc.toml")),
    (
        "front-between-behind",
        include_str!("../calculi/front-between-behind.toml"),
    ),
];

/// The six ternary point calculi of the thesis's Monte Carlo study (§2.3.1), finest first.
/// Every one is a merge of `edc`.
pub const POINT_CALCULI: [&str; 6] = [
    "edc",
    "edc-lune",
    "triple-cross",
    "double-cross",
    "quadrant",
    "left-right",
];

/// Names listed by `qrm calculus list` (`star-m` accepts any even m from 2 to 32).
pub const BUILTIN_NAMES: [&str; 12] = [
    "edc",
    "edc-lune",
    "triple-cross",
    "double-cross",
    "quadrant",
    "left-right",
    "single-cross",
    "relative-distance",
    "tpcc",
    "star-4",
    "star-8",
    "front-between-behind",
];

fn cache() -> &'static Mutex<BTreeMap<String, Calculus>> {
    static CACHE: OnceLock<Mutex<BTreeMap<String, Calculus>>> = OnceLock::new();
    CACHE.get_or_init(Mutex::default)
}

impl Calculus {
    /// A built-in calculus by name (see [`BUILTIN_NAMES`]; also `star-m` for even m).
    ///
    /// Built-ins are compiled once per process; clones share their cached derived structure.
    ///
    /// # Errors
    /// [`QsrError::UnknownCalculus`].
    pub fn builtin(name: &str) -> Result<Calculus> {
        if let Ok(map) = cache().lock()
            && let Some(c) = map.get(name)
        {
            return Ok(c.clone());
        }
        let spec = builtin_spec(name)?;
        let calculus = Calculus::from_spec(spec)?;
        if let Ok(mut map) = cache().lock() {
            map.insert(name.to_owned(), calculus.clone());
        }
        Ok(calculus)
    }
}

/// The spec of a built-in calculus.
///
/// # Errors
/// [`QsrError::UnknownCalculus`].
pub fn builtin_spec(name: &str) -> Result<CalculusSpec> {
    if let Some((_, text)) = BUILTIN_SPECS.iter().find(|(n, _)| *n == name) {
        return CalculusSpec::from_toml_str(text);
    }
    if let Some(m) = name
        .strip_prefix("star-")
        .and_then(|m| m.parse::<usize>().ok())
        && (2..=32).contains(&m)
        && m % 2 == 0
    {
        return Ok(star_spec(m));
    }
    if let Some(e) = crate::binary::name_out_of_range(name) {
        return Err(e);
    }
    Err(QsrError::UnknownCalculus {
        name: name.to_owned(),
        known: format!(
            "{}, star-m (even m, 2..=32); binary: opra-M (1 ≤ M ≤ {})",
            BUILTIN_NAMES.join(", "),
            crate::binary::MAX_OPRA_M
        ),
    })
}

/// `star-m`: m equal sectors about an oriented point, sector 0 centred on its heading.
///
/// Built from m/2 lines through the origin at angles (k + ½)·2π/m from the heading, so the
/// heading itself lies inside a sector (StarVars-like, thesis §4.2 Fig 4.1).
fn star_spec(m: usize) -> CalculusSpec {
    let sector = TAU / m as f64;
    let constraints: Vec<ConstraintSpec> = (0..m / 2)
        .map(|k| {
            let phi = (k as f64 + 0.5) * sector;
            ConstraintSpec {
                name: format!("ray-{k}"),
                // Normal of the line at angle phi ccw from +y: (cos phi, sin phi).
                shape: Shape::Line {
                    a: phi.cos(),
                    b: phi.sin(),
                    c: 0.0,
                },
                zero: Side::Positive,
            }
        })
        .collect();
    let states = (0..m)
        .map(|j| {
            let theta = j as f64 * sector;
            let cells = (0..m / 2)
                .map(|k| {
                    let phi = (k as f64 + 0.5) * sector;
                    if (phi - theta).sin() > 0.0 { '+' } else { '-' }
                })
                .collect::<String>();
            let label = star_label(m, j);
            StateSpec {
                label,
                cells: vec![cells],
            }
        })
        .collect();
    CalculusSpec {
        name: format!("star-{m}"),
        description: format!(
            "Star calculus: {m} equal sectors about an oriented point, sector 0 centred on its heading"
        ),
        frame: FrameKind::BinaryOriented,
        constraints,
        raster: None,
        states,
    }
}

/// The name of sector `j` of `star-m`: compass words for m = 4 and 8, `s{j}` otherwise
/// (shared by the oriented spec calculus and the binary STAR algebra).
pub(crate) fn star_label(m: usize, j: usize) -> String {
    const NAMES8: [&str; 8] = [
        "front",
        "front-left",
        "left",
        "back-left",
        "back",
        "back-right",
        "right",
        "front-right",
    ];
    match m {
        4 => NAMES8[2 * j].to_owned(),
        8 => NAMES8[j].to_owned(),
        _ => format!("s{j}"),
    }
}
