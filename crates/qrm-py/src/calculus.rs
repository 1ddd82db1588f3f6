//! `qrm.Calculus`: a thin wrapper of `qsr_core::Calculus`.

use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use qsr_core::{ComposeOptions, Permutation};
use rayon::prelude::*;

use crate::errors::{invalid, qsr};

/// Names of the built-in calculi.
#[pyfunction]
pub(crate) fn builtin_names() -> Vec<&'static str> {
    qsr_core::BUILTIN_NAMES.to_vec()
}

/// A qualitative calculus (built-in, from a spec file, or learned).
#[pyclass(module = "qrm", frozen, from_py_object)]
#[derive(Clone)]
pub(crate) struct Calculus {
    pub(crate) inner: qsr_core::Calculus,
}

impl Calculus {
    /// Classification without copying the input when it is C-contiguous (the usual case):
    /// the array's memory is read as rows in place, with the interpreter released.
    fn classify_ids(
        &self,
        py: Python<'_>,
        points: &PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Vec<i64>> {
        let view = points.as_array();
        let k = self.inner.frame().input_len();
        if view.ncols() != k {
            return Err(invalid(format!(
                "points: calculus `{}` takes rows of {k} numbers, got an array of shape {:?}",
                self.inner.name(),
                view.shape()
            )));
        }
        let calc = &self.inner;
        // `view.as_slice()` is `Some` only for C order: the numpy crate's `as_slice` also
        // hands out a Fortran-ordered array's memory, whose rows are not contiguous
        // (regression: a Fortran-ordered array was classified column-wise).
        let result: Result<Vec<i64>, qsr_core::QsrError> = match (k, view.as_slice()) {
            (6, Some(flat)) => {
                let (rows, _) = flat.as_chunks::<6>();
                crate::pool::detach(py, || {
                    let mut out = vec![0i64; rows.len()];
                    calc.classify_triplets_as(rows, &mut out).map(|()| out)
                })
            }
            _ => {
                let rows: Vec<Vec<f64>> = view.rows().into_iter().map(|r| r.to_vec()).collect();
                crate::pool::detach(py, || {
                    rows.iter()
                        .enumerate()
                        .map(|(i, r)| {
                            calc.classify_row(r)
                                .map(|s| i64::from(s.0))
                                .map_err(|e| annotate(i, e))
                        })
                        .collect()
                })
            }
        };
        result.map_err(qsr)
    }
}

/// Ids per parallel work item: a cache-resident id buffer, and enough items that both cores
/// stay busy on inputs of a few hundred thousand triplets.
const CHUNK: usize = 4096;

/// Classifies rows into `dst`, chunks in parallel, each state written as i64 by the kernel
/// itself (`classify_triplets_as`: no buffer of ids widened in a second pass, which cost
/// 0.3–0.8 ns a triplet from memory). Every id depends on its row alone, so the result does
/// not depend on the thread count.
fn classify_into(
    calc: &qsr_core::Calculus,
    rows: &[[f64; 6]],
    dst: &mut [i64],
) -> Result<(), qsr_core::QsrError> {
    let all_valid: Result<(), ()> = rows
        .par_chunks(CHUNK)
        .zip(dst.par_chunks_mut(CHUNK))
        .try_for_each(|(r, d)| calc.classify_triplets_as(r, d).map_err(|_| ()));
    if all_valid.is_err() {
        // Whichever worker met a bad row, report the first one of the whole array.
        return classify_each(calc, rows.len(), |i| rows[i], dst);
    }
    Ok(())
}

/// Fills `out` (or a new int64 array of length `n`) through `fill`, run with the interpreter
/// released in this process's pool.
fn write_ids<'py>(
    py: Python<'py>,
    out: Option<Bound<'py, PyArray1<i64>>>,
    n: usize,
    fill: impl FnOnce(&mut [i64]) -> Result<(), qsr_core::QsrError> + Send,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let target = match out {
        Some(o) => o,
        None => PyArray1::<i64>::zeros(py, n, false),
    };
    {
        let mut rw = target.try_readwrite()?;
        let dst = rw
            .as_slice_mut()
            .map_err(|e| invalid(format!("out must be contiguous: {e}")))?;
        crate::pool::detach(py, || fill(dst)).map_err(qsr)?;
    }
    Ok(target)
}

/// Row by row, failing on the first bad row with its index: the slow path that names it.
fn classify_each(
    calc: &qsr_core::Calculus,
    n: usize,
    row: impl Fn(usize) -> [f64; 6],
    dst: &mut [i64],
) -> Result<(), qsr_core::QsrError> {
    for (i, d) in dst.iter_mut().enumerate().take(n) {
        *d = i64::from(calc.classify_row(&row(i)).map_err(|e| annotate(i, e))?.0);
    }
    Ok(())
}

/// Prefixes a row error with its index, keeping its kind.
fn annotate(i: usize, e: qsr_core::QsrError) -> qsr_core::QsrError {
    match e {
        qsr_core::QsrError::DegenerateFrame { reason } => qsr_core::QsrError::DegenerateFrame {
            reason: format!("row {i}: {reason}"),
        },
        qsr_core::QsrError::NonFinite { what } => qsr_core::QsrError::NonFinite {
            what: format!("row {i}: {what}"),
        },
        other => other,
    }
}

#[pymethods]
impl Calculus {
    /// A built-in calculus by name.
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        qsr_core::Calculus::builtin(name)
            .map(|inner| Self { inner })
            .map_err(qsr)
    }

    /// A calculus from a TOML or JSON spec file.
    #[staticmethod]
    fn from_spec(path: std::path::PathBuf) -> PyResult<Self> {
        qsr_core::Calculus::from_path(&path)
            .map(|inner| Self { inner })
            .map_err(qsr)
    }

    /// A calculus from spec text (`format` is "toml" or "json").
    #[staticmethod]
    #[pyo3(signature = (text, *, format = "toml"))]
    fn from_spec_text(text: &str, format: &str) -> PyResult<Self> {
        let inner = match format {
            "toml" => qsr_core::Calculus::from_toml_str(text),
            "json" => qsr_core::Calculus::from_json_str(text),
            other => {
                return Err(invalid(format!(
                    "format must be \"toml\" or \"json\", got {other:?}"
                )));
            }
        };
        inner.map(|inner| Self { inner }).map_err(qsr)
    }

    /// Name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_owned()
    }

    /// Frame kind: "ternary", "binary-oriented" or "extended".
    #[getter]
    fn frame(&self) -> &'static str {
        self.inner.frame().as_str()
    }

    /// State labels in id order.
    #[getter]
    fn labels(&self) -> Vec<String> {
        self.inner.labels().to_vec()
    }

    /// Number of states.
    #[getter]
    fn n_states(&self) -> usize {
        self.inner.n_states()
    }

    /// ln Q, the entropy of a uniform belief.
    #[getter]
    fn max_entropy(&self) -> f64 {
        self.inner.max_entropy()
    }

    /// State ids of an (n, k) float64 array of configurations (k = 6 ternary
    /// `ax ay bx by cx cy`, 5 binary `ox oy yaw cx cy`, 10 extended). With `out` (an int64
    /// array of length n, NumPy style) the ids are written there and nothing is allocated.
    #[pyo3(signature = (points, *, out = None))]
    fn classify<'py>(
        &self,
        py: Python<'py>,
        points: Bound<'py, PyAny>,
        out: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let points = crate::arrays::floats2(&points, "points")?;
        let n = points.as_array().nrows();
        let out = out.map(|o| crate::arrays::out_ids(o, n)).transpose()?;
        let k = self.inner.frame().input_len();
        let view = points.as_array();
        // checked before the fast path, which reads the memory in rows of six (regression:
        // an (n, 5) array was read as rows of six numbers)
        if view.ncols() != k {
            return Err(invalid(format!(
                "points: calculus `{}` takes rows of {k} numbers, got an array of shape {:?}",
                self.inner.name(),
                view.shape()
            )));
        }
        let (Some(flat), 6) = (view.as_slice(), k) else {
            let ids = self.classify_ids(py, &points)?;
            return match out {
                None => Ok(ids.into_pyarray(py)),
                Some(o) => {
                    o.try_readwrite()?
                        .as_slice_mut()
                        .map_err(|e| invalid(e.to_string()))?
                        .copy_from_slice(&ids);
                    Ok(o)
                }
            };
        };
        let (rows, _) = flat.as_chunks::<6>();
        let calc = &self.inner;
        write_ids(py, out, n, |dst| classify_into(calc, rows, dst))
    }

    /// State ids of n ternary configurations given as six columns (a = (ax, ay), b, c; each
    /// of length n): how data often arrives — columns of a data frame, the samples of a
    /// filter — read in place when they are contiguous float64, with no (n, 6) array built.
    /// `out` as in `classify`.
    #[pyo3(signature = (ax, ay, bx, by, cx, cy, *, out = None))]
    #[allow(clippy::too_many_arguments)] // the six columns of a ternary configuration
    fn classify_columns<'py>(
        &self,
        py: Python<'py>,
        ax: Bound<'py, PyAny>,
        ay: Bound<'py, PyAny>,
        bx: Bound<'py, PyAny>,
        by: Bound<'py, PyAny>,
        cx: Bound<'py, PyAny>,
        cy: Bound<'py, PyAny>,
        out: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        if self.inner.frame().input_len() != 6 {
            return Err(invalid(format!(
                "classify_columns: calculus `{}` is not ternary; use classify with rows",
                self.inner.name()
            )));
        }
        let names = ["ax", "ay", "bx", "by", "cx", "cy"];
        let arrays = [&ax, &ay, &bx, &by, &cx, &cy]
            .iter()
            .zip(names)
            .map(|(a, name)| crate::arrays::floats1(a, name))
            .collect::<PyResult<Vec<_>>>()?;
        let n = arrays[0].len();
        if let Some((name, a)) = names.iter().zip(&arrays).find(|(_, a)| a.len() != n) {
            return Err(invalid(format!(
                "classify_columns: ax has {n} values but {name} has {}",
                a.len()
            )));
        }
        // In place when contiguous; a strided column (e.g. `t[:, 0]`) is copied once.
        let cols: Vec<std::borrow::Cow<'_, [f64]>> = arrays
            .iter()
            .map(|a| {
                a.as_slice().map_or_else(
                    |_| std::borrow::Cow::Owned(a.as_array().to_vec()),
                    std::borrow::Cow::Borrowed,
                )
            })
            .collect();
        let out = out.map(|o| crate::arrays::out_ids(o, n)).transpose()?;
        let calc = &self.inner;
        let c = &cols;
        let row = |i: usize| [c[0][i], c[1][i], c[2][i], c[3][i], c[4][i], c[5][i]];
        write_ids(py, out, n, |dst| {
            let all_valid: Result<(), ()> =
                dst.par_chunks_mut(CHUNK)
                    .enumerate()
                    .try_for_each(|(k, d)| {
                        let r = k * CHUNK..k * CHUNK + d.len();
                        let col = |j: usize| &c[j][r.clone()];
                        calc.classify_columns_as(
                            (col(0), col(1)),
                            (col(2), col(3)),
                            (col(4), col(5)),
                            d,
                        )
                        .map_err(|_| ())
                    });
            match all_valid {
                Ok(()) => Ok(()),
                Err(()) => classify_each(calc, n, row, dst),
            }
        })
    }

    /// Labels of classified configurations (see `classify`).
    fn classify_labels<'py>(
        &self,
        py: Python<'py>,
        points: Bound<'py, PyAny>,
    ) -> PyResult<Vec<String>> {
        let ids = self.classify_ids(py, &crate::arrays::floats2(&points, "points")?)?;
        Ok(ids
            .iter()
            .map(|i| self.inner.labels()[*i as usize].clone())
            .collect())
    }

    /// Conceptual neighbours: {"states", "adjacent", "distance"} (distance matrix in state
    /// order, None for unconnected pairs).
    fn neighbours<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let g = crate::pool::detach(py, || self.inner.neighbours().clone());
        neighbours_dict(py, self.inner.labels(), &g)
    }

    /// Composition table {r: {s: [t, ...]}} of {AB:C} ∘ {BC:D} → {AB:D}; `generic=True` for
    /// configurations in general position only.
    #[pyo3(signature = (*, generic = false))]
    fn compose(
        &self,
        py: Python<'_>,
        generic: bool,
    ) -> PyResult<qsr_core::table_text::LabelledCompose> {
        let table = crate::pool::detach(py, || {
            if generic {
                self.inner.compose_table_with(&ComposeOptions::generic())
            } else {
                self.inner.compose_table().cloned()
            }
        })
        .map_err(qsr)?;
        Ok(table.labelled(self.inner.labels()))
    }

    /// A permutation table {r: [t, ...]}; `op` is inverse, shortcut, shortcut-inverse,
    /// homing or homing-inverse.
    #[pyo3(signature = (op, *, generic = false))]
    fn permute(
        &self,
        py: Python<'_>,
        op: &str,
        generic: bool,
    ) -> PyResult<qsr_core::table_text::LabelledRows> {
        let op: Permutation = op.parse().map_err(qsr)?;
        let table =
            crate::pool::detach(py, || self.inner.permutation_with(op, !generic)).map_err(qsr)?;
        Ok(table.labelled(self.inner.labels()))
    }

    /// For each state of this calculus, the state of `coarse` it merges into (int array).
    fn merge_map<'py>(
        &self,
        py: Python<'py>,
        coarse: &Calculus,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let m = crate::pool::detach(py, || self.inner.merge_map(&coarse.inner)).map_err(qsr)?;
        Ok(m.as_slice()
            .iter()
            .map(|s| i64::from(s.0))
            .collect::<Vec<_>>()
            .into_pyarray(py))
    }

    /// The spec as TOML text.
    fn spec_toml(&self) -> PyResult<String> {
        self.inner.spec().to_toml_string().map_err(qsr)
    }

    /// An SVG picture of the partition.
    #[pyo3(signature = (*, width = 640))]
    fn render_svg(&self, width: u32) -> PyResult<String> {
        qsr_core::render_svg(
            &self.inner,
            &qsr_core::RenderOptions {
                width,
                ..qsr_core::RenderOptions::default()
            },
        )
        .map_err(qsr)
    }

    /// The partition drawn in a notebook.
    fn _repr_svg_(&self) -> PyResult<String> {
        self.render_svg(400)
    }

    /// Pickles as its spec (multiprocessing, Ray): `Calculus.from_spec_text(spec_toml)`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let ctor = slf.get_type().getattr("from_spec_text")?;
        Ok((ctor, (slf.get().spec_toml()?,)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Calculus({:?}, {} states, {})",
            self.inner.name(),
            self.inner.n_states(),
            self.inner.frame().as_str()
        )
    }
}

/// `{"states", "adjacent", "distance"}` of a neighbour graph (ternary and binary calculi).
pub(crate) fn neighbours_dict<'py>(
    py: Python<'py>,
    labels: &[String],
    g: &qsr_core::NeighbourGraph,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let d = pyo3::types::PyDict::new(py);
    d.set_item("states", labels.to_vec())?;
    let adjacent: Vec<(String, String)> = g
        .edges()
        .iter()
        .map(|(a, b)| (labels[a.index()].clone(), labels[b.index()].clone()))
        .collect();
    d.set_item("adjacent", adjacent)?;
    d.set_item("distance", g.distance_matrix().to_vec())?;
    Ok(d)
}
