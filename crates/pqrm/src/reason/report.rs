//! What the reasoning commands hand a user: inferences as a file (`qrm reason infer`) and a
//! consistency check as text (`qrm reason check`).

use std::fmt::Write as _;

use qsr_core::Calculus;
use serde::Serialize;

use crate::reason::check::MapCheck;
use crate::reason::inference::{InferOptions, Inference};

/// An inference below uniform entropy by more than this (nats) is "more informative than
/// uniform": a distribution the paths moved.
pub const INFORMATIVE_NATS: f64 = 0.05;

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
    /// The calculus's name.
    pub calculus: String,
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
    /// The report of `inferences` made over a map of `calculus` with `options` and α.
    #[must_use]
    pub fn new(
        calculus: &Calculus,
        options: &InferOptions,
        alpha: f64,
        inferences: &[Inference],
    ) -> Self {
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
            alpha,
            calculus: calculus.name().to_owned(),
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
