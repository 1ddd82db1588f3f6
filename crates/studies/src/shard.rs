//! Shards: a study's work split into independent parts that can run on other machines and
//! be merged, in any order, into the result of a local run.

use crate::error::{Result, StudyError};

/// Checks that `indices` are `0..n`, each exactly once.
///
/// # Errors
/// [`StudyError::InvalidParameter`] naming the missing, duplicated and out-of-range shards:
/// a sweep that lost a shard must fail, not average what came back.
pub fn check_indices(n: usize, indices: impl IntoIterator<Item = usize>) -> Result<()> {
    let mut seen = vec![0usize; n];
    let mut foreign = Vec::new();
    for i in indices {
        match seen.get_mut(i) {
            Some(c) => *c += 1,
            None => foreign.push(i),
        }
    }
    let missing: Vec<usize> = (0..n).filter(|&i| seen[i] == 0).collect();
    let twice: Vec<usize> = (0..n).filter(|&i| seen[i] > 1).collect();
    if missing.is_empty() && twice.is_empty() && foreign.is_empty() {
        return Ok(());
    }
    let mut why = Vec::new();
    if !missing.is_empty() {
        why.push(format!("missing {missing:?}"));
    }
    if !twice.is_empty() {
        why.push(format!("more than once {twice:?}"));
    }
    if !foreign.is_empty() {
        why.push(format!("beyond the {n} shards {foreign:?}"));
    }
    Err(StudyError::InvalidParameter(format!(
        "shards of a study of {n}: {}",
        why.join("; ")
    )))
}

fn show(v: Option<&serde_json::Value>) -> String {
    v.map_or_else(|| "absent".to_owned(), ToString::to_string)
}

/// A shard as a file (`qrm study shard` writes one, `qrm study aggregate` reads them): the
/// study and config it belongs to travel with it, so a shard of another run is refused
/// instead of merged.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShardFile {
    /// The config the shard ran.
    pub config: serde_json::Value,
    /// Its index, `0..shards`.
    pub index: usize,
    /// What it produced.
    pub shard: serde_json::Value,
    /// The study's name.
    pub study: String,
}

impl ShardFile {
    /// Reads a shard file's text; `origin` names it in errors.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`]: not a shard file, or a shard of another study or
    /// config than `study` and `config`.
    pub fn read(text: &str, origin: &str, study: &str, config: &serde_json::Value) -> Result<Self> {
        let file: Self = serde_json::from_str(text).map_err(|e| {
            StudyError::InvalidParameter(format!("{origin}: not a shard file: {e}"))
        })?;
        if file.study != study {
            return Err(StudyError::InvalidParameter(format!(
                "{origin}: a shard of study `{}`, not of `{study}`",
                file.study
            )));
        }
        if &file.config != config {
            let differ: Vec<String> = match (&file.config, config) {
                (serde_json::Value::Object(a), serde_json::Value::Object(b)) => a
                    .keys()
                    .chain(b.keys())
                    .filter(|k| a.get(*k) != b.get(*k))
                    .map(|k| format!("`{k}` {} ≠ {}", show(a.get(k)), show(b.get(k))))
                    .collect::<std::collections::BTreeSet<_>>()
                    .into_iter()
                    .collect(),
                _ => vec!["the whole config".to_owned()],
            };
            return Err(StudyError::InvalidParameter(format!(
                "{origin}: a shard of another config of `{study}` (the shard's vs this run's: {})",
                differ.join(", ")
            )));
        }
        Ok(file)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn every_shard_once_in_any_order() {
        assert!(check_indices(3, [2, 0, 1]).is_ok());
        assert!(check_indices(0, []).is_ok());
        let e = check_indices(4, [3, 0, 0, 7]).err().map(|e| e.to_string());
        let e = e.unwrap_or_default();
        assert!(e.contains("missing [1, 2]"), "{e}");
        assert!(e.contains("more than once [0]"), "{e}");
        assert!(e.contains("beyond the 4 shards [7]"), "{e}");
    }

    #[test]
    fn a_shard_of_another_study_or_config_is_refused_saying_what_differs() {
        let file = ShardFile {
            config: json!({"seed": 0, "folds": 5}),
            index: 2,
            shard: json!([1, 2]),
            study: "serge-cv".into(),
        };
        let text = serde_json::to_string(&file).unwrap();
        let read = ShardFile::read(&text, "s.json", "serge-cv", &file.config).unwrap();
        assert_eq!(read, file);
        let e = ShardFile::read(&text, "s.json", "field", &file.config).unwrap_err();
        assert!(
            e.to_string()
                .contains("of study `serge-cv`, not of `field`"),
            "{e}"
        );
        let e = ShardFile::read(&text, "s.json", "serge-cv", &json!({"seed": 3, "folds": 5}))
            .unwrap_err()
            .to_string();
        assert!(e.contains("`seed` 0 ≠ 3") && !e.contains("folds"), "{e}");
        assert!(ShardFile::read("{}", "s.json", "serge-cv", &file.config).is_err());
    }
}
