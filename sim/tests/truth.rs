//! The plaster scored on the truth: every plasterable surface of the named
//! rooms counts, what furniture keeps from the tool is blocked and says
//! what blocks it, the rest left bare is unreached.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use stucco_core::{Pose2, ThicknessGrid};
use stucco_sim::{
    Coat, Deposition, Finish, Layout, Reach, SprayerSpec, SurfaceKind, TrueScore, WorldSpec,
    score_truth,
};

const COAT_M: f64 = 0.01;

/// The robot and tool of the project's defaults (the Luleå tricycle, the
/// three-axis gantry).
fn reach() -> Reach {
    Reach {
        body_x_m: [-0.15, 0.75],
        body_half_width_m: 0.31,
        body_top_m: 1.9,
        clearance_m: 0.12,
        drive_margin_m: 0.03,
        rail_m: [-0.25, 0.85],
        arm_m: [-0.3, 0.9],
        lift_m: [0.02, 3.1],
        wall_standoff_m: 0.3,
        ceiling_standoff_m: 0.3,
    }
}

fn finish() -> Finish {
    Finish {
        coat_m: COAT_M,
        tolerance: 0.1,
        skirting_m: 0.1,
        edge_margin_m: 0.11,
        opening_margin_m: 0.1,
    }
}

fn world(rooms: &str, more: &str) -> WorldSpec {
    let text = format!(
        "name = \"t\"\nseed = 1\n[robot]\nat = [1.0, 1.0]\nheading_deg = 0.0\n{rooms}\n{more}"
    );
    WorldSpec::parse(&text, "test").expect("a world")
}

const ROOM: &str = "[[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [5.0, 0.0], [5.0, 4.0], [0.0, 4.0]]\nheight_m = 2.6\n";

/// The bare coats of `w`, each passed through `paint`.
fn coats(w: &WorldSpec, paint: impl Fn(&Coat, &mut ThicknessGrid)) -> (Layout, Vec<Coat>) {
    let layout = Layout::of(w);
    let spec = SprayerSpec {
        flow_m3ps: 1e-4,
        sigma_m: 0.04,
        sigma_at_m: 0.3,
        axis_speed_mps: 0.5,
        cell_m: 0.02,
        park_m: [0.3, 0.0, 0.5],
        camera: None,
    };
    let mut coats = Deposition::new(spec, &layout).coats().to_vec();
    for c in &mut coats {
        let mut g = c.grid.clone();
        paint(c, &mut g);
        c.grid = g;
    }
    (layout, coats)
}

fn score(w: &WorldSpec, paint: impl Fn(&Coat, &mut ThicknessGrid)) -> TrueScore {
    let (layout, coats) = coats(w, paint);
    score_truth(
        &layout,
        &coats,
        &["r".to_owned()],
        &Pose2::new(w.robot.at[0], w.robot.at[1], 0.0),
        &reach(),
        &finish(),
    )
}

fn everywhere(_: &Coat, g: &mut ThicknessGrid) {
    g.thickness_m.iter_mut().for_each(|t| *t = COAT_M);
}

fn near(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn a_room_coated_all_over_is_covered_all_over_and_nothing_else_counts() {
    let s = score(&world(ROOM, ""), everywhere);
    // Walls: 18 m of perimeter less 0.22 m of corner bands each, 2.6 m
    // less the skirting and the ceiling band; the ceiling less its band.
    let walls = 2.0 * ((5.0 - 0.22) + (4.0 - 0.22)) * (2.6 - 0.1 - 0.11);
    let ceiling = (5.0 - 0.22) * (4.0 - 0.22);
    assert!(
        near(s.walls.plasterable_m2, walls, 0.02 * walls),
        "{:?}",
        s.walls
    );
    assert!(
        near(s.ceilings.plasterable_m2, ceiling, 0.02 * ceiling),
        "{:?}",
        s.ceilings
    );
    assert_eq!(s.walls.covered_m2, s.walls.plasterable_m2);
    assert_eq!(s.walls.coverage_pct(), Some(100.0));
    assert_eq!(s.ceilings.coverage_pct(), Some(100.0));
    assert!(s.blockers.is_empty());
    // A room the job does not name is not scored.
    let (layout, coats) = coats(&world(ROOM, ""), everywhere);
    let none = score_truth(
        &layout,
        &coats,
        &["elsewhere".to_owned()],
        &Pose2::new(1.0, 1.0, 0.0),
        &reach(),
        &finish(),
    );
    assert_eq!(none.walls.plasterable_m2, 0.0);
}

#[test]
fn a_bare_empty_room_is_all_unreached_none_of_it_blocked() {
    let s = score(&world(ROOM, ""), |_, _| {});
    assert_eq!(s.walls.covered_m2, 0.0);
    // Corners, the skirting and the ceiling line are all in reach.
    assert!(s.walls.blocked_m2 < 1e-9, "{:?}", s.blockers);
    assert!(s.ceilings.blocked_m2 < 1e-9, "{:?}", s.blockers);
    assert!(near(s.walls.unreached_m2, s.walls.plasterable_m2, 1e-9));
    assert_eq!(s.walls.coverage_pct(), Some(0.0));
}

#[test]
fn a_wardrobe_against_a_wall_blocks_the_wall_behind_it_and_is_named() {
    // 1.0 m wide, 0.6 m deep, 2.0 m high, against the north wall.
    let w = world(
        ROOM,
        "[[box]]\nat = [2.5, 3.7]\nsize_m = [1.0, 0.6]\nheight_m = 2.0\n",
    );
    let s = score(&w, |_, _| {});
    let behind = 1.0 * (2.0 - 0.1);
    assert!(near(s.walls.blocked_m2, behind, 0.1), "{:?}", s.walls);
    let b = &s.blockers[0];
    assert_eq!(b.what, Some("box"));
    assert_eq!(b.at, Some([2.5, 3.7]));
    assert_eq!(b.surface, SurfaceKind::Wall { index: 2 });
    assert!(near(b.area_m2, behind, 0.1), "{b:?}");
    // Above its top the arm passes over it: reached.
    assert!(s.walls.unreached_m2 > s.walls.plasterable_m2 - behind - 0.1);
    // What is blocked is out of the coverage's denominator: coat the rest
    // and the walls are covered in full.
    let blocked_wall = |c: &Coat, g: &mut ThicknessGrid| {
        if c.kind != (SurfaceKind::Wall { index: 2 }) {
            everywhere(c, g);
            return;
        }
        let nu = g.cells[0];
        for k in 0..g.thickness_m.len() {
            let [u, v] = g.center(k % nu, k / nu);
            // The wall runs east to west: x = 5 − u.
            let x = 5.0 - u;
            if !((2.0..=3.0).contains(&x) && v < 2.0) {
                g.thickness_m[k] = COAT_M;
            }
        }
    };
    let s = score(&w, blocked_wall);
    assert!(s.walls.coverage_pct() > Some(99.5), "{:?}", s.walls);
    assert!(s.walls.unreached_m2 < 0.05, "{:?}", s.walls);
}

#[test]
fn a_radiator_keeps_the_wall_behind_it() {
    let w = world(
        ROOM,
        "[[radiator]]\nroom = \"r\"\nwall = 0\noffset_m = 1.0\nlength_m = 1.2\n",
    );
    let s = score(&w, |_, _| {});
    // 1.2 m long from 0.1 m (the skirting) to its top at 0.7 m.
    let south = &s.blockers[0];
    assert_eq!(south.surface, SurfaceKind::Wall { index: 0 });
    assert!(near(south.area_m2, 1.2 * 0.6, 0.03), "{:?}", s.blockers);
    // It also keeps the body 12 cm off, and so the nozzle out of the west
    // wall's last few centimetres by the corner: blocked by it too.
    assert!(
        s.blockers.iter().all(|b| b.what == Some("radiator")),
        "{:?}",
        s.blockers
    );
    assert!(s.walls.blocked_m2 < 1.2 * 0.6 + 0.15, "{:?}", s.blockers);
}

#[test]
fn the_ceiling_over_a_wide_table_is_blocked_where_the_arm_does_not_reach() {
    // 2.4 × 1.6 m: from either long side the arm reaches 0.9 m left of a
    // body kept 0.43 m off the table's edge.
    let w = world(ROOM, "[[table]]\nat = [2.5, 2.0]\nsize_m = [2.4, 1.6]\n");
    let s = score(&w, |_, _| {});
    let middle = 2.0 * (0.8 - (0.9 - 0.31 - 0.12)); // the band out of reach
    assert!(
        s.ceilings.blocked_m2 > 0.5 * middle * 2.0,
        "{:?}",
        s.ceilings
    );
    assert!(s.ceilings.blocked_m2 < 2.4 * 1.6, "{:?}", s.ceilings);
    assert_eq!(s.blockers[0].what, Some("table"));
    assert_eq!(s.blockers[0].surface, SurfaceKind::Ceiling);
}

#[test]
fn an_l_shaped_room_scores_its_own_ceiling_not_its_bounding_box() {
    // 6 × 5 m less a 2.5 × 2 m notch in its north-east corner.
    let l = "[[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [6.0, 0.0], [6.0, 3.0], [3.5, 3.0], [3.5, 5.0], [0.0, 5.0]]\nheight_m = 2.6\n";
    let s = score(&world(l, ""), everywhere);
    let m = 0.11;
    // The polygon shrunk by the band: two rectangles.
    let ceiling = (6.0 - 2.0 * m) * (3.0 - 2.0 * m) + (3.5 - 2.0 * m) * (2.0);
    assert!(
        near(s.ceilings.plasterable_m2, ceiling, 0.02 * ceiling),
        "{:?}",
        s.ceilings
    );
    // Six walls, the notch's two among them.
    assert_eq!(
        s.surfaces
            .iter()
            .filter(|t| matches!(t.surface, SurfaceKind::Wall { .. }))
            .count(),
        6
    );
    let walls: f64 = [6.0, 3.0, 2.5, 2.0, 3.5, 5.0]
        .iter()
        .map(|l| l - 2.0 * m)
        .sum::<f64>()
        * (2.6 - 0.1 - m);
    assert!(
        near(s.walls.plasterable_m2, walls, 0.02 * walls),
        "{:?}",
        s.walls
    );
    // Bare, it is all within reach.
    let bare = score(&world(l, ""), |_, _| {});
    assert!(
        bare.walls.blocked_m2 < 1e-9 && bare.ceilings.blocked_m2 < 1e-9,
        "{:?}",
        bare.blockers
    );
}

#[test]
fn floor_cut_off_from_the_robot_is_blocked() {
    // A bed wall to wall across the room at x = 3.5..4.5 shuts off the
    // east end from the robot standing in the west.
    let w = world(
        ROOM,
        "[[box]]\nat = [4.0, 2.0]\nsize_m = [1.0, 4.0]\nheight_m = 0.6\n",
    );
    let s = score(&w, |_, _| {});
    let east = s
        .surfaces
        .iter()
        .find(|t| t.surface == SurfaceKind::Wall { index: 1 })
        .map(|t| t.tally)
        .unwrap_or_default();
    // The east wall, 0.5 m beyond the bed: the robot cannot get there.
    assert!(east.blocked_m2 > 0.9 * east.plasterable_m2, "{east:?}");
}

#[test]
fn a_corridors_end_walls_are_blocked_for_a_robot_that_cannot_turn_across_it() {
    // 1.2 m wide: turning on the spot about its rear axle the body sweeps
    // 0.81 m ahead of it and 0.34 m behind, 1.15 m, and 1.21 m with the
    // protective field's 3 cm each side.
    let hall = "[[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [6.0, 0.0], [6.0, 1.2], [0.0, 1.2]]\nheight_m = 2.6\n";
    let mut w = world(hall, "");
    w.robot.at = [1.0, 0.6];
    let s = score(&w, |_, _| {});
    let wall = |k: usize| {
        s.surfaces
            .iter()
            .find(|t| t.surface == SurfaceKind::Wall { index: k })
            .map(|t| t.tally)
            .unwrap_or_default()
    };
    for end in [1, 3] {
        let t = wall(end);
        assert!(
            t.blocked_m2 >= 0.999 * t.plasterable_m2,
            "wall {end}: {t:?}"
        );
    }
    // Facing east, the tool sprays to its left: the north wall is reached
    // from end to end; the south one would need the robot turned round,
    // which it cannot do here either.
    let north = wall(2);
    assert!(north.blocked_m2 < 1e-9, "{north:?}");
    let south = wall(0);
    assert!(
        south.blocked_m2 >= 0.999 * south.plasterable_m2,
        "{south:?}"
    );
    // A room wide enough to turn in: its end walls are reached.
    let room = "[[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [6.0, 0.0], [6.0, 2.0], [0.0, 2.0]]\nheight_m = 2.6\n";
    let s = score(&world(room, ""), |_, _| {});
    assert!(s.walls.blocked_m2 < 1e-9, "{:?}", s.blockers);
}

#[test]
fn a_room_behind_a_shut_door_is_blocked_by_that_door_and_has_no_coverage() {
    // The robot in a hall; the room beyond a shut door.
    let rooms = "[[room]]\nname = \"hall\"\ncorners = [[0.0, -2.0], [5.0, -2.0], [5.0, -0.15], [0.0, -0.15]]\n\
        [[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [5.0, 0.0], [5.0, 4.0], [0.0, 4.0]]\nheight_m = 2.6\nshared_walls = [0]\n";
    let mut w = world(
        rooms,
        "[[door]]\nroom = \"hall\"\nwall = 2\noffset_m = 2.0\nwidth_m = 0.9\nopen = false\n",
    );
    w.robot.at = [1.0, -1.0];
    let s = score(&w, |_, _| {});
    assert!(s.walls.plasterable_m2 > 30.0);
    assert_eq!(s.walls.blocked_m2, s.walls.plasterable_m2);
    assert_eq!(s.walls.coverage_pct(), None);
    assert!(
        s.blockers
            .iter()
            .all(|b| b.what == Some(stucco_sim::SHUT_DOOR)),
        "{:?}",
        s.blockers
    );
    // The door's middle: 2.45 m along the hall's north wall from its
    // east end.
    let at = s.blockers[0].at.unwrap_or_default();
    assert!(
        (at[0] - 2.55).abs() < 1e-9 && (at[1] - 0.0).abs() < 0.2,
        "{at:?}"
    );
    // Open, the room is reached.
    w.doors[0].open = true;
    let s = score(&w, |_, _| {});
    assert!(
        s.walls.blocked_m2 < 0.05 * s.walls.plasterable_m2,
        "{:?}",
        s.blockers
    );
}
