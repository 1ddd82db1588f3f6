//! The exception hierarchy and the mapping from the Rust error enums.
//!
//! ```text
//! QrmError
//! ├── InvalidInput        bad numbers, shapes, covariances, arity, configuration
//! │   └── DegenerateFrame coincident reference points / landmarks
//! ├── SpecError           malformed or invalid calculus spec, unknown calculus/state/op
//! ├── UnsupportedError    an operation a calculus does not define
//! ├── FormatError         malformed saved map or input file
//! └── IoError             a file that cannot be read or written
//! ```

use pqrm::PqrmError;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use qsr_core::QsrError;

pyo3::create_exception!(qrm, QrmError, PyException, "Base class of every qrm error.");
pyo3::create_exception!(
    qrm,
    InvalidInput,
    QrmError,
    "Bad numbers, shapes, covariances or settings."
);
pyo3::create_exception!(
    qrm,
    DegenerateFrame,
    InvalidInput,
    "Coincident reference points or landmarks."
);
pyo3::create_exception!(
    qrm,
    SpecError,
    QrmError,
    "A calculus spec or name that is not valid."
);
pyo3::create_exception!(
    qrm,
    UnsupportedError,
    QrmError,
    "An operation the calculus does not define."
);
pyo3::create_exception!(
    qrm,
    FormatError,
    QrmError,
    "A malformed saved map or input file."
);
pyo3::create_exception!(
    qrm,
    IoError,
    QrmError,
    "A file that cannot be read or written."
);

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("QrmError", py.get_type::<QrmError>())?;
    m.add("InvalidInput", py.get_type::<InvalidInput>())?;
    m.add("DegenerateFrame", py.get_type::<DegenerateFrame>())?;
    m.add("SpecError", py.get_type::<SpecError>())?;
    m.add("UnsupportedError", py.get_type::<UnsupportedError>())?;
    m.add("FormatError", py.get_type::<FormatError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    Ok(())
}

/// The Python exception for a calculus-layer error.
pub(crate) fn qsr(e: QsrError) -> PyErr {
    let msg = e.to_string();
    match e {
        QsrError::DegenerateFrame { .. } => DegenerateFrame::new_err(msg),
        QsrError::NonFinite { .. } | QsrError::Arity(_) => InvalidInput::new_err(msg),
        QsrError::Spec { .. }
        | QsrError::UnknownCalculus { .. }
        | QsrError::UnknownState { .. }
        | QsrError::UnknownOperation { .. } => SpecError::new_err(msg),
        QsrError::Unsupported { .. } | QsrError::NotARefinement { .. } => {
            UnsupportedError::new_err(msg)
        }
        QsrError::Io { .. } => io_error(msg),
        _ => QrmError::new_err(msg),
    }
}

/// The Python exception for a mapper error.
pub(crate) fn pqrm(e: PqrmError) -> PyErr {
    let msg = e.to_string();
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

fn io_error(msg: String) -> PyErr {
    IoError::new_err(msg)
}

/// An `InvalidInput` with a message.
pub(crate) fn invalid(msg: impl Into<String>) -> PyErr {
    InvalidInput::new_err(msg.into())
}
