//! `qrm serge ...`: salient region maps (thesis chapter 3).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use serge::learner::CalculusLearner;
use serge::selection::TripletSelection;
use serge::{BeliefSet, SergeParams};
use studies::serge::SergeStudy;
use studies::serge::calculus_learning::LearnedFromRecording;
use studies::serge::datasets::{DATASETS, DatasetName};
use studies::serge::region_map::RegionMapJob;

use crate::flags::StudyFlags;

/// `qrm serge ...`.
#[derive(Debug, clap::Subcommand)]
pub enum SergeCmd {
    /// Build a salient region map from your own beliefs (JSON) and draw it.
    Run(RunArgs),
    /// The 5-fold cross-validation study of thesis §3.4 (Figs 3.7–3.10) with a report
    /// (`--quick`: 60×60 grid, 5 μ, 3 σ, T = 5·K, 2,000 samples; under a minute).
    Study(StudyArgs),
    /// Learn a calculus from observed landmark triplets (an observation CSV, as `qrm sim`
    /// writes): SERGE in the normalised frame, the calculus spec, its compose table.
    Learn(LearnArgs),
}

/// `qrm serge run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Beliefs: `{"beliefs": [{"mean": [x, y], "cov": [[a, b], [b, c]]}, {"samples": [[x, y], ...]}]}`.
    #[arg(long)]
    pub beliefs: PathBuf,
    /// Desired number of regions μ (1..=K).
    #[arg(long)]
    pub mu: usize,
    /// Tolerance σ ≥ 0 (0: exactly μ regions).
    #[arg(long, default_value_t = 2.0)]
    pub sigma: f64,
    /// Trials (default 100·K).
    #[arg(long)]
    pub trials: Option<usize>,
    /// Grid cells per side.
    #[arg(long, default_value_t = 200)]
    pub grid: usize,
    /// Grid window `x0,x1,y0,y1` (default: around the beliefs); negative values work as
    /// `--window -10,10,-5,5`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub window: Option<Vec<f64>>,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory (map.json, map.svg, map.png).
    #[arg(long)]
    pub out: PathBuf,
}

/// `qrm serge study`.
#[derive(Debug, clap::Args)]
pub struct StudyArgs {
    /// A dataset, or all of them.
    #[arg(long, default_value = "all",
          value_parser = clap::builder::PossibleValuesParser::new(DATASETS.iter().copied().chain(["all"])))]
    pub dataset: String,
    /// --quick, --seed, --out.
    #[command(flatten)]
    pub run: StudyFlags,
}

/// `qrm serge learn`.
#[derive(Debug, clap::Args)]
pub struct LearnArgs {
    /// Observation CSV `t,robot,landmark,x,y,cxx,cxy,cyy` (robot frame).
    #[arg(long)]
    pub input: PathBuf,
    /// Desired number of states μ.
    #[arg(long)]
    pub mu: usize,
    /// Tolerance σ.
    #[arg(long, default_value_t = 2.0)]
    pub sigma: f64,
    /// Use at most this many landmark triplets (drawn with the seed, each in a random
    /// ordering: which landmark is located and which two make the frame).
    #[arg(long, default_value_t = 60)]
    pub max_triplets: usize,
    /// A landmark set needs this many frames with all three landmarks.
    #[arg(long, default_value_t = 5)]
    pub min_frames: usize,
    /// Samples per triplet belief.
    #[arg(long, default_value_t = 2000)]
    pub samples: usize,
    /// Grid cells per side over the normalised window.
    #[arg(long, default_value_t = 64)]
    pub grid: usize,
    /// Normalised window `x0,x1,y0,y1`.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_values_t = [-3.0, 3.0, -2.5, 3.5]
    )]
    pub window: Vec<f64>,
    /// Trials (default 100·K).
    #[arg(long)]
    pub trials: Option<usize>,
    /// Name of the learned calculus.
    #[arg(long, default_value = "learned")]
    pub name: String,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs a `qrm serge` subcommand.
pub fn run(cmd: SergeCmd) -> Result<()> {
    match cmd {
        SergeCmd::Run(a) => run_map(a),
        SergeCmd::Study(a) => study(a),
        SergeCmd::Learn(a) => learn(a),
    }
}

fn window4(v: &[f64]) -> Result<[f64; 4]> {
    match v {
        [a, b, c, d] => Ok([*a, *b, *c, *d]),
        _ => bail!("a window is four numbers x0,x1,y0,y1"),
    }
}

fn run_map(a: RunArgs) -> Result<()> {
    // stage two: validate everything before any work
    let text = qsr_core::text_file::read_text(&a.beliefs, qsr_core::text_file::MAX_INPUT_BYTES)
        .with_context(|| format!("reading {}", a.beliefs.display()))?;
    let mut params = SergeParams::new(a.mu, a.sigma).seed(a.seed);
    if let Some(t) = a.trials {
        params = params.trials(t);
    }
    let job = RegionMapJob {
        beliefs: BeliefSet::from_json_str(&text, &a.beliefs.display().to_string())?,
        window: a.window.as_deref().map(window4).transpose()?,
        cells: a.grid,
        params,
    };
    let run = job.run()?;
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = crate::output::stage(&a.out)?;
    qrm_files::write_products(stage.path(), &run.products())?;
    outln!("{}; wrote {}", run.describe(), a.out.display())?;
    stage.commit()?;
    Ok(())
}

// ---------------------------------------------------------------------------------------
// the study: `qrm study run serge-cv` with its common options as flags

fn study(a: StudyArgs) -> Result<()> {
    let mut config = a.run.config::<SergeStudy>();
    if a.dataset != "all" {
        config.datasets = vec![DatasetName::parse(&a.dataset)?];
    }
    crate::study_cmd::run_study::<SergeStudy>(&config, &a.run.out)
}

// ---------------------------------------------------------------------------------------
// learning a calculus from observations

fn learn(a: LearnArgs) -> Result<()> {
    let learner = CalculusLearner {
        selection: TripletSelection {
            min_frames: a.min_frames,
            max_triplets: a.max_triplets,
            seed: a.seed,
        },
        samples: a.samples,
        window: window4(&a.window)?,
        cells: a.grid,
        mu: a.mu,
        sigma: a.sigma,
        trials: a.trials,
    };
    let learned = LearnedFromRecording::learn(&learner, &a.input, &a.name)?;
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = crate::output::stage(&a.out)?;
    qrm_files::write_products(stage.path(), &learned.products()?)?;
    outln!("{}; wrote {}", learned.describe(), a.out.display())?;
    stage.commit()?;
    Ok(())
}
