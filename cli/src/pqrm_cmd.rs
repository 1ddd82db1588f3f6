//! `qrm pqrm ...` and `qrm map`: thin formatting, plotting and reporting over `pqrm`.

use std::fmt::Write as _;
use std::io::{BufRead, Read, Write};
use std::path::Path;

use anyhow::{Context, Result, ensure};
use pqrm::study::ObservationQuery;
use pqrm::temper::TemperChoice;
use pqrm::{Orderings, PqrmConfig};
use qsr_core::Calculus;
use serde_json::json;
use studies::calibration::Calibration;
use studies::mapping::{MapJob, OrderingsChoice};
use studies::pqrm::monte_carlo::MonteCarlo;
use studies::pqrm::real_data::{RealData, RealDataConfig};

use crate::args::{
    CalibrateArgs, MapArgs, MergeArgs, OrderingsArg, PqrmCmd, RealArgs, StudyArgs, TruthDataset,
};
use crate::output::write_atomic;

/// Runs one `pqrm` subcommand.
pub fn run(cmd: PqrmCmd) -> Result<()> {
    match cmd {
        PqrmCmd::Prob {
            calculus,
            samples,
            seed,
            floor,
        } => prob(&calculus, samples, seed, floor),
        PqrmCmd::Study(a) => study(a),
        PqrmCmd::Real(a) => real(a),
        PqrmCmd::Merge(a) => merge(a),
        PqrmCmd::Calibrate(a) => calibrate(a),
    }
}

fn prob(calculus: &str, samples: usize, seed: u64, floor: f64) -> Result<()> {
    let calc =
        Calculus::resolve(calculus).with_context(|| format!("loading calculus `{calculus}`"))?;
    ensure!(samples >= 1, "--samples must be >= 1");
    // The map's own bound (issue 39: `--floor 1e308` printed probabilities that were all 0).
    pqrm::config::check_floor(floor).context("--floor")?;
    let mut out = String::new();
    // Capped like every input file: an endless line (`< /dev/zero`) ends instead of growing.
    let capped = std::io::stdin()
        .lock()
        .take(qsr_core::text_file::MAX_INPUT_BYTES);
    for (i, line) in capped.lines().enumerate() {
        let lineno = i + 1;
        let line = line.with_context(|| format!("reading stdin line {lineno}"))?;
        if line.trim().is_empty() {
            continue;
        }
        let query = ObservationQuery::from_json(&line, Path::new("stdin"), lineno)?;
        let probs = query
            .probabilities(&calc, samples, floor, seed)
            .with_context(|| format!("stdin line {lineno}"))?;
        writeln!(out, "{}", json!({"states": calc.labels(), "p": probs}))?;
    }
    std::io::stdout().lock().write_all(out.as_bytes())?;
    Ok(())
}

/// `qrm map`: the flags become a `studies::mapping::MapJob` (stage two), which reads, maps
/// and scores; here the progress, the files and the summary on stdout.
pub fn map(a: MapArgs) -> Result<()> {
    let job = map_job(&a)?;
    let warn = |w: String| eprintln!("warning: {w}");
    let input = job.read(&warn)?;
    if a.orderings == OrderingsArg::Auto && input.orderings == Orderings::Canonical {
        eprintln!(
            "note: the recording could give {} ordered landmark sets (more than {}); \
             recording one ordering per unordered set, the other five derived on reading \
             (--orderings all to record all six)",
            input.possible_sets,
            OrderingsChoice::AUTO_CANONICAL_ABOVE
        );
    }
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = crate::output::stage(&a.out)?;
    let summary = if a.per_robot {
        let mut all = serde_json::Map::new();
        for r in input.robots() {
            let dir = stage.path().join(format!("robot{r}"));
            let one = input.of_robot(r);
            let s = map_into(&dir, &job, &input, &one, &format!("mapping robot {r}"))?;
            all.insert(format!("robot{r}"), s);
        }
        serde_json::Value::Object(all)
    } else {
        map_into(stage.path(), &job, &input, &input.data, "mapping")?
    };
    // Committed before printing: a closed pipe must not lose the result.
    stage.commit()?;
    outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    Ok(())
}

/// Stage two of `qrm map`'s parsing: the job, every value checked before work.
fn map_job(a: &MapArgs) -> Result<MapJob> {
    let calculus = Calculus::resolve(&a.calculus)
        .with_context(|| format!("loading calculus `{}`", a.calculus))?;
    let config = PqrmConfig {
        samples: a.samples,
        floor: a.floor,
        // resolved once the recording is read (`--orderings auto` depends on it)
        orderings: Orderings::All,
        seed: a.seed,
        sensor: pqrm::sensor::SensorModel::parse(&a.sensor)?,
        temper: 1.0,
    };
    config.validate()?;
    a.noise.request().validate()?;
    let mut log = qrm_log::ReadOptions {
        topics: a.topic.clone(),
        range_max: a.range_max,
        allow_truncated: a.allow_truncated,
        ..Default::default()
    };
    log.lidar.sigma = a.lidar_sigma;
    if a.min_points == 0 || a.min_points > 10_000 {
        anyhow::bail!("--min-points {}: must be in 1..=10000", a.min_points);
    }
    if !(a.landmark_radius.is_finite() && a.landmark_radius > 0.0 && a.landmark_radius <= 100.0) {
        anyhow::bail!(
            "--landmark-radius {:?}: must be a positive number of metres, at most 100",
            a.landmark_radius
        );
    }
    log.lidar.extractor.min_points = a.min_points;
    log.lidar.extractor.max_points = log.lidar.extractor.max_points.max(a.min_points);
    log.lidar.extractor.max_radius = a.landmark_radius;
    Ok(MapJob {
        format: a.format.into(),
        input: a.input.clone(),
        truth: a.truth.clone(),
        noise: a.noise.request(),
        log,
        gate: a.gate,
        robots: a.robots.clone(),
        calculus,
        config,
        orderings: a.orderings.into(),
        temper: TemperChoice::parse(&a.temper).context("--temper")?,
        evidence: studies::mapping::EvidenceRequest::parse(&a.evidence).context("--evidence")?,
        map_format: a.map_format.into(),
    })
}

/// Maps `data` into `dir`: `map.json` (or `map.pqrm`) and `summary.json` (scored when the
/// data has a truth).
fn map_into(
    dir: &Path,
    job: &MapJob,
    input: &studies::mapping::MapInput,
    data: &pqrm::loaders::Dataset,
    label: &str,
) -> Result<serde_json::Value> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let pb = crate::progress::Bar::new(0, label);
    let mut mapped = job.map(input, data, &pb)?;
    pb.finish_and_clear();
    if let Some(why) = &mapped.fell_back {
        eprintln!("warning: {label}: {why}");
    }
    if let Some(fit) = &mapped.temper_fit {
        eprintln!(
            "{label}: τ = {:.3} chosen from held-out frames (log score {:.4} vs {:.4} at τ = 1)",
            fit.chosen,
            fit.chosen_score(),
            fit.untempered_score().unwrap_or(f64::NAN)
        );
    }
    mapped.save(dir)?;
    let summary = serde_json::Value::Object(mapped.summary);
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(summary)
}

/// `qrm pqrm calibrate`.
fn calibrate(a: CalibrateArgs) -> Result<()> {
    let calibration = Calibration::of_recording(a.format.into(), &a.input)?;
    let stage = crate::output::stage(&a.out)?;
    qrm_files::write_products(stage.path(), &calibration.products())?;
    // Committed before printing: a closed pipe must not lose the result.
    stage.commit()?;
    outln!("{}", serde_json::to_string_pretty(&calibration.summary())?)?;
    Ok(())
}

/// `qrm pqrm merge`.
fn merge(a: MergeArgs) -> Result<()> {
    let (merged, summary) = studies::mapping::merge_saved(&a.maps, a.truth.as_deref())
        .with_context(|| format!("merging {} maps", a.maps.len()))?;
    // binary for a `.pqrm` path, JSON otherwise; atomic either way
    merged
        .save(&a.out)
        .with_context(|| format!("writing {}", a.out.display()))?;
    outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    Ok(())
}

fn study(a: StudyArgs) -> Result<()> {
    // stage two: the flags become the `monte-carlo` study's config, run by `qrm study`'s runner
    let mut config = a.run.config::<MonteCarlo>();
    if let Some(c) = a.calculi {
        config.calculi = c;
    }
    if let Some(t) = a.trials {
        config.trials = t;
    }
    if let Some(s) = a.samples {
        config.samples = s;
    }
    if let Some(s) = a.sigmas {
        config.sigmas = s;
    }
    if let Some(l) = a.landmarks {
        config.landmarks = l;
    }
    crate::study_cmd::run_study::<MonteCarlo>(&config, &a.run.out)
}

fn real(a: RealArgs) -> Result<()> {
    // stage two: the flags become the `real-data` study's config, run by `qrm study`'s runner.
    // `--dataset` has one value today (clap refuses others): MRCLAM, whose landmarks are
    // surveyed.
    let TruthDataset::Mrclam = a.dataset;
    let mut config = RealDataConfig::full(a.seed);
    let mut inputs = a.input.into_iter();
    if let Some(input) = inputs.next() {
        config.input = input;
    }
    config.also = inputs.collect();
    config.evidence = pqrm::EvidenceModel::parse(&a.evidence).context("--evidence")?;
    config.samples = a.samples;
    config.max_frames = a.max_frames;
    config.gate_sigmas = a.gate.then_some(RealDataConfig::GATE_SIGMAS);
    config.sensor = pqrm::sensor::SensorModel::parse(&a.sensor).context("--sensor")?;
    config.temper = TemperChoice::parse(&a.temper).context("--temper")?;
    config.request_noise(&a.noise.request())?;
    crate::study_cmd::run_study::<RealData>(&config, &a.out)
}
