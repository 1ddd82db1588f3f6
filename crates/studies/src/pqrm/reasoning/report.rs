//! What the reasoning study says: its scores and consistency checks as tables, its claims
//! judged by `pqrm::reason_study::claims` (the thesis has no number to set beside them), the
//! reliability of hidden-set predictions and a reference pair's frame as figures, and
//! `reason.json` with every result.

use pqrm::reason::Fusion;
use pqrm::reason_study::{Predictors, ReasonCalculusResult, Score, best_fusion, claims};
use serde_json::json;

use super::{ReasonConfig, ReasonOutput};
use crate::report::{Attachment, Cell, Claim, Column, Figure, Line, Plot, Report, Table, Verdict};

/// What the thesis says beside each claim: nothing measured.
const THESIS: &str = "no measurement (§3.3.2 builds the tables, reports no inference)";

/// The report of a run.
#[must_use]
pub fn report(config: &ReasonConfig, output: &ReasonOutput) -> Report {
    let best = best_fusion(&output.results).unwrap_or_default();
    let mut figures = Vec::new();
    for r in &output.results {
        figures.push(reliability(r));
        figures.extend(reference_pair(r));
    }
    Report {
        title: format!("Reasoning over maps — {}", config.input.display()),
        setup: format!(
            "{} {}\n\n{}",
            crate::pqrm::real_data::recordings::evidence_sentence(config.study.evidence),
            reading_sentence(config),
            setup(output, best)
        ),
        tables: vec![scores_table(&output.results), check_table(&output.results)],
        claims: output
            .results
            .iter()
            .flat_map(|r| claims(r, Fusion::default()))
            .map(|c| Claim {
                what: c.what,
                thesis: THESIS.to_owned(),
                ours: c.ours,
                verdict: Verdict::holds_if(c.holds),
                why: String::new(),
            })
            .collect(),
        figures,
        notes: NOTES.to_owned(),
        attachments: vec![reason_json(config, output, best)],
    }
}

/// How the recording was read and how paths share a composition entry, from the config.
fn reading_sentence(config: &ReasonConfig) -> String {
    let fitted = config.format == crate::recording::RecordingFormat::Mrclam
        && config.noise.sigma_range.is_none()
        && config.noise.sigma_bearing.is_none()
        && config.noise.mode != Some(crate::recording::NoiseMode::Fixed);
    let noise = if fitted {
        "its range-bearing noise fitted from the recording"
    } else {
        "the noise given (or the recording's own covariances)"
    };
    let gated = if config.gate.unwrap_or(fitted) {
        "gross outliers gated (3σ)"
    } else {
        "every detection kept"
    };
    format!(
        "The recording is read as `qrm map` reads it: {noise}, {gated}. Composition entries \
         share a path's probability {}.",
        match config.study.composition {
            pqrm::reason::Composition::Learned =>
                "as often as the map's own observed quadruples show each state (`learned`)",
            pqrm::reason::Composition::Uniform => "evenly among their states (`uniform`)",
        }
    )
}

fn setup(output: &ReasonOutput, best: Fusion) -> String {
    format!(
        "{} frames. The thesis builds compose tables and calls compose-based reasoning \"one of \
         the most useful capabilities of QSRs\" (§3.3.2) but reports no measurement of it, so \
         there is no thesis number to stand beside ours; each claim below is judged by \
         `pqrm::reason_study::claims`.\n\n\
         - **hidden**: a fraction of the observed sets is hidden from the map and inferred from \
         the rest; scored against the surveyed truth beside the marginal prior (the frequency \
         of most likely states in the visible map), random, and the map's own belief of the \
         hidden set (what observing it gave).\n- **unseen**: the Monte Carlo world with a short \
         sensor range; every triplet the robot never saw at once is inferred by chained \
         composition (rounds); **reached** is the part of them some chain reached (the rest \
         stay uniform: no fourth landmark links them to anything observed).\n- **check**: \
         the most likely states of the full map under algebraic closure; flags are the entries \
         relaxed (greedily by belief) to restore consistency.\n\nLowest mean log loss on hidden \
         sets: **{}** fusion.\n",
        output.frames,
        best.name()
    )
}

const NOTES: &str = "Figures: `reliability_CALCULUS` (hidden-set predictions binned by \
P(ML)), `reference_pair_CALCULUS` (every landmark in the frame of the pair with the most hidden \
sets: circles observed, triangles inferred, colour = probability of the true state).";

/// Rows: part, predictor, score.
fn rows(r: &ReasonCalculusResult) -> Vec<(&'static str, String, &Score)> {
    let mut v = Vec::new();
    for (name, p) in [
        ("hidden", &r.hidden),
        ("unseen", &r.unseen),
        ("reached", &r.unseen_reached),
    ] {
        let p: &Predictors = p;
        for (k, s) in &p.inferred {
            v.push((name, format!("inferred ({k})"), s));
        }
        v.push((name, "prior".to_owned(), &p.prior));
        v.push((name, "random".to_owned(), &p.random));
        if let Some(o) = &p.observed {
            v.push((name, "observed (not hidden)".to_owned(), o));
        }
    }
    v
}

/// A score: four decimals in the CSV, three for a person.
fn score(v: f64) -> Cell {
    Cell {
        csv: format!("{v:.4}"),
        text: format!("{v:.3}"),
    }
}

/// What chance gives calibrated predictions of the same sets ([`Score::chance`]: its median
/// for `at` 0, 95th percentile for 1); empty where it was not computed (the baselines).
fn chance(s: &Score, at: usize) -> Cell {
    Cell::maybe((s.chance.draws > 0).then_some(s.chance.ece[at]), score)
}

fn scores_table(results: &[ReasonCalculusResult]) -> Table {
    let mut t = Table::new(
        "scores",
        "Scores",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("part", "part"),
            Column::new("predictor", "predictor"),
            Column::new("n", "n"),
            Column::new("error_rate", "error"),
            Column::new("top2_error", "top-2 error"),
            Column::new("mean_neighbor_distance", "neighbour dist."),
            Column::new("log_loss", "log loss"),
            Column::new("coverage", "coverage"),
            Column::new("calibration_error", "ECE"),
            Column::new("chance_ece_median", "ECE if calibrated: median"),
            Column::new("chance_ece_95", "95th pct"),
        ],
    );
    for r in results {
        for (part, pred, s) in rows(r) {
            t.push(vec![
                Cell::text(r.calculus.clone()),
                Cell::text(part),
                Cell::text(pred),
                Cell::int(s.n as u64),
                score(s.error_rate),
                score(s.top2_error),
                score(s.mean_neighbor_distance),
                score(s.log_loss),
                score(s.coverage),
                score(s.calibration_error),
                chance(s, 0),
                chance(s, 1),
            ]);
        }
    }
    t
}

/// A ratio that may be undefined (nothing to divide by).
fn ratio(v: Option<f64>) -> Cell {
    Cell::maybe(v, |x| Cell::number(x, 3))
}

fn check_table(results: &[ReasonCalculusResult]) -> Table {
    let mut t = Table::new(
        "check",
        "Consistency check",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("sets", "sets"),
            Column::new("wrong", "wrong ML"),
            Column::new("consistent", "passes closure as is"),
            Column::new("flagged", "flagged"),
            Column::new("flagged_wrong", "flagged and wrong"),
            Column::new("precision", "precision"),
            Column::new("recall", "recall"),
            Column::new("base_rate", "base rate"),
        ],
    );
    for r in results {
        let c = &r.check;
        t.push(vec![
            Cell::text(r.calculus.clone()),
            Cell::int(c.sets as u64),
            Cell::int(c.wrong as u64),
            Cell::text(if c.consistent { "yes" } else { "no" }),
            Cell::int(c.flagged as u64),
            Cell::int(c.flagged_wrong as u64),
            ratio(c.precision),
            ratio(c.recall),
            Cell::number(c.base_rate, 3),
        ]);
    }
    t
}

fn reliability(r: &ReasonCalculusResult) -> Figure {
    let curve = |s: &Score| -> Vec<(f64, f64)> {
        s.bins
            .iter()
            .filter(|b| b.count > 0)
            .map(|b| (b.mean_p, b.accuracy))
            .collect()
    };
    let line = |name: String, points: Vec<(f64, f64)>, reference: bool| Line {
        name,
        points,
        err: None,
        reference,
    };
    let mut series: Vec<Line> = r
        .hidden
        .inferred
        .iter()
        .map(|(k, s)| line(format!("inferred ({k})"), curve(s), false))
        .collect();
    if let Some(o) = &r.hidden.observed {
        series.push(line("observed (map belief)".into(), curve(o), false));
    }
    series.push(line(
        "perfect calibration".into(),
        vec![(0.0, 0.0), (1.0, 1.0)],
        true,
    ));
    Figure {
        name: format!("reliability_{}", r.calculus),
        title: format!("{}: reliability of hidden-set predictions", r.calculus),
        x_label: "mean P(most likely state) in bin".into(),
        y_label: "fraction right".into(),
        plot: Plot::Lines { series },
    }
}

fn reference_pair(r: &ReasonCalculusResult) -> Option<Figure> {
    let p = r.picture.as_ref()?;
    let pts = |observed: bool| -> Vec<(f64, f64, f64)> {
        p.points
            .iter()
            .filter(|q| q.observed == observed)
            .map(|q| (q.xy[0], q.xy[1], q.p_true))
            .collect()
    };
    Some(Figure {
        name: format!("reference_pair_{}", r.calculus),
        title: format!(
            "{}: landmarks in the frame of {}→{}",
            r.calculus, p.pair[0], p.pair[1]
        ),
        x_label: "x (normalised)".into(),
        y_label: "y (normalised)".into(),
        plot: Plot::ReferencePair {
            observed: pts(true),
            inferred: pts(false),
        },
    })
}

/// `reason.json`: the input, the settings, the frames, the best fusion and every result.
fn reason_json(config: &ReasonConfig, output: &ReasonOutput, best: Fusion) -> Attachment {
    let value = json!({
        "input": config.input.display().to_string(),
        "config": config.study,
        "frames": output.frames,
        "best_fusion": best.name(),
        "results": output.results,
    });
    Attachment::text(
        "reason.json",
        serde_json::to_string_pretty(&value).unwrap_or_default(),
    )
}
