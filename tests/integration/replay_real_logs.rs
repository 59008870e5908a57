//! `stucco replay` on real laser logs (Radish): on the corrected logs the
//! map-building EKF fed by odometry made worse on purpose recovers the
//! corrected trajectory, at least five times nearer it than the odometry
//! over 10 m; on the Intel lab's raw log it beats the raw odometry against
//! the poses stored in the log. `freiburg-079` (2 MB, 4,791 scans) is
//! replayed by the README's command, not here.

use std::path::PathBuf;
use stucco_cli::{LogReplayJob, LogReplayReport, OdometrySource, Reference, run_log_replay};

fn log(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("data/carmen")
        .join(name)
}

fn freiburg_101() -> PathBuf {
    log("freiburg-101-corrected.log.gz")
}

/// 5 % long, drifting 3° a metre, noisy: a poor robot's odometry.
const POOR_ODOMETRY: &str =
    "scale=0.05,drift_deg_per_m=3,trans_sigma_m=0.03,rot_sigma_deg=2,seed=1";

fn replay_corrected(name: &str, scan_matching: bool) -> LogReplayReport {
    let job = LogReplayJob {
        log: log(name),
        reference: Reference::FromLog,
        odometry: OdometrySource::Scan,
        odom_noise: Some(POOR_ODOMETRY.parse().unwrap()),
        out: None,
        rpe_distance_m: 10.0,
        scan_matching,
    };
    run_log_replay(&job, |_, _| {}).unwrap()
}

#[test]
fn every_corrected_log_is_recovered_five_times_nearer_than_its_bad_odometry() {
    for name in [
        "freiburg-101-corrected.log.gz",
        "aces-corrected.log.gz",
        "intel-corrected.log.gz",
        "orebro-corrected.log.gz",
    ] {
        let report = replay_corrected(name, true);
        let (rpe, odom) = (report.rpe.unwrap(), report.odom_rpe.unwrap());
        println!(
            "{name}: filter {:.3} m {:.4} rad, odometry {:.3} m {:.4} rad ({:.1}× / {:.1}×), {:.1} % of the scans matched",
            rpe.trans_mean_m,
            rpe.rot_mean_rad,
            odom.trans_mean_m,
            odom.rot_mean_rad,
            odom.trans_mean_m / rpe.trans_mean_m,
            odom.rot_mean_rad / rpe.rot_mean_rad,
            100.0 * report.scans_matched_share
        );
        assert!(
            rpe.trans_mean_m * 5.0 < odom.trans_mean_m
                && rpe.rot_mean_rad * 5.0 < odom.rot_mean_rad,
            "{name}: filter {rpe:?}, odometry {odom:?}"
        );
        assert!(report.scans_matched_share > 0.9, "{name}: {report:?}");
    }
}

#[test]
fn scan_matching_more_than_halves_the_error_the_walls_alone_leave_in_the_intel_lab() {
    // The walls the lab's clutter leaves (`stucco walls`) hold the heading
    // but leave the position to the odometry between them.
    let alone = replay_corrected("intel-corrected.log.gz", false);
    assert_eq!(alone.scans_matched_share, 0.0);
    let alone = alone.rpe.unwrap();
    let matched = replay_corrected("intel-corrected.log.gz", true)
        .rpe
        .unwrap();
    println!("intel: walls alone {alone:?}, with scan matching {matched:?}");
    assert!(
        matched.trans_mean_m * 2.0 < alone.trans_mean_m,
        "{matched:?} {alone:?}"
    );
}

#[test]
fn the_intel_lab_from_its_raw_odometry_beats_that_odometry() {
    let job = LogReplayJob {
        log: log("intel.gfs.log.gz"),
        reference: Reference::FromLog,
        odometry: OdometrySource::Odom,
        odom_noise: None,
        out: None,
        rpe_distance_m: 10.0,
        scan_matching: true,
    };
    let report = run_log_replay(&job, |_, _| {}).unwrap();
    let (rpe, odom) = (report.rpe.unwrap(), report.odom_rpe.unwrap());
    println!("intel.gfs: filter {rpe:?}, raw odometry {odom:?}");
    assert!(
        rpe.trans_mean_m * 1.5 < odom.trans_mean_m && rpe.rot_mean_rad * 1.5 < odom.rot_mean_rad,
        "filter {rpe:?}, odometry {odom:?}"
    );
}

#[test]
fn the_wall_map_recovers_a_building_from_bad_odometry() {
    let out = tempfile::tempdir().unwrap();
    let job = LogReplayJob {
        log: freiburg_101(),
        reference: Reference::FromLog,
        odometry: OdometrySource::Scan,
        odom_noise: Some(POOR_ODOMETRY.parse().unwrap()),
        out: Some(out.path().to_path_buf()),
        rpe_distance_m: 10.0,
        scan_matching: true,
    };
    let report = run_log_replay(&job, |_, _| {}).unwrap();
    assert_eq!(report.scans, 292);
    let (rpe, odom) = (report.rpe.unwrap(), report.odom_rpe.unwrap());
    assert!(
        rpe.trans_mean_m * 5.0 < odom.trans_mean_m && rpe.rot_mean_rad * 5.0 < odom.rot_mean_rad,
        "filter {rpe:?}, odometry {odom:?}"
    );
    let csv = std::fs::read_to_string(out.path().join("trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 293);
    let map: stucco_nav::WallMap =
        serde_json::from_slice(&std::fs::read(out.path().join("map.json")).unwrap()).unwrap();
    assert_eq!(map.walls.len(), report.map_walls);
    assert!(report.building_walls >= 15, "{report:?}");
    let svg = std::fs::read_to_string(out.path().join("map.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("<polyline"));
}

#[test]
fn odometry_from_a_log_without_odom_lines_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-odom.log");
    let ranges = vec!["2.0"; 181].join(" ");
    std::fs::write(
        &path,
        format!("FLASER 181 {ranges} 0 0 0 0 0 0 1.5 host 1.5\n"),
    )
    .unwrap();
    let job = LogReplayJob {
        log: path,
        reference: Reference::None,
        odometry: OdometrySource::Odom,
        odom_noise: None,
        out: None,
        rpe_distance_m: 1.0,
        scan_matching: true,
    };
    let err = run_log_replay(&job, |_, _| {}).unwrap_err().to_string();
    assert!(
        err.contains("no-odom.log") && err.contains("no ODOM lines"),
        "{err}"
    );
}

#[test]
fn a_reference_log_without_the_scans_stamps_is_refused_with_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let ranges = vec!["2.0"; 181].join(" ");
    let log = dir.path().join("run.log");
    std::fs::write(
        &log,
        format!("FLASER 181 {ranges} 0 0 0 0 0 0 1.5 host 1.5\n"),
    )
    .unwrap();
    // The reference was logged at another time: no scan within 5 ms.
    let other = dir.path().join("reference.log");
    std::fs::write(
        &other,
        format!("FLASER 181 {ranges} 0 0 0 0 0 0 9.5 host 9.5\n"),
    )
    .unwrap();
    let job = LogReplayJob {
        log,
        reference: Reference::Log(other),
        odometry: OdometrySource::Scan,
        odom_noise: None,
        out: None,
        rpe_distance_m: 1.0,
        scan_matching: true,
    };
    let err = run_log_replay(&job, |_, _| {}).unwrap_err().to_string();
    assert!(
        err.contains("reference.log") && err.contains("scan on line 1"),
        "{err}"
    );
}
