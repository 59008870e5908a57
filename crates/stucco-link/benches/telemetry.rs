//! What the robot's telemetry costs: one state message serialised and
//! published to an operator's session watching it (over a Unix socket);
//! one 450-echo scan; one second of everything the robot publishes (50
//! states, 10 scans, the map and the heartbeat: its time over a second is
//! the share of one core telemetry takes); and one telecommand's round
//! trip to its reply. Run with
//! `cargo bench -p stucco-link --bench telemetry -- --noplot`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use serde::Serialize;
use std::time::{Duration, Instant};
use stucco_core::{Ack, Command, Pose2, Reply, Stamp, Telecommand};
use stucco_link::{LinkConfig, OperatorClient, RobotLink, ScanFrame, keys, open};

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
    let others: Vec<_> = [keys::scan("r1"), keys::map("r1"), keys::heartbeat("r1")]
        .into_iter()
        .map(|k| op.watch(k).unwrap())
        .collect();
    let drain = || {
        while let Ok(Some(_)) = watch.try_recv() {}
        for w in &others {
            while let Ok(Some(_)) = w.try_recv() {}
        }
    };
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
    // A room's scan: 450 echoes.
    let scan = ScanFrame {
        stamp: Stamp::from_secs_f64(12.34),
        points: (0..450)
            .map(|i| {
                let a = (-135.0 + 0.6 * f64::from(i)).to_radians();
                let r = (2.5 / a.cos().abs()).min(1.5 / a.sin().abs());
                [(r * a.cos()) as f32, (r * a.sin()) as f32]
            })
            .collect(),
    };
    g.bench_function("publish_scan", |b| {
        b.iter(|| {
            robot.publish_scan(&scan).unwrap();
            drain();
        });
    });
    // A map as large as a furnished room's: doors, a window, furniture.
    let map = serde_json::json!({
        "stamp": 12_340_000_000i64,
        "pose": {"x": 2.5, "y": 0.6, "theta": 3.1},
        "position_sigma_m": 0.004, "heading_sigma_rad": 0.002,
        "room_m": [5.01, 2.85], "room_sigma_m": [0.003, 0.004],
        "walls_seen": [120, 340, 95, 410],
        "doors": [{"wall": "north", "position_m": 0.9, "width_m": 0.86, "sigma_m": 0.01},
                  {"wall": "east", "position_m": 1.2, "width_m": null, "sigma_m": 0.03}],
        "height_m": 2.6,
        "windows": [{"wall": "south", "along_m": [1.8, 3.2], "sill_head_m": [0.9, 2.1]}],
        "obstacles": [{"min": [0.2, 0.3], "max": [1.1, 0.9], "height_m": 1.0},
                      {"min": [3.0, 1.0], "max": [4.2, 1.8], "height_m": 1.0}],
    });
    g.bench_function("one_second", |b| {
        b.iter(|| {
            for k in 0..50 {
                robot.publish_state(&state).unwrap();
                if k % 5 == 0 {
                    robot.publish_scan(&scan).unwrap();
                }
            }
            robot.publish_map(&map).unwrap();
            robot.heartbeat(Stamp::ZERO).unwrap();
            drain();
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
