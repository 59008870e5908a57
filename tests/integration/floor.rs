//! Floors mapped while driving, 20 seeds each at 0.5–1.0 m/s with the
//! robot's own laser and odometry: the office floor
//! (`sim/worlds/floor.toml`: a corridor, four rooms, two of them the same
//! size, a loop through them) and the apartment (`apartment.toml`: the
//! living room, the hall crossed into the bedroom and backed out of it).
//! The walls of the map against the true walls, nothing left in it that
//! lies along no surface, and the room graph against the rooms and doors
//! driven through.

use rayon::prelude::*;
use std::path::PathBuf;
use stucco_cli::{FloorRun, map_floor};
use stucco_sim::WorldSpec;

fn world(file: &str) -> WorldSpec {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../sim/worlds")).join(file);
    WorldSpec::load(&path).unwrap()
}

/// Maps `file` along its tour `tour` for `seconds` on `seeds` seeds from
/// `first`, their speeds spread from 0.5 to 1.0 m/s, and asserts issue 5's
/// figures: the walls within 1 cm / 0.3° RMS, none along no surface, and
/// the room graph right in 19 runs of 20.
fn map_seeds(file: &str, tour: &str, first: u64, seeds: u64, seconds: f64) {
    let world = world(file);
    let tour = world.tour_named(tour).unwrap();
    let runs: Vec<FloorRun> = (0..seeds)
        .into_par_iter()
        .map(|k| {
            let speed = 0.5 + 0.5 * k as f64 / (seeds - 1).max(1) as f64;
            map_floor(&world, &tour, first + k, speed, seconds).unwrap()
        })
        .collect();
    let mut correct = 0;
    for r in &runs {
        eprintln!(
            "seed {} at {:.2} m/s: {} walls, {:.1} mm / {:.3}° RMS, {} stray; RPE {:.4} m {:.5} rad; {} rooms, {} doors{}",
            r.seed,
            r.speed_mps,
            r.walls,
            r.wall_dist_rms_m * 1e3,
            r.wall_angle_rms_rad.to_degrees(),
            r.stray_walls,
            r.rpe.trans_mean_m,
            r.rpe.rot_mean_rad,
            r.graph.rooms().len(),
            r.graph.doors().len(),
            r.graph_fault
                .as_ref()
                .map(|f| format!(" — {f}"))
                .unwrap_or_default()
        );
        correct += usize::from(r.graph_correct);
    }
    let n: f64 = runs.iter().map(|r| r.walls as f64).sum();
    let rms = |f: fn(&FloorRun) -> f64| {
        (runs
            .iter()
            .map(|r| f(r).powi(2) * r.walls as f64)
            .sum::<f64>()
            / n)
            .sqrt()
    };
    let (dist, angle) = (rms(|r| r.wall_dist_rms_m), rms(|r| r.wall_angle_rms_rad));
    eprintln!(
        "all seeds: {n} walls, {:.1} mm / {:.3}° RMS; graphs right {correct} of {seeds}; {} runs with a wall along no surface",
        dist * 1e3,
        angle.to_degrees(),
        runs.iter().filter(|r| r.stray_walls > 0).count()
    );
    assert!(dist <= 0.01, "{dist}");
    assert!(angle <= 0.3f64.to_radians(), "{angle}");
    let stray: Vec<u64> = runs
        .iter()
        .filter(|r| r.stray_walls > 0)
        .map(|r| r.seed)
        .collect();
    assert!(
        stray.is_empty(),
        "walls along no surface on seeds {stray:?}"
    );
    assert!(20 * correct >= 19 * seeds as usize, "{correct} of {seeds}");
}

#[test]
fn a_floor_is_mapped_with_its_rooms_and_doors() {
    map_seeds("floor.toml", "tour", 100, 20, 200.0);
}

#[test]
fn the_apartment_is_mapped_through_its_hall() {
    map_seeds("apartment.toml", "through-the-hall", 200, 20, 120.0);
}

/// Both floors on 100 seeds the default run's tests were never tuned on
/// (1000–1099): whether their figures hold beyond the 20 seeds each.
#[test]
#[ignore = "study: 200 floor runs; run with --release -- --ignored --nocapture"]
fn both_floors_hold_on_a_hundred_fresh_seeds() {
    map_seeds("floor.toml", "tour", 1000, 100, 200.0);
    map_seeds("apartment.toml", "through-the-hall", 1000, 100, 120.0);
}
