//! A calculus described: for people (`qrm calculus show`) and for programs (`--json`), ternary
//! and binary alike — its frame, its states and what its partition is made of.

use std::fmt::Write as _;

use serde_json::{Value, json};

use crate::binary::BinaryCalculus;
use crate::{Calculus, FrameKind, Shape};

impl Calculus {
    /// Name, frame, states (with their cells, for a spec's merge table), constraints and
    /// raster, as text.
    #[must_use]
    pub fn describe(&self) -> String {
        let spec = self.spec();
        let mut s = format!("{} — {}\n", self.name(), self.description());
        let frame = self.frame();
        let _ = writeln!(
            s,
            "frame: {} ({} numbers per line for `classify`)",
            frame.as_str(),
            frame.input_len()
        );
        let _ = writeln!(
            s,
            "states: {} (max entropy {:.3} nats)",
            self.n_states(),
            self.max_entropy()
        );
        for st in self.states() {
            let cells = &spec.states[st.index()].cells;
            if cells.is_empty() {
                let _ = writeln!(s, "  {:>3}  {}", st.0, self.label(st));
            } else {
                let _ = writeln!(
                    s,
                    "  {:>3}  {:<16} cells {}",
                    st.0,
                    self.label(st),
                    cells.join(" ")
                );
            }
        }
        if !spec.constraints.is_empty() {
            s.push_str("constraints (sign pattern order):\n");
            for (i, k) in spec.constraints.iter().enumerate() {
                let geom = match k.shape {
                    Shape::Line { a, b, c } => format!("line {a}·x + {b}·y + {c} = 0"),
                    Shape::Circle { center, radius } => format!(
                        "circle centre ({}, {}) radius {radius}",
                        center[0], center[1]
                    ),
                };
                let _ = writeln!(
                    s,
                    "  {i}  {:<10} {geom}, zero set joins the {:?} side",
                    k.name, k.zero
                );
            }
        }
        if let Some(r) = &spec.raster {
            let _ = writeln!(
                s,
                "raster: {}x{} over {:?}, outside: {:?}",
                r.nx, r.ny, r.window, r.outside
            );
        }
        s
    }

    /// [`Calculus::describe`] as JSON: `name, description, frame, arity, input_len, n_states,
    /// max_entropy, states [{id, label}], constraints, raster`.
    #[must_use]
    pub fn describe_json(&self) -> Value {
        let spec = self.spec();
        let arity = match self.frame() {
            FrameKind::BinaryOriented => 2,
            FrameKind::Ternary | FrameKind::Extended => 3,
        };
        json!({
            "name": self.name(),
            "description": self.description(),
            "frame": self.frame().as_str(),
            "arity": arity,
            "input_len": self.frame().input_len(),
            "n_states": self.n_states(),
            "max_entropy": self.max_entropy(),
            "states": self.states().map(|s| json!({"id": s.0, "label": self.label(s)})).collect::<Vec<_>>(),
            "constraints": spec.constraints,
            "raster": spec.raster.as_ref().map(|r| json!({"window": r.window, "nx": r.nx, "ny": r.ny, "outside": r.outside})),
        })
    }
}

impl BinaryCalculus {
    /// Name, input, sectors, relations and the table hash (the disk cache's key), as text.
    #[must_use]
    pub fn describe(&self) -> String {
        let mut s = format!("{} — {}\n", self.name(), self.description());
        let _ = writeln!(
            s,
            "binary calculus, {} numbers per line for `classify`, {} sectors per point",
            self.input_len(),
            self.partition().n_sectors()
        );
        let _ = writeln!(s, "relations: {}", self.n_states());
        for r in self.states() {
            let _ = writeln!(s, "  {:>4}  {}", r.0, self.label(r));
        }
        let _ = writeln!(s, "table hash (disk cache key): {:016x}", self.table_hash());
        s
    }

    /// [`BinaryCalculus::describe`] as JSON: `name, description, frame, arity, input_len,
    /// n_states, sectors, states [{id, label}], table_hash`.
    #[must_use]
    pub fn describe_json(&self) -> Value {
        json!({
            "name": self.name(),
            "description": self.description(),
            "frame": if self.is_oriented() { "binary-opra" } else { "binary-star" },
            "arity": 2,
            "input_len": self.input_len(),
            "n_states": self.n_states(),
            "sectors": self.partition().n_sectors(),
            "states": self.states().map(|s| json!({"id": s.0, "label": self.label(s)})).collect::<Vec<_>>(),
            "table_hash": format!("{:016x}", self.table_hash()),
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    #[test]
    fn a_description_lists_every_state_and_its_json_agrees() {
        let c = Calculus::builtin("double-cross").unwrap();
        let text = c.describe();
        for s in c.states() {
            assert!(text.contains(c.label(s)), "{}", c.label(s));
        }
        assert!(text.contains("constraints (sign pattern order):"));
        let j = c.describe_json();
        assert_eq!(j["n_states"], c.n_states());
        assert_eq!(j["states"].as_array().unwrap().len(), c.n_states());
        assert_eq!(j["arity"], 3);
        let b = BinaryCalculus::builtin("opra-2").unwrap();
        assert_eq!(b.describe().lines().count(), 3 + b.n_states() + 1);
        assert_eq!(b.describe_json()["frame"], "binary-opra");
    }
}
