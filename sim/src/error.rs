//! Errors of the simulator: world files it cannot read or accept.

use thiserror::Error;

/// What went wrong building a simulation.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SimError {
    /// The world file could not be read.
    #[error("cannot read {path}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The world file is not valid TOML or has a wrong or unknown key.
    #[error("{origin}:{line}:{column}: {message}")]
    Syntax {
        /// The file (or other origin) of the text.
        origin: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// The world file parses but describes an impossible world.
    #[error("{origin}:{line}: {field}: {reason}")]
    Invalid {
        /// The file (or other origin) of the text.
        origin: String,
        /// 1-based line of the table holding the field (0 if unknown).
        line: usize,
        /// The field, as `table[index].key`.
        field: String,
        /// What is wrong.
        reason: String,
    },
}
