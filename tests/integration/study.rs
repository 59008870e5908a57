//! `stucco study` on a reduced apartment study (`tests/data/study-reduced.toml`:
//! the settings the paper's trends are read at, four seeds): the trends of
//! the sensor-precision paper (Rogers et al.) and its scanner comparison.
//!
//! The paper's Fig. 5–8 plot the mean incremental heading error, so the
//! trends are read on the rotational RPE, each against the span from the
//! full sensor to the odometry alone: `lost(s) = (e(s) − e_full) /
//! (e_odometry − e_full)`, the share of what the laser brings that a
//! setting loses. "Little change" is at most a tenth of it lost; "sharp"
//! is at least half.

use std::path::PathBuf;
use stucco_cli::{Axis, SettingReport, StudyJob, StudyReport, run_study};

fn reduced() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/study-reduced.toml"
    ))
}

fn at<'a>(report: &'a StudyReport, axis: Axis, setting: &str) -> &'a SettingReport {
    report
        .axis(axis)
        .iter()
        .find(|r| r.setting == setting)
        .unwrap_or_else(|| panic!("no {} setting {setting}", axis.name()))
}

#[test]
fn the_study_shows_the_papers_trends_and_beats_its_scanners() {
    let out = tempfile::tempdir().unwrap();
    let job = StudyJob {
        study: reduced(),
        seeds: None,
        out: Some(out.path().to_path_buf()),
    };
    let report = run_study(&job, |_, _| {}).unwrap();
    assert_eq!(report.seeds, 4);
    let rot = |axis, s: &str| at(&report, axis, s).rpe.rot_mean_rad;
    let trans = |axis, s: &str| at(&report, axis, s).rpe.trans_mean_m;
    let full = at(&report, Axis::Range, "30");
    let (e_full, e_odo) = (full.rpe.rot_mean_rad, full.odom_rpe.rot_mean_rad);
    let lost = |e: f64| (e - e_full) / (e_odo - e_full);
    eprintln!(
        "rotational RPE, rad: full {e_full:.5}, odometry {e_odo:.5}; range 0.8 {:.5} 1.2 {:.5} 3 {:.5}; resolution 1° {:.5} 2.5° {:.5}; fov 90° {:.5}; noise 2 cm {:.5} 10 cm {:.5}",
        rot(Axis::Range, "0.8"),
        rot(Axis::Range, "1.2"),
        rot(Axis::Range, "3"),
        rot(Axis::Resolution, "1"),
        rot(Axis::Resolution, "2.5"),
        rot(Axis::Fov, "90"),
        rot(Axis::Noise, "0.02"),
        rot(Axis::Noise, "0.1"),
    );
    // The laser is worth having at all: odometry alone is far worse.
    assert!(e_odo > 10.0 * e_full, "{e_odo} vs {e_full}");

    // Range: the error grows sharply below ~1.6 m and is kept above it.
    assert!(lost(rot(Axis::Range, "0.8")) >= 0.5);
    assert!(rot(Axis::Range, "0.8") >= 5.0 * e_full);
    assert!(trans(Axis::Range, "0.8") >= 5.0 * full.rpe.trans_mean_m);
    assert!(rot(Axis::Range, "1.2") >= 2.0 * rot(Axis::Range, "3"));
    assert!(rot(Axis::Range, "3") <= 1.25 * e_full);

    // Angular resolution: little change down to 1°, worse past it.
    assert!(lost(rot(Axis::Resolution, "1")) <= 0.1);
    assert!(trans(Axis::Resolution, "1") <= 1.25 * trans(Axis::Resolution, "0.25"));
    assert!(rot(Axis::Resolution, "2.5") >= 1.1 * rot(Axis::Resolution, "1"));
    assert!(trans(Axis::Resolution, "2.5") > trans(Axis::Resolution, "1"));

    // Field of view: little change down to 90° with the full range.
    assert!(lost(rot(Axis::Fov, "90")) <= 0.1);

    // Noise: 2 cm hurts markedly, and more hurts more.
    assert!(rot(Axis::Noise, "0.02") >= 1.3 * rot(Axis::Noise, "0"));
    assert!(trans(Axis::Noise, "0.02") >= 1.3 * trans(Axis::Noise, "0"));
    assert!(rot(Axis::Noise, "0.1") > rot(Axis::Noise, "0.02"));
    assert!(rot(Axis::Noise, "0.1") >= 3.0 * rot(Axis::Noise, "0"));

    // The scanners of the paper's Fig. 9, each below its figure; the
    // UTM-30 the best in translation, the URG the worst in rotation, as
    // there.
    let paper = [
        ("hokuyo-urg", 0.020, 0.0099),
        ("sick-lms291", 0.021, 0.0066),
        ("hokuyo-utm30", 0.0098, 0.0070),
    ];
    let scanner = |name: &str| {
        report
            .scanners
            .iter()
            .find(|r| r.setting == name)
            .unwrap_or_else(|| panic!("no scanner {name}"))
    };
    for (name, t, r) in paper {
        let s = scanner(name);
        eprintln!(
            "{name}: {:.4} m, {:.5} rad (paper {t} m, {r} rad)",
            s.rpe.trans_mean_m, s.rpe.rot_mean_rad
        );
        assert!(
            s.rpe.trans_mean_m < t && s.rpe.rot_mean_rad < r,
            "{name}: {:?}",
            s.rpe
        );
    }
    let (urg, sick, utm) = (
        scanner("hokuyo-urg"),
        scanner("sick-lms291"),
        scanner("hokuyo-utm30"),
    );
    assert!(utm.rpe.trans_mean_m < urg.rpe.trans_mean_m.min(sick.rpe.trans_mean_m));
    assert!(urg.rpe.rot_mean_rad > utm.rpe.rot_mean_rad.max(sick.rpe.rot_mean_rad));

    // The walls of the maps sit where the true walls are.
    assert!(full.map_walls >= 4 * 4, "{full:?}");
    assert!(
        full.map_dist_rms_m < 0.01 && full.map_angle_rms_rad < 0.3f64.to_radians(),
        "{full:?}"
    );

    // The files the acceptance scripts read, with their columns.
    for name in ["range", "resolution", "fov", "noise"] {
        let csv = std::fs::read_to_string(out.path().join(format!("{name}.csv"))).unwrap();
        assert!(
            csv.starts_with("setting,trans_mean_m,trans_std_m,rot_mean_rad,rot_std_rad"),
            "{name}.csv: {csv}"
        );
        assert_eq!(
            csv.lines().count(),
            1 + report
                .axis(Axis::ALL.into_iter().find(|a| a.name() == name).unwrap())
                .len()
        );
        for plot in ["svg", "png"] {
            let meta = std::fs::metadata(out.path().join(format!("{name}.{plot}"))).unwrap();
            assert!(meta.len() > 1000, "{name}.{plot}");
        }
    }
    let csv = std::fs::read_to_string(out.path().join("scanners.csv")).unwrap();
    assert!(csv.starts_with("scanner,trans_mean_m,trans_std_m,rot_mean_rad,rot_std_rad"));
    assert_eq!(csv.lines().count(), 4);
}
