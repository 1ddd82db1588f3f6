//! `qrm.BinaryCalculus`: a thin wrapper of `qsr_core::binary` (OPRA-m, STAR-m), and the
//! closure of binary networks.

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use qsr_core::binary::{BinaryNetwork, close_binary};

use crate::errors::{invalid, qsr};

/// A binary point calculus (`opra-M`, `star-m`) with exact converse and composition.
#[pyclass(module = "qrm", frozen, from_py_object)]
#[derive(Clone)]
pub(crate) struct BinaryCalculus {
    pub(crate) inner: qsr_core::binary::BinaryCalculus,
}

#[pymethods]
impl BinaryCalculus {
    /// `opra-M` (1 ≤ M ≤ 63; composition up to OPRA-10) or `star-m` (even m, 2 ≤ m ≤ 32).
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        Ok(Self {
            inner: qsr_core::binary::BinaryCalculus::builtin(name).map_err(qsr)?,
        })
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_owned()
    }

    #[getter]
    fn labels(&self) -> Vec<String> {
        self.inner.labels().to_vec()
    }

    #[getter]
    fn n_states(&self) -> usize {
        self.inner.n_states()
    }

    /// Relation ids of an (n, k) float64 array: OPRA k = 6 `ax ay a_heading bx by
    /// b_heading`, STAR k = 5 `ox oy reference bx by` (radians, counter-clockwise from +x).
    fn classify<'py>(
        &self,
        py: Python<'py>,
        points: Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let points = crate::arrays::floats2(&points, "points")?;
        let a = points.as_array();
        let k = self.inner.input_len();
        if a.ncols() != k {
            return Err(invalid(format!(
                "points: {} classifies rows of {k} numbers, the array has {} columns",
                self.inner.name(),
                a.ncols()
            )));
        }
        let mut ids = Vec::with_capacity(a.nrows());
        for (i, row) in a.rows().into_iter().enumerate() {
            let row: Vec<f64> = row.iter().copied().collect();
            let s = self
                .inner
                .classify_row(&row)
                .map_err(|e| invalid(format!("row {i}: {e}")))?;
            ids.push(i64::from(s.0));
        }
        Ok(ids.into_pyarray(py))
    }

    /// The composition table {r: {s: [t, ...]}} of {A:B} ∘ {B:C} → {A:C} (exact).
    fn compose(&self, py: Python<'_>) -> PyResult<qsr_core::table_text::LabelledCompose> {
        let c = &self.inner;
        let table = crate::pool::detach(py, || c.compose_table().cloned()).map_err(qsr)?;
        Ok(table.labelled(c.labels()))
    }

    /// The converse table {r: [t]}: X r Y ⇒ Y t X.
    fn converse(&self, py: Python<'_>) -> qsr_core::table_text::LabelledRows {
        let c = &self.inner;
        let table = crate::pool::detach(py, || c.converse().clone());
        table.labelled(c.labels())
    }

    /// Conceptual neighbours: {"states", "adjacent", "distance"}.
    fn neighbours<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let c = &self.inner;
        let g = crate::pool::detach(py, || c.neighbours().cloned()).map_err(qsr)?;
        crate::calculus::neighbours_dict(py, c.labels(), &g)
    }

    /// The partition of directions as SVG text.
    #[pyo3(signature = (*, width = 640))]
    fn render_svg(&self, width: u32) -> String {
        qsr_core::binary::render_binary_svg(&self.inner, width)
    }

    /// The partition drawn in a notebook.
    fn _repr_svg_(&self) -> String {
        self.render_svg(400)
    }

    /// Pickles as its name (every binary calculus is a built-in family member).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let ctor = slf.get_type().getattr("builtin")?;
        Ok((ctor, (slf.get().inner.name().to_owned(),)))
    }

    fn __repr__(&self) -> String {
        format!(
            "BinaryCalculus('{}', {} relations)",
            self.inner.name(),
            self.inner.n_states()
        )
    }
}

/// Algebraic closure of a binary network given as `[(A, B, [labels]), ...]`; returns JSON
/// `{"consistent", "constraints", "explanation"}`.
#[pyfunction]
pub(crate) fn reason_close_binary(
    py: Python<'_>,
    calculus: &Bound<'_, PyAny>,
    constraints: Vec<(String, String, Vec<String>)>,
) -> PyResult<String> {
    let a = algebra_of(calculus)?;
    let net = BinaryNetwork::from_constraints(&a, &constraints).map_err(qsr)?;
    let closed = crate::pool::detach(py, || close_binary(net)).map_err(qsr)?;
    Ok(serde_json::json!({
        "consistent": closed.is_consistent(),
        "constraints": closed.network.constraints_json(),
        "explanation": closed.describe(),
    })
    .to_string())
}

/// One law of a relation algebra: its statement, whether it holds (None: not checked), and
/// a witness where it fails.
type LawRow = (String, Option<bool>, Option<String>);

/// A binary calculus's reasoning tables, derived (OPRA-m, STAR-m) or read from GQR's or
/// SparQ's files (RCC-8, Allen, the point algebra, ...).
#[pyclass(module = "qrm", frozen, from_py_object)]
#[derive(Clone)]
pub(crate) struct BinaryAlgebra {
    pub(crate) inner: qsr_core::binary::BinaryAlgebra,
}

#[pymethods]
impl BinaryAlgebra {
    /// A GQR calculus: its `.spec` file (tables relative to the spec's directory).
    #[staticmethod]
    fn from_gqr(path: std::path::PathBuf) -> PyResult<Self> {
        Ok(Self {
            inner: qsr_core::binary::BinaryAlgebra::from_gqr_spec(&path).map_err(qsr)?,
        })
    }

    /// A SparQ `def-calculus` file (binary calculi).
    #[staticmethod]
    fn from_sparq(path: std::path::PathBuf) -> PyResult<Self> {
        Ok(Self {
            inner: qsr_core::binary::BinaryAlgebra::from_sparq_file(&path).map_err(qsr)?,
        })
    }

    /// Tables as the texts of GQR's files.
    #[staticmethod]
    #[pyo3(signature = (name, converse, composition, identity, weights = None))]
    fn from_gqr_tables(
        name: &str,
        converse: &str,
        composition: &str,
        identity: &str,
        weights: Option<&str>,
    ) -> PyResult<Self> {
        Ok(Self {
            inner: qsr_core::binary::BinaryAlgebra::from_gqr_tables(
                name,
                converse,
                composition,
                identity,
                weights,
            )
            .map_err(qsr)?,
        })
    }

    /// The algebra of a built-in binary calculus.
    #[staticmethod]
    fn of(calculus: &BinaryCalculus) -> Self {
        Self {
            inner: qsr_core::binary::AsBinaryAlgebra::binary_algebra(&calculus.inner),
        }
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_owned()
    }

    #[getter]
    fn labels(&self) -> Vec<String> {
        self.inner.labels().to_vec()
    }

    #[getter]
    fn n_states(&self) -> usize {
        self.inner.n_states()
    }

    #[getter]
    fn identity(&self) -> Option<String> {
        self.inner
            .identity()
            .map(|i| self.inner.label(i).to_owned())
    }

    /// Which laws of a relation algebra the tables obey: `[(law, holds, witness), ...]`;
    /// `holds` is None when not checked.
    fn laws(&self, py: Python<'_>) -> PyResult<Vec<LawRow>> {
        let a = &self.inner;
        let check = crate::pool::detach(py, || a.check()).map_err(qsr)?;
        Ok(check
            .laws
            .into_iter()
            .map(|l| (l.law.describe().to_owned(), l.holds, l.witness))
            .collect())
    }

    /// The tables in GQR's text forms: `(converse, composition, weights, spec)`.
    fn to_gqr_tables(&self) -> PyResult<(String, String, String, String)> {
        let t = self.inner.to_gqr_tables().map_err(qsr)?;
        Ok((t.converse, t.composition, t.weights, t.spec))
    }

    /// Pickles as its tables (a loaded calculus has no name to look up).
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (String, String, String, String, String))> {
        let a = &slf.get().inner;
        let t = a.to_gqr_tables().map_err(qsr)?;
        let identity = a
            .identity()
            .map(|i| a.label(i).to_owned())
            .unwrap_or_default();
        let ctor = slf.get_type().getattr("from_gqr_tables")?;
        Ok((
            ctor,
            (
                a.name().to_owned(),
                t.converse,
                t.composition,
                identity,
                t.weights,
            ),
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "BinaryAlgebra('{}', {} relations)",
            self.inner.name(),
            self.inner.n_states()
        )
    }
}

/// The algebra of a `BinaryCalculus` or a `BinaryAlgebra`.
fn algebra_of(calculus: &Bound<'_, PyAny>) -> PyResult<qsr_core::binary::BinaryAlgebra> {
    if let Ok(c) = calculus.extract::<BinaryCalculus>() {
        return Ok(qsr_core::binary::AsBinaryAlgebra::binary_algebra(&c.inner));
    }
    if let Ok(a) = calculus.extract::<BinaryAlgebra>() {
        return Ok(a.inner);
    }
    Err(invalid(format!(
        "calculus: a BinaryCalculus or a BinaryAlgebra, not {}",
        calculus.get_type().name()?
    )))
}

/// Consistency of a binary network by search (GQR's `consistency`); returns JSON
/// `{"status": "consistent" | "inconsistent" | "unknown", "constraints", "nodes"}`. The split
/// set is a GQR cover-set file (`split_path`) or its members as label lists (`split_sets`).
#[pyfunction]
#[pyo3(signature = (calculus, constraints, *, max_nodes = 1_000_000, split_path = None, split_sets = None, restarts = true))]
pub(crate) fn reason_solve_binary(
    py: Python<'_>,
    calculus: &Bound<'_, PyAny>,
    constraints: Vec<(String, String, Vec<String>)>,
    max_nodes: u64,
    split_path: Option<std::path::PathBuf>,
    split_sets: Option<Vec<Vec<String>>>,
    restarts: bool,
) -> PyResult<String> {
    use qsr_core::binary::{SolveOptions, SolveOutcome, SplitSet, solve_binary};
    let a = algebra_of(calculus)?;
    let net = BinaryNetwork::from_constraints(&a, &constraints).map_err(qsr)?;
    let split = match (split_path, split_sets) {
        (Some(path), None) => Some(SplitSet::from_gqr_file(&a, &path).map_err(qsr)?),
        (None, Some(sets)) => {
            let text: String = sets
                .iter()
                .map(|m| format!("( {} )\n", m.join(" ")))
                .collect();
            Some(SplitSet::from_gqr_str(&a, &text, "split").map_err(qsr)?)
        }
        (None, None) => None,
        (Some(_), Some(_)) => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "give the split set as a file or as sets, not both",
            ));
        }
    };
    let options = SolveOptions {
        max_nodes,
        split,
        restarts,
    };
    let solved = crate::pool::detach(py, || solve_binary(net, &options)).map_err(qsr)?;
    let (status, constraints) = match &solved.outcome {
        SolveOutcome::Consistent(s) => ("consistent", Some(s.constraints_json())),
        SolveOutcome::Inconsistent => ("inconsistent", None),
        SolveOutcome::Unknown => ("unknown", None),
    };
    Ok(
        serde_json::json!({"status": status, "constraints": constraints, "nodes": solved.nodes})
            .to_string(),
    )
}

/// The networks of a GQR `.csp` text: JSON `[{"name", "points", "constraints"}, ...]`.
#[pyfunction]
pub(crate) fn reason_read_csp(calculus: &Bound<'_, PyAny>, text: &str) -> PyResult<String> {
    let a = algebra_of(calculus)?;
    let nets = qsr_core::binary::from_gqr_csp_str(&a, text).map_err(qsr)?;
    let out: Vec<serde_json::Value> = nets
        .iter()
        .map(|g| {
            serde_json::json!({
                "name": g.name,
                "points": g.network.names(),
                "constraints": g.network.constraints_json(),
            })
        })
        .collect();
    Ok(serde_json::Value::Array(out).to_string())
}
