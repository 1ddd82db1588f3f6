//! The exception hierarchy and the mapping from the Rust error enums.
//!
//! ```text
//! QrmError                                   (Exception)
//! ├── InvalidInput        + ValueError          bad numbers, shapes, covariances, arity, configuration
//! │   ├── DegenerateFrame                       coincident reference points / landmarks
//! │   └── InvalidType     + TypeError           an argument of a type or dtype qrm does not take
//! ├── SpecError           + ValueError          malformed or invalid calculus spec, unknown calculus/state/op
//! ├── UnsupportedError    + NotImplementedError an operation a calculus does not define
//! ├── FormatError         + ValueError          malformed saved map or input file
//! └── IoError             + OSError             a file that cannot be read or written
//! ```

use pqrm::PqrmError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyModule, PyType};
use qsr_core::QsrError;

/// The hierarchy as Python source. Each class also derives from the builtin a Python user
/// would catch for that kind of failure (`except ValueError` catches a bad input, `except
/// OSError` a missing file), which `pyo3::create_exception!` cannot express: it takes one base.
const HIERARCHY: &std::ffi::CStr = cr#"
class QrmError(Exception):
    """Base class of every qrm error."""
    __module__ = "qrm"

class InvalidInput(QrmError, ValueError):
    """Bad numbers, shapes, covariances or settings (also a ValueError)."""
    __module__ = "qrm"

class DegenerateFrame(InvalidInput):
    """Coincident reference points or landmarks (also a ValueError)."""
    __module__ = "qrm"

class InvalidType(InvalidInput, TypeError):
    """An argument of a type or dtype qrm does not take: a string array, float ids, a 1-D
    array where rows are asked for, an int32 `out=` (an InvalidInput, so also a ValueError,
    and a TypeError, what NumPy raises for such arguments)."""
    __module__ = "qrm"

class SpecError(QrmError, ValueError):
    """A calculus spec or name that is not valid (also a ValueError)."""
    __module__ = "qrm"

class UnsupportedError(QrmError, NotImplementedError):
    """An operation the calculus does not define (also a NotImplementedError)."""
    __module__ = "qrm"

class FormatError(QrmError, ValueError):
    """A malformed saved map or input file (also a ValueError)."""
    __module__ = "qrm"

class IoError(QrmError, OSError):
    """A file that cannot be read or written (also an OSError)."""
    __module__ = "qrm"
"#;

/// The class names, in the order they are registered.
const CLASSES: [&str; 8] = [
    "QrmError",
    "InvalidInput",
    "DegenerateFrame",
    "InvalidType",
    "SpecError",
    "UnsupportedError",
    "FormatError",
    "IoError",
];

static MODULE: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

/// The module holding the classes, built once per interpreter.
fn hierarchy(py: Python<'_>) -> PyResult<&Bound<'_, PyModule>> {
    MODULE
        .get_or_try_init(py, || {
            PyModule::from_code(py, HIERARCHY, c"qrm/_errors.py", c"qrm._errors").map(Bound::unbind)
        })
        .map(|m| m.bind(py))
}

/// The class called `name`.
fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyType>> {
    Ok(hierarchy(py)?.getattr(name)?.cast_into::<PyType>()?)
}

/// One zero-sized handle per class, with the `new_err` constructor the rest of the crate uses.
macro_rules! exception {
    ($($name:ident),*) => {$(
        pub(crate) struct $name;
        impl $name {
            pub(crate) fn new_err(msg: impl Into<String>) -> PyErr {
                let msg = msg.into();
                Python::attach(|py| match class(py, stringify!($name)) {
                    Ok(ty) => PyErr::from_type(ty, msg),
                    Err(e) => e,
                })
            }
        }
    )*};
}
exception!(
    QrmError,
    InvalidInput,
    DegenerateFrame,
    InvalidType,
    SpecError,
    UnsupportedError,
    FormatError,
    IoError
);

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    for name in CLASSES {
        m.add(name, class(py, name)?)?;
    }
    Ok(())
}

/// An error and its causes, `a: b: c` (errors keep their cause out of their own text, as
/// the standard library's convention asks, so it is not printed twice by chain printers).
pub(crate) fn chain(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        msg.push_str(": ");
        msg.push_str(&c.to_string());
        cause = c.source();
    }
    msg
}

/// The Python exception for a calculus-layer error.
pub(crate) fn qsr(e: QsrError) -> PyErr {
    let msg = chain(&e);
    match e {
        QsrError::DegenerateFrame { .. } => DegenerateFrame::new_err(msg),
        QsrError::NonFinite { .. } | QsrError::Arity(_) | QsrError::TooLarge { .. } => {
            InvalidInput::new_err(msg)
        }
        QsrError::Spec { .. }
        | QsrError::UnknownCalculus { .. }
        | QsrError::UnknownState { .. }
        | QsrError::UnknownOperation { .. } => SpecError::new_err(msg),
        QsrError::Unsupported { .. } | QsrError::NotARefinement { .. } => {
            UnsupportedError::new_err(msg)
        }
        QsrError::Io { .. } => io_error(msg),
        QsrError::Network { .. } => FormatError::new_err(msg),
        _ => QrmError::new_err(msg),
    }
}

/// The Python exception for a mapper error.
pub(crate) fn pqrm(e: PqrmError) -> PyErr {
    let msg = chain(&e);
    match e {
        PqrmError::Calculus(inner) => qsr(inner),
        PqrmError::CoincidentLandmarks { .. } => DegenerateFrame::new_err(msg),
        PqrmError::NonFinite(_)
        | PqrmError::BadCovariance { .. }
        | PqrmError::DuplicateLandmark(_)
        | PqrmError::InvalidConfig(_)
        | PqrmError::Mismatch(_) => InvalidInput::new_err(msg),
        PqrmError::Parse { .. } | PqrmError::Format(_) => FormatError::new_err(msg),
        PqrmError::Io { .. } => io_error(msg),
        _ => QrmError::new_err(msg),
    }
}

/// The Python exception for a robot-log error: the file is broken → `FormatError`; the file
/// is fine but not what was asked (topic, schema, values) → `InvalidInput`.
pub(crate) fn log(e: qrm_log::LogError) -> PyErr {
    use qrm_log::LogError as L;
    let msg = chain(&e);
    match e {
        L::Io { .. } | L::Write { .. } => io_error(msg),
        L::Damaged { .. } | L::Message { .. } => FormatError::new_err(msg),
        _ => InvalidInput::new_err(msg),
    }
}

fn io_error(msg: String) -> PyErr {
    IoError::new_err(msg)
}

/// An `InvalidInput` with a message.
pub(crate) fn invalid(msg: impl Into<String>) -> PyErr {
    InvalidInput::new_err(msg.into())
}

/// The Python exception for a Q-Link error.
pub(crate) fn qlink_err(e: qlink::QlinkError) -> PyErr {
    let msg = chain(&e);
    match e {
        qlink::QlinkError::Calculus(inner) => qsr(inner),
        qlink::QlinkError::Pqrm(inner) => pqrm(inner),
        qlink::QlinkError::UnknownLandmark(_)
        | qlink::QlinkError::SameStartGoal(_)
        | qlink::QlinkError::EmptyMap
        | qlink::QlinkError::InvalidParameter(_) => InvalidInput::new_err(msg),
        qlink::QlinkError::NoPath { .. } => QrmError::new_err(msg),
        qlink::QlinkError::Unsupported(_) => UnsupportedError::new_err(msg),
        _ => QrmError::new_err(msg),
    }
}

/// The Python exception for a SERGE error.
pub(crate) fn serge_err(e: serge::SergeError) -> PyErr {
    let msg = chain(&e);
    match e {
        serge::SergeError::Calculus(inner) => qsr(inner),
        serge::SergeError::Parse { .. } => FormatError::new_err(msg),
        serge::SergeError::Io { .. } => IoError::new_err(msg),
        _ => InvalidInput::new_err(msg),
    }
}

/// The Python exception for a simulator error.
pub(crate) fn sim_err(e: sim2d::SimError) -> PyErr {
    match e {
        sim2d::SimError::UnknownScenario(_) => SpecError::new_err(e.to_string()),
        other => invalid(other.to_string()),
    }
}

/// The Python exception for a study's error: its cause's, or `InvalidInput` for a refused
/// configuration.
pub(crate) fn study_err(e: studies::StudyError) -> PyErr {
    let msg = chain(&e);
    match e {
        studies::StudyError::Qlink(inner) => qlink_err(inner),
        studies::StudyError::Serge(inner) => serge_err(inner),
        studies::StudyError::Pqrm(inner) => pqrm(inner),
        studies::StudyError::Calculus(inner) => qsr(inner),
        studies::StudyError::Sim(inner) => sim_err(inner),
        studies::StudyError::Log(inner) => log(inner),
        studies::StudyError::InvalidParameter(_) => InvalidInput::new_err(msg),
        _ => QrmError::new_err(msg),
    }
}

/// The Python exception for an error writing results: the file system → `IoError`; a
/// config or figure that cannot be written → as the study's errors.
pub(crate) fn files_err(e: qrm_files::FileError) -> PyErr {
    use qrm_files::FileError as F;
    let msg = chain(&e);
    match e {
        F::Study(inner) => study_err(inner),
        F::Io { .. } | F::Path(_) => io_error(msg),
        _ => QrmError::new_err(msg),
    }
}
