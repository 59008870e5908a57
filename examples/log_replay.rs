//! A map of walls built from a real laser log: the Intel lab's mapping
//! run, its raw wheel odometry corrected by scan matching, the walls found
//! in each scan (RWHT) fused in one EKF with the pose; the trajectory's
//! relative pose error over 10 m against the log's own corrected poses.
//!
//! `cargo run --release -p stucco-examples --example log_replay [LOG]`
//! (default `tests/data/carmen/intel.gfs.log.gz`).

use anyhow::Result;
use std::path::PathBuf;
use stucco_cli::{LogReplayJob, OdometrySource, Reference, run_log_replay};

fn main() -> Result<()> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let log = std::env::args().nth(1).map_or_else(
        || root.join("tests/data/carmen/intel.gfs.log.gz"),
        PathBuf::from,
    );
    let job = LogReplayJob {
        log,
        reference: Reference::FromLog,
        odometry: OdometrySource::Odom,
        odom_noise: None,
        out: None,
        rpe_distance_m: 10.0,
        scan_matching: true,
    };
    let report = run_log_replay(&job, |_, _| {})?;
    println!(
        "{}: {} scans, {} walls mapped ({} of the building)",
        report.log, report.scans, report.map_walls, report.building_walls
    );
    for (what, rpe) in [
        ("the filter", &report.rpe),
        ("the odometry", &report.odom_rpe),
    ] {
        if let Some(r) = rpe {
            println!(
                "{what}: RPE over {} m, {:.3} ± {:.3} m, {:.2}° ± {:.2}° ({} pairs)",
                report.rpe_pair_distance_m,
                r.trans_mean_m,
                r.trans_std_m,
                r.rot_mean_rad.to_degrees(),
                r.rot_std_rad.to_degrees(),
                r.pairs
            );
        }
    }
    Ok(())
}
