//! Examples of stucco used as a library (`cargo run --release -p
//! stucco-examples --example NAME`):
//!
//! - `embed`: the robot's runtime on a platform of your own — here a toy
//!   tricycle in an empty room, its laser cast against four walls — as a
//!   real robot's driver would be; nothing of the simulator.
//! - `sim_job`: a mission's job in the simulator, scored against the
//!   truth, as `stucco run` does it.
//! - `log_replay`: a map of walls built from a real laser log's odometry
//!   and scans, its trajectory's error against the log's reference.
