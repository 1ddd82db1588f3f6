//! A user's recording mapped: the `qrm map` job as a library. The recording is read in its
//! form (noise given or fitted, a log's topics, outliers gated, robots chosen), mapped by
//! PQRM with one calculus — τ fixed or chosen from the recording — and scored when it has
//! surveyed truth. A front end only parses flags into a [`MapJob`], shows progress and writes
//! [`Mapped::summary`] beside the map [`Mapped::save`] wrote.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use pqrm::layout::Layout;
use pqrm::loaders::{Dataset, read_truth_csv};
use pqrm::map_file::MapFormat;
use pqrm::temper::{TemperChoice, TemperFit, TemperOptions, fit_temper};
use pqrm::{Orderings, Pqrm, PqrmConfig, evaluate};
use qsr_core::Calculus;
use qsr_core::progress::Progress;
use serde_json::{Map, Value, json};

use crate::error::{Result, StudyError};
use crate::recording::{NoiseRequest, RecordingFormat};

/// Which orderings of a landmark set a map records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OrderingsChoice {
    /// All six up to [`OrderingsChoice::AUTO_CANONICAL_ABOVE`] possible ordered sets,
    /// canonical beyond.
    Auto,
    /// All six orderings of every set (what the thesis reports).
    All,
    /// One ordering per unordered set, the other five derived on reading.
    Canonical,
}

impl OrderingsChoice {
    /// Above this many possible ordered sets `auto` records canonical orderings: the six
    /// orderings of a 65-landmark scan are 262,080 sets (~30 MB and ~2 s per five scans); a
    /// map of that size is a large map, and a sixth of it serves the same queries.
    pub const AUTO_CANONICAL_ABOVE: u64 = 250_000;

    /// The orderings for a recording that could give `possible` ordered sets
    /// ([`possible_ordered_sets`]).
    #[must_use]
    pub fn resolve(self, possible: u64) -> Orderings {
        match self {
            Self::All => Orderings::All,
            Self::Canonical => Orderings::Canonical,
            Self::Auto if possible > Self::AUTO_CANONICAL_ABOVE => Orderings::Canonical,
            Self::Auto => Orderings::All,
        }
    }
}

/// The file a map is saved as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFormatChoice {
    /// JSON up to [`MapFormatChoice::AUTO_BINARY_ABOVE`] sets, binary beyond.
    Auto,
    /// Versioned JSON (`map.json`).
    Json,
    /// The binary map format (`map.pqrm`, [`pqrm::map_file`]).
    Binary,
}

impl MapFormatChoice {
    /// Above this many sets `auto` writes binary: a JSON map of 100,000 EDC sets is ~30 MB.
    pub const AUTO_BINARY_ABOVE: usize = 100_000;

    /// The format for a map of `n_sets` sets.
    #[must_use]
    pub fn resolve(self, n_sets: usize) -> MapFormat {
        match self {
            Self::Json => MapFormat::Json,
            Self::Binary => MapFormat::Binary,
            Self::Auto if n_sets > Self::AUTO_BINARY_ABOVE => MapFormat::Binary,
            Self::Auto => MapFormat::Json,
        }
    }
}

/// Says what a user should know before mapping: no scan with three landmarks (the map will be
/// empty), or far more landmark ids than any scan sees (a recogniser splitting landmarks), with
/// the likely cause (issue 40: a 360-beam lidar gave an empty map with exit 0 and no word).
fn warn_if_unmappable(scans: &[pqrm::Scan], warn: &dyn Fn(String)) {
    let most = scans
        .iter()
        .map(|s| s.observations.len())
        .max()
        .unwrap_or(0);
    let ids: BTreeSet<u32> = scans
        .iter()
        .flat_map(|s| s.observations.iter().map(|o| o.id.0))
        .collect();
    if most < 3 {
        warn(format!(
            "{} scans with landmarks, none with three (at most {most}): the map will have no \
             sets. From a lidar: its landmarks may be too thin or too far for its resolution \
             (a pole needs three returns; --min-points, --landmark-radius), or --range-max \
             cuts them off",
            scans.iter().filter(|s| !s.observations.is_empty()).count()
        ));
    } else if ids.len() > 50 && ids.len() > 10 * most {
        warn(format!(
            "{} landmark ids, but no scan sees more than {most}: landmarks are probably being \
             split into many ids (from a lidar: recognition losing them between scans; a \
             landmark too thin for the scanner, or clutter taken for landmarks)",
            ids.len()
        ));
    }
}

/// An upper bound on the ordered sets a map of `scans` can hold: the smaller of
/// `n(n−1)(n−2)` over the `n` distinct landmarks and the sum of `m(m−1)(m−2)` over the
/// scans (`m` landmarks each). Saturates instead of overflowing.
#[must_use]
pub fn possible_ordered_sets(scans: &[pqrm::Scan]) -> u64 {
    let ordered = |m: u64| {
        m.saturating_mul(m.saturating_sub(1))
            .saturating_mul(m.saturating_sub(2))
    };
    let distinct: BTreeSet<u32> = scans
        .iter()
        .flat_map(|s| s.observations.iter().map(|o| o.id.0))
        .collect();
    let per_scan = scans
        .iter()
        .map(|s| ordered(s.observations.len() as u64))
        .fold(0u64, u64::saturating_add);
    ordered(distinct.len() as u64).min(per_scan)
}

/// Drops gross outliers frame by frame (3σ of the noise fit; [`pqrm::calibrate::gate_outliers`])
/// when `gate` asks for it — by default (`None`) where the noise was fitted from the recording
/// (`fit`: MRCLAM's `--noise auto`), which leaving one MRCLAM recording out chose in every fold
/// (docs/calibration.md). One rule for `qrm map` and `qrm convert`, so a converted log maps as
/// the recording does. Returns what was dropped, `None` when not gated.
///
/// # Errors
/// [`StudyError::InvalidParameter`] when gating was asked for and the noise cannot be fitted.
pub fn gate(
    data: &mut Dataset,
    gate: Option<bool>,
    fit: Option<&pqrm::calibrate::NoiseFit>,
) -> Result<Option<pqrm::calibrate::Gated>> {
    if !gate.unwrap_or(fit.is_some()) {
        return Ok(None);
    }
    let fitted;
    let fit = match fit {
        Some(f) => f,
        None => {
            fitted = pqrm::calibrate::fit_noise(data).map_err(|e| {
                StudyError::InvalidParameter(format!("fitting the noise for --gate: {e}"))
            })?;
            &fitted
        }
    };
    let (kept, gated) = pqrm::calibrate::gate_outliers(data, fit, 3.0);
    data.scans = kept.scans;
    Ok(Some(gated))
}

/// What to map and how (stage two of a front end's parsing: every field checked or checkable
/// before work).
#[derive(Debug, Clone)]
pub struct MapJob {
    /// The recording's form.
    pub format: RecordingFormat,
    /// Its file or folder.
    pub input: PathBuf,
    /// A `landmark,x,y` CSV to score against (MRCLAM brings its own).
    pub truth: Option<PathBuf>,
    /// The range-bearing noise (MRCLAM).
    pub noise: NoiseRequest,
    /// How an MCAP log is read (topics, ranges, lidar extraction, damage).
    pub log: qrm_log::ReadOptions,
    /// Drop gross outliers frame by frame (3σ of the fitted noise). `None`: where the noise is
    /// fitted from the recording (MRCLAM's `--noise auto`, the default there) — leaving one
    /// MRCLAM recording out chose it in every fold (docs/calibration.md) — and not elsewhere.
    pub gate: Option<bool>,
    /// Only these robots' scans (empty: all).
    pub robots: Vec<u32>,
    /// The calculus.
    pub calculus: Calculus,
    /// The filter's settings; its orderings and τ are resolved by
    /// [`MapJob::orderings`] and [`MapJob::temper`] once the recording is read.
    pub config: PqrmConfig,
    /// Which orderings to record.
    pub orderings: OrderingsChoice,
    /// τ, or `auto`.
    pub temper: TemperChoice,
    /// How a set's frames combine into its belief: a model, or one the recording chooses.
    pub evidence: EvidenceRequest,
    /// The map file's format.
    pub map_format: MapFormatChoice,
}

/// What `--evidence` asks for: a model as given, or one chosen from the recording (the
/// summary's `evidence_choice` then says which and why).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EvidenceRequest {
    /// This model.
    Model(pqrm::EvidenceModel),
    /// `auto`, `qrm map`'s default: the layout map where the frames agree on one layout
    /// ([`layout_agrees`]) and τ = 1, else the filter under `shared:4`.
    Auto,
    /// `shared:auto`: the filter, read with the `N` the whole recording's layout measures
    /// ([`pqrm::layout::SharedError::frames`], `σ_frame² / σ_shared²`; the same for every
    /// robot's map of it, so they merge), or `shared:4` where the layout cannot say.
    SharedMeasured,
}

impl EvidenceRequest {
    /// Parses `auto`, `shared:auto` or a model ([`pqrm::EvidenceModel::parse`]).
    ///
    /// # Errors
    /// The model's, naming what is accepted.
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim();
        if t.eq_ignore_ascii_case("auto") {
            Ok(Self::Auto)
        } else if t.eq_ignore_ascii_case("shared:auto") {
            Ok(Self::SharedMeasured)
        } else {
            pqrm::EvidenceModel::parse(t).map(Self::Model).map_err(|e| {
                StudyError::InvalidParameter(format!(
                    "{e} — or `auto` (the default: the layout where the frames agree on one) or \
                     `shared:auto` (the filter with the N the recording's layout measures)"
                ))
            })
        }
    }
}

/// Whether the frames agree on one layout: the error they share beyond it within their own
/// noise (`σ_shared ≤ σ_frame`). A layout map assumes one rigid layout every frame sees; where
/// the frames disagree with their best layout by more than their own noise, ids do not name
/// one place in every frame (the lidar-only pipeline's false and swapped landmarks: σ_shared
/// 5.1 m against σ_frame 3·10⁻⁵ m) and the filter, whose evidence stays within each set's
/// frames, is the better map. MRCLAM's recordings measure 0.25–0.49 of their noise.
#[must_use]
pub fn layout_agrees(layout: &Layout) -> bool {
    let s = layout.shared_error();
    s.sigma_shared <= s.sigma_frame
}

/// The recording a [`MapJob`] read, and what the reading did.
#[derive(Debug, Clone)]
pub struct MapInput {
    /// The scans (gated, restricted to the robots asked for) and the truth.
    pub data: Dataset,
    /// The orderings chosen for the whole recording (so per-robot maps merge).
    pub orderings: Orderings,
    /// The possible ordered sets, the count `auto` chose by.
    pub possible_sets: u64,
    /// What every summary says of the reading: the noise fit, the outliers gated, the log's
    /// topics and where its landmarks came from.
    pub reading: Map<String, Value>,
}

impl MapInput {
    /// The robots whose scans it holds.
    #[must_use]
    pub fn robots(&self) -> BTreeSet<u32> {
        self.data.scans.iter().map(|s| s.robot).collect()
    }

    /// Robot `robot`'s scans alone, with the truth.
    #[must_use]
    pub fn of_robot(&self, robot: u32) -> Dataset {
        Dataset {
            scans: self
                .data
                .scans
                .iter()
                .filter(|s| s.robot == robot)
                .cloned()
                .collect(),
            truth: self.data.truth.clone(),
            skipped: 0,
        }
    }
}

/// A map made, with its summary (`summary.json`).
#[derive(Debug)]
pub struct Mapped {
    /// The map.
    pub map: Pqrm,
    /// What was mapped, with what, and how well (scored when the recording has truth).
    pub summary: Map<String, Value>,
    /// The τ chosen from the recording, when `auto` chose one (also in the summary).
    pub temper_fit: Option<TemperFit>,
    /// Why the evidence model is not the one asked for, when the recording could not give it
    /// (also the summary's `evidence_choice`): a user should be told.
    pub fell_back: Option<String>,
    format: MapFormatChoice,
}

/// What [`MapJob`] maps a recording under.
struct Chosen {
    evidence: pqrm::EvidenceModel,
    /// The fitted layout, when that is the model.
    layout: Option<Layout>,
    /// For a model the recording chose: which and why.
    why: Option<String>,
    /// Whether the recording could not give what was asked (the layout, or the measured N).
    fell_back: bool,
}

impl Chosen {
    /// A model as given.
    fn given(evidence: pqrm::EvidenceModel) -> Self {
        Self {
            evidence,
            layout: None,
            why: None,
            fell_back: false,
        }
    }

    /// The filter under `evidence`, chosen for `why`.
    fn filter(evidence: pqrm::EvidenceModel, why: String, fell_back: bool) -> Self {
        Self {
            evidence,
            layout: None,
            why: Some(why),
            fell_back,
        }
    }
}

impl MapJob {
    /// Reads the recording: its form's loader (errors name the file and line, or topic,
    /// message and field), its truth, the gate, the robots; `warn` hears what a user should
    /// know but that does not stop the job (a damaged log read up to its last chunk, a noise
    /// that could not be fitted).
    ///
    /// # Errors
    /// The loaders'; [`StudyError::InvalidParameter`] for MCAP options on another form or a
    /// robot without scans.
    pub fn read(&self, warn: &dyn Fn(String)) -> Result<MapInput> {
        let mcap = self.format == RecordingFormat::Mcap;
        let (mut data, fit, log_read) = if mcap {
            let r = qrm_log::read_mcap(&self.input, &self.log)?;
            if let Some(d) = &r.damage {
                warn(format!(
                    "{} is damaged; read up to its last readable chunk ({d})",
                    self.input.display()
                ));
            }
            (r.dataset.clone(), None, Some(r))
        } else {
            let defaults = qrm_log::ReadOptions::default();
            if !self.log.topics.is_empty()
                || self.log.range_max.is_some()
                || self.log.allow_truncated != defaults.allow_truncated
            {
                return Err(StudyError::InvalidParameter(
                    "--topic, --range-max and --allow-truncated are for --format mcap".into(),
                ));
            }
            let noise = self.noise.resolve(self.format, &self.input, warn)?;
            let data = crate::recording::read(self.format, &self.input, noise.noise)?;
            (data, noise.fit, None)
        };
        if let Some(t) = &self.truth {
            data.truth = Some(read_truth_csv(t)?);
        }
        let mut reading = Map::new();
        if let Some(fit) = &fit {
            reading.insert("noise_fit".into(), json!(fit));
        }
        if let Some(gated) = gate(&mut data, self.gate, fit.as_ref())? {
            reading.insert("gated".into(), json!(gated));
        }
        self.keep_robots(&mut data)?;
        if let Some(r) = &log_read {
            log_reading(&mut reading, r);
        }
        let possible_sets = possible_ordered_sets(&data.scans);
        warn_if_unmappable(&data.scans, warn);
        Ok(MapInput {
            orderings: self.orderings.resolve(possible_sets),
            possible_sets,
            data,
            reading,
        })
    }

    fn keep_robots(&self, data: &mut Dataset) -> Result<()> {
        if self.robots.is_empty() {
            return Ok(());
        }
        let present: BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
        if let Some(r) = self.robots.iter().find(|r| !present.contains(r)) {
            return Err(StudyError::InvalidParameter(format!(
                "--robots: robot {r} has no scans in {} (robots present: {present:?})",
                self.input.display()
            )));
        }
        data.scans.retain(|s| self.robots.contains(&s.robot));
        Ok(())
    }

    /// τ for `data` read under `evidence`: the given one, or `auto` chosen from held-out
    /// frames (no ground truth).
    ///
    /// # Errors
    /// The fit's (too few frames to hold any out).
    fn temper_under(
        &self,
        evidence: pqrm::EvidenceModel,
        data: &Dataset,
        config: PqrmConfig,
        progress: &dyn Progress,
    ) -> Result<(PqrmConfig, Option<TemperFit>)> {
        match self.temper {
            TemperChoice::Fixed(temper) => Ok((PqrmConfig { temper, ..config }, None)),
            TemperChoice::Auto => {
                progress.add_total(2 * data.scans.len());
                let mut fits = fit_temper(
                    std::slice::from_ref(&self.calculus),
                    &data.scans,
                    config,
                    // the τ is chosen on top of the evidence model the map is read under
                    &TemperOptions::default().evidence(evidence),
                    &|| progress.tick(),
                )
                .map_err(|e| match e {
                    pqrm::PqrmError::Cancelled(_) => e.into(),
                    _ => StudyError::InvalidParameter(format!(
                        "choosing the tempering exponent (--temper auto): {e}"
                    )),
                })?;
                let fit = fits.remove(0);
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

    /// The model `data` is mapped under, with the fitted layout when that is the layout, and,
    /// for a model the recording chooses, what was chosen and why.
    fn choose_evidence(
        &self,
        whole: &Dataset,
        data: &Dataset,
        progress: &dyn Progress,
    ) -> Result<Chosen> {
        let auto = match self.evidence {
            EvidenceRequest::Model(pqrm::EvidenceModel::Layout) => false,
            EvidenceRequest::Model(model) => return Ok(Chosen::given(model)),
            EvidenceRequest::Auto => true,
            EvidenceRequest::SharedMeasured => {
                let s = Layout::fit(&whole.scans, progress)?.shared_error();
                return Ok(match s.frames() {
                    Some(frames) => {
                        let model = pqrm::EvidenceModel::Shared { frames };
                        Chosen::filter(
                            model,
                            format!(
                                "shared:auto: the filter ({model}), N = (σ_frame {:.3} m / \
                                 σ_shared {:.3} m)² from the recording's layout",
                                s.sigma_frame, s.sigma_shared
                            ),
                            false,
                        )
                    }
                    None => {
                        let model = pqrm::EvidenceModel::shared_default();
                        Chosen::filter(
                            model,
                            format!(
                                "shared:auto: the filter ({model}): the recording's layout cannot \
                                 measure N (σ_shared {:.3} m, σ_frame {:.3} m, measured: {})",
                                s.sigma_shared, s.sigma_frame, s.measured
                            ),
                            true,
                        )
                    }
                });
            }
        };
        let filter = pqrm::EvidenceModel::shared_default();
        if auto && self.temper != TemperChoice::Fixed(1.0) {
            let why = format!("auto: the filter ({filter}): τ tempers its frames");
            return Ok(Chosen::filter(filter, why, false));
        }
        let fitted = Layout::fit(&data.scans, progress)?;
        if auto && !layout_agrees(&fitted) {
            let s = fitted.shared_error();
            let why = format!(
                "auto: the filter ({filter}): the frames disagree with their best layout by σ \
                 {:.3} m, more than their own noise (σ {:.3} m) — landmark ids that do not name \
                 one place in every frame",
                s.sigma_shared, s.sigma_frame
            );
            return Ok(Chosen::filter(filter, why, true));
        }
        Ok(Chosen {
            evidence: pqrm::EvidenceModel::Layout,
            layout: Some(fitted),
            why: auto.then(|| "auto: the layout".to_owned()),
            fell_back: false,
        })
    }

    /// Maps `data` (all of the input, or one robot's) with the orderings `input` chose.
    ///
    /// # Errors
    /// The filter's and the scoring's.
    pub fn map(&self, input: &MapInput, data: &Dataset, progress: &dyn Progress) -> Result<Mapped> {
        let config = PqrmConfig {
            orderings: input.orderings,
            ..self.config
        };
        let start = Instant::now();
        let Chosen {
            evidence,
            layout,
            why,
            fell_back,
        } = self.choose_evidence(&input.data, data, progress)?;
        let (map, config, temper_fit, layout) = if let Some(fitted) = layout {
            if self.temper != TemperChoice::Fixed(1.0) {
                return Err(StudyError::InvalidParameter(
                    "--temper tempers the filter's frames; a layout map (--evidence layout) \
                     has none to temper"
                        .into(),
                ));
            }
            let map = fitted.map(self.calculus.clone(), &data.scans, config, progress)?;
            (map, config, None, Some(fitted))
        } else {
            let (config, temper_fit) = self.temper_under(evidence, data, config, progress)?;
            let mut map = Pqrm::new(self.calculus.clone(), config)?.with_evidence(evidence)?;
            progress.add_total(data.scans.len());
            for scan in &data.scans {
                progress.check()?;
                map.update(scan)?;
                progress.tick();
            }
            // done growing: what is summarised and saved below has the memory
            map.release_step_buffers();
            (map, config, temper_fit, None)
        };
        let robots: BTreeSet<u32> = data.scans.iter().map(|s| s.robot).collect();
        let mut summary = Map::new();
        let mut put = |k: &str, v: Value| {
            summary.insert(k.to_owned(), v);
        };
        put("calculus", json!(map.calculus().name()));
        put("n_scans", json!(data.scans.len()));
        put("robots", json!(robots));
        put("floor", json!(config.floor));
        put("sensor", json!(config.sensor));
        put("temper", json!(config.temper));
        put("evidence", json!(map.evidence()));
        put("samples", json!(config.samples));
        put("orderings", json!(config.orderings));
        put("skipped_measurements", json!(data.skipped));
        put("n_sets", json!(map.len()));
        put("map_bytes_in_memory", json!(map.heap_bytes()));
        put("mean_entropy", json!(map.mean_entropy()));
        put("seconds", json!(start.elapsed().as_secs_f64()));
        if let Some(fit) = &temper_fit {
            put("temper_fit", json!(fit));
        }
        if let Some(why) = &why {
            put("evidence_choice", json!(why));
        }
        if let Some(l) = &layout {
            put(
                "layout",
                json!({
                    "shared_error": l.shared_error(),
                    // the filter's reading this recording measures (`--evidence shared:N` for
                    // a filter map of it), null where the layout cannot say
                    "filter_evidence": l
                        .shared_error()
                        .frames()
                        .map(|frames| pqrm::EvidenceModel::Shared { frames }.to_string()),
                    "landmarks": l
                        .landmarks()
                        .iter()
                        .map(|(id, m)| (id.0.to_string(), json!(m)))
                        .collect::<Map<String, Value>>(),
                    "rounds": l.rounds(),
                    "converged": l.converged(),
                }),
            );
        }
        for (k, v) in &input.reading {
            put(k, v.clone());
        }
        if let Some(truth) = &data.truth
            && !map.is_empty()
        {
            score_into(&mut summary, &evaluate(&map, truth)?);
        }
        Ok(Mapped {
            map,
            summary,
            temper_fit,
            fell_back: if fell_back { why } else { None },
            format: self.map_format,
        })
    }
}

/// What an MCAP log's reading says: the topics used, where the landmarks came from, damage.
fn log_reading(reading: &mut Map<String, Value>, r: &qrm_log::Recording) {
    let used: Vec<_> = r
        .topics
        .iter()
        .filter(|t| t.used)
        .map(|t| json!({"topic": t.topic, "schema": t.schema, "messages": t.messages, "robot": t.robot}))
        .collect();
    reading.insert("topics".into(), json!(used));
    let from = if r.from_scans {
        "lidar scans (extracted, recognised by triangles)"
    } else {
        "detections"
    };
    reading.insert("landmarks_from".into(), json!(from));
    reading.insert("damage".into(), json!(r.damage));
}

impl Mapped {
    /// Saves the map into `dir` as `map.json` or `map.pqrm` (by the job's format choice and
    /// the map's size), atomically, and adds the file's name and the saving time to the
    /// summary.
    ///
    /// # Errors
    /// [`StudyError::Pqrm`] naming the file.
    pub fn save(&mut self, dir: &Path) -> Result<()> {
        let format = self.format.resolve(self.map.len());
        let file = format!("map.{}", format.extension());
        let saving = Instant::now();
        self.map.save_as(&dir.join(&file), format)?;
        self.summary.insert("map_file".into(), json!(file));
        self.summary
            .insert("save_seconds".into(), json!(saving.elapsed().as_secs_f64()));
        Ok(())
    }
}

/// Saved maps of one area merged into one (`qrm pqrm merge`; the maps' beliefs of a set
/// fused, [`pqrm::robots::merge_maps`]), with a summary scored against `truth` when given: a
/// MRCLAM folder (its surveyed landmarks) or a truth CSV `landmark,x,y`.
///
/// # Errors
/// The loaders' errors naming the file; [`StudyError::InvalidParameter`] for a folder without
/// surveyed landmarks; [`StudyError::Pqrm`] for maps of different calculi.
pub fn merge_saved(maps: &[PathBuf], truth: Option<&Path>) -> Result<(Pqrm, Map<String, Value>)> {
    let loaded = maps
        .iter()
        .map(|p| Pqrm::load(p))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let truth = match truth {
        Some(t) if t.is_dir() => Some(
            pqrm::loaders::read_mrclam(t, pqrm::loaders::RangeBearingNoise::MRCLAM)?
                .truth
                .ok_or_else(|| {
                    StudyError::InvalidParameter(format!(
                        "{} has no surveyed landmarks",
                        t.display()
                    ))
                })?,
        ),
        Some(t) => Some(read_truth_csv(t)?),
        None => None,
    };
    let merged = pqrm::robots::merge_maps(&loaded)?;
    let mut summary = Map::new();
    summary.insert("calculus".into(), json!(merged.calculus().name()));
    let names: Vec<String> = maps.iter().map(|p| p.display().to_string()).collect();
    summary.insert("maps".into(), json!(names));
    let sizes: Vec<usize> = loaded.iter().map(Pqrm::len).collect();
    summary.insert("sets_per_map".into(), json!(sizes));
    summary.insert("n_sets".into(), json!(merged.len()));
    summary.insert("mean_entropy".into(), json!(merged.mean_entropy()));
    if let Some(truth) = &truth
        && !merged.is_empty()
    {
        score_into(&mut summary, &evaluate(&merged, truth)?);
    }
    Ok((merged, summary))
}

/// A map's scores against the truth, into a summary.
pub fn score_into(summary: &mut Map<String, Value>, m: &pqrm::MapMetrics) {
    summary.insert("n_scored".into(), json!(m.n_scored));
    summary.insert("error_rate".into(), json!(m.error_rate));
    summary.insert(
        "mean_neighbor_distance".into(),
        json!(m.mean_neighbor_distance),
    );
    summary.insert("p_ml_mean".into(), json!(m.p_ml_mean));
    summary.insert("top_n_error".into(), json!(m.top_n_error));
    summary.insert("normalized_entropy".into(), json!(m.normalized_entropy));
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    fn scan(ids: std::ops::Range<u32>) -> pqrm::Scan {
        let obs = ids
            .map(|i| pqrm::Observation {
                id: pqrm::LandmarkId(i),
                mean: [f64::from(i), 0.5 * f64::from(i % 3)],
                cov: [[0.04, 0.0], [0.0, 0.04]],
            })
            .collect();
        pqrm::Scan::new(0.0, 1, obs).unwrap()
    }

    #[test]
    fn possible_ordered_sets_is_the_smaller_bound() {
        // Few scans of many landmarks: the landmarks bound.
        assert_eq!(possible_ordered_sets(&[scan(0..10), scan(0..10)]), 720);
        // Many landmarks, each scan sees a few: the scans bound.
        let scans: Vec<_> = (0..5).map(|s| scan(s * 4..s * 4 + 4)).collect();
        assert_eq!(possible_ordered_sets(&scans), 5 * 24);
        assert_eq!(possible_ordered_sets(&[]), 0);
        assert_eq!(possible_ordered_sets(&[scan(0..2)]), 0);
    }

    #[test]
    fn evidence_requests_parse_auto_shared_auto_and_every_model() {
        assert_eq!(
            EvidenceRequest::parse(" Auto ").ok(),
            Some(EvidenceRequest::Auto)
        );
        assert_eq!(
            EvidenceRequest::parse("shared:auto").ok(),
            Some(EvidenceRequest::SharedMeasured)
        );
        assert_eq!(
            EvidenceRequest::parse("shared:8").ok(),
            Some(EvidenceRequest::Model(pqrm::EvidenceModel::Shared {
                frames: 8.0
            }))
        );
        assert_eq!(
            EvidenceRequest::parse("layout").ok(),
            Some(EvidenceRequest::Model(pqrm::EvidenceModel::Layout))
        );
        let err = EvidenceRequest::parse("shared:many")
            .unwrap_err()
            .to_string();
        assert!(err.contains("many") && err.contains("shared:auto"), "{err}");
    }

    #[test]
    fn auto_turns_canonical_above_64_landmarks_in_view() {
        let at = |n: u64| OrderingsChoice::Auto.resolve(n * (n - 1) * (n - 2));
        assert_eq!(at(64), Orderings::All);
        assert_eq!(at(65), Orderings::Canonical);
        assert_eq!(OrderingsChoice::All.resolve(u64::MAX), Orderings::All);
        assert_eq!(OrderingsChoice::Canonical.resolve(6), Orderings::Canonical);
    }

    #[test]
    fn auto_writes_binary_above_100k_sets() {
        assert_eq!(MapFormatChoice::Auto.resolve(100_000), MapFormat::Json);
        assert_eq!(MapFormatChoice::Auto.resolve(100_001), MapFormat::Binary);
        assert_eq!(MapFormatChoice::Json.resolve(usize::MAX), MapFormat::Json);
    }
}
