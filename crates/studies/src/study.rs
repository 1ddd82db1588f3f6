//! The one shape of every study, and the registry the front ends run them from.
//!
//! A study is a serde [`Study::Config`] with [`Study::quick`] and [`Study::full`] versions,
//! [`Study::run`] from a config to an [`Study::Output`] (records and summaries, serde), and
//! [`Study::report`] from the two to a [`Report`]. Nothing else: no files, no terminal, no
//! plotting — those are the front ends'. [`AnyStudy`] is the same shape over JSON values, so
//! `qrm study run NAME` and `qrm.studies.run(name)` need no code per study; [`STUDIES`] lists
//! them.

use qsr_core::progress::Progress;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::{Result, StudyError};
use crate::report::Report;

/// A thesis experiment.
pub trait Study {
    /// The name a front end runs it by (`table-4-1`).
    const NAME: &'static str;
    /// One line: what it reproduces.
    const ABOUT: &'static str;
    /// What it runs; every field has a meaning a user can change.
    type Config: Serialize + DeserializeOwned + Clone;
    /// What a run produced: records and summaries.
    type Output: Serialize + DeserializeOwned;

    /// A run of a minute or less, for tests and a first look.
    fn quick(seed: u64) -> Self::Config;
    /// The thesis's settings.
    fn full(seed: u64) -> Self::Config;
    /// Checks a config before any work.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] naming the field.
    fn check(config: &Self::Config) -> Result<()>;
    /// Runs the study; `progress` ticks per unit of work and can stop it.
    ///
    /// # Errors
    /// The study's errors; [`StudyError::Cancelled`] when `progress` asked it to stop.
    fn run(config: &Self::Config, progress: &dyn Progress) -> Result<Self::Output>;
    /// What the run says beside the thesis: tables, claims with computed verdicts, figures.
    fn report(config: &Self::Config, output: &Self::Output) -> Report;
}

/// A run through [`AnyStudy`]: the config it ran, its output and its report.
#[derive(Debug, Clone)]
pub struct Ran {
    /// The config, as JSON.
    pub config: serde_json::Value,
    /// The output, as JSON.
    pub output: serde_json::Value,
    /// The report.
    pub report: Report,
}

/// A [`Study`] over JSON values: what the registry holds.
pub trait AnyStudy: Sync {
    /// [`Study::NAME`].
    fn name(&self) -> &'static str;
    /// [`Study::ABOUT`].
    fn about(&self) -> &'static str;
    /// The quick or full config with `seed`, as JSON.
    fn config(&self, full: bool, seed: u64) -> serde_json::Value;
    /// Reads and checks a config.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] naming the field that does not fit.
    fn check(&self, config: &serde_json::Value) -> Result<()>;
    /// Runs a config.
    ///
    /// # Errors
    /// As [`AnyStudy::check`] and [`Study::run`].
    fn run(&self, config: &serde_json::Value, progress: &dyn Progress) -> Result<Ran>;
}

/// The [`AnyStudy`] of `S`.
pub struct Registered<S>(std::marker::PhantomData<fn() -> S>);

impl<S> Registered<S> {
    /// The study `S`.
    #[must_use]
    pub const fn new() -> Self {
        Self(std::marker::PhantomData)
    }
}

impl<S> Default for Registered<S> {
    fn default() -> Self {
        Self::new()
    }
}

fn read<S: Study>(config: &serde_json::Value) -> Result<S::Config> {
    let c: S::Config = serde_json::from_value(config.clone())
        .map_err(|e| StudyError::InvalidParameter(format!("config of `{}`: {e}", S::NAME)))?;
    S::check(&c)?;
    Ok(c)
}

fn to_json<T: Serialize>(v: &T, what: &str) -> Result<serde_json::Value> {
    serde_json::to_value(v).map_err(|e| StudyError::InvalidParameter(format!("{what}: {e}")))
}

impl<S: Study> AnyStudy for Registered<S> {
    fn name(&self) -> &'static str {
        S::NAME
    }
    fn about(&self) -> &'static str {
        S::ABOUT
    }
    fn config(&self, full: bool, seed: u64) -> serde_json::Value {
        let c = if full { S::full(seed) } else { S::quick(seed) };
        // A config is plain data (numbers, strings, lists, enums): it always serialises.
        serde_json::to_value(c).unwrap_or(serde_json::Value::Null)
    }
    fn check(&self, config: &serde_json::Value) -> Result<()> {
        read::<S>(config).map(|_| ())
    }
    fn run(&self, config: &serde_json::Value, progress: &dyn Progress) -> Result<Ran> {
        let c = read::<S>(config)?;
        let output = S::run(&c, progress)?;
        let report = S::report(&c, &output);
        Ok(Ran {
            config: to_json(&c, "config")?,
            output: to_json(&output, "output")?,
            report,
        })
    }
}

/// Every study, in the thesis's order.
pub static STUDIES: &[&dyn AnyStudy] = &[&Registered::<crate::qlink::table_4_1::Table41>::new()];

/// The study named `name`.
///
/// # Errors
/// [`StudyError::InvalidParameter`] listing the names there are.
pub fn find(name: &str) -> Result<&'static dyn AnyStudy> {
    STUDIES
        .iter()
        .copied()
        .find(|s| s.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = STUDIES.iter().map(|s| s.name()).collect();
            StudyError::InvalidParameter(format!(
                "unknown study `{name}` (studies: {})",
                names.join(", ")
            ))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_study_is_found_by_name_and_its_configs_are_valid() {
        assert!(!STUDIES.is_empty());
        for s in STUDIES {
            let found = find(s.name()).map(|f| f.name());
            assert_eq!(found.ok(), Some(s.name()));
            for full in [false, true] {
                let c = s.config(full, 3);
                assert!(c.is_object(), "{}: {c}", s.name());
                s.check(&c).unwrap_or_else(|e| panic!("{}: {e}", s.name()));
            }
        }
        let e = find("table-9-9")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("unknown study `table-9-9`") && e.contains("table-4-1"),
            "{e}"
        );
    }

    #[test]
    fn a_misspelt_field_is_refused_with_its_name() {
        let s = find("table-4-1").ok().map(|s| s.config(false, 0));
        let mut c = s.unwrap_or_default();
        if let Some(o) = c.as_object_mut() {
            o.insert("pairs".into(), serde_json::json!("many"));
        }
        let e = find("table-4-1")
            .and_then(|s| s.check(&c))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("config of `table-4-1`") && e.contains("many"),
            "{e}"
        );
    }
}
