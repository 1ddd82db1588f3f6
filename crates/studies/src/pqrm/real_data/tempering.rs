//! The real-data report's tempering part: τ chosen from the data beside τ = 1, every τ tried,
//! the held-out score against τ, and the sensor models compared at fixed τ.

use serde_json::json;

use pqrm::calibration::{CALIBRATED_ECE, CALIBRATED_GAP, MIN_BIN, is_calibrated};
use pqrm::study::SensorVariant;

use super::Tempering;
use super::report::yes_no;
use crate::report::{Attachment, Cell, Column, Figure, Line, Plot, Table};

/// The held-out log score against τ, per calculus, relative to τ = 1.
pub(super) fn temper_figure(t: &Tempering) -> Figure {
    let line = |name: String, points: Vec<(f64, f64)>| Line {
        name,
        points,
        err: None,
        reference: false,
    };
    Figure {
        name: "temper_fit".into(),
        title: "Held-out log score against τ (relative to τ = 1; the chosen τ is the maximum)"
            .into(),
        x_label: "log10 τ".into(),
        y_label: "gain in mean log predictive probability (nats)".into(),
        plot: Plot::Lines {
            series: t
                .fits
                .iter()
                .map(|f| {
                    let base = f.untempered_score().unwrap_or(0.0);
                    line(
                        f.calculus.clone(),
                        f.scores
                            .iter()
                            .map(|p| (p.temper.log10(), p.log_score - base))
                            .collect(),
                    )
                })
                .collect(),
        },
    }
}

pub(super) fn tempering_table(t: &Tempering) -> Table {
    let better = t
        .chosen
        .iter()
        .zip(&t.untempered)
        .filter(|(c, u)| c.calibration.ece <= u.calibration.ece)
        .count();
    let mut table = Table::new(
        "tempering",
        "Tempering chosen from the data",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("temper", "τ"),
            Column::new("accuracy", "accuracy"),
            Column::new("p_ml_mean", "mean P(ML), τ = 1 → τ"),
            Column::new("ece", "ECE, τ = 1 → τ"),
            Column::new("max_gap", "largest gap, τ = 1 → τ"),
            Column::new("calibrated", "calibrated at τ"),
        ],
    )
    .caption(format!(
        "Eq. 2.10 counts every frame as independent evidence; frames of a robot standing still, or of one \
         geometry seen again and again, are not. τ is chosen per calculus without ground truth: the frames are cut into contiguous blocks, \
         each held out once, and τ is the exponent under which the other blocks' map best predicts the held-out frames (mean log predictive \
         probability; `temper.csv`, `temper_fit.svg`), read under the report's evidence model, so τ is a correction on top of that model \
         (both columns use it). Tempering changes no most-likely state — the error is the same — only how sure the map says it is. \
         The chosen τ lowers or keeps the expected calibration error for {better} of {} calculi. The criterion assumes that frames err \
         independently given the geometry (then it finds the τ a ground truth would pick: `crates/pqrm/tests/temper_fit.rs`); errors shared by \
         neighbouring frames make it hedge, and a fitted noise may already absorb them.",
        t.fits.len()
    ));
    let arrow = |a: f64, b: f64| Cell {
        csv: format!("{a};{b}"),
        text: format!("{a:.3} → {b:.3}"),
    };
    for ((f, c), u) in t.fits.iter().zip(&t.chosen).zip(&t.untempered) {
        table.push(vec![
            Cell::text(f.calculus.clone()),
            Cell::number(f.chosen, 3),
            Cell::number(1.0 - c.pqrm.error_rate, 3),
            arrow(u.pqrm.p_ml_mean, c.pqrm.p_ml_mean),
            arrow(u.calibration.ece, c.calibration.ece),
            arrow(u.calibration.max_gap, c.calibration.max_gap),
            yes_no(c.calibration.is_calibrated()),
        ]);
    }
    table
}

/// `temper.csv`: every τ tried per calculus, as before the move.
pub(super) fn temper_csv(t: &Tempering) -> Table {
    let mut table = Table::new(
        "temper",
        "Held-out log score per τ",
        ["calculus", "temper", "outlier_rate", "log_score", "chosen"]
            .iter()
            .map(|k| Column::new(k, k))
            .collect(),
    )
    .data_only();
    for f in &t.fits {
        for p in &f.scores {
            table.push(vec![
                Cell::text(f.calculus.clone()),
                Cell::text(p.temper.to_string()),
                Cell::text(p.outlier_rate.to_string()),
                Cell::fixed(p.log_score, 6),
                Cell::text((p.temper == f.chosen).to_string()),
            ]);
        }
    }
    table
}

/// `temper.json`: the fits beside the maps at τ = 1 and at the chosen τ, as before the move.
pub(super) fn temper_json(t: &Tempering) -> Attachment {
    let rows: Vec<serde_json::Value> = t
        .fits
        .iter()
        .zip(&t.chosen)
        .zip(&t.untempered)
        .map(|((f, c), u)| {
            json!({
                "fit": f,
                "untempered": {"p_ml_mean": u.pqrm.p_ml_mean, "calibration": u.calibration, "mean_entropy": u.pqrm.mean_entropy},
                "tempered": {"p_ml_mean": c.pqrm.p_ml_mean, "calibration": c.calibration, "mean_entropy": c.pqrm.mean_entropy},
            })
        })
        .collect();
    Attachment::text(
        "temper.json",
        serde_json::to_string_pretty(&rows).unwrap_or_default(),
    )
}

pub(super) fn sensor_models_table(sweep: &[SensorVariant]) -> Table {
    let mut t = Table::new(
        "sensor_models",
        "Sensor models and tempering",
        vec![
            Column::new("sensor", "sensor"),
            Column::new("temper", "τ"),
            Column::new("calculus", "calculus"),
            Column::new("error_rate", "PQRM error"),
            Column::new("majority_error_rate", "majority vote"),
            Column::new("beats_majority", "≤ majority").human_only(),
            Column::new("p_ml_mean", "mean P(ML)"),
            Column::new("ece", "ECE"),
            Column::new("max_gap", "largest gap"),
            Column::new("calibrated", "calibrated").human_only(),
        ],
    )
    .caption(format!(
        "The same frames mapped under each inverse sensor model and tempering exponent τ (each frame's \
         log-likelihood × τ). Heavy tails keep one outlier frame from ruling a state out; τ < 1 counts correlated frames as fewer \
         independent ones; every row reads frames as independent (eq. 2.10). Calibrated = ECE ≤ {CALIBRATED_ECE} and every P(ML) bin of ≥ {MIN_BIN} triplets within {CALIBRATED_GAP} of its accuracy."
    ));
    let num = |v: f64| Cell {
        csv: format!("{v:.4}"),
        text: format!("{v:.3}"),
    };
    for v in sweep {
        t.push(vec![
            Cell::text(v.sensor.label()),
            Cell::text(v.temper.to_string()),
            Cell::text(v.calculus.clone()),
            num(v.error_rate),
            num(v.majority_error_rate),
            yes_no(v.error_rate <= v.majority_error_rate),
            num(v.p_ml_mean),
            num(v.ece),
            num(v.max_gap),
            yes_no(is_calibrated(v.ece, v.max_gap)),
        ]);
    }
    t
}
