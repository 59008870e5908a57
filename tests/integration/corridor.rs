//! Corridor centring at 0.8 m/s (paper A §4.1) in the simulator,
//! `missions/corridor.toml` through `stucco run`: the 20 m corridor with
//! doors open and closed on both sides, the pose and the corridor's width
//! from the room filter, the papers' line law on the middle; the lateral
//! offset from the true middle is scored over the settled 10 m. Target:
//! σ ≤ 5 mm.

use std::path::PathBuf;

#[test]
fn corridor_centring_at_08_mps_within_5_mm() {
    let report = crate::run_mission_file("corridor", None).unwrap();
    let c = &report.conditions[0];
    println!(
        "corridor at 0.8 m/s: lateral σ {:.1} mm, mean {:+.1} mm, heading σ {:.2} mrad over {} runs",
        c.lateral_std_m * 1e3,
        c.lateral_mean_m * 1e3,
        c.heading_std_rad * 1e3,
        c.runs
    );
    assert!(c.lateral_std_m <= 0.005, "σ {} m", c.lateral_std_m);
    // Centred on the built corridor, not on the map's 5 cm wider idea of it.
    assert!(
        c.lateral_mean_m.abs() <= 0.01,
        "mean {} m",
        c.lateral_mean_m
    );
}

/// The room's size learnt while touring on the filter's own estimate,
/// `missions/room-size.toml`: σ ≤ 3 mm over runs.
#[test]
fn room_size_learnt_on_tour_within_3_mm() {
    let report = crate::run_mission_file("room-size", None).unwrap();
    let (sd, m) = (
        report.room_size_std_m.unwrap(),
        report.room_size_mean_m.unwrap(),
    );
    println!(
        "room size over {} runs: {:.4} × {:.4} m, σ {:.1} mm; position RMS {:.1} mm",
        report.runs,
        m[0],
        m[1],
        sd * 1e3,
        report.pose_rms_m.unwrap() * 1e3
    );
    assert!(sd <= 0.003, "σ {sd} m");
    assert!(report.pose_rms_m.unwrap() <= 0.01);
    assert!(report.heading_rms_rad.unwrap() <= 0.3_f64.to_radians());
}

/// Every file in `missions/` parses and names a world that parses.
#[test]
fn every_mission_file_parses() {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../missions"));
    let names: Vec<String> = stucco_cli::load_all(&dir)
        .unwrap()
        .into_iter()
        .map(|m| m.name)
        .collect();
    assert!(names.len() >= 3, "{names:?}");
}

#[test]
fn a_malformed_mission_names_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, "name = \"x\"\nworld = \"w.toml\"\nseed = 1\n\n[corridor]\nroom_m = [1.0, 1.0]\nsped_mps = 0.8\n").unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:7") && err.contains("sped_mps"),
        "{err}"
    );
}

/// Values out of range are refused with the file, the line and the key,
/// and so is `--runs 0`.
#[test]
fn a_mission_out_of_range_names_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    let door = "name = \"x\"\nworld = \"w.toml\"\nseed = 1\n\n[door_passage]\nroom_m = [5.0, 5.0]\ndoor_m = [5.0, 2.5]\nspeeds_mps = [0.2, -0.5]\n\n[[door_passage.start]]\nname = \"easy\"\nat = [2.0, 2.0]\nheading_deg = 0.0\n";
    std::fs::write(&path, door).unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:8") && err.contains("speeds_mps"),
        "{err}"
    );
    let corridor = "name = \"x\"\nworld = \"w.toml\"\nseed = 1\n\n[corridor]\nroom_m = [19.5, 2.1]\nspeed_mps = 0.8\nscore_x_m = [16.0, 6.0]\n\n[corridor.start]\nname = \"west\"\nat = [1.5, 1.0]\nheading_deg = 0.0\n";
    std::fs::write(&path, corridor).unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:8") && err.contains("score_x_m"),
        "{err}"
    );
    let err = crate::run_mission_file("corridor", Some(0)).unwrap_err();
    assert!(format!("{err:#}").contains("runs"), "{err:#}");
}
