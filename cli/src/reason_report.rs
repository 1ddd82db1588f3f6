//! `qrm reason study`: runs `pqrm::reason_study`, writes JSON, CSV, figures and the report.
//! Every verdict in the report comes from `pqrm::reason_study::claims`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, ensure};
use pqrm::loaders::RangeBearingNoise;
use pqrm::reason::Fusion;
use pqrm::reason_study::{
    Predictors, ReasonCalculusResult, ReasonStudyConfig, Score, best_fusion, claims,
    run_reason_study,
};
use serde_json::json;

use crate::output::{CsvTable, Staging, write_atomic, write_picture};
use crate::reason_cmd::ReasonStudyArgs;
use qrm_plot::Series;

pub fn study(a: &ReasonStudyArgs) -> Result<()> {
    let input = a
        .input
        .clone()
        .unwrap_or_else(|| PathBuf::from("../shared/data/mrclam-dataset7"));
    let mut data = crate::pqrm_cmd::load_dataset(a.format, &input, RangeBearingNoise::MRCLAM)
        .context("loading the recording (choose it with --input)")?;
    if let Some(t) = &a.truth {
        data.truth = Some(pqrm::loaders::read_truth_csv(t)?);
    }
    ensure!(
        data.truth.is_some(),
        "{} has no surveyed truth: give --truth FILE (id,x,y)",
        input.display()
    );
    data.scans.retain(|s| s.observations.len() >= 3);
    if let Some(n) = a.max_frames {
        data.scans.truncate(n);
    }
    let mut config = if a.quick {
        ReasonStudyConfig::quick()
    } else {
        ReasonStudyConfig::default()
    };
    if let Some(c) = &a.calculi {
        config.calculi.clone_from(c);
    }
    config.seed = a.seed;
    config.map.seed = a.seed;
    config.validate()?;
    let pb = crate::progress::bar(config.work_units(), "reasoning study");
    let start = Instant::now();
    let results = run_reason_study(&data, &config, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let best = best_fusion(&results).unwrap_or_default();
    write_atomic(
        &out_dir.join("reason.json"),
        serde_json::to_string_pretty(&json!({
            "input": input.display().to_string(),
            "config": config,
            "frames": data.scans.len(),
            "best_fusion": best.name(),
            "results": results,
        }))?
        .as_bytes(),
    )?;
    scores_csv(&results)?.write(&out_dir.join("scores.csv"))?;
    let mut figures = Vec::new();
    for r in &results {
        figures.extend(reliability(&out_dir, r)?);
        if let Some(p) = &r.picture {
            let pts = |observed: bool| -> Vec<(f64, f64, f64)> {
                p.points
                    .iter()
                    .filter(|q| q.observed == observed)
                    .map(|q| (q.xy[0], q.xy[1], q.p_true))
                    .collect()
            };
            figures.extend(write_picture(
                &out_dir.join(format!("reference_pair_{}", r.calculus)),
                &qrm_plot::reference_pair(
                    &format!(
                        "{}: landmarks in the frame of {}→{}",
                        r.calculus, p.pair[0], p.pair[1]
                    ),
                    &pts(true),
                    &pts(false),
                )?,
            )?);
        }
    }
    let report = report(&input, &results, best, secs, data.scans.len());
    write_atomic(&out_dir.join("report.md"), report.as_bytes())?;
    print_summary(&results)?;
    outln!(
        "{} frames, {:.1} s; lowest log loss: {} fusion; wrote {} (report.md, reason.json, \
         scores.csv, {} figures)",
        data.scans.len(),
        secs,
        best.name(),
        a.out.display(),
        figures.len()
    )?;
    stage.commit()?;
    Ok(())
}

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

fn scores_csv(results: &[ReasonCalculusResult]) -> Result<CsvTable> {
    let mut csv = CsvTable::new([
        "calculus",
        "part",
        "predictor",
        "n",
        "error_rate",
        "top2_error",
        "mean_neighbor_distance",
        "log_loss",
        "coverage",
        "calibration_error",
    ])?;
    for r in results {
        for (part, pred, s) in rows(r) {
            csv.row([
                (r.calculus).to_string(),
                (part).to_string(),
                (pred).to_string(),
                (s.n).to_string(),
                format!("{:.4}", s.error_rate),
                format!("{:.4}", s.top2_error),
                format!("{:.4}", s.mean_neighbor_distance),
                format!("{:.4}", s.log_loss),
                format!("{:.4}", s.coverage),
                format!("{:.4}", s.calibration_error),
            ])?;
        }
    }
    Ok(csv)
}

fn reliability(out: &std::path::Path, r: &ReasonCalculusResult) -> Result<Vec<PathBuf>> {
    let curve = |s: &Score| -> Vec<(f64, f64)> {
        s.bins
            .iter()
            .filter(|b| b.count > 0)
            .map(|b| (b.mean_p, b.accuracy))
            .collect()
    };
    let mut series: Vec<Series> = r
        .hidden
        .inferred
        .iter()
        .map(|(k, s)| Series::line(format!("inferred ({k})"), curve(s)))
        .collect();
    if let Some(o) = &r.hidden.observed {
        series.push(Series::line("observed (map belief)", curve(o)));
    }
    series.push(Series::reference(
        "perfect calibration",
        vec![(0.0, 0.0), (1.0, 1.0)],
    ));
    write_picture(
        &out.join(format!("reliability_{}", r.calculus)),
        &qrm_plot::line_chart(
            &format!("{}: reliability of hidden-set predictions", r.calculus),
            "mean P(most likely state) in bin",
            "fraction right",
            &series,
        )?,
    )
}

/// A ratio that may be undefined (nothing to divide by).
fn ratio(v: Option<f64>) -> String {
    v.map_or_else(|| "–".to_owned(), |x| format!("{x:.3}"))
}

fn print_summary(results: &[ReasonCalculusResult]) -> Result<()> {
    outln!(
        "{:<14} {:<8} {:<24} {:>7} {:>8} {:>8} {:>8} {:>8}",
        "calculus",
        "part",
        "predictor",
        "n",
        "err",
        "top2",
        "logloss",
        "ECE"
    )?;
    for r in results {
        for (part, pred, s) in rows(r) {
            outln!(
                "{:<14} {:<8} {:<24} {:>7} {:>8.3} {:>8.3} {:>8.3} {:>8.3}",
                r.calculus,
                part,
                pred,
                s.n,
                s.error_rate,
                s.top2_error,
                s.log_loss,
                s.calibration_error
            )?;
        }
        let c = &r.check;
        outln!(
            "{:<14} check    {} sets, {} wrong; {} flagged, {} of them wrong (precision {}, recall {})",
            r.calculus,
            c.sets,
            c.wrong,
            c.flagged,
            c.flagged_wrong,
            ratio(c.precision),
            ratio(c.recall)
        )?;
    }
    Ok(())
}

fn report(
    input: &std::path::Path,
    results: &[ReasonCalculusResult],
    best: Fusion,
    secs: f64,
    frames: usize,
) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Reasoning over maps — {}\n\n{frames} frames, {secs:.1} s. The thesis builds compose \
         tables and calls compose-based reasoning \"one of the most useful capabilities of \
         QSRs\" (§3.3.2) but reports no measurement of it, so there is no thesis number to \
         stand beside ours; each claim below is judged by `pqrm::reason_study::claims`.\n",
        input.display()
    );
    let _ = writeln!(
        md,
        "- **hidden**: a fraction of the observed sets is hidden from the map and inferred from \
         the rest; scored against the surveyed truth beside the marginal prior (the frequency \
         of most likely states in the visible map), random, and the map's own belief of the \
         hidden set (what observing it gave).\n- **unseen**: the Monte Carlo world with a short \
         sensor range; every triplet the robot never saw at once is inferred by chained \
         composition (rounds); **reached** is the part of them some chain reached (the rest \
         stay uniform: no fourth landmark links them to anything observed).\n- **check**: \
         the most likely states of the full map under algebraic closure; flags are the entries \
         relaxed (greedily by belief) to restore consistency.\n\nLowest mean log loss on hidden \
         sets: **{}** fusion.\n",
        best.name()
    );
    let _ = writeln!(md, "## Claims\n\n| claim | ours | holds |\n|---|---|---|");
    for r in results {
        for c in claims(r, Fusion::default()) {
            let _ = writeln!(
                md,
                "| {} | {} | {} |",
                c.what,
                c.ours,
                if c.holds { "yes" } else { "**no**" }
            );
        }
    }
    let _ = writeln!(
        md,
        "\n## Scores\n\n| calculus | part | predictor | n | error | top-2 error | neighbour dist. | log loss | coverage | ECE |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in results {
        for (part, pred, s) in rows(r) {
            let _ = writeln!(
                md,
                "| {} | {part} | {pred} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                r.calculus,
                s.n,
                s.error_rate,
                s.top2_error,
                s.mean_neighbor_distance,
                s.log_loss,
                s.coverage,
                s.calibration_error
            );
        }
    }
    let _ = writeln!(
        md,
        "\n## Consistency check\n\n| calculus | sets | wrong ML | passes closure as is | flagged | flagged and wrong | precision | recall | base rate |\n|---|---|---|---|---|---|---|---|---|"
    );
    for r in results {
        let c = &r.check;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.3} |",
            r.calculus,
            c.sets,
            c.wrong,
            if c.consistent { "yes" } else { "no" },
            c.flagged,
            c.flagged_wrong,
            ratio(c.precision),
            ratio(c.recall),
            c.base_rate
        );
    }
    let _ = writeln!(
        md,
        "\nFigures: `reliability_CALCULUS.svg` (hidden-set predictions binned by P(ML)), \
         `reference_pair_CALCULUS.svg` (every landmark in the frame of the pair with the most \
         hidden sets: circles observed, triangles inferred, colour = probability of the true \
         state)."
    );
    md
}
