//! Helpers shared by the tests and benches of stucco-nav.

pub mod flaser;
