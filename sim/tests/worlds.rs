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
