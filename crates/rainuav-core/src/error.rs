//! The one error type of the core. The Python binding maps it onto the
//! `rainuav.RainuavError` hierarchy; Rust callers match on it.

use thiserror::Error;

/// Everything the core can refuse or fail at.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CoreError {
    /// An argument is outside its allowed range or is not a known name.
    #[error("{name} {allowed} (got {got})")]
    InvalidArgument {
        /// The argument's name as the user wrote it (`freq_hz`, `rain_rate_mm_h`, ...).
        name: &'static str,
        /// What is allowed, phrased to follow the name: "must be finite and >= 0".
        allowed: String,
        /// The offending value, formatted.
        got: String,
    },
    /// A computation that should not fail did (a bug or an extreme input we did not foresee).
    #[error("internal error: {0}")]
    Internal(String),
}

impl CoreError {
    /// Shorthand for [`CoreError::InvalidArgument`].
    pub fn invalid(name: &'static str, allowed: impl Into<String>, got: impl ToString) -> Self {
        CoreError::InvalidArgument {
            name,
            allowed: allowed.into(),
            got: got.to_string(),
        }
    }
}

/// Result alias used throughout the core.
pub type Result<T> = std::result::Result<T, CoreError>;

/// Checks that `value` is finite and inside `[lo, hi]`.
pub fn check_range(name: &'static str, value: f64, lo: f64, hi: f64, allowed: &str) -> Result<()> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(CoreError::invalid(name, allowed, value))
    }
}
