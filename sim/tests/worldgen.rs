//! The building generator: every building is a world the simulator takes,
//! within the ranges it promises, its drawing true to it within 3 cm, and
//! the same seed gives the same files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use nalgebra::Point2;
use stucco_sim::{CORRIDOR, Layout, WorldSpec, edge_distance, generate, inside};

const SEEDS: u64 = 300;

fn near_wall(corners: &[[f64; 2]], p: [f64; 2], within: f64) -> bool {
    let corners: Vec<Point2<f64>> = corners.iter().map(|c| Point2::new(c[0], c[1])).collect();
    edge_distance(&corners, &Point2::new(p[0], p[1])) <= within
}

#[test]
fn every_building_is_a_world_within_its_ranges() {
    let mut kinds = std::collections::BTreeSet::new();
    let (mut shut, mut to_the_floor, mut people, mut columns) = (0, 0, 0, 0);
    for seed in 0..SEEDS {
        let b = generate(seed);
        let text = b.world_toml();
        let w = WorldSpec::parse(&text, &format!("seed {seed}"))
            .unwrap_or_else(|e| panic!("seed {seed}: {e}\n{text}"));
        assert_eq!(w, b.world, "seed {seed}: the file says what was made");
        let rooms = w.rooms.len() - 1;
        assert!((1..=5).contains(&rooms), "seed {seed}");
        assert_eq!(w.rooms[0].name, CORRIDOR);
        let corridor_w = w.rooms[0].corners[2][1];
        assert!(
            (1.2..=1.8).contains(&corridor_w),
            "seed {seed}: {corridor_w}"
        );
        for r in &w.rooms[1..] {
            assert!((2.4..=3.0).contains(&r.height_m), "seed {seed}");
            let (lo, hi) = r
                .corners
                .iter()
                .fold(([f64::MAX; 2], [f64::MIN; 2]), |(l, h), c| {
                    (
                        [l[0].min(c[0]), l[1].min(c[1])],
                        [h[0].max(c[0]), h[1].max(c[1])],
                    )
                });
            for k in 0..2 {
                assert!(
                    (2.4 - 1e-9..=8.0 + 1e-9).contains(&(hi[k] - lo[k])),
                    "seed {seed}: {r:?}"
                );
            }
        }
        // One door a room, into the corridor.
        assert_eq!(w.doors.len(), rooms, "seed {seed}");
        for d in &w.doors {
            assert!((0.7..=1.0).contains(&d.width_m), "seed {seed}");
            shut += usize::from(!d.open);
        }
        for win in &w.windows {
            assert!((0.4..=3.0).contains(&win.width_m), "seed {seed}");
            assert!((0.0..=1.2).contains(&win.sill_m), "seed {seed}");
            assert!(win.head_m > win.sill_m, "seed {seed}");
            to_the_floor += usize::from(win.sill_m == 0.0);
        }
        for r in &w.rooms[1..] {
            assert!(w.windows.iter().filter(|x| x.room == r.name).count() <= 3);
        }
        let pieces = w.tables.len() + w.chairs.len() + w.boxes.len() + w.columns.len();
        assert!(pieces <= 6 * rooms, "seed {seed}");
        // Everything standing stands inside a room, the robot too.
        let layout = Layout::of(&w);
        for piece in &layout.pieces {
            let p = Point2::new(piece.at[0], piece.at[1]);
            let room = layout
                .rooms
                .iter()
                .find(|r| inside(&r.corners, &p))
                .unwrap_or_else(|| panic!("seed {seed}: {piece:?}"));
            // Its whole footprint in that room, and no corner of the room
            // standing in it (a wall through it).
            for solid in &layout.solids[piece.solids.clone()] {
                let stucco_sim::Solid::Box {
                    center,
                    half,
                    yaw_rad,
                    ..
                } = *solid
                else {
                    continue;
                };
                let (sn, cs) = yaw_rad.sin_cos();
                let feet: Vec<Point2<f64>> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .iter()
                    .map(|(fx, fy)| {
                        let (x, y) = (fx * half[0], fy * half[1]);
                        Point2::new(center[0] + cs * x - sn * y, center[1] + sn * x + cs * y)
                    })
                    .collect();
                for f in &feet {
                    assert!(inside(&room.corners, f), "seed {seed}: {piece:?}");
                }
                for c in &room.corners {
                    assert!(!inside(&feet, c), "seed {seed}: {piece:?} round {c:?}");
                }
            }
        }
        assert!(w.people.len() <= 3);
        people += w.people.len();
        columns += w.columns.len();
        for (_, k) in &b.shapes {
            kinds.insert(*k);
        }
        // The drawing: the world's rooms, each corner within 3 cm; each
        // door within reach of a wall of both its rooms.
        assert_eq!(b.drawing.rooms.len(), w.rooms.len());
        for ((name, drawn), room) in b.drawing.rooms.iter().zip(&w.rooms) {
            assert_eq!(name, &room.name);
            for (d, t) in drawn.iter().zip(&room.corners) {
                assert!((d[0] - t[0]).abs() <= 0.03 + 1e-9 && (d[1] - t[1]).abs() <= 0.03 + 1e-9);
            }
        }
        for d in &b.drawing.doors {
            for name in &d.rooms {
                let (_, corners) = b.drawing.rooms.iter().find(|(n, _)| n == name).unwrap();
                assert!(
                    near_wall(corners, d.at_m, 0.3),
                    "seed {seed}: {d:?} in {name}"
                );
            }
        }
    }
    // Every kind of room, and the rest the generator promises, came up.
    let want = ["L", "T", "angled", "chimney breast", "rectangle"];
    assert_eq!(kinds.into_iter().collect::<Vec<_>>(), want);
    assert!(shut > 0 && to_the_floor > 0 && people > 0 && columns > 0);
}

#[test]
fn the_same_seed_gives_the_same_files() {
    for seed in [0, 7, 123_456] {
        let (a, b) = (generate(seed), generate(seed));
        assert_eq!(a.world_toml(), b.world_toml());
        assert_eq!(a.plan_toml(), b.plan_toml());
        assert_eq!(a.mission_toml(), b.mission_toml());
    }
    assert_ne!(generate(1).world_toml(), generate(2).world_toml());
}

#[test]
fn generated_buildings_run_in_the_simulator() {
    use stucco_core::{DriveCommand, Platform};
    for seed in 0..5 {
        let w = generate(seed).world;
        let mut sim = stucco_sim::Simulator::new(&w, stucco_sim::SimConfig::default(), None);
        sim.command(DriveCommand {
            speed_mps: 0.2,
            steer_rad: 0.0,
        });
        let r = sim.advance(1.0);
        assert!(!r.scans.is_empty(), "seed {seed}");
        assert!(sim.truth().drive.pose.x > w.robot.at[0], "seed {seed}");
    }
}
