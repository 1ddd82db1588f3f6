//! `qrm qlink field`: the §4.4.2 field-site experiment in simulation (see `qlink::field`).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use qlink::field::{
    FieldMap, FieldParams, FieldResult, FieldSummary, FieldTrial, FieldVariant, TaskDraws,
    run_field, summarise,
};
use serde_json::json;

use crate::output::write_atomic;
use crate::qlink_cmd::FieldArgs;

/// Thesis Table 4.2: (|P|, paths, mean trajectory length m).
const THESIS_TABLE_4_2: [(usize, usize, f64); 6] = [
    (1, 2, 2.5),
    (2, 3, 6.5),
    (3, 2, 12.7),
    (4, 3, 14.3),
    (6, 2, 32.9),
    (8, 1, 38.4),
];

/// Runs `qrm qlink field`.
pub fn run(a: FieldArgs) -> Result<()> {
    let mut params = if a.quick {
        FieldParams::quick(a.seed)
    } else {
        FieldParams::full(a.seed)
    };
    if let Some(n) = a.trials {
        anyhow::ensure!(n > 0, "--trials must be at least 1");
        params.trials = n;
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let t0 = Instant::now();
    let pb = crate::progress::bar(0, "field trials");
    let variants = FieldVariant::ALL;
    let (field, draws, trials) =
        run_field(&params, &variants, &|n| pb.inc_length(n as u64), &|| {
            pb.inc(1)
        })?;
    pb.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    let summaries = summarise(&trials, &variants);
    let s = &field.stats;
    println!(
        "map: {} scans, {} ids ({} real landmarks of {}, {} false), {} + {} elements \
         (points + walls), effective range {:.1} m, {} of {} mapping detections aliased",
        s.frames,
        s.mapped_ids,
        s.real_landmarks,
        s.world_landmarks,
        s.false_landmarks,
        s.point_elements,
        s.wall_elements,
        s.effective_range,
        s.aliased_detections,
        s.detections
    );
    println!(
        "{:<30} {:>7} {:>8} {:>9} {:>9} {:>9} {:>9}",
        "variant", "trials", "no_path", "success", "rate", "aliasing", "features"
    );
    for x in &summaries {
        println!(
            "{:<30} {:>7} {:>8} {:>9} {:>8.1}% {:>9} {:>9}",
            x.variant.name(),
            x.trials,
            x.no_path,
            x.successes,
            100.0 * x.success_rate,
            x.perceptual_aliasing,
            x.insufficient_features + x.insufficient_features_and_aliasing
        );
    }
    println!(
        "start/goal draws: {} kept, redrawn {} trivial, {} no start, {} no path, {} blocked",
        draws.kept, draws.trivial, draws.no_start, draws.no_path, draws.blocked
    );
    write_outputs(&a.out, &params, &field, &draws, &trials, &summaries, secs)?;
    println!(
        "thesis: 13 of 18 (72 %); field experiment in {secs:.1} s; wrote {}",
        a.out.display()
    );
    Ok(())
}

fn write_outputs(
    out: &Path,
    params: &FieldParams,
    field: &FieldMap,
    draws: &TaskDraws,
    trials: &[FieldTrial],
    summaries: &[FieldSummary],
    secs: f64,
) -> Result<()> {
    let mut csv = String::from(
        "variant,trial,start_x,start_y,goal,result,plan_len,replans,length,final_distance,detections,aliased\n",
    );
    for t in trials {
        let _ = writeln!(
            csv,
            "{},{},{:.3},{:.3},{},{},{},{},{:.3},{:.3},{},{}",
            t.variant.name(),
            t.task.trial,
            t.task.start[0],
            t.task.start[1],
            t.task.goal,
            t.result.name(),
            t.plan_len,
            t.replans,
            t.length,
            t.final_distance,
            t.detections,
            t.aliased
        );
    }
    write_atomic(&out.join("trials.csv"), csv.as_bytes())?;
    let mut t42 = String::from("variant,plan_len,paths,mean_length\n");
    for x in summaries {
        for (k, n, l) in &x.by_plan_len {
            let _ = writeln!(t42, "{},{k},{n},{l:.3}", x.variant.name());
        }
    }
    write_atomic(&out.join("table_4_2.csv"), t42.as_bytes())?;
    let summary = json!({
        "params": params,
        "mapping": field.stats,
        "draws": draws,
        "variants": summaries,
        "thesis": {"trials": 18, "successes": 13, "success_rate": 13.0 / 18.0},
        "seconds": secs,
    });
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let drive: Vec<(f64, f64)> = field.drive.iter().map(|p| (p[0], p[1])).collect();
    for v in [FieldVariant::Thesis, FieldVariant::Both] {
        let runs: Vec<(Vec<(f64, f64)>, bool)> = trials
            .iter()
            .filter(|t| t.variant == v && t.result != FieldResult::NoPath)
            .take(40)
            .map(|t| {
                (
                    t.trajectory.iter().map(|p| (p[0], p[1])).collect(),
                    t.result == FieldResult::Success,
                )
            })
            .collect();
        crate::plot::runs_map(
            &out.join(format!("fig_4_9_{}", v.name().replace('+', "_"))),
            &format!(
                "Field trials ({}): solid reached, dashed failed (first {})",
                v.name(),
                runs.len()
            ),
            field.scenario.world.spec(),
            &drive,
            &runs,
        )?;
    }
    write_atomic(
        &out.join("report.md"),
        report(params, field, draws, summaries, secs).as_bytes(),
    )?;
    Ok(())
}

fn report(
    params: &FieldParams,
    field: &FieldMap,
    draws: &TaskDraws,
    summaries: &[FieldSummary],
    secs: f64,
) -> String {
    let s = &field.stats;
    let mut r = String::new();
    let _ = writeln!(
        r,
        "# Q-Link field-site experiment (thesis §4.4.2), simulated\n\n\
         Command: `qrm qlink field --seed {} --trials {}`{}; {secs:.1} s.\n",
        params.seed,
        params.trials,
        if params.samples < 300 {
            " (quick settings)"
        } else {
            ""
        }
    );
    let _ = writeln!(
        r,
        "## The map\n\n\
         | | thesis | ours |\n|---|---|---|\n\
         | point landmarks in the map | 25 | {} ids: {} real landmarks (of {} in the world), {} false (ground returns) |\n\
         | extended landmarks | 2 walls | 2 walls (one frame, {} scans saw both) |\n\
         | map elements | 44 | {} point triplets + {} wall elements |\n\
         | noise model | N(0, 0.7) | N(0, 0.7) |\n\
         | recognition | triangles of side lengths | triangles, tolerance {} m, two matching triangles; {} of {} mapping detections on another object than the one their id was most often recognised from |\n\
         | effective range for points | (60 m lidar, conservative extraction) | {:.1} m (median recognition distance; 30 m scanner) |\n",
        s.mapped_ids,
        s.real_landmarks,
        s.world_landmarks,
        s.false_landmarks,
        s.wall_frames,
        s.point_elements,
        s.wall_elements,
        params.tolerance,
        s.aliased_detections,
        s.detections,
        s.effective_range
    );
    let _ = writeln!(
        r,
        "## Success rate and causes of failure\n\n\
         A success reaches an element holding the goal landmark, finds the goal itself in that \
         element's frame (POMDP search; an element where it is not found is given up and \
         another planned to) and the object found truly is the goal (checked against the \
         simulator). Starts are drawn within 8 m of the mapping \
         drive, goals among the map's real landmarks; a draw is redrawn when the goal (or an \
         element holding it) is in view at the start ({} draws), when the robot localises in \
         no element there ({}), or when the link graph has no path ({}; {} kept).\n\n\
         | variant | trials | no path | successes | success rate | perceptual aliasing | insufficient features | insufficient features + aliasing | re-planned successes | mean length (m) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n\
         | thesis (in vivo) | 18 | – | 13 | 72.2 % | 0 | 4 | 1 | 5 | – |",
        draws.trivial, draws.no_start, draws.no_path, draws.kept
    );
    for x in summaries {
        let _ = writeln!(
            r,
            "| {} | {} | {} | {} | {:.1} % | {} | {} | {} | {} | {:.1} |",
            x.variant.name(),
            x.trials,
            x.no_path,
            x.successes,
            100.0 * x.success_rate,
            x.perceptual_aliasing,
            x.insufficient_features,
            x.insufficient_features_and_aliasing,
            x.replanned_successes,
            x.mean_length
        );
    }
    let _ = writeln!(
        r,
        "\n## Table 4.2: trajectory length vs |P|\n\n\
         |P| counts transitions of the first plan here (the thesis's |P| counts elements; its \
         |P| = 1 paths of 2.5 m are runs that started next to the goal element).\n"
    );
    let _ = writeln!(
        r,
        "| |P| | thesis paths | thesis mean (m) | ours ({}) paths | ours mean (m) |\n|---|---|---|---|---|",
        FieldVariant::Thesis.name()
    );
    let ours = summaries
        .iter()
        .find(|x| x.variant == FieldVariant::Thesis)
        .map(|x| x.by_plan_len.clone())
        .unwrap_or_default();
    let mut keys: Vec<usize> = THESIS_TABLE_4_2
        .iter()
        .map(|t| t.0)
        .chain(ours.iter().map(|t| t.0))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    for k in keys {
        let th = THESIS_TABLE_4_2.iter().find(|t| t.0 == k);
        let us = ours.iter().find(|t| t.0 == k);
        let _ = writeln!(
            r,
            "| {k} | {} | {} | {} | {} |",
            th.map_or("–".into(), |t| t.1.to_string()),
            th.map_or("–".into(), |t| format!("{:.1}", t.2)),
            us.map_or("0".into(), |t| t.1.to_string()),
            us.map_or("–".into(), |t| format!("{:.1}", t.2)),
        );
    }
    let monotone = ours.windows(2).all(|w| w[1].2 >= w[0].2);
    let _ = writeln!(
        r,
        "\nThe thesis: mean trajectory length grows monotonically with |P|. Ours: {}.\n",
        if monotone {
            "agrees"
        } else {
            "not strictly monotone (few paths per |P|; see table_4_2.csv)"
        }
    );
    r.push_str(
        "## Where we differ and why\n\n\
         - The thesis ran 18 trials with a real robot; we run many simulated ones with random \
           starts near the mapping drive and random goals (real landmarks of the map, out of \
           view at the start), so rates are comparable in kind, not trial for trial.\n\
         - Insufficient features here come from the extractor's 10–50-return rule (a thin \
           trunk is a landmark only within ≈ 9–14 m), occlusion by the pines and the walls, \
           and identification that needs four candidates at once (two matching triangles); \
           the thesis's main cause, the \
           ground plane seen on pitched terrain, has no counterpart in a flat 2-D world \
           (clutter discs stand in for ground returns).\n\
         - Perceptual aliasing happens when the recogniser matches the wrong object by \
           triangle side lengths; the robot then measures relative to the wrong object.\n\
         - Our map keeps every triplet seen together in at least three scans: thousands of \
           elements against the thesis's 44, so with β = 2 most goals are one transition \
           away and |P| is short; the thesis's longer plans came from a sparser map.\n\
         - The improvements are measured, not assumed: compare the variants' rows above. \
           Safe search keeps the references within the effective range; visibility-aware \
           costs prefer links the mapping drive recognised often, which can mean longer \
           plans through more transitions.\n\
         - The walls are recognised as *which* wall by appearance (given), and their frame \
           comes from their true end points; only their detection is from the lidar.\n",
    );
    r
}
