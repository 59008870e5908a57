//! The extractor and the door search give the walls and doors of the
//! implementation they replaced (`stucco_nav::baseline`, kept verbatim)
//! bit for bit: they were made faster (issue 34: ≤ 50 µs a scan on fr079)
//! by doing the same arithmetic with less overhead, not by changing what
//! is computed. Real scans from the repository's Radish logs (and fr079
//! from the shared data when it is there) and synthetic scans of the
//! reference room, still and moving.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::flaser::{flaser_scans, repo_log, shared_log};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stucco_core::{LaserSpec, Scan, Stamp, Twist2, wrap_angle};
use stucco_nav::{
    DoorConfig, DoorOpening, FitConfig, RwhtConfig, RwhtExtractor, ScanPoints, Wall, WallExtractor,
    baseline, find_doors, find_doors_moving, synthetic,
};

/// Every number of a wall, as bits.
fn wall_bits(w: &Wall) -> Vec<u64> {
    let mut b = vec![
        w.d_m.to_bits(),
        w.gamma_rad.to_bits(),
        w.points as u64,
        w.rms_residual_m.to_bits(),
    ];
    b.extend(w.covariance.iter().map(|v| v.to_bits()));
    b.extend(w.ends.iter().flat_map(|e| [e.x.to_bits(), e.y.to_bits()]));
    b
}

/// Every number of a door opening, as bits.
fn door_bits(d: &DoorOpening) -> Vec<u64> {
    let mut b = vec![
        d.wall as u64,
        d.center.x.to_bits(),
        d.center.y.to_bits(),
        d.width_m.to_bits(),
        d.width_sigma_m.to_bits(),
    ];
    b.extend(d.covariance.iter().map(|v| v.to_bits()));
    b.extend(d.frames.iter().flat_map(|e| [e.x.to_bits(), e.y.to_bits()]));
    b
}

/// How two extractions of the same scans compare.
#[derive(Debug, Default)]
struct Comparison {
    scans: usize,
    walls: usize,
    doors: usize,
    /// Scans whose walls or doors differ in any bit.
    differing_scans: usize,
    /// Largest difference in `d` and `γ` between walls of the same rank.
    max_d_m: f64,
    max_gamma_rad: f64,
}

impl Comparison {
    fn add(&mut self, new: (&[Wall], &[DoorOpening]), old: (&[Wall], &[DoorOpening])) {
        self.scans += 1;
        self.walls += old.0.len();
        self.doors += old.1.len();
        let same = new.0.len() == old.0.len()
            && new.1.len() == old.1.len()
            && new
                .0
                .iter()
                .zip(old.0)
                .all(|(a, b)| wall_bits(a) == wall_bits(b))
            && new
                .1
                .iter()
                .zip(old.1)
                .all(|(a, b)| door_bits(a) == door_bits(b));
        if !same {
            self.differing_scans += 1;
        }
        for (a, b) in new.0.iter().zip(old.0) {
            self.max_d_m = self.max_d_m.max((a.d_m - b.d_m).abs());
            self.max_gamma_rad = self
                .max_gamma_rad
                .max(wrap_angle(a.gamma_rad - b.gamma_rad).abs());
        }
    }

    fn assert_identical(&self, what: &str) {
        assert!(self.scans > 0, "{what}: no scans");
        assert_eq!(self.differing_scans, 0, "{what}: {self:?}");
    }
}

/// Both implementations over `scans`, each with its own extractor kept
/// from scan to scan (as `stucco walls` keeps one), the points deskewed
/// for `twist`.
fn compare(scans: &[Scan], twist: &Twist2, rwht: &RwhtConfig, doors: &DoorConfig) -> Comparison {
    let mut new = RwhtExtractor::new(rwht.clone()).unwrap();
    let mut old = baseline::RwhtExtractor::new(rwht.clone()).unwrap();
    let mut points = ScanPoints::default();
    let mut cmp = Comparison::default();
    for scan in scans {
        points.fill_deskewed(scan, twist);
        let walls = new.extract(&points);
        let found = find_doors_moving(scan, twist, &walls, doors);
        let walls0 = old.extract(&points);
        let found0 = baseline::find_doors_moving(scan, twist, &walls0, doors);
        cmp.add((&walls, &found), (&walls0, &found0));
        if *twist == Twist2::default() {
            // The still laser's entry point is the same search.
            let still = find_doors(scan, &walls, doors);
            assert_eq!(
                still.iter().map(door_bits).collect::<Vec<_>>(),
                found.iter().map(door_bits).collect::<Vec<_>>()
            );
        }
    }
    cmp
}

#[test]
fn walls_and_doors_of_real_logs_are_the_baselines_bit_for_bit() {
    let (rwht, doors) = common::log_settings();
    let mut logs: Vec<_> = [
        "freiburg-101-corrected.log.gz",
        "intel-corrected.log.gz",
        "aces-corrected.log.gz",
        "orebro-corrected.log.gz",
    ]
    .iter()
    .map(|name| repo_log(name))
    .collect();
    // The log, when the shared data sits beside the repository.
    let fr079 = shared_log("freiburg-079-corrected.log.gz");
    if fr079.exists() {
        logs.push(fr079);
    } else {
        eprintln!(
            "{} not found: compared on the repository's logs only",
            fr079.display()
        );
    }
    for log in &logs {
        let scans = flaser_scans(log).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
        let cmp = compare(&scans, &Twist2::default(), &rwht, &doors);
        eprintln!("{}: {cmp:?}", log.display());
        cmp.assert_identical(&log.display().to_string());
        assert!(cmp.walls > 2 * cmp.scans, "{}: {cmp:?}", log.display());
    }
}

#[test]
fn walls_and_doors_of_synthetic_scans_are_the_baselines_bit_for_bit() {
    let moving = Twist2 {
        vx_mps: 0.8,
        vy_mps: 0.0,
        omega_radps: 0.4,
    };
    let mut total_doors = 0;
    for spec in [
        LaserSpec::ibeo_ladar_2d(),
        LaserSpec::hokuyo_utm30(),
        LaserSpec::sick_lms291(),
    ] {
        let laser = synthetic::SyntheticLaser::new(spec.clone());
        let rwht = RwhtConfig {
            fit: FitConfig::for_laser(&spec),
            ..RwhtConfig::default()
        };
        let doors = DoorConfig::for_laser(&spec);
        for twist in [Twist2::default(), moving] {
            let mut rng = ChaCha8Rng::seed_from_u64(34);
            let scans: Vec<Scan> = (0..150)
                .map(|i| {
                    let robot = synthetic::random_pose((5.45, 5.64), 0.5, &mut rng);
                    let room = synthetic::reference_room(robot.position(), i % 13, &mut rng);
                    laser.scan(&room.world, &robot, &twist, Stamp::ZERO, &mut rng)
                })
                .collect();
            let cmp = compare(&scans, &twist, &rwht, &doors);
            cmp.assert_identical(&format!("{} {twist:?}", spec.name));
            total_doors += cmp.doors;
        }
    }
    // The door search had doors to find.
    assert!(total_doors > 50, "{total_doors} doors");
}

#[test]
fn the_comparison_sees_a_single_bit() {
    let (rwht, doors) = common::log_settings();
    let scans = flaser_scans(&repo_log("freiburg-101-corrected.log.gz")).unwrap();
    let mut extractor = RwhtExtractor::new(rwht).unwrap();
    let points = ScanPoints::from_scan(&scans[0]);
    let walls = extractor.extract(&points);
    let found = find_doors(&scans[0], &walls, &doors);
    let mut nudged = walls.clone();
    nudged[0].gamma_rad = f64::from_bits(nudged[0].gamma_rad.to_bits() + 1);
    let mut cmp = Comparison::default();
    cmp.add((&nudged, &found), (&walls, &found));
    assert_eq!(cmp.differing_scans, 1);
    assert!(cmp.max_gamma_rad > 0.0 && cmp.max_gamma_rad < 1e-15);
}
