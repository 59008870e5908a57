//! The wall and door extraction as it stood before it was made faster
//! (commit 990aea6): the reference kept for benchmarks and tests.
//!
//! [`RwhtExtractor`] and [`find_doors`] here are verbatim copies of the
//! previous implementation. The extractor of the crate must give the same
//! walls and doors, bit for bit, on every scan (the tests compare them on
//! real and synthetic scans), and the `extract` bench runs both side by
//! side.

mod door;
mod line_fit;
mod rwht;
mod segments;

pub use door::{find_doors, find_doors_moving};
pub use rwht::RwhtExtractor;
