//! A study's config as a user edits it: printed as TOML, read back from a file whose fields
//! replace the built-in ones, changed one field at a time (`pairs=100`,
//! `schedule.fallbacks=0`). The CLI's `qrm study config/run --config/--set` and Python's
//! config dicts go through these, so a field named wrong is refused the same way everywhere.

use serde_json::Value;

use crate::error::{Result, StudyError};

fn invalid(why: String) -> StudyError {
    StudyError::InvalidParameter(why)
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
/// [`StudyError::InvalidParameter`] for an assignment without `=`, a field the config does
/// not have (listing the ones it has) or a key through a field that is not a table.
pub fn set_field(config: &mut Value, assignment: &str) -> Result<()> {
    let Some((key, raw)) = assignment.split_once('=') else {
        return Err(invalid(format!("`{assignment}`: expected KEY=VALUE")));
    };
    let (key, raw) = (key.trim(), raw.trim());
    let value = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|t| t.get("v").cloned())
        .map_or_else(|| Ok(Value::String(raw.to_owned())), serde_json::to_value)
        .map_err(|e| invalid(format!("`{key}`: {e}")))?;
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
    Err(invalid(format!("`{assignment}`: empty key")))
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
/// [`StudyError::InvalidParameter`] with the parser's line and column.
pub fn from_toml(text: &str, origin: &str) -> Result<Value> {
    toml::from_str(text).map_err(|e| invalid(format!("{origin}: not a TOML config: {e}")))
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
