//! `qrm pqrm ...` and `qrm map`: thin formatting, plotting and reporting over `pqrm`.

use std::fmt::Write as _;
use std::io::{BufRead, Read, Write};
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use pqrm::loaders::{Dataset, RangeBearingNoise, read_mrclam, read_truth_csv};
use pqrm::study::ObservationQuery;
use pqrm::temper::TemperChoice;
use pqrm::{Orderings, Pqrm, PqrmConfig, evaluate};
use qsr_core::Calculus;
use serde_json::json;
use studies::Study;
use studies::pqrm::monte_carlo::MonteCarlo;
use studies::pqrm::real_data::{NoiseSource, RealData, RealDataConfig};

use crate::args::{
    CalibrateArgs, MapArgs, MapFormatArg, MergeArgs, OrderingsArg, PqrmCmd, RealArgs, StudyArgs,
    TruthDataset,
};
use crate::flags::{InputFormat, NoiseMode};
use crate::output::{Staging, write_atomic, write_picture};
use crate::recording::{load_dataset, resolve_noise};

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

/// What `qrm map` read: the recording, the noise fit, the gated outliers, what the log reader
/// did.
struct MapInput {
    data: Dataset,
    noise_fit: Option<pqrm::calibrate::NoiseFit>,
    gated: Option<pqrm::calibrate::Gated>,
    log_read: Option<qrm_log::Recording>,
}

/// `qrm map`.
pub fn map(a: MapArgs) -> Result<()> {
    let calc = Calculus::resolve(&a.calculus)
        .with_context(|| format!("loading calculus `{}`", a.calculus))?;
    let mut config = PqrmConfig {
        samples: a.samples,
        floor: a.floor,
        // resolved below, once the recording is read (`--orderings auto` depends on it)
        orderings: Orderings::All,
        seed: a.seed,
        sensor: pqrm::sensor::SensorModel::parse(&a.sensor)?,
        temper: 1.0,
    };
    config.validate()?;
    let temper = TemperChoice::parse(&a.temper).context("--temper")?;
    let read = read_for_map(&a)?;
    let data = &read.data;
    // One choice for the whole recording, so that per-robot maps can be merged.
    let possible = crate::args::possible_ordered_sets(&data.scans);
    config.orderings = a.orderings.resolve(possible);
    if a.orderings == OrderingsArg::Auto && config.orderings == Orderings::Canonical {
        eprintln!(
            "note: the recording could give {possible} ordered landmark sets (more than {}); \
             recording one ordering per unordered set, the other five derived on reading \
             (--orderings all to record all six)",
            OrderingsArg::AUTO_CANONICAL_ABOVE
        );
    }
    let extra = read_summary(&read);
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let settings = (config, temper, a.map_format);
    let summary = if a.per_robot {
        let robots: std::collections::BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
        let mut all = serde_json::Map::new();
        for r in robots {
            let dir = out_dir.join(format!("robot{r}"));
            std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
            let one = Dataset {
                scans: data
                    .scans
                    .iter()
                    .filter(|s| s.robot == r)
                    .cloned()
                    .collect(),
                truth: data.truth.clone(),
                skipped: 0,
            };
            let label = format!("mapping robot {r}");
            let s = map_into(&dir, &one, &calc, settings, &extra, &label)?;
            all.insert(format!("robot{r}"), s);
        }
        serde_json::Value::Object(all)
    } else {
        map_into(&out_dir, data, &calc, settings, &extra, "mapping")?
    };
    // Committed before printing: a closed pipe must not lose the result.
    stage.commit()?;
    outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    Ok(())
}

/// The recording `qrm map` maps: read in its form (the loaders' errors name the file and
/// line, or topic, message and field), with its truth, gated, restricted to `--robots`.
fn read_for_map(a: &MapArgs) -> Result<MapInput> {
    let (noise, noise_fit) = if a.format == InputFormat::Mcap {
        (RangeBearingNoise::MRCLAM, None)
    } else {
        resolve_noise(a.format, &a.input, &a.noise)?
    };
    let mut log_read = None;
    let mut data = if a.format == InputFormat::Mcap {
        let mut options = qrm_log::ReadOptions {
            topics: a.topic.clone(),
            range_max: a.range_max,
            allow_truncated: a.allow_truncated,
            ..Default::default()
        };
        options.lidar.sigma = a.lidar_sigma;
        let r = qrm_log::read_mcap(&a.input, &options)?;
        if let Some(d) = &r.damage {
            eprintln!(
                "warning: {} is damaged; read up to its last readable chunk ({d})",
                a.input.display()
            );
        }
        let data = r.dataset.clone();
        log_read = Some(r);
        data
    } else {
        ensure!(
            a.topic.is_empty() && a.range_max.is_none() && !a.allow_truncated,
            "--topic, --range-max and --allow-truncated are for --format mcap"
        );
        load_dataset(a.format, &a.input, noise)?
    };
    if let Some(t) = &a.truth {
        data.truth = Some(read_truth_csv(t)?);
    }
    let mut gated = None;
    if a.gate {
        let fit = match &noise_fit {
            Some(f) => *f,
            None => pqrm::calibrate::fit_noise(&data).context("fitting the noise for --gate")?,
        };
        let (kept, g) = pqrm::calibrate::gate_outliers(&data, &fit, 3.0);
        data.scans = kept.scans;
        gated = Some(g);
    }
    if !a.robots.is_empty() {
        let present: std::collections::BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
        if let Some(r) = a.robots.iter().find(|r| !present.contains(r)) {
            bail!(
                "--robots: robot {r} has no scans in {} (robots present: {present:?})",
                a.input.display()
            );
        }
        data.scans.retain(|s| a.robots.contains(&s.robot));
    }
    Ok(MapInput {
        data,
        noise_fit,
        gated,
        log_read,
    })
}

/// What the reading did, for every summary: the noise fit, the outliers gated, the log's
/// topics and where its landmarks came from.
fn read_summary(read: &MapInput) -> serde_json::Map<String, serde_json::Value> {
    let mut extra = serde_json::Map::new();
    if let Some(fit) = &read.noise_fit {
        extra.insert("noise_fit".into(), json!(fit));
    }
    if let Some(g) = &read.gated {
        extra.insert("gated".into(), json!(g));
    }
    if let Some(r) = &read.log_read {
        let used: Vec<_> = r
            .topics
            .iter()
            .filter(|t| t.used)
            .map(|t| json!({"topic": t.topic, "schema": t.schema, "messages": t.messages, "robot": t.robot}))
            .collect();
        extra.insert("topics".into(), json!(used));
        extra.insert(
            "landmarks_from".into(),
            json!(if r.from_scans {
                "lidar scans (extracted, recognised by triangles)"
            } else {
                "detections"
            }),
        );
        extra.insert("damage".into(), json!(r.damage));
    }
    extra
}

/// The config to map `data` with: a fixed τ as given, or `auto` chosen from the data
/// (`pqrm::temper`), with the evidence.
fn resolve_temper(
    data: &Dataset,
    calc: &Calculus,
    config: PqrmConfig,
    temper: TemperChoice,
    label: &str,
) -> Result<(PqrmConfig, Option<pqrm::temper::TemperFit>)> {
    match temper {
        TemperChoice::Fixed(temper) => Ok((PqrmConfig { temper, ..config }, None)),
        TemperChoice::Auto => {
            let pb =
                crate::progress::bar(2 * data.scans.len() as u64, &format!("{label}: choosing τ"));
            let mut fits = pqrm::temper::fit_temper(
                std::slice::from_ref(calc),
                &data.scans,
                config,
                &pqrm::temper::TemperOptions::default(),
                &|| pb.inc(1),
            )
            .context("choosing the tempering exponent (--temper auto)")?;
            pb.finish_and_clear();
            let fit = fits.remove(0);
            eprintln!(
                "{label}: τ = {:.3} chosen from held-out frames (log score {:.4} vs {:.4} at τ = 1)",
                fit.chosen,
                fit.chosen_score(),
                fit.untempered_score().unwrap_or(f64::NAN)
            );
            Ok((
                PqrmConfig {
                    temper: fit.chosen,
                    ..config
                },
                Some(fit),
            ))
        }
    }
}

/// Maps `data` into `dir`: `map.json` (or `map.pqrm`) and `summary.json` (scored when the
/// data has a truth).
fn map_into(
    dir: &Path,
    data: &Dataset,
    calc: &Calculus,
    (config, temper, map_format): (PqrmConfig, TemperChoice, MapFormatArg),
    extra: &serde_json::Map<String, serde_json::Value>,
    label: &str,
) -> Result<serde_json::Value> {
    let (config, temper_fit) = resolve_temper(data, calc, config, temper, label)?;
    let mut map = Pqrm::new(calc.clone(), config)?;
    let start = Instant::now();
    let pb = crate::progress::bar(data.scans.len() as u64, label);
    for scan in &data.scans {
        map.update(scan)?;
        pb.inc(1);
    }
    pb.finish_and_clear();
    let map_format = map_format.resolve(map.len());
    let map_file = format!("map.{}", map_format.extension());
    let saving = Instant::now();
    map.save_as(&dir.join(&map_file), map_format)?;
    let save_seconds = saving.elapsed().as_secs_f64();
    let robots: std::collections::BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
    let mut summary = json!({
        "calculus": map.calculus().name(),
        "n_scans": data.scans.len(),
        "robots": robots,
        "floor": config.floor,
        "sensor": config.sensor,
        "temper": config.temper,
        "samples": config.samples,
        "orderings": config.orderings,
        "skipped_measurements": data.skipped,
        "n_sets": map.len(),
        "map_file": map_file,
        "map_bytes_in_memory": map.heap_bytes(),
        "save_seconds": save_seconds,
        "mean_entropy": map.mean_entropy(),
        "seconds": start.elapsed().as_secs_f64(),
    });
    let obj = summary.as_object_mut().context("summary is an object")?;
    if let Some(fit) = &temper_fit {
        obj.insert("temper_fit".into(), json!(fit));
    }
    for (k, v) in extra {
        obj.insert(k.clone(), v.clone());
    }
    if let Some(truth) = &data.truth
        && !map.is_empty()
    {
        score_into(obj, &evaluate(&map, truth)?);
    }
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(summary)
}

fn score_into(obj: &mut serde_json::Map<String, serde_json::Value>, m: &pqrm::MapMetrics) {
    obj.insert("n_scored".into(), json!(m.n_scored));
    obj.insert("error_rate".into(), json!(m.error_rate));
    obj.insert(
        "mean_neighbor_distance".into(),
        json!(m.mean_neighbor_distance),
    );
    obj.insert("p_ml_mean".into(), json!(m.p_ml_mean));
    obj.insert("top_n_error".into(), json!(m.top_n_error));
    obj.insert("normalized_entropy".into(), json!(m.normalized_entropy));
}

/// `qrm pqrm calibrate`.
fn calibrate(a: CalibrateArgs) -> Result<()> {
    let data = load_dataset(a.format, &a.input, RangeBearingNoise::MRCLAM)?;
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
        score_into(obj, &evaluate(&merged, truth)?);
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
    let mut config = if a.quick {
        MonteCarlo::quick(a.seed)
    } else {
        MonteCarlo::full(a.seed)
    };
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
    crate::study_cmd::run_study::<MonteCarlo>(&config, &a.out)
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
