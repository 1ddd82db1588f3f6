//! `qrm.SalientRegionMap`, `qrm._qrm.serge_run` and the SERGE study: thin wrappers of the
//! `serge` crate.

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use serge::{BeliefSet, SergeParams};

use crate::calculus::Calculus;
use crate::errors::{invalid, serge_err};

/// A salient region map (thesis §3.2): regions of grid cells, a region per belief.
#[pyclass(module = "qrm", frozen)]
pub(crate) struct SalientRegionMap {
    inner: serge::SalientRegionMap,
    initial_regions: usize,
}

#[pymethods]
impl SalientRegionMap {
    /// Number of regions |R|.
    #[getter]
    fn n_regions(&self) -> usize {
        self.inner.n_regions
    }

    /// Region of each belief (input order).
    #[getter]
    fn assignment(&self) -> Vec<u32> {
        self.inner.assignment.clone()
    }

    /// Saliency (mass on its region) of each belief.
    #[getter]
    fn saliency(&self) -> Vec<f64> {
        self.inner.saliency.clone()
    }

    /// log ψ3: the sum of the beliefs' log saliencies.
    #[getter]
    fn log_saliency(&self) -> f64 {
        self.inner.log_saliency
    }

    /// log φ = log ψ1 + log ψ3.
    #[getter]
    fn log_phi(&self) -> f64 {
        self.inner.log_phi()
    }

    /// Number of initial regions SERGE started from.
    #[getter]
    fn initial_regions(&self) -> usize {
        self.initial_regions
    }

    /// Grid window (x0, x1, y0, y1).
    #[getter]
    fn window(&self) -> (f64, f64, f64, f64) {
        let w = self.inner.grid.window;
        (w[0], w[1], w[2], w[3])
    }

    /// Region of every grid cell as an (ny, nx) int64 array, row 0 at y0.
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let g = self.inner.grid;
        let flat: Vec<i64> = self
            .inner
            .cell_region
            .iter()
            .map(|&r| i64::from(r))
            .collect();
        flat.into_pyarray(py)
            .reshape([g.ny, g.nx])
            .map_err(|e| invalid(e.to_string()))
    }

    /// Region of each point of an (n, 2) array (points outside the window: the nearest
    /// border cell's).
    fn region_of<'py>(
        &self,
        py: Python<'py>,
        points: Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let points = crate::arrays::floats2(&points, "points")?;
        let view = points.as_array();
        if view.ncols() != 2 {
            return Err(invalid(format!(
                "points must have shape (n, 2), got {:?}",
                view.shape()
            )));
        }
        let out: Vec<i64> = view
            .rows()
            .into_iter()
            .map(|r| {
                if r[0].is_finite() && r[1].is_finite() {
                    Ok(self.inner.region_of([r[0], r[1]]).map_or(-1, i64::from))
                } else {
                    Err(invalid(format!("point ({}, {}) is not finite", r[0], r[1])))
                }
            })
            .collect::<PyResult<_>>()?;
        Ok(out.into_pyarray(py))
    }

    /// Region adjacency as (a, b, shared border in cell edges) triples.
    fn adjacency(&self) -> Vec<(usize, usize, u32)> {
        let g = self.inner.adjacency();
        g.edge_indices()
            .filter_map(|e| {
                let (a, b) = g.edge_endpoints(e)?;
                Some((a.index(), b.index(), g[e]))
            })
            .collect()
    }

    /// Outline rings of region `r` as lists of (x, y).
    fn polygons(&self, r: u32) -> PyResult<Vec<Vec<(f64, f64)>>> {
        if r as usize >= self.inner.n_regions {
            return Err(invalid(format!(
                "no region {r} (the map has {})",
                self.inner.n_regions
            )));
        }
        Ok(self
            .inner
            .polygons(r)
            .into_iter()
            .map(|ring| ring.into_iter().map(|p| (p[0], p[1])).collect())
            .collect())
    }

    /// Rebuilds a pickled map (its full serde state; see `__reduce__`).
    #[staticmethod]
    fn _from_state(state: &str, initial_regions: usize) -> PyResult<Self> {
        let inner: serge::SalientRegionMap = serde_json::from_str(state)
            .map_err(|e| invalid(format!("not a pickled SalientRegionMap: {e}")))?;
        Ok(Self {
            inner,
            initial_regions,
        })
    }

    /// Pickles as its full state (multiprocessing, Ray).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String, usize))> {
        let ctor = slf.get_type().getattr("_from_state")?;
        let me = slf.get();
        let state = serde_json::to_string(&me.inner).map_err(|e| invalid(e.to_string()))?;
        Ok((ctor, (state, me.initial_regions)))
    }

    /// The map as JSON (what `qrm serge run` writes as map.json).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner.to_json()).map_err(|e| invalid(e.to_string()))
    }

    /// The map as a learned ternary calculus (beliefs must be in a normalised triplet frame).
    #[pyo3(signature = (name = "learned", description = ""))]
    fn to_calculus(&self, name: &str, description: &str) -> PyResult<Calculus> {
        Ok(Calculus {
            inner: self
                .inner
                .to_calculus(name, description)
                .map_err(serge_err)?,
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "SalientRegionMap(n_regions={}, log_saliency={:.4}, mu={}, sigma={})",
            self.inner.n_regions, self.inner.log_saliency, self.inner.mu, self.inner.sigma
        )
    }
}

/// SERGE on beliefs given as the JSON input document.
#[pyfunction]
#[pyo3(signature = (beliefs_json, mu, sigma, trials, grid, window, seed))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn serge_run(
    py: Python<'_>,
    beliefs_json: &str,
    mu: usize,
    sigma: f64,
    trials: Option<usize>,
    grid: usize,
    window: Option<(f64, f64, f64, f64)>,
    seed: u64,
) -> PyResult<SalientRegionMap> {
    let beliefs = BeliefSet::from_json_str(beliefs_json, "beliefs").map_err(serge_err)?;
    let mut params = SergeParams::new(mu, sigma).seed(seed);
    if let Some(t) = trials {
        params = params.trials(t);
    }
    // the job `qrm serge run` runs
    let job = studies::serge::region_map::RegionMapJob {
        beliefs,
        window: window.map(|(a, b, c, d)| [a, b, c, d]),
        cells: grid,
        params,
    };
    let run = crate::pool::detach(py, move || job.run()).map_err(crate::errors::study_err)?;
    Ok(SalientRegionMap {
        inner: run.map,
        initial_regions: run.initial_regions,
    })
}

/// The thesis's cross-validation study on a generated dataset; returns JSON records.
#[pyfunction]
#[pyo3(signature = (dataset, quick, seed, progress = None))]
pub(crate) fn serge_cross_validate(
    py: Python<'_>,
    dataset: &str,
    quick: bool,
    seed: u64,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let name = dataset.to_owned();
    let records = crate::pool::watched(py, progress, move |watch| {
        let config = if quick {
            studies::serge::cross_validation::StudyConfig::quick(seed)
        } else {
            studies::serge::cross_validation::StudyConfig::full(seed)
        };
        let name = studies::serge::datasets::DatasetName::parse(&name)?;
        let data = studies::serge::study::dataset(name, &config)?;
        studies::serge::cross_validation::cross_validate(&data, &config, watch)
    })?
    .map_err(crate::errors::study_err)?;
    serde_json::to_string(&records).map_err(|e| invalid(e.to_string()))
}

/// Algorithm 3 compose table of a learned (raster) calculus, sound by construction.
/// Watched: Ctrl-C stops it, `progress(done, total)` counts raster cells.
#[pyfunction]
#[pyo3(signature = (calculus, progress = None))]
pub(crate) fn compose_cells(
    py: Python<'_>,
    calculus: &Calculus,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<std::collections::BTreeMap<String, std::collections::BTreeMap<String, Vec<String>>>> {
    let c = &calculus.inner;
    let table = crate::pool::watched(py, progress, |watch| serge::learn::compose_table(c, watch))?
        .map_err(serge_err)?;
    Ok(c.states()
        .map(|r| {
            (
                c.label(r).to_owned(),
                c.states()
                    .map(|s| {
                        (
                            c.label(s).to_owned(),
                            table
                                .get(r, s)
                                .iter()
                                .map(|t| c.label(*t).to_owned())
                                .collect(),
                        )
                    })
                    .collect(),
            )
        })
        .collect())
}
