//! `qrm study ...`: every thesis study through one runner. The study itself (config, run,
//! report with computed verdicts) is in the `studies` crate; here the flags become a config
//! (stage two of parsing), progress is shown, and the report's tables, figures and markdown
//! are written.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use studies::{AnyStudy, Report};

use studies::config::{from_toml, overlay, set_field, to_toml};
use studies::shard::ShardFile;

use crate::output::write_atomic;

/// `qrm study ...`.
#[derive(Debug, clap::Subcommand)]
pub enum StudyCmd {
    /// The studies there are, one a line.
    List,
    /// Print a study's config as TOML, to edit and pass back with `--config`.
    Config {
        /// The study (`qrm study list`).
        #[arg(value_parser = study_names())]
        name: String,
        /// The thesis's settings (default: the quick ones).
        #[arg(long)]
        full: bool,
        /// Seed written into the config (default: the study's, 0 but for `demo`).
        #[arg(long)]
        seed: Option<u64>,
    },
    /// Run a study: tables as CSV, figures, report.md and the config it ran in `--out`.
    Run(RunArgs),
    /// Run one shard of a study (a world, a fold, a range of trials) and write it as JSON:
    /// shards run anywhere, in any order, and `qrm study aggregate` merges them into exactly
    /// the result of `qrm study run`.
    Shard(ShardArgs),
    /// Merge shard files written by `qrm study shard` (each exactly once) and write the run's
    /// files as `qrm study run` does.
    Aggregate(AggregateArgs),
}

/// `qrm study shard`.
#[derive(Debug, clap::Args)]
pub struct ShardArgs {
    /// The study's config, as `qrm study run` takes it.
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Which shard (0-based); without it, prints how many shards the config has.
    #[arg(long)]
    pub index: Option<usize>,
    /// The shard's JSON file (required with --index).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `qrm study aggregate`.
#[derive(Debug, clap::Args)]
pub struct AggregateArgs {
    /// The study's config, as the shards ran it.
    #[command(flatten)]
    pub config: ConfigArgs,
    /// The shard files.
    #[arg(long = "shard", required = true, num_args = 1..)]
    pub shards: Vec<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// `qrm study run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// The study and its config.
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// A study and its config: the built-in one, a file's fields over it, `--set` over both.
#[derive(Debug, clap::Args)]
pub struct ConfigArgs {
    /// The study (`qrm study list`).
    #[arg(value_parser = study_names())]
    pub name: String,
    /// The quick config (a minute or less) instead of the thesis's.
    #[arg(long)]
    pub quick: bool,
    /// A config file (TOML, as `qrm study config NAME` prints): the fields it has replace the
    /// built-in config's (the full one, or the quick one with --quick).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Change one field of the config: `--set pairs=100`, `--set trial=\"occlusion\"`,
    /// `--set schedule.fallbacks=0` (a TOML value; a bare word is taken as a string).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Seed of the built-in config (a --config file's own seed wins; default: the study's, 0
    /// but for `demo`).
    #[arg(long)]
    pub seed: Option<u64>,
}

/// The registry's names, as the values clap accepts and lists.
fn study_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(studies::STUDIES.iter().map(|s| s.name()))
}

/// Runs a `qrm study` subcommand.
pub fn run(cmd: StudyCmd) -> Result<()> {
    match cmd {
        StudyCmd::List => {
            for s in studies::STUDIES {
                outln!("{:<14} {}", s.name(), s.about())?;
            }
            Ok(())
        }
        StudyCmd::Config { name, full, seed } => {
            let study = studies::find(&name)?;
            let seed = seed.unwrap_or(study.default_seed());
            outln!("{}", to_toml(&study.config(full, seed))?.trim_end())?;
            Ok(())
        }
        StudyCmd::Run(a) => {
            let (study, config) = config_of(&a.config)?;
            run_and_write(study, &config, &a.out, Shown::Tables)
        }
        StudyCmd::Shard(a) => shard(&a),
        StudyCmd::Aggregate(a) => aggregate(&a),
    }
}

fn shard(a: &ShardArgs) -> Result<()> {
    let (study, config) = config_of(&a.config)?;
    let n = study.shards(&config)?;
    let Some(index) = a.index else {
        outln!("{n}")?;
        return Ok(());
    };
    let Some(out) = &a.out else {
        bail!("--index needs --out FILE.json for the shard");
    };
    if index >= n {
        bail!(
            "--index {index}: `{}` has {n} shards (0..{n})",
            study.name()
        );
    }
    let pb = crate::progress::Bar::new(0, &format!("{} shard {index}", study.name()));
    let value = study.run_shard(&config, index, &pb)?;
    pb.finish_and_clear();
    let file = ShardFile {
        config,
        index,
        shard: value,
        study: study.name().to_owned(),
    };
    write_atomic(out, serde_json::to_string(&file)?.as_bytes())?;
    outln!("wrote shard {index} of {n}: {}", out.display())?;
    Ok(())
}

fn aggregate(a: &AggregateArgs) -> Result<()> {
    let (study, config) = config_of(&a.config)?;
    let mut shards = Vec::new();
    for path in &a.shards {
        let text = qsr_core::text_file::read_text(path, qsr_core::text_file::MAX_INPUT_BYTES)
            .with_context(|| format!("reading {}", path.display()))?;
        let file = ShardFile::read(&text, &path.display().to_string(), study.name(), &config)?;
        shards.push((file.index, file.shard));
    }
    let stage = crate::output::stage(&a.out)?;
    let ran = study.aggregate(&config, shards)?;
    qrm_files::write_run(stage.path(), &ran, None)?;
    print_report(&ran.report)?;
    outln!("wrote {}", a.out.display())?;
    stage.commit()?;
    Ok(())
}

/// The study and the config flags ask for (stage two of parsing): the built-in config, the
/// file's fields over it, then each `--set`; checked before any work.
fn config_of(a: &ConfigArgs) -> Result<(&'static dyn AnyStudy, serde_json::Value)> {
    let study = studies::find(&a.name)?;
    let mut config = study.config(!a.quick, a.seed.unwrap_or(study.default_seed()));
    if let Some(path) = &a.config {
        let text = qsr_core::text_file::read_text(path, qsr_core::text_file::MAX_INPUT_BYTES)
            .with_context(|| format!("reading {}", path.display()))?;
        overlay(&mut config, from_toml(&text, &path.display().to_string())?);
    }
    for s in &a.set {
        set_field(&mut config, s).context("--set")?;
    }
    study.check(&config)?;
    Ok((study, config))
}

/// What a run prints on the terminal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shown {
    /// The report's tables and claims (`qrm study run`).
    Tables,
    /// The report's set-up, a few lines telling the run (`qrm demo`).
    Story,
}

/// Runs study `S` with a typed config (what an alias such as `qrm qlink field` builds from its
/// flags) through the same runner as `qrm study run`; the config is checked before anything
/// is created on disk.
pub fn run_study<S: studies::Study>(config: &S::Config, out: &Path) -> Result<()> {
    run_study_shown::<S>(config, out, Shown::Tables)
}

/// [`run_study`], printing what `shown` says.
pub fn run_study_shown<S: studies::Study>(
    config: &S::Config,
    out: &Path,
    shown: Shown,
) -> Result<()> {
    let study = studies::find(S::NAME)?;
    // Checked as typed first: a value JSON cannot hold (a NaN from a flag) is refused by the
    // study's own check, naming the field, rather than as a null in its JSON form.
    S::check(config)?;
    let config = serde_json::to_value(config)?;
    study.check(&config)?;
    run_and_write(study, &config, out, shown)
}

/// Runs `config` with a progress bar and writes everything into `out` (staged: nothing is
/// left half-written on an error or Ctrl-C).
pub fn run_and_write(
    study: &dyn AnyStudy,
    config: &serde_json::Value,
    out: &Path,
    shown: Shown,
) -> Result<()> {
    let stage = crate::output::stage(out)?;
    let pb = crate::progress::Bar::new(0, study.name());
    let t0 = std::time::Instant::now();
    let ran = study.run(config, &pb)?;
    let seconds = t0.elapsed().as_secs_f64();
    pb.finish_and_clear();
    qrm_files::write_run(
        stage.path(),
        &ran,
        Some((seconds, rayon::current_num_threads())),
    )?;
    let threads = rayon::current_num_threads();
    match shown {
        Shown::Tables => {
            outln!("{} in {seconds:.1} s on {threads} threads", study.name())?;
            print_report(&ran.report)?;
            outln!("wrote {}", out.display())?;
        }
        Shown::Story => {
            outln!("{}", ran.report.setup.trim_end())?;
            outln!(
                "Wrote {} in {seconds:.1} s on {threads} threads.",
                out.display()
            )?;
        }
    }
    stage.commit()?;
    Ok(())
}

/// The report's tables and claims on the terminal.
fn print_report(report: &Report) -> Result<()> {
    let text = report.to_terminal();
    if !text.is_empty() {
        outln!("{}", text.trim_end_matches('\n'))?;
    }
    Ok(())
}
