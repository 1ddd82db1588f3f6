//! `qrm pqrm ...` and `qrm map`: thin formatting, plotting and reporting over `pqrm`.

use std::fmt::Write as _;
use std::io::{BufRead, Read, Write};
use std::path::Path;

use anyhow::{Context, Result, ensure};
use pqrm::loaders::{RangeBearingNoise, read_mrclam, read_truth_csv};
use pqrm::study::ObservationQuery;
use pqrm::temper::TemperChoice;
use pqrm::{Orderings, Pqrm, PqrmConfig, evaluate};
use qsr_core::Calculus;
use serde_json::json;
use studies::mapping::{MapJob, OrderingsChoice};
use studies::pqrm::monte_carlo::MonteCarlo;
use studies::pqrm::real_data::{NoiseSource, RealData, RealDataConfig};

use crate::args::{
    CalibrateArgs, MapArgs, MergeArgs, OrderingsArg, PqrmCmd, RealArgs, StudyArgs, TruthDataset,
};
use crate::flags::{InputFormat, NoiseMode};
use crate::output::{Staging, write_atomic, write_picture};

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
    ensure!(
        floor.is_finite() && floor >= 0.0,
        "--floor must be finite and >= 0"
    );
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
    let stage = Staging::new(&a.out)?;
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
    let mut log = qrm_log::ReadOptions {
        topics: a.topic.clone(),
        range_max: a.range_max,
        allow_truncated: a.allow_truncated,
        ..Default::default()
    };
    log.lidar.sigma = a.lidar_sigma;
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
    let data = studies::recording::read(a.format.into(), &a.input, RangeBearingNoise::MRCLAM)?;
    let fit = pqrm::calibrate::fit_noise(&data)
        .with_context(|| format!("fitting the noise of {}", a.input.display()))?;
    let z: Vec<f64> = pqrm::calibrate::residuals(&data, &fit)
        .iter()
        .filter(|r| r.sigma > 0.0)
        .map(|r| (r.residual / r.sigma).clamp(-8.0, 8.0))
        .collect();
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let summary = json!({
        "input": a.input.display().to_string(),
        "format": a.format.as_str(),
        "fit": fit,
        "method": "spread of the distance between landmarks seen in one frame about its median over frames; IRLS on |z| <= 3; outlier rate = share beyond 3 sigma minus 0.27 %",
        // Only a range-bearing format takes the fitted σs; the others carry their own
        // covariances, which this fit is a check of.
        "use": if a.format == InputFormat::Mrclam {
            format!("qrm map --format mrclam --input {} --noise auto  (or --sigma-range {:.4} --sigma-bearing {:.5}; heavy tails: --sensor outliers:{:.3},{:.0})",
                a.input.display(), fit.sigma_range, fit.sigma_bearing, fit.outlier_rate, fit.max_range.ceil())
        } else {
            format!("{} files carry their own covariances: compare them with this fit; for heavy tails: qrm map --sensor outliers:{:.3},{:.0}",
                a.format.as_str(), fit.outlier_rate, fit.max_range.ceil())
        },
    });
    write_atomic(
        &out_dir.join("calibration.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let edges: Vec<f64> = (0..=32).map(|i| -8.0 + 0.5 * f64::from(i)).collect();
    write_picture(
        &out_dir.join("residuals"),
        &qrm_plot::histogram(
            &format!(
                "residual / fitted σ (N(0,1) if the model is right; {:.1} % beyond ±3)",
                100.0 * z.iter().filter(|v| v.abs() > 3.0).count() as f64 / z.len().max(1) as f64
            ),
            "normalised residual of a pairwise distance (clamped to ±8)",
            &edges,
            &[("residuals".to_owned(), z)],
        )?,
    )?;
    // Committed before printing: a closed pipe must not lose the result.
    stage.commit()?;
    outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    Ok(())
}

/// `qrm pqrm merge`.
fn merge(a: MergeArgs) -> Result<()> {
    let maps = a
        .maps
        .iter()
        .map(|p| Pqrm::load(p).with_context(|| format!("loading the map {}", p.display())))
        .collect::<Result<Vec<_>>>()?;
    let truth = match &a.truth {
        Some(t) if t.is_dir() => Some(
            read_mrclam(t, RangeBearingNoise::MRCLAM)?
                .truth
                .with_context(|| format!("{} has no surveyed landmarks", t.display()))?,
        ),
        Some(t) => Some(read_truth_csv(t)?),
        None => None,
    };
    let merged =
        pqrm::robots::merge_maps(&maps).with_context(|| format!("merging {} maps", maps.len()))?;
    let mut summary = json!({
        "calculus": merged.calculus().name(),
        "maps": a.maps.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "sets_per_map": maps.iter().map(Pqrm::len).collect::<Vec<_>>(),
        "n_sets": merged.len(),
        "mean_entropy": merged.mean_entropy(),
    });
    if let Some(truth) = &truth
        && !merged.is_empty()
    {
        let obj = summary.as_object_mut().context("summary is an object")?;
        studies::mapping::score_into(obj, &evaluate(&merged, truth)?);
    }
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
    if let Some(input) = a.input {
        config.input = input;
    }
    config.samples = a.samples;
    config.max_frames = a.max_frames;
    config.gate_sigmas = a.gate.then_some(RealDataConfig::GATE_SIGMAS);
    config.sensor = pqrm::sensor::SensorModel::parse(&a.sensor).context("--sensor")?;
    config.temper = TemperChoice::parse(&a.temper).context("--temper")?;
    let given = a.noise.sigma_range.is_some() || a.noise.sigma_bearing.is_some();
    config.noise = match a.noise.mode {
        Some(NoiseMode::Auto) => {
            ensure!(
                !given,
                "--noise auto fits σ_r and σ_b; drop --sigma-range/--sigma-bearing or say --noise fixed"
            );
            NoiseSource::Fitted
        }
        Some(NoiseMode::Fixed) => NoiseSource::Given,
        None if given => NoiseSource::Given,
        None => NoiseSource::Fitted,
    };
    if let Some(s) = a.noise.sigma_range {
        config.sigma_range = s;
    }
    if let Some(s) = a.noise.sigma_bearing {
        config.sigma_bearing = s;
    }
    crate::study_cmd::run_study::<RealData>(&config, &a.out)
}
