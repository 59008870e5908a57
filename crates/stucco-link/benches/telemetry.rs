//! What the robot's telemetry costs: one state message serialised and
//! published to an operator's session watching it (over a Unix socket),
//! and one telecommand's round trip to its reply. At 50 states a second
//! the first, times 50, is the share of one core telemetry takes; run with
//! `cargo bench -p stucco-link --bench telemetry -- --noplot`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use serde::Serialize;
use std::time::{Duration, Instant};
use stucco_core::{Ack, Command, Pose2, Reply, Stamp, Telecommand};
use stucco_link::{LinkConfig, OperatorClient, RobotLink, keys, open};

/// A state as large as the robot's.
#[derive(Serialize)]
struct State {
    stamp: Stamp,
    name: &'static str,
    mission: &'static str,
    task: (usize, &'static str),
    behaviour: &'static str,
    pose: Pose2,
    position_sigma_m: f64,
}

fn telemetry(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = format!("unixsock-stream/{}", dir.path().join("z.sock").display());
    let robot_session = open(&LinkConfig {
        listen: vec![endpoint.clone()],
        ..LinkConfig::default()
    })
    .unwrap();
    let mut robot = RobotLink::new(&robot_session, "r1").unwrap();
    let op_session = open(&LinkConfig {
        connect: vec![endpoint],
        ..LinkConfig::default()
    })
    .unwrap();
    let op = OperatorClient::new(op_session);
    let watch = op.watch(keys::state("r1")).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let state = State {
        stamp: Stamp::from_secs_f64(12.34),
        name: "r1",
        mission: "running",
        task: (2, "follow_wall"),
        behaviour: "follow_wall",
        pose: Pose2::new(2.5, 0.6, 3.1),
        position_sigma_m: 0.004,
    };
    let mut g = c.benchmark_group("telemetry");
    g.bench_function("publish_state", |b| {
        b.iter(|| {
            robot.publish_state(&state).unwrap();
            // Keep the watcher's queue drained, as a console would.
            while let Ok(Some(_)) = watch.try_recv() {}
        });
    });
    g.finish();
    // A command's round trip, the robot answering from another thread.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let answering = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                let cmds = robot.wait_commands(Stamp::ZERO, Duration::from_millis(20));
                let acks: Vec<Ack> = cmds
                    .iter()
                    .map(|t| Ack {
                        id: t.id.clone(),
                        stamp: Stamp::ZERO,
                        reply: Reply::Done,
                    })
                    .collect();
                robot.send_acks(&acks).unwrap();
            }
        })
    };
    let mut g = c.benchmark_group("command");
    let mut k = 0u64;
    g.bench_function("round_trip", |b| {
        b.iter(|| {
            k += 1;
            let t = Telecommand {
                id: format!("b{k}"),
                operator: "ann".into(),
                issued: Stamp::ZERO,
                deadline: Stamp::from_secs_f64(1e6),
                command: Command::Status,
            };
            op.send(
                "r1",
                &t,
                Duration::from_millis(500),
                Instant::now() + Duration::from_secs(5),
            )
            .unwrap()
        });
    });
    g.finish();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    answering.join().unwrap();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(30);
    targets = telemetry
}
criterion_main!(benches);
