//! The one shape of every study.
//!
//! A study is a serde [`Study::Config`] with [`Study::quick`] and [`Study::full`] versions,
//! [`Study::run`] from a config to an [`Study::Output`] (records and summaries, serde), and
//! [`Study::report`] from the two to a [`Report`]. Nothing else: no files, no terminal, no
//! plotting — those are the front ends'. [`AnyStudy`] is the same shape over JSON values, so
//! `qrm study run NAME` and `qrm.studies.run(name)` need no code per study;
//! [`crate::registry::STUDIES`] lists them.
//!
//! **Shards.** Every study splits its work into [`Study::shards`] independent parts (a world,
//! a fold, a range of trials) that depend on the config and their index alone:
//! [`Study::run_shard`] runs one anywhere, [`Study::aggregate`] merges them in any order, and
//! a local [`Study::run`] *is* the aggregate of every shard run here — so a sweep on a cluster
//! gives the local result exactly, and a missing or duplicated shard is an error. An output
//! holds no timings for the same reason: the same config gives the same bytes.
//!
//! **Progress.** A shard ticks [`Study::shard_units`] units — counted from the config before
//! any work — and checks for a stop between units (a unit is under a second at the thesis's
//! settings). [`Study::run`] and [`AnyStudy::run_shard`] announce the total once, before the
//! first tick, so a bar's total never moves while the work runs.

use qsr_core::progress::{FixedTotal, Progress};
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
    /// A file the whole output is worth writing to as JSON (`None`: too large to be useful
    /// beside the report's tables).
    const OUTPUT_FILE: Option<&'static str> = None;
    /// The seed every front end runs when none is given (`qrm study run`, `qrm.studies.run`,
    /// an alias such as `qrm demo`), so they run one config: 0 unless a study says why not.
    const DEFAULT_SEED: u64 = 0;
    /// What it runs; every field has a meaning a user can change.
    type Config: Serialize + DeserializeOwned + Clone;
    /// What a run produced: records and summaries.
    type Output: Serialize + DeserializeOwned;
    /// What one shard produced.
    type Shard: Serialize + DeserializeOwned + Send;

    /// A run of a minute or less, for tests and a first look.
    fn quick(seed: u64) -> Self::Config;
    /// The thesis's settings.
    fn full(seed: u64) -> Self::Config;
    /// Checks a config before any work.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] naming the field.
    fn check(config: &Self::Config) -> Result<()>;
    /// How many shards the work of `config` splits into.
    ///
    /// # Errors
    /// As [`Study::check`].
    fn shards(config: &Self::Config) -> Result<usize>;
    /// The units of work shard `index` ticks, counted before it runs (it may read the
    /// inputs, never do the work).
    ///
    /// # Errors
    /// As [`Study::check`]; [`StudyError::InvalidParameter`] for an index beyond
    /// [`Study::shards`]; an input that cannot be read.
    fn shard_units(config: &Self::Config, index: usize) -> Result<usize>;
    /// Runs shard `index`; `progress` ticks per unit of work and can stop it. Called through
    /// [`Study::run`] or [`AnyStudy::run_shard`], which announce the units up front.
    ///
    /// # Errors
    /// The study's errors; [`StudyError::Cancelled`] when `progress` asked it to stop;
    /// [`StudyError::InvalidParameter`] for an index beyond [`Study::shards`].
    fn run_shard(
        config: &Self::Config,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<Self::Shard>;
    /// Merges shards `(index, shard)` given in any order.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] for a missing, duplicated or foreign shard.
    fn aggregate(config: &Self::Config, shards: Vec<(usize, Self::Shard)>) -> Result<Self::Output>;
    /// Runs the study here: every shard, then [`Study::aggregate`].
    ///
    /// # Errors
    /// As [`Study::run_shard`].
    fn run(config: &Self::Config, progress: &dyn Progress) -> Result<Self::Output> {
        Self::check(config)?;
        let n = Self::shards(config)?;
        let mut units = 0usize;
        for i in 0..n {
            units = units.saturating_add(Self::shard_units(config, i)?);
        }
        progress.add_total(units);
        let fixed = FixedTotal(progress);
        let shards = (0..n)
            .map(|i| Self::run_shard(config, i, &fixed).map(|s| (i, s)))
            .collect::<Result<Vec<_>>>()?;
        Self::aggregate(config, shards)
    }
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
    /// [`Study::OUTPUT_FILE`] and the output as JSON in the output's own field order (what
    /// that file holds).
    pub output_file: Option<(&'static str, String)>,
}

impl Ran {
    fn of<S: Study>(config: &S::Config, output: &S::Output) -> Result<Self> {
        Ok(Self {
            config: to_json(config, "config")?,
            output: to_json(output, "output")?,
            report: S::report(config, output),
            output_file: match S::OUTPUT_FILE {
                Some(name) => Some((
                    name,
                    serde_json::to_string(output)
                        .map_err(|e| StudyError::InvalidParameter(format!("output: {e}")))?,
                )),
                None => None,
            },
        })
    }
}

/// A [`Study`] over JSON values: what the registry holds.
pub trait AnyStudy: Sync {
    /// [`Study::NAME`].
    fn name(&self) -> &'static str;
    /// [`Study::ABOUT`].
    fn about(&self) -> &'static str;
    /// [`Study::OUTPUT_FILE`].
    fn output_file(&self) -> Option<&'static str>;
    /// [`Study::DEFAULT_SEED`].
    fn default_seed(&self) -> u64;
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
    /// [`Study::shards`] of a config.
    ///
    /// # Errors
    /// As [`AnyStudy::check`].
    fn shards(&self, config: &serde_json::Value) -> Result<usize>;
    /// [`Study::run_shard`], the shard as JSON.
    ///
    /// # Errors
    /// As [`AnyStudy::check`] and [`Study::run_shard`].
    fn run_shard(
        &self,
        config: &serde_json::Value,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<serde_json::Value>;
    /// [`Study::aggregate`] of JSON shards `(index, shard)`, then the report.
    ///
    /// # Errors
    /// As [`AnyStudy::check`] and [`Study::aggregate`]; a shard that is not the study's.
    fn aggregate(
        &self,
        config: &serde_json::Value,
        shards: Vec<(usize, serde_json::Value)>,
    ) -> Result<Ran>;
    /// The run a config and its output make, report and all — what a front end saves from a
    /// run it holds as JSON (Python's `qrm.studies.save`): the same files as the run itself.
    ///
    /// # Errors
    /// As [`AnyStudy::check`]; an output that is not the study's.
    fn rebuild(&self, config: &serde_json::Value, output: serde_json::Value) -> Result<Ran>;
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
    // The path to the field at fault: serde_json alone says "invalid type: null, expected
    // f64" and leaves the user to guess which of forty fields (issue 39).
    let c: S::Config = serde_path_to_error::deserialize(config.clone()).map_err(|e| {
        let field = e.path().to_string();
        let why = e.into_inner();
        StudyError::InvalidParameter(if field == "." {
            format!("config of `{}`: {why}", S::NAME)
        } else {
            format!("config of `{}`: field `{field}`: {why}", S::NAME)
        })
    })?;
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
    fn default_seed(&self) -> u64 {
        S::DEFAULT_SEED
    }
    fn output_file(&self) -> Option<&'static str> {
        S::OUTPUT_FILE
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
        Ran::of::<S>(&c, &output)
    }
    fn shards(&self, config: &serde_json::Value) -> Result<usize> {
        S::shards(&read::<S>(config)?)
    }
    fn run_shard(
        &self,
        config: &serde_json::Value,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<serde_json::Value> {
        let c = read::<S>(config)?;
        progress.add_total(S::shard_units(&c, index)?);
        to_json(&S::run_shard(&c, index, &FixedTotal(progress))?, "shard")
    }
    fn aggregate(
        &self,
        config: &serde_json::Value,
        shards: Vec<(usize, serde_json::Value)>,
    ) -> Result<Ran> {
        let c = read::<S>(config)?;
        let shards = shards
            .into_iter()
            .map(|(i, v)| {
                serde_json::from_value::<S::Shard>(v)
                    .map(|s| (i, s))
                    .map_err(|e| {
                        StudyError::InvalidParameter(format!(
                            "shard {i} is not a shard of `{}`: {e}",
                            S::NAME
                        ))
                    })
            })
            .collect::<Result<Vec<_>>>()?;
        let output = S::aggregate(&c, shards)?;
        Ran::of::<S>(&c, &output)
    }
    fn rebuild(&self, config: &serde_json::Value, output: serde_json::Value) -> Result<Ran> {
        let c = read::<S>(config)?;
        let output: S::Output = serde_json::from_value(output).map_err(|e| {
            StudyError::InvalidParameter(format!("not an output of `{}`: {e}", S::NAME))
        })?;
        Ran::of::<S>(&c, &output)
    }
}
