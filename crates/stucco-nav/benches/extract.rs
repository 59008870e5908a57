//! Time to extract walls from one scan of the cluttered reference room: the RWHT extractor (and the implementation it replaced, `stucco_nav::baseline`, side by side), the RANSAC baseline and the rectangular-room search, on 450-beam (IBEO LADAR 2D) and 1081-beam (Hokuyo UTM-30) scans, plus the Hough transform alone; and walls and doors of every scan of the fr079 log as `stucco walls` times them, now and before, when the shared data sits beside the repository. Run with `cargo bench -p stucco-nav --bench extract -- --noplot`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Duration;
use stucco_core::{LaserSpec, Pose2, Stamp, Twist2};
use stucco_nav::{
    FitConfig, HoughConfig, HoughTransform, RansacConfig, RansacExtractor, RoomConfig, RoomSearch,
    RwhtConfig, RwhtExtractor, ScanPoints, WallExtractor, Weighting, baseline, find_doors,
    synthetic,
};

/// Robot poses (and rooms) per scan set.
const POSES: usize = 16;
/// People walking about the reference room.
const PEOPLE: usize = 12;
/// Size of the reference room, m.
const ROOM_M: (f64, f64) = (5.45, 5.64);

/// The same `POSES` poses for every sensor: the scan sets differ only in
/// the laser.
fn poses() -> Vec<Pose2> {
    let mut rng = ChaCha8Rng::seed_from_u64(0x57_0cc0);
    (0..POSES)
        .map(|_| synthetic::random_pose(ROOM_M, 0.5, &mut rng))
        .collect()
}

/// One scan of the reference room from each pose; room `i` (its clutter
/// and people) is the same for every sensor.
fn scans(spec: &LaserSpec) -> Vec<ScanPoints> {
    let laser = synthetic::SyntheticLaser::new(spec.clone());
    poses()
        .iter()
        .enumerate()
        .map(|(i, robot)| {
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + i as u64);
            let room = synthetic::reference_room(robot.position(), PEOPLE, &mut rng);
            let scan = laser.scan(
                &room.world,
                robot,
                &Twist2::default(),
                Stamp::ZERO,
                &mut rng,
            );
            ScanPoints::from_scan(&scan)
        })
        .collect()
}

/// The scans in turn, one per call, round and round.
fn cycle<'a, T>(scans: &'a [T]) -> impl FnMut() -> &'a T {
    let mut i = 0;
    move || {
        let s = &scans[i % scans.len()];
        i += 1;
        s
    }
}

fn extract(c: &mut Criterion) {
    for (group, spec) in [
        ("extract/ibeo-450", LaserSpec::ibeo_ladar_2d()),
        ("extract/utm30-1081", LaserSpec::hokuyo_utm30()),
    ] {
        let scans = scans(&spec);
        assert!(scans.iter().all(|s| !s.is_empty()), "{group}: empty scan");
        let fit = FitConfig::for_laser(&spec);
        let mut g = c.benchmark_group(group);

        let mut rwht = RwhtExtractor::new(RwhtConfig {
            fit: fit.clone(),
            ..RwhtConfig::default()
        })
        .expect("valid RWHT settings");
        let mut next = cycle(&scans);
        g.bench_function("rwht", |b| {
            b.iter(|| black_box(rwht.extract(black_box(next()))));
        });

        let mut before = baseline::RwhtExtractor::new(RwhtConfig {
            fit: fit.clone(),
            ..RwhtConfig::default()
        })
        .expect("valid RWHT settings");
        let mut next = cycle(&scans);
        g.bench_function("rwht-baseline", |b| {
            b.iter(|| black_box(before.extract(black_box(next()))));
        });

        let mut ransac = RansacExtractor::new(RansacConfig {
            fit: fit.clone(),
            ..RansacConfig::default()
        })
        .expect("valid RANSAC settings");
        let mut next = cycle(&scans);
        g.bench_function("ransac", |b| {
            b.iter(|| black_box(ransac.extract(black_box(next()))));
        });

        let mut room = RoomSearch::new(RoomConfig {
            fit,
            ..RoomConfig::default()
        })
        .expect("valid room settings");
        let mut next = cycle(&scans);
        g.bench_function("room", |b| {
            b.iter(|| black_box(room.find(black_box(next()))));
        });

        g.finish();
    }
}

fn hough(c: &mut Criterion) {
    let scans = scans(&LaserSpec::ibeo_ladar_2d());
    let mut transform = HoughTransform::new(HoughConfig {
        weighting: Weighting::Range,
        ..HoughConfig::default()
    })
    .expect("valid Hough settings");
    let mut next = cycle(&scans);
    let mut g = c.benchmark_group("hough");
    g.bench_function("ibeo-450", |b| {
        b.iter(|| {
            transform.compute(black_box(next().points()));
            black_box(transform.value(0, 0))
        });
    });
    g.finish();
}

/// Walls and doors of every scan of fr079 in turn, each timed as `stucco
/// walls` times it (the points, the walls, the doors), by the extractor and
/// by the baseline; nothing when the shared log is not there.
fn fr079(c: &mut Criterion) {
    let log = common::flaser::shared_log("freiburg-079-corrected.log.gz");
    let Ok(scans) = common::flaser::flaser_scans(&log) else {
        eprintln!("{} not found: fr079 not benched", log.display());
        return;
    };
    let (config, doors) = common::log_settings();
    let mut g = c.benchmark_group("walls/fr079");
    let mut points = ScanPoints::default();
    let mut rwht = RwhtExtractor::new(config.clone()).expect("valid RWHT settings");
    let mut next = cycle(&scans);
    g.bench_function("rwht+doors", |b| {
        b.iter(|| {
            let scan = next();
            points.fill(scan);
            let walls = rwht.extract(&points);
            black_box(find_doors(scan, &walls, &doors))
        });
    });
    let mut before = baseline::RwhtExtractor::new(config).expect("valid RWHT settings");
    let mut next = cycle(&scans);
    g.bench_function("baseline", |b| {
        b.iter(|| {
            let scan = next();
            points.fill(scan);
            let walls = before.extract(&points);
            black_box(baseline::find_doors(scan, &walls, &doors))
        });
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(30);
    targets = extract, hough, fr079
}
criterion_main!(benches);
