//! The printed forms of a calculus's tables, ternary and binary alike: maps keyed by label
//! (what JSON and Python show), text for people, and GQR's text form for GQR and SparQ users.
//! One definition each, so `qrm calculus compose --json`, Python's `Calculus.compose()` and
//! the GQR export cannot drift apart.
//!
//! Every form takes the calculus's labels (`labels[s.index()]` names state `s`), so the same
//! code serves [`crate::Calculus`] and [`crate::binary::BinaryCalculus`].

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde_json::json;

use crate::binary::ConverseTable;
use crate::{ComposeTable, NeighbourGraph, PermutationTable, StateId};

/// `{r: [t, ...]}`: a one-argument table by label.
pub type LabelledRows = BTreeMap<String, Vec<String>>;
/// `{r: {s: [t, ...]}}`: a composition table by label.
pub type LabelledCompose = BTreeMap<String, LabelledRows>;

fn ids(n: usize) -> impl Iterator<Item = StateId> {
    (0..n).map(|i| StateId(u16::try_from(i).unwrap_or(u16::MAX)))
}

fn names(labels: &[String], set: &[StateId]) -> Vec<String> {
    set.iter().map(|s| labels[s.index()].clone()).collect()
}

fn rows<'t>(labels: &[String], get: impl Fn(StateId) -> &'t [StateId]) -> LabelledRows {
    ids(labels.len())
        .map(|r| (labels[r.index()].clone(), names(labels, get(r))))
        .collect()
}

/// `heading`, then `  r  → {t, ...}` per state, the labels padded to `width`.
fn rows_text<'t>(
    heading: &str,
    labels: &[String],
    width: usize,
    get: impl Fn(StateId) -> &'t [StateId],
) -> String {
    let mut s = format!("{heading}\n");
    for r in ids(labels.len()) {
        let _ = writeln!(
            s,
            "  {:<width$} → {{{}}}",
            labels[r.index()],
            names(labels, get(r)).join(", ")
        );
    }
    s
}

impl ComposeTable {
    /// `{r: {s: [t, ...]}}` by label.
    #[must_use]
    pub fn labelled(&self, labels: &[String]) -> LabelledCompose {
        ids(labels.len())
            .map(|r| (labels[r.index()].clone(), rows(labels, |s| self.get(r, s))))
            .collect()
    }

    /// JSON `{"states": [...], "table": {r: {s: [t, ...]}}}`.
    #[must_use]
    pub fn to_json(&self, labels: &[String]) -> serde_json::Value {
        json!({"states": labels, "table": self.labelled(labels)})
    }

    /// `name: notation, N entries`, then `  r ∘ s = {t, ...}` per pair (`notation` says which
    /// relations are composed: `{AB:C} ∘ {BC:D} → {AB:D}` or `{A:B} ∘ {B:C} → {A:C}`).
    #[must_use]
    pub fn to_text(&self, name: &str, labels: &[String], notation: &str) -> String {
        let mut s = format!("{name}: {notation}, {} entries\n", self.n_entries());
        for r in ids(labels.len()) {
            for t in ids(labels.len()) {
                let _ = writeln!(
                    s,
                    "  {} ∘ {} = {{{}}}",
                    labels[r.index()],
                    labels[t.index()],
                    names(labels, self.get(r, t)).join(", ")
                );
            }
        }
        s
    }

    /// GQR's form: `r : s :: ( t1 t2 )` per pair.
    #[must_use]
    pub fn to_gqr(&self, labels: &[String]) -> String {
        let mut s = String::new();
        for r in ids(labels.len()) {
            for t in ids(labels.len()) {
                let each: String = names(labels, self.get(r, t))
                    .iter()
                    .map(|l| format!(" {l}"))
                    .collect();
                let _ = writeln!(
                    s,
                    "{} : {} :: ({each} )",
                    labels[r.index()],
                    labels[t.index()]
                );
            }
        }
        s
    }
}

impl PermutationTable {
    /// `{r: [t, ...]}` by label.
    #[must_use]
    pub fn labelled(&self, labels: &[String]) -> LabelledRows {
        rows(labels, |r| self.get(r))
    }

    /// JSON `{"states": [...], "op": name, "table": {r: [t, ...]}}`.
    #[must_use]
    pub fn to_json(&self, labels: &[String]) -> serde_json::Value {
        json!({"states": labels, "op": self.op().name(), "table": self.labelled(labels)})
    }

    /// `name: operation`, then `  r → {t, ...}` per state.
    #[must_use]
    pub fn to_text(&self, name: &str, labels: &[String]) -> String {
        rows_text(&format!("{name}: {}", self.op()), labels, 16, |r| {
            self.get(r)
        })
    }
}

impl ConverseTable {
    /// `{r: [t]}` by label.
    #[must_use]
    pub fn labelled(&self, labels: &[String]) -> LabelledRows {
        rows(labels, |r| self.get(r))
    }

    /// JSON `{"states": [...], "op": "converse", "table": {r: [t]}}`.
    #[must_use]
    pub fn to_json(&self, labels: &[String]) -> serde_json::Value {
        json!({"states": labels, "op": "converse", "table": self.labelled(labels)})
    }

    /// `name: converse (…)`, then `  r → {t}` per relation.
    #[must_use]
    pub fn to_text(&self, name: &str, labels: &[String]) -> String {
        let heading = format!("{name}: converse (X r Y ⇒ Y conv(r) X)");
        rows_text(&heading, labels, 12, |r| self.get(r))
    }

    /// GQR's form: `r :: t` per relation.
    #[must_use]
    pub fn to_gqr(&self, labels: &[String]) -> String {
        let mut s = String::new();
        for r in ids(labels.len()) {
            let _ = writeln!(
                s,
                "{} :: {}",
                labels[r.index()],
                names(labels, self.get(r)).join(" ")
            );
        }
        s
    }
}

impl NeighbourGraph {
    /// JSON `{"states", "adjacent": [[a, b], ...], "distance", "diameter"}`.
    #[must_use]
    pub fn to_json(&self, labels: &[String]) -> serde_json::Value {
        let label = |s: &StateId| labels[s.index()].as_str();
        json!({
            "states": labels,
            "adjacent": self.edges().iter().map(|(a, b)| [label(a), label(b)]).collect::<Vec<_>>(),
            "distance": self.distance_matrix(),
            "diameter": self.diameter(),
        })
    }

    /// Adjacency lists and the distance matrix, for people.
    #[must_use]
    pub fn to_text(&self, name: &str, labels: &[String]) -> String {
        let mut s = format!(
            "{name}: {} states, {} adjacent pairs, diameter {:?}\n",
            labels.len(),
            self.edges().len(),
            self.diameter()
        );
        for r in ids(labels.len()) {
            let ns: Vec<&str> = self
                .neighbours_of(r)
                .iter()
                .map(|n| labels[n.index()].as_str())
                .collect();
            let _ = writeln!(s, "  {:<16} {}", labels[r.index()], ns.join(" "));
        }
        s.push_str("distance matrix (rows and columns in state order):\n");
        for row in self.distance_matrix() {
            let cells: Vec<String> = row
                .iter()
                .map(|d| d.map_or("-".into(), |d| d.to_string()))
                .collect();
            let _ = writeln!(s, "  {}", cells.join(" "));
        }
        s
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use crate::Calculus;
    use crate::binary::BinaryCalculus;

    #[test]
    fn the_forms_agree_with_the_table() {
        let c = Calculus::builtin("left-right").unwrap();
        let t = c.compose_table().unwrap();
        let by_label = t.labelled(c.labels());
        for r in c.states() {
            for s in c.states() {
                let want: Vec<&str> = t.get(r, s).iter().map(|x| c.label(*x)).collect();
                assert_eq!(by_label[c.label(r)][c.label(s)], want);
            }
        }
        let text = t.to_text(c.name(), c.labels(), "{AB:C} ∘ {BC:D} → {AB:D}");
        assert_eq!(text.lines().count(), 1 + c.n_states() * c.n_states());
        assert!(text.starts_with(&format!(
            "left-right: {{AB:C}} ∘ {{BC:D}} → {{AB:D}}, {} entries",
            t.n_entries()
        )));
    }

    #[test]
    fn gqr_forms_are_one_line_per_entry_in_gqrs_syntax() {
        let c = BinaryCalculus::builtin("star-4").unwrap();
        let t = c.compose_table().unwrap();
        let gqr = t.to_gqr(c.labels());
        assert_eq!(gqr.lines().count(), c.n_states() * c.n_states());
        for line in gqr.lines() {
            let (head, set) = line.split_once(" :: ").unwrap();
            assert_eq!(head.split(" : ").count(), 2, "{line}");
            assert!(set.starts_with("( ") && set.ends_with(" )"), "{line}");
        }
        let conv = c.converse().to_gqr(c.labels());
        assert_eq!(conv.lines().count(), c.n_states());
        assert!(conv.lines().all(|l| l.split(" :: ").count() == 2));
    }
}
