//! Acceptance tests: whole jobs on real data, asserted on what a user sees.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod corridor;
mod door_passage;
mod walls_on_real_logs;
