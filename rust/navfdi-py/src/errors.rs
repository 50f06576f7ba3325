//! Core errors → Python exceptions.
//!
//! `NotPositiveDefinite` and `Numerical` (numerical failures during a computation) become
//! `navfdi.LinAlgError`, a subclass of `ValueError`; `TooLarge` (a computation refused before
//! allocating more memory than is available) is a `MemoryError` whose message says how much
//! is needed and what to change; `Format` (a malformed data file) is
//! `navfdi.FileFormatError`, a subclass of `ValueError`; `Io` is an `OSError`; `Cancelled` is a `KeyboardInterrupt`; every other variant is
//! a `ValueError`.
//! The message is the core error's message, which names the argument and the problem.

use navfdi_core::Error;
use pyo3::exceptions::{PyKeyboardInterrupt, PyMemoryError, PyOSError, PyValueError};
use pyo3::{create_exception, PyErr};

create_exception!(
    navfdi._core,
    LinAlgError,
    PyValueError,
    "A numerical linear-algebra failure: a matrix that must be positive definite is not, or a result is not finite. Subclass of ValueError."
);

create_exception!(
    navfdi._core,
    FileFormatError,
    PyValueError,
    "A data file (RINEX) is malformed, truncated or of the wrong kind; the message names the file, the line when known, and what was expected. Subclass of ValueError."
);

/// Convert a core error into a Python exception.
pub fn to_py(e: Error) -> PyErr {
    match &e {
        Error::NotPositiveDefinite { .. } | Error::Numerical { .. } => {
            LinAlgError::new_err(e.to_string())
        }
        Error::Cancelled => PyKeyboardInterrupt::new_err("cancelled"),
        Error::TooLarge(_) => PyMemoryError::new_err(e.to_string()),
        Error::Format(_) => FileFormatError::new_err(e.to_string()),
        Error::Io(_) => PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// Extension to turn `navfdi_core::Result` into `PyResult`.
pub trait IntoPyResult<T> {
    /// Map the error with [`to_py`].
    fn py(self) -> pyo3::PyResult<T>;
}

impl<T> IntoPyResult<T> for navfdi_core::Result<T> {
    fn py(self) -> pyo3::PyResult<T> {
        self.map_err(to_py)
    }
}
