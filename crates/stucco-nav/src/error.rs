//! The error type of the navigation core.

/// What can go wrong in the navigation core.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NavError {
    /// A setting is out of its valid range.
    #[error("invalid setting `{field}`: {reason}")]
    InvalidConfig {
        /// The setting's name.
        field: &'static str,
        /// Why it is refused.
        reason: String,
    },
}
