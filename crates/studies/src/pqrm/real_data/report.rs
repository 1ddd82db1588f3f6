//! The real-data report: the maps beside the baselines and the thesis's New College numbers,
//! the thesis's claims of §2.3.2 judged on the recording, the reliability diagram, tempering,
//! sensor models and many robots; the CSV and JSON files of the old `qrm pqrm real` keep
//! their names and contents.

use pqrm::calibration::{CALIBRATED_ECE, CALIBRATED_GAP, MIN_BIN};
use pqrm::robots::RobotComparison;
use pqrm::study::RealCalculusResult;
use serde_json::json;

use super::tempering::{
    sensor_models_table, temper_csv, temper_figure, temper_json, tempering_table,
};
use super::{RealDataConfig, RealDataOutput};
use crate::report::{Attachment, Cell, Claim, Column, Figure, Line, Plot, Report, Table, Verdict};

/// The thesis's New College maps (EDC, §2.3.2, Figs 2.14–2.15): mean entropy and mean
/// neighbour distance per way of extracting landmarks.
pub const THESIS_NEW_COLLEGE: [(&str, f64, f64); 3] = [
    ("Stereo", 0.7, 0.13),
    ("Sampled Stereo", 1.3, 0.95),
    ("Monocular", 1.7, 1.3),
];

/// The report of a run.
#[must_use]
pub fn report(config: &RealDataConfig, out: &RealDataOutput) -> Report {
    let m = &out.main;
    let mut tables = vec![
        maps_table(&m.results),
        beside_thesis_table(&m.results),
        calibration_table(&m.results),
        reliability_table(&m.results),
        real_csv(&m.results),
    ];
    let mut attachments = vec![real_json(out)];
    if let Some(t) = &m.tempering {
        tables.push(tempering_table(t));
        tables.push(temper_csv(t));
        attachments.push(temper_json(t));
    }
    tables.push(sensor_models_table(&out.sensor_models));
    let recording_rows = super::recordings::rows(out);
    tables.push(super::recordings::table(&recording_rows));
    tables.push(super::recordings::survey_table(&recording_rows));
    if !m.robots.is_empty() {
        tables.push(many_robots_table(&m.robots));
        tables.push(robots_csv(&m.robots));
        attachments.push(Attachment::text(
            "robots.json",
            serde_json::to_string_pretty(&m.robots).unwrap_or_default(),
        ));
    }
    Report {
        title: format!(
            "PQRM on {} (the analogue of thesis §2.3.2)",
            m.recording.title
        ),
        setup: setup(config, out),
        tables,
        claims: claims(&m.results)
            .into_iter()
            .chain(super::recordings::claims(&recording_rows))
            .collect(),
        figures: figures(out)
            .into_iter()
            .chain(super::recordings::figures(&recording_rows))
            .collect(),
        notes: notes(out),
        attachments,
    }
}

fn setup(config: &RealDataConfig, out: &RealDataOutput) -> String {
    let r = &out.main.recording;
    let check = &r.noise_check;
    let mut s = format!(
        "{}\n\n",
        super::recordings::evidence_sentence(config.evidence)
    );
    for sus in &check.suspects {
        s.push_str(&format!(
            "**Warning: the survey of landmark {} disagrees with the measurements** (median |z| {:.1} over {} pairs, the recording's median {:.2}): \
             swapped, moved or misidentified? Every triplet with it is scored against a truth that may be wrong.\n\n",
            sus.landmark, sus.median_abs_z, sus.pairs, check.z_median_abs
        ));
    }
    let source = r.noise_fit.map_or_else(
        || "given in the config".to_owned(),
        |f| {
            format!(
                "fitted from the recording without ground truth: {} residuals of {} landmark pairs, outlier rate {:.1} %",
                f.residuals,
                f.pairs,
                100.0 * f.outlier_rate
            )
        },
    );
    s.push_str(&format!(
        "{} frames with three or more landmarks; noise model σ_r = {:.4} m, σ_b = {:.5} rad ({source}).\n\n",
        r.frames, r.noise.sigma_range, r.noise.sigma_bearing
    ));
    if r.skipped_measurements > 0 {
        s.push_str(&format!(
            "Measurements skipped on purpose by the loader (robot-to-robot sightings, barcodes without a surveyed landmark): {}.\n\n",
            r.skipped_measurements
        ));
    }
    if let Some(g) = r.gated {
        s.push_str(&format!(
            "Gross outliers gated (a detection whose distances to its frame's other landmarks are off their medians by more than `gate_sigmas` σ): {} of {} detections.\n\n",
            g.detections, g.of
        ));
    }
    s.push_str(&format!(
        "Noise model check (pairs of landmarks seen in one frame, measured vs surveyed distance): {} pairs, normalised residual std {:.2} \
         (1.0 if the model were right), median |z| {:.2} (0.67), {:.1} % beyond 3σ (0.3 %), median absolute error {:.3} m.",
        check.pairs,
        check.z_std,
        check.z_median_abs,
        100.0 * check.outlier_fraction,
        check.median_abs_error
    ));
    s
}

fn maps_table(results: &[RealCalculusResult]) -> Table {
    let mut t = Table::new(
        "maps",
        "Maps and baselines",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("sets", "sets"),
            Column::new("mean_entropy", "PQRM entropy"),
            Column::new("error_rate", "PQRM error"),
            Column::new("majority_error_rate", "majority vote error"),
            Column::new("per_frame_error_rate", "per-frame error"),
            Column::new("random_error_rate", "random error"),
            Column::new("mean_neighbor_distance", "PQRM neighbour distance"),
            Column::new("top_2_error", "top-2 error"),
        ],
    )
    .caption(
        "Baselines. *Majority vote*: each triplet takes the state most frames' single-frame ML states agree on, scored once per triplet \
         as the map is — the fair baseline a filter must beat. *Per-frame*: every (triplet, frame) scored once, so often-seen (mostly easy) \
         triplets weigh more; it measures a single frame, not a map.",
    );
    for r in results {
        t.push(vec![
            Cell::text(r.calculus.clone()),
            Cell::int(r.pqrm.n_sets as u64),
            Cell::number(r.pqrm.mean_entropy, 3),
            Cell::number(r.pqrm.error_rate, 3),
            Cell::number(r.majority.error_rate, 3),
            Cell::number(r.per_frame.error_rate, 3),
            Cell::number(r.random.error_rate, 3),
            Cell::number(r.pqrm.mean_neighbor_distance, 3),
            Cell::maybe(r.pqrm.top_n_error.get(1).copied(), |v| Cell::number(v, 3)),
        ]);
    }
    t
}

fn edc(results: &[RealCalculusResult]) -> Option<&RealCalculusResult> {
    results.iter().find(|r| r.calculus == "edc")
}

fn beside_thesis_table(results: &[RealCalculusResult]) -> Table {
    let mut t = Table::new(
        "beside_thesis",
        "EDC beside the thesis's New College maps",
        vec![
            Column::new("map", "map"),
            Column::new("mean_entropy", "mean entropy (nats)"),
            Column::new("mean_neighbor_distance", "mean neighbour distance"),
        ],
    )
    .caption(
        "The thesis's numbers come from another sensor (stereo salient regions) and a ground truth built from the same data; \
         MRCLAM's truth is surveyed, so the comparison is of orders of magnitude only and no verdict is drawn from it.",
    );
    for (method, h, nd) in THESIS_NEW_COLLEGE {
        t.push(vec![
            Cell::text(format!("thesis, New College ({method})")),
            Cell::number(h, 2),
            Cell::number(nd, 2),
        ]);
    }
    if let Some(r) = edc(results) {
        t.push(vec![
            Cell::text("ours"),
            Cell::number(r.pqrm.mean_entropy, 3),
            Cell::number(r.pqrm.mean_neighbor_distance, 3),
        ]);
    }
    t
}

pub(super) fn yes_no(yes: bool) -> Cell {
    Cell::text(if yes { "yes" } else { "**no**" })
}

fn calibration_table(results: &[RealCalculusResult]) -> Table {
    let mut t = Table::new(
        "calibration",
        "Calibration",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("beats_majority", "PQRM error ≤ majority vote"),
            Column::new("ece", "calibration: ECE"),
            Column::new(
                "max_gap",
                &format!("largest bin gap (bins ≥ {MIN_BIN} triplets)"),
            ),
            Column::new(
                "calibrated",
                &format!("calibrated (ECE ≤ {CALIBRATED_ECE}, every gap ≤ {CALIBRATED_GAP})"),
            ),
            Column::new("log_loss", "log loss"),
            Column::new("vote_log_loss", "smoothed vote log loss"),
            Column::new("beats_vote", "log loss < smoothed vote"),
        ],
    )
    .caption(
        "Log loss: mean −ln P(true state) over the scored triplets. Smoothed vote: each triplet's histogram of single-frame \
         ML states with one pseudo-count per state — a map whose probabilities lose to it says less than counting frames.",
    );
    for r in results {
        t.push(vec![
            Cell::text(r.calculus.clone()),
            Cell {
                csv: (r.pqrm.error_rate <= r.majority.error_rate).to_string(),
                text: format!(
                    "{} ({:.3} vs {:.3})",
                    if r.pqrm.error_rate <= r.majority.error_rate {
                        "yes"
                    } else {
                        "**no**"
                    },
                    r.pqrm.error_rate,
                    r.majority.error_rate
                ),
            },
            Cell::number(r.calibration.ece, 3),
            Cell::number(r.calibration.max_gap, 3),
            yes_no(r.calibration.is_calibrated()),
            Cell::number(r.log_loss, 3),
            Cell::number(r.vote_log_loss, 3),
            yes_no(r.log_loss < r.vote_log_loss),
        ]);
    }
    t
}

fn reliability_table(results: &[RealCalculusResult]) -> Table {
    let mut t = Table::new(
        "reliability",
        "Reliability diagram",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("bin", "P(ML) bin"),
            Column::new("triplets", "triplets"),
            Column::new("mean_p_ml", "mean P(ML)"),
            Column::new("accuracy", "accuracy"),
        ],
    )
    .caption("Triplets binned by P(ML); a calibrated map has accuracy ≈ mean P(ML) in every bin.");
    for r in results {
        for b in &r.calibration.bins {
            t.push(vec![
                Cell::text(r.calculus.clone()),
                Cell::text(format!("[{}, {})", b.lo, b.hi)),
                Cell::int(b.n as u64),
                Cell::number(b.mean_p_ml, 3),
                Cell::number(b.accuracy, 3),
            ]);
        }
    }
    t
}

/// `real.csv`: PQRM, the majority vote and single frames per calculus, as before the study
/// moved (four decimals).
fn real_csv(results: &[RealCalculusResult]) -> Table {
    let mut t = Table::new(
        "real",
        "Every method per calculus",
        [
            "calculus",
            "method",
            "n",
            "mean_entropy",
            "error_rate",
            "mean_neighbor_distance",
            "top_n_error",
        ]
        .iter()
        .map(|k| Column::new(k, k))
        .collect(),
    )
    .data_only();
    let f4 = |v: f64| Cell::fixed(v, 4);
    let top = |v: &[f64]| {
        Cell::text(
            v.iter()
                .map(|x| format!("{x:.4}"))
                .collect::<Vec<_>>()
                .join(";"),
        )
    };
    for r in results {
        let c = || Cell::text(r.calculus.clone());
        t.push(vec![
            c(),
            Cell::text("pqrm"),
            Cell::int(r.pqrm.n_scored as u64),
            f4(r.pqrm.mean_entropy),
            f4(r.pqrm.error_rate),
            f4(r.pqrm.mean_neighbor_distance),
            top(&r.pqrm.top_n_error),
        ]);
        t.push(vec![
            c(),
            Cell::text("majority-vote"),
            Cell::int(r.majority.n as u64),
            Cell::text(""),
            f4(r.majority.error_rate),
            f4(r.majority.mean_neighbor_distance),
            Cell::text(""),
        ]);
        t.push(vec![
            c(),
            Cell::text("per-frame"),
            Cell::int(r.per_frame.n as u64),
            f4(r.per_frame.mean_entropy),
            f4(r.per_frame.error_rate),
            f4(r.per_frame.mean_neighbor_distance),
            top(&r.per_frame.top_n_error),
        ]);
    }
    t
}

/// `real.json`: the main run's results and the recording's summary, as before the move.
fn real_json(out: &RealDataOutput) -> Attachment {
    let r = &out.main.recording;
    let value = json!({
        "results": out.main.results,
        "noise_check": r.noise_check,
        "frames": r.frames,
        "noise": r.noise,
        "noise_fit": r.noise_fit,
        "gated": r.gated,
        "skipped_measurements": r.skipped_measurements,
    });
    Attachment::text(
        "real.json",
        serde_json::to_string_pretty(&value).unwrap_or_default(),
    )
}

/// A count of the calculi for which `holds`, and whether it holds for all.
fn count_of<'a>(
    results: &'a [RealCalculusResult],
    holds: impl Fn(&RealCalculusResult) -> bool,
    show: impl Fn(&'a RealCalculusResult) -> String,
) -> (String, bool) {
    let n = results.iter().filter(|r| holds(r)).count();
    let detail: Vec<String> = results.iter().map(show).collect();
    (
        format!("{n} of {} calculi ({})", results.len(), detail.join("; ")),
        n == results.len() && n > 0,
    )
}

fn claims(results: &[RealCalculusResult]) -> Vec<Claim> {
    let top = |r: &RealCalculusResult, k: usize| r.pqrm.top_n_error.get(k).copied();
    let halves = |r: &RealCalculusResult| match (top(r, 0), top(r, 1)) {
        (Some(one), Some(two)) => two <= 0.5 * one,
        _ => false,
    };
    let (ours_half, all_half) = count_of(results, halves, |r| {
        format!(
            "{} {:.3} → {:.3}",
            r.calculus,
            top(r, 0).unwrap_or(f64::NAN),
            top(r, 1).unwrap_or(f64::NAN)
        )
    });
    let accuracy = |r: &RealCalculusResult| 1.0 - r.pqrm.error_rate;
    let (ours_cons, all_cons) = count_of(
        results,
        |r| r.pqrm.p_ml_mean <= accuracy(r),
        |r| {
            format!(
                "{} P(ML) {:.3} vs accuracy {:.3}",
                r.calculus,
                r.pqrm.p_ml_mean,
                accuracy(r)
            )
        },
    );
    let (ours_cal, all_cal) = count_of(
        results,
        |r| r.calibration.is_calibrated(),
        |r| {
            format!(
                "{} ECE {:.3}, gap {:.3}",
                r.calculus, r.calibration.ece, r.calibration.max_gap
            )
        },
    );
    let (ours_loss, all_loss) = count_of(
        results,
        |r| r.log_loss < r.vote_log_loss,
        |r| format!("{} {:.3} vs {:.3}", r.calculus, r.log_loss, r.vote_log_loss),
    );
    let (ours_vote, all_vote) = count_of(
        results,
        |r| r.pqrm.error_rate <= r.majority.error_rate,
        |r| {
            format!(
                "{} {:.3} vs {:.3}",
                r.calculus, r.pqrm.error_rate, r.majority.error_rate
            )
        },
    );
    vec![
        Claim {
            what: "Error halves from the most likely state to the two most likely (Fig 2.16a)".into(),
            thesis: "\"The error rates are reduced by half when the number of states output from the PQRM increases from 1 to 2\" (Stereo, every calculus)".into(),
            ours: ours_half,
            verdict: Verdict::agree_if(all_half),
            why: String::new(),
        },
        Claim {
            what: "The map is conservative: mean P(ML) ≤ accuracy".into(),
            thesis: "\"the map entropy is inflated, indicating that conservative estimates of the map certainty are produced\"".into(),
            ours: ours_cons,
            verdict: Verdict::agree_if(all_cons),
            why: "Eq. 2.10 counts every frame as independent evidence; frames of a robot standing still or of one geometry seen again and again are not, and make the map surer than it is (see tempering)".into(),
        },
        Claim {
            what: format!("The map's probabilities are consistent: ECE ≤ {CALIBRATED_ECE} and every P(ML) bin of ≥ {MIN_BIN} triplets within {CALIBRATED_GAP} of its accuracy"),
            thesis: "\"maps created with the PQRM have a consistent estimate of the distribution over qualitative states\" (§2.4)".into(),
            ours: ours_cal,
            verdict: Verdict::agree_if(all_cal),
            why: String::new(),
        },
        Claim {
            what: "The map's probabilities say more than counting frames: log loss below the smoothed vote's".into(),
            thesis: "the premise of a probabilistic map (§2.4); the thesis compares with no baseline".into(),
            ours: ours_loss,
            verdict: Verdict::agree_if(all_loss),
            why: String::new(),
        },
        Claim {
            what: "The filter beats voting frame by frame: PQRM error ≤ the per-triplet majority vote's".into(),
            thesis: "the premise of the recursive filter (eq. 2.10); the thesis compares with no baseline".into(),
            ours: ours_vote,
            verdict: Verdict::agree_if(all_vote),
            why: String::new(),
        },
    ]
}

fn figures(out: &RealDataOutput) -> Vec<Figure> {
    let results = &out.main.results;
    let nd_calculi = ["edc", "edc-lune", "triple-cross"];
    let nd = results
        .iter()
        .filter(|r| nd_calculi.contains(&r.calculus.as_str()))
        .map(|r| {
            let v = r
                .pqrm
                .neighbor_histogram
                .iter()
                .enumerate()
                .flat_map(|(d, n)| std::iter::repeat_n(d as f64, *n as usize))
                .collect();
            (r.calculus.clone(), v)
        })
        .collect();
    let line = |name: String, points: Vec<(f64, f64)>| Line {
        name,
        points,
        err: None,
        reference: false,
    };
    let mut figures = vec![
        Figure {
            name: "fig2_14_entropy_histogram".into(),
            title: format!(
                "Fig 2.14 analogue — entropy of map triplets ({})",
                short_title(&out.main.recording.title)
            ),
            x_label: "entropy (nats)".into(),
            y_label: String::new(),
            plot: Plot::Histogram {
                edges: (0..=15).map(|i| f64::from(i) * 0.2).collect(),
                groups: results
                    .iter()
                    .map(|r| (r.calculus.clone(), r.entropies.clone()))
                    .collect(),
            },
        },
        Figure {
            name: "fig2_15_neighbor_distance".into(),
            title: "Fig 2.15 analogue — neighbour distance of the ML state".into(),
            x_label: "neighbour distance".into(),
            y_label: String::new(),
            plot: Plot::Histogram {
                edges: (0..=5).map(f64::from).map(|v| v - 0.5).collect(),
                groups: nd,
            },
        },
        Figure {
            name: "fig2_16_top_n_error".into(),
            title: "Fig 2.16 analogue — error rate vs n most likely states".into(),
            x_label: "n".into(),
            y_label: "error rate".into(),
            plot: Plot::Lines {
                series: results
                    .iter()
                    .map(|r| {
                        line(
                            format!("{} PQRM", r.calculus),
                            r.pqrm
                                .top_n_error
                                .iter()
                                .enumerate()
                                .map(|(i, e)| ((i + 1) as f64, *e))
                                .take(8)
                                .collect(),
                        )
                    })
                    .collect(),
            },
        },
    ];
    figures.extend(out.main.tempering.as_ref().map(temper_figure));
    figures
}

/// "MRCLAM" for the MRCLAM recordings (the figure's title says which dataset, not which
/// directory), else the directory's name.
fn short_title(title: &str) -> String {
    if title.to_ascii_lowercase().starts_with("mrclam") {
        "MRCLAM".to_owned()
    } else {
        title.to_owned()
    }
}

fn many_robots_table(robots: &[RobotComparison]) -> Table {
    let mut t = Table::new(
        "many_robots",
        "Many robots, one map",
        vec![
            Column::new("calculus", "calculus"),
            Column::new("best_robot", "best robot: error (merged, same sets)"),
            Column::new("pooled_error", "pooled error"),
            Column::new("merged_error", "merged error"),
            Column::new("agreement_tv", "merged vs pooled: agreement, TV"),
            Column::new("entropy", "mean entropy pooled / merged"),
            Column::new("p_ml", "P(ML) pooled / merged"),
            Column::new("merged_beats_best_robot", "merged beats the best robot"),
        ],
    )
    .caption(
        "Each robot mapped alone, all robots' scans through one filter (pooled), and the robots' maps merged \
         by adding log-likelihoods (`qrm pqrm merge`; no common frame needed). A single robot sees fewer triplets, so its error is \
         compared with the merged map's error *on the same triplets*. Agreement: the share of triplets whose most likely state is \
         the same in the merged and pooled maps; TV: their mean total-variation distance (0 = identical beliefs; the rest is \
         sampling noise, the two filters draw different samples). Merging is the filter's: under the layout model (a map of \
         a whole recording, which merges with nothing) these are the filter's maps read under the shared-error model.",
    );
    let pair = |a: f64, b: f64| Cell {
        csv: format!("{a};{b}"),
        text: format!("{a:.3} / {b:.3}"),
    };
    for r in robots {
        let best = r
            .robots
            .iter()
            .min_by(|a, b| a.metrics.error_rate.total_cmp(&b.metrics.error_rate));
        t.push(vec![
            Cell::text(r.calculus.clone()),
            best.map_or_else(Cell::missing, |b| {
                Cell::text(format!(
                    "robot {}: {:.3} ({:.3})",
                    b.robot, b.metrics.error_rate, b.merged_error_on_these_sets
                ))
            }),
            Cell::number(r.pooled.error_rate, 3),
            Cell::number(r.merged.error_rate, 3),
            Cell {
                csv: format!("{};{}", r.ml_agreement, r.mean_total_variation),
                text: format!(
                    "{:.1} %, {:.3}",
                    100.0 * r.ml_agreement,
                    r.mean_total_variation
                ),
            },
            pair(r.pooled.mean_entropy, r.merged.mean_entropy),
            pair(r.pooled.p_ml_mean, r.merged.p_ml_mean),
            yes_no(r.merged_beats_best_robot),
        ]);
    }
    t
}

/// `robots.csv`: each robot, the pooled and the merged map per calculus, as before the move.
fn robots_csv(robots: &[RobotComparison]) -> Table {
    let mut t = Table::new(
        "robots",
        "Each robot, pooled and merged",
        [
            "calculus",
            "map",
            "scans",
            "sets",
            "error_rate",
            "mean_entropy",
            "p_ml_mean",
            "merged_error_on_same_sets",
        ]
        .iter()
        .map(|k| Column::new(k, k))
        .collect(),
    )
    .data_only();
    let f4 = |v: f64| Cell::fixed(v, 4);
    for r in robots {
        for row in &r.robots {
            t.push(vec![
                Cell::text(r.calculus.clone()),
                Cell::text(format!("robot{}", row.robot)),
                Cell::int(row.scans as u64),
                Cell::int(row.metrics.n_sets as u64),
                f4(row.metrics.error_rate),
                f4(row.metrics.mean_entropy),
                f4(row.metrics.p_ml_mean),
                f4(row.merged_error_on_these_sets),
            ]);
        }
        for (name, m) in [("pooled", &r.pooled), ("merged", &r.merged)] {
            t.push(vec![
                Cell::text(r.calculus.clone()),
                Cell::text(name),
                Cell::text(""),
                Cell::int(m.n_sets as u64),
                f4(m.error_rate),
                f4(m.mean_entropy),
                f4(m.p_ml_mean),
                Cell::text(""),
            ]);
        }
    }
    t
}

fn notes(out: &RealDataOutput) -> String {
    let mut s = String::new();
    if let Some(why) = &out.main.tempering_failed {
        s.push_str(&format!(
            "τ was not chosen from this recording ({why}); the tempering section is left out.\n\n"
        ));
    }
    s.push_str(
        "Notes. The thesis's §2.3.2 maps New College, whose landmarks are salient image regions and whose truth is built from the \
         same stereo data; here the truth is MRCLAM's survey, so the claims above are judged on a map scored against a truth it \
         did not make.",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(
        calculus: &str,
        top: [f64; 2],
        p_ml: f64,
        gap: f64,
        majority: f64,
    ) -> RealCalculusResult {
        let mut r: RealCalculusResult = serde_json::from_value(json!({
            "calculus": calculus,
            "pqrm": pqrm::MapMetrics::default(),
            "entropies": [],
            "per_frame": pqrm::study::FrameMetrics::default(),
            "majority": pqrm::study::VoteMetrics::default(),
            "calibration": pqrm::calibration::Calibration::default(),
            "random": pqrm::metrics::random_baselines(&qsr_core::Calculus::builtin("edc").unwrap_or_else(|_| unreachable!())),
        }))
        .unwrap_or_else(|e| panic!("{e}"));
        r.pqrm.top_n_error = top.to_vec();
        r.pqrm.error_rate = top[0];
        r.pqrm.p_ml_mean = p_ml;
        r.calibration.max_gap = gap;
        r.majority.error_rate = majority;
        r
    }

    fn verdict_of(claims: &[Claim], start: &str) -> Verdict {
        claims
            .iter()
            .find(|c| c.what.starts_with(start))
            .map(|c| c.verdict)
            .unwrap_or_else(|| panic!("no claim `{start}`"))
    }

    #[test]
    fn probabilities_must_beat_the_smoothed_vote_on_every_calculus() {
        let mut a = result("edc", [0.1, 0.05], 0.9, 0.01, 0.2);
        let mut b = result("left-right", [0.02, 0.0], 0.98, 0.01, 0.02);
        (a.log_loss, a.vote_log_loss) = (0.3, 1.2);
        (b.log_loss, b.vote_log_loss) = (0.05, 0.06);
        let says = "The map's probabilities say more";
        assert_eq!(
            verdict_of(&claims(&[a.clone(), b.clone()]), says),
            Verdict::Agree
        );
        b.log_loss = 0.06; // a tie is not "below"
        assert_eq!(verdict_of(&claims(&[a, b]), says), Verdict::Disagree);
    }

    #[test]
    fn an_overconfident_map_is_not_called_conservative() {
        // MRCLAM's full run: mean P(ML) 0.998 with accuracy 0.967 — surer than right
        let sure = [result("edc", [0.033, 0.015], 0.998, 0.035, 0.062)];
        assert_eq!(
            verdict_of(&claims(&sure), "The map is conservative"),
            Verdict::Disagree
        );
        let modest = [result("edc", [0.033, 0.015], 0.9, 0.035, 0.062)];
        assert_eq!(
            verdict_of(&claims(&modest), "The map is conservative"),
            Verdict::Agree
        );
    }

    #[test]
    fn every_calculus_must_halve_and_beat_the_vote() {
        let both = [
            result("edc", [0.1, 0.05], 0.9, 0.01, 0.2),
            result("left-right", [0.02, 0.0], 0.98, 0.01, 0.02),
        ];
        let c = claims(&both);
        assert_eq!(verdict_of(&c, "Error halves"), Verdict::Agree);
        assert_eq!(verdict_of(&c, "The filter beats voting"), Verdict::Agree);
        assert_eq!(
            verdict_of(&c, "The map's probabilities are consistent"),
            Verdict::Agree
        );
        let one_short = [
            result("edc", [0.1, 0.051], 0.9, 0.11, 0.099),
            result("left-right", [0.02, 0.0], 0.98, 0.01, 0.02),
        ];
        let c = claims(&one_short);
        assert_eq!(verdict_of(&c, "Error halves"), Verdict::Disagree);
        assert_eq!(verdict_of(&c, "The filter beats voting"), Verdict::Disagree);
        assert_eq!(
            verdict_of(&c, "The map's probabilities are consistent"),
            Verdict::Disagree
        );
        assert!(claims(&[]).iter().all(|c| c.verdict == Verdict::Disagree));
    }
}
