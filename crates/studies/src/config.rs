//! A study's config as a user edits it: printed as TOML, read back from a file whose fields
//! replace the built-in ones, changed one field at a time (`pairs=100`,
//! `schedule.fallbacks=0`). The CLI's `qrm study config/run --config/--set` and Python's
//! config dicts go through these, so a field named wrong is refused the same way everywhere.

use serde_json::Value;

use crate::error::{Result, StudyError};

fn invalid(why: String) -> StudyError {
    StudyError::InvalidParameter(why)
}

/// The first non-finite float in a TOML value, by dotted path below `at`: JSON (which every
/// config passes through) has no NaN or infinity, and serde_json would turn one into `null` —
/// read as "not set", so `max_frames = nan` silently meant "every frame" (issue 39).
fn non_finite(v: &toml::Value, at: &str) -> Option<(String, f64)> {
    let join = |k: &str| {
        if at.is_empty() {
            k.to_owned()
        } else {
            format!("{at}.{k}")
        }
    };
    match v {
        toml::Value::Float(f) if !f.is_finite() => Some((at.to_owned(), *f)),
        toml::Value::Array(a) => a
            .iter()
            .enumerate()
            .find_map(|(i, x)| non_finite(x, &format!("{at}[{i}]"))),
        toml::Value::Table(t) => t.iter().find_map(|(k, x)| non_finite(x, &join(k))),
        _ => None,
    }
}

fn refuse_non_finite(v: &toml::Value, at: &str, origin: &str) -> Result<()> {
    match non_finite(v, at) {
        Some((field, f)) => Err(invalid(format!(
            "{origin}`{field}` = {f}: a config value must be a finite number (NaN and \
             infinity are not settings; leave a field out for its default)"
        ))),
        None => Ok(()),
    }
}

/// A `--set` value: a TOML value; an integer above TOML's (i64) range that fits a u64 (a
/// seed); else the bare word as a string.
fn set_value(key: &str, raw: &str) -> Result<Value> {
    if let Some(v) = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|t| t.get("v").cloned())
    {
        refuse_non_finite(&v, key, "")?;
        return serde_json::to_value(v).map_err(|e| invalid(format!("`{key}`: {e}")));
    }
    if let Ok(n) = raw.replace('_', "").parse::<u64>() {
        return Ok(Value::from(n));
    }
    Ok(Value::String(raw.to_owned()))
}

/// Replaces the fields of `base` that `top` has, table by table (a file that names only
/// `pairs` keeps every other field of the built-in config).
pub fn overlay(base: &mut Value, top: Value) {
    match (base, top) {
        (Value::Object(b), Value::Object(t)) => {
            for (k, v) in t {
                match b.get_mut(&k) {
                    Some(slot) if slot.is_object() && v.is_object() => overlay(slot, v),
                    _ => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, t) => *b = t,
    }
}

/// Sets `key=value` in `config`: a dotted key naming a field the config has, a TOML value or
/// a bare word (taken as a string).
///
/// # Errors
/// [`StudyError::InvalidParameter`] for an assignment without `=`, a NaN or infinity, a field
/// the config does not have (listing the ones it has) or a key through a field that is not a
/// table.
pub fn set_field(config: &mut Value, assignment: &str) -> Result<()> {
    let Some((key, raw)) = assignment.split_once('=') else {
        return Err(invalid(format!(
            "`{}`: expected KEY=VALUE",
            qsr_core::text_file::shorten(assignment)
        )));
    };
    let (key, raw) = (key.trim(), raw.trim());
    let value = set_value(key, raw)?;
    let mut node = config;
    let parts: Vec<&str> = key.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let Some(obj) = node.as_object_mut() else {
            return Err(invalid(format!(
                "`{key}`: `{}` is not a table",
                parts[..i].join(".")
            )));
        };
        if !obj.contains_key(*part) {
            let known: Vec<&String> = obj.keys().collect();
            return Err(invalid(format!(
                "`{key}`: no field `{part}` (fields: {known:?})"
            )));
        }
        let Some(slot) = obj.get_mut(*part) else {
            break;
        };
        if i + 1 == parts.len() {
            *slot = value;
            return Ok(());
        }
        node = slot;
    }
    Err(invalid(format!(
        "`{}`: empty key",
        qsr_core::text_file::shorten(assignment)
    )))
}

/// A config (or any JSON value) as TOML. TOML has no null: a field left at `None` is left
/// out, and takes its default when the file is read back.
///
/// # Errors
/// [`StudyError::InvalidParameter`] for a value TOML cannot hold (a bare list at the top).
pub fn to_toml(v: &Value) -> Result<String> {
    fn strip(v: &Value) -> Value {
        match v {
            Value::Object(o) => Value::Object(
                o.iter()
                    .filter(|(_, x)| !x.is_null())
                    .map(|(k, x)| (k.clone(), strip(x)))
                    .collect(),
            ),
            Value::Array(a) => Value::Array(a.iter().map(strip).collect()),
            x => x.clone(),
        }
    }
    toml::to_string(&strip(v)).map_err(|e| invalid(format!("the config as TOML: {e}")))
}

/// A config file's text (TOML, as [`to_toml`] writes) as JSON; `origin` names it in errors.
///
/// # Errors
/// [`StudyError::InvalidParameter`] with the parser's line and column, or naming a field that
/// holds NaN or infinity.
pub fn from_toml(text: &str, origin: &str) -> Result<Value> {
    let table: toml::Value =
        toml::from_str(text).map_err(|e| invalid(format!("{origin}: not a TOML config: {e}")))?;
    refuse_non_finite(&table, "", &format!("{origin}: "))?;
    serde_json::to_value(table).map_err(|e| invalid(format!("{origin}: {e}")))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn set_takes_toml_values_dotted_keys_and_bare_words() {
        let mut c = json!({"pairs": 400, "trial": "all", "schedule": {"fallbacks": 1}});
        set_field(&mut c, "pairs=12").unwrap();
        set_field(&mut c, "trial=occlusion").unwrap();
        set_field(&mut c, "schedule.fallbacks = 0").unwrap();
        assert_eq!(
            c,
            json!({"pairs": 12, "trial": "occlusion", "schedule": {"fallbacks": 0}})
        );
        let e = set_field(&mut c, "pears=3").unwrap_err().to_string();
        assert!(e.contains("no field `pears`") && e.contains("pairs"), "{e}");
        assert!(set_field(&mut c, "pairs").is_err());
        assert!(set_field(&mut c, "pairs.x=1").is_err());
    }

    /// Issue 39: NaN went through serde_json as `null`, i.e. "not set": `--set
    /// max_frames=nan` ran every frame, and a config file's `gate_sigmas = nan` turned gating
    /// off, without a word.
    #[test]
    fn regression_nan_and_infinity_are_refused_by_name_not_read_as_unset() {
        let mut c = json!({"gate_sigmas": 3.0, "grid": {"step": 0.5}, "sigmas": [1.0]});
        for (set, field) in [
            ("gate_sigmas=nan", "gate_sigmas"),
            ("gate_sigmas=-inf", "gate_sigmas"),
            ("grid.step=inf", "grid.step"),
            ("sigmas=[1.0, nan]", "sigmas[1]"),
        ] {
            let e = set_field(&mut c, set).unwrap_err().to_string();
            assert!(
                e.contains(&format!("`{field}`")) && e.contains("finite"),
                "{set}: {e}"
            );
        }
        let e = from_toml("[grid]\nstep = nan\n", "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.toml") && e.contains("`grid.step`"), "{e}");
        assert_eq!(
            c,
            json!({"gate_sigmas": 3.0, "grid": {"step": 0.5}, "sigmas": [1.0]})
        );
    }

    /// Issue 39: `--set seed=18446744073709551615` was refused as "a string" (TOML integers
    /// are i64) though `--seed` takes it.
    #[test]
    fn regression_a_u64_seed_is_a_number() {
        let mut c = json!({"seed": 0});
        set_field(&mut c, "seed=18446744073709551615").unwrap();
        assert_eq!(c, json!({"seed": u64::MAX}));
        set_field(&mut c, "seed=word").unwrap();
        assert_eq!(c, json!({"seed": "word"}));
    }

    #[test]
    fn overlay_replaces_only_the_fields_given() {
        let mut c = json!({"pairs": 400, "schedule": {"fallbacks": 1, "sweep": true}});
        overlay(&mut c, json!({"schedule": {"fallbacks": 0}}));
        assert_eq!(
            c,
            json!({"pairs": 400, "schedule": {"fallbacks": 0, "sweep": true}})
        );
    }

    #[test]
    fn toml_round_trip_leaves_out_nulls() {
        let c = json!({"pairs": 12, "max_frames": null, "calculi": ["edc", "double-cross"]});
        let text = to_toml(&c).unwrap();
        assert!(!text.contains("max_frames"), "{text}");
        assert_eq!(
            from_toml(&text, "c.toml").unwrap(),
            json!({"pairs": 12, "calculi": ["edc", "double-cross"]})
        );
        let e = from_toml("pairs = = 3", "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.toml"), "{e}");
    }
}
