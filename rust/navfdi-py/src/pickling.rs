//! Pickling and copying (`pickle`, `copy.deepcopy`, Dask, multiprocessing).
//!
//! Each stateful class's `__reduce__` returns `(navfdi._core._restore, (class name, state))`,
//! where `state` is the core object serialised as JSON (serde; floats round-trip exactly). The
//! restored object continues exactly where the original was.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use serde::{de::DeserializeOwned, Serialize};

/// Serialise a core object for `__reduce__`.
pub fn state<T: Serialize>(what: &str, v: &T) -> PyResult<String> {
    serde_json::to_string(v)
        .map_err(|e| PyValueError::new_err(format!("cannot pickle this {what}: {e}")))
}

/// Deserialise a core object in `_restore`.
pub fn load<T: DeserializeOwned>(what: &str, state: &str) -> PyResult<T> {
    serde_json::from_str(state).map_err(|e| {
        PyValueError::new_err(format!(
            "cannot restore a {what} from its pickled state: {e}"
        ))
    })
}

/// `(navfdi._core._restore, (kind, state))`.
pub fn reduce<'py>(
    py: Python<'py>,
    kind: &str,
    state: String,
) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
    let f = py.import("navfdi._core")?.getattr("_restore")?;
    Ok((f, (kind.to_string(), state)))
}
