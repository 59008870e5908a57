//! Acceptance tests: whole jobs on real data, asserted on what a user sees.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod acl;
mod corridor;
mod door_passage;
mod link;
mod missions;
mod walls_on_real_logs;

/// `stucco run` on `missions/<name>.toml`, with the mission's own seed and
/// `runs` (or the mission's count).
fn run_mission_file(name: &str, runs: Option<u64>) -> anyhow::Result<stucco_cli::RunReport> {
    stucco_cli::run_mission(&stucco_cli::RunJob {
        mission: std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../missions")
            .join(format!("{name}.toml")),
        seed: None,
        runs,
    })
}
