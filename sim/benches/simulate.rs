//! The simulator's speed: ten simulated seconds of one robot on the
//! apartment's tour (IBEO laser 8 Hz × 450 beams, odometry 50 Hz, range
//! camera 5 Hz, physics 100 Hz, four people walking), setup outside the
//! timed loop, with the cameras cast by the simulator's own caster and,
//! beside it, through rapier as before (the baseline). The real-time
//! factor is 10 s over the median. And a camera's profile of rays alone,
//! both ways, on the same rays.
//! `cargo bench -p stucco-sim --bench simulate -- --noplot`
#![allow(clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use stucco_core::Platform;
use stucco_sim::{Layout, Scene, SimConfig, Simulator, TourDriver, WorldSpec, cast, cast_rapier};

fn simulate(c: &mut Criterion) {
    let mut g = c.benchmark_group("simulate-10s");
    for name in ["apartment", "reference-room"] {
        let path = format!("{}/worlds/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let world = WorldSpec::load(Path::new(&path)).expect("a world");
        let vehicle = SimConfig::default().vehicle;
        for (label, rapier) in [("", false), ("/baseline-rapier-cameras", true)] {
            g.bench_function(format!("{name}{label}"), |b| {
                b.iter_batched(
                    || {
                        let mut sim = Simulator::new(&world, SimConfig::default(), None);
                        if rapier {
                            sim.cast_cameras_through_rapier();
                        }
                        (sim, TourDriver::new(world.tour.clone(), 0.5))
                    },
                    |(mut sim, mut driver)| {
                        for _ in 0..500 {
                            let pose = sim.truth().drive.pose;
                            sim.command(driver.command(&pose, &vehicle));
                            black_box(sim.advance(0.02));
                        }
                    },
                    criterion::BatchSize::LargeInput,
                );
            });
        }
    }
    g.finish();
}

/// A camera's profile: 200 rays from 1.2 m up fanned from the floor to
/// the ceiling across a wall of the apartment, cast by the simulator's
/// caster and through rapier.
fn camera_rays(c: &mut Criterion) {
    let path = format!("{}/worlds/apartment.toml", env!("CARGO_MANIFEST_DIR"));
    let world = WorldSpec::load(Path::new(&path)).expect("a world");
    let layout = Layout::of(&world);
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(1);
    let scene = Scene::build(
        &layout,
        &world.people,
        &SimConfig::default().vehicle,
        &mut rng,
    );
    let o = [world.robot.at[0], world.robot.at[1], 1.2];
    let rays: Vec<[f64; 3]> = (0..200)
        .map(|i| {
            let el = -1.2 + 2.4 * f64::from(i) / 199.0;
            let az = world.robot.heading_deg.to_radians() + std::f64::consts::FRAC_PI_2;
            [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]
        })
        .collect();
    let mut g = c.benchmark_group("camera-profile-200-rays");
    g.bench_function("grid", |b| {
        b.iter(|| {
            rays.iter()
                .filter_map(|d| cast(&scene, o, *d, 10.0))
                .sum::<f64>()
        });
    });
    g.bench_function("baseline-rapier", |b| {
        b.iter(|| {
            rays.iter()
                .filter_map(|d| cast_rapier(&scene, o, *d, 10.0))
                .sum::<f64>()
        });
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10))
        .sample_size(20);
    targets = simulate, camera_rays
}
criterion_main!(benches);
