//! The claims of the field experiment (thesis §4.4.2) judged on a run: the in-vivo study's
//! success rate, failure causes and re-planning share, Table 4.2 by trend and by magnitude,
//! the map's size, Propositions 2 and 4, and the proposed improvements. The thesis's numbers
//! are the constants here, nowhere else.

use super::output::{FieldOutput, FieldWorld};
use super::summary::{BoundRange, FieldSummary};
use super::trials::{FieldResult, FieldTrial};
use std::collections::BTreeMap;

use qlink::Stranded;

use super::{FieldParams, FieldVariant};
use crate::report::{Claim, Verdict};
use crate::verdict::{Trend, two_proportion_z, wilson_interval};

/// What the thesis's in-vivo study counted (§4.4.2: 18 trials).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InVivo {
    /// Trials run.
    pub trials: usize,
    /// Paths completed.
    pub successes: usize,
    /// Failures from perceptual aliasing alone.
    pub perceptual_aliasing: usize,
    /// Failures from insufficient features alone.
    pub insufficient_features: usize,
    /// Failures from both.
    pub insufficient_features_and_aliasing: usize,
    /// Successes that re-planned at the link level.
    pub replanned_successes: usize,
}

/// The thesis's in-vivo study: 13 of 18 completed, all five failures for insufficient
/// features (one with aliasing), five successes re-planned.
pub const THESIS_IN_VIVO: InVivo = InVivo {
    trials: 18,
    successes: 13,
    perceptual_aliasing: 0,
    insufficient_features: 4,
    insufficient_features_and_aliasing: 1,
    replanned_successes: 5,
};

/// Thesis Table 4.2: (|P|, paths, mean trajectory length m). Its |P| counts map elements:
/// ours, which counts transitions, + 1 ([`thesis_plan_len`]).
pub const THESIS_TABLE_4_2: [(usize, usize, f64); 6] = [
    (1, 2, 2.5),
    (2, 3, 6.5),
    (3, 2, 12.7),
    (4, 3, 14.3),
    (6, 2, 32.9),
    (8, 1, 38.4),
];

/// The thesis's field map: "44 distinct QRM map elements".
pub const THESIS_ELEMENTS: usize = 44;

/// The thesis's field map's point landmarks ("25 point landmarks and 2 walls").
pub const THESIS_POINT_LANDMARKS: usize = 25;

/// Table 4.2's |P| above which "the path length dramatically increases".
pub const THESIS_RISE_ABOVE: usize = 5;

/// A plan of ours in the thesis's count: it counts the map elements of a path (its |P| = 1 is
/// "goal visible from the start"), we count the transitions between them.
#[must_use]
pub fn thesis_plan_len(transitions: usize) -> usize {
    transitions + 1
}

/// The success claim's why: the rule, and where the pooled rate differs, the worlds' own
/// rates (`per_world`, thesis set-up) — the thesis measured one site, and ours differ from
/// world to world.
fn success_why(agree: bool, per_world: &[f64]) -> String {
    let rule = "agree when ours lies in the Wilson 95 % interval of the thesis's 18 trials";
    let (Some(lo), Some(hi)) = (
        per_world.iter().copied().reduce(f64::min),
        per_world.iter().copied().reduce(f64::max),
    ) else {
        return rule.into();
    };
    if agree {
        return rule.into();
    }
    let th = THESIS_IN_VIVO;
    let theirs = th.successes as f64 / th.trials as f64;
    let inside = (lo..=hi).contains(&theirs);
    format!(
        "{rule}; our {} world(s) succeed {:.1}–{:.1} % of their runs, so the thesis's one site \
         at {:.0} % is {} the range of our sites",
        per_world.len(),
        100.0 * lo,
        100.0 * hi,
        100.0 * theirs,
        if inside { "within" } else { "outside" }
    )
}

/// Attempts (trials with a path) and successes of a pooled summary.
fn attempts(s: &FieldSummary) -> (usize, usize) {
    (s.successes, s.trials - s.no_path)
}

/// Every claim of a run.
pub(super) fn claims(config: &FieldParams, output: &FieldOutput) -> Vec<Claim> {
    let mut claims = Vec::new();
    let th = THESIS_IN_VIVO;
    let Some(ours) = output.pooled(FieldVariant::Thesis) else {
        return claims;
    };
    let (k, n) = attempts(ours);
    let [lo, hi] = wilson_interval(th.successes, th.trials, 1.96);
    claims.push(Claim {
        what: "success rate (thesis set-up, all worlds pooled)".into(),
        thesis: format!(
            "{} of {} ({:.0} %; 95 % interval {:.0}–{:.0} %)",
            th.successes,
            th.trials,
            100.0 * th.successes as f64 / th.trials as f64,
            100.0 * lo,
            100.0 * hi
        ),
        ours: format!("{k} of {n} ({:.1} %)", 100.0 * ours.success_rate),
        verdict: Verdict::agree_if((lo..=hi).contains(&ours.success_rate)).over(n),
        why: success_why(
            (lo..=hi).contains(&ours.success_rate),
            &output
                .worlds
                .iter()
                .filter_map(|w| {
                    w.variants
                        .iter()
                        .find(|s| s.variant == FieldVariant::Thesis && s.judged() > 0)
                        .map(|s| s.success_rate)
                })
                .collect::<Vec<_>>(),
        ),
    });
    let insufficient = ours.insufficient_features + ours.insufficient_features_and_aliasing;
    claims.push(Claim {
        what: "most failures are for insufficient features, not perceptual aliasing".into(),
        thesis: format!(
            "{} of {} failures for insufficient features ({} with aliasing), {} aliasing alone",
            th.insufficient_features + th.insufficient_features_and_aliasing,
            th.trials - th.successes,
            th.insufficient_features_and_aliasing,
            th.perceptual_aliasing
        ),
        ours: format!(
            "{insufficient} of {} failures for insufficient features ({} with aliasing), {} \
             aliasing alone",
            n - k,
            ours.insufficient_features_and_aliasing,
            ours.perceptual_aliasing
        ),
        verdict: Verdict::agree_if(insufficient > ours.perceptual_aliasing).over(n - k),
        why: String::new(),
    });
    let mut ground = ground_claim(
        &output
            .trials()
            .filter(|(_, t)| t.variant == FieldVariant::Thesis)
            .map(|(_, t)| (t.result, t.final_ground_share))
            .collect::<Vec<_>>(),
    );
    if ground.verdict == Verdict::Disagree {
        let runs: Vec<(FieldResult, usize, usize)> = output
            .worlds
            .iter()
            .flat_map(|w| {
                w.trials
                    .iter()
                    .filter(|t| {
                        t.variant == FieldVariant::Thesis && t.result != FieldResult::NoPath
                    })
                    .map(|t| (t.result, t.detections, w.map_size.elements))
            })
            .collect();
        if let Some(why) = features_why(&runs) {
            ground.why = format!("{}; {why}", ground.why);
        }
    }
    claims.push(ground);
    claims.push(replanning_claim(
        ours,
        &output
            .trials()
            .filter(|(_, t)| t.variant == FieldVariant::Thesis && t.result != FieldResult::NoPath)
            .map(|(_, t)| (t.result, t.replans, t.stranded))
            .collect::<Vec<_>>(),
    ));
    let successes: Vec<(usize, f64)> = output
        .trials()
        .filter(|(_, t)| t.variant == FieldVariant::Thesis && t.result == FieldResult::Success)
        .map(|(_, t)| (thesis_plan_len(t.plan_len), t.length))
        .collect();
    claims.push(table_4_2_claim(&successes));
    claims.push(table_4_2_magnitude_claim(output));
    claims.push(rise_claim(&successes));
    claims.extend(map_size_claims(config, output));
    claims.extend(bound_claims(output));
    claims.extend(improvement_claims(output, ours));
    claims
}

/// `(|P|, paths, mean trajectory m, its standard error)` of `successes` (|P|, length m) per
/// |P| with two paths or more (one path has no spread to judge a step by), by |P|.
fn rows_by_plan_len(successes: &[(usize, f64)]) -> Vec<(usize, usize, f64, f64)> {
    let mut by_len: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for &(k, l) in successes {
        by_len.entry(k).or_default().push(l);
    }
    by_len
        .iter()
        .filter_map(|(&k, v)| {
            mean_sd(v).map(|(m, sd)| (k, v.len(), m, sd / (v.len() as f64).sqrt()))
        })
        .collect()
}

/// Table 4.2's trend: the mean trajectory per |P| (thesis count) rises — read through the
/// means' noise ([`Trend::of_means`], 1.96 standard errors), over the |P| with two paths or
/// more. `successes`: (|P| in the thesis's count, trajectory length m) of the thesis set-up.
fn table_4_2_claim(successes: &[(usize, f64)]) -> Claim {
    let theirs: Vec<f64> = THESIS_TABLE_4_2.iter().map(|r| r.2).collect();
    let rows = rows_by_plan_len(successes);
    let means: Vec<(f64, f64)> = rows.iter().map(|r| (r.2, r.3)).collect();
    let (t_theirs, t_ours) = (Trend::of(&theirs, 0.0), Trend::of_means(&means, 1.96));
    let series = |rows: &mut dyn Iterator<Item = (usize, f64)>| {
        rows.map(|(k, l)| format!("{k}: {l:.1}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let ours_series = rows
        .iter()
        .map(|&(k, n, m, se)| format!("{k}: {m:.1} ± {:.1} ({n})", 1.96 * se))
        .collect::<Vec<_>>()
        .join(", ");
    // one |P| (or none) has no direction: it is not "flat", it is too little to judge
    let judged = rows.len() >= 2;
    let beyond: Vec<String> = rows
        .windows(2)
        .filter_map(|w| {
            let (a, b) = (w[0], w[1]);
            let d = b.2 - a.2;
            let noise = 1.96 * a.3.hypot(b.3);
            (d.abs() > noise).then(|| format!("{} → {}: {d:+.1} m (noise ±{noise:.1} m)", a.0, b.0))
        })
        .collect();
    Claim {
        what: "Table 4.2: mean trajectory length grows with |P|".into(),
        thesis: format!(
            "{} ({})",
            t_theirs.phrase(),
            series(&mut THESIS_TABLE_4_2.iter().map(|r| (r.0, r.2)))
        ),
        ours: if judged {
            format!(
                "{} through the means' noise (|P|: mean ± 1.96 SE m (paths): {ours_series})",
                t_ours.phrase()
            )
        } else {
            format!(
                "successes at {} |P| value(s) with two paths or more ({ours_series})",
                rows.len()
            )
        },
        verdict: Verdict::agree_if(judged && t_ours == t_theirs).over(rows.len()),
        why: if !judged {
            "fewer than two |P| values with two paths or more among the successes: no trend to \
             compare"
                .into()
        } else if t_ours == t_theirs {
            String::new()
        } else if beyond.is_empty() {
            "no step between neighbouring |P| and none from the first to the last is beyond \
             the noise of the means"
                .into()
        } else {
            format!("steps beyond the noise of the means: {}", beyond.join("; "))
        },
    }
}

/// "None of the paths exceed either distance bound provided by Propositions 2 or 4", read
/// on the lengths the thesis reports (whole trajectories, Table 4.2), with the length driven
/// in transitions (what the proofs sum) beside them.
fn bound_claims(output: &FieldOutput) -> Vec<Claim> {
    let bounds = &output.bounds;
    let mut claims = Vec::new();
    if let Some(b) = bounds
        .iter()
        .find(|b| b.variant == FieldVariant::Thesis && b.range == BoundRange::Lidar)
    {
        let successes: Vec<&FieldTrial> = output
            .trials()
            .map(|(_, t)| t)
            .filter(|t| t.variant == FieldVariant::Thesis && t.result == FieldResult::Success)
            .collect();
        for (p, exceeded, applies) in [
            (2, b.exceeded()[0], b.prop2_applies),
            (4, b.exceeded()[1], b.prop4_applies),
        ] {
            let over = successes
                .iter()
                .filter(|t| {
                    let c = &t.bounds[0];
                    t.length > if p == 2 { c.prop2 } else { c.prop4 } + 1e-9
                })
                .count();
            claims.push(Claim {
                what: format!("no path exceeds Proposition {p}'s bound (R = lidar range)"),
                thesis: "none of the in-vivo paths does".into(),
                ours: format!(
                    "{over} of {} successful trajectories exceed it ({exceeded} by the length \
                     driven in transitions alone); its assumptions hold for {applies}",
                    successes.len()
                ),
                verdict: Verdict::agree_if(over == 0).over(successes.len()),
                why: if over == 0 {
                    String::new()
                } else {
                    "the runs are outside the guarantee, whose assumptions fail here (see the \
                     bounds table); a trajectory also holds the localisation before the first \
                     transition and the search for the goal after the last"
                        .into()
                },
            });
        }
    }
    let contradictions: usize = bounds.iter().map(|b| b.contradictions).sum();
    let applied: usize = bounds
        .iter()
        .map(|b| b.prop2_applies + b.prop4_applies)
        .sum();
    claims.push(Claim {
        what: "Propositions 2 and 4: a run whose assumptions hold stays within the bound".into(),
        thesis: "proved".into(),
        ours: format!(
            "{contradictions} runs exceed a bound whose assumptions hold ({applied} run-bounds \
             applied, every variant, both R)"
        ),
        verdict: Verdict::holds_if(contradictions == 0).over(applied),
        why: String::new(),
    });
    claims
}

fn improvement_claims(output: &FieldOutput, base: &FieldSummary) -> Vec<Claim> {
    let (k0, n0) = attempts(base);
    let mut claims = Vec::new();
    for (variant, thesis) in [
        (
            FieldVariant::SafeSearch,
            "a safe-search controller \"will increase the chance of success, but at the expense \
             of trajectory length\" (proposed, not measured)",
        ),
        (
            FieldVariant::VisibilityCosts,
            "modelling where observations are less likely steers plans away from them \
             (proposed, not measured)",
        ),
    ] {
        let Some(s) = output.pooled(variant) else {
            continue;
        };
        let (k1, n1) = attempts(s);
        let z = two_proportion_z(k1, n1, k0, n0);
        let better = z > 1.96;
        let longer = s.mean_length > base.mean_length;
        let ours = format!(
            "{:.1} % against {:.1} % (z = {z:.2}); mean length {:.1} m against {:.1} m",
            100.0 * s.success_rate,
            100.0 * base.success_rate,
            s.mean_length,
            base.mean_length
        );
        let agree = match variant {
            FieldVariant::SafeSearch => better && longer,
            _ => better,
        };
        claims.push(Claim {
            what: format!("{} raises the success rate", variant.name()),
            thesis: thesis.into(),
            ours,
            verdict: Verdict::agree_if(agree).over(n0.min(n1)),
            why: if better {
                String::new()
            } else {
                "not higher by more than the two rates' noise (z ≤ 1.96)".into()
            },
        });
    }
    claims
}

/// Table 4.2 of the thesis variant, pooled over the worlds, keyed by the thesis's |P| count:
/// `(|P|, paths, mean length m)`.
pub(super) fn ours_by_plan_len(output: &FieldOutput) -> Vec<(usize, usize, f64)> {
    output
        .pooled(FieldVariant::Thesis)
        .map(|x| {
            x.by_plan_len
                .iter()
                .map(|&(k, n, l)| (thesis_plan_len(k), n, l))
                .collect()
        })
        .unwrap_or_default()
}

/// "In five of the successful trajectories, the robot … re-plans at the link level": ours
/// within the Wilson 95 % interval of the thesis's 5 of 13. `planned`: (result, re-plans,
/// what a run stranded for want of features lacked) of the thesis set-up's runs that had a
/// plan — where ours differs, how many met a contingency, how many of those it recovered
/// from, and what the others were left without say why.
fn replanning_claim(
    ours: &FieldSummary,
    planned: &[(FieldResult, usize, Option<Stranded>)],
) -> Claim {
    let th = THESIS_IN_VIVO;
    let [lo, hi] = wilson_interval(th.replanned_successes, th.successes, 1.96);
    let share = ours.replanned_successes as f64 / ours.successes.max(1) as f64;
    let agree = (lo..=hi).contains(&share);
    let met = planned.iter().filter(|(_, n, _)| *n > 0).count();
    let recovered = planned
        .iter()
        .filter(|(r, n, _)| *n > 0 && *r == FieldResult::Success)
        .count();
    let stranded = |s: Stranded| planned.iter().filter(|p| p.2 == Some(s)).count();
    let pct = |k: usize, n: usize| 100.0 * k as f64 / n.max(1) as f64;
    Claim {
        what: "successes that re-planned at the link level (thesis set-up)".into(),
        thesis: format!(
            "{} of {} ({:.0} %; 95 % interval {:.0}–{:.0} %)",
            th.replanned_successes,
            th.successes,
            100.0 * th.replanned_successes as f64 / th.successes as f64,
            100.0 * lo,
            100.0 * hi
        ),
        ours: format!(
            "{} of {} ({:.1} %)",
            ours.replanned_successes,
            ours.successes,
            100.0 * share
        ),
        verdict: Verdict::agree_if(agree).over(ours.successes),
        why: if agree || ours.successes == 0 {
            String::new()
        } else {
            format!(
                "a contingency (a failed transition or goal search) met {met} of our {} planned \
                 runs ({:.1} %), and {recovered} of those ({:.0} %) still reached the goal; the \
                 thesis's 5 re-planned successes are {:.0} % of its 18 runs. Runs ended for \
                 want of features: {} with no map element in view even after the localisation \
                 circle, {} with no path left to the goal once the failed links were excluded, \
                 {} with the re-plan budget spent",
                planned.len(),
                pct(met, planned.len()),
                pct(recovered, met),
                pct(th.replanned_successes, 18),
                stranded(Stranded::NoElementInView),
                stranded(Stranded::NoPathLeft),
                stranded(Stranded::ReplanBudget),
            )
        },
    }
}

/// "The most frequent causes of insufficient features are ground plane interference due to
/// the varying terrain pitch …": judged on what the robot's last scans held — the share of
/// their rays that met the ground is larger in the runs that failed for insufficient features
/// than in the successes, by more than the noise (Welch z > 1.96). `trials`: (result, final
/// ground share) of the thesis set-up's runs.
fn ground_claim(trials: &[(FieldResult, f64)]) -> Claim {
    let of = |f: &dyn Fn(FieldResult) -> bool| {
        trials
            .iter()
            .filter(|(r, _)| f(*r))
            .map(|(_, g)| *g)
            .collect::<Vec<f64>>()
    };
    let failed = of(&|r| {
        matches!(
            r,
            FieldResult::InsufficientFeatures | FieldResult::InsufficientFeaturesAndAliasing
        )
    });
    let ok = of(&|r| r == FieldResult::Success);
    let (verdict, ours) = match (mean_sd(&failed), mean_sd(&ok)) {
        (Some((mf, sf)), Some((ms, ss))) => {
            let se = (sf * sf / failed.len() as f64 + ss * ss / ok.len() as f64).sqrt();
            let z = if se > 0.0 { (mf - ms) / se } else { 0.0 };
            (
                Verdict::agree_if(z > 1.96),
                format!(
                    "rays on the ground in the last scans: {:.1} % in the {} runs that failed \
                     for insufficient features, {:.1} % in the {} successes (z = {z:.2})",
                    100.0 * mf,
                    failed.len(),
                    100.0 * ms,
                    ok.len()
                ),
            )
        }
        _ => (
            Verdict::Disagree.over(failed.len().min(ok.len())),
            format!(
                "{} runs failed for insufficient features, {} succeeded: too few to compare",
                failed.len(),
                ok.len()
            ),
        ),
    };
    Claim {
        what: "insufficient features come with the ground plane on pitched terrain".into(),
        thesis: "\"the most frequent causes of insufficient features are ground plane \
                 interference due to the varying terrain pitch and the conservative nature of \
                 the lidar landmark processing\""
            .into(),
        ours,
        verdict,
        why: "agree when the failed runs' last scans met the ground more than the successes' \
              by more than the noise (Welch z > 1.96)"
            .into(),
    }
}

/// Where the runs that failed for insufficient features were, measured: the landmarks they
/// detected per run against the successes', and how many of them ran in the world(s) whose map
/// has the fewest elements against how many runs did. `runs`: (result, detections, its world's
/// map elements) of the thesis set-up's planned runs. `None` without a failure and a success.
fn features_why(runs: &[(FieldResult, usize, usize)]) -> Option<String> {
    let failed = |r: FieldResult| {
        matches!(
            r,
            FieldResult::InsufficientFeatures | FieldResult::InsufficientFeaturesAndAliasing
        )
    };
    let mean = |f: &dyn Fn(FieldResult) -> bool| {
        let v: Vec<f64> = runs.iter().filter(|t| f(t.0)).map(|t| t.1 as f64).collect();
        (!v.is_empty()).then(|| (v.iter().sum::<f64>() / v.len() as f64, v.len()))
    };
    let (df, nf) = mean(&failed)?;
    let (ds, _) = mean(&|r| r == FieldResult::Success)?;
    let thinnest = runs.iter().map(|t| t.2).min()?;
    let there =
        |f: &dyn Fn(FieldResult) -> bool| runs.iter().filter(|t| t.2 == thinnest && f(t.0)).count();
    Some(format!(
        "the runs that failed for insufficient features detected {df:.0} landmarks per run \
         against {ds:.0} in the successes, and {} of those {nf} ran in the world(s) whose map \
         has the fewest elements ({thinnest}), where {} of all {} runs did",
        there(&failed),
        there(&|_| true),
        runs.len()
    ))
}

/// Mean and sample standard deviation of `v` (`None` below two values).
fn mean_sd(v: &[f64]) -> Option<(f64, f64)> {
    if v.len() < 2 {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    Some((mean, var.sqrt()))
}

/// Table 4.2 by magnitude: could each of the thesis's rows be the mean of its few paths drawn
/// from our trajectories at the same |P|? A row agrees when the thesis's mean lies within
/// 1.96 standard errors (our spread at that |P| over √(its paths)) of our mean.
fn table_4_2_magnitude_claim(output: &FieldOutput) -> Claim {
    let successes: Vec<(usize, f64, f64)> = output
        .trials()
        .map(|(_, t)| t)
        .filter(|t| t.variant == FieldVariant::Thesis && t.result == FieldResult::Success)
        .map(|t| (t.plan_len, t.length, t.transit_length))
        .collect();
    table_4_2_magnitude(&successes)
}

/// [`table_4_2_magnitude_claim`] on successes `(|P| in transitions, trajectory length m,
/// length driven in transitions m)`. Where rows differ, the why is measured on the same
/// successes: metres per transition against the thesis's metres per element, and the share
/// of the trajectory driven outside transitions.
fn table_4_2_magnitude(successes: &[(usize, f64, f64)]) -> Claim {
    let mut within = 0;
    let mut rows = Vec::new();
    for &(k, n, mean_t) in &THESIS_TABLE_4_2 {
        let lengths: Vec<f64> = successes
            .iter()
            .filter(|t| thesis_plan_len(t.0) == k)
            .map(|t| t.1)
            .collect();
        match mean_sd(&lengths) {
            Some((m, sd)) => {
                let half = 1.96 * sd / (n as f64).sqrt();
                let ok = (mean_t - m).abs() <= half;
                within += usize::from(ok);
                rows.push(format!(
                    "{k}: {m:.1} ± {half:.1} m ({} paths){}",
                    lengths.len(),
                    if ok { "" } else { " ✗" }
                ));
            }
            None => rows.push(format!("{k}: {} path(s) ✗", lengths.len())),
        }
    }
    Claim {
        what: "Table 4.2 by magnitude: each row's mean trajectory within our spread at its |P|"
            .into(),
        thesis: THESIS_TABLE_4_2
            .iter()
            .map(|r| {
                format!(
                    "{}: {:.1} m ({} path{})",
                    r.0,
                    r.2,
                    r.1,
                    if r.1 == 1 { "" } else { "s" }
                )
            })
            .collect::<Vec<_>>()
            .join(", "),
        ours: format!(
            "{within} of {} rows within ({})",
            THESIS_TABLE_4_2.len(),
            rows.join(", ")
        ),
        verdict: Verdict::agree_if(within == THESIS_TABLE_4_2.len()).over(successes.len()),
        why: if within == THESIS_TABLE_4_2.len() {
            String::new()
        } else {
            per_element_why(successes)
        },
    }
}

/// Metres per transition of ours against metres per element of the thesis's Table 4.2, and
/// the share of our trajectories outside transitions (localising first, finding the goal
/// last): the measured reason Table 4.2's magnitudes differ.
fn per_element_why(successes: &[(usize, f64, f64)]) -> String {
    let theirs: f64 = THESIS_TABLE_4_2
        .iter()
        .map(|r| r.1 as f64 * r.2)
        .sum::<f64>()
        / THESIS_TABLE_4_2
            .iter()
            .map(|r| (r.1 * r.0) as f64)
            .sum::<f64>();
    let transitions: usize = successes.iter().map(|t| t.0).sum();
    let transit: f64 = successes.iter().map(|t| t.2).sum();
    let total: f64 = successes.iter().map(|t| t.1).sum();
    if transitions == 0 || total <= 0.0 {
        return format!("no successful transitions of ours (thesis: {theirs:.1} m per element)");
    }
    format!(
        "measured on our {} successes: {:.1} m driven per transition against the thesis's \
         {theirs:.1} m per element of a path, and {:.0} % of our trajectories driven outside \
         transitions (localising at the start, finding the goal at the end)",
        successes.len(),
        transit / transitions as f64,
        100.0 * (1.0 - transit / total)
    )
}

/// The largest rise between successive |P| of `rows` (`(|P|, paths, mean)`, sorted by |P|):
/// `(from, to, rise m)`.
fn largest_rise(rows: &[(usize, usize, f64)]) -> Option<(usize, usize, f64)> {
    rows.windows(2)
        .map(|w| (w[0].0, w[1].0, w[1].2 - w[0].2))
        .max_by(|a, b| a.2.total_cmp(&b.2))
}

/// "The path length dramatically increases for |P| > 5": of ours (the |P| with two paths or
/// more, thesis count), the steepest step between neighbouring |P| is the one across |P| = 5
/// **and** it is beyond its noise (1.96 standard errors of the difference of the two means):
/// a steepest step within the noise is not a dramatic increase. `successes`: (|P| in the
/// thesis's count, trajectory length m) of the thesis set-up.
fn rise_claim(successes: &[(usize, f64)]) -> Claim {
    let rows = rows_by_plan_len(successes);
    // (from, to, rise m, noise m)
    let steps: Vec<(usize, usize, f64, f64)> = rows
        .windows(2)
        .map(|w| (w[0].0, w[1].0, w[1].2 - w[0].2, 1.96 * w[0].3.hypot(w[1].3)))
        .collect();
    let across = |s: &(usize, usize, f64, f64)| s.0 <= THESIS_RISE_ABOVE && s.1 > THESIS_RISE_ABOVE;
    let steepest = steps.iter().copied().max_by(|a, b| a.2.total_cmp(&b.2));
    let agree = steepest.is_some_and(|s| across(&s) && s.2 > s.3);
    let step = |(a, b, d, n): (usize, usize, f64, f64)| format!("{a} → {b}: {d:+.1} ± {n:.1} m");
    let theirs = largest_rise(&THESIS_TABLE_4_2).map_or(String::new(), |(a, b, d)| {
        format!("steepest step from |P| = {a} to {b} ({d:+.1} m)")
    });
    let why = match (steepest, steps.iter().copied().find(across)) {
        _ if agree => String::new(),
        (None, _) => "fewer than two |P| values with two paths or more among the successes: \
                      no step to compare"
            .into(),
        (Some(s), _) if across(&s) => format!(
            "the steepest step ({}) is within the noise of its two means",
            step(s)
        ),
        (Some(s), Some(c)) => format!(
            "the step across |P| = {THESIS_RISE_ABOVE} ({}) is not the steepest ({})",
            step(c),
            step(s)
        ),
        (Some(s), None) => format!(
            "no two neighbouring |P| of ours with two paths or more lie either side of \
             |P| = {THESIS_RISE_ABOVE}; the steepest step is {}",
            step(s)
        ),
    };
    Claim {
        what: format!(
            "Table 4.2: trajectories lengthen most across |P| = {THESIS_RISE_ABOVE} (thesis \
             count), beyond noise"
        ),
        thesis: theirs,
        ours: steepest.map_or_else(
            || format!("{} |P| value(s) with two paths or more", rows.len()),
            |s| format!("steepest step {}", step(s)),
        ),
        verdict: Verdict::agree_if(agree).over(rows.len()),
        why,
    }
}

/// `(min, max)` of `f` over the worlds.
fn world_range(output: &FieldOutput, f: impl Fn(&FieldWorld) -> usize) -> Option<(usize, usize)> {
    let v: Vec<usize> = output.worlds.iter().map(f).collect();
    Some((*v.iter().min()?, *v.iter().max()?))
}

/// The thesis's map: 44 elements over 25 point landmarks and 2 walls. Ours agree when the
/// thesis's count lies within our worlds' range; the false landmarks are given beside.
fn map_size_claims(config: &FieldParams, output: &FieldOutput) -> Vec<Claim> {
    let (Some(elements), Some(ids)) = (
        world_range(output, |w| w.map_size.elements),
        world_range(output, |w| w.mapping.mapped_ids),
    ) else {
        return Vec::new();
    };
    let false_ids = world_range(output, |w| w.mapping.false_landmarks).unwrap_or((0, 0));
    let n = output.worlds.len();
    let per: f64 = output
        .worlds
        .iter()
        .map(|w| w.map_size.elements_per_landmark)
        .sum::<f64>()
        / n.max(1) as f64;
    let span = |(lo, hi): (usize, usize)| {
        if lo == hi {
            lo.to_string()
        } else {
            format!("{lo}–{hi}")
        }
    };
    vec![
        Claim {
            what: "the field map's elements".into(),
            thesis: format!("{THESIS_ELEMENTS}"),
            ours: format!("{} over {n} world(s)", span(elements)),
            verdict: Verdict::agree_if((elements.0..=elements.1).contains(&THESIS_ELEMENTS)),
            why: if (elements.0..=elements.1).contains(&THESIS_ELEMENTS) {
                String::new()
            } else {
                format!(
                    "our maps keep {}: {per:.1} elements per landmark on average against the \
                     thesis's {:.1}, over {} mapped ids against its {THESIS_POINT_LANDMARKS} \
                     (see the map's size)",
                    config.elements.rule(config.min_observations),
                    THESIS_ELEMENTS as f64 / THESIS_POINT_LANDMARKS as f64,
                    span(ids)
                )
            },
        },
        Claim {
            what: "the field map's point landmarks".into(),
            thesis: format!("{THESIS_POINT_LANDMARKS} (and 2 walls)"),
            ours: format!(
                "{} ids over {n} world(s), of them {} false (clutter, ground)",
                span(ids),
                span(false_ids)
            ),
            verdict: Verdict::agree_if((ids.0..=ids.1).contains(&THESIS_POINT_LANDMARKS)),
            why: if (ids.0..=ids.1).contains(&THESIS_POINT_LANDMARKS) {
                String::new()
            } else {
                format!(
                    "the drive recognised {} of the world's {} landmarks in at least {} scans \
                     (extracted as landmarks up to {} m in radius), and {} false ids",
                    span(world_range(output, |w| w.mapping.real_landmarks).unwrap_or((0, 0))),
                    span(world_range(output, |w| w.mapping.world_landmarks).unwrap_or((0, 0))),
                    config.min_landmark_scans,
                    config.max_landmark_radius,
                    span(false_ids)
                )
            },
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(v: FieldVariant, trials: usize, successes: usize, length: f64) -> FieldSummary {
        FieldSummary {
            variant: v,
            trials,
            no_path: 0,
            successes,
            success_rate: successes as f64 / trials as f64,
            perceptual_aliasing: 0,
            insufficient_features: trials - successes,
            insufficient_features_and_aliasing: 0,
            mean_length: length,
            replanned_successes: 0,
            by_plan_len: vec![(1, 1, 5.0), (2, 1, 4.0)],
        }
    }

    fn output(variants: Vec<FieldSummary>) -> FieldOutput {
        FieldOutput {
            worlds: Vec::new(),
            variants,
            success_rate_over_worlds: Vec::new(),
            bounds: Vec::new(),
        }
    }

    #[test]
    fn the_ground_is_a_cause_only_when_failures_saw_more_of_it_beyond_noise() {
        use FieldResult::{InsufficientFeatures as F, Success as S};
        let spread = |base: f64, n: usize| (0..n).map(move |i| base + 0.01 * (i % 5) as f64);
        let mut trials: Vec<(FieldResult, f64)> = spread(0.30, 20).map(|g| (F, g)).collect();
        trials.extend(spread(0.05, 80).map(|g| (S, g)));
        assert_eq!(ground_claim(&trials).verdict, Verdict::Agree);
        // the same shares in both: no cause
        let same: Vec<(FieldResult, f64)> = spread(0.10, 20)
            .map(|g| (F, g))
            .chain(spread(0.10, 80).map(|g| (S, g)))
            .collect();
        assert_eq!(ground_claim(&same).verdict, Verdict::Disagree);
        // less ground in the failures: no cause either
        let less: Vec<(FieldResult, f64)> = spread(0.02, 20)
            .map(|g| (F, g))
            .chain(spread(0.20, 80).map(|g| (S, g)))
            .collect();
        assert_eq!(ground_claim(&less).verdict, Verdict::Disagree);
        // one of each is too few to compare; no success at all is nothing to compare with
        assert_eq!(
            ground_claim(&[(F, 0.3), (S, 0.1)]).verdict,
            Verdict::Disagree
        );
        assert_eq!(ground_claim(&[(F, 0.3)]).verdict, Verdict::NotJudged);
    }

    #[test]
    fn an_improvement_within_noise_is_not_called_an_improvement() {
        let o = output(vec![
            summary(FieldVariant::Thesis, 12, 8, 50.0),
            summary(FieldVariant::SafeSearch, 12, 9, 60.0),
            summary(FieldVariant::VisibilityCosts, 200, 190, 40.0),
        ]);
        let base = &o.variants[0];
        let c = improvement_claims(&o, base);
        assert_eq!(c[0].verdict, Verdict::Disagree, "{:?}", c[0]);
        assert!(c[0].why.contains("noise"));
        // 190 of 200 against 8 of 12 is beyond noise
        assert_eq!(c[1].verdict, Verdict::Agree, "{:?}", c[1]);
    }

    #[test]
    fn a_falling_table_4_2_is_not_called_growing() {
        // paths (|P|, length): three at each |P| with a spread of ±1 m
        let paths = |rows: &[(usize, f64)]| -> Vec<(usize, f64)> {
            rows.iter()
                .flat_map(|&(k, m)| [(k, m - 1.0), (k, m), (k, m + 1.0)])
                .collect()
        };
        // the old test was `>=` between neighbours: a flat or falling series "agreed"
        let c = table_4_2_claim(&paths(&[(1, 9.0), (2, 4.0)]));
        assert_eq!(c.verdict, Verdict::Disagree);
        assert!(c.ours.starts_with("falls"), "{}", c.ours);
        assert!(c.why.contains("1 → 2: -5.0 m"), "{}", c.why);
        let c = table_4_2_claim(&paths(&[(1, 3.0), (2, 3.0)]));
        assert_eq!(c.verdict, Verdict::Disagree, "flat is not growth");
        let c = table_4_2_claim(&paths(&[(1, 3.0), (3, 9.0)]));
        assert_eq!(c.verdict, Verdict::Agree);
        // a dip within the means' noise (±1.96·√(2/3) ≈ 1.6 m) is not a fall; beyond it is
        let c = table_4_2_claim(&paths(&[(1, 3.0), (2, 9.0), (3, 8.0), (4, 14.0)]));
        assert_eq!(c.verdict, Verdict::Agree, "{}", c.ours);
        let c = table_4_2_claim(&paths(&[(1, 3.0), (2, 9.0), (3, 6.0), (4, 14.0)]));
        assert_eq!(c.verdict, Verdict::Disagree, "{}", c.ours);
        assert!(c.ours.starts_with("rises and falls"), "{}", c.ours);
        // one |P| is not a flat series: too little to judge, and said so; nor is a |P|
        // with one path
        let c = table_4_2_claim(&paths(&[(1, 63.4)]));
        assert_eq!(c.verdict, Verdict::Disagree);
        assert!(c.why.contains("fewer than two"), "{}", c.why);
        assert!(!c.ours.contains("flat"), "{}", c.ours);
        let c = table_4_2_claim(&[(1, 3.0), (1, 4.0), (2, 9.0)]);
        assert!(c.why.contains("fewer than two"), "{}", c.why);
        assert_eq!(table_4_2_claim(&[]).verdict, Verdict::NotJudged);
    }

    #[test]
    fn table_4_2_rows_agree_only_within_our_spread_at_the_thesis_count() {
        // the thesis's rows, each drawn as ours at its |P| (thesis count = transitions + 1)
        // with a spread of ±1 m: every row within
        let mut ok = Vec::new();
        for &(k, _, mean) in &THESIS_TABLE_4_2 {
            ok.extend([
                (k - 1, mean - 1.0, mean / 2.0),
                (k - 1, mean + 1.0, mean / 2.0),
            ]);
        }
        let c = table_4_2_magnitude(&ok);
        assert_eq!(c.verdict, Verdict::Agree, "{}", c.ours);
        assert!(c.ours.starts_with("6 of 6 rows within"), "{}", c.ours);
        // keyed by transitions without the + 1, every row is off
        let shifted: Vec<(usize, f64, f64)> = ok.iter().map(|&(k, l, t)| (k + 1, l, t)).collect();
        assert_eq!(table_4_2_magnitude(&shifted).verdict, Verdict::Disagree);
        // ten times longer trajectories (ours at full scale: 70–221 m against 2.5–38.4 m)
        let long: Vec<(usize, f64, f64)> = ok.iter().map(|&(k, l, t)| (k, 10.0 * l, t)).collect();
        let c = table_4_2_magnitude(&long);
        assert_eq!(c.verdict, Verdict::Disagree);
        assert!(c.ours.starts_with("0 of 6"), "{}", c.ours);
        // the why is measured: transit per transition, and the share outside transitions
        // (half of each trajectory was in transitions, so 95 % is outside at ten times longer)
        assert!(
            c.why.contains("the thesis's 4.3 m per element"),
            "{}",
            c.why
        );
        assert!(
            c.why.contains("95 % of our trajectories driven outside"),
            "{}",
            c.why
        );
        // a row with a single path of ours is not judged within
        let c = table_4_2_magnitude(&ok[1..]);
        assert!(
            c.ours.starts_with("5 of 6") && c.ours.contains("1 path(s) ✗"),
            "{}",
            c.ours
        );
    }

    /// The rise is judged on the thesis's reading (steepest across |P| = 5) and through the
    /// means' noise: a steepest step within it is not a dramatic increase.
    #[test]
    fn failures_for_want_of_features_say_where_they_were() {
        use FieldResult::{InsufficientFeatures as F, PerceptualAliasing as A, Success as S};
        let runs = [
            (F, 10, 11),
            (F, 20, 11),
            (F, 30, 40),
            (S, 50, 40),
            (S, 70, 40),
            (S, 60, 11),
            (A, 99, 11),
        ];
        assert_eq!(
            features_why(&runs).unwrap(),
            "the runs that failed for insufficient features detected 20 landmarks per run \
             against 60 in the successes, and 2 of those 3 ran in the world(s) whose map has \
             the fewest elements (11), where 4 of all 7 runs did"
        );
        assert!(features_why(&[(S, 5, 3)]).is_none());
        assert!(features_why(&[(F, 5, 3)]).is_none());
    }

    #[test]
    fn a_success_rate_that_differs_names_the_worlds_own_rates() {
        let why = success_why(false, &[0.694, 0.975, 0.904]);
        assert!(
            why.ends_with(
                "our 3 world(s) succeed 69.4–97.5 % of their runs, so the thesis's one site at \
                 72 % is within the range of our sites"
            ),
            "{why}"
        );
        assert!(success_why(false, &[0.9, 0.95]).ends_with("outside the range of our sites"));
        assert!(!success_why(true, &[0.9]).contains("world"));
        assert!(!success_why(false, &[]).contains("world"));
    }

    #[test]
    fn the_rise_across_five_is_the_steepest_step_beyond_noise_only() {
        // three paths per |P| at each mean, ± `spread`
        let paths = |rows: &[(usize, f64)], spread: f64| -> Vec<(usize, f64)> {
            rows.iter()
                .flat_map(|&(k, m)| [(k, m - spread), (k, m), (k, m + spread)])
                .collect()
        };
        let thesis: Vec<(usize, f64)> = THESIS_TABLE_4_2.iter().map(|r| (r.0, r.2)).collect();
        let c = rise_claim(&paths(&thesis, 1.0));
        assert_eq!(c.verdict, Verdict::Agree, "{c:?}");
        assert!(c.ours.contains("4 → 6: +18.6"), "{}", c.ours);
        // the same means, each ± 20 m over three paths: 18.6 m is within 1.96·√2·20/√3·… noise
        let c = rise_claim(&paths(&thesis, 20.0));
        assert_eq!(c.verdict, Verdict::Disagree);
        assert!(c.why.contains("within the noise"), "{}", c.why);
        // a steady rise has its steepest step elsewhere
        let c = rise_claim(&paths(&[(2, 10.0), (3, 30.0), (4, 40.0), (6, 45.0)], 1.0));
        assert_eq!(c.verdict, Verdict::Disagree);
        assert!(c.why.contains("across |P| = 5 (4 → 6: +5.0"), "{}", c.why);
        assert!(c.why.contains("(2 → 3: +20.0"), "{}", c.why);
        // one path per |P| has no spread: not a row; one row has no step; none is not judged
        assert_eq!(
            rise_claim(&[(4, 10.0), (6, 50.0)]).verdict,
            Verdict::NotJudged
        );
        assert_eq!(
            rise_claim(&paths(&[(3, 5.0)], 1.0)).verdict,
            Verdict::Disagree
        );
    }

    #[test]
    fn the_replanning_share_agrees_within_the_thesis_interval_only() {
        let with = |successes: usize, replanned: usize| FieldSummary {
            replanned_successes: replanned,
            ..summary(FieldVariant::Thesis, 200, successes, 1.0)
        };
        // runs: 90 successes without a contingency, 10 with one, 20 failures after one
        let planned: Vec<(FieldResult, usize, Option<Stranded>)> =
            [(FieldResult::Success, 0, None); 90]
                .into_iter()
                .chain([(FieldResult::Success, 1, None); 10])
                .chain(
                    [(
                        FieldResult::InsufficientFeatures,
                        2,
                        Some(Stranded::NoPathLeft),
                    ); 15],
                )
                .chain(
                    [(
                        FieldResult::InsufficientFeatures,
                        1,
                        Some(Stranded::NoElementInView),
                    ); 5],
                )
                .collect();
        // thesis: 5 of 13 (38 %; Wilson 95 % ≈ 18–64 %)
        assert_eq!(
            replanning_claim(&with(100, 38), &planned).verdict,
            Verdict::Agree
        );
        let few = replanning_claim(&with(100, 10), &planned);
        assert_eq!(few.verdict, Verdict::Disagree);
        assert!(
            few.why.contains("met 30 of our 120 planned runs (25.0 %)")
                && few.why.contains("10 of those (33 %)")
                && few.why.contains("5 with no map element in view")
                && few.why.contains("15 with no path left")
                && few.why.contains("0 with the re-plan budget"),
            "{}",
            few.why
        );
        assert_eq!(
            replanning_claim(&with(100, 80), &planned).verdict,
            Verdict::Disagree
        );
        // no success: nothing to take a share of — not judged (it said "disagree", and the
        // bounds' "0 of 0 exceed it" said "agree")
        assert_eq!(
            replanning_claim(&with(0, 0), &[]).verdict,
            Verdict::NotJudged
        );
    }

    #[test]
    fn the_success_rate_agrees_within_the_thesis_interval_only() {
        let claim = |k: usize| {
            claims(
                &FieldParams::quick(0),
                &output(vec![summary(FieldVariant::Thesis, 100, k, 1.0)]),
            )
            .into_iter()
            .next()
            .map(|c| c.verdict)
        };
        assert_eq!(claim(80), Some(Verdict::Agree));
        assert_eq!(claim(95), Some(Verdict::Disagree));
        assert_eq!(claim(40), Some(Verdict::Disagree));
    }
}
