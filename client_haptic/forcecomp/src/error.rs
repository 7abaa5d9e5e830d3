//! Errors of the force layer: only configuration checks; force computation itself never fails.

/// A configuration value that cannot give stable, safe forces.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ForceCompError {
    /// A parameter is negative, zero where it must not be, or not finite.
    #[error("{name} = {value} is out of range ({expected})")]
    OutOfRange {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f32,
        /// What is allowed.
        expected: &'static str,
    },
}

/// `Result` with [`ForceCompError`].
pub type Result<T, E = ForceCompError> = std::result::Result<T, E>;

/// Checks `value >= 0` and finite.
pub(crate) fn non_negative(name: &'static str, value: f32) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ForceCompError::OutOfRange { name, value, expected: "finite and >= 0" })
    }
}

/// Checks `value > 0` and finite.
pub(crate) fn positive(name: &'static str, value: f32) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ForceCompError::OutOfRange { name, value, expected: "finite and > 0" })
    }
}
