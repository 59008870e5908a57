//! The map-building filter's cost as the map grows: one prediction and one
//! scan of six walls (classified and applied) with 20, 100 and 400 walls in
//! the map, setup outside the timed loop.
//! `cargo bench -p stucco-nav --bench map -- --noplot`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix2, Matrix3, Point2};
use std::hint::black_box;
use std::time::Duration;
use stucco_core::{Pose2, Stamp, wrap_angle};
use stucco_nav::{Displacement, MapWall, Wall, WallMap, WallMapConfig, WallMapEkf, WallRole};

/// A floor of rooms 5 m square, 8 m apart on a grid (their walls on one
/// line stay apart), walls facing out of each room, `n` walls in all (the
/// first six: the robot's room and a pillar in it).
fn floor(n: usize) -> Vec<MapWall> {
    let mut walls = Vec::with_capacity(n);
    for room in 0.. {
        let (ox, oy) = ((room % 10) as f64 * 8.0, (room / 10) as f64 * 8.0);
        let corner = |x: f64, y: f64| Point2::new(ox + x, oy + y);
        // Each face: its two ends and the direction into it.
        let mut faces = vec![
            (
                corner(0.0, 0.0),
                corner(5.0, 0.0),
                -std::f64::consts::FRAC_PI_2,
            ),
            (corner(5.0, 0.0), corner(5.0, 5.0), 0.0),
            (
                corner(5.0, 5.0),
                corner(0.0, 5.0),
                std::f64::consts::FRAC_PI_2,
            ),
            (corner(0.0, 5.0), corner(0.0, 0.0), std::f64::consts::PI),
        ];
        if room == 0 {
            faces.push((corner(1.0, 3.0), corner(1.0, 4.0), std::f64::consts::PI));
            faces.push((
                corner(1.0, 3.0),
                corner(2.0, 3.0),
                std::f64::consts::FRAC_PI_2,
            ));
        }
        for (a, b, alpha) in faces {
            let mut w = MapWall {
                id: walls.len() as u32,
                rho_m: 0.0,
                alpha_rad: wrap_angle(alpha),
                covariance: Matrix2::new(1e-4, 0.0, 0.0, 1e-6),
                extent_m: [0.0, 0.0],
                observations: 10,
                wall_behind_scans: 0,
                role: WallRole::Wall,
            };
            w.rho_m = w.normal().dot(&a.coords);
            let (ta, tb) = (w.along(&a), w.along(&b));
            w.extent_m = [ta.min(tb), ta.max(tb)];
            walls.push(w);
            if walls.len() == n {
                return walls;
            }
        }
    }
    walls
}

fn map(c: &mut Criterion) {
    let pose = Pose2::new(2.5, 1.5, 0.3);
    let mut group = c.benchmark_group("map");
    for n in [20, 100, 400] {
        let walls = floor(n);
        // What the laser at `pose` sees of the robot's room.
        let seen: Vec<Wall> = walls[..6]
            .iter()
            .filter_map(|w| {
                let d = w.in_front(&pose.position());
                (d > 0.0).then(|| {
                    let gamma = wrap_angle(w.alpha_rad - pose.theta);
                    let inv = pose.inverse();
                    let ends = w.ends().map(|e| inv.transform_point(&e));
                    Wall {
                        d_m: d + 0.003,
                        gamma_rad: gamma,
                        covariance: Matrix2::new(1e-4, 0.0, 0.0, 1e-5),
                        points: 100,
                        rms_residual_m: 0.01,
                        ends,
                    }
                })
            })
            .collect();
        let filter = WallMapEkf::in_map(
            WallMapConfig::default(),
            &WallMap {
                walls,
                pose: Pose2::IDENTITY,
            },
            pose,
            Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-3, 1e-3, 1e-4)),
        );
        let step = Displacement {
            since: Stamp::ZERO,
            until: Stamp::ZERO,
            pose: Pose2::IDENTITY,
            covariance: Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-6, 1e-6, 1e-7)),
        };
        let mut check = filter.clone();
        check.predict(&step);
        let update = check.scan(&seen);
        assert!(
            update.matched.len() >= 4 && update.merged.is_empty() && update.added.is_empty(),
            "{n} walls: {update:?}"
        );
        group.bench_with_input(BenchmarkId::new("predict_and_scan", n), &n, |b, _| {
            b.iter_batched_ref(
                || filter.clone(),
                |f| {
                    f.predict(black_box(&step));
                    black_box(f.scan(black_box(&seen)))
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().measurement_time(Duration::from_secs(4)).sample_size(30);
    targets = map
}
criterion_main!(benches);
