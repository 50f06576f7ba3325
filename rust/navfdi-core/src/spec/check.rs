//! Validation helpers shared by the scenario's parts: errors that name the field path.

use crate::error::{Error, Result};

pub(crate) fn bad(path: impl Into<String>, msg: impl std::fmt::Display) -> Error {
    Error::Invalid(format!("{}: {msg}", path.into()))
}

pub(crate) fn positive(path: &str, v: f64) -> Result<()> {
    if !(v > 0.0 && v.is_finite()) {
        return Err(bad(
            path,
            format!("{} must be a positive finite number", crate::error::num(v)),
        ));
    }
    Ok(())
}

/// A sensor's σ (`what`: noise or offset) within what the filter's arithmetic can square.
pub(crate) fn sensor_scale(path: &str, v: f64, what: &str) -> Result<()> {
    if v > 1e7 {
        return Err(bad(
            path,
            format!(
                "{} is beyond any sensor's {what} (at most 1e7 in the component's SI unit)",
                crate::error::num(v)
            ),
        ));
    }
    Ok(())
}

pub(crate) fn non_negative(path: &str, v: f64) -> Result<()> {
    if !(v >= 0.0 && v.is_finite()) {
        return Err(bad(
            path,
            format!("{} must be a finite number >= 0", crate::error::num(v)),
        ));
    }
    Ok(())
}
