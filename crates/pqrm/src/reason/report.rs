//! What the reasoning commands hand a user: inferences as a file (`qrm reason infer`) and a
//! consistency check as text (`qrm reason check`).

use std::fmt::Write as _;

use qsr_core::Calculus;
use serde::Serialize;

use crate::evidence::EvidenceModel;
use crate::reason::check::MapCheck;
use crate::reason::inference::{Inference, Inferrer};

/// An inference below uniform entropy by more than this (nats) is "more informative than
/// uniform": a distribution the paths moved.
pub const INFORMATIVE_NATS: f64 = 0.05;

/// What someone inferring over a map read under `evidence` should know about how far the
/// inferences' probabilities were measured to hold; `None` for the filter's maps (the reason
/// study's own, `shared:4`). Composition fits its pool on the map's own beliefs, and a layout
/// map's beliefs all come from one set of positions: a path and the set it predicts share
/// the layout's error, so the fit cannot see it. Measured (reason study, hidden sets,
/// Datasets 2 / 5 / 7, `docs/reasoning.md` "Reasoning over a layout map"): EDC ECE 0.100 /
/// 0.034 / 0.120 over layout maps against 0.044 / 0.020 / 0.065 over the filter's, and no
/// tempering of the pool fixed it on all three.
#[must_use]
pub fn calibration_note(evidence: EvidenceModel) -> Option<&'static str> {
    match evidence {
        EvidenceModel::Layout => Some(
            "this is a layout map (evidence \"layout\"): inference over layout maps was measured \
             overconfident on two of three MRCLAM recordings, where inference over the filter's maps was \
             closer to calibrated (docs/reasoning.md, \"Reasoning over a layout map\"); for a map to reason over, map with \
             the filter (qrm map --evidence shared; Python: qrm.Pqrm)",
        ),
        EvidenceModel::Independent | EvidenceModel::Shared { .. } => None,
    }
}

/// One inferred set, with its most likely state and entropy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InferredSet {
    /// Entropy of `p` (nats).
    pub entropy: f64,
    /// The most likely state's label.
    pub ml: String,
    /// Probabilities in state order.
    pub p: Vec<f64>,
    /// Paths combined.
    pub paths: usize,
    /// The round that reached it (0: none, uniform).
    pub round: usize,
    /// The ordered set `[a, b, d]`.
    pub set: [u32; 3],
    /// The fourth landmarks that gave a path.
    pub via: Vec<u32>,
}

/// Inferences of one map, as `qrm reason infer` writes them (fields in alphabetical order,
/// as the file has always had them).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InferenceReport {
    /// The fitted pooling weight α.
    pub alpha: f64,
    /// Whether the pool divided the base rate out of each path and counted it once
    /// ([`Inferrer::divides_base_rate`](crate::reason::Inferrer::divides_base_rate)).
    pub base_rate: bool,
    /// The calculus's name.
    pub calculus: String,
    /// How composition entries shared a path's probability (`learned` or `uniform`).
    pub composition: &'static str,
    /// ε.
    pub epsilon: f64,
    /// The fusion rule's name.
    pub fusion: &'static str,
    /// The sets.
    pub inferences: Vec<InferredSet>,
    /// Rounds of chained inference.
    pub rounds: usize,
    /// The calculus's state labels.
    pub states: Vec<String>,
}

impl InferenceReport {
    /// The report of `inferences` made over a map of `calculus` by `inferrer`.
    #[must_use]
    pub fn new(calculus: &Calculus, inferrer: &Inferrer<'_>, inferences: &[Inference]) -> Self {
        let options = inferrer.options();
        let inferences = inferences
            .iter()
            .map(|inf| InferredSet {
                entropy: crate::metrics::entropy(&inf.p),
                ml: calculus.label(inf.ml_state()).to_owned(),
                p: inf.p.clone(),
                paths: inf.paths,
                round: inf.round,
                set: inf.set,
                via: inf.via.clone(),
            })
            .collect();
        Self {
            alpha: inferrer.alpha(),
            base_rate: inferrer.divides_base_rate(),
            calculus: calculus.name().to_owned(),
            composition: options.composition.name(),
            epsilon: options.epsilon,
            fusion: options.fusion.name(),
            inferences,
            rounds: options.rounds,
            states: calculus.labels().to_vec(),
        }
    }

    /// How many inferences are more informative than uniform ([`INFORMATIVE_NATS`]).
    #[must_use]
    pub fn informative(&self) -> usize {
        let uniform = (self.states.len() as f64).ln();
        self.inferences
            .iter()
            .filter(|i| i.entropy < uniform - INFORMATIVE_NATS)
            .count()
    }

    /// Why inferences say little, for people: how many had no path and how many had paths
    /// that composed to about uniform; `None` when every inference is informative (or there
    /// are none). Issue 40: `qrm reason infer` printed "0 more informative than uniform" and
    /// left the user to guess why.
    #[must_use]
    pub fn uninformative_note(&self) -> Option<String> {
        let total = self.inferences.len();
        let vague = total - self.informative();
        if vague == 0 {
            return None;
        }
        let no_path = self.inferences.iter().filter(|i| i.paths == 0).count();
        let composed = vague - no_path;
        let mut why = Vec::new();
        if no_path > 0 {
            why.push(format!(
                "{no_path} have no path — a set {{a, b, d}} is composed through a fourth landmark c \
                 from two sets that hold c, {{a, b, c}} and {{b, c, d}} in some order, and for these no \
                 landmark c has both among the map's sets (observed, or inferred within {} \
                 round{}), so they stay uniform",
                self.rounds,
                if self.rounds == 1 { "" } else { "s" }
            ));
        }
        if composed > 0 {
            why.push(format!(
                "{composed} have paths whose composition stays within {INFORMATIVE_NATS} nats of \
                 uniform (`{}`'s composition constrains little there, or the beliefs composed are \
                 themselves uncertain)",
                self.calculus
            ));
        }
        Some(format!(
            "{vague} of {total} inferred sets are no more informative than uniform: {}",
            why.join("; ")
        ))
    }
}

impl MapCheck {
    /// The check for people: the verdict, the first contradiction, the entries to relax.
    #[must_use]
    pub fn to_text(&self, calculus: &str) -> String {
        let verdict = if self.consistent { "pass" } else { "fail" };
        let mut s = format!(
            "{} sets of `{calculus}`: the most likely states {verdict} closure\n",
            self.sets
        );
        if let Some(c) = &self.contradiction {
            let _ = writeln!(s, "first contradiction: {c}");
        }
        if !self.flagged.is_empty() {
            let _ = writeln!(
                s,
                "{} entries to relax (irreducible, chosen greedily by belief; {} closures):",
                self.flagged.len(),
                self.closures
            );
            let _ = writeln!(s, "{:<18} {:<16} {:>8}", "set", "ML state", "P(ML)");
            for f in &self.flagged {
                let set = format!("{:?}", f.set);
                let _ = writeln!(s, "{set:<18} {:<16} {:>8.4}", f.state, f.p);
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_layout_map_gets_the_calibration_note() {
        let note = calibration_note(EvidenceModel::Layout).unwrap_or_default();
        assert!(
            note.contains("layout map") && note.contains("--evidence shared"),
            "{note}"
        );
        assert_eq!(calibration_note(EvidenceModel::Independent), None);
        assert_eq!(calibration_note(EvidenceModel::shared_default()), None);
    }

    fn set(p: Vec<f64>, paths: usize) -> InferredSet {
        InferredSet {
            entropy: crate::metrics::entropy(&p),
            ml: "a".into(),
            p,
            paths,
            round: usize::from(paths > 0),
            set: [1, 2, 3],
            via: Vec::new(),
        }
    }

    fn report(inferences: Vec<InferredSet>) -> InferenceReport {
        InferenceReport {
            alpha: 0.5,
            base_rate: false,
            calculus: "left-right".into(),
            composition: "uniform",
            epsilon: 0.01,
            fusion: "fitted",
            inferences,
            rounds: 2,
            states: vec!["a".into(), "b".into()],
        }
    }

    /// Issue 40: `qrm reason infer` on MRCLAM Dataset 7 said "0 more informative than
    /// uniform" and no more; the note says how many had no path and how many composed to
    /// about uniform.
    #[test]
    fn regression_an_uninformative_inference_run_says_why() {
        let uniform = || vec![0.5, 0.5];
        let mixed = report(vec![
            set(uniform(), 0),
            set(uniform(), 0),
            set(uniform(), 3),
            set(vec![0.9, 0.1], 2),
        ]);
        assert_eq!(mixed.informative(), 1);
        let note = mixed.uninformative_note().unwrap_or_default();
        assert!(note.starts_with("3 of 4 inferred sets"), "{note}");
        assert!(note.contains("2 have no path"), "{note}");
        assert!(note.contains("within 2 rounds"), "{note}");
        assert!(note.contains("1 have paths whose composition"), "{note}");
        let all_without = report(vec![set(uniform(), 0)]);
        let note = all_without.uninformative_note().unwrap_or_default();
        assert!(
            note.contains("1 have no path") && !note.contains("composition stays"),
            "{note}"
        );
        assert_eq!(
            report(vec![set(vec![0.99, 0.01], 1)]).uninformative_note(),
            None
        );
        assert_eq!(report(Vec::new()).uninformative_note(), None);
    }
}
