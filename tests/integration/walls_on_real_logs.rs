//! `stucco walls` on the Intel Research Lab log (Radish, corrected poses):
//! every scan processed, walls re-observed consistently in the world frame,
//! and a malformed log refused with file, line and field.

use std::io::Write;
use std::path::PathBuf;
use stucco_cli::{ExtractorKind, WallsJob, run_walls};

fn intel() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/carmen/intel-corrected.log.gz"
    ))
}

#[test]
fn intel_log_walls_are_consistent_across_scans() {
    let out = tempfile::tempdir().unwrap();
    let job = WallsJob {
        log: intel(),
        extractor: ExtractorKind::Rwht,
        out: Some(out.path().to_path_buf()),
        baseline: false,
    };
    let report = run_walls(&job, |_| {}).unwrap();
    assert_eq!(report.scans, 910);
    assert!(report.walls_per_scan > 2.0, "{report:?}");
    // Re-observations of the same world wall agree to a few centimetres and
    // about a degree: the log's corrected poses are themselves good to ~2 cm.
    assert!(
        report.world_walls >= 50 && report.reobservations >= 1000,
        "{report:?}"
    );
    assert!(
        report.wall_spread_m < 0.05 && report.wall_spread_rad < 0.025,
        "{report:?}"
    );
    let lines = std::fs::read_to_string(out.path().join("walls.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 910);
    let first: serde_json::Value = serde_json::from_str(lines.lines().next().unwrap()).unwrap();
    let wall = &first["walls"][0];
    for key in ["d_m", "gamma_rad", "sigma_d_m", "sigma_gamma_rad", "ends"] {
        assert!(!wall[key].is_null(), "missing {key} in {first}");
    }
    let svg = std::fs::read_to_string(out.path().join("walls.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("<polyline"),
        "not an SVG map"
    );
}

#[test]
fn malformed_log_is_refused_with_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.log");
    let mut f = std::fs::File::create(&path).unwrap();
    writeln!(f, "PARAM robot_frontlaser_offset 0.0 nohost 0").unwrap();
    writeln!(f, "FLASER 3 1.0 2.0 x 0 0 0 0 0 0 1.5 host 1.5").unwrap();
    drop(f);
    let job = WallsJob {
        log: path.clone(),
        extractor: ExtractorKind::Rwht,
        out: None,
        baseline: false,
    };
    let err = format!("{:#}", run_walls(&job, |_| {}).unwrap_err());
    assert!(
        err.contains("broken.log:2") && err.contains("range[2]"),
        "{err}"
    );
}
