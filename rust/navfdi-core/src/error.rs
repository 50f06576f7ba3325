//! The one error type of the core.
//!
//! Every fallible function of the core returns [`Result`]. Variants name the offending argument
//! (as the caller spelled it, e.g. `"R"` or `"Phi[12]"`) so that a binding can turn them into
//! messages a user can act on. The binding crate maps [`Error::NotPositiveDefinite`] and
//! [`Error::Numerical`] to a linear-algebra exception and every other variant to `ValueError`.

use thiserror::Error;

/// Errors of the navfdi core.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Error {
    /// An array has the wrong shape.
    #[error("{name}: expected shape {expected}, got {got}")]
    Shape {
        /// Argument name.
        name: String,
        /// Expected shape, e.g. `(6, 15)`.
        expected: String,
        /// Shape received.
        got: String,
    },
    /// An array holds NaN or infinity where only finite numbers are allowed.
    #[error(
        "{name}: {} is {value}; only finite numbers are allowed",
        element(index)
    )]
    NonFinite {
        /// Argument name.
        name: String,
        /// Position of the first offending element, e.g. `[2, 3]`.
        index: String,
        /// The offending value.
        value: f64,
    },
    /// A covariance matrix is not symmetric.
    #[error("{name}: not symmetric (|M - M^T| reaches {asymmetry:.3e} at {index}, tolerance {tolerance:.3e})")]
    NotSymmetric {
        /// Argument name.
        name: String,
        /// Largest absolute difference between `M[i, j]` and `M[j, i]`.
        asymmetry: f64,
        /// Position of the largest asymmetry.
        index: String,
        /// Tolerance applied.
        tolerance: f64,
    },
    /// A covariance matrix that must be positive semi-definite is not.
    #[error("{name}: not positive semi-definite ({detail})")]
    NotPositiveSemiDefinite {
        /// Argument name.
        name: String,
        /// What was found, e.g. a negative diagonal element.
        detail: String,
    },
    /// A matrix that must be positive definite (to be factored) is not.
    #[error("{name}: not positive definite ({detail})")]
    NotPositiveDefinite {
        /// Argument or quantity name, e.g. `"innovation covariance A"`.
        name: String,
        /// What was found.
        detail: String,
    },
    /// A scalar parameter is outside its allowed range.
    #[error("{name} = {}: {requirement}", num(*value))]
    InvalidParameter {
        /// Parameter name.
        name: String,
        /// Value received.
        value: f64,
        /// The rule it breaks, e.g. `"must be in (0, 1)"`.
        requirement: String,
    },
    /// A configuration is inconsistent (e.g. a stack length differs from the number of epochs).
    #[error("{0}")]
    Invalid(String),
    /// The computation was stopped through its [`crate::cancel::Cancel`] flag (e.g. Ctrl-C).
    #[error("cancelled")]
    Cancelled,
    /// The computation would need more memory than is available; the message says how much
    /// and which inputs to change.
    #[error("{0}")]
    TooLarge(String),
    /// A data file is malformed, truncated or of the wrong kind; the message names the file,
    /// the line when known, and what was expected.
    #[error("{0}")]
    Format(String),
    /// A file could not be read (not found, no permission); the message names it.
    #[error("{0}")]
    Io(String),
    /// A numerical procedure failed to produce a finite result.
    #[error("numerical failure in {context}: {detail}")]
    Numerical {
        /// Where it failed.
        context: String,
        /// What happened.
        detail: String,
    },
}

/// A number for messages: plain decimals for moderate magnitudes (`0.1`, `-5`), scientific
/// notation otherwise (`1e-300`), never hundreds of digits.
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e16).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Result alias of the core.
pub type Result<T> = std::result::Result<T, Error>;

/// `element [i, j]` in a message, or `the value` for a scalar (empty index).
fn element(index: &str) -> String {
    if index.is_empty() {
        "the value".into()
    } else {
        format!("element {index}")
    }
}
