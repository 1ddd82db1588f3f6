//! Array arguments received the way NumPy functions receive them.
//!
//! A Python user passes whatever NumPy reads as numbers — a float64 array, a float32 or int64
//! array, a list of lists — and expects `np.asarray` semantics: no copy when the array already
//! has the dtype, one conversion otherwise. [`floats2`] and [`ints1`] do that for a named
//! argument, and each error names the argument, what was expected (dtype kind, dimensions)
//! and what came.
//!
//! What is refused, and why: booleans, complex numbers, strings and objects are not
//! coordinates (NumPy would cast some of them, silently dropping an imaginary part or turning
//! `True` into 1.0); floats are not landmark ids (a cast would truncate 1.5 to 1).

use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::Borrowed;
use pyo3::prelude::*;

use crate::errors::InvalidType;

/// `np.asarray(obj)`, its dtype kind and shape; an `InvalidType` (a TypeError) naming `expected` if NumPy cannot
/// read it as one array.
fn as_array<'py>(
    obj: Borrowed<'_, 'py, PyAny>,
    expected: &str,
) -> PyResult<(Bound<'py, PyAny>, String, Vec<usize>)> {
    let py = obj.py();
    let array = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| {
            InvalidType::new_err(format!(
                "expected {expected}; NumPy cannot read this {} as one array ({e})",
                type_name(&obj)
            ))
        })?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    Ok((array, kind, shape))
}

fn type_name(obj: &Borrowed<'_, '_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "object".to_owned(), |n| n.to_string())
}

fn dtype_name(array: &Bound<'_, PyAny>) -> String {
    array
        .getattr("dtype")
        .and_then(|d| d.str())
        .map_or_else(|_| "?".to_owned(), |s| s.to_string())
}

/// A shape as Python prints it: `(3,)`, `(2, 6)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// `np.asarray(obj).astype(float64)` when it holds real numbers (an empty array holds no
/// other kind) in `ndim` dimensions; otherwise an `InvalidType` saying `expected` and what came.
fn floats_nd<'py>(
    obj: &Bound<'py, PyAny>,
    expected: &str,
    ndim: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let (array, kind, shape) = as_array(obj.as_borrowed(), expected)?;
    let empty = shape.iter().product::<usize>() == 0;
    if !(matches!(kind.as_str(), "f" | "i" | "u") || empty) {
        return Err(InvalidType::new_err(format!(
            "{expected}, got dtype {}",
            dtype_name(&array)
        )));
    }
    if shape.len() != ndim {
        return Err(InvalidType::new_err(format!(
            "{expected}, got shape {}",
            shape_text(&shape)
        )));
    }
    array.call_method1("astype", ("float64",))
}

/// Argument `arg` as a 2-D float64 array (shape `(n, k)`), from anything NumPy reads as
/// real numbers.
pub(crate) fn floats2<'py>(
    obj: &Bound<'py, PyAny>,
    arg: &str,
) -> PyResult<PyReadonlyArray2<'py, f64>> {
    if let Ok(a) = obj.cast::<PyArray2<f64>>() {
        return Ok(a.try_readonly()?);
    }
    let expected = format!("{arg}: expected a 2-D array of real numbers, shape (n, k)");
    let converted = floats_nd(obj, &expected, 2)?;
    Ok(converted.cast_into::<PyArray2<f64>>()?.try_readonly()?)
}

/// Argument `arg` as a 1-D float64 array (shape `(n,)`), from anything NumPy reads as real
/// numbers (a column of a data frame, a float32 array, a list).
pub(crate) fn floats1<'py>(
    obj: &Bound<'py, PyAny>,
    arg: &str,
) -> PyResult<PyReadonlyArray1<'py, f64>> {
    if let Ok(a) = obj.cast::<PyArray1<f64>>() {
        return Ok(a.try_readonly()?);
    }
    let expected = format!("{arg}: expected a 1-D array of real numbers, shape (n,)");
    let converted = floats_nd(obj, &expected, 1)?;
    Ok(converted.cast_into::<PyArray1<f64>>()?.try_readonly()?)
}

/// Argument `arg` as a 1-D int64 array (shape `(n,)`), from anything NumPy reads as integers.
pub(crate) fn ints1<'py>(
    obj: &Bound<'py, PyAny>,
    arg: &str,
) -> PyResult<PyReadonlyArray1<'py, i64>> {
    if let Ok(a) = obj.cast::<PyArray1<i64>>() {
        return Ok(a.try_readonly()?);
    }
    let expected = format!("{arg}: expected a 1-D array of integers, shape (n,)");
    let (array, kind, shape) = as_array(obj.as_borrowed(), &expected)?;
    let empty = shape.iter().product::<usize>() == 0;
    // An empty list reads as float64 in NumPy; it holds no float.
    if !(matches!(kind.as_str(), "i" | "u") || empty) {
        return Err(InvalidType::new_err(format!(
            "{expected}, got dtype {}",
            dtype_name(&array)
        )));
    }
    if shape.len() != 1 {
        return Err(InvalidType::new_err(format!(
            "{expected}, got shape {}",
            shape_text(&shape)
        )));
    }
    if kind == "u" && !empty {
        // uint64 beyond int64 would wrap in the cast
        let max: u64 = array.call_method0("max")?.extract()?;
        if i64::try_from(max).is_err() {
            return Err(InvalidType::new_err(format!(
                "{expected}, got {max}, beyond int64"
            )));
        }
    }
    let converted = array.call_method1("astype", ("int64",))?;
    Ok(converted.cast_into::<PyArray1<i64>>()?.try_readonly()?)
}

/// An `out=` argument: a writable, contiguous int64 array of length `n`, or an `InvalidType` that
/// says so.
pub(crate) fn out_ids<'py>(
    out: Bound<'py, PyAny>,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let expected = format!("out must be a writable int64 array of shape ({n},)");
    let got = || {
        let shape: Option<Vec<usize>> = out.getattr("shape").and_then(|s| s.extract()).ok();
        match shape {
            Some(shape) => format!(
                "a {} array of shape {}",
                dtype_name(&out),
                shape_text(&shape)
            ),
            None => out
                .get_type()
                .name()
                .map_or_else(|_| "an object".to_owned(), |t| format!("a {t}")),
        }
    };
    let Ok(array) = out.cast::<PyArray1<i64>>() else {
        return Err(InvalidType::new_err(format!("{expected}, got {}", got())));
    };
    if array.len() != n {
        return Err(InvalidType::new_err(format!("{expected}, got {}", got())));
    }
    if array.try_readwrite().is_err() {
        return Err(InvalidType::new_err(format!(
            "{expected}, got a read-only or borrowed array"
        )));
    }
    Ok(array.clone())
}
