//! `qrm.Pqrm`, observation files and the Monte Carlo study shards: thin wrappers of `pqrm`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pqrm::study::{MonteCarloConfig, TrialRecord};
use pqrm::{GroundTruth, LandmarkId, LandmarkSet, Observation, Orderings, PqrmConfig, Scan};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::calculus::Calculus;
use crate::errors::{invalid, pqrm as perr};

fn scan_from_arrays(
    t: f64,
    robot: u32,
    ids: &PyReadonlyArray1<'_, i64>,
    xy: &PyReadonlyArray2<'_, f64>,
    cov: &PyReadonlyArray2<'_, f64>,
) -> PyResult<Scan> {
    let (ids, xy, cov) = (ids.as_array(), xy.as_array(), cov.as_array());
    let n = ids.len();
    if xy.shape() != [n, 2] || cov.shape() != [n, 3] {
        return Err(invalid(format!(
            "expected ids (n,), xy (n, 2) and cov (n, 3) = [cxx, cxy, cyy] with one n; got {:?}, {:?}, {:?}",
            ids.shape(),
            xy.shape(),
            cov.shape()
        )));
    }
    let obs = (0..n)
        .map(|i| {
            let id = u32::try_from(ids[i]).map_err(|_| {
                invalid(format!(
                    "landmark id {} is not a non-negative 32-bit integer",
                    ids[i]
                ))
            })?;
            Observation::new(
                LandmarkId(id),
                [xy[[i, 0]], xy[[i, 1]]],
                [[cov[[i, 0]], cov[[i, 1]]], [cov[[i, 1]], cov[[i, 2]]]],
            )
            .map_err(perr)
        })
        .collect::<PyResult<Vec<_>>>()?;
    Scan::new(t, robot, obs).map_err(perr)
}

/// `orderings=` as Python gives it: "all" or "canonical".
fn parse_orderings(orderings: &str) -> PyResult<Orderings> {
    match orderings {
        "all" => Ok(Orderings::All),
        "canonical" => Ok(Orderings::Canonical),
        other => Err(invalid(format!(
            "orderings must be \"all\" or \"canonical\", got {other:?}"
        ))),
    }
}

/// Surveyed positions as Python sees them: {landmark: (x, y)}.
type TruthDict = BTreeMap<u32, (f64, f64)>;

fn truth_from_dict(truth: &BTreeMap<u32, (f64, f64)>) -> GroundTruth {
    GroundTruth {
        positions: truth
            .iter()
            .map(|(k, (x, y))| (LandmarkId(*k), [*x, *y]))
            .collect(),
    }
}

/// A probabilistic qualitative relational map.
#[pyclass(module = "qrm")]
pub(crate) struct Pqrm {
    pub(crate) inner: pqrm::Pqrm,
}

#[pymethods]
impl Pqrm {
    /// An empty map over `calculus`.
    /// `sensor` is "gaussian", "student-t:NU" or "outliers:RATE,SPREAD"; `temper` ∈ (0, 1]
    /// scales each step's log-likelihood; `evidence` is "shared" (frames share the geometry
    /// and an error, `pqrm::evidence`: probabilities calibrated on real recordings),
    /// "shared:N" or "independent" (the thesis's eq. 2.10).
    #[new]
    #[allow(clippy::too_many_arguments)] // the constructor's keyword arguments, and the token
    #[pyo3(signature = (calculus, *, samples = 1000, floor = 1.0, orderings = "all", seed = 0, sensor = "gaussian", temper = 1.0, evidence = "shared"))]
    fn new(
        py: Python<'_>,
        calculus: &Calculus,
        samples: usize,
        floor: f64,
        orderings: &str,
        seed: u64,
        sensor: &str,
        temper: f64,
        evidence: &str,
    ) -> PyResult<Self> {
        let evidence = pqrm::EvidenceModel::parse(evidence).map_err(perr)?;
        let orderings = parse_orderings(orderings)?;
        let config = PqrmConfig {
            samples,
            floor,
            orderings,
            seed,
            sensor: pqrm::sensor::SensorModel::parse(sensor).map_err(perr)?,
            temper,
        };
        let calculus = calculus.inner.clone();
        crate::pool::detach(py, || {
            pqrm::Pqrm::new(calculus, config).and_then(|m| m.with_evidence(evidence))
        })
        .map(|inner| Self { inner })
        .map_err(perr)
    }

    /// How a set's frames combine into its belief: "shared:N" or "independent".
    #[getter]
    fn evidence(&self) -> String {
        self.inner.evidence().to_string()
    }

    /// One time step: landmark `ids` (n,), positions `xy` (n, 2) and covariances `cov`
    /// (n, 3) = [cxx, cxy, cyy], in the robot frame. Returns {"observed", "new", "conflicts"}.
    #[pyo3(signature = (t, ids, xy, cov, *, robot = 0))]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        ids: Bound<'py, PyAny>,
        xy: Bound<'py, PyAny>,
        cov: Bound<'py, PyAny>,
        robot: u32,
    ) -> PyResult<Bound<'py, PyDict>> {
        let scan = scan_from_arrays(
            t,
            robot,
            &crate::arrays::ints1(&ids, "ids")?,
            &crate::arrays::floats2(&xy, "xy")?,
            &crate::arrays::floats2(&cov, "cov")?,
        )?;
        let map = &mut self.inner;
        let report = crate::pool::detach(py, || map.update(&scan)).map_err(perr)?;
        let d = PyDict::new(py);
        d.set_item("observed", report.observed)?;
        d.set_item("new", report.new)?;
        d.set_item("conflicts", report.conflicts)?;
        Ok(d)
    }

    /// The belief of the ordered set (a, b, c) as probabilities in state order, or None.
    fn belief<'py>(
        &self,
        py: Python<'py>,
        set: (u32, u32, u32),
    ) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner
            .belief(LandmarkSet::new(set.0, set.1, set.2))
            .map(|p| p.into_pyarray(py))
    }

    /// A distribution for the ordered set (a, b, d) from the map's other beliefs through the
    /// compose table (see `pqrm::reason`): {"p": array, "paths": int, "via": [ids], "round":
    /// int, "alpha": float, "composition": str, "base_rate": bool}. A set the map observed is predicted from the observed beliefs; a
    /// set never observed is inferred as in the run over every unseen set (`rounds` of
    /// chained composition), so the two agree. `composition`: "learned" (each composition
    /// entry's states shared as the map's own quadruples show them) or "uniform". On a layout
    /// map (`layout_map`) a UserWarning says inference over layout maps was measured
    /// overconfident where over the filter's (`Pqrm`) it was closer to calibrated (docs/reasoning.md).
    #[pyo3(signature = (set, *, fusion = "fitted", epsilon = 0.01, rounds = 1, composition = "learned"))]
    fn infer<'py>(
        &self,
        py: Python<'py>,
        set: (u32, u32, u32),
        fusion: &str,
        epsilon: f64,
        rounds: usize,
        composition: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let fusion: pqrm::reason::Fusion = fusion.parse().map_err(perr)?;
        let composition: pqrm::reason::Composition = composition.parse().map_err(perr)?;
        let options = pqrm::reason::InferOptions {
            fusion,
            composition,
            epsilon,
            rounds,
        };
        let map = &self.inner;
        if let Some(note) = pqrm::reason::calibration_note(map.evidence()) {
            let text = std::ffi::CString::new(note)
                .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
            PyErr::warn(
                py,
                &py.get_type::<pyo3::exceptions::PyUserWarning>(),
                &text,
                1,
            )?;
        }
        let (inf, alpha, base_rate) = crate::pool::detach(py, || {
            let mut inferrer = pqrm::reason::Inferrer::new(map, options)?;
            // as the run over every unseen set infers it (`Inferrer::infer_sets`)
            let mut inf = inferrer.infer_sets(&[LandmarkSet::new(set.0, set.1, set.2)])?;
            Ok::<_, pqrm::PqrmError>((
                inf.remove(0),
                inferrer.alpha(),
                inferrer.divides_base_rate(),
            ))
        })
        .map_err(perr)?;
        let d = PyDict::new(py);
        d.set_item("p", inf.p.into_pyarray(py))?;
        d.set_item("paths", inf.paths)?;
        d.set_item("via", inf.via)?;
        d.set_item("round", inf.round)?;
        d.set_item("alpha", alpha)?;
        d.set_item("composition", composition.name())?;
        d.set_item("base_rate", base_rate)?;
        Ok(d)
    }

    /// The consistency check of the most likely states: {"sets", "consistent",
    /// "contradiction", "flagged": [{"set", "state", "p"}], "closures"}.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let map = &self.inner;
        let result = crate::pool::detach(py, || pqrm::reason::check(map)).map_err(perr)?;
        let json = serde_json::to_string(&result).map_err(|e| invalid(e.to_string()))?;
        py.import("json")?.call_method1("loads", (json,))
    }

    /// Mean entropy over the recorded sets (nats), None for an empty map.
    fn entropy(&self) -> Option<f64> {
        self.inner.mean_entropy()
    }

    /// The recorded ordered sets.
    fn sets(&self) -> Vec<(u32, u32, u32)> {
        self.inner.iter().map(|(s, _)| s.ids().into()).collect()
    }

    /// The calculus.
    #[getter]
    fn calculus(&self) -> Calculus {
        Calculus {
            inner: self.inner.calculus().clone(),
        }
    }

    /// Scores against surveyed positions {landmark: (x, y)}.
    fn metrics<'py>(
        &self,
        py: Python<'py>,
        truth: BTreeMap<u32, (f64, f64)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let truth = truth_from_dict(&truth);
        let m = crate::pool::detach(py, || pqrm::evaluate(&self.inner, &truth)).map_err(perr)?;
        let d = PyDict::new(py);
        d.set_item("n_sets", m.n_sets)?;
        d.set_item("n_scored", m.n_scored)?;
        d.set_item("mean_entropy", m.mean_entropy)?;
        d.set_item("normalized_entropy", m.normalized_entropy)?;
        d.set_item("error_rate", m.error_rate)?;
        d.set_item("mean_neighbor_distance", m.mean_neighbor_distance)?;
        d.set_item("p_ml_mean", m.p_ml_mean)?;
        d.set_item("top_n_error", m.top_n_error)?;
        d.set_item("confusion", m.confusion)?;
        Ok(d)
    }

    /// Folds another map of the same calculus into this one (the product of the two beliefs
    /// of a set in both). The merged map keeps this map's evidence model; both store
    /// eq. 2.10's sums, so the rows do not depend on either map's model.
    fn merge(&mut self, py: Python<'_>, other: &Pqrm) -> PyResult<()> {
        let inner = &mut self.inner;
        crate::pool::detach(py, || inner.merge(&other.inner)).map_err(perr)
    }

    /// Saves atomically: binary for a `.pqrm` path (compact, checksummed, fast for large
    /// maps), JSON otherwise.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        crate::pool::detach(py, || inner.save(&path)).map_err(perr)
    }

    /// Loads a saved map, JSON or binary (told apart by its first bytes).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        // In the fork-aware pool, as every call below: loading checks its rows in parallel,
        // and a forked child of a parent that had touched rayon's global pool hung (issue 40).
        crate::pool::detach(py, || pqrm::Pqrm::load(&path))
            .map(|inner| Self { inner })
            .map_err(perr)
    }

    /// The map as JSON text.
    fn to_json(&self, py: Python<'_>) -> PyResult<String> {
        let inner = &self.inner;
        crate::pool::detach(py, || inner.to_json()).map_err(perr)
    }

    /// A map from its JSON text (`to_json`).
    #[staticmethod]
    fn from_json(py: Python<'_>, text: &str) -> PyResult<Self> {
        crate::pool::detach(py, || pqrm::Pqrm::from_json(text))
            .map(|inner| Self { inner })
            .map_err(perr)
    }

    /// The map in the binary map format (what a `.pqrm` file holds).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let inner = &self.inner;
        let bytes = crate::pool::detach(py, || inner.to_binary()).map_err(perr)?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// A map from `to_bytes()` (checked: size, checksum, every belief).
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        crate::pool::detach(py, || pqrm::Pqrm::from_binary(data))
            .map(|inner| Self { inner })
            .map_err(perr)
    }

    /// Pickles as its binary form (multiprocessing, Ray): `Pqrm.from_bytes(to_bytes())`,
    /// exact and a tenth of the JSON.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let ctor = slf.get_type().getattr("from_bytes")?;
        Ok((ctor, (slf.borrow().to_bytes(slf.py())?,)))
    }

    /// Every recorded set as columns: {"a", "b", "c", "ml_state", "p_ml", "entropy",
    /// "updates"} (NumPy arrays; `qrm.to_pandas(map)` makes a DataFrame of it).
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let n = self.inner.len();
        let (mut a, mut b, mut c) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        let (mut ml, mut p, mut h, mut u) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for (set, belief) in self.inner.iter() {
            let [x, y, z] = set.ids();
            a.push(i64::from(x));
            b.push(i64::from(y));
            c.push(i64::from(z));
            let s = belief.ml_state();
            ml.push(i64::from(s.0));
            p.push(belief.log_p[s.index()].exp());
            h.push(belief.entropy());
            u.push(i64::from(belief.updates));
        }
        let d = PyDict::new(py);
        d.set_item("a", a.into_pyarray(py))?;
        d.set_item("b", b.into_pyarray(py))?;
        d.set_item("c", c.into_pyarray(py))?;
        d.set_item("ml_state", ml.into_pyarray(py))?;
        d.set_item("p_ml", p.into_pyarray(py))?;
        d.set_item("entropy", h.into_pyarray(py))?;
        d.set_item("updates", u.into_pyarray(py))?;
        Ok(d)
    }

    /// The sets as a pandas DataFrame (`columns()`); pandas is optional.
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pd = py.import("pandas").map_err(|e| {
            pyo3::exceptions::PyImportError::new_err(format!(
                "Pqrm.to_pandas needs pandas (pip install pandas): {e}"
            ))
        })?;
        pd.call_method1("DataFrame", (self.columns(py)?,))
    }

    /// The map in a notebook: the histogram of P(ML) over its sets.
    fn _repr_svg_(&self) -> PyResult<String> {
        let p: Vec<f64> = self
            .inner
            .iter()
            .map(|(_, b)| b.log_p[b.ml_state().index()].exp())
            .collect();
        let title = format!(
            "{} map: {} sets, how sure",
            self.inner.calculus().name(),
            self.inner.len()
        );
        crate::picture::p_ml_histogram(&title, &p).map_err(invalid)
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Pqrm({:?}, {} sets, {} steps)",
            self.inner.calculus().name(),
            self.inner.len(),
            self.inner.steps()
        )
    }
}

/// One scan as `{"t", "robot", "ids", "xy", "cov"}` (NumPy arrays; cov rows
/// `[cxx, cxy, cyy]`).
fn scan_dict<'py>(py: Python<'py>, s: &pqrm::Scan) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t", s.t)?;
    d.set_item("robot", s.robot)?;
    d.set_item(
        "ids",
        s.observations
            .iter()
            .map(|o| i64::from(o.id.0))
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    let xy: Vec<Vec<f64>> = s.observations.iter().map(|o| o.mean.to_vec()).collect();
    let cov: Vec<Vec<f64>> = s
        .observations
        .iter()
        .map(|o| vec![o.cov[0][0], o.cov[0][1], o.cov[1][1]])
        .collect();
    d.set_item(
        "xy",
        PyArray2::from_vec2(py, &xy).map_err(|e| invalid(e.to_string()))?,
    )?;
    d.set_item(
        "cov",
        PyArray2::from_vec2(py, &cov).map_err(|e| invalid(e.to_string()))?,
    )?;
    Ok(d)
}

// `survey_agreement`'s defaults are literals (Python shows them); they are the library's
const _: () = assert!(pqrm::survey::OFF_SURVEY_M == 0.1 && pqrm::survey::MIN_FRAMES == 5);

/// Which landmark pairs the survey disagrees with the frames on (`pqrm::survey`, what
/// `qrm pqrm real` writes in `survey.csv`): for every pair of surveyed landmarks seen together
/// in at least `min_frames` scans, the median of (distance seen − surveyed distance); a pair
/// is off the survey when that median is beyond `off` metres and beyond three standard errors
/// of the median. `scans` as `read_observations` returns them (each a dict with "t", "robot",
/// "ids", "xy", "cov"), `survey` {landmark: (x, y)}. Returns {"pairs_seen": int, "off":
/// [(a, b, median, frames)]}, pairs with a < b, in order.
#[pyfunction]
#[pyo3(signature = (scans, survey, *, off = 0.1, min_frames = 5))]
pub(crate) fn survey_agreement<'py>(
    py: Python<'py>,
    scans: Vec<Bound<'py, PyDict>>,
    survey: TruthDict,
    off: f64,
    min_frames: usize,
) -> PyResult<Bound<'py, PyDict>> {
    if !(off.is_finite() && off >= 0.0) {
        return Err(invalid(format!(
            "off must be a finite distance ≥ 0 (metres), got {off}"
        )));
    }
    if min_frames == 0 {
        return Err(invalid("min_frames must be at least 1"));
    }
    let parsed = scans_from_dicts(&scans)?;
    let truth = truth_from_dict(&survey);
    let agreement = crate::pool::detach(py, || {
        pqrm::survey::SurveyAgreement::measure(&parsed, &truth, off, min_frames)
    });
    let d = PyDict::new(py);
    d.set_item("pairs_seen", agreement.pairs_seen)?;
    let pairs: Vec<(u32, u32, f64, usize)> = agreement
        .off
        .iter()
        .map(|p| (p.pair[0].0, p.pair[1].0, p.median, p.frames))
        .collect();
    d.set_item("off", pairs)?;
    Ok(d)
}

/// Scans as `read_observations` returns them (dicts with "t", "robot", "ids", "xy", "cov").
fn scans_from_dicts(scans: &[Bound<'_, PyDict>]) -> PyResult<Vec<Scan>> {
    scans
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let item = |key: &str| {
                d.get_item(key)?.ok_or_else(|| {
                    invalid(format!(
                        "scans[{k}] has no {key:?} (a scan is a dict with \"t\", \"robot\", \"ids\", \"xy\", \"cov\", as read_observations returns)"
                    ))
                })
            };
            let t = item("t")?
                .extract::<f64>()
                .map_err(|_| invalid(format!("scans[{k}][\"t\"] is not a number")))?;
            let robot = item("robot")?.extract::<u32>().map_err(|_| {
                invalid(format!(
                    "scans[{k}][\"robot\"] is not a non-negative 32-bit integer"
                ))
            })?;
            scan_from_arrays(
                t,
                robot,
                &crate::arrays::ints1(&item("ids")?, "ids")?,
                &crate::arrays::floats2(&item("xy")?, "xy")?,
                &crate::arrays::floats2(&item("cov")?, "cov")?,
            )
            .map_err(|e| invalid(format!("scans[{k}]: {e}")))
        })
        .collect::<PyResult<Vec<Scan>>>()
}

/// The layout map of a recording (`pqrm::layout`: what `qrm map` makes by default where the
/// frames agree on one layout, `--evidence layout`): every frame aligned into one layout of the landmarks, each set's belief the share
/// of draws of its three positions — the layout's, give or take the error the frames share
/// beyond it, measured from the frames — that fall in each state. `scans` as
/// `read_observations` returns them. Returns (map, layout): the map a `Pqrm` whose evidence
/// is "layout" (it takes no more frames and merges with nothing: map the whole recording
/// again), layout a dict {"sigma_shared", "sigma_frame", "pairs", "rounds", "converged",
/// "landmarks": {id: {"position": (x, y), "sightings", "component", "sigma_shared"}}}.
#[pyfunction]
#[pyo3(signature = (calculus, scans, *, orderings = "all", seed = 0))]
pub(crate) fn layout_map<'py>(
    py: Python<'py>,
    calculus: &Calculus,
    scans: Vec<Bound<'py, PyDict>>,
    orderings: &str,
    seed: u64,
) -> PyResult<(Pqrm, Bound<'py, PyDict>)> {
    let orderings = parse_orderings(orderings)?;
    let parsed = scans_from_dicts(&scans)?;
    let config = PqrmConfig {
        orderings,
        seed,
        ..PqrmConfig::default()
    };
    let calc = calculus.inner.clone();
    let (layout, map) = crate::pool::detach(py, || {
        let layout = pqrm::layout::Layout::fit(&parsed, &|| {})?;
        let map = layout.map(calc, &parsed, config, &|| {})?;
        Ok::<_, pqrm::PqrmError>((layout, map))
    })
    .map_err(perr)?;
    let d = PyDict::new(py);
    let shared = layout.shared_error();
    d.set_item("sigma_shared", shared.sigma_shared)?;
    d.set_item("sigma_frame", shared.sigma_frame)?;
    d.set_item("pairs", shared.pairs)?;
    d.set_item("rounds", layout.rounds())?;
    d.set_item("converged", layout.converged())?;
    let marks = PyDict::new(py);
    for (id, m) in layout.landmarks() {
        let one = PyDict::new(py);
        one.set_item("position", (m.position[0], m.position[1]))?;
        one.set_item("sightings", m.sightings)?;
        one.set_item("component", m.component)?;
        one.set_item("sigma_shared", m.sigma_shared)?;
        marks.set_item(id.0, one)?;
    }
    d.set_item("landmarks", marks)?;
    Ok((Pqrm { inner: map }, d))
}

/// Reads an observation file as `qrm map` reads it: `format` is "csv", "mrclam" (a
/// directory), "g2o" or "mcap" (a ROS 2 bag or Foxglove/qrm log; `topic` is one topic or a
/// list, default: every detection topic, else the one LaserScan topic). MRCLAM's range-bearing
/// noise is fitted from the recording unless `sigma_range`/`sigma_bearing` are given or
/// `noise="fixed"` (MRCLAM's 0.15 m / 0.01 rad where one is missing); gross outliers are
/// gated (3σ of the fit) where the noise was fitted, unless `gate=False` (`gate=True` gates
/// any form). Returns (scans, truth): each scan a dict {"t", "robot", "ids", "xy", "cov"} of
/// NumPy arrays, truth a dict {landmark: (x, y)} or None. A fit nobody asked for that cannot
/// be made (a recording too short) keeps the fixed noise and warns.
#[pyfunction]
#[pyo3(signature = (path, format, *, sigma_range = None, sigma_bearing = None, noise = None, gate = None, topic = None, range_max = None, allow_truncated = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn read_observations<'py>(
    py: Python<'py>,
    path: PathBuf,
    format: &str,
    sigma_range: Option<f64>,
    sigma_bearing: Option<f64>,
    noise: Option<&str>,
    gate: Option<bool>,
    topic: Option<Bound<'py, PyAny>>,
    range_max: Option<f32>,
    allow_truncated: bool,
) -> PyResult<(Vec<Bound<'py, PyDict>>, Option<TruthDict>)> {
    use studies::recording::{NoiseMode, NoiseRequest, RecordingFormat};
    let mode = match noise {
        None => None,
        Some("auto") => Some(NoiseMode::Auto),
        Some("fixed") => Some(NoiseMode::Fixed),
        Some(other) => {
            return Err(invalid(format!(
                "noise must be \"auto\" or \"fixed\", got {other:?}"
            )));
        }
    };
    let request = NoiseRequest {
        mode,
        sigma_range,
        sigma_bearing,
    };
    let topics: Vec<String> = match &topic {
        None => Vec::new(),
        Some(t) => match t.extract::<String>() {
            Ok(one) => vec![one],
            Err(_) => t
                .extract::<Vec<String>>()
                .map_err(|_| invalid("topic must be a str or a list of str"))?,
        },
    };
    if format != "mcap" && (!topics.is_empty() || range_max.is_some() || allow_truncated) {
        return Err(invalid(
            "topic, range_max and allow_truncated are for format=\"mcap\"",
        ));
    }
    let options = qrm_log::ReadOptions {
        topics,
        range_max,
        allow_truncated,
        ..Default::default()
    };
    let recording = match format {
        "csv" => Some(RecordingFormat::Csv),
        "mrclam" => Some(RecordingFormat::Mrclam),
        "g2o" => Some(RecordingFormat::G2o),
        "mcap" => None,
        other => {
            return Err(invalid(format!(
                "format must be csv, mrclam, g2o or mcap, got {other:?}"
            )));
        }
    };
    if recording.is_none() && (mode.is_some() || sigma_range.is_some() || sigma_bearing.is_some()) {
        return Err(invalid(
            "noise, sigma_range and sigma_bearing are for a range-bearing recording \
             (format=\"mrclam\"); an MCAP log carries its own covariances",
        ));
    }
    // the two refusals of `NoiseRequest::resolve`, in this function's words (its own name
    // the command line's flags)
    if mode == Some(NoiseMode::Auto) {
        if recording != Some(RecordingFormat::Mrclam) {
            return Err(invalid(format!(
                "noise=\"auto\" fits a range-bearing sensor (format=\"mrclam\"); a {format} \
                 recording carries its own covariances"
            )));
        }
        if sigma_range.is_some() || sigma_bearing.is_some() {
            return Err(invalid(
                "noise=\"auto\" fits sigma_range and sigma_bearing: drop them, or say \
                 noise=\"fixed\"",
            ));
        }
    }
    let (data, warnings) = crate::pool::detach(py, || {
        let warnings = std::sync::Mutex::new(Vec::new());
        let warn = |w: String| warnings.lock().map(|mut v| v.push(w)).unwrap_or(());
        let (mut data, fit) = match recording {
            Some(form) => {
                let resolved = request
                    .resolve(form, &path, &warn)
                    .map_err(crate::errors::study_err)?;
                let data = studies::recording::read(form, &path, resolved.noise)
                    .map_err(crate::errors::study_err)?;
                (data, resolved.fit)
            }
            None => (
                qrm_log::read_mcap(&path, &options)
                    .map(|r| r.dataset)
                    .map_err(crate::errors::log)?,
                None,
            ),
        };
        studies::mapping::gate(&mut data, gate, fit.as_ref()).map_err(crate::errors::study_err)?;
        let warnings = warnings.into_inner().unwrap_or_default();
        Ok::<_, PyErr>((data, warnings))
    })?;
    for w in warnings {
        let msg = std::ffi::CString::new(w).map_err(|e| invalid(e.to_string()))?;
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &msg,
            1,
        )?;
    }
    let scans = data
        .scans
        .iter()
        .map(|s| scan_dict(py, s))
        .collect::<PyResult<Vec<_>>>()?;
    let truth = data.truth.map(|t| {
        t.positions
            .iter()
            .map(|(k, v)| (k.0, (v[0], v[1])))
            .collect()
    });
    Ok((scans, truth))
}

/// Single-observation p(R | Z) of three points `points` (3, 2) with covariances `cov`
/// (3, 3) = [cxx, cxy, cyy] per point (eq. 2.9 without the filter).
#[pyfunction]
#[pyo3(signature = (calculus, points, cov, *, samples = 1000, floor = 0.0, seed = 0))]
pub(crate) fn single_observation<'py>(
    py: Python<'py>,
    calculus: &Calculus,
    points: Bound<'py, PyAny>,
    cov: Bound<'py, PyAny>,
    samples: usize,
    floor: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (points, cov) = (
        crate::arrays::floats2(&points, "points")?,
        crate::arrays::floats2(&cov, "cov")?,
    );
    let (p, c) = (points.as_array(), cov.as_array());
    if p.shape() != [3, 2] || c.shape() != [3, 3] {
        return Err(invalid(format!(
            "expected points (3, 2) and cov (3, 3), got {:?} and {:?}",
            p.shape(),
            c.shape()
        )));
    }
    let pts = [
        [p[[0, 0]], p[[0, 1]]],
        [p[[1, 0]], p[[1, 1]]],
        [p[[2, 0]], p[[2, 1]]],
    ];
    let covs = [0, 1, 2].map(|i| [[c[[i, 0]], c[[i, 1]]], [c[[i, 1]], c[[i, 2]]]]);
    let calc = &calculus.inner;
    let probs = crate::pool::detach(py, || {
        pqrm::study::single_observation(calc, pts, covs, samples, floor, seed)
    })
    .map_err(perr)?;
    Ok(probs.into_pyarray(py))
}

fn config_from_json(config: &str) -> PyResult<MonteCarloConfig> {
    serde_json::from_str(config).map_err(|e| invalid(format!("study config: {e}")))
}

/// Runs trials `start..start+count` of the Monte Carlo study described by `config` (JSON);
/// returns the trial records as JSON. Shards with the same config merge into one run.
/// Watched: Ctrl-C stops it, `progress(done, total)` counts trials.
#[pyfunction]
#[pyo3(signature = (config, start, count, progress = None))]
pub(crate) fn monte_carlo_shard(
    py: Python<'_>,
    config: &str,
    start: usize,
    count: usize,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let cfg = config_from_json(config)?;
    let records = crate::pool::watched(py, progress, |watch| {
        pqrm::study::run_monte_carlo_shard(&cfg, start, count, watch)
    })?
    .map_err(perr)?;
    serde_json::to_string(&records).map_err(|e| invalid(e.to_string()))
}

/// Aggregates shards' trial records (JSON texts) into the study result (JSON).
#[pyfunction]
pub(crate) fn monte_carlo_aggregate(
    py: Python<'_>,
    config: &str,
    shards: Vec<String>,
) -> PyResult<String> {
    let cfg = config_from_json(config)?;
    let mut records: Vec<TrialRecord> = Vec::new();
    for s in &shards {
        let mut r: Vec<TrialRecord> =
            serde_json::from_str(s).map_err(|e| invalid(format!("shard records: {e}")))?;
        records.append(&mut r);
    }
    let result = crate::pool::detach(py, || pqrm::study::aggregate_monte_carlo(&cfg, &records))
        .map_err(perr)?;
    serde_json::to_string(&result).map_err(|e| invalid(e.to_string()))
}

/// The default (or quick) Monte Carlo configuration as JSON.
#[pyfunction]
#[pyo3(signature = (*, quick = false))]
pub(crate) fn monte_carlo_config(quick: bool) -> PyResult<String> {
    let c = if quick {
        MonteCarloConfig::quick()
    } else {
        MonteCarloConfig::default()
    };
    serde_json::to_string(&c).map_err(|e| invalid(e.to_string()))
}
