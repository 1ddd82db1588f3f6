//! Every numeric field of every study config, set to each extreme, through the study's own
//! check (issue 39): the check answers within a second, never panics, and refuses the counts
//! and distances that drive the work.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use serde_json::Value;

/// Dotted paths of every number in `v` (array elements by index).
fn numeric_paths(v: &Value, at: &str, out: &mut Vec<String>) {
    match v {
        Value::Number(_) => out.push(at.to_owned()),
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                numeric_paths(x, &format!("{at}[{i}]"), out);
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                let p = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                numeric_paths(x, &p, out);
            }
        }
        _ => {}
    }
}

fn slot<'a>(v: &'a mut Value, path: &str) -> &'a mut Value {
    let mut node = v;
    for part in path.split('.') {
        let (key, index) = match part.split_once('[') {
            Some((k, rest)) => (
                k,
                Some(rest.trim_end_matches(']').parse::<usize>().unwrap()),
            ),
            None => (part, None),
        };
        node = node.get_mut(key).unwrap();
        if let Some(i) = index {
            node = node.get_mut(i).unwrap();
        }
    }
    node
}

/// Integer fields that may be 10¹² without driving the work: seeds, thresholds, a cap the
/// recording bounds anyway, and the reasoning study's `world` fields its part (b) does not
/// use (it simulates the world's geometry only).
const COUNT_FIELDS_NOT_WORK: [(&str, &str); 6] = [
    ("*", "seed"),
    ("field", "min_observations"),
    ("field", "min_landmark_scans"),
    ("real-data", "max_frames"),
    ("reason", "study.world.samples"),
    ("reason", "study.world.trials"),
];

/// Float fields that may be 1e308: thresholds and tolerances (larger only accepts or merges
/// more), odometry errors (finite, the robot only errs more), and the reasoning study's unused
/// `world` fields.
const FLOATS_UNBOUNDED: [(&str, &str); 9] = [
    ("real-data", "gate_sigmas"),
    ("real-data", "variants[*].sensor.nu"),
    ("serge-cv", "sigmas[*]"),
    ("serge-cv", "sigma_for_mu"),
    ("table-4-1", "references.perceived.heading_error"),
    ("table-4-1", "references.perceived.scale_error"),
    ("reason", "study.world.detail_sigmas[*]"),
    ("reason", "study.world.floor"),
    ("reason", "study.world.sigmas[*]"),
];

/// Whether `path` of `study` is in `list` (`*` any study; `[*]` any index; a last part alone
/// matches that field at any depth).
fn listed(study: &str, path: &str, list: &[(&str, &str)]) -> bool {
    let general: String = path
        .split('[')
        .enumerate()
        .map(|(i, p)| {
            if i == 0 {
                p.to_owned()
            } else {
                format!("[*]{}", p.split_once(']').map_or("", |(_, rest)| rest))
            }
        })
        .collect();
    list.iter().any(|(s, f)| {
        (*s == "*" || *s == study) && (general == *f || general.ends_with(&format!(".{f}")))
    })
}

/// Issue 39: a count of 10¹² (trials, pairs, folds, a grid, samples, a horizon) or a distance
/// of 1e308 was accepted by a study's check and then ran for ever or aborted. Every number of
/// every study's config, at each extreme, goes through the check every front end runs: it
/// answers within a second, and the counts and distances that drive the work are refused.
#[test]
fn every_config_field_at_every_extreme_is_refused_or_bounded() {
    let extremes: [f64; 5] = [1e-12, 1e12, 1e308, -1.0, 0.0];
    let mut problems = Vec::new();
    for study in studies::STUDIES {
        let base = study.config(false, 0);
        let mut paths = Vec::new();
        numeric_paths(&base, "", &mut paths);
        for path in &paths {
            let integer = base_is_integer(&base, path);
            for x in extremes {
                let mut c = base.clone();
                let value = if integer && x.fract() == 0.0 && x.abs() < 9e15 {
                    Value::from(x as i64)
                } else {
                    Value::from(x)
                };
                *slot(&mut c, path) = value;
                let t0 = std::time::Instant::now();
                let verdict = study.check(&c);
                let took = t0.elapsed();
                let accepted = verdict.is_ok();
                // A refusal for work or memory is the one estimate's (qsr_core::cost), in its
                // one form: the knobs, the estimate, the limits of a run.
                if let Err(e) = &verdict {
                    let text = e.to_string();
                    if text.contains("needs about")
                        && !text.contains("; the limits are 4 GiB and 48 core-hours")
                    {
                        problems.push(format!(
                            "{} {path} = {x:e}: an estimate not in the one form: {text}",
                            study.name()
                        ));
                    }
                }
                assert!(
                    took.as_secs_f64() < 1.0,
                    "{} {path} = {x:e}: the check took {took:?}",
                    study.name()
                );
                let count_unbounded =
                    integer && x == 1e12 && !listed(study.name(), path, &COUNT_FIELDS_NOT_WORK);
                let float_unbounded =
                    !integer && x == 1e308 && !listed(study.name(), path, &FLOATS_UNBOUNDED);
                if accepted && (count_unbounded || float_unbounded) {
                    problems.push(format!("{} {path} = {x:e} is accepted", study.name()));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_lists_match_by_study_and_path() {
    assert!(listed("field", "seed", &COUNT_FIELDS_NOT_WORK));
    assert!(listed("reason", "study.map.seed", &COUNT_FIELDS_NOT_WORK));
    assert!(!listed("field", "samples", &COUNT_FIELDS_NOT_WORK));
    assert!(listed("serge-cv", "sigmas[2]", &FLOATS_UNBOUNDED));
    assert!(!listed("monte-carlo", "sigmas[2]", &FLOATS_UNBOUNDED));
    assert!(!listed(
        "monte-carlo",
        "detail_sigmas[0]",
        &FLOATS_UNBOUNDED
    ));
    assert!(listed(
        "real-data",
        "variants[1].sensor.nu",
        &FLOATS_UNBOUNDED
    ));
}

fn base_is_integer(base: &Value, path: &str) -> bool {
    let mut b = base.clone();
    let v = slot(&mut b, path);
    v.is_u64() || v.is_i64()
}
