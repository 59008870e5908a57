//! Cost of planning a room and of predicting its coat, and of laying a
//! wall's vertical stroke on a 1 cm grid in the 1 cm steps the simulator
//! lays it in (by the stroke's factors, and cell by cell as before: the
//! baseline).
#![allow(clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use stucco_core::{Pose2, ThicknessGrid, VehicleSpec, WallName};
use stucco_plan::{OpeningKind, RoomModel, SprayTool, WallOpening, plan, predicted_score};

fn living_room() -> RoomModel {
    RoomModel {
        size_m: [5.0, 2.85],
        corners: Vec::new(),
        height_m: 2.6,
        openings: vec![
            WallOpening {
                wall: WallName::SOUTH,
                kind: OpeningKind::Window,
                along_m: [2.0, 3.2],
                sill_head_m: [0.9, 2.1],
            },
            WallOpening {
                wall: WallName::EAST,
                kind: OpeningKind::Door,
                along_m: [1.0, 1.9],
                sill_head_m: [0.0, 2.0],
            },
        ],
        obstacles: Vec::new(),
    }
}

fn bench(c: &mut Criterion) {
    let room = living_room();
    let tool = SprayTool::default();
    let v = VehicleSpec::default();
    let start = Pose2::new(2.5, 1.4, 0.0);
    c.bench_function("plan living room", |b| {
        b.iter(|| plan(black_box(&room), &tool, &v, &start))
    });
    let p = plan(&room, &tool, &v, &start).expect("plan");
    c.bench_function("predict living room", |b| {
        b.iter(|| predicted_score(black_box(&p)))
    });
    let mut g = c.benchmark_group("lay a 2.4 m stroke in 1 cm steps");
    for (name, cell_by_cell) in [("factors", false), ("baseline-cell-by-cell", true)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut grid = ThicknessGrid::new([1.0, 2.6], 0.01);
                for k in 0..240 {
                    let (v0, v1) = (0.1 + 0.01 * f64::from(k), 0.11 + 0.01 * f64::from(k));
                    if cell_by_cell {
                        grid.deposit_cell_by_cell([0.5, v0], [0.5, v1], 1e-6, 0.04);
                    } else {
                        grid.deposit([0.5, v0], [0.5, v1], 1e-6, 0.04);
                    }
                }
                black_box(grid)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
