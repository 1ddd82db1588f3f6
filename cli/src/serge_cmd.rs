//! `qrm serge ...`: salient region maps (thesis chapter 3).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde_json::json;
use serge::{BeliefSet, CellMasses, Grid, SalientRegionMap, Serge, SergeParams};
use studies::serge::SergeStudy;
use studies::serge::datasets::{DATASETS, DatasetName};
use studies::serge::learned_calculus::compose_table_json;

use crate::flags::StudyFlags;
use crate::output::{Staging, write_atomic, write_picture};
use qrm_plot::{RegionPicture, region_map};
use serge::learner::CalculusLearner;
use serge::selection::TripletSelection;

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

fn draw_map(stem: &Path, title: &str, map: &SalientRegionMap, points: &[[f64; 2]]) -> Result<()> {
    let picture = region_map(
        title,
        &RegionPicture {
            window: map.grid.window,
            nx: map.grid.nx,
            ny: map.grid.ny,
            cell_region: &map.cell_region,
            points,
            highlight: &[],
            shade: None,
            marks: &[],
            numbers: map.n_regions <= 60,
        },
    )?;
    write_picture(stem, &picture)?;
    Ok(())
}

fn run_map(a: RunArgs) -> Result<()> {
    // stage two: validate everything before any work
    let text = qsr_core::text_file::read_text(&a.beliefs, qsr_core::text_file::MAX_INPUT_BYTES)
        .with_context(|| format!("reading {}", a.beliefs.display()))?;
    let beliefs = BeliefSet::from_json_str(&text, &a.beliefs.display().to_string())?;
    let grid = match &a.window {
        Some(w) => Grid::new(window4(w)?, a.grid, a.grid)?,
        None => Grid::around(&beliefs, a.grid, a.grid)?,
    };
    let mut params = SergeParams::new(a.mu, a.sigma).seed(a.seed);
    if let Some(t) = a.trials {
        params = params.trials(t);
    }
    let start = Instant::now();
    let masses = CellMasses::compute(&beliefs, grid)?;
    let serge = Serge::new(&masses)?;
    let map = serge.run(&params)?;
    let secs = start.elapsed().as_secs_f64();
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let mut doc = map.to_json();
    doc["initial_regions"] = json!(serge.n_initial_regions());
    doc["seconds"] = json!(secs);
    write_atomic(
        &out_dir.join("map.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;
    let means: Vec<[f64; 2]> = beliefs.as_slice().iter().map(serge::Belief::mean).collect();
    draw_map(
        &out_dir.join("map"),
        &format!(
            "SERGE: {} regions (μ = {}, σ = {}), log saliency {:.3}",
            map.n_regions, a.mu, a.sigma, map.log_saliency
        ),
        &map,
        &means,
    )?;
    outln!(
        "{} beliefs, {} initial regions → {} regions; log saliency {:.4}; log φ {:.4}; {} trials in {secs:.2} s; wrote {}",
        beliefs.len(),
        serge.n_initial_regions(),
        map.n_regions,
        map.log_saliency,
        map.log_phi(),
        map.trials,
        a.out.display()
    )?;
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
    let scans = pqrm::loaders::read_csv(&a.input)?.scans;
    let start = Instant::now();
    let (selected, map) = learner
        .learn(&studies::recording::sightings(&scans))
        .with_context(|| format!("learning from {}", a.input.display()))?;
    let (triplets, obs) = (selected.triplets, selected.observations);
    let calc = map.to_calculus(
        &a.name,
        &format!(
            "learned by SERGE from {} triplets of {} (μ = {}, σ = {})",
            triplets.len(),
            a.input.display(),
            a.mu,
            a.sigma
        ),
    )?;
    let table = serge::learn::compose_table(&calc, &|| {})?;
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    write_learned(stage.path(), &a.name, &calc, &table, &map, &triplets, &obs)?;
    outln!(
        "{} triplets, {} observations → `{}` with {} states, compose {} entries, in {:.1} s; wrote {}",
        triplets.len(),
        obs.len(),
        a.name,
        calc.n_states(),
        table.n_entries(),
        start.elapsed().as_secs_f64(),
        a.out.display()
    )?;
    stage.commit()?;
    Ok(())
}

/// The learned calculus's files in `dir`: its spec, Algorithm 3's compose table, the SR map
/// with the triplets it came from, and its picture over the data.
fn write_learned(
    dir: &Path,
    name: &str,
    calc: &qsr_core::Calculus,
    table: &qsr_core::ComposeTable,
    map: &SalientRegionMap,
    triplets: &[[u32; 3]],
    obs: &[serge::learn::TripletObservation],
) -> Result<()> {
    write_atomic(
        &dir.join("calculus.json"),
        calc.spec().to_json_string()?.as_bytes(),
    )?;
    let rows = compose_table_json(calc, table);
    write_atomic(
        &dir.join("compose.json"),
        serde_json::to_string(
            &json!({"states": calc.labels(), "table": rows, "method": "algorithm-3-intervals"}),
        )?
        .as_bytes(),
    )?;
    let mut doc = map.to_json();
    doc["triplets"] = json!(triplets);
    write_atomic(
        &dir.join("map.json"),
        serde_json::to_string(&doc)?.as_bytes(),
    )?;
    let points: Vec<[f64; 2]> = obs
        .iter()
        .filter_map(|o| serge::learn::normalise(o.points[0], o.points[1], o.points[2]))
        .collect();
    draw_map(
        &dir.join("calculus"),
        &format!("learned calculus `{name}`: {} states", calc.n_states()),
        map,
        &points,
    )?;
    Ok(())
}
