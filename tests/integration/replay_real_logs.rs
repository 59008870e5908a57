//! `stucco replay` on the Freiburg building 101 log (Radish, corrected
//! poses): the map-building EKF fed by odometry made worse on purpose
//! recovers the corrected trajectory, and writes its trajectory and map.

use std::path::PathBuf;
use stucco_cli::{LogReplayJob, OdometrySource, Reference, run_log_replay};

fn freiburg_101() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/carmen/freiburg-101-corrected.log.gz"
    ))
}

#[test]
fn the_wall_map_recovers_a_building_from_bad_odometry() {
    let out = tempfile::tempdir().unwrap();
    let job = LogReplayJob {
        log: freiburg_101(),
        reference: Reference::FromLog,
        odometry: OdometrySource::Scan,
        // 5 % long, drifting 3° a metre, noisy: a poor robot's odometry.
        odom_noise: Some(
            "scale=0.05,drift_deg_per_m=3,trans_sigma_m=0.03,rot_sigma_deg=2,seed=1"
                .parse()
                .unwrap(),
        ),
        out: Some(out.path().to_path_buf()),
        rpe_distance_m: 10.0,
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
    };
    let err = run_log_replay(&job, |_, _| {}).unwrap_err().to_string();
    assert!(
        err.contains("reference.log") && err.contains("scan on line 1"),
        "{err}"
    );
}
