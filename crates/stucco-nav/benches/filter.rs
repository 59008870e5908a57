//! The room filter's cost: one update with four walls, and one whole scan
//! cycle (the room search on a 450-beam scan of the cluttered reference
//! room, association and update), setup outside the timed loop.
//! `cargo bench -p stucco-nav --bench filter -- --noplot`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix2, Point2, SVector};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Duration;
use stucco_core::{LaserSpec, Pose2, Stamp, Twist2};
use stucco_nav::{
    OdometryConfig, RoomConfig, RoomCovariance, RoomEkf, RoomEkfConfig, RoomSearch, RoomState,
    ScanPoints, Wall, observe, synthetic,
};

fn filter(c: &mut Criterion) {
    let mount = Pose2::new(0.35, 0.0, 0.0);
    let truth = RoomState::new(2.0, 2.5, 0.4, 5.45, 5.64);
    let p0 = RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(1e-4, 1e-4, 1e-4, 1e-3, 1e-3));
    let walls: Vec<Wall> = (0..4)
        .map(|q| {
            let (z, _) = observe(
                &nalgebra::DVector::from_column_slice(truth.as_slice()),
                q,
                &mount,
            );
            Wall {
                d_m: z.x,
                gamma_rad: z.y,
                covariance: Matrix2::new(1e-5, 0.0, 0.0, 1e-6),
                points: 80,
                rms_residual_m: 0.02,
                ends: [Point2::origin(), Point2::origin()],
            }
        })
        .collect();
    let fresh = || {
        RoomEkf::new(
            RoomEkfConfig::new(OdometryConfig::default(), mount),
            truth,
            p0,
            Stamp::ZERO,
        )
    };
    let mut g = c.benchmark_group("room-filter");
    g.bench_function("update-4-walls", |b| {
        b.iter_batched(
            fresh,
            |mut ekf| black_box(ekf.scan(Stamp::from_secs_f64(0.1), black_box(&walls), &[])),
            criterion::BatchSize::SmallInput,
        );
    });
    // Scans of the reference room from the filter's true pose.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let laser = synthetic::SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
    let sensor = Pose2::new(truth[0], truth[1], truth[2]) * mount;
    let scans: Vec<ScanPoints> = (0..16)
        .map(|_| {
            let room = synthetic::reference_room(sensor.position(), 12, &mut rng);
            ScanPoints::from_scan(&laser.scan(
                &room.world,
                &sensor,
                &Twist2::default(),
                Stamp::ZERO,
                &mut rng,
            ))
        })
        .collect();
    let mut search = RoomSearch::new(RoomConfig::default()).unwrap();
    let mut i = 0;
    g.bench_function("scan-cycle-450", |b| {
        b.iter_batched(
            fresh,
            |mut ekf| {
                i = (i + 1) % scans.len();
                let walls: Vec<Wall> = search
                    .find(&scans[i])
                    .map(|r| r.walls.into_iter().flatten().collect())
                    .unwrap_or_default();
                black_box(ekf.scan(Stamp::from_secs_f64(0.1), &walls, &[]))
            },
            criterion::BatchSize::SmallInput,
        );
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(30);
    targets = filter
}
criterion_main!(benches);
