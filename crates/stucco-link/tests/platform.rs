//! The platform keys between a brain ([`ZenohPlatform`]) and a body
//! ([`PlatformServer`]) in two sessions over a Unix socket: lockstep
//! steps once per command even when readings are lost and the command
//! comes again; free-running, a period gathers every message the
//! platform's clock put in it; a platform gone fails the brain's period
//! with its name, it does not hang.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;
use stucco_core::{
    DriveCommand, EncoderSample, Platform, Readings, RobotSpec, Scan, Stamp, ToolCommand,
};
use stucco_link::platform::{PlatformInfo, PlatformReadings};
use stucco_link::{LinkConfig, PlatformServer, Session, ZenohPlatform, open};
use zenoh::Wait;

fn pair(dir: &std::path::Path) -> (Session, Session) {
    let endpoint = format!("unixsock-stream/{}", dir.join("z.sock").display());
    let body = open(&LinkConfig {
        listen: vec![endpoint.clone()],
        ..LinkConfig::default()
    })
    .unwrap();
    let brain = open(&LinkConfig {
        connect: vec![endpoint],
        ..LinkConfig::default()
    })
    .unwrap();
    (body, brain)
}

/// A body whose encoders count the drive's speed in mm per period and
/// whose laser returns one beam at the commanded steering; `lose` names a
/// period whose command it does not hear the first time (lost on the
/// way).
struct Body {
    stop: Arc<AtomicBool>,
    /// Periods stepped.
    stepped: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

impl Body {
    fn lockstep(session: Session, lose: Option<u64>) -> Body {
        let stop = Arc::new(AtomicBool::new(false));
        let stepped = Arc::new(AtomicU64::new(0));
        let (s, n) = (stop.clone(), stepped.clone());
        let thread = std::thread::spawn(move || {
            let mut server = PlatformServer::new(&session, "b1").unwrap();
            let mut now = Stamp::ZERO;
            let mut ticks = 0;
            let mut last = None;
            let mut lost = false;
            while !s.load(Ordering::Relaxed) {
                let info = || PlatformInfo {
                    name: "b1".into(),
                    spec: RobotSpec::default(),
                    now,
                    lockstep: true,
                    period_s: 0.02,
                };
                server.answer(info, || Err("no world".into())).unwrap();
                let Some(cmd) = server.next_command(Duration::from_millis(20)) else {
                    continue;
                };
                if Some(cmd.period) == lose && !lost {
                    lost = true;
                    continue;
                }
                if last == Some(cmd.period) {
                    assert!(server.republish(cmd.period).unwrap());
                    continue;
                }
                last = Some(cmd.period);
                n.fetch_add(1, Ordering::Relaxed);
                now = now.offset_secs(cmd.dt_s);
                ticks += (cmd.drive.speed_mps * 1000.0 * cmd.dt_s).round() as i64;
                let readings = PlatformReadings {
                    period: cmd.period,
                    now,
                    readings: Readings {
                        encoders: vec![EncoderSample {
                            stamp: now,
                            left_ticks: ticks,
                            right_ticks: ticks,
                        }],
                        scans: vec![Scan {
                            stamp: now,
                            sensor: "laser".into(),
                            angle_min_rad: cmd.drive.steer_rad,
                            angle_increment_rad: 0.01,
                            sweep_duration_s: 0.0,
                            max_range_m: 8.0,
                            ranges_m: vec![1.5, f64::INFINITY],
                        }],
                        profiles: Vec::new(),
                        bumper: cmd.period == 7,
                    },
                    truth: None,
                };
                server.publish(&readings).unwrap();
            }
        });
        Body {
            stop,
            stepped,
            thread: Some(thread),
        }
    }

    /// A body stepping on its own clock, `period_s` a period, holding the
    /// last speed.
    fn free(session: Session, period_s: f64) -> Body {
        let stop = Arc::new(AtomicBool::new(false));
        let stepped = Arc::new(AtomicU64::new(0));
        let (s, n) = (stop.clone(), stepped.clone());
        let thread = std::thread::spawn(move || {
            let mut server = PlatformServer::new(&session, "b1").unwrap();
            let mut now = Stamp::ZERO;
            let mut k = 0;
            while !s.load(Ordering::Relaxed) {
                let info = || PlatformInfo {
                    name: "b1".into(),
                    spec: RobotSpec::default(),
                    now,
                    lockstep: false,
                    period_s,
                };
                server.answer(info, || Err("no world".into())).unwrap();
                let _ = server.take_commands();
                k += 1;
                now = now.offset_secs(period_s);
                n.fetch_add(1, Ordering::Relaxed);
                server
                    .publish(&PlatformReadings {
                        period: k,
                        now,
                        readings: Readings {
                            encoders: vec![EncoderSample {
                                stamp: now,
                                left_ticks: k as i64,
                                right_ticks: k as i64,
                            }],
                            ..Readings::default()
                        },
                        truth: None,
                    })
                    .unwrap();
                std::thread::sleep(Duration::from_secs_f64(period_s));
            }
        });
        Body {
            stop,
            stepped,
            thread: Some(thread),
        }
    }
}

impl Drop for Body {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[test]
fn lockstep_steps_once_per_command_and_recovers_a_lost_command() {
    let dir = tempfile::tempdir().unwrap();
    let (body_session, brain) = pair(dir.path());
    let body = Body::lockstep(body_session, Some(4));
    let mut p = ZenohPlatform::connect(&brain, "b1", Duration::from_secs(10)).unwrap();
    assert!(p.info().lockstep);
    assert_eq!(p.now(), Stamp::ZERO);
    let mut bumped = Vec::new();
    for k in 1..=10u64 {
        p.command(DriveCommand {
            speed_mps: 0.5,
            steer_rad: 0.1 * k as f64,
        });
        p.tool(ToolCommand::default());
        let r = p.advance(0.02).unwrap();
        // Exactly the period's readings, what the command asked in them.
        assert_eq!(r.encoders.len(), 1, "period {k}");
        assert_eq!(r.encoders[0].left_ticks, 10 * k as i64);
        assert_eq!(r.scans[0].angle_min_rad, 0.1 * k as f64);
        assert!(r.scans[0].ranges_m[1].is_infinite(), "no return kept");
        assert_eq!(p.now(), Stamp::from_secs_f64(0.02 * k as f64));
        if r.bumper {
            bumped.push(k);
        }
    }
    assert_eq!(bumped, [7]);
    // Period 4's command was lost once: sent again, stepped once.
    assert_eq!(body.stepped.load(Ordering::Relaxed), 10);
}

#[test]
fn free_running_a_period_gathers_what_the_platform_clock_put_in_it() {
    let dir = tempfile::tempdir().unwrap();
    let (body_session, brain) = pair(dir.path());
    let _body = Body::free(body_session, 0.005);
    let mut p = ZenohPlatform::connect(&brain, "b1", Duration::from_secs(10)).unwrap();
    assert!(!p.info().lockstep);
    let mut encoders = Vec::new();
    for _ in 0..10 {
        let before = p.now();
        let r = p.advance(0.02).unwrap();
        // The platform's clock went a period on, give or take half of
        // one of its own.
        assert!(p.now().seconds_since(before) >= 0.02 - 0.0025);
        encoders.extend(r.encoders);
    }
    // In order, none twice.
    let ticks: Vec<i64> = encoders.iter().map(|e| e.left_ticks).collect();
    assert!(ticks.windows(2).all(|w| w[1] == w[0] + 1), "{ticks:?}");
    assert!(ticks.len() >= 30, "{ticks:?}");
}

#[test]
fn a_platform_gone_fails_the_period_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let (body_session, brain) = pair(dir.path());
    let body = Body::lockstep(body_session, None);
    let mut p = ZenohPlatform::connect(&brain, "b1", Duration::from_secs(2)).unwrap();
    p.advance(0.02).unwrap();
    drop(body);
    let e = p.advance(0.02).unwrap_err();
    assert!(e.to_string().contains("b1"), "{e}");
    assert!(e.to_string().contains("period 2"), "{e}");
    // Nobody answers a brain looking for a platform that is not there.
    let e = ZenohPlatform::connect(&brain, "nobody", Duration::from_millis(300))
        .err()
        .expect("no platform");
    assert!(e.to_string().contains("nobody"), "{e}");
}

#[test]
fn malformed_messages_are_refused_naming_the_key_and_where() {
    let dir = tempfile::tempdir().unwrap();
    let (body, brain) = pair(dir.path());
    let mut server = PlatformServer::new(&body, "b1").unwrap();
    // A command that is not one is skipped; the next good one is taken.
    let commands = brain
        .declare_publisher(stucco_link::platform::keys::command("b1"))
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(200));
    commands
        .put("{\"period\": 1, \"dt_s\": \"soon\"}")
        .wait()
        .unwrap();
    let good = stucco_link::platform::PlatformCommand {
        period: 2,
        dt_s: 0.02,
        drive: DriveCommand::STOP,
        tool: ToolCommand::default(),
    };
    commands
        .put(serde_json::to_vec(&good).unwrap())
        .wait()
        .unwrap();
    assert_eq!(server.next_command(Duration::from_secs(5)), Some(good));
    // Readings that are not readings fail the brain's period, naming the
    // key and the place in the message.
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let liar = std::thread::spawn(move || {
        let readings = body
            .declare_publisher(stucco_link::platform::keys::readings("b1"))
            .wait()
            .unwrap();
        while !s.load(Ordering::Relaxed) {
            let info = || PlatformInfo {
                name: "b1".into(),
                spec: RobotSpec::default(),
                now: Stamp::ZERO,
                lockstep: true,
                period_s: 0.02,
            };
            server.answer(info, || Err("no world".into())).unwrap();
            if server.next_command(Duration::from_millis(20)).is_some() {
                readings
                    .put("{\"period\": 1,\n \"now\": -}")
                    .wait()
                    .unwrap();
            }
        }
    });
    let mut p = ZenohPlatform::connect(&brain, "b1", Duration::from_secs(10)).unwrap();
    let e = p.advance(0.02).unwrap_err().to_string();
    stop.store(true, Ordering::Relaxed);
    liar.join().unwrap();
    assert!(e.contains("stucco/b1/platform/readings"), "{e}");
    assert!(e.contains("line 2"), "{e}");
}
