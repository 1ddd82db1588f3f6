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
    calculus: &BinaryCalculus,
    constraints: Vec<(String, String, Vec<String>)>,
) -> PyResult<String> {
    let c = &calculus.inner;
    let net = BinaryNetwork::from_constraints(c, &constraints).map_err(qsr)?;
    let closed = crate::pool::detach(py, || close_binary(net)).map_err(qsr)?;
    Ok(serde_json::json!({
        "consistent": closed.is_consistent(),
        "constraints": closed.network.constraints_json(),
        "explanation": closed.describe(),
    })
    .to_string())
}
