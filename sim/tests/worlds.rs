//! Every world file in `sim/worlds/` parses, passes its checks, and builds.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use stucco_sim::{SimConfig, Simulator, WorldSpec};

#[test]
fn every_world_file_parses_and_builds() {
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/worlds"));
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let world = WorldSpec::load(&path).unwrap_or_else(|e| panic!("{e}"));
            let sim = Simulator::new(&world, SimConfig::default(), None);
            assert!(!sim.layout().walls.is_empty(), "{}", path.display());
            names.push(world.name);
        }
    }
    names.sort();
    assert_eq!(names, ["apartment", "corridor", "floor", "reference room"]);
}

/// A door written on one room's wall is a hole in the wall of the room
/// that shares it too (the office floor's doors are written on the
/// corridor's side): its plaster and its openings are those of both
/// faces.
#[test]
fn a_door_is_an_opening_of_both_rooms_that_share_its_wall() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/worlds/floor.toml");
    let layout = stucco_sim::Layout::of(&WorldSpec::load(std::path::Path::new(path)).unwrap());
    let doors_of = |room: &str| {
        let mut v: Vec<(usize, [f64; 2])> = layout
            .openings
            .iter()
            .filter(|o| o.room == room)
            .map(|o| {
                let c = nalgebra::center(&o.edges[0], &o.edges[1]);
                (
                    o.wall,
                    [(c.x * 100.0).round() / 100.0, (c.y * 100.0).round() / 100.0],
                )
            })
            .collect();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        v
    };
    // Office A: its own door to B (east wall, 1) and the corridor's door
    // in its south wall (0), on A's face of it; its window (north, 2).
    assert_eq!(
        doors_of("office-a"),
        [(0, [2.5, 3.15]), (1, [5.0, 5.5]), (2, [2.8, 7.0])]
    );
    // B shares A's east wall (its west, 3) and the corridor's north wall.
    assert_eq!(doors_of("office-b"), [(0, [8.0, 3.15]), (3, [5.15, 5.5])]);
    // The lab, south of the corridor: the corridor's south door.
    assert_eq!(doors_of("lab"), [(2, [4.0, -0.15])]);
}

#[test]
fn walls_close_an_l_shaped_rooms_inner_corner_without_standing_in_the_room() {
    // 6 × 5 m less a 2.5 × 2 m notch: the walls turn right at (3.5, 3).
    let text = "name = \"l\"\nseed = 1\n[robot]\nat = [1.0, 1.0]\nheading_deg = 0.0\n\
        [[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [6.0, 0.0], [6.0, 3.0], [3.5, 3.0], [3.5, 5.0], [0.0, 5.0]]\n";
    let world = stucco_sim::WorldSpec::parse(text, "l").expect("a world");
    let caster = stucco_sim::SpaceCaster::new(&stucco_sim::Layout::of(&world));
    // Just south of the notch, east to the far wall; just west of it,
    // north to the far wall.
    let east = caster.cast([3.0, 2.95, 1.0], [1.0, 0.0, 0.0], 10.0, 0.0);
    let north = caster.cast([3.45, 2.5, 1.0], [0.0, 1.0, 0.0], 10.0, 0.0);
    assert!(east.is_some_and(|s| (s - 3.0).abs() < 1e-9), "{east:?}");
    assert!(north.is_some_and(|s| (s - 2.5).abs() < 1e-9), "{north:?}");
    // The notch's own walls are there.
    let notch = caster.cast([4.5, 2.5, 1.0], [0.0, 1.0, 0.0], 10.0, 0.0);
    assert!(notch.is_some_and(|s| (s - 0.5).abs() < 1e-9), "{notch:?}");
}
