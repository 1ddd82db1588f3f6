//! The claims of thesis §4.4.1 judged on a run: Propositions 1–2, Table 4.1 by trend and by
//! magnitude, Figs 4.6–4.7. Every verdict is computed from the records; where ours differs
//! from the thesis, the reason given is a measurement of the same run — the robot's errors
//! removed one at a time ([`Ablation`]) or the occlusion rows under other sensing schedules —
//! never a typed guess.

use qlink::Failure;

use super::{Ablation, SettingInfo, StudyConfig, TableRow, Trial, TrialRecord, matched_length};
use crate::report::{Claim, Verdict};
use crate::verdict::{Trend, two_proportion_z, wilson_interval};

use super::report::{THESIS_PAIRS, thesis_failure_rate};

/// The longest Link Graph path of the thesis's Fig 4.6–4.7, in its count (map elements).
pub const THESIS_LONGEST_PLAN: usize = 18;

/// Fig 4.6: "the majority of the paths have |P| ≤ 10" (the thesis's count).
pub const THESIS_MAJORITY_PLAN: usize = 10;

/// The largest |skewness| of a distribution called "approximately Gaussian" (the usual rule
/// of thumb for a symmetric distribution; Fig 4.6's claim).
pub const GAUSSIAN_SKEW: f64 = 0.5;

fn percent_series(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{:.1} %", 100.0 * x))
        .collect::<Vec<_>>()
        .join(" → ")
}

/// The rows of the main table: the configured schedule, the full robot.
fn main_rows<'a>(rows: &'a [TableRow], config: &StudyConfig) -> Vec<&'a TableRow> {
    rows.iter()
        .filter(|r| r.schedule == config.schedule && r.robot == Ablation::Full)
        .collect()
}

/// Every claim of a run.
#[must_use]
pub fn claims(
    records: &[TrialRecord],
    rows: &[TableRow],
    settings: &[SettingInfo],
    config: &StudyConfig,
) -> Vec<Claim> {
    let main = main_rows(rows, config);
    let mut out = Vec::new();
    if let Some(b) = main
        .iter()
        .find(|r| r.trial == Trial::SensorRange && (r.value - 1.0).abs() < 1e-9)
    {
        out.push(Claim {
            what: "Proposition 1 (R' = R, no occlusion): every pair with a path succeeds".into(),
            thesis: "0 failures".into(),
            ours: format!(
                "{} failures of {} pairs with a path",
                b.failures,
                b.pairs - b.no_path
            ),
            verdict: Verdict::holds_if(b.failures == 0).over(b.pairs - b.no_path),
            why: if b.failures == 0 {
                String::new()
            } else {
                robot_cause(records, rows, b, Some(0.0)).unwrap_or_else(|| {
                    "Proposition 1 assumes a robot that perceives and drives exactly; this one \
                     errs (see the set-up)"
                        .into()
                })
            },
        });
    }
    out.extend(bound_claims(rows));
    for (trial, descending, what) in [
        (Trial::SensorRange, true, "Failure rate as R' shrinks"),
        (Trial::Occlusion, false, "Failure rate as landmarks grow"),
    ] {
        let mut sel: Vec<&&TableRow> = main.iter().filter(|r| r.trial == trial).collect();
        if sel.len() < 2 {
            continue;
        }
        sel.sort_by(|a, b| a.value.total_cmp(&b.value));
        if descending {
            sel.reverse();
        }
        let rates: Vec<f64> = sel.iter().map(|r| r.failure_rate).collect();
        let thesis: Vec<f64> = sel
            .iter()
            .filter_map(|r| thesis_failure_rate(r.trial, r.value))
            .collect();
        let (ours, theirs) = (Trend::of(&rates, 1e-9), Trend::of(&thesis, 1e-9));
        out.push(Claim {
            what: what.into(),
            thesis: format!("{} ({})", theirs.phrase(), percent_series(&thesis)),
            ours: format!("{} ({})", ours.phrase(), percent_series(&rates)),
            verdict: Verdict::agree_if(ours == theirs),
            why: String::new(),
        });
        if trial == Trial::SensorRange {
            out.extend(largest_rise_claim(&sel));
        }
    }
    out.extend(magnitude_claims(records, rows, &main));
    out.extend(length_claims(records, &main, config));
    out.extend(plan_length_claims(records, settings, config));
    out.extend(length_rises_with_plan_claim(records, &main));
    out
}

/// "A large increase in the path failure rate occurs when R' = 0.8R": the largest step
/// between successive sensor-range rows is the one into 0.8 R (`sel` from R' = R down).
fn largest_rise_claim(sel: &[&&TableRow]) -> Option<Claim> {
    let thesis: Vec<(f64, f64)> = sel
        .iter()
        .filter_map(|r| thesis_failure_rate(r.trial, r.value).map(|t| (r.value, t)))
        .collect();
    let step_into = |v: &[(f64, f64)]| {
        v.windows(2)
            .max_by(|a, b| (a[1].1 - a[0].1).total_cmp(&(b[1].1 - b[0].1)))
            .map(|w| (w[1].0, w[1].1 - w[0].1))
    };
    let ours: Vec<(f64, f64)> = sel.iter().map(|r| (r.value, r.failure_rate)).collect();
    let (t_at, t_step) = step_into(&thesis)?;
    let (o_at, o_step) = step_into(&ours)?;
    Some(Claim {
        what: "The largest rise in failure rate as R' shrinks".into(),
        thesis: format!("at R' = {t_at} R (+{:.1} points)", 100.0 * t_step),
        ours: format!("at R' = {o_at} R (+{:.1} points)", 100.0 * o_step),
        verdict: Verdict::agree_if((o_at - t_at).abs() < 1e-9),
        why: String::new(),
    })
}

/// Proposition 2 on every schedule run (the full robot): the bound (2π+1)R|P| against each
/// successful run's trajectory — what the thesis's Fig 4.7 sets beside it — with the length
/// driven in transitions (what the proof sums) beside it.
fn bound_claims(rows: &[TableRow]) -> Vec<Claim> {
    let mut schedules: Vec<super::Schedule> = Vec::new();
    for r in rows.iter().filter(|r| r.robot == Ablation::Full) {
        if !schedules.contains(&r.schedule) {
            schedules.push(r.schedule);
        }
    }
    schedules
        .into_iter()
        .map(|s| {
            let sel: Vec<&TableRow> = rows
                .iter()
                .filter(|r| r.schedule == s && r.robot == Ablation::Full)
                .collect();
            let successes: usize = sel.iter().map(|r| r.pairs - r.no_path - r.failures).sum();
            let trajectory: usize = sel.iter().map(|r| r.over_bound_trajectory).sum();
            let transit: usize = sel.iter().map(|r| r.over_bound).sum();
            Claim {
                what: format!(
                    "Proposition 2: no trajectory exceeds (2π+1)R|P| ({s}, every setting)"
                ),
                thesis: "never exceeded (very conservative)".into(),
                ours: format!(
                    "{trajectory} of {successes} successful trajectories exceed it ({transit} by \
                     the length driven in transitions alone)"
                ),
                verdict: Verdict::holds_if(trajectory == 0).over(successes),
                why: if trajectory == 0 {
                    String::new()
                } else {
                    "the bound is proved only under Assumptions 1–2, which R' < R, occlusion and \
                     a robot that errs break; the trajectory also holds the localisation before \
                     the first transition and the search for the goal after the last"
                        .into()
                },
            }
        })
        .collect()
}

/// Each row of the main table against the thesis's rate by magnitude: our failures among the
/// pairs with a path against the thesis's rate over its [`THESIS_PAIRS`], a two-proportion
/// z-test at the 5 % level (agree when |z| < 1.96) — a trend can agree while every rate is
/// off by a factor. A row that disagrees says why, measured: [`robot_cause`] for the
/// sensor-range rows, [`schedule_cause`] for the occlusion rows.
fn magnitude_claims(records: &[TrialRecord], rows: &[TableRow], main: &[&TableRow]) -> Vec<Claim> {
    main.iter()
        .filter_map(|r| {
            let thesis = thesis_failure_rate(r.trial, r.value)?;
            let n = r.pairs - r.no_path;
            let k0 = (thesis * THESIS_PAIRS as f64).round() as usize;
            let z = two_proportion_z(r.failures, n, k0, THESIS_PAIRS);
            let [lo, hi] = wilson_interval(r.failures, n, 1.96);
            let agree = n > 0 && z.abs() < 1.96;
            let why = if agree {
                String::new()
            } else {
                let robot = robot_cause(records, rows, r, Some(thesis));
                let schedule = schedule_cause(rows, r, thesis);
                [robot, schedule]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            Some(Claim {
                what: format!("Failure rate at {} {} by magnitude", r.trial, r.value),
                thesis: format!("{:.1} % of {THESIS_PAIRS} pairs", 100.0 * thesis),
                ours: format!(
                    "{:.1} % of {n} pairs with a path (95 % interval {:.1}–{:.1} %), z = {z:.2}",
                    100.0 * r.failure_rate,
                    100.0 * lo,
                    100.0 * hi
                ),
                verdict: Verdict::agree_if(agree),
                why,
            })
        })
        .collect()
}

/// Failures and pairs with a path among `records`.
fn failures(records: &[&TrialRecord]) -> (usize, usize) {
    let with_path: Vec<&&TrialRecord> = records
        .iter()
        .filter(|r| r.failure != Some(Failure::NoPath))
        .collect();
    (
        with_path.iter().filter(|r| !r.success).count(),
        with_path.len(),
    )
}

/// What the robot's errors do to `row`, measured by the ablation rows at its setting: the
/// full robot's rate on the ablations' pairs (the same pairs, world and seed), the exact
/// robot's, and the error whose removal lowers the rate most; with the thesis's rate
/// `thesis`, whether the exact robot itself differs from it (then the robot's errors are not
/// the whole difference). `None` without ablation rows.
#[must_use]
pub fn robot_cause(
    records: &[TrialRecord],
    rows: &[TableRow],
    row: &TableRow,
    thesis: Option<f64>,
) -> Option<String> {
    let at = |r: &TrialRecord| {
        r.trial == row.trial
            && r.value.to_bits() == row.value.to_bits()
            && r.schedule == row.schedule
    };
    let ablated: Vec<&TableRow> = rows
        .iter()
        .filter(|a| {
            a.robot != Ablation::Full
                && a.trial == row.trial
                && a.value.to_bits() == row.value.to_bits()
                && a.schedule == row.schedule
        })
        .collect();
    let first = ablated.first()?;
    let pairs: std::collections::HashSet<(u32, u32)> = records
        .iter()
        .filter(|r| at(r) && r.robot == first.robot)
        .map(|r| (r.start, r.goal))
        .collect();
    let full: Vec<&TrialRecord> = records
        .iter()
        .filter(|r| at(r) && r.robot == Ablation::Full && pairs.contains(&(r.start, r.goal)))
        .collect();
    let (k_full, n_full) = failures(&full);
    if n_full == 0 {
        return None;
    }
    let rate = |k: usize, n: usize| 100.0 * k as f64 / n.max(1) as f64;
    let mut parts = vec![format!(
        "Measured on the same {} pairs: {} fails {:.1} %",
        pairs.len(),
        Ablation::Full.phrase(),
        rate(k_full, n_full)
    )];
    let mut best: Option<(&TableRow, f64)> = None;
    for a in &ablated {
        let n = a.pairs - a.no_path;
        parts.push(format!("{} {:.1} %", a.robot.phrase(), rate(a.failures, n)));
        if a.robot.is_single() {
            let z = two_proportion_z(k_full, n_full, a.failures, n);
            if best.is_none_or(|b| z > b.1) {
                best = Some((a, z));
            }
        }
    }
    let mut s = parts.join(", ");
    s.push('.');
    match best {
        Some((a, z)) if z > 1.96 => {
            let _ = std::fmt::Write::write_fmt(
                &mut s,
                format_args!(
                    " Of the single errors, removing {} lowers it most ({:.1} → {:.1} %, z = {z:.1}).",
                    a.robot.removes().unwrap_or("nothing"),
                    rate(k_full, n_full),
                    rate(a.failures, a.pairs - a.no_path)
                ),
            );
        }
        Some(_) => s.push_str(" No single error's removal lowers it beyond noise (z ≤ 1.96)."),
        None => {}
    }
    if let (Some(t), Some(e)) = (thesis, ablated.iter().find(|a| a.robot == Ablation::Exact)) {
        let n = e.pairs - e.no_path;
        let k0 = (t * THESIS_PAIRS as f64).round() as usize;
        let z = two_proportion_z(e.failures, n, k0, THESIS_PAIRS);
        if z.abs() >= 1.96 {
            let _ = std::fmt::Write::write_fmt(
                &mut s,
                format_args!(
                    " The exact robot's {:.1} % is itself {} the thesis's {:.1} % (z = {z:.1}): \
                     the robot's errors are not the whole difference.",
                    rate(e.failures, n),
                    if z > 0.0 { "above" } else { "below" },
                    100.0 * t
                ),
            );
        }
    }
    Some(s)
}

/// What the unstated sensing schedule does to an occlusion row: the same size under every
/// schedule run (the full robot), and whether the thesis's rate lies among them. `None` for
/// a sensor-range row or a single schedule.
#[must_use]
pub fn schedule_cause(rows: &[TableRow], row: &TableRow, thesis: f64) -> Option<String> {
    if row.trial != Trial::Occlusion {
        return None;
    }
    let sel: Vec<&TableRow> = rows
        .iter()
        .filter(|r| {
            r.trial == Trial::Occlusion
                && r.value.to_bits() == row.value.to_bits()
                && r.robot == Ablation::Full
        })
        .collect();
    if sel.len() < 2 {
        return None;
    }
    let lo = sel
        .iter()
        .min_by(|a, b| a.failure_rate.total_cmp(&b.failure_rate))?;
    let hi = sel
        .iter()
        .max_by(|a, b| a.failure_rate.total_cmp(&b.failure_rate))?;
    let inside = (lo.failure_rate..=hi.failure_rate).contains(&thesis);
    Some(format!(
        "Where the robot looks decides this row: at {} m our schedules fail from {:.1} % ({}) to \
         {:.1} % ({}), and the thesis's {:.1} % lies {} them; the thesis does not give its \
         schedule.",
        row.value,
        100.0 * lo.failure_rate,
        lo.schedule,
        100.0 * hi.failure_rate,
        hi.schedule,
        100.0 * thesis,
        if inside { "between" } else { "outside" }
    ))
}

/// The trajectory-length claims, compared at matched |P| so the mix of plan lengths does not
/// decide.
fn length_claims(records: &[TrialRecord], main: &[&TableRow], config: &StudyConfig) -> Vec<Claim> {
    let mut out = Vec::new();
    let base_sel = |r: &TrialRecord| {
        r.trial == Trial::SensorRange
            && r.value == 1.0
            && r.schedule == config.schedule
            && r.robot == Ablation::Full
    };
    let matched = |trial: Trial| -> Vec<(f64, f64)> {
        main.iter()
            .filter(|r| r.trial == trial)
            .filter_map(|r| {
                let sel = |x: &TrialRecord| {
                    x.trial == r.trial
                        && x.value == r.value
                        && x.schedule == r.schedule
                        && x.robot == r.robot
                };
                matched_length(records, &sel, &base_sel).map(|l| (r.value, l))
            })
            .collect()
    };
    let mut range_lengths = matched(Trial::SensorRange);
    if range_lengths.len() >= 2 {
        range_lengths.sort_by(|a, b| b.0.total_cmp(&a.0));
        let l: Vec<f64> = range_lengths.iter().map(|x| x.1).collect();
        let ours = Trend::of(&l, 0.5);
        out.push(Claim {
            what: "Trajectory length as R' shrinks (mean over |P| weighted as at R' = R)".into(),
            thesis: Trend::Rises.phrase().into(),
            ours: format!(
                "{} ({} m)",
                ours.phrase(),
                l.iter()
                    .map(|v| format!("{v:.1}"))
                    .collect::<Vec<_>>()
                    .join(" → ")
            ),
            verdict: Verdict::agree_if(ours == Trend::Rises),
            why: String::new(),
        });
    }
    let occ = matched(Trial::Occlusion);
    if let (Some(base), false) = (
        matched_length(records, &base_sel, &base_sel),
        occ.is_empty(),
    ) {
        let longer = occ.iter().filter(|o| o.1 > base).count();
        out.push(Claim {
            what: format!(
                "Occluded trajectories against unoccluded ones (same weighting; R' = R: {base:.1} m)"
            ),
            thesis: "longer at every size".into(),
            ours: format!(
                "longer at {longer} of {} sizes ({})",
                occ.len(),
                occ.iter()
                    .map(|o| format!("{} m: {:.1} m", o.0, o.1))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            verdict: Verdict::agree_if(longer == occ.len()),
            why: String::new(),
        });
    }
    out
}

/// The plans Fig 4.6 counts, in the thesis's count (map elements: our transitions + 1): the
/// pairs with a path at R' = R without occlusion on the main schedule, the full robot.
#[must_use]
pub fn fig_4_6_plans(records: &[TrialRecord], config: &StudyConfig) -> Vec<usize> {
    records
        .iter()
        .filter(|r| {
            r.trial == Trial::SensorRange
                && (r.value - 1.0).abs() < 1e-9
                && r.schedule == config.schedule
                && r.robot == Ablation::Full
                && r.failure != Some(Failure::NoPath)
        })
        .map(|r| r.plan_len + 1)
        .collect()
}

/// The sample skewness of `v` (0 for fewer than three values or no spread).
#[must_use]
pub fn skewness(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    if v.len() < 3 {
        return 0.0;
    }
    let mean = v.iter().sum::<f64>() / n;
    let m2 = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    let m3 = v.iter().map(|x| (x - mean).powi(3)).sum::<f64>() / n;
    if m2 <= 0.0 { 0.0 } else { m3 / m2.powf(1.5) }
}

/// Fig 4.6: the plans reach |P| = 18, most have |P| ≤ 10, and they are distributed about
/// as a Gaussian. Where the longest plan falls short, the why is the link graph's measured
/// density (links per element).
fn plan_length_claims(
    records: &[TrialRecord],
    settings: &[SettingInfo],
    config: &StudyConfig,
) -> Vec<Claim> {
    let plans = fig_4_6_plans(records, config);
    if plans.is_empty() {
        return Vec::new();
    }
    let longest = plans.iter().copied().max().unwrap_or(0);
    let majority = plans.iter().filter(|&&p| p <= THESIS_MAJORITY_PLAN).count();
    let as_f: Vec<f64> = plans.iter().map(|&p| p as f64).collect();
    let skew = skewness(&as_f);
    let mean = as_f.iter().sum::<f64>() / as_f.len() as f64;
    let graph = settings.iter().find(|i| {
        i.trial == Trial::SensorRange && i.robot == Ablation::Full && i.schedule == config.schedule
    });
    let density = graph.map(|g| {
        format!(
            "our link graph joins elements that share a landmark (β = 1): {} directed links \
             over {} elements, {:.0} per element, so a plan needs few transitions",
            g.edges,
            g.elements,
            g.edges as f64 / g.elements.max(1) as f64
        )
    });
    vec![
        Claim {
            what: format!(
                "Fig 4.6: the longest plans reach |P| = {THESIS_LONGEST_PLAN} (the thesis's count: elements, ours + 1)"
            ),
            thesis: format!("|P| = {THESIS_LONGEST_PLAN}"),
            ours: format!(
                "longest |P| = {longest} of {} pairs with a path (mean {mean:.1})",
                plans.len()
            ),
            verdict: Verdict::agree_if(longest >= THESIS_LONGEST_PLAN),
            why: if longest >= THESIS_LONGEST_PLAN {
                String::new()
            } else {
                density.unwrap_or_default()
            },
        },
        Claim {
            what: format!("Fig 4.6: the majority of plans have |P| ≤ {THESIS_MAJORITY_PLAN}"),
            thesis: "the majority".into(),
            ours: format!(
                "{:.1} % of {} pairs with a path",
                100.0 * majority as f64 / plans.len() as f64,
                plans.len()
            ),
            verdict: Verdict::agree_if(2 * majority > plans.len()),
            why: String::new(),
        },
        Claim {
            what: format!(
                "Fig 4.6: plan lengths are distributed approximately Gaussian (|skewness| < {GAUSSIAN_SKEW})"
            ),
            thesis: "approximately Gaussian".into(),
            ours: format!("skewness {skew:.2}"),
            verdict: Verdict::agree_if(skew.abs() < GAUSSIAN_SKEW),
            why: String::new(),
        },
    ]
}

/// Fig 4.7: "trajectory length increases with increasing Link Graph path length … for all
/// sets of parameters": the mean trajectory per |P| rises in every main setting (|P| with at
/// least ten successes, steps within a metre level).
fn length_rises_with_plan_claim(records: &[TrialRecord], main: &[&TableRow]) -> Option<Claim> {
    let mut rising = Vec::new();
    let mut not = Vec::new();
    for r in main {
        let ok: Vec<&TrialRecord> = records
            .iter()
            .filter(|x| {
                x.trial == r.trial
                    && x.value.to_bits() == r.value.to_bits()
                    && x.schedule == r.schedule
                    && x.robot == r.robot
                    && x.success
            })
            .collect();
        let top = ok.iter().map(|x| x.plan_len).max().unwrap_or(0);
        let means: Vec<f64> = (0..=top)
            .filter_map(|p| {
                let l: Vec<f64> = ok
                    .iter()
                    .filter(|x| x.plan_len == p)
                    .map(|x| x.length)
                    .collect();
                (l.len() >= 10).then(|| l.iter().sum::<f64>() / l.len() as f64)
            })
            .collect();
        if means.len() < 2 {
            continue;
        }
        let name = format!("{} {}", r.trial, r.value);
        if Trend::of(&means, 1.0) == Trend::Rises {
            rising.push(name);
        } else {
            not.push(name);
        }
    }
    let n = rising.len() + not.len();
    (n > 0).then(|| Claim {
        what: "Fig 4.7: trajectory length rises with |P| in every setting".into(),
        thesis: "for all sets of parameters".into(),
        ours: if not.is_empty() {
            format!("in all {n} settings")
        } else {
            format!(
                "in {} of {n} settings (not: {})",
                rising.len(),
                not.join(", ")
            )
        },
        verdict: Verdict::agree_if(not.is_empty()),
        why: String::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qlink::table_4_1::{MAP_RANGE, Schedule, table};

    fn rec(value: f64, robot: Ablation, pair: u32, success: bool) -> TrialRecord {
        TrialRecord {
            trial: Trial::SensorRange,
            value,
            schedule: Schedule::CONTINUOUS,
            robot,
            start: pair,
            goal: pair + 1000,
            plan_len: 3,
            success,
            failure: (!success).then_some(Failure::InsufficientFeatures),
            length: 100.0,
            transit_length: 80.0,
            bound: (2.0 * std::f64::consts::PI + 1.0) * MAP_RANGE * 3.0,
            bound_direct: 60.0,
        }
    }

    #[test]
    fn the_robot_cause_compares_on_the_ablations_pairs_and_names_the_largest() {
        // full robot: 400 pairs, failing the first 80 (20 %); the ablations ran pairs 0..200,
        // where the full robot fails 80 of 200 (40 %). Without detection noise: 10 of 200;
        // without misses 70 of 200; exact 4 of 200.
        let mut v: Vec<TrialRecord> = (0..400)
            .map(|p| rec(0.9, Ablation::Full, p, p >= 80))
            .collect();
        for (a, k) in [
            (Ablation::Exact, 4),
            (Ablation::WithoutMisses, 70),
            (Ablation::WithoutDetectionNoise, 10),
        ] {
            v.extend((0..200).map(|p| rec(0.9, a, p, p >= k)));
        }
        let rows = table(&v);
        let full = rows.iter().find(|r| r.robot == Ablation::Full).unwrap();
        let why = robot_cause(&v, &rows, full, Some(0.02)).unwrap();
        assert!(why.contains("same 200 pairs"), "{why}");
        assert!(why.contains("as configured fails 40.0 %"), "{why}");
        assert!(why.contains("the exact robot 2.0 %"), "{why}");
        assert!(
            why.contains("removing the detections' position noise lowers it most (40.0 → 5.0 %"),
            "{why}"
        );
        // no ablation rows: nothing measured, nothing said
        let only_full: Vec<TrialRecord> = v
            .iter()
            .filter(|r| r.robot == Ablation::Full)
            .cloned()
            .collect();
        let rows = table(&only_full);
        assert!(robot_cause(&only_full, &rows, &rows[0], None).is_none());
        // the exact robot's 2.0 % of 200 is not beyond the thesis's 2.0 %: nothing said; 40 %
        // would be
        assert!(!why.contains("is itself"), "{why}");
        let rows = table(&v);
        let full = rows.iter().find(|r| r.robot == Ablation::Full).unwrap();
        let why = robot_cause(&v, &rows, full, Some(0.4)).unwrap();
        assert!(
            why.contains("The exact robot's 2.0 % is itself below the thesis's 40.0 %"),
            "{why}"
        );
    }

    #[test]
    fn the_schedule_cause_says_whether_the_thesis_lies_among_the_schedules() {
        let row = |schedule: Schedule, failures: usize| TableRow {
            trial: Trial::Occlusion,
            value: 0.7,
            schedule,
            robot: Ablation::Full,
            pairs: 100,
            no_path: 0,
            failures,
            failure_rate: failures as f64 / 100.0,
            over_bound: 0,
            over_bound_trajectory: 0,
            mean_length: 0.0,
        };
        let stops = Schedule {
            sensing: qlink::Sensing::AtStops { degrees: 30.0 },
            fallbacks: 0,
        };
        let rows = vec![row(Schedule::CONTINUOUS, 3), row(stops, 50)];
        let s = schedule_cause(&rows, &rows[0], 0.163).unwrap();
        assert!(
            s.contains(
                "from 3.0 % (continuous, 1 fallback) to 50.0 % (stops every 30°, 0 fallbacks)"
            ),
            "{s}"
        );
        assert!(s.contains("lies between"), "{s}");
        let s = schedule_cause(&rows, &rows[0], 0.6).unwrap();
        assert!(s.contains("lies outside"), "{s}");
        assert!(schedule_cause(&rows[..1], &rows[0], 0.163).is_none());
    }

    #[test]
    fn skewness_of_symmetric_and_skewed_samples() {
        assert!(skewness(&[1.0, 2.0, 3.0, 4.0, 5.0]).abs() < 1e-12);
        assert!(skewness(&[1.0, 1.0, 1.0, 1.0, 10.0]) > 1.0);
        assert_eq!(skewness(&[2.0, 2.0, 2.0]), 0.0);
    }
}
