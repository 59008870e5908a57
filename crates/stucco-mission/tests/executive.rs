//! The executive on a kinematic tricycle with a perfect estimate: each task
//! ends where it should, the mission's states and events follow the
//! operator, the supervisor stops for what is in the way, and a mission
//! resumed from its progress never does a finished task again.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use nalgebra::Point2;
use std::collections::BTreeMap;
use stucco_control::{GainSchedule, Limiter};
use stucco_core::{
    Ack, Command, DriveCommand, Pose2, Reply, Stamp, SurfaceId, Telecommand, Twist2, VehicleSpec,
    wrap_angle,
};
use stucco_mission::*;
use stucco_plan::Rect;

const DT: f64 = 0.02;
const ROOM: [f64; 2] = [5.0, 3.0];

/// The robot: a kinematic tricycle behind the vehicle's limits.
struct Robot {
    pose: Pose2,
    limiter: Limiter,
    spec: VehicleSpec,
    now: Stamp,
    room_sigma: [f64; 2],
    doors: Vec<DoorEstimate>,
    /// The plan's room the pose is in, and its size.
    room: Option<usize>,
    room_m: [f64; 2],
    /// σ of the position, m.
    position_sigma: f64,
    /// What the map has standing on the floor.
    floor: Vec<stucco_plan::Obstacle>,
    /// The windows the cameras have found.
    windows: Vec<WindowEstimate>,
    /// Scans each wall has been seen in.
    walls_seen: Vec<usize>,
}

impl Robot {
    fn at(pose: Pose2) -> Self {
        let spec = VehicleSpec::default();
        Robot {
            pose,
            limiter: Limiter::new(&spec),
            spec,
            now: Stamp::ZERO,
            room_sigma: [0.001; 2],
            doors: Vec::new(),
            room: None,
            room_m: ROOM,
            position_sigma: 0.003,
            floor: Vec::new(),
            windows: Vec::new(),
            walls_seen: vec![100; 4],
        }
    }

    fn estimate(&self) -> Estimate {
        Estimate {
            stamp: self.now,
            pose: self.pose,
            position_sigma_m: self.position_sigma,
            heading_sigma_rad: 0.002,
            room_m: self.room_m,
            room_sigma_m: self.room_sigma,
            corners: Vec::new(),
            walls_seen: self.walls_seen.clone(),
            walls_sigma_m: Vec::new(),
            doors: self.doors.clone(),
            height_m: 2.6,
            windows: self.windows.clone(),
            obstacles: self.floor.clone(),
            room: self.room,
        }
    }

    /// In `room` of `plan`, knowing its doors as the plan places them.
    fn in_room(&mut self, plan: &FloorPlan, room: usize) {
        self.room = Some(room);
        self.room_m = plan.rooms()[room].size_m;
        self.doors = plan
            .doors_of(room)
            .map(|(door, side)| DoorEstimate {
                wall: side.wall,
                position_m: side.along_m,
                width_m: Some(plan.doors()[door].width_m),
                sigma_m: 0.01,
                plan_door: Some(door),
            })
            .collect();
    }

    /// Beyond `door` of `plan`: the frame moved into the next room, as the
    /// navigation core moves it.
    fn through(&mut self, plan: &FloorPlan, door: usize) {
        let room = self.room.unwrap();
        let along = plan.side(door, room).unwrap().along_m;
        let here = plan
            .door_middle(door, room, &[], self.room_m, along)
            .unwrap();
        let (next, pose) = plan.transfer(door, room, &self.pose, here, None).unwrap();
        self.in_room(plan, next);
        self.pose = pose;
    }

    fn drive(&mut self, cmd: DriveCommand) {
        let c = self.limiter.limit(cmd, DT);
        let v = c.speed_mps * c.steer_rad.cos();
        let w = c.speed_mps * c.steer_rad.sin() / self.spec.wheelbase_m;
        self.pose = self.pose * Twist2::new(v, 0.0, w).displacement(DT);
        self.now = self.now.offset_secs(DT);
    }
}

/// What the robot sees and hears in one tick, besides its estimate.
#[derive(Default)]
struct Seen<'a> {
    obstacles: &'a [Point2<f64>],
    unseen: &'a [Point2<f64>],
    bumper: bool,
    estop: bool,
    operator: &'a [OperatorCommand],
    telecommands: &'a [Telecommand],
}

/// One tick of `exec` with the laser seeing `obstacles` (robot frame).
fn ask_seeing(exec: &mut Executive, robot: &Robot, obstacles: &[Point2<f64>]) -> Outputs {
    ask(
        exec,
        robot,
        Seen {
            obstacles,
            ..Seen::default()
        },
    )
}

/// One tick of `exec` on `robot`'s estimate (the robot is not moved).
fn ask(exec: &mut Executive, robot: &Robot, seen: Seen) -> Outputs {
    let est = robot.estimate();
    exec.tick(
        robot.now,
        &Inputs {
            estimate: &est,
            obstacles: seen.obstacles,
            unseen: seen.unseen,
            bumper: seen.bumper,
            estop: seen.estop,
            operator: seen.operator,
            telecommands: seen.telecommands,
        },
    )
}

/// A straight move of `dx_m` at 0.3 m/s.
fn forward(dx_m: f64) -> TaskSpec {
    TaskSpec::MoveRelative {
        dx_m,
        dy_m: 0.0,
        dtheta_deg: 0.0,
        landmark: None,
        speed_mps: 0.3,
    }
}

/// The settings of the tests' robot.
fn config(unattended: bool) -> ExecutiveConfig {
    ExecutiveConfig {
        vehicle: VehicleSpec::default(),
        gains: GainSchedule::default(),
        safety: SafetyConfig::default(),
        unattended,
        spray: None,
        floor: None,
        body_camera_azimuth_rad: Some(std::f64::consts::FRAC_PI_2),
    }
}

fn executive(tasks: Vec<TaskSpec>, unattended: bool) -> Executive {
    Executive::new(config(unattended), tasks)
}

/// Runs until the mission is over or `seconds` pass; the events.
fn run(
    exec: &mut Executive,
    robot: &mut Robot,
    seconds: f64,
    mut operator: impl FnMut(Stamp, &Executive) -> Vec<OperatorCommand>,
) -> Vec<Event> {
    let mut events = Vec::new();
    let steps = (seconds / DT) as usize;
    for _ in 0..steps {
        let ops = operator(robot.now, exec);
        let out = ask(
            exec,
            robot,
            Seen {
                operator: &ops,
                ..Seen::default()
            },
        );
        events.extend(out.events);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    events
}

fn kinds(events: &[Event]) -> Vec<String> {
    events
        .iter()
        .map(|e| {
            serde_json::to_value(e).unwrap()["event"]
                .as_str()
                .unwrap()
                .to_owned()
        })
        .collect()
}

#[test]
fn move_relative_ends_at_the_goal_turning_on_the_spot() {
    let start = Pose2::new(1.5, 1.5, 0.0);
    let mut robot = Robot::at(start);
    let mut exec = executive(
        vec![TaskSpec::MoveRelative {
            dx_m: 1.0,
            dy_m: 0.5,
            dtheta_deg: 90.0,
            landmark: None,
            speed_mps: 0.3,
        }],
        true,
    );
    let events = run(&mut exec, &mut robot, 60.0, |_, _| Vec::new());
    assert_eq!(exec.mode(), &MissionMode::Done, "{events:?}");
    let goal = start * Pose2::new(1.0, 0.5, std::f64::consts::FRAC_PI_2);
    let err = (robot.pose.position() - goal.position()).norm();
    assert!(err < 0.02, "{err} m off: {:?}", robot.pose);
    assert!(wrap_angle(robot.pose.theta - goal.theta).abs() < 0.02);
    let k = kinds(&events);
    assert_eq!(k.first().map(String::as_str), Some("mission_started"));
    assert_eq!(k.iter().filter(|e| *e == "behaviour_started").count(), 3);
    assert_eq!(k.last().map(String::as_str), Some("mission_done"));
}

/// A pass along the south wall at 0.6 m, from 3 m to 4 m along it.
fn south_pass() -> TaskSpec {
    TaskSpec::FollowWall {
        wall: WallName::SOUTH,
        standoff_m: 0.6,
        from_m: 3.0,
        to_m: 4.0,
        speed_mps: 0.25,
    }
}

#[test]
fn follow_wall_keeps_the_standoff_and_stops_at_the_end_of_the_pass() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(vec![south_pass()], true);
    let mut worst = 0.0f64;
    let mut following = 0;
    let mut farthest = 0.0f64;
    let steps = (120.0 / DT) as usize;
    for _ in 0..steps {
        let out = ask(&mut exec, &robot, Seen { ..Seen::default() });
        // The pass proper: from `from_m` on, the standoff holds.
        if matches!(
            exec.current_behaviour(),
            Some(BehaviourKind::FollowWall { .. })
        ) && robot.pose.x >= 3.0
        {
            following += 1;
            worst = worst.max((robot.pose.y - 0.6).abs());
            farthest = farthest.max(robot.pose.x);
        }
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done);
    assert!(following > 100, "{following} steps along the wall");
    assert!(worst < 0.01, "standoff off by {worst} m");
    assert!(
        (farthest - 4.0).abs() < 0.02,
        "the pass ended at {farthest}"
    );
    // Then it backed out along the wall to where it turned in (1.01 m from
    // the west wall) and drove out to a lane as far from the south wall,
    // free to turn again.
    assert!(
        (robot.pose.x - 3.01).abs() < 0.02 && (robot.pose.y - 1.01).abs() < 0.02,
        "{:?}",
        robot.pose
    );
    assert!(robot.pose.theta.abs() < 0.02);
}

#[test]
fn a_pass_too_near_the_corner_is_refused_with_a_reason() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(
        vec![TaskSpec::FollowWall {
            wall: WallName::SOUTH,
            standoff_m: 0.6,
            from_m: 1.0,
            to_m: 4.0,
            speed_mps: 0.25,
        }],
        true,
    );
    run(&mut exec, &mut robot, 1.0, |_, _| Vec::new());
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?}", exec.mode());
    };
    assert!(reason.contains("too near the corner"), "{reason}");
    // And a pass running into the end wall.
    let mut exec = executive(
        vec![TaskSpec::FollowWall {
            wall: WallName::SOUTH,
            standoff_m: 0.6,
            from_m: 2.6,
            to_m: 4.6,
            speed_mps: 0.25,
        }],
        true,
    );
    run(&mut exec, &mut robot, 1.0, |_, _| Vec::new());
    assert!(
        matches!(exec.mode(), MissionMode::Failed { reason } if reason.contains("body reaches"))
    );
}

#[test]
fn a_failure_is_typed_in_events_and_replies_with_its_sentence() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(
        vec![TaskSpec::FollowWall {
            wall: WallName::SOUTH,
            standoff_m: 0.6,
            from_m: 1.0,
            to_m: 4.0,
            speed_mps: 0.25,
        }],
        true,
    );
    let events = run(&mut exec, &mut robot, 1.0, |_, _| Vec::new());
    let failure = exec.failure().cloned().expect("failed");
    assert!(
        matches!(failure, TaskFailure::PassStartsAtCorner { at_m, .. } if (at_m - 1.0).abs() < 1e-9),
        "{failure:?}"
    );
    assert_eq!(failure.code(), "pass_starts_at_corner");
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?}", exec.mode());
    };
    assert_eq!(reason, &failure.to_string());
    // The event log keeps the sentence where its readers find it, and the
    // failure typed beside it.
    let failed = events
        .iter()
        .find(|e| matches!(e.kind, EventKind::TaskFailed { .. }))
        .expect("a task_failed event");
    let json = serde_json::to_value(failed).expect("json");
    assert_eq!(json["event"], "task_failed");
    assert_eq!(json["reason"].as_str(), Some(reason.as_str()));
    assert_eq!(json["failure"]["code"], "pass_starts_at_corner");
    // A telecommand's task that fails is answered with the code and the
    // sentence.
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = standing_by();
    tick_with(&mut exec, &mut robot, &[]);
    let pass = command(
        "f1",
        Stamp::ZERO,
        Command::FollowWall {
            wall: WallName::SOUTH,
            standoff_m: 0.6,
            from_m: 1.0,
            to_m: 4.0,
        },
    );
    let mut replies = tick_with(&mut exec, &mut robot, &[pass]).acks;
    for _ in 0..10 {
        replies.extend(tick_with(&mut exec, &mut robot, &[]).acks);
    }
    let failed = replies
        .iter()
        .find(|a| a.id == "f1" && matches!(a.reply, Reply::Failed { .. }))
        .expect("the task failed");
    let Reply::Failed { reason, code } = &failed.reply else {
        unreachable!()
    };
    assert_eq!(code.as_deref(), Some("pass_starts_at_corner"));
    assert!(reason.contains("too near the corner"), "{reason}");
}

fn waiting_tasks() -> Vec<TaskSpec> {
    vec![
        TaskSpec::WaitForOperator {
            prompt: "ready?".to_owned(),
            timeout_s: None,
            on_timeout: OnTimeout::Fail,
        },
        forward(0.5),
        TaskSpec::WaitForOperator {
            prompt: "again?".to_owned(),
            timeout_s: Some(2.0),
            on_timeout: OnTimeout::Continue,
        },
    ]
}

#[test]
fn the_operator_pauses_resumes_and_answers() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(waiting_tasks(), false);
    let mut paused_at = None;
    let events = run(&mut exec, &mut robot, 60.0, |now, e| {
        let t = now.as_secs_f64();
        match (t, e.current_task()) {
            // The first task waits for its answer.
            (t, Some((0, _))) if t > 1.0 => vec![OperatorCommand::Continue],
            // Halfway through the move: pause for 2 s.
            (t, Some((1, _))) if paused_at.is_none() && t > 2.0 => {
                paused_at = Some(t);
                vec![OperatorCommand::Pause]
            }
            (t, _) if paused_at.is_some_and(|p| t > p + 2.0 && t < p + 2.03) => {
                vec![OperatorCommand::Resume]
            }
            _ => Vec::new(),
        }
    });
    assert_eq!(exec.mode(), &MissionMode::Done, "{events:?}");
    // The last wait timed out into `continue`.
    assert!(exec.status().iter().all(|s| *s == TaskStatus::Done));
    let k = kinds(&events);
    for want in [
        "operator_prompt",
        "paused",
        "resumed",
        "task_done",
        "mission_done",
    ] {
        assert!(k.iter().any(|e| e == want), "no {want} in {k:?}");
    }
    assert!((robot.pose.x - 2.0).abs() < 0.02);
}

#[test]
fn skip_and_abort_leave_the_progress_as_they_say() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(waiting_tasks(), false);
    let mut sent = 0;
    run(&mut exec, &mut robot, 10.0, |_, e| match e.current_task() {
        Some((0, _)) if sent == 0 => {
            sent += 1;
            vec![OperatorCommand::Skip]
        }
        Some((1, _)) if sent == 1 => {
            sent += 1;
            vec![OperatorCommand::Abort]
        }
        _ => Vec::new(),
    });
    assert_eq!(exec.mode(), &MissionMode::Aborted);
    assert_eq!(
        exec.status(),
        [
            TaskStatus::Skipped,
            TaskStatus::Pending,
            TaskStatus::Pending
        ]
    );
}

#[test]
fn a_resumed_mission_never_does_a_finished_task_again() {
    let tasks = vec![forward(0.5), forward(0.5)];
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(tasks.clone(), true);
    // Stopped (aborted) while the second task is under way.
    let mut saved = None;
    run(&mut exec, &mut robot, 60.0, |_, e| {
        if saved.is_none() && e.current_task().map(|t| t.0) == Some(1) {
            saved = Some(e.progress());
            vec![OperatorCommand::Abort]
        } else {
            Vec::new()
        }
    });
    let saved = saved.expect("the second task started");
    // The progress goes through JSON, as a checkpoint file keeps it.
    let text = serde_json::to_string(&saved).unwrap();
    let back: Progress = serde_json::from_str(&text).unwrap();
    let mut again = executive(tasks.clone(), true);
    again.resume_from(&back).expect("same mission");
    let x0 = robot.pose.x;
    let events = run(&mut again, &mut robot, 60.0, |_, _| Vec::new());
    assert_eq!(again.mode(), &MissionMode::Done);
    let started: Vec<_> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::TaskStarted { task, .. } => Some(*task),
            _ => None,
        })
        .collect();
    assert_eq!(started, [1]);
    assert!((robot.pose.x - x0 - 0.5).abs() < 0.02);
    // Another mission's progress is refused.
    let mut other = executive(tasks[..1].to_vec(), true);
    let err = other.resume_from(&back).expect_err("mismatch");
    assert!(err.to_string().contains("checkpoint holds"), "{err}");
}

#[test]
fn an_obstacle_stops_the_robot_and_a_lasting_one_fails_the_task() {
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], true);
    // A person standing 1.5 m ahead of the start, in the robot's frame as
    // it moves.
    let person = Point2::new(2.5 + 0.2, 1.5);
    let mut stopped_at = None;
    let mut events = Vec::new();
    for _ in 0..(60.0 / DT) as usize {
        let seen = [robot.pose.inverse().transform_point(&person)];
        let out = ask_seeing(&mut exec, &robot, &seen);
        if exec.hazard() == Some(Hazard::Obstacle) && stopped_at.is_none() {
            stopped_at = Some(robot.pose.x);
        }
        events.extend(out.events);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    let x = stopped_at.expect("stopped for the person");
    // The field reached past the body's front (0.75 m) when it stopped.
    assert!(person.x - x > 0.75 && person.x - x < 1.2, "stopped at {x}");
    // Slowed as its field neared the person, it stood no nearer than the
    // field's margin.
    let margin = SafetyConfig::default().obstacle_margin_m;
    assert!(
        robot.pose.x < person.x - 0.75 - margin,
        "drove into it: {:?}",
        robot.pose
    );
    assert!(matches!(exec.mode(), MissionMode::Failed { reason } if reason.contains("blocked")));
    assert!(kinds(&events).iter().any(|k| k == "safety_stop"));
    // The failure says where the robot stood and what held it, in the
    // room's frame: the person.
    let failure = events
        .iter()
        .find_map(|e| match &e.kind {
            EventKind::TaskFailed { failure, .. } => Some(failure.clone()),
            _ => None,
        })
        .expect("the task failed");
    let TaskFailure::WayBlocked {
        pose,
        obstacle_m: Some(held),
        backing: false,
    } = failure
    else {
        panic!("{failure:?}");
    };
    assert!((pose[0] - robot.pose.x).abs() < 1e-9, "{pose:?}");
    assert!((held[0] - person.x).abs() < 1e-9 && (held[1] - person.y).abs() < 1e-9);
}

/// With nobody there, a touch (a person walking into the robot) holds it,
/// the spray off, and it goes on by itself once the bumper has been free a
/// while; touches that go on past the mission's timeout fail the task.
#[test]
fn a_touch_with_nobody_there_holds_the_robot_until_it_is_free() {
    let touched = |exec: &mut Executive, robot: &Robot, bumper: bool| {
        ask(
            exec,
            robot,
            Seen {
                bumper,
                ..Seen::default()
            },
        )
    };
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], true);
    let mut events = Vec::new();
    for k in 0..(60.0 / DT) as usize {
        // Touched for a second, 2 s into the move.
        let bumper = (100..150).contains(&k);
        let out = touched(&mut exec, &robot, bumper);
        if bumper || (150..(150 + (0.5 / DT) as usize - 1)).contains(&k) {
            assert_eq!(out.drive, DriveCommand::STOP, "tick {k}");
            assert!(!out.tool.spray);
            assert_eq!(exec.hazard(), Some(Hazard::Touch), "tick {k}");
        }
        events.extend(out.events);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done, "{events:?}");
    assert!((robot.pose.x - 3.0).abs() < 0.05, "{:?}", robot.pose);
    let touches = events
        .iter()
        .filter(|e| {
            matches!(
                e.kind,
                EventKind::SafetyStop {
                    hazard: Hazard::Touch
                }
            )
        })
        .count();
    assert_eq!(touches, 1, "{events:?}");
    // A touch that does not end: the task fails after the timeout.
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], true);
    let timeout = SafetyConfig::default().touch_timeout_s;
    let mut failed_at = None;
    for k in 0..((timeout + 10.0) / DT) as usize {
        let out = touched(&mut exec, &robot, k >= 50);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            failed_at = Some(k as f64 * DT - 1.0);
            break;
        }
    }
    let t = failed_at.expect("failed");
    assert!((t - timeout).abs() < 0.1, "failed after {t} s");
    assert!(matches!(exec.mode(), MissionMode::Failed { .. }));
    // Touches that keep coming back, the hold letting go between them (a
    // robot pushing into someone it cannot see): the task fails after the
    // timeout as well. The robot is held where it is (something behind the
    // bumper), its task not done.
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], true);
    let every = (2.0 / DT) as usize;
    let mut failed_at = None;
    let mut moved = 0;
    for k in 0..((timeout + 10.0) / DT) as usize {
        let out = touched(&mut exec, &robot, k >= 50 && k % every < 5);
        moved += usize::from(out.drive.speed_mps > 0.0);
        robot.drive(DriveCommand::STOP);
        if exec.mode().is_final() {
            failed_at = Some(k as f64 * DT - 1.0);
            break;
        }
    }
    let t = failed_at.expect("failed");
    assert!((t - timeout).abs() < 2.0, "failed after {t} s");
    assert!(moved > every, "the hold let go between touches");
}

#[test]
fn the_estop_stops_at_once_and_waits_for_release_and_resume() {
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], false);
    let mut pressed = false;
    for k in 0..(60.0 / DT) as usize {
        let estop = (100..200).contains(&k);
        let ops = if k == 250 {
            vec![OperatorCommand::Resume]
        } else {
            Vec::new()
        };
        let out = ask(
            &mut exec,
            &robot,
            Seen {
                estop,
                operator: &ops,
                ..Seen::default()
            },
        );
        if estop {
            pressed = true;
            assert_eq!(out.drive, DriveCommand::STOP);
            assert_eq!(exec.mode(), &MissionMode::EStopped);
        }
        if (200..250).contains(&k) {
            // Released but not resumed: still standing.
            assert_eq!(out.drive, DriveCommand::STOP);
        }
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert!(pressed);
    assert_eq!(exec.mode(), &MissionMode::Done);
    // Unattended, the e-stop ends the mission.
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(waiting_tasks(), true);
    let out = ask(
        &mut exec,
        &robot,
        Seen {
            estop: true,
            ..Seen::default()
        },
    );
    robot.drive(out.drive);
    assert!(matches!(exec.mode(), MissionMode::Failed { reason } if reason.contains("e-stop")));
    assert!(out.checkpoint_due);
}

/// A `map_room` on `path` (without: from the places view planning
/// chooses), done when every wall is seen 20 times and the size known to
/// 5 mm.
fn map_room(path: Option<Vec<[f64; 2]>>) -> TaskSpec {
    TaskSpec::MapRoom {
        path,
        walls: None,
        min_sightings: 20,
        speed_mps: 0.4,
        max_size_sigma_m: 0.005,
        timeout_s: 120.0,
        on_loose_size: OnTimeout::Fail,
    }
}

/// The loop a mission gives, 1 m inside the 5 × 3 m room's walls.
const LOOP: [[f64; 2]; 4] = [[1.0, 1.0], [4.0, 1.0], [4.0, 2.0], [1.0, 2.0]];

#[test]
fn map_room_drives_loops_until_the_room_is_known() {
    let mut robot = Robot::at(Pose2::new(1.0, 1.0, 0.0));
    robot.room_sigma = [0.05; 2];
    let mut exec = executive(vec![map_room(Some(LOOP.to_vec()))], true);
    let mut loops_seen = 0;
    for _ in 0..(120.0 / DT) as usize {
        // The size is learnt on the second loop (a stand-in for the
        // filter, which the simulator tests exercise).
        robot.room_sigma = [if loops_seen >= 2 { 0.002 } else { 0.05 }; 2];
        let out = ask(&mut exec, &robot, Seen { ..Seen::default() });
        loops_seen += out
            .events
            .iter()
            .filter(|e| {
                matches!(&e.kind, EventKind::BehaviourStarted { behaviour, .. } if behaviour == "path")
            })
            .count();
        robot.drive(out.drive);
        // It stays inside the room, clear of the walls.
        let p = robot.pose;
        assert!(p.x > 0.8 && p.x < 4.2 && p.y > 0.8 && p.y < 2.2, "{p:?}");
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done);
    assert!(loops_seen >= 2, "{loops_seen} loops");
}

/// Without a loop given, `map_room` looks from the places view planning
/// chooses: a robot with the west wall behind it, outside the laser's
/// fan, turns or drives to see it, and is done once every wall is seen
/// and the room's size known, its body in the room all along.
#[test]
fn map_room_without_a_loop_goes_where_it_sees_the_walls_it_has_not() {
    let mut robot = Robot::at(Pose2::new(1.2, 1.5, 0.0));
    robot.walls_seen = vec![0; 4];
    robot.room_sigma = [0.05; 2];
    let mut exec = executive(vec![map_room(None)], true);
    let middles = [[0.0, 1.5], [2.5, 0.0], [5.0, 1.5], [2.5, 3.0]];
    let mut west_at = None;
    for tick in 0..(120.0 / DT) as usize {
        // A stand-in for the laser: a wall whose middle lies within 120°
        // of the heading, from the laser 0.35 m ahead of the rear axle,
        // is seen in this tick's scan; the size is known once every wall
        // has been seen.
        let laser = robot.pose.transform_point(&Point2::new(0.35, 0.0));
        for (k, m) in middles.iter().enumerate() {
            let bearing = (m[1] - laser.y).atan2(m[0] - laser.x);
            if wrap_angle(bearing - robot.pose.theta).abs() <= 120f64.to_radians() {
                robot.walls_seen[k] += 1;
            }
        }
        if robot.walls_seen[0] > 0 && west_at.is_none() {
            west_at = Some(tick);
        }
        if robot.walls_seen.iter().all(|&n| n >= 20) {
            robot.room_sigma = [0.002; 2];
        }
        let out = ask(&mut exec, &robot, Seen::default());
        robot.drive(out.drive);
        let p = robot.pose;
        assert!(p.x > 0.3 && p.x < 4.7 && p.y > 0.3 && p.y < 2.7, "{p:?}");
        if exec.mode().is_final() {
            break;
        }
    }
    assert!(west_at.is_some(), "the west wall was never faced");
    assert_eq!(exec.mode(), &MissionMode::Done);
    assert!(
        robot.walls_seen.iter().all(|&n| n >= 20),
        "{:?}",
        robot.walls_seen
    );
}

/// A room known (its walls seen, its size measured) while the robot is
/// held between two corners of its loop (someone standing in its way):
/// map_room is done at its timeout where the robot stands, not failed.
#[test]
fn map_room_held_between_corners_with_the_room_known_is_done_at_its_timeout() {
    let mut robot = Robot::at(Pose2::new(1.0, 1.0, 0.0));
    robot.room_sigma = [0.05; 2];
    let spec = TaskSpec::MapRoom {
        path: Some(LOOP.to_vec()),
        walls: None,
        min_sightings: 20,
        speed_mps: 0.4,
        max_size_sigma_m: 0.005,
        timeout_s: 20.0,
        on_loose_size: OnTimeout::Fail,
    };
    let mut exec = executive(vec![spec], true);
    let mut held = 0;
    for _ in 0..(60.0 / DT) as usize {
        let moving = robot.pose.x > 1.2;
        if moving {
            // Known now; someone steps in just past the field's edge.
            robot.room_sigma = [0.002; 2];
        }
        let seen = if moving {
            vec![
                Point2::new(0.85, 0.0),
                Point2::new(0.85, 0.2),
                Point2::new(0.85, -0.2),
            ]
        } else {
            Vec::new()
        };
        let out = ask_seeing(&mut exec, &robot, &seen);
        held += usize::from(exec.hazard() == Some(Hazard::Obstacle));
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert!(held > 0, "never held");
    assert_eq!(exec.mode(), &MissionMode::Done);
}

/// A room whose walls are all seen but whose size stays known to 6 mm
/// only: `map_room` fails at its timeout by default, naming how well the
/// size is known; with `on_loose_size = "continue"` (a job from the
/// drawing) it is done then instead, and an event tells how well.
#[test]
fn map_room_with_the_size_loose_at_its_timeout_fails_or_goes_on_as_asked() {
    for on_loose_size in [OnTimeout::Fail, OnTimeout::Continue] {
        let mut robot = Robot::at(Pose2::new(1.0, 1.0, 0.0));
        robot.room_sigma = [0.006; 2];
        let mut spec = map_room(Some(LOOP.to_vec()));
        if let TaskSpec::MapRoom {
            timeout_s,
            on_loose_size: on,
            ..
        } = &mut spec
        {
            (*timeout_s, *on) = (20.0, on_loose_size);
        }
        let mut exec = executive(vec![spec], true);
        let events = run(&mut exec, &mut robot, 60.0, |_, _| Vec::new());
        let told = events.iter().find_map(|e| match e.kind {
            EventKind::RoomSizeLoose { task, sigma_m } => Some((task, sigma_m)),
            _ => None,
        });
        let failure = events.iter().find_map(|e| match &e.kind {
            EventKind::TaskFailed { failure, .. } => Some(failure.clone()),
            _ => None,
        });
        match on_loose_size {
            OnTimeout::Fail => {
                assert!(
                    matches!(failure, Some(TaskFailure::RoomSizeLoose { sigma_m, .. }) if (sigma_m - 0.006).abs() < 1e-9),
                    "{failure:?}"
                );
                assert!(told.is_none());
            }
            OnTimeout::Continue => {
                assert_eq!(exec.mode(), &MissionMode::Done, "{failure:?}");
                let (task, sigma_m) = told.expect("no room_size_loose event");
                assert_eq!(task, 0);
                assert!((sigma_m - 0.006).abs() < 1e-9, "{sigma_m}");
            }
        }
    }
}

// ---- Telecommands --------------------------------------------------------

fn command(id: &str, at: Stamp, command: Command) -> Telecommand {
    Telecommand {
        id: id.to_owned(),
        operator: "ann".to_owned(),
        issued: at,
        deadline: at.offset_secs(10.0),
        command,
    }
}

/// One tick with `telecommands`; the outputs.
fn tick_with(exec: &mut Executive, robot: &mut Robot, telecommands: &[Telecommand]) -> Outputs {
    let out = ask(
        exec,
        robot,
        Seen {
            telecommands,
            ..Seen::default()
        },
    );
    robot.drive(out.drive);
    out
}

/// A robot with nothing scripted, waiting for its operator.
fn standing_by() -> Executive {
    executive(
        vec![TaskSpec::WaitForOperator {
            prompt: "standing by".to_owned(),
            timeout_s: None,
            on_timeout: OnTimeout::Fail,
        }],
        false,
    )
}

#[test]
fn a_task_from_the_operator_is_accepted_then_done() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = standing_by();
    // The robot is standing by when the command comes.
    tick_with(&mut exec, &mut robot, &[]);
    let mv = command(
        "m1",
        Stamp::ZERO,
        Command::MoveRelative {
            dx_m: 0.8,
            dy_m: 0.0,
            dtheta_deg: 0.0,
            landmark: None,
        },
    );
    let first = tick_with(&mut exec, &mut robot, &[mv]);
    assert_eq!(first.acks.len(), 1);
    assert_eq!(first.acks[0].reply, Reply::Accepted);
    let mut done = None;
    for _ in 0..(30.0 / DT) as usize {
        let out = tick_with(&mut exec, &mut robot, &[]);
        if let Some(a) = out.acks.iter().find(|a| a.id == "m1") {
            done = Some(a.reply.clone());
            break;
        }
    }
    assert_eq!(done, Some(Reply::Done));
    assert!((robot.pose.x - 2.3).abs() < 0.02, "{:?}", robot.pose);
    // The operator's answer also ended the wait: the mission is done.
    tick_with(&mut exec, &mut robot, &[]);
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    // The checkpoint keeps the mission file's task only.
    assert_eq!(exec.progress().tasks, ["wait_for_operator"]);
}

/// `plaster_surface` from the operator: refused by a robot without a spray
/// tool; with one, the south wall alone is planned and sprayed, then done.
#[test]
fn the_operator_has_one_surface_plastered() {
    let south = Command::PlasterSurface {
        surface: SurfaceId::Wall(WallName::SOUTH),
        region: None,
    };
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let mut bare = standing_by();
    tick_with(&mut bare, &mut robot, &[]);
    let out = tick_with(
        &mut bare,
        &mut robot,
        &[command("p0", Stamp::ZERO, south.clone())],
    );
    assert!(
        matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("spray")),
        "{:?}",
        out.acks
    );
    let mut exec = Executive::new(
        ExecutiveConfig {
            vehicle: VehicleSpec::default(),
            gains: GainSchedule::default(),
            safety: SafetyConfig::default(),
            unattended: false,
            spray: Some(stucco_plan::SprayTool::default()),
            floor: None,
            body_camera_azimuth_rad: Some(std::f64::consts::FRAC_PI_2),
        },
        vec![TaskSpec::WaitForOperator {
            prompt: "standing by".to_owned(),
            timeout_s: None,
            on_timeout: OnTimeout::Fail,
        }],
    );
    tick_with(&mut exec, &mut robot, &[]);
    // A wall the room does not have is refused at once.
    let p0 = command(
        "p0",
        robot.now,
        Command::PlasterSurface {
            surface: SurfaceId::Wall(WallName::new(7)),
            region: None,
        },
    );
    let out = tick_with(&mut exec, &mut robot, &[p0]);
    assert!(
        matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("no wall 7")),
        "{:?}",
        out.acks
    );
    let p1 = command("p1", robot.now, south);
    let first = tick_with(&mut exec, &mut robot, &[p1]);
    assert_eq!(first.acks[0].reply, Reply::Accepted);
    let (mut done, mut passes, mut surfaces) = (None, 0, std::collections::BTreeSet::new());
    for _ in 0..(3000.0 / DT) as usize {
        let out = tick_with(&mut exec, &mut robot, &[]);
        passes += out
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::PassDone { .. }))
            .count();
        if let Some(plan) = exec.plaster_plan() {
            surfaces.extend(plan.passes().map(|(_, p)| p.surface));
        }
        if let Some(a) = out.acks.iter().find(|a| a.id == "p1") {
            done = Some(a.reply.clone());
            break;
        }
    }
    assert_eq!(done, Some(Reply::Done), "{:?}", exec.status());
    assert_eq!(
        surfaces.into_iter().collect::<Vec<_>>(),
        [SurfaceId::Wall(WallName::SOUTH)],
        "planned on other surfaces"
    );
    assert!(passes > 0);
}

#[test]
fn retries_are_answered_but_carried_out_once_and_stale_or_impossible_commands_refused() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = standing_by();
    let mv = command(
        "m1",
        Stamp::ZERO,
        Command::MoveRelative {
            dx_m: 0.3,
            dy_m: 0.0,
            dtheta_deg: 0.0,
            landmark: None,
        },
    );
    let mut started = 0;
    let mut replies = Vec::new();
    for k in 0..600 {
        // The same command again every second.
        let again = if k % 50 == 0 {
            vec![mv.clone()]
        } else {
            Vec::new()
        };
        let out = tick_with(&mut exec, &mut robot, &again);
        started += out
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::TaskStarted { task: 1, .. }))
            .count();
        replies.extend(out.acks.into_iter().map(|a| a.reply));
    }
    assert_eq!(started, 1);
    assert_eq!(replies.first(), Some(&Reply::Accepted));
    assert!(replies.iter().filter(|r| **r == Reply::Done).count() >= 5);
    assert!((robot.pose.x - 1.8).abs() < 0.02);
    // Past its deadline.
    let mut late = command("m2", Stamp::ZERO, Command::MapRoom);
    late.deadline = Stamp::from_secs_f64(1.0);
    let out = tick_with(&mut exec, &mut robot, &[late]);
    assert!(matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("stale")));
    // A door the robot does not know.
    let at = robot.now;
    let out = tick_with(
        &mut exec,
        &mut robot,
        &[command("m3", at, Command::PassDoor { door: 2 })],
    );
    assert!(
        matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("not known")),
        "{:?}",
        out.acks
    );
}

#[test]
fn stop_acts_in_the_same_tick_and_a_jog_ends_at_its_time_to_live() {
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], false);
    for _ in 0..100 {
        tick_with(&mut exec, &mut robot, &[]);
    }
    let at = robot.now;
    let out = tick_with(&mut exec, &mut robot, &[command("s", at, Command::Stop)]);
    assert_eq!(out.drive, DriveCommand::STOP);
    assert_eq!(out.acks[0].reply, Reply::Done);
    assert!(matches!(exec.mode(), MissionMode::Paused { .. }));
    // A jog while stopped is taken, but the robot stays stopped until
    // resumed; resumed, the jog drives, then stops at its time to live.
    let jog = command(
        "j",
        robot.now,
        Command::Jog {
            speed_mps: 0.2,
            steer_rad: 0.0,
            ttl_s: 0.5,
        },
    );
    let resume = command("r", robot.now, Command::Resume);
    let t0 = robot.now;
    let out = tick_with(&mut exec, &mut robot, &[resume, jog]);
    assert_eq!(out.drive.speed_mps, 0.2);
    let mut last_drive = t0;
    let mut done_at = None;
    for _ in 0..100 {
        let out = tick_with(&mut exec, &mut robot, &[]);
        if out.drive.speed_mps == 0.2 {
            last_drive = robot.now;
        }
        if out
            .acks
            .iter()
            .any(|a| a.id == "j" && a.reply == Reply::Done)
        {
            done_at = Some(robot.now);
            break;
        }
    }
    let done_at = done_at.expect("the jog ended");
    // The last jog command went out before the time to live ran out, and
    // the one after it was not a jog.
    assert!(last_drive.seconds_since(t0) <= 0.5 + 1e-9);
    assert!(done_at.seconds_since(t0) <= 0.5 + DT + 1e-9);
}

/// A channel that delays (up to 1 s), drops (20%), duplicates and
/// reorders messages, both ways.
struct Lossy {
    rng: rand_chacha::ChaCha8Rng,
    queue: Vec<(Stamp, Telecommand)>,
    back: Vec<(Stamp, Ack)>,
}

impl Lossy {
    fn delay(&mut self) -> f64 {
        use rand::RngExt;
        self.rng.random_range(0.0..1.0)
    }
    fn send(&mut self, now: Stamp, t: &Telecommand) {
        use rand::RngExt;
        for _ in 0..if self.rng.random_bool(0.1) { 2 } else { 1 } {
            if !self.rng.random_bool(0.2) {
                let d = self.delay();
                self.queue.push((now.offset_secs(d), t.clone()));
            }
        }
    }
    fn answer(&mut self, now: Stamp, a: Ack) {
        use rand::RngExt;
        if !self.rng.random_bool(0.2) {
            let d = self.delay();
            self.back.push((now.offset_secs(d), a));
        }
    }
    fn due<T>(list: &mut Vec<(Stamp, T)>, now: Stamp) -> Vec<T> {
        let (due, rest): (Vec<_>, Vec<_>) = std::mem::take(list)
            .into_iter()
            .partition(|(t, _)| *t <= now);
        *list = rest;
        due.into_iter().map(|(_, x)| x).collect()
    }
}

/// Under 1 s of delay, 20% loss, duplication and reordering, with the
/// operator retrying every 0.5 s until answered, every command is carried
/// out exactly once or refused with a reason.
#[test]
fn over_a_lossy_link_every_command_is_carried_out_once_or_refused() {
    use rand::SeedableRng;
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = standing_by();
    let mut link = Lossy {
        rng: rand_chacha::ChaCha8Rng::seed_from_u64(5),
        queue: Vec::new(),
        back: Vec::new(),
    };
    // Four moves forward, a status query, one stale command, one move the
    // room has no space for (refused by its own checks: a turn too near).
    let moves: Vec<Telecommand> = (0..4)
        .map(|i| {
            command(
                &format!("move-{i}"),
                Stamp::from_secs_f64(i as f64 * 8.0),
                Command::MoveRelative {
                    dx_m: 0.4,
                    dy_m: 0.0,
                    dtheta_deg: 0.0,
                    landmark: None,
                },
            )
        })
        .collect();
    let mut plan: Vec<Telecommand> = moves.clone();
    plan.push(command(
        "status",
        Stamp::from_secs_f64(3.0),
        Command::Status,
    ));
    let mut stale = command("stale", Stamp::from_secs_f64(4.0), Command::MapRoom);
    stale.deadline = Stamp::from_secs_f64(4.1);
    plan.push(stale);
    let mut answered: BTreeMap<String, Reply> = BTreeMap::new();
    let mut final_replies: BTreeMap<String, Reply> = BTreeMap::new();
    let mut last_sent: BTreeMap<String, Stamp> = BTreeMap::new();
    let mut started = 0;
    for _ in 0..(90.0 / DT) as usize {
        let now = robot.now;
        // The operator sends what is due and retries what is unanswered.
        for t in &plan {
            let due = now >= t.issued && !answered.contains_key(&t.id);
            let retry = last_sent
                .get(&t.id)
                .is_none_or(|s| now.seconds_since(*s) >= 0.5);
            if due && retry && now <= t.deadline {
                link.send(now, t);
                last_sent.insert(t.id.clone(), now);
            }
        }
        let arriving = Lossy::due(&mut link.queue, now);
        let out = tick_with(&mut exec, &mut robot, &arriving);
        started += out
            .events
            .iter()
            .filter(|e| matches!(&e.kind, EventKind::TaskStarted { name, .. } if name == "move_relative"))
            .count();
        for a in out.acks {
            link.answer(now, a);
        }
        for a in Lossy::due(&mut link.back, now) {
            answered.entry(a.id.clone()).or_insert(a.reply.clone());
            if matches!(
                a.reply,
                Reply::Done | Reply::Failed { .. } | Reply::Rejected { .. }
            ) {
                final_replies.insert(a.id.clone(), a.reply);
            }
        }
    }
    // Each move ran exactly once and ended done; the robot moved 1.6 m.
    assert_eq!(started, 4);
    assert!((robot.pose.x - 2.6).abs() < 0.03, "{:?}", robot.pose);
    for m in &moves {
        assert!(answered.contains_key(&m.id), "{} never answered", m.id);
    }
    assert_eq!(final_replies.get("status"), Some(&Reply::Done));
    // The stale one may have been lost every time before its deadline;
    // if it got through, it was refused (its deadline is 0.1 s after its
    // issue, shorter than the link's delay) or taken, never run twice.
    if let Some(r) = final_replies.get("stale") {
        assert!(matches!(r, Reply::Rejected { .. } | Reply::Done), "{r:?}");
    }
}

/// A lost link stops a jog at once and, by default, pauses the mission;
/// with `continue` the task goes on.
#[test]
fn a_lost_link_stops_a_jog_and_pauses_by_default() {
    for policy in [LinkLossPolicy::Pause, LinkLossPolicy::Continue] {
        let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
        let mut exec = Executive::new(
            ExecutiveConfig {
                vehicle: VehicleSpec::default(),
                gains: GainSchedule::default(),
                safety: SafetyConfig {
                    on_link_loss: policy,
                    ..SafetyConfig::default()
                },
                unattended: false,
                spray: None,
                floor: None,
                body_camera_azimuth_rad: Some(std::f64::consts::FRAC_PI_2),
            },
            vec![forward(2.0)],
        );
        exec.link(robot.now, true);
        for _ in 0..50 {
            tick_with(&mut exec, &mut robot, &[]);
        }
        let at = robot.now;
        let jog = command(
            "j",
            at,
            Command::Jog {
                speed_mps: 0.2,
                steer_rad: 0.0,
                ttl_s: 1.0,
            },
        );
        let out = tick_with(&mut exec, &mut robot, &[jog]);
        assert_eq!(out.drive.speed_mps, 0.2);
        exec.link(robot.now, false);
        let out = tick_with(&mut exec, &mut robot, &[]);
        assert!(
            out.acks
                .iter()
                .any(|a| a.id == "j" && matches!(a.reply, Reply::Failed { .. })),
            "{:?}",
            out.acks
        );
        match policy {
            LinkLossPolicy::Pause => {
                assert_eq!(out.drive, DriveCommand::STOP);
                assert!(matches!(exec.mode(), MissionMode::Paused { .. }));
            }
            LinkLossPolicy::Continue => {
                // Back to the task, not the jog.
                assert_eq!(exec.mode(), &MissionMode::Running);
                assert_ne!(out.drive.speed_mps, 0.2);
            }
        }
    }
}

fn plaster(survey: bool) -> TaskSpec {
    TaskSpec::Plaster {
        walls: None,
        ceiling: true,
        speed_mps: 0.5,
        settle_s: 0.5,
        survey,
        survey_speed_mps: 0.3,
        region: None,
        spray: None,
        rooms: None,
    }
}

/// What [`plaster_finding_a_window`] saw.
struct WindowRun {
    /// Ticks the tool's camera looked.
    looking: usize,
    /// Plaster flowed while it looked.
    sprayed_looking: bool,
    /// The window put in the estimate: its wall, where, and the station.
    window: Option<(WallName, Rect, usize)>,
    events: Vec<Event>,
    /// The plan as carried out last.
    plan: Option<stucco_plan::Plan>,
}

/// Runs a plastering task in a 5 × 3 m room planned with no window known;
/// the tool's camera, while it looks at the first station on a wall, finds
/// one in the middle of what that station reaches.
fn plaster_finding_a_window(camera: bool) -> WindowRun {
    let tool = stucco_plan::SprayTool {
        camera,
        ..stucco_plan::SprayTool::default()
    };
    let mut cfg = config(true);
    cfg.spray = Some(tool);
    let mut exec = Executive::new(cfg, vec![plaster(false)]);
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let (mut looking, mut sprayed_looking) = (0, false);
    let (mut station, mut window) = (0, None);
    let (mut events, mut last_plan) = (Vec::new(), None);
    for _ in 0..(4000.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        if let Some(p) = exec.plaster_plan() {
            last_plan = Some(p.clone());
        }
        for e in &out.events {
            if let EventKind::StationStarted { station: k, .. } = e.kind {
                station = k;
            }
        }
        events.extend(out.events.iter().cloned());
        if out.tool_look {
            looking += 1;
            sprayed_looking |= out.tool.spray;
            if window.is_none() {
                let plan = exec.plaster_plan().expect("a plan");
                let pass = plan.stations[station]
                    .passes
                    .iter()
                    .find(|p| p.surface != SurfaceId::Ceiling)
                    .expect("a wall at a station the camera looks from");
                let SurfaceId::Wall(wall) = pass.surface else {
                    unreachable!()
                };
                let us = pass.moves.iter().flat_map(|m| [m.from_m[0], m.to_m[0]]);
                let (lo, hi) = us.fold((f64::MAX, f64::MIN), |(a, b), u| (a.min(u), b.max(u)));
                let mid = 0.5 * (lo + hi);
                let rect = Rect {
                    u_m: [mid - 0.25, mid + 0.25],
                    v_m: [1.0, 2.0],
                };
                robot.windows.push(WindowEstimate {
                    wall,
                    along_m: rect.u_m,
                    sill_head_m: rect.v_m,
                    along_sigma_m: [0.005; 2],
                });
                window = Some((wall, rect, station));
            }
        }
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    WindowRun {
        looking,
        sprayed_looking,
        window,
        events,
        plan: last_plan,
    }
}

/// A plastering survey of the 5 × 3 m room knowing a window in its north
/// wall, 1.8-3.0 m along, its far edge `far_sigma_m` uncertain (and a
/// door in its south wall as loose), by a robot whose body camera looks
/// out at `camera_azimuth_rad` (or that has none); up to the plan made
/// again after it. The events, and each tick's pose.
fn survey_knowing_a_window(
    far_sigma_m: f64,
    camera_azimuth_rad: Option<f64>,
) -> (Vec<Event>, Vec<Pose2>) {
    let mut cfg = config(true);
    cfg.spray = Some(stucco_plan::SprayTool::default());
    cfg.body_camera_azimuth_rad = camera_azimuth_rad;
    let mut exec = Executive::new(cfg, vec![plaster(true)]);
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    robot.windows.push(WindowEstimate {
        wall: WallName::NORTH,
        along_m: [1.8, 3.0],
        sill_head_m: [0.9, 2.1],
        along_sigma_m: [0.005, far_sigma_m],
    });
    // A door the camera found as an opening down to the floor, its edges
    // as loose: the laser's to measure, not looked at.
    robot.windows.push(WindowEstimate {
        wall: WallName::SOUTH,
        along_m: [1.0, 1.9],
        sill_head_m: [0.0, 2.0],
        along_sigma_m: [far_sigma_m; 2],
    });
    // A plan is made as the task starts, and again after the survey.
    let plans = |events: &[Event]| {
        events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::PlanMade { .. }))
            .count()
    };
    let (mut events, mut poses) = (Vec::new(), Vec::new());
    for _ in 0..(600.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        events.extend(out.events);
        if plans(&events) == 2 {
            break;
        }
        robot.drive(out.drive);
        poses.push(robot.pose);
    }
    assert_eq!(plans(&events), 2, "{:?}", kinds(&events));
    (events, poses)
}

/// The looks a survey made: wall, edge and its spread.
fn edge_looks(events: &[Event]) -> Vec<(WallName, f64, f64)> {
    events
        .iter()
        .filter_map(|e| match e.kind {
            EventKind::WindowEdgeLook {
                wall,
                along_m,
                sigma_m,
                ..
            } => Some((wall, along_m, sigma_m)),
            _ => None,
        })
        .collect()
}

/// An edge the survey's camera bracketed loosely is looked at again before
/// the plan is made: the body's camera (looking left) swept slowly across
/// it, meeting the wall within 25° of square, a profile a centimetre or
/// less apart at 20 a second. Edges known well are not.
#[test]
fn a_window_edge_known_loosely_is_swept_slowly_before_the_plan_is_made() {
    let left = std::f64::consts::FRAC_PI_2;
    let (events, poses) = survey_knowing_a_window(0.02, Some(left));
    assert_eq!(edge_looks(&events), vec![(WallName::NORTH, 3.0, 0.02)]);
    assert!(
        slow_crossings(&poses, left) >= 1,
        "the fan never swept the edge slowly"
    );
    let (events, poses) = survey_knowing_a_window(0.005, Some(left));
    assert!(edge_looks(&events).is_empty(), "{:?}", kinds(&events));
    assert_eq!(slow_crossings(&poses, left), 0);
}

/// The look is made with the body's camera where the robot carries it: a
/// camera looking right sweeps the edge with its own fan, and a body
/// without a camera makes no look.
#[test]
fn a_window_edge_is_looked_at_with_the_camera_the_body_carries() {
    let (left, right) = (std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2);
    let (events, poses) = survey_knowing_a_window(0.02, Some(right));
    assert_eq!(edge_looks(&events), vec![(WallName::NORTH, 3.0, 0.02)]);
    assert!(
        slow_crossings(&poses, right) >= 1,
        "the right-looking fan never swept the edge slowly"
    );
    assert_eq!(slow_crossings(&poses, left), 0);
    let (events, poses) = survey_knowing_a_window(0.02, None);
    assert!(edge_looks(&events).is_empty(), "{:?}", kinds(&events));
    assert_eq!(slow_crossings(&poses, right), 0);
    assert_eq!(slow_crossings(&poses, left), 0);
}

/// Ticks in which a body camera's fan at `azimuth_rad` passed the far
/// edge of [`survey_knowing_a_window`]'s window meeting the wall within
/// 25° of square, sweeping along it at 0.2 m/s or slower.
fn slow_crossings(poses: &[Pose2], azimuth_rad: f64) -> usize {
    let g = WallGeometry::of(WallName::NORTH, ROOM).unwrap();
    let edge = g.origin + g.along * 3.0;
    let fan = |p: &Pose2| p.theta + azimuth_rad;
    poses
        .windows(2)
        .filter(|pair| {
            let (a, b) = (pair[0], pair[1]);
            let to = edge - b.position().coords;
            let bearing = to.y.atan2(to.x);
            let (ea, eb) = (
                stucco_core::wrap_angle(fan(&a) - bearing),
                stucco_core::wrap_angle(fan(&b) - bearing),
            );
            let incidence = (-g.inward.dot(&to) / to.norm()).acos();
            let on_wall_mps = stucco_core::wrap_angle(b.theta - a.theta).abs() / DT * to.norm();
            ea.signum() != eb.signum()
                && ea.abs() < 0.5
                && incidence < 25f64.to_radians()
                && on_wall_mps <= 0.2 + 1e-3
        })
        .count()
}

#[test]
fn a_window_the_tools_camera_finds_at_a_station_is_kept_out_of_the_coat_from_there_on() {
    let WindowRun {
        looking,
        sprayed_looking,
        window,
        events,
        plan,
    } = plaster_finding_a_window(true);
    let (wall, rect, station) = window.expect("the camera looked");
    // Every wall station was looked at, spray off.
    let walls = events
        .iter()
        .filter(|e| matches!(&e.kind, EventKind::PassDone { surface, .. } if surface != "ceiling"))
        .count();
    assert!(walls >= 4, "{walls} wall passes");
    assert!(
        looking as f64 * DT > walls as f64 * 1.0,
        "{looking} ticks looking"
    );
    assert!(!sprayed_looking);
    let found: Vec<_> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::WindowFound {
                station: k,
                wall: w,
                along_m,
                ..
            } => Some((*k, w.clone(), *along_m)),
            _ => None,
        })
        .collect();
    assert_eq!(
        found,
        vec![(station, SurfaceId::Wall(wall).name().to_owned(), rect.u_m)]
    );
    // The plan carried out sprays nothing into it from that station on,
    // and has it as an opening of the wall.
    let plan = plan.expect("a plan");
    let keep_out = rect.grown(plan.tool.spray_off_m - 1e-9);
    for (k, st) in plan.stations.iter().enumerate().skip(station) {
        for p in st
            .passes
            .iter()
            .filter(|p| p.surface == SurfaceId::Wall(wall))
        {
            assert!(
                !p.moves
                    .iter()
                    .any(|m| m.spray && keep_out.clip(m.from_m, m.to_m).is_some()),
                "station {k} sprays into the window"
            );
        }
    }
    let surface = plan.surface(SurfaceId::Wall(wall)).expect("the wall");
    assert!(surface.openings.iter().any(|o| o.rect == rect));
}

#[test]
fn a_tool_without_a_camera_sprays_without_looking() {
    let WindowRun {
        looking,
        window,
        events,
        ..
    } = plaster_finding_a_window(false);
    assert_eq!(looking, 0);
    assert!(window.is_none());
    assert!(
        !events
            .iter()
            .any(|e| matches!(e.kind, EventKind::WindowFound { .. }))
    );
}

#[test]
fn a_plaster_task_without_a_spray_tool_fails_saying_so() {
    let mut exec = executive(vec![plaster(false)], true);
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let events = run(&mut exec, &mut robot, 1.0, |_, _| Vec::new());
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?} {events:?}", exec.mode());
    };
    assert!(reason.contains("[spray]"), "{reason}");
}

/// A plastering job alone, unattended, with the mission's spray tool
/// and no survey, the robot in the middle of the 5 × 3 m room.
fn plastering_alone() -> (Executive, Robot) {
    let config = ExecutiveConfig {
        spray: Some(stucco_plan::SprayTool::default()),
        ..config(true)
    };
    (
        Executive::new(config, vec![plaster(false)]),
        Robot::at(Pose2::new(2.5, 1.5, 0.0)),
    )
}

/// Echoes ahead and behind the body, in its width, that the field of any
/// run along its heading holds, even creeping (robot frame).
const HOLDING: [Point2<f64>; 2] = [Point2::new(0.85, 0.0), Point2::new(-0.25, 0.0)];

/// The stations of the first plan the events tell of.
fn planned_stations(events: &[Event]) -> usize {
    events
        .iter()
        .find_map(|e| match e.kind {
            EventKind::PlanMade { stations, .. } => Some(stations),
            _ => None,
        })
        .expect("a plan made")
}

/// Asserts the job done with one station put last and none given up;
/// the events' kinds.
fn done_with_one_station_put_last(exec: &Executive, events: &[Event]) -> Vec<String> {
    assert_eq!(*exec.mode(), MissionMode::Done, "{:?}", kinds(events));
    let k = kinds(events);
    assert_eq!(
        k.iter().filter(|k| *k == "station_deferred").count(),
        1,
        "{k:?}"
    );
    assert!(!k.iter().any(|k| k == "station_given_up"), "{k:?}");
    k
}

/// A position the estimate keeps known only to 1.5 cm (the spray needs
/// 1 cm) everywhere: the robot holds the spray at each station as long as
/// the supervisor waits for a lost estimate, puts the station last once
/// (from the others the walls that hold the position may show), and at
/// the last the task fails saying why, never having sprayed, instead of
/// standing there for ever.
#[test]
fn a_station_held_for_a_loose_position_fails_the_task_after_the_timeout() {
    let timeout_s = SafetyConfig::default().lost_timeout_s;
    let (mut exec, mut robot) = plastering_alone();
    robot.position_sigma = 0.015;
    let (mut sprayed, mut t, mut started) = (false, 0.0, None);
    let mut events = Vec::new();
    for _ in 0..(3600.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        sprayed |= out.tool.spray;
        if out
            .events
            .iter()
            .any(|e| matches!(e.kind, EventKind::StationStarted { .. }))
        {
            started = Some(t);
        }
        events.extend(out.events);
        robot.drive(out.drive);
        t += DT;
        if exec.mode().is_final() {
            break;
        }
    }
    assert!(!sprayed, "sprayed on a position known to 1.5 cm");
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?}", exec.mode());
    };
    assert!(
        reason.contains("known to 15.0 mm") && reason.contains("needs 10.0 mm"),
        "{reason}"
    );
    let k = kinds(&events);
    let stations = planned_stations(&events);
    // Each station put last once, none twice.
    let deferred = k.iter().filter(|k| *k == "station_deferred").count();
    assert_eq!(deferred, stations, "{k:?}");
    // At the last station it waited the timeout, and not much longer (the
    // nozzle's travel to its first point).
    let waited = t - started.expect("never got to a station");
    assert!(
        waited > timeout_s && waited < timeout_s + 10.0,
        "{waited} s"
    );
}

/// The position too loose to spray at the first station (its walls
/// hidden from there by someone standing) until it is put last: the
/// station, not begun, is put last after the timeout and the job goes
/// on; plastered at the end, the job is done, each pass sprayed once.
#[test]
fn a_station_where_the_position_stays_loose_is_put_last_and_done_at_the_end() {
    let (mut exec, mut robot) = plastering_alone();
    let (mut events, mut at_first, mut plan) = (Vec::<Event>::new(), false, None);
    for _ in 0..(6000.0 / DT) as usize {
        let deferred = events
            .iter()
            .any(|e| matches!(e.kind, EventKind::StationDeferred { .. }));
        robot.position_sigma = if at_first && !deferred { 0.015 } else { 0.003 };
        let out = ask(&mut exec, &robot, Seen::default());
        at_first |= out
            .events
            .iter()
            .any(|e| matches!(e.kind, EventKind::StationStarted { .. }));
        plan = plan.or_else(|| exec.plaster_plan().cloned());
        events.extend(out.events);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    let k = done_with_one_station_put_last(&exec, &events);
    let plan = plan.expect("a plan");
    let passes: usize = plan.stations.iter().map(|s| s.passes.len()).sum();
    assert_eq!(k.iter().filter(|k| *k == "pass_done").count(), passes);
    // The first station started twice: put last, and at the end.
    let started = k.iter().filter(|k| *k == "station_started").count();
    assert_eq!(started, plan.stations.len() + 1);
}

/// Runs a plastering task alone, the position known to 1.5 cm (too
/// loose to spray) wherever the robot stands within 0.3 m of the first
/// station once `loose(t, started)` says so (`t` the time, `started` when
/// the first station was first started), to 3 mm elsewhere: the
/// executive at the end, the events and the first plan.
fn plaster_loose_at_the_first_station(
    loose: impl Fn(f64, Option<f64>) -> bool,
) -> (Executive, Vec<Event>, stucco_plan::Plan) {
    let (mut exec, mut robot) = plastering_alone();
    let (mut events, mut plan) = (Vec::<Event>::new(), None);
    let (mut t, mut started) = (0.0, None);
    for _ in 0..(6000.0 / DT) as usize {
        plan = plan.or_else(|| exec.plaster_plan().cloned());
        let near = plan
            .as_ref()
            .and_then(|p| p.stations.first())
            .is_some_and(|s| (s.base.x - robot.pose.x).hypot(s.base.y - robot.pose.y) < 0.3);
        robot.position_sigma = if near && loose(t, started) {
            0.015
        } else {
            0.003
        };
        let out = ask(&mut exec, &robot, Seen::default());
        if out
            .events
            .iter()
            .any(|e| matches!(e.kind, EventKind::StationStarted { station: 0, .. }))
        {
            started.get_or_insert(t);
        }
        events.extend(out.events);
        robot.drive(out.drive);
        t += DT;
        if exec.mode().is_final() {
            break;
        }
    }
    (exec, events, plan.expect("a plan"))
}

/// The position too loose to spray wherever the robot stands at the
/// first station (the far end of a long corridor, its end wall behind
/// the robot): the station is put last, loose again there, given up, and
/// the rest of the job is plastered and done, the station's area
/// reported unreachable.
#[test]
fn a_station_where_the_position_stays_loose_for_good_is_given_up() {
    let (exec, events, plan) = plaster_loose_at_the_first_station(|_, _| true);
    let k = kinds(&events);
    assert_eq!(*exec.mode(), MissionMode::Done, "{k:?}");
    let given_up: Vec<(usize, f64, GiveUpReason)> = events
        .iter()
        .filter_map(|e| match e.kind {
            EventKind::StationGivenUp {
                station,
                unreachable_m2,
                reason,
                ..
            } => Some((station, unreachable_m2, reason)),
            _ => None,
        })
        .collect();
    assert_eq!(given_up.len(), 1, "{k:?}");
    assert!(given_up[0].1 > 0.0, "{given_up:?}");
    assert_eq!(given_up[0].2, GiveUpReason::PositionLoose);
    let passes: usize = plan.stations[1..].iter().map(|s| s.passes.len()).sum();
    assert_eq!(k.iter().filter(|k| *k == "pass_done").count(), passes);
}

/// The position goes too loose to spray at the first station 5 s into
/// its strokes, and stays so there: the rest of the station is given up
/// after the timeout, and the other stations are plastered and the job
/// done, not failed at the station begun.
#[test]
fn a_station_begun_where_the_position_goes_loose_for_good_is_given_up() {
    let (exec, events, plan) =
        plaster_loose_at_the_first_station(|t, started| started.is_some_and(|s| t > s + 5.0));
    let k = kinds(&events);
    assert_eq!(*exec.mode(), MissionMode::Done, "{k:?}");
    let given_up: Vec<GiveUpReason> = events
        .iter()
        .filter_map(|e| match e.kind {
            EventKind::StationGivenUp { reason, .. } => Some(reason),
            _ => None,
        })
        .collect();
    assert_eq!(given_up, [GiveUpReason::PositionLoose], "{k:?}");
    assert!(!k.iter().any(|k| k == "station_deferred"), "{k:?}");
    let passes: usize = plan.stations[1..].iter().map(|s| s.passes.len()).sum();
    assert_eq!(k.iter().filter(|k| *k == "pass_done").count(), passes);
}

/// Held on the last stretch onto a station it already stands on within
/// what the gantry has spare (something stays in the field ahead: a wall
/// the station stands nearer than the field's margin), the robot takes
/// the station from where it stands instead of waiting for a clear field
/// until the way fails.
#[test]
fn a_robot_held_within_the_gantrys_spare_of_its_station_takes_it_from_there() {
    let (mut exec, mut robot) = plastering_alone();
    let (mut held, mut stopped) = (false, false);
    let mut started = None;
    for _ in 0..(300.0 / DT) as usize {
        // Within 2 cm of the first station, driving: something shows up
        // just past the field's edge in the way it drives, and stays.
        let base = exec.plaster_plan().map(|p| p.stations[0].base);
        let near = base.is_some_and(|b| (b.inverse() * robot.pose).x.abs() < 0.02);
        held |= near && started.is_none();
        let seen: Vec<Point2<f64>> = if held && started.is_none() {
            HOLDING.to_vec()
        } else {
            Vec::new()
        };
        let out = ask_seeing(&mut exec, &robot, &seen);
        stopped |= exec.hazard() == Some(Hazard::Obstacle);
        for e in &out.events {
            if let EventKind::StationStarted {
                station: 0,
                offset_m,
                ..
            } = e.kind
            {
                started = Some(offset_m);
            }
        }
        robot.drive(out.drive);
        if started.is_some() || exec.mode().is_final() {
            break;
        }
    }
    assert!(held && stopped, "never held near the station");
    let offset = started.unwrap_or_else(|| panic!("{:?}", exec.mode()));
    assert!(
        offset[0].abs() <= 0.03 && offset[1].abs() <= 0.03,
        "{offset:?}"
    );
}

/// Someone standing in the way to the second station for 20 s (longer
/// than half the supervisor's timeout): the station is put last and the
/// job goes on; the person gone, it is plastered at the end and the job
/// is done, every station of the plan plastered.
#[test]
fn a_station_whose_way_stays_blocked_is_put_last_and_done_at_the_end() {
    let (mut exec, mut robot) = plastering_alone();
    let (mut events, mut block_from) = (Vec::new(), None);
    for _ in 0..(6000.0 / DT) as usize {
        let blocking = block_from.is_some_and(|t: f64| robot.now.as_secs_f64() - t < 20.0);
        let seen: Vec<Point2<f64>> = if blocking {
            HOLDING.to_vec()
        } else {
            Vec::new()
        };
        let out = ask_seeing(&mut exec, &robot, &seen);
        for e in &out.events {
            if block_from.is_none()
                && matches!(e.kind, EventKind::BehaviourStarted { .. })
                && events
                    .iter()
                    .any(|e: &Event| matches!(e.kind, EventKind::PassDone { station: 0, .. }))
            {
                block_from = Some(robot.now.as_secs_f64());
            }
        }
        events.extend(out.events);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    let k = done_with_one_station_put_last(&exec, &events);
    let stations = planned_stations(&events);
    let started = k.iter().filter(|k| *k == "station_started").count();
    assert_eq!(started, stations);
}

/// On the kinematic robot with a perfect estimate, a 5 × 3 m room: every
/// pass of the plan is sprayed, the nozzle only ever within the gantry's
/// travel and spraying only while standing, a checkpoint due at least
/// every stroke; and a run stopped halfway and resumed from its progress
/// and plan takes the stroke up where it stopped.
#[test]
fn a_plaster_task_sprays_every_pass_and_resumes_mid_stroke() {
    let tool = stucco_plan::SprayTool::default();
    let make = || {
        Executive::new(
            ExecutiveConfig {
                vehicle: VehicleSpec::default(),
                gains: GainSchedule::default(),
                safety: SafetyConfig::default(),
                unattended: true,
                spray: Some(tool.clone()),
                floor: None,
                body_camera_azimuth_rad: Some(std::f64::consts::FRAC_PI_2),
            },
            vec![plaster(false)],
        )
    };
    let mut exec = make();
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let (mut spraying_s, mut checkpoints, mut passes) = (0.0, 0, 0);
    let mut halfway = None;
    for _ in 0..(4000.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        let n = out.tool.nozzle_m;
        assert!(
            n[0] >= tool.rail_m[0] - 1e-9 && n[0] <= tool.rail_m[1] + 1e-9,
            "{n:?}"
        );
        assert!(
            n[1] >= tool.arm_m[0] - 1e-9 && n[1] <= tool.arm_m[1] + 1e-9,
            "{n:?}"
        );
        if out.tool.spray {
            assert_eq!(out.drive.speed_mps, 0.0, "sprays while driving");
            spraying_s += DT;
        }
        checkpoints += usize::from(out.checkpoint_due);
        passes += out
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::PassDone { .. }))
            .count();
        if halfway.is_none() && spraying_s > 600.0 && out.tool.spray {
            halfway = Some((
                exec.progress(),
                exec.plaster_plan().cloned().unwrap(),
                robot.pose,
            ));
            // The coverage it publishes: the spraying done so far, of the
            // plan's, surface by surface.
            let c = exec.coverage().unwrap();
            let done: f64 = c.surfaces.iter().map(|s| s.done_spray_s).sum();
            let planned: f64 = c.surfaces.iter().map(|s| s.planned_spray_s).sum();
            let plan_s = exec.plaster_plan().unwrap().spray_s();
            assert!((planned - plan_s).abs() < 1e-6, "{planned} {plan_s}");
            // (ticks that end a move part-way count whole on the tool's
            // side: a few ticks over ten minutes)
            assert!(
                (done - spraying_s).abs() < 1e-3 * spraying_s,
                "{done} {spraying_s}"
            );
            assert!(c.stations_done < c.stations, "{c:?}");
        }
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(*exec.mode(), MissionMode::Done);
    let (progress, plan, pose) = halfway.unwrap();
    let planned: usize = plan.stations.iter().map(|s| s.passes.len()).sum();
    assert_eq!(passes, planned);
    let spray_s = plan.spray_s();
    assert!(
        (spraying_s - spray_s).abs() < 0.01 * spray_s,
        "{spraying_s} {spray_s}"
    );
    assert!(checkpoints as f64 >= spray_s, "{checkpoints} checkpoints");
    // Resumed: the same plan from the same stroke, a second at most before
    // where it stopped.
    let p = progress.plaster.clone().unwrap();
    assert!(p.in_move_s > 0.0, "{p:?}");
    let mut again = make();
    again.resume_plan(plan.clone());
    again.resume_from(&progress).unwrap();
    let mut robot = Robot::at(pose);
    let mut resumed_s = 0.0;
    for _ in 0..(4000.0 / DT) as usize {
        let out = ask(&mut again, &robot, Seen::default());
        if out.tool.spray {
            resumed_s += DT;
        }
        robot.drive(out.drive);
        if again.mode().is_final() {
            break;
        }
    }
    assert_eq!(*again.mode(), MissionMode::Done);
    // What was left, within a second of what the first run had still to
    // spray when it was stopped.
    assert!(
        resumed_s < spray_s - 600.0 + 1.5,
        "{resumed_s} of {spray_s}"
    );
    assert!(
        resumed_s > spray_s - 600.0 - 1.5,
        "{resumed_s} of {spray_s}"
    );
    // A plan that is not the one the checkpoint names is refused.
    let mut wrong = make();
    let mut other = plan;
    other.stations.pop();
    wrong.resume_plan(other);
    wrong.resume_from(&progress).unwrap();
    let mut robot = Robot::at(pose);
    run(&mut wrong, &mut robot, 1.0, |_, _| Vec::new());
    assert!(
        matches!(wrong.mode(), MissionMode::Failed { reason } if reason.contains("not the one")),
        "{:?}",
        wrong.mode()
    );
}

// ---- Rooms of a floor plan ------------------------------------------------

/// Two offices side by side joined by a door, a hall south of both.
fn offices() -> FloorPlan {
    let room = |name: &str, origin_m, size_m| PlanRoom {
        name: name.to_owned(),
        origin_m,
        size_m,
        corners: None,
    };
    let door = |a: &str, b: &str, at_m| PlanDoor {
        rooms: [a.to_owned(), b.to_owned()],
        at_m,
        width_m: 1.0,
        height_m: None,
        shut: false,
    };
    FloorPlan::new(
        vec![
            room("hall", [0.0, 0.0], [10.3, 3.0]),
            room("west", [0.0, 3.15], [5.0, 4.0]),
            room("east", [5.3, 3.15], [5.0, 4.0]),
        ],
        vec![
            door("hall", "west", [2.5, 3.075]),
            door("west", "east", [5.15, 5.5]),
        ],
    )
    .unwrap()
}

fn with_plan(tasks: Vec<TaskSpec>, unattended: bool) -> Executive {
    let floor = Some(offices());
    Executive::new(
        ExecutiveConfig {
            floor,
            ..config(unattended)
        },
        tasks,
    )
}

fn go_to(room: &str) -> TaskSpec {
    TaskSpec::GoToRoom {
        room: room.to_owned(),
        approach_m: 1.0,
        beyond_m: 0.8,
        speed_mps: 0.3,
    }
}

/// Runs `exec` on `robot`, moving the robot's frame through each door
/// the executive says it went through when `follow` (as the navigation
/// core does); the doors it said so for.
fn run_rooms(
    exec: &mut Executive,
    robot: &mut Robot,
    plan: &FloorPlan,
    follow: bool,
) -> Vec<usize> {
    let mut doors = Vec::new();
    for _ in 0..(240.0 / DT) as usize {
        let out = ask(exec, robot, Seen::default());
        if let Some(door) = out.enter_room {
            doors.push(door);
            if follow {
                robot.through(plan, door);
            }
        }
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    doors
}

#[test]
fn go_to_room_passes_each_door_of_the_way_and_follows_the_frame() {
    let plan = offices();
    let mut robot = Robot::at(Pose2::new(1.5, 1.2, 0.0));
    robot.in_room(&plan, 0);
    let mut exec = with_plan(vec![go_to("east"), go_to("east"), go_to("hall")], true);
    let doors = run_rooms(&mut exec, &mut robot, &plan, true);
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    // Hall → west → east, then nothing (there already), then back.
    assert_eq!(doors, [0, 1, 1, 0]);
    assert_eq!(robot.room, Some(0));
    // 0.8 m beyond the west office's south wall at the door, heading
    // south, in the hall's frame.
    let p = robot.pose;
    assert!(
        (p.x - 2.5).abs() < 0.05 && (p.y - 2.35).abs() < 0.05,
        "{p:?}"
    );
}

#[test]
fn a_frame_that_does_not_follow_fails_the_task_and_stops_the_robot() {
    let plan = offices();
    let mut robot = Robot::at(Pose2::new(1.5, 1.2, 0.0));
    robot.in_room(&plan, 0);
    let mut exec = with_plan(vec![go_to("east")], true);
    let doors = run_rooms(&mut exec, &mut robot, &plan, false);
    assert_eq!(doors, [0]);
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?}", exec.mode());
    };
    assert!(reason.contains("estimate did not follow"), "{reason}");
}

#[test]
fn go_to_room_from_the_operator_names_what_is_wrong() {
    let plan = offices();
    let mut robot = Robot::at(Pose2::new(1.5, 1.2, 0.0));
    robot.in_room(&plan, 0);
    let go = |id: &str, room: &str| {
        command(
            id,
            Stamp::ZERO,
            Command::GoToRoom {
                room: room.to_owned(),
            },
        )
    };
    // No plan: refused, saying so.
    let mut exec = standing_by();
    let out = tick_with(&mut exec, &mut robot, &[go("g0", "west")]);
    let Reply::Rejected { reason } = &out.acks[0].reply else {
        panic!("{:?}", out.acks);
    };
    assert!(reason.contains("no floor plan"), "{reason}");
    // A room the plan does not have: refused, naming those it has.
    let mut exec = with_plan(exec.tasks().to_vec(), false);
    let out = tick_with(&mut exec, &mut robot, &[go("g1", "kitchen")]);
    let Reply::Rejected { reason } = &out.acks[0].reply else {
        panic!("{:?}", out.acks);
    };
    assert!(reason.contains("hall, west, east"), "{reason}");
    // A room it has: accepted, carried out, done.
    let out = tick_with(&mut exec, &mut robot, &[go("g2", "west")]);
    assert_eq!(out.acks[0].reply, Reply::Accepted);
    let mut done = None;
    for _ in 0..(120.0 / DT) as usize {
        let out = tick_with(&mut exec, &mut robot, &[]);
        if let Some(door) = out.enter_room {
            robot.through(&plan, door);
        }
        if let Some(a) = out.acks.iter().find(|a| a.id == "g2") {
            done = Some(a.reply.clone());
            break;
        }
    }
    assert_eq!(done, Some(Reply::Done));
    assert_eq!(robot.room, Some(1));
}

/// A move relative to a landmark ends where the landmark's frame says:
/// a metre before a door facing it, or before the middle of a wall and
/// half a metre to its left; a door the robot does not know fails the task
/// saying so.
#[test]
fn a_move_relative_to_a_door_or_a_wall_ends_in_its_frame() {
    let to = |landmark, dx_m, dy_m| TaskSpec::MoveRelative {
        dx_m,
        dy_m,
        dtheta_deg: 0.0,
        speed_mps: 0.3,
        landmark: Some(landmark),
    };
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    robot.doors = vec![DoorEstimate {
        wall: WallName::SOUTH,
        position_m: 2.5,
        width_m: Some(0.9),
        sigma_m: 0.01,
        plan_door: None,
    }];
    let mut exec = executive(vec![to(Landmark::Door(0), -1.0, 0.0)], true);
    run(&mut exec, &mut robot, 60.0, |_, _| Vec::new());
    assert_eq!(exec.mode(), &MissionMode::Done);
    let p = robot.pose;
    assert!(
        (p.x - 2.5).abs() < 0.02 && (p.y - 1.0).abs() < 0.02,
        "{p:?}"
    );
    assert!(
        wrap_angle(p.theta + std::f64::consts::FRAC_PI_2).abs() < 0.02,
        "{p:?}"
    );
    // Facing the east wall (x = 5) from 1.2 m, half a metre to its left.
    let mut exec = executive(vec![to(Landmark::Wall(WallName::EAST), -1.2, 0.5)], true);
    run(&mut exec, &mut robot, 60.0, |_, _| Vec::new());
    let p = robot.pose;
    assert!(
        (p.x - 3.8).abs() < 0.02 && (p.y - 2.0).abs() < 0.02,
        "{p:?}"
    );
    assert!(wrap_angle(p.theta).abs() < 0.02, "{p:?}");
    let mut exec = executive(vec![to(Landmark::Door(3), -1.0, 0.0)], true);
    run(&mut exec, &mut robot, 5.0, |_, _| Vec::new());
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?}", exec.mode());
    };
    assert!(reason.contains("door 3 is not known"), "{reason}");
}

/// `plaster_surface` with a region: the plan sprays that part of the wall
/// only (every stroke inside it), the rest of the wall kept out as an
/// opening is; a region of the ceiling is refused naming the field.
#[test]
fn the_operator_has_a_region_of_a_wall_plastered() {
    let region = Region {
        along_m: [1.0, 3.0],
        height_m: [0.0, 1.5],
    };
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let mut exec = Executive::new(
        ExecutiveConfig {
            spray: Some(stucco_plan::SprayTool::default()),
            ..config(false)
        },
        vec![TaskSpec::WaitForOperator {
            prompt: "standing by".to_owned(),
            timeout_s: None,
            on_timeout: OnTimeout::Fail,
        }],
    );
    tick_with(&mut exec, &mut robot, &[]);
    let ceiling = Command::PlasterSurface {
        surface: SurfaceId::Ceiling,
        region: Some(region),
    };
    let c = command("c", robot.now, ceiling);
    let out = tick_with(&mut exec, &mut robot, &[c]);
    assert!(
        matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("region")),
        "{:?}",
        out.acks
    );
    let south = Command::PlasterSurface {
        surface: SurfaceId::Wall(WallName::SOUTH),
        region: Some(region),
    };
    let r = command("r", robot.now, south);
    let out = tick_with(&mut exec, &mut robot, &[r]);
    assert_eq!(out.acks[0].reply, Reply::Accepted);
    let mut plan = None;
    for _ in 0..(600.0 / DT) as usize {
        let out = tick_with(&mut exec, &mut robot, &[]);
        if out
            .events
            .iter()
            .any(|e| matches!(e.kind, EventKind::PlanMade { .. }))
        {
            plan = exec.plaster_plan().cloned();
            break;
        }
    }
    let plan = plan.expect("a plan");
    let mut strokes = 0;
    for (_, pass) in plan.passes() {
        assert_eq!(pass.surface, stucco_plan::SurfaceId::Wall(WallName::SOUTH));
        for m in pass.moves.iter().filter(|m| m.spray) {
            strokes += 1;
            for p in [m.from_m, m.to_m] {
                assert!(
                    (1.0..=3.0).contains(&p[0]) && (0.0..=1.5).contains(&p[1]),
                    "a stroke at {p:?}, outside the region"
                );
            }
        }
    }
    assert!(strokes >= 5, "{strokes} strokes");
}

/// A mission that is over still says what would hold the robot, and
/// clears it when it has gone: the estimate lost after the last task (as
/// when the frame has just moved through a door), then found again.
#[test]
fn a_hold_is_told_and_cleared_while_the_mission_stands() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(vec![forward(0.3)], true);
    run(&mut exec, &mut robot, 30.0, |_, _| Vec::new());
    assert_eq!(exec.mode(), &MissionMode::Done);
    robot.position_sigma = 0.2;
    let out = ask(&mut exec, &robot, Seen::default());
    assert_eq!(exec.hazard(), Some(Hazard::Lost));
    assert_eq!(kinds(&out.events), ["safety_stop"]);
    robot.position_sigma = 0.003;
    let out = ask(&mut exec, &robot, Seen::default());
    assert_eq!(exec.hazard(), None);
    assert_eq!(kinds(&out.events), ["safety_clear"]);
    assert_eq!(exec.mode(), &MissionMode::Done);
}

/// The apartment's drawing (missions/plans/apartment.toml): a hall 1.2 m
/// wide with the living room and the kitchen to its south, the bedroom
/// and the bathroom (its door shut) to its north.
fn apartment() -> FloorPlan {
    let room = |name: &str, origin_m, size_m| PlanRoom {
        name: name.to_owned(),
        origin_m,
        size_m,
        corners: None,
    };
    let door = |a: &str, b: &str, at_m, width_m| PlanDoor {
        rooms: [a.to_owned(), b.to_owned()],
        at_m,
        width_m,
        height_m: None,
        shut: false,
    };
    FloorPlan::new(
        vec![
            room("living", [0.0, 0.0], [5.0, 2.85]),
            room("kitchen", [5.15, 0.0], [2.85, 2.85]),
            room("hall", [0.0, 3.0], [8.0, 1.2]),
            room("bedroom", [0.0, 4.35], [4.0, 3.65]),
            room("bath", [4.15, 4.35], [3.85, 3.65]),
        ],
        vec![
            door("living", "hall", [3.55, 2.925], 0.9),
            door("kitchen", "hall", [6.6, 2.925], 0.8),
            door("hall", "bedroom", [3.4, 4.275], 0.8),
            PlanDoor {
                shut: true,
                height_m: Some(2.0),
                ..door("hall", "bath", [4.9, 4.275], 0.7)
            },
        ],
    )
    .unwrap()
}

/// Runs `exec` on `robot` in the apartment `plan` for at most `max_s`,
/// moving the robot's frame through each door the executive says it went
/// through: those doors, and how near a wall the body came at the
/// closest ([`body_inside`]).
fn run_rooms_inside(
    exec: &mut Executive,
    robot: &mut Robot,
    plan: &FloorPlan,
    max_s: f64,
) -> (Vec<usize>, f64) {
    let mut doors = Vec::new();
    let mut closest = f64::INFINITY;
    for _ in 0..(max_s / DT) as usize {
        let out = ask(exec, robot, Seen::default());
        if let Some(door) = out.enter_room {
            doors.push(door);
            robot.through(plan, door);
        }
        robot.drive(out.drive);
        closest = closest.min(body_inside(robot, plan));
        if exec.mode().is_final() {
            break;
        }
    }
    (doors, closest)
}

/// How far the body's corners keep inside the rooms of `plan`, m
/// (negative: into a wall); a corner in a door's gap through a wall is
/// not counted. The room frames
/// lie on the drawing's axes, their origins at the rooms' south-west
/// corners.
fn body_inside(robot: &Robot, plan: &FloorPlan) -> f64 {
    let origin = plan.rooms()[robot.room.unwrap()].origin_m;
    let s = &robot.spec;
    let front = s.front_m();
    let half = 0.5 * s.width_m;
    let corners = [
        (-s.rear_overhang_m, -half),
        (-s.rear_overhang_m, half),
        (front, -half),
        (front, half),
    ];
    let room_depth = |r: &PlanRoom, p: [f64; 2]| {
        (p[0] - r.origin_m[0])
            .min(r.origin_m[0] + r.size_m[0] - p[0])
            .min(p[1] - r.origin_m[1])
            .min(r.origin_m[1] + r.size_m[1] - p[1])
    };
    corners
        .iter()
        .map(|&(x, y)| {
            let c = robot.pose.transform_point(&Point2::new(x, y));
            let p = [c.x + origin[0], c.y + origin[1]];
            let in_gap = plan.doors().iter().any(|d| {
                // The doors of this plan are in walls along x.
                (p[0] - d.at_m[0]).abs() <= 0.5 * d.width_m && (p[1] - d.at_m[1]).abs() <= 0.1
            });
            let depth = plan
                .rooms()
                .iter()
                .map(|r| room_depth(r, p))
                .fold(f64::NEG_INFINITY, f64::max);
            if in_gap { f64::INFINITY } else { depth }
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn the_robot_turns_in_a_hall_too_narrow_to_turn_on_the_spot_in() {
    // Its front sweeps 0.81 m about the rear axle; the hall is 1.2 m
    // wide. Living room → kitchen → bedroom → living room, every door
    // through the hall.
    let plan = apartment();
    let mut robot = Robot::at(Pose2::new(1.7, 1.0, 0.0));
    robot.in_room(&plan, 0);
    let mut cfg = config(true);
    cfg.floor = Some(plan.clone());
    cfg.safety.obstacle_margin_m = 0.03;
    cfg.safety.lateral_margin_m = 0.02;
    let tasks = ["kitchen", "bedroom", "living"]
        .iter()
        .map(|r| TaskSpec::GoToRoom {
            room: (*r).to_owned(),
            approach_m: 1.0,
            beyond_m: 0.5,
            speed_mps: 0.3,
        })
        .collect();
    let mut exec = Executive::new(cfg, tasks);
    let (doors, closest) = run_rooms_inside(&mut exec, &mut robot, &plan, 900.0);
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    assert_eq!(doors, [0, 1, 1, 2, 2, 0]);
    assert_eq!(robot.room, Some(0));
    // The body kept off every wall by a centimetre at least (the plan
    // keeps the field's 2 cm sides and 2 cm more; the rest is the line
    // law's tracking).
    println!("closest to a wall: {closest:.3} m");
    assert!(closest >= 0.01, "{closest}");
}

/// With the default protective field (15 cm past each move's end), a
/// robot standing across the 1.2 m hall as deep as a door's approach
/// asks has its trailing end and the field behind it on the far wall: no
/// way reaches that approach. It turns into the door nearer it, without
/// touching a wall (the way was driven unchecked, through the walls).
#[test]
fn a_door_out_of_a_narrow_hall_is_approached_where_the_robot_can_turn_into_it() {
    let plan = apartment();
    // At the hall's east end, facing it.
    let mut robot = Robot::at(Pose2::new(7.2, 0.6, 0.0));
    robot.in_room(&plan, 2);
    let mut cfg = config(true);
    cfg.floor = Some(plan.clone());
    let mut exec = Executive::new(cfg, vec![go_to("living")]);
    let (doors, closest) = run_rooms_inside(&mut exec, &mut robot, &plan, 600.0);
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    assert_eq!(doors, [0]);
    assert_eq!(robot.room, Some(0));
    assert!(closest >= 0.01, "{closest}");
}

#[test]
fn the_robot_plasters_a_hall_too_narrow_to_turn_across_and_gives_up_its_end_walls() {
    // The apartment's hall, 8 × 1.2 m: the long walls' stations are turned
    // onto with the front in a doorway; the end walls' stand across the
    // hall, which no way turns the robot to. The laser sees the walls, so
    // the supervisor stops a way into one; the station is then given up.
    let (plan, mut robot, mut exec) = in_the_hall(plaster(false));
    let walls = hall_walls();
    let (mut first_plan, mut last_plan, mut given_up, mut passes) = (None, None, Vec::new(), 0);
    let mut closest = f64::INFINITY;
    for _ in 0..(4000.0 / DT) as usize {
        let seen = within_3_m(&robot, &walls);
        let out = ask_seeing(&mut exec, &robot, &seen);
        if first_plan.is_none() {
            first_plan = exec.plaster_plan().cloned();
        }
        if !out.events.is_empty()
            && let Some(p) = exec.plaster_plan()
        {
            last_plan = Some(p.clone());
        }
        for e in &out.events {
            match e.kind {
                EventKind::StationGivenUp {
                    unreachable_m2,
                    reason,
                    ..
                } => {
                    assert_eq!(reason, GiveUpReason::NoWay);
                    given_up.push(unreachable_m2);
                }
                EventKind::PassDone { .. } => passes += 1,
                _ => {}
            }
        }
        robot.drive(out.drive);
        closest = closest.min(body_inside(&robot, &plan));
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    let (first, last) = (first_plan.unwrap(), last_plan.unwrap());
    let lanes = |p: &stucco_plan::Plan, w: WallName| {
        p.stations
            .iter()
            .filter(|s| s.lane == stucco_plan::Lane::Wall(w))
            .count()
    };
    // Planned on every wall; every station along the long walls carried
    // out, every one facing an end wall given up.
    for w in WallName::ALL {
        assert!(lanes(&first, w) > 0, "{w:?}");
    }
    for w in [WallName::EAST, WallName::WEST] {
        assert_eq!(lanes(&last, w), 0, "{w:?}");
    }
    let end_walls = lanes(&first, WallName::EAST) + lanes(&first, WallName::WEST);
    assert_eq!(given_up.len(), end_walls, "{given_up:?}");
    assert_eq!(last.stations.len() + end_walls, first.stations.len());
    assert_eq!(
        passes,
        last.stations.iter().map(|s| s.passes.len()).sum::<usize>()
    );
    // What they alone reached is reported: the end walls less their
    // edges, 2.4 m² each.
    let lost = |p: &stucco_plan::Plan, w: WallName| {
        p.unreachable
            .iter()
            .filter(|u| u.surface == SurfaceId::Wall(w))
            .map(|u| u.area_m2)
            .sum::<f64>()
    };
    for w in [WallName::EAST, WallName::WEST] {
        assert!(
            (2.3..2.5).contains(&lost(&last, w)),
            "{w:?}: {}",
            lost(&last, w)
        );
    }
    // Nothing of the long walls is lost with them, and of the ceiling
    // only strips along the end walls (the long walls' stations reach
    // the rest).
    for w in [WallName::NORTH, WallName::SOUTH] {
        assert!(lost(&last, w) <= lost(&first, w) + 1e-9, "{w:?}");
    }
    let ceiling = |p: &stucco_plan::Plan| {
        p.unreachable
            .iter()
            .filter(|u| u.surface == SurfaceId::Ceiling)
            .map(|u| u.area_m2)
            .sum::<f64>()
    };
    assert!(
        ceiling(&last) <= ceiling(&first) + 0.3,
        "{}",
        ceiling(&last)
    );
    let reported: f64 = given_up.iter().sum();
    assert!(
        (reported - (last.unreachable_m2() - first.unreachable_m2())).abs() < 1e-6,
        "{reported}"
    );
    println!("closest to a wall: {closest:.3} m; given up: {given_up:?}");
    assert!(closest >= 0.01, "{closest}");
}

/// A robot in the apartment's hall (its room 2), the executive of an
/// unattended mission of `task` with the tight field the apartment's
/// missions set.
fn in_the_hall(task: TaskSpec) -> (FloorPlan, Robot, Executive) {
    let plan = apartment();
    let mut robot = Robot::at(Pose2::new(3.4, 0.6, 0.0));
    robot.in_room(&plan, 2);
    let mut cfg = config(true);
    cfg.spray = Some(stucco_plan::SprayTool::default());
    cfg.floor = Some(plan.clone());
    cfg.safety.obstacle_margin_m = 0.03;
    cfg.safety.lateral_margin_m = 0.02;
    (plan, robot, Executive::new(cfg, vec![task]))
}

/// The points of `walls` (room frame) within 3 m of `robot`, in its frame:
/// what its laser sees of them.
fn within_3_m(robot: &Robot, walls: &[Point2<f64>]) -> Vec<Point2<f64>> {
    let to_robot = robot.pose.inverse();
    walls
        .iter()
        .map(|p| to_robot.transform_point(p))
        .filter(|p| p.coords.norm() < 3.0)
        .collect()
}

/// The apartment's hall's walls as the laser sees them (hall frame), every
/// 2 cm, with the rooms beyond the open doors 1.6 m back.
fn hall_walls() -> Vec<Point2<f64>> {
    let line = |a: [f64; 2], b: [f64; 2]| {
        let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.02).ceil() as usize;
        (0..=n).map(move |k| {
            let t = k as f64 / n as f64;
            Point2::new(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
        })
    };
    line([0.0, 0.0], [3.1, 0.0])
        .chain(line([4.0, 0.0], [6.2, 0.0]))
        .chain(line([7.0, 0.0], [8.0, 0.0]))
        .chain(line([0.0, 1.2], [3.0, 1.2]))
        .chain(line([3.8, 1.2], [8.0, 1.2]))
        .chain(line([0.0, 0.0], [0.0, 1.2]))
        .chain(line([8.0, 0.0], [8.0, 1.2]))
        .chain(line([3.1, -1.6], [4.0, -1.6]))
        .chain(line([6.2, -1.6], [7.0, -1.6]))
        .chain(line([3.0, 2.8], [3.8, 2.8]))
        .collect()
}

/// Plastering only the hall's end walls, which no way turns the robot to
/// face: every station is given up, and the task fails saying so, never
/// done.
#[test]
fn a_plaster_task_whose_stations_are_all_given_up_fails_saying_why() {
    let (exec, given_up, _) = plaster_hall_walls(vec![WallName::EAST, WallName::WEST], 2000.0);
    let given_up = given_up.len();
    assert!(given_up > 0);
    assert!(
        matches!(exec.mode(), MissionMode::Failed { .. }),
        "{:?}",
        exec.mode()
    );
    match exec.failure() {
        Some(stucco_mission::TaskFailure::AllStationsGivenUp {
            stations,
            loose,
            unreachable_m2,
        }) => {
            assert_eq!(*stations, given_up);
            assert_eq!(*loose, 0, "no way reached them");
            // Both end walls less their edges, 2.4 m² each.
            assert!((4.6..5.0).contains(unreachable_m2), "{unreachable_m2}");
        }
        other => panic!("{other:?}: {:?}", exec.status()),
    }
}

/// Plastering the walls of a room whose floor the map holds taken along
/// every wall, a metre deep: no station is planned, and the task fails
/// saying so at once, never done.
#[test]
fn a_plaster_task_planned_no_station_fails_saying_why() {
    let config = ExecutiveConfig {
        spray: Some(stucco_plan::SprayTool::default()),
        ..config(true)
    };
    let mut walls_only = plaster(false);
    if let TaskSpec::Plaster { ceiling, .. } = &mut walls_only {
        *ceiling = false;
    }
    let mut exec = Executive::new(config, vec![walls_only]);
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let along = |min_m: [f64; 2], max_m: [f64; 2]| stucco_plan::Obstacle {
        min_m,
        max_m,
        height_m: 2.0,
    };
    robot.floor = vec![
        along([0.0, 0.0], [5.0, 1.0]),
        along([0.0, 2.0], [5.0, 3.0]),
        along([0.0, 0.0], [1.0, 3.0]),
        along([4.0, 0.0], [5.0, 3.0]),
    ];
    let mut events = Vec::new();
    for _ in 0..(60.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        events.extend(out.events);
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(planned_stations(&events), 0);
    match exec.failure() {
        Some(stucco_mission::TaskFailure::NothingReachable { unreachable_m2 }) => {
            assert!(*unreachable_m2 > 10.0, "{unreachable_m2}");
        }
        other => panic!("{other:?}: {:?}", exec.mode()),
    }
}

/// A plaster task of only `walls` of the apartment's hall, no ceiling,
/// run for at most `max_s` with the laser seeing the hall's walls: the
/// executive at the end, the stations given up (as numbered when given
/// up), and the first plan made.
fn plaster_hall_walls(
    walls: Vec<WallName>,
    max_s: f64,
) -> (Executive, Vec<usize>, Option<stucco_plan::Plan>) {
    let mut task = plaster(false);
    if let TaskSpec::Plaster {
        walls: w, ceiling, ..
    } = &mut task
    {
        *w = Some(walls);
        *ceiling = false;
    }
    let (_, mut robot, mut exec) = in_the_hall(task);
    let seen_walls = hall_walls();
    let (mut given_up, mut first) = (Vec::new(), None);
    for _ in 0..(max_s / DT) as usize {
        let seen = within_3_m(&robot, &seen_walls);
        let out = ask_seeing(&mut exec, &robot, &seen);
        first = first.or_else(|| exec.plaster_plan().cloned());
        given_up.extend(out.events.iter().filter_map(|e| match e.kind {
            EventKind::StationGivenUp { station, .. } => Some(station),
            _ => None,
        }));
        robot.drive(out.drive);
        if exec.mode().is_final() {
            break;
        }
    }
    (exec, given_up, first)
}

/// How far the body's outline keeps off the walls of its room and off
/// every box on its floor, m (negative: into one).
fn body_clearance(robot: &Robot) -> f64 {
    let s = &robot.spec;
    let front = s.front_m();
    let half = 0.5 * s.width_m;
    // The outline, every 5 cm.
    let outline: Vec<Point2<f64>> = (0..=20)
        .flat_map(|k| {
            let t = k as f64 / 20.0;
            let x = -s.rear_overhang_m + t * (front + s.rear_overhang_m);
            let y = -half + t * 2.0 * half;
            [(x, -half), (x, half), (-s.rear_overhang_m, y), (front, y)]
        })
        .map(|(x, y)| robot.pose.transform_point(&Point2::new(x, y)))
        .collect();
    let [xs, ys] = robot.room_m;
    outline
        .iter()
        .map(|p| {
            let walls = p.x.min(xs - p.x).min(p.y).min(ys - p.y);
            robot.floor.iter().fold(walls, |m, o| {
                let dx = (o.min_m[0] - p.x).max(p.x - o.max_m[0]);
                let dy = (o.min_m[1] - p.y).max(p.y - o.max_m[1]);
                // Outside: the distance; inside: how deep (negative).
                let d = if dx > 0.0 || dy > 0.0 {
                    dx.max(0.0).hypot(dy.max(0.0))
                } else {
                    dx.max(dy)
                };
                m.min(d)
            })
        })
        .fold(f64::INFINITY, f64::min)
}

/// The apartment's kitchen as its map has it: 2.85 m square, a counter
/// along the south wall 0.75 m deep, a column's box in the north-east
/// corner (not yet in the robot's floor map); a plastering task with a
/// survey, the apartment's margins, the robot facing south in the middle.
fn kitchen() -> (Executive, Robot, [stucco_plan::Obstacle; 2]) {
    let mut cfg = config(true);
    cfg.spray = Some(stucco_plan::SprayTool::default());
    cfg.safety.obstacle_margin_m = 0.03;
    cfg.safety.lateral_margin_m = 0.02;
    let exec = Executive::new(cfg, vec![plaster(true)]);
    let mut robot = Robot::at(Pose2::new(1.45, 2.0, -std::f64::consts::FRAC_PI_2));
    robot.room_m = [2.85, 2.85];
    let counter = stucco_plan::Obstacle {
        min_m: [0.0, 0.0],
        max_m: [2.85, 0.75],
        height_m: 1.0,
    };
    let column = stucco_plan::Obstacle {
        min_m: [2.25, 2.2],
        max_m: [2.85, 2.85],
        height_m: 1.0,
    };
    (exec, robot, [counter, column])
}

#[test]
fn the_robot_plasters_a_kitchen_with_a_counter_along_one_wall_and_a_column_in_a_corner() {
    // The kitchen, counter and column in the map from the start. The
    // survey loop turned on the move would be 0.4 m long; it is driven
    // corner to corner. The ways between stations, out of the lanes and
    // onto them again are the planned ones, every one clear.
    let (mut exec, mut robot, [counter, column]) = kitchen();
    robot.floor = vec![counter, column];
    let (mut closest, mut passes, mut legs) = (f64::INFINITY, 0, 0);
    let mut planned = 0;
    for _ in 0..(3000.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        if let Some(plan) = exec.plaster_plan() {
            planned = plan.stations.iter().map(|s| s.passes.len()).sum();
        }
        passes += out
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::PassDone { .. }))
            .count();
        legs += out
            .events
            .iter()
            .filter(|e| matches!(&e.kind, EventKind::BehaviourStarted { behaviour, .. } if behaviour == "path"))
            .count();
        robot.drive(out.drive);
        closest = closest.min(body_clearance(&robot));
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    assert_eq!(passes, planned);
    assert!(planned >= 8, "{planned} passes");
    // No loop turned on the move: the survey went corner to corner.
    assert_eq!(legs, 0);
    println!("closest to a wall or the furniture: {closest:.3} m");
    assert!(closest >= 0.01, "{closest}");
}

#[test]
fn a_survey_driven_corner_to_corner_moves_its_corners_off_a_column_found_under_way() {
    // The kitchen again, but the column in its north-east corner is not
    // yet in the floor map when the survey starts (the laser had not
    // looked that way): it appears once the first leg is under way. The
    // loop's north-east corner, fitted before, stands in it. The survey
    // still faces the east wall: it drives the loop's east side heading
    // south, its corners fitted again to the map as each leg starts.
    let (mut exec, mut robot, [counter, column]) = kitchen();
    robot.floor = vec![counter];
    let (mut plans, mut seen_since) = (0, None);
    // Seconds the camera (looking left) faced the east wall from the
    // loop's east side, squarely enough for the window finder.
    let mut facing_east_s = 0.0;
    let mut closest = f64::INFINITY;
    for _ in 0..(1500.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        plans += out
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::PlanMade { .. }))
            .count();
        if plans == 1 && seen_since.is_none() {
            seen_since = Some(robot.now);
        }
        if seen_since.is_some_and(|t| robot.now.seconds_since(t) > 5.0) && robot.floor.len() == 1 {
            robot.floor.push(column);
        }
        robot.drive(out.drive);
        closest = closest.min(body_clearance(&robot));
        let heading_south = (robot.pose.theta + std::f64::consts::FRAC_PI_2).abs() < 0.45;
        if plans == 1 && heading_south && robot.pose.x > 1.5 {
            facing_east_s += DT;
        }
        if plans >= 2 || exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(robot.floor.len(), 2, "the column was never added");
    assert!(plans >= 2, "no plan after the survey: {:?}", exec.status());
    println!("facing the east wall: {facing_east_s:.1} s; closest {closest:.3} m");
    assert!(facing_east_s > 2.0, "{facing_east_s} s");
    assert!(closest >= 0.01, "{closest}");
}

#[test]
fn a_survey_stays_on_the_robots_side_of_furniture_across_the_whole_room() {
    // A bedroom as its floor map may have it: the bed and the desk one box
    // right across the room, 1.45-2.0 m from the south wall, the robot in
    // the strip south of it. The strip beyond is wider, but no way leads
    // there: the loop is the robot's strip's, and it is driven.
    let tool = stucco_plan::SprayTool::default();
    let mut cfg = config(true);
    cfg.spray = Some(tool);
    cfg.safety.obstacle_margin_m = 0.03;
    cfg.safety.lateral_margin_m = 0.02;
    let mut exec = Executive::new(cfg, vec![plaster(true)]);
    let mut robot = Robot::at(Pose2::new(3.4, 0.35, std::f64::consts::FRAC_PI_2));
    robot.room_m = [4.0, 3.65];
    robot.floor = vec![stucco_plan::Obstacle {
        min_m: [0.0, 1.45],
        max_m: [4.0, 2.0],
        height_m: 1.0,
    }];
    let mut plans = Vec::new();
    let mut farthest_north = f64::MIN;
    for _ in 0..(600.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        for e in &out.events {
            if matches!(e.kind, EventKind::PlanMade { .. }) {
                plans.push(robot.now);
            }
        }
        robot.drive(out.drive);
        farthest_north = farthest_north.max(robot.pose.y);
        if plans.len() >= 2 || exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(plans.len(), 2, "{:?}", exec.status());
    let survey_s = plans[1].seconds_since(plans[0]);
    println!("survey {survey_s:.1} s, the rear axle at most {farthest_north:.2} m north");
    assert!(survey_s > 10.0, "{survey_s} s");
    assert!(farthest_north < 1.45, "{farthest_north}");
}

#[test]
fn a_survey_loop_something_blocks_goes_on_corner_to_corner() {
    // The survey's loop, turned on the move, meets something standing on
    // its first side, 1 m before the robot's front as the loop starts (a
    // chair the map did not hold; the
    // floor map holds it once the robot has stopped for it). The loop does
    // not go round; the survey goes on corner to corner, each leg the
    // planned way, and the plan is made again on what it saw.
    let tool = stucco_plan::SprayTool::default();
    let mut cfg = config(true);
    cfg.spray = Some(tool);
    let mut exec = Executive::new(cfg, vec![plaster(true)]);
    // At the loop's first corner, facing along its first side (west).
    let mut robot = Robot::at(Pose2::new(4.2, 1.0, std::f64::consts::PI));
    let (mut plans, mut chair, mut stopped) = (0, None, false);
    for _ in 0..(400.0 / DT) as usize {
        let seen: Vec<Point2<f64>> = chair
            .iter()
            .map(|c| robot.pose.inverse().transform_point(c))
            .collect();
        let out = ask_seeing(&mut exec, &robot, &seen);
        for e in &out.events {
            match &e.kind {
                EventKind::PlanMade { .. } => plans += 1,
                EventKind::BehaviourStarted { behaviour, .. }
                    if behaviour == "path" && chair.is_none() =>
                {
                    let ahead = robot.pose.transform_point(&Point2::new(1.0 + 0.75, 0.0));
                    chair = Some(ahead);
                }
                _ => {}
            }
        }
        if exec.hazard() == Some(Hazard::Obstacle)
            && !stopped
            && let Some(c) = chair
        {
            stopped = true;
            robot.floor.push(stucco_plan::Obstacle {
                min_m: [c.x - 0.15, c.y - 0.15],
                max_m: [c.x + 0.15, c.y + 0.15],
                height_m: 0.45,
            });
        }
        robot.drive(out.drive);
        if plans >= 2 || exec.mode().is_final() {
            break;
        }
    }
    assert!(
        stopped,
        "the loop never met the chair {chair:?} plans {plans} {:?}",
        robot.pose
    );
    assert!(!exec.mode().is_final(), "{:?}", exec.mode());
    assert_eq!(plans, 2, "{:?}", exec.status());
}

/// Furniture over three corners of a map_room loop near the walls (driven
/// corner to corner).
fn furniture_on_three_corners() -> Vec<stucco_plan::Obstacle> {
    let corner = |x: f64, y: f64| stucco_plan::Obstacle {
        min_m: [x - 0.5, y - 0.5],
        max_m: [x + 0.5, y + 0.5],
        height_m: 0.8,
    };
    vec![corner(0.5, 0.5), corner(4.5, 0.5), corner(4.5, 2.5)]
}

/// A `map_room` on a loop near the walls through those three corners,
/// driven corner to corner.
fn three_corner_map_room() -> Executive {
    executive(
        vec![map_room(Some(vec![[0.5, 0.5], [4.5, 0.5], [4.5, 2.5]]))],
        true,
    )
}

/// Runs until the timeout of [`map_room`] is past and asserts the task
/// failed saying no way reaches the corners, the robot still at `at`.
fn fails_with_no_way_to_corners(exec: &mut Executive, robot: &mut Robot, at: Point2<f64>) {
    let events = run(exec, robot, 130.0, |_, _| Vec::new());
    let MissionMode::Failed { reason } = exec.mode() else {
        panic!("{:?} {:?}", exec.mode(), kinds(&events));
    };
    assert!(
        reason.contains("no clear way reaches any corner"),
        "{reason}"
    );
    assert!((robot.pose.position() - at).norm() < 1e-6);
}

#[test]
fn a_map_room_loop_no_clear_way_reaches_fails_saying_so_without_moving_into_anything() {
    // Every corner of the loop taken by furniture: the robot waits where
    // it stands for the floor to change; at the timeout the task fails
    // naming why.
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    robot.room_sigma = [0.05; 2];
    robot.floor = furniture_on_three_corners();
    let mut exec = three_corner_map_room();
    fails_with_no_way_to_corners(&mut exec, &mut robot, Point2::new(2.5, 1.5));
    assert!(robot.now.as_secs_f64() > 120.0, "{:?}", robot.now);
}

#[test]
fn a_map_room_loop_blocked_goes_on_once_the_floor_is_clear() {
    // The furniture over the loop's corners is carried out after 30 s: the
    // loop is planned again on the clear floor and driven.
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    robot.room_sigma = [0.05; 2];
    robot.floor = furniture_on_three_corners();
    let mut exec = three_corner_map_room();
    run(&mut exec, &mut robot, 30.0, |_, _| Vec::new());
    assert!(!exec.mode().is_final(), "{:?}", exec.mode());
    assert!((robot.pose.position() - Point2::new(2.5, 1.5)).norm() < 1e-6);
    robot.floor.clear();
    run(&mut exec, &mut robot, 30.0, |_, _| Vec::new());
    assert!(!exec.mode().is_final(), "{:?}", exec.mode());
    assert!(
        (robot.pose.position() - Point2::new(2.5, 1.5)).norm() > 0.5,
        "{:?}",
        robot.pose
    );
}

#[test]
fn a_map_room_robot_at_a_corner_no_way_leaves_is_stuck_there() {
    // The robot stands at the loop's first corner; the other two are
    // taken by furniture. Standing at a corner is no way found: the task
    // fails at its timeout saying no way reaches the corners (it used to
    // plan every tick, its walls never seen).
    let mut robot = Robot::at(Pose2::new(0.5, 0.5, 0.0));
    robot.room_sigma = [0.05; 2];
    robot.floor = furniture_on_three_corners().split_off(1);
    let mut exec = three_corner_map_room();
    fails_with_no_way_to_corners(&mut exec, &mut robot, Point2::new(0.5, 0.5));
}

#[test]
fn a_map_room_robot_held_with_a_wall_behind_it_turns_to_look_at_it() {
    // A corridor 1.6 m wide, its loop end to end; furniture over its far
    // end. The near end wall is behind the robot (the laser sees 135°
    // either side of ahead): it turns on its spot toward it, sees it, and
    // the room is known where it stands.
    let mut robot = Robot::at(Pose2::new(1.0, 0.8, 0.0));
    robot.room_m = [5.0, 1.6];
    robot.floor = vec![stucco_plan::Obstacle {
        min_m: [3.5, 0.3],
        max_m: [4.5, 1.3],
        height_m: 0.8,
    }];
    robot.walls_seen[WallName::WEST.index()] = 0;
    let mut exec = executive(vec![map_room(Some(vec![[1.0, 0.8], [4.0, 0.8]]))], true);
    for _ in 0..(60.0 / DT) as usize {
        let out = ask(&mut exec, &robot, Seen::default());
        robot.drive(out.drive);
        let west = Pose2::new(0.0, 0.8, 0.0).position() - robot.pose.position();
        let bearing = wrap_angle(west.y.atan2(west.x) - robot.pose.theta);
        if bearing.abs() < 135f64.to_radians() {
            robot.walls_seen[WallName::WEST.index()] += 1;
        }
        if exec.mode().is_final() {
            break;
        }
    }
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    assert!(
        (robot.pose.position() - Point2::new(1.0, 0.8)).norm() < 0.3,
        "{:?}",
        robot.pose
    );
}

#[test]
fn a_map_room_loop_blocked_by_a_box_seen_on_the_way_goes_round_it_corner_to_corner() {
    // The loop 1 m inside the walls, turned on the move; a box on its
    // first side, in the floor map only once the loop is planned (it
    // takes the laser a while to map it). The loop goes on
    // corner to corner, each leg planned round the box, instead of
    // standing before it until the way is given up.
    let mut robot = Robot::at(Pose2::new(1.0, 1.0, 0.0));
    robot.room_sigma = [0.05; 2];
    let mut exec = executive(vec![map_room(Some(LOOP.to_vec()))], true);
    let (lo, hi) = ([2.4, 0.6], [3.0, 1.4]);
    let outline: Vec<Point2<f64>> = (0..=12)
        .flat_map(|k| {
            let t = k as f64 / 12.0;
            let (x, y) = (lo[0] + t * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1]));
            [
                Point2::new(x, lo[1]),
                Point2::new(x, hi[1]),
                Point2::new(lo[0], y),
                Point2::new(hi[0], y),
            ]
        })
        .collect();
    let mut beyond = false;
    for step in 0..(90.0 / DT) as usize {
        if step as f64 * DT > 1.0 && robot.floor.is_empty() {
            robot.floor.push(stucco_plan::Obstacle {
                min_m: lo,
                max_m: hi,
                height_m: 0.8,
            });
        }
        // The box's outline in the robot's frame.
        let seen: Vec<Point2<f64>> = outline
            .iter()
            .map(|p| robot.pose.inverse().transform_point(p))
            .collect();
        let out = ask_seeing(&mut exec, &robot, &seen);
        robot.drive(out.drive);
        let p = robot.pose.position();
        assert!(
            !(p.x > lo[0] && p.x < hi[0] && p.y > lo[1] && p.y < hi[1]),
            "{p:?}"
        );
        beyond |= p.x > 3.5;
        assert!(!exec.mode().is_final(), "{:?}", exec.mode());
    }
    assert!(beyond, "never got past the box: {:?}", robot.pose);
}

#[test]
fn a_second_coat_of_another_thickness_is_a_task_with_its_own_settings() {
    #[derive(serde::Deserialize)]
    struct File {
        task: Vec<TaskSpec>,
    }
    let f: File = toml::from_str(
        r#"
        [[task]]
        task = "plaster"
        walls = ["south"]
        ceiling = false
        survey = false

        [[task]]
        task = "plaster"
        walls = ["south"]
        ceiling = false
        survey = false
        spray = { thickness_mm = 5.0, flow_l_per_min = 6.0 }
        "#,
    )
    .expect("a mission with two coats");
    let base = stucco_plan::SprayTool::default();
    let TaskSpec::Plaster {
        spray: Some(second),
        ..
    } = &f.task[1]
    else {
        panic!("{:?}", f.task[1]);
    };
    let thinner = spray_with(&base, second).expect("settings of the tool");
    assert_eq!(thinner.thickness_mm, 5.0);
    assert_eq!(thinner.flow_l_per_min, 6.0);
    assert_eq!(thinner.footprint_sigma_m, base.footprint_sigma_m);
    // A setting the tool does not have, or of the wrong kind, is named.
    let mut bad = SpraySettings::new();
    bad.insert("thickness".to_owned(), 5.0.into());
    assert!(spray_with(&base, &bad).unwrap_err().contains("thickness"));
    bad.clear();
    bad.insert("thickness_mm".to_owned(), "thin".into());
    assert!(spray_with(&base, &bad).is_err());
    // Each coat is planned with its own thickness: the second one's
    // strokes, laying less plaster per m², take less time.
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = Executive::new(
        ExecutiveConfig {
            spray: Some(base.clone()),
            ..config(true)
        },
        f.task,
    );
    let mut plans: BTreeMap<usize, stucco_plan::Plan> = BTreeMap::new();
    run(&mut exec, &mut robot, 60.0, |_, exec| {
        match (exec.current_task(), exec.plaster_plan()) {
            (Some((task, "plaster")), Some(plan)) if !plans.contains_key(&task) => {
                plans.insert(task, plan.clone());
                // Planned: on with the next coat.
                vec![OperatorCommand::Skip]
            }
            _ => Vec::new(),
        }
    });
    assert_eq!(plans.len(), 2, "{:?}", exec.status());
    assert_eq!(plans[&0].tool.thickness_mm, 10.0);
    assert_eq!(plans[&1].tool.thickness_mm, 5.0);
    assert!(
        plans[&1].spray_s() < plans[&0].spray_s(),
        "{} s then {} s",
        plans[&0].spray_s(),
        plans[&1].spray_s()
    );
}

// ---- Operator link safety --------------------------------------------------

/// One tick with the telecommands `make` writes at the robot's time.
fn send(
    exec: &mut Executive,
    robot: &mut Robot,
    make: impl FnOnce(Stamp) -> Vec<Telecommand>,
) -> Outputs {
    let t = make(robot.now);
    tick_with(exec, robot, &t)
}

/// A jog is the operator driving: taken in any state but the e-stop's —
/// paused (the task held), after the mission's tasks are over — and ended
/// by a stop or the e-stop.
#[test]
fn a_jog_drives_in_any_state_but_the_e_stop() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(vec![forward(0.2)], false);
    run(&mut exec, &mut robot, 5.0, |_, _| Vec::new());
    assert_eq!(exec.mode(), &MissionMode::Done);
    let jog = |id: &str, at: Stamp| {
        command(
            id,
            at,
            Command::Jog {
                speed_mps: -0.2,
                steer_rad: 0.0,
                ttl_s: 0.5,
            },
        )
    };
    // After the mission's tasks are over.
    let out = send(&mut exec, &mut robot, |now| vec![jog("j1", now)]);
    assert_eq!(out.acks[0].reply, Reply::Accepted);
    assert_eq!(out.drive.speed_mps, -0.2);
    // Paused by a stop: the stop ends the jog at once; a new jog drives.
    let mut exec = executive(vec![forward(2.0)], false);
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    for _ in 0..50 {
        tick_with(&mut exec, &mut robot, &[]);
    }
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("s", now, Command::Stop)]
    });
    assert_eq!(out.drive, DriveCommand::STOP);
    assert!(matches!(exec.mode(), MissionMode::Paused { .. }));
    let x0 = robot.pose.x;
    for k in 0..10 {
        let cmds = if k == 0 {
            vec![jog("j2", robot.now)]
        } else {
            Vec::new()
        };
        let out = tick_with(&mut exec, &mut robot, &cmds);
        assert_eq!(out.drive.speed_mps, -0.2, "tick {k}");
    }
    assert!(robot.pose.x < x0 - 0.01, "{} → {}", x0, robot.pose.x);
    assert!(
        matches!(exec.mode(), MissionMode::Paused { .. }),
        "the task stays held"
    );
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("s2", now, Command::Stop)]
    });
    assert_eq!(out.drive, DriveCommand::STOP);
    assert!(
        out.acks
            .iter()
            .any(|a| a.id == "j2" && matches!(a.reply, Reply::Failed { .. }))
    );
    // E-stopped: the e-stop ends a jog, and a jog is refused until resumed.
    send(&mut exec, &mut robot, |now| vec![jog("j3", now)]);
    let out = ask(
        &mut exec,
        &robot,
        Seen {
            estop: true,
            ..Seen::default()
        },
    );
    assert_eq!(out.drive, DriveCommand::STOP);
    let out = send(&mut exec, &mut robot, |now| vec![jog("j4", now)]);
    assert!(
        matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("e-stop")),
        "{:?}",
        out.acks
    );
    assert_eq!(out.drive, DriveCommand::STOP);
}

/// A stop always stops: stale, or reusing an id an earlier command had.
/// Any other command reusing an id for other content is refused, naming
/// the id; a true retry gets the earlier reply.
#[test]
fn a_stop_always_stops_and_an_id_reused_for_another_command_is_refused() {
    let mut robot = Robot::at(Pose2::new(1.0, 1.5, 0.0));
    let mut exec = executive(vec![forward(2.0)], false);
    let status = command("c1", robot.now, Command::Status);
    let out = tick_with(&mut exec, &mut robot, std::slice::from_ref(&status));
    assert_eq!(out.acks[0].reply, Reply::Done);
    for _ in 0..50 {
        tick_with(&mut exec, &mut robot, &[]);
    }
    assert!(robot.pose.x > 1.01);
    // A stop reusing the status's id.
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("c1", now, Command::Stop)]
    });
    assert_eq!(out.drive, DriveCommand::STOP);
    assert!(matches!(exec.mode(), MissionMode::Paused { reason } if reason == "stop from ann"));
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("r", now, Command::Resume)]
    });
    assert_eq!(out.acks[0].reply, Reply::Done);
    // A stale stop.
    let mut stale = command("s-old", Stamp::ZERO, Command::Stop);
    stale.deadline = Stamp::from_secs_f64(0.1);
    let out = tick_with(&mut exec, &mut robot, &[stale]);
    assert_eq!(out.drive, DriveCommand::STOP);
    assert!(matches!(exec.mode(), MissionMode::Paused { .. }));
    // Another command under a used id: refused, nothing done.
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("c1", now, Command::Resume)]
    });
    assert!(
        matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains("another command")),
        "{:?}",
        out.acks
    );
    assert!(matches!(exec.mode(), MissionMode::Paused { .. }));
    // The status itself again: the same reply, once more.
    let out = tick_with(&mut exec, &mut robot, &[status]);
    assert_eq!(out.acks[0].reply, Reply::Done);
}

/// Targets no robot could reach are refused when the command arrives:
/// nothing is queued, and the mission goes on as it was.
#[test]
fn absurd_targets_are_refused_at_acceptance() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = standing_by();
    tick_with(&mut exec, &mut robot, &[]);
    let mv = |dx_m: f64, dy_m: f64| Command::MoveRelative {
        dx_m,
        dy_m,
        dtheta_deg: 0.0,
        landmark: None,
    };
    for (k, (cmd, why)) in [
        (mv(1e300, 0.0), "outside"),
        (mv(4.0, 0.0), "outside"),
        (mv(0.0, -1.4), "outside"),
        (
            Command::FollowWall {
                wall: WallName::SOUTH,
                standoff_m: 0.6,
                from_m: 1.0,
                to_m: 40.0,
            },
            "to_m",
        ),
        (
            Command::AlignToWall {
                wall: WallName::WEST,
                standoff_m: 9.0,
                at_m: 1.0,
                side: Side::Left,
            },
            "standoff_m",
        ),
        (
            Command::MoveRelative {
                dx_m: -1.0,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: Some(Landmark::Door(99)),
            },
            "door 99",
        ),
        (Command::PassDoor { door: 99 }, "door 99"),
        (
            Command::FollowWall {
                wall: WallName::new(5),
                standoff_m: 0.6,
                from_m: 1.0,
                to_m: 2.0,
            },
            "no wall 5",
        ),
        (
            Command::MoveRelative {
                dx_m: -1.0,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: Some(Landmark::Wall(WallName::new(4))),
            },
            "no wall 4",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let out = send(&mut exec, &mut robot, |now| {
            vec![command(&format!("a{k}"), now, cmd)]
        });
        assert!(
            matches!(&out.acks[0].reply, Reply::Rejected { reason } if reason.contains(why)),
            "{k}: {:?}",
            out.acks
        );
    }
    assert_eq!(exec.tasks().len(), 1, "nothing queued");
    assert_eq!(exec.mode(), &MissionMode::Running);
    // A move that stays in the room is taken.
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("ok", now, mv(1.0, 0.0))]
    });
    assert_eq!(out.acks[0].reply, Reply::Accepted);
}

/// A pass along the south wall that starts at its corner: it fails at
/// once.
fn impossible_pass() -> TaskSpec {
    TaskSpec::FollowWall {
        wall: WallName::SOUTH,
        standoff_m: 0.6,
        from_m: 1.0,
        to_m: 4.0,
        speed_mps: 0.25,
    }
}

/// An operator's task that fails is answered `failed` and the robot
/// stands ready: the next command runs. A scripted task's failure stops
/// the mission (the default policy), the operator's commands are still
/// taken, and `resume` tries the failed task again; with
/// `on_task_failure = "continue"` the mission goes on and ends failed.
#[test]
fn a_failed_task_leaves_the_robot_ready_for_the_next_command() {
    let impossible_pass = impossible_pass();
    // The operator's task fails alone.
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = standing_by();
    tick_with(&mut exec, &mut robot, &[]);
    let pass = command(
        "f1",
        robot.now,
        Command::FollowWall {
            wall: WallName::SOUTH,
            standoff_m: 0.6,
            from_m: 1.0,
            to_m: 4.0,
        },
    );
    let mut replies = tick_with(&mut exec, &mut robot, &[pass]).acks;
    for _ in 0..5 {
        replies.extend(tick_with(&mut exec, &mut robot, &[]).acks);
    }
    assert!(
        replies
            .iter()
            .any(|a| a.id == "f1" && matches!(a.reply, Reply::Failed { .. }))
    );
    assert!(
        !matches!(exec.mode(), MissionMode::Failed { .. }),
        "{:?}",
        exec.mode()
    );
    let out = send(&mut exec, &mut robot, |now| {
        vec![command(
            "m",
            now,
            Command::MoveRelative {
                dx_m: 0.3,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: None,
            },
        )]
    });
    assert_eq!(out.acks[0].reply, Reply::Accepted);
    let mut done = false;
    for _ in 0..300 {
        done |= tick_with(&mut exec, &mut robot, &[])
            .acks
            .iter()
            .any(|a| a.id == "m" && a.reply == Reply::Done);
    }
    assert!(done, "the next command ran");

    // A scripted task's failure stops the mission; the operator still
    // commands; resumed, the failed task is tried again.
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(vec![impossible_pass.clone(), forward(0.3)], false);
    run(&mut exec, &mut robot, 1.0, |_, _| Vec::new());
    assert!(matches!(exec.mode(), MissionMode::Failed { .. }));
    let out = send(&mut exec, &mut robot, |now| {
        vec![command(
            "m",
            now,
            Command::MoveRelative {
                dx_m: 0.2,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: None,
            },
        )]
    });
    assert_eq!(out.acks[0].reply, Reply::Accepted);
    let mut steps = 0;
    while !matches!(exec.mode(), MissionMode::Failed { .. }) {
        tick_with(&mut exec, &mut robot, &[]);
        steps += 1;
        assert!(steps < 500, "{:?}", exec.mode());
    }
    assert_eq!(
        exec.status()[2],
        TaskStatus::Pending,
        "the mission's own task stays held"
    );
    let out = send(&mut exec, &mut robot, |now| {
        vec![command("r", now, Command::Resume)]
    });
    assert_eq!(out.acks[0].reply, Reply::Done);
    // Tried again (and, its pass still impossible, failed again).
    assert_eq!(
        kinds(&out.events),
        ["resumed", "task_failed", "mission_failed"],
        "{:?}",
        out.events
    );
    assert!(matches!(exec.mode(), MissionMode::Failed { .. }));

    // Going on past a failure, the mission ends failed for it.
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut cfg = config(false);
    cfg.safety.on_task_failure = FailurePolicy::Continue;
    let mut exec = Executive::new(cfg, vec![impossible_pass, forward(0.3)]);
    let events = run(&mut exec, &mut robot, 10.0, |_, _| Vec::new());
    assert_eq!(exec.status()[1], TaskStatus::Done, "{:?}", kinds(&events));
    assert!(matches!(exec.mode(), MissionMode::Failed { reason } if reason.contains("corner")));
}

/// By default, a task of one room's share of a job over rooms that fails
/// gives that room up (the rest of its share is skipped: no mapping of a
/// room the robot did not get to) and the job goes on with the next
/// room, ending failed for it; with `on_task_failure = "stop"` it stops.
#[test]
fn a_failed_room_is_given_up_and_the_job_goes_on_with_the_next() {
    let impossible_pass = impossible_pass();
    let tasks = vec![impossible_pass, forward(0.3), forward(0.3)];
    let shares = vec![Some(0), Some(0), Some(1)];
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(tasks.clone(), true).with_rooms(shares.clone());
    let events = run(&mut exec, &mut robot, 10.0, |_, _| Vec::new());
    assert!(matches!(exec.status()[0], TaskStatus::Failed { .. }));
    assert_eq!(
        exec.status()[1..],
        [TaskStatus::Skipped, TaskStatus::Done],
        "{:?}",
        kinds(&events)
    );
    assert!(matches!(exec.mode(), MissionMode::Failed { reason } if reason.contains("corner")));
    assert!(
        robot.pose.x > 1.7,
        "the next room's task drove: {:?}",
        robot.pose
    );

    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut cfg = config(true);
    cfg.safety.on_task_failure = FailurePolicy::Stop;
    let mut exec = Executive::new(cfg, tasks).with_rooms(shares);
    run(&mut exec, &mut robot, 10.0, |_, _| Vec::new());
    assert_eq!(
        exec.status()[1..],
        [TaskStatus::Pending, TaskStatus::Pending]
    );
    assert!(matches!(exec.mode(), MissionMode::Failed { .. }));
}

/// A million commands at 1,000 a second: the ids remembered for retries
/// stay those within their deadlines (10 s ahead here), never all.
#[test]
fn a_million_commands_keep_the_memory_of_ids_bounded() {
    let robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = standing_by();
    let est = robot.estimate();
    let mut most = 0;
    for k in 0..1_000_000_u64 {
        let now = Stamp::from_nanos(k as i64 * 1_000_000);
        let acks = exec.telecommands(
            now,
            &[command(&format!("c{k}"), now, Command::Status)],
            &est,
        );
        assert_eq!(acks[0].reply, Reply::Done);
        most = most.max(exec.remembered_commands());
    }
    assert!(most <= 10_002, "{most} ids kept");
}

/// A jog backwards stops for what the laser saw before and no longer
/// sees (behind the robot); forwards, such echoes hold nothing up.
#[test]
fn a_jog_backwards_stops_for_what_is_behind() {
    let mut robot = Robot::at(Pose2::new(2.5, 1.5, 0.0));
    let mut exec = standing_by();
    tick_with(&mut exec, &mut robot, &[]);
    // A box 0.15 m behind the body (its back is 0.15 m behind the rear
    // axle): within the field at 0.2 m/s.
    let behind = [Point2::new(-0.3, 0.0), Point2::new(-0.3, 0.1)];
    let jog = |id: &str, at: Stamp, speed_mps: f64| {
        command(
            id,
            at,
            Command::Jog {
                speed_mps,
                steer_rad: 0.0,
                ttl_s: 0.5,
            },
        )
    };
    for (id, speed, moves) in [("back", -0.2, false), ("ahead", 0.2, true)] {
        let t = [jog(id, robot.now, speed)];
        let out = ask(
            &mut exec,
            &robot,
            Seen {
                unseen: &behind,
                telecommands: &t,
                ..Seen::default()
            },
        );
        assert_eq!(out.drive.speed_mps != 0.0, moves, "{id}: {:?}", out.drive);
        assert_eq!(exec.hazard().is_some(), !moves, "{id}");
        send(&mut exec, &mut robot, |now| {
            vec![command(&format!("{id}-stop"), now, Command::Stop)]
        });
        for _ in 0..30 {
            tick_with(&mut exec, &mut robot, &[]);
        }
    }
}

/// A planned move backwards is guarded as a jog is: at the end of a wall
/// pass the robot backs out along its standoff, and the echoes kept
/// behind it (the laser looks ahead) hold it there until they are gone.
#[test]
fn a_planned_move_backwards_stops_for_what_is_behind() {
    let mut robot = Robot::at(Pose2::new(1.5, 1.5, 0.0));
    let mut exec = executive(vec![south_pass()], true);
    let backing = |exec: &Executive| {
        matches!(
            exec.current_behaviour(),
            Some(BehaviourKind::Reverse { .. })
        )
    };
    let mut k = 0;
    while !backing(&exec) {
        tick_with(&mut exec, &mut robot, &[]);
        k += 1;
        assert!(k < 6000, "no backing out in 120 s: {:?}", exec.mode());
    }
    // A box 0.15 m behind the body (its back is 0.15 m behind the rear
    // axle): within the field.
    let behind = [Point2::new(-0.3, 0.0), Point2::new(-0.3, 0.1)];
    let at = robot.pose;
    for _ in 0..100 {
        let out = ask(
            &mut exec,
            &robot,
            Seen {
                unseen: &behind,
                ..Seen::default()
            },
        );
        assert!(out.drive.speed_mps >= 0.0, "{:?}", out.drive);
        robot.drive(out.drive);
    }
    assert_eq!(exec.hazard(), Some(Hazard::Obstacle));
    assert!((robot.pose.position() - at.position()).norm() < 0.01);
    // Gone: it backs out.
    let mut backed = false;
    for _ in 0..100 {
        backed |= tick_with(&mut exec, &mut robot, &[]).drive.speed_mps < 0.0;
    }
    assert!(backed, "{:?}", exec.current_behaviour());
}

/// Plastering the hall's east end wall and its north wall: the robot is
/// held turning toward the end wall's station, which it cannot face, and
/// that station is given up where the field holds it. It runs out of
/// there before the way on is planned: from where it was held, no way to
/// any station was found clear, and every station of the north wall was
/// given up in turn (the task failed with nothing plastered).
#[test]
fn a_robot_held_turning_toward_a_station_given_up_runs_out_before_the_next() {
    let (exec, given_up, first) = plaster_hall_walls(vec![WallName::EAST, WallName::NORTH], 3000.0);
    assert_eq!(exec.mode(), &MissionMode::Done, "{:?}", exec.status());
    let first = first.expect("a plan");
    let on = |w: WallName| {
        first
            .stations
            .iter()
            .filter(|s| s.lane == stucco_plan::Lane::Wall(w))
            .count()
    };
    // Only the end wall's stations are given up.
    assert!(on(WallName::NORTH) >= 5, "{}", on(WallName::NORTH));
    assert_eq!(given_up.len(), on(WallName::EAST), "{given_up:?}");
}

/// A survey driven corner to corner, held on its way for good (someone
/// the robot backs toward, cornered at a corridor's end): each leg is
/// planned again three times, then its corner is left out and the survey
/// goes on with the next; done with its corners, it plans on what it
/// found. The job failed there when the way stayed blocked 30 s.
#[test]
fn a_survey_leg_held_for_good_is_left_out_and_the_survey_goes_on() {
    let (mut exec, mut robot, [counter, column]) = kitchen();
    robot.floor = vec![counter, column];
    // Just off the body ahead and behind: no move of it is clear (the
    // kitchen's margins are small).
    let holding = [Point2::new(0.77, 0.0), Point2::new(-0.18, 0.0)];
    let (mut events, mut held_s) = (Vec::new(), 0.0f64);
    for _ in 0..(120.0 / DT) as usize {
        let out = ask_seeing(&mut exec, &robot, &holding);
        events.extend(out.events);
        if exec.hazard() == Some(Hazard::Obstacle) {
            held_s += DT;
        }
        robot.drive(out.drive);
        if exec.mode().is_final() || exec.plaster_plan().is_some_and(|_| held_s > 60.0) {
            break;
        }
    }
    let k = kinds(&events);
    assert!(held_s > 5.0, "never held: {k:?}");
    assert!(!exec.mode().is_final(), "{:?} {k:?}", exec.mode());
}
