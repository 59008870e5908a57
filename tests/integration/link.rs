//! The robot process and the operator's console over zenoh, in one test
//! process: two sessions over a Unix socket in a temporary folder (never a
//! fixed TCP port).

use std::time::Duration;
use stucco_cli::{LinkConfig, Operator};
use stucco_core::telemetry::EventKind;
use stucco_core::{Command, Reply, Side, SurfaceId, WallName};

/// Robot `r1` standing by on a Unix socket in `dir`, and the link
/// configuration of a peer connecting to it.
fn robot_on_socket(dir: &std::path::Path, speed: f64) -> (crate::RunningRobot, LinkConfig) {
    let endpoint = format!("unixsock-stream/{}", dir.join("z.sock").display());
    let robot = crate::RunningRobot::start(
        "r1",
        LinkConfig {
            listen: vec![endpoint.clone()],
            ..LinkConfig::default()
        },
        speed,
    );
    let peer = LinkConfig {
        connect: vec![endpoint],
        ..LinkConfig::default()
    };
    (robot, peer)
}

/// `robot` moves `dx_m` forward on `op`'s command: accepted, then done.
fn forward_done(op: &mut Operator, robot: &str, dx_m: f64) {
    let command = Command::MoveRelative {
        dx_m,
        dy_m: 0.0,
        dtheta_deg: 0.0,
        landmark: None,
    };
    let r = op
        .send(robot, command, 10.0, Some(Duration::from_secs(30)))
        .unwrap();
    assert_eq!(r.ack.reply, Reply::Accepted);
    assert_eq!(r.last.map(|a| a.reply), Some(Reply::Done));
}

#[test]
fn an_operator_commands_a_robot_over_zenoh() {
    let dir = tempfile::tempdir().unwrap();
    let (robot, peer) = robot_on_socket(dir.path(), 10.0);
    let mut op = Operator::connect(&peer, "ann").unwrap();
    assert_eq!(op.list().unwrap(), ["r1"]);
    // A harmless query: done at once.
    let r = op.send("r1", Command::Status, 10.0, None).unwrap();
    assert_eq!(r.ack.reply, Reply::Done);
    // A move: accepted, then done.
    let r = op
        .send(
            "r1",
            Command::MoveRelative {
                dx_m: 0.5,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: None,
            },
            10.0,
            Some(Duration::from_secs(30)),
        )
        .unwrap();
    assert_eq!(r.ack.reply, Reply::Accepted);
    assert_eq!(r.last.map(|a| a.reply), Some(Reply::Done));
    // Stale: its deadline already past in the robot's time.
    let r = op.send("r1", Command::MapRoom, -1.0, None).unwrap();
    assert!(matches!(&r.ack.reply, Reply::Rejected { reason } if reason.contains("stale")));
    // A door it does not know.
    let r = op
        .send("r1", Command::PassDoor { door: 7 }, 10.0, None)
        .unwrap();
    assert!(matches!(&r.ack.reply, Reply::Rejected { reason } if reason.contains("not known")));
    // Round trips, measured (the figure is the bench's to report).
    let b = op.bench("r1", 50).unwrap();
    assert_eq!(b.count, 50);
    assert!(b.p50_ms > 0.0 && b.p50_ms <= b.p99_ms);
    // With an operator's heartbeat the link is up; a long move starts;
    // the heartbeat stops: the link is lost and the mission pauses.
    for _ in 0..10 {
        op.heartbeat("r1").unwrap();
        std::thread::sleep(Duration::from_millis(50));
    }
    let r = op
        .send(
            "r1",
            Command::MoveRelative {
                dx_m: 1.0,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: None,
            },
            10.0,
            None,
        )
        .unwrap();
    assert_eq!(r.ack.reply, Reply::Accepted);
    for _ in 0..4 {
        op.heartbeat("r1").unwrap();
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(600));
    let state = op.state("r1", Duration::from_secs(3)).unwrap();
    assert_eq!(state.mission.name(), "paused", "{state:?}");
    assert!(
        state.mission.reason().is_some_and(|r| r.contains("link")),
        "{state:?}"
    );
    robot.stop();
}

/// `stucco op NAME watch`: a person follows the robot in lines (state,
/// events, replies, the map), a program in JSON messages (scans too).
#[test]
fn an_operator_watches_a_robot() {
    let dir = tempfile::tempdir().unwrap();
    let (robot, peer) = robot_on_socket(dir.path(), 4.0);
    // Each watcher says when its first line came: it is subscribed, and
    // the command's events will reach it (a fixed wait lost the
    // task_started event on a loaded machine).
    let (ready, watching) = std::sync::mpsc::channel::<()>();
    let watcher = |json: bool| {
        let peer = peer.clone();
        let ready = ready.clone();
        std::thread::spawn(move || {
            let op = Operator::connect(&peer, "vic").unwrap();
            let mut lines = Vec::new();
            op.watch("r1", Some(8.0), json, |l| {
                if lines.is_empty() {
                    let _ = ready.send(());
                }
                lines.push(l);
            })
            .unwrap();
            lines
        })
    };
    let (person, program) = (watcher(false), watcher(true));
    for _ in 0..2 {
        watching.recv_timeout(Duration::from_secs(5)).unwrap();
    }
    let mut op = Operator::connect(&peer, "ann").unwrap();
    forward_done(&mut op, "r1", 0.3);
    let person = person.join().unwrap();
    let text = person.join("\n");
    let has = |needle: &str| person.iter().any(|l| l.contains(needle));
    assert!(has("state  running · task"), "{text}");
    assert!(has("pose ") && has("nearest "), "{text}");
    assert!(has("map    room "), "{text}");
    assert!(has("reply  accepted") && has("reply  done"), "{text}");
    assert!(has("event  task_started"), "{text}");
    // The map line comes again only when the map changes.
    let maps = person.iter().filter(|l| l.contains("map    room")).count();
    assert!(maps < 4, "{text}");
    let program: Vec<serde_json::Value> = program
        .join()
        .unwrap()
        .iter()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let topic = |t: &'static str| program.iter().filter(move |m| m["topic"] == t);
    let scan = topic("scan").next().expect("no scan");
    assert!(
        scan["message"]["points"].as_array().unwrap().len() > 100,
        "{scan}"
    );
    // Scans 10 a second of the robot's time (here 4× the wall clock).
    assert!(topic("scan").count() > 100, "{}", topic("scan").count());
    assert!(topic("map").next().unwrap()["message"]["room_m"].is_array());
    assert!(topic("state").count() > 100);
    robot.stop();
}

/// A site: a router, two robots and an operator connected to it as
/// clients; the operator sees both robots and commands each by name.
#[test]
fn two_robots_and_an_operator_through_a_router() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = format!(
        "unixsock-stream/{}",
        dir.path().join("router.sock").display()
    );
    let _router = stucco_cli::router(&LinkConfig {
        listen: vec![endpoint.clone()],
        ..LinkConfig::default()
    })
    .unwrap();
    let client = LinkConfig {
        mode: stucco_cli::LinkMode::Client,
        connect: vec![endpoint],
        ..LinkConfig::default()
    };
    let robots: Vec<_> = ["r1", "r2"]
        .into_iter()
        .map(|name| crate::RunningRobot::start(name, client.clone(), 10.0))
        .collect();
    std::thread::sleep(Duration::from_millis(800));
    let mut op = Operator::connect(&client, "ann").unwrap();
    assert_eq!(op.list().unwrap(), ["r1", "r2"]);
    for name in ["r1", "r2"] {
        let r = op.send(name, Command::Status, 10.0, None).unwrap();
        assert_eq!(r.ack.reply, Reply::Done, "{name}");
    }
    forward_done(&mut op, "r2", 0.3);
    for r in robots {
        r.stop();
    }
}

/// Under up to 1 s of delay each way, 20% loss, duplication and
/// reordering between operator and robot, every command of the
/// vocabulary is carried out exactly once or refused with a reason.
#[test]
fn over_a_faulty_link_every_command_runs_once_or_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (robot, peer) = robot_on_socket(dir.path(), 5.0);
    // The robot's own events, seen directly, to count what it did.
    let watcher = Operator::connect(&peer, "watcher").unwrap();
    let events = watcher.events("r1").unwrap();
    // The operator talks to the relay only; the relay to the robot.
    let relay_endpoint = format!(
        "unixsock-stream/{}",
        dir.path().join("relay.sock").display()
    );
    let relay = stucco_cli::FaultyRelay::start(
        &LinkConfig {
            listen: vec![relay_endpoint.clone()],
            connect: peer.connect.clone(),
            ..LinkConfig::default()
        },
        "faulty",
        "r1",
        stucco_cli::Faults {
            max_delay_s: 1.0,
            loss: 0.2,
            duplication: 0.1,
        },
        8,
    )
    .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let mut op = Operator::connect(
        &LinkConfig {
            connect: vec![relay_endpoint],
            ..LinkConfig::default()
        },
        "ann",
    )
    .unwrap();
    // In an order whose outcome is known: standing by, paused and resumed,
    // a door it does not know, a jog, the wait answered (the mission is
    // done, so skip is refused), a move reopens it, a wall to follow and an
    // alignment refused (the operator typed a standoff of -1 m), a room map
    // and stop pausing it (sent at once: the map looks only for what the
    // robot has not seen, in seconds, no longer round a loop), plastering
    // refused (this robot carries no spray tool), abort ends it. (Tasks that start and then fail are the
    // executive's tests': here a failed task would end the mission.)
    let vocabulary = [
        Command::Status,
        Command::Pause,
        Command::Resume,
        Command::PassDoor { door: 3 },
        Command::Jog {
            speed_mps: 0.1,
            steer_rad: 0.0,
            ttl_s: 0.3,
        },
        Command::Continue,
        Command::Skip,
        Command::MoveRelative {
            dx_m: 0.3,
            dy_m: 0.0,
            dtheta_deg: 0.0,
            landmark: None,
        },
        Command::FollowWall {
            wall: WallName::SOUTH,
            standoff_m: -1.0,
            from_m: 2.6,
            to_m: 3.6,
        },
        Command::AlignToWall {
            wall: WallName::SOUTH,
            standoff_m: -1.0,
            at_m: 3.4,
            side: Side::Left,
        },
        Command::MapRoom,
        Command::Stop,
        Command::PlasterSurface {
            surface: SurfaceId::Ceiling,
            region: None,
        },
        Command::GoToRoom {
            room: "hall".to_owned(),
        },
        Command::Abort,
    ];
    let mut refusals = Vec::new();
    for command in vocabulary {
        let r = op.send("faulty", command.clone(), 20.0, None).unwrap();
        match &r.ack.reply {
            Reply::Rejected { reason } => {
                assert!(!reason.is_empty());
                refusals.push(reason.clone());
            }
            Reply::Failed { .. } => panic!("{command:?}: {:?}", r.ack),
            _ => {}
        }
        // Let retries still in flight arrive, as they would on a bad link.
        std::thread::sleep(Duration::from_millis(1500));
    }
    std::thread::sleep(Duration::from_secs(2));
    drop(relay);
    robot.stop();
    let mut kinds: Vec<String> = Vec::new();
    for e in events.drain() {
        kinds.push(e.kind.name().to_owned());
        if let EventKind::TaskStarted { name, .. } = &e.kind {
            kinds.push(format!("started {name}"));
        }
    }
    let count = |k: &str| kinds.iter().filter(|x| *x == k).count();
    // Each task command ran once; pause and stop paused once each, resume
    // resumed once, abort ended it once.
    assert_eq!(count("started move_relative"), 1, "{kinds:?}");
    assert_eq!(count("started map_room"), 1, "{kinds:?}");
    // Refused, each with its reason: the door, skip, the two standoffs,
    // the spray tool, a room without a floor plan.
    assert_eq!(refusals.len(), 6, "{refusals:?}");
    assert!(
        refusals.iter().any(|r| r.contains("no floor plan")),
        "{refusals:?}"
    );
    assert_eq!(
        refusals.iter().filter(|r| r.contains("standoff_m")).count(),
        2,
        "{refusals:?}"
    );
    assert!(refusals.iter().any(|r| r.contains("spray")), "{refusals:?}");
    for refused in ["follow_wall", "align_to_wall", "plaster"] {
        assert_eq!(count(&format!("started {refused}")), 0, "{kinds:?}");
    }
    assert_eq!(count("paused"), 2, "{kinds:?}");
    assert_eq!(count("resumed"), 1, "{kinds:?}");
    assert_eq!(count("aborted"), 1, "{kinds:?}");
}

/// On the office floor's plan, the operator sends the robot from the
/// corridor into office A and on into B: each done, the robot's state
/// naming the room it is in; a room the plan does not have is refused,
/// naming those it has.
#[test]
fn an_operator_sends_the_robot_from_room_to_room() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = format!("unixsock-stream/{}", dir.path().join("z.sock").display());
    let robot = crate::RunningRobot::start_on(
        "robot-floor",
        "r1",
        LinkConfig {
            listen: vec![endpoint.clone()],
            ..LinkConfig::default()
        },
        10.0,
    );
    let peer = LinkConfig {
        connect: vec![endpoint],
        ..LinkConfig::default()
    };
    let mut op = Operator::connect(&peer, "ann").unwrap();
    // Left unread while the robot drives: it must not hold the robot up.
    let states = op.states("r1").unwrap();
    let go = |room: &str| Command::GoToRoom {
        room: room.to_owned(),
    };
    let r = op.send("r1", go("kitchen"), 10.0, None).unwrap();
    assert!(
        matches!(&r.ack.reply, Reply::Rejected { reason } if reason.contains("office-a")),
        "{:?}",
        r.ack
    );
    for room in ["office-a", "office-b"] {
        let r = op
            .send("r1", go(room), 10.0, Some(Duration::from_secs(60)))
            .unwrap();
        assert_eq!(r.ack.reply, Reply::Accepted);
        assert_eq!(r.last.map(|a| a.reply), Some(Reply::Done), "{room}");
        std::thread::sleep(Duration::from_millis(300));
        let last = states.drain().pop().unwrap();
        assert_eq!(last.room.as_deref(), Some(room), "{last:?}");
    }
    robot.stop();
}

/// The operator jogs the robot and vanishes (its session closed): the
/// robot stops at the jog's time to live, within 0.3 s of it.
#[test]
fn a_jog_stops_at_its_time_to_live_when_the_operator_is_gone() {
    let dir = tempfile::tempdir().unwrap();
    let (robot, peer) = robot_on_socket(dir.path(), 1.0);
    let watcher = Operator::connect(&peer, "watcher").unwrap();
    let states = watcher.states("r1").unwrap();
    let ttl = 0.5;
    let accepted_at = {
        let mut op = Operator::connect(&peer, "ann").unwrap();
        let r = op
            .send(
                "r1",
                Command::Jog {
                    speed_mps: 0.1,
                    steer_rad: 0.0,
                    ttl_s: ttl,
                },
                10.0,
                None,
            )
            .unwrap();
        assert_eq!(r.ack.reply, Reply::Accepted);
        r.ack.stamp
        // The operator's session closes here.
    };
    std::thread::sleep(Duration::from_secs(2));
    let seen = states.drain();
    robot.stop();
    // The robot's own clock: the last period it drove, after the jog began.
    let driving: Vec<i64> = seen
        .iter()
        .filter(|s| s.drive.speed_mps > 0.0)
        .map(|s| s.stamp.as_nanos())
        .collect();
    assert!(!driving.is_empty(), "the jog never drove");
    let last = stucco_core::Stamp::from_nanos(*driving.iter().max().unwrap());
    let after_ttl = last.seconds_since(accepted_at) - ttl;
    println!("the jog's last driving period began {after_ttl:+.3} s from its time to live");
    assert!(
        after_ttl <= 0.3,
        "drove {after_ttl:.3} s past the time to live"
    );
    // And nothing drove later.
    assert!(seen.iter().any(|s| s.stamp > last));
}

/// With a watcher connected to a robot (a peer with no endpoint of its
/// own), an operator's session opened next does not wait for it: zenoh's
/// gossip tells of the watcher, which cannot be reached, and opening
/// waited the whole scouting delay (500 ms) for it before the first
/// command could go out.
#[test]
fn a_watcher_connected_to_the_robot_does_not_hold_up_the_next_operator() {
    let dir = tempfile::tempdir().unwrap();
    let (robot, peer) = robot_on_socket(dir.path(), 1.0);
    let watcher = Operator::connect(&peer, "watcher").unwrap();
    let _states = watcher.states("r1").unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let mut opening = Vec::new();
    for _ in 0..7 {
        let t0 = std::time::Instant::now();
        let mut op = Operator::connect(&peer, "ann").unwrap();
        opening.push(t0.elapsed());
        let r = op.send("r1", Command::Status, 10.0, None).unwrap();
        assert_eq!(r.ack.reply, Reply::Done);
    }
    robot.stop();
    // The scouting delay is a fixed 500 ms wait: an opening that waited it
    // is no slow machine's doing.
    assert!(
        opening.iter().all(|t| *t < Duration::from_millis(450)),
        "{opening:?}"
    );
}
