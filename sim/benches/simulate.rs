//! The simulator's speed: ten simulated seconds of one robot on the
//! apartment's tour (IBEO laser 8 Hz × 450 beams, odometry 50 Hz, range
//! camera 5 Hz, physics 100 Hz, four people walking), setup outside the
//! timed loop. The real-time factor is 10 s over the median.
//! `cargo bench -p stucco-sim --bench simulate -- --noplot`
#![allow(clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use stucco_core::Platform;
use stucco_sim::{SimConfig, Simulator, TourDriver, WorldSpec};

fn simulate(c: &mut Criterion) {
    let mut g = c.benchmark_group("simulate-10s");
    for name in ["apartment", "reference-room"] {
        let path = format!("{}/worlds/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let world = WorldSpec::load(Path::new(&path)).expect("a world");
        let vehicle = SimConfig::default().vehicle;
        g.bench_function(name, |b| {
            b.iter_batched(
                || {
                    (
                        Simulator::new(&world, SimConfig::default(), None),
                        TourDriver::new(world.tour.clone(), 0.5),
                    )
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
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10))
        .sample_size(20);
    targets = simulate
}
criterion_main!(benches);
