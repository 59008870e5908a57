//! The `stucco` command-line tool as a library, so acceptance tests can call
//! its jobs without spawning a process.
//!
//! - [`read_carmen_file`], [`CarmenReader`]: CARMEN laser logs.
//! - [`run_walls`]: the `stucco walls` job.
//! - [`run_simbench`]: the `stucco simbench` job.
#![warn(missing_docs)]

mod carmen;
mod simbench;
mod walls;

pub use carmen::*;
pub use simbench::{SimbenchJob, SimbenchReport, run_simbench};
pub use walls::{
    ExtractorKind, MIN_REOBSERVATIONS, WallsJob, WallsReport, make_extractor, run_walls,
};
