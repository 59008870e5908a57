//! The planner on the rooms of generated buildings, as their drawings give
//! them (L, T, chimney breasts, walls at an angle, rectangles): every wall
//! of the polygon gets its lane (or what no station reaches of it is
//! reported), every station stands inside the room,
//! and the coat covers what the plan reaches of the walls and the ceiling
//! to the targets. Seeds nobody planned on by hand.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use stucco_core::{Pose2, SurfaceId, VehicleSpec, WallName};
use stucco_plan::{Lane, Outline, RoomModel, SprayTool, plan, predicted_score};

/// The drawn room `corners` (world), moved to its box's corner, `height_m`
/// high, bare; and a point inside it to start from.
fn drawn(corners: &[[f64; 2]], height_m: f64) -> (RoomModel, Pose2) {
    let lo = corners
        .iter()
        .fold([f64::MAX; 2], |m, c| [m[0].min(c[0]), m[1].min(c[1])]);
    let corners: Vec<[f64; 2]> = corners
        .iter()
        .map(|c| [c[0] - lo[0], c[1] - lo[1]])
        .collect();
    let size = corners
        .iter()
        .fold([0.0f64; 2], |m, c| [m[0].max(c[0]), m[1].max(c[1])]);
    let outline = Outline::new(&corners);
    // The middle of the widest stretch of the room's middle row.
    let y = size[1] / 2.0;
    let span = outline
        .row_spans(y, 0.6)
        .into_iter()
        .max_by(|a, b| (a[1] - a[0]).total_cmp(&(b[1] - b[0])))
        .expect("the room's middle row runs inside it");
    let room = RoomModel {
        size_m: size,
        corners,
        height_m,
        openings: Vec::new(),
        obstacles: Vec::new(),
    };
    (room, Pose2::new((span[0] + span[1]) / 2.0, y, 0.0))
}

#[test]
fn generated_rooms_of_any_shape_are_planned_to_the_targets() {
    let (tool, vehicle) = (SprayTool::default(), VehicleSpec::default());
    let mut shapes = std::collections::BTreeSet::new();
    for seed in 200..212 {
        let b = stucco_sim::generate(seed);
        for (name, corners) in &b.drawing.rooms {
            let shape = b
                .shapes
                .iter()
                .find(|(n, _)| n == name)
                .map_or("corridor", |(_, s)| *s);
            let height = b
                .world
                .rooms
                .iter()
                .find(|r| &r.name == name)
                .map(|r| r.height_m)
                .unwrap();
            let (room, start) = drawn(corners, height);
            let p = plan(&room, &tool, &vehicle, &start)
                .unwrap_or_else(|e| panic!("seed {seed} {name} ({shape}): {e}"));
            shapes.insert(shape);
            let walls = room.corners.len();
            // A wall has its lane, or what of it no station reaches (a
            // chimney breast's alcove narrower than the body) is reported.
            for k in 0..walls {
                let w = WallName::new(k);
                assert!(
                    p.stations.iter().any(|s| s.lane == Lane::Wall(w))
                        || p.unreachable
                            .iter()
                            .any(|u| u.surface == SurfaceId::Wall(w)),
                    "seed {seed} {name} ({shape}): nothing planned or reported for {w}"
                );
            }
            let s = predicted_score(&p);
            // Of what the plan reaches (the scores leave out the rest,
            // which the plan reports).
            let (walls_pct, ceiling_pct) = (s.wall_coverage_pct, s.ceiling_coverage_pct);
            let lost: f64 = p.unreachable.iter().map(|u| u.area_m2).sum();
            eprintln!(
                "seed {seed} {name} ({shape}, {walls} walls): walls {walls_pct:.2} %, ceiling \
                 {ceiling_pct:.2} % of the plan's reach, {lost:.2} m² out of reach, overspray {:.3} %",
                s.overspray_pct
            );
            assert!(walls_pct >= 99.5, "seed {seed} {name} ({shape}): {s:?}");
            assert!(ceiling_pct >= 99.0, "seed {seed} {name} ({shape}): {s:?}");
            assert!(
                s.overspray_pct <= 0.5,
                "seed {seed} {name} ({shape}): {s:?}"
            );
        }
    }
    // The seeds hold rooms of more than one shape.
    assert!(shapes.len() >= 3, "{shapes:?}");
}
