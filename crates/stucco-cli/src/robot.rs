//! `stucco robot`: the executive and the simulator paced to the wall clock
//! (or faster), commanded and watched over zenoh through `stucco-link`.

use crate::mission::{BadInput, Mission};
use crate::navigator::DT_S;
use crate::task_mission::mission_navigator;
use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use stucco_core::{DriveCommand, Pose2, Stamp};
use stucco_link::{Denial, LinkConfig, RobotLink, ScanFrame};
use stucco_mission::{BehaviourKind, Hazard, Inputs, MissionMode};

/// What `stucco robot` was asked to do.
#[derive(Clone, Debug)]
pub struct RobotJob {
    /// The mission file (its world, its start, its failsafe; its tasks run
    /// first, then the operator's).
    pub mission: PathBuf,
    /// The robot's name on the network.
    pub name: String,
    /// How to join the network.
    pub link: LinkConfig,
    /// Simulated seconds per wall-clock second (1: real time).
    pub speed: f64,
    /// Stop after this much simulated time (none: until told to stop).
    pub stop_after_s: Option<f64>,
}

/// The robot's state as `stucco/NAME/state` publishes it.
#[derive(Clone, Debug, Serialize)]
pub struct RobotState<'a> {
    /// Simulated time.
    pub stamp: Stamp,
    /// The robot's name.
    pub name: &'a str,
    /// The mission's state.
    pub mission: &'a MissionMode,
    /// The task under way: index and name.
    pub task: Option<(usize, &'static str)>,
    /// The behaviour under way.
    pub behaviour: Option<&'a BehaviourKind>,
    /// The floor plan's room the robot is in (the pose's frame), when the
    /// mission has a plan.
    pub room: Option<&'a str>,
    /// The estimated pose in the room.
    pub pose: Pose2,
    /// Its position σ, m.
    pub position_sigma_m: f64,
    /// What the supervisor holds the robot for.
    pub hazard: Option<Hazard>,
    /// The drive command going out, after the supervisor.
    pub drive: DriveCommand,
}

/// Control periods between two published scans (10 a second).
const SCAN_EVERY: u64 = 5;
/// Control periods in a second.
const ONCE_A_SECOND: u64 = (1.0 / DT_S) as u64;

/// How a robot's run ended.
#[derive(Clone, Debug, Serialize)]
pub struct RobotRun {
    /// Simulated seconds run.
    pub simulated_s: f64,
    /// What zenoh's access control refused on the robot's keys, in order
    /// (each one also logged as it came).
    pub denials: Vec<Denial>,
}

/// Runs the robot until `stop` is set or the job's time is up. Installs the
/// process's log ([`crate::init_logging`]) if none is installed.
pub fn run_robot(job: &RobotJob, stop: &Arc<AtomicBool>) -> Result<RobotRun> {
    crate::init_logging();
    let mission = Mission::load(&job.mission)?;
    let world = mission.load_world(&job.mission)?;
    if !(job.speed.is_finite() && job.speed > 0.0) {
        return Err(BadInput("--speed: a positive number".to_owned()).into());
    }
    // The robot is put at the world's start, in the room frame of the room
    // it stands in.
    let (mut nav, _) = mission_navigator(&mission, &world, mission.seed, None)?;
    nav.discover_doors(true);
    let mut exec = mission.executive(false);
    let session = match stucco_link::open(&job.link) {
        Ok(s) => s,
        Err(e @ stucco_link::LinkError::Config { .. }) => {
            return Err(BadInput(format!("--zenoh-config: {e}")).into());
        }
        Err(e) => return Err(anyhow::Error::from(e).context("joining the zenoh network")),
    };
    tracing::info!(
        robot = %job.name,
        "on zenoh: stucco/{}/... (Ctrl-C stops it)",
        job.name
    );
    if job.link.config_file.is_none() {
        tracing::warn!(
            robot = %job.name,
            "no --zenoh-config: the link is open, anyone who reaches this robot may command it \
             (fine on one machine; see README, \"Who may command\")"
        );
    }
    let mut link = RobotLink::new(&session, &job.name)?;
    let t0 = Instant::now();
    let mut bumper = false;
    let mut step = 0u64;
    let mut heard: Option<Instant> = None;
    let mut denials = Vec::new();
    // The link's timeout on the wall clock.
    let link_timeout = Duration::from_secs_f64(mission.failsafe.link_timeout_s / job.speed);
    loop {
        let now = nav.now();
        let sim_s = now.as_secs_f64();
        if link.operator_heartbeat() {
            heard = Some(Instant::now());
        }
        for d in link.denials() {
            tracing::warn!(robot = %job.name, zid = %d.zid, "{d}");
            denials.push(d);
        }
        if let Some(h) = heard {
            exec.link(now, h.elapsed() <= link_timeout);
        }
        if stop.load(Ordering::Relaxed) || job.stop_after_s.is_some_and(|t| sim_s >= t) {
            break;
        }
        let telecommands = link.take_commands(now);
        let est = nav.mission_estimate();
        let out = exec.tick(
            now,
            &Inputs {
                estimate: &est,
                obstacles: nav.obstacles(),
                bumper,
                estop: false,
                operator: &[],
                telecommands: &telecommands,
            },
        );
        link.send_acks(&out.acks)?;
        link.publish_events(&out.events)?;
        // State every control period (50 Hz of the robot's time): a
        // watcher sees a stop when it happens.
        link.publish_state(&RobotState {
            stamp: now,
            name: &job.name,
            mission: exec.mode(),
            task: exec.current_task(),
            behaviour: exec.current_behaviour(),
            room: nav.room_name(),
            pose: est.pose,
            position_sigma_m: est.position_sigma_m,
            hazard: exec.hazard(),
            drive: out.drive,
        })?;
        // Scans 10 a second; the map, the coverage and the heartbeat once.
        if step.is_multiple_of(SCAN_EVERY) {
            link.publish_scan(&ScanFrame {
                stamp: now,
                points: nav
                    .obstacles()
                    .iter()
                    .map(|p| [p.x as f32, p.y as f32])
                    .collect(),
            })?;
        }
        if step.is_multiple_of(ONCE_A_SECOND) {
            link.heartbeat(now)?;
            link.publish_map(&est)?;
            if let Some(c) = exec.coverage() {
                link.publish_coverage(&c)?;
            }
        }
        if let Some(door) = out.enter_room
            && let Err(why) = nav.enter_through(door)
        {
            // The executive fails the task on its next tick.
            tracing::warn!(robot = %job.name, door, "the robot's frame stays: {why}");
        }
        nav.tool(out.tool);
        nav.tool_look(out.tool_look);
        bumper = nav.drive(out.drive);
        step += 1;
        // Paced: simulated time runs `speed` times the wall clock. Until the
        // next period, commands are taken as they come and answered at once.
        let due = t0 + Duration::from_secs_f64((sim_s + DT_S) / job.speed);
        while let Some(wait) = due.checked_duration_since(Instant::now()) {
            let now = nav.now();
            let cmds = link.wait_commands(now, wait);
            if !cmds.is_empty() {
                let est = nav.mission_estimate();
                let acks = exec.telecommands(now, &cmds, &est);
                link.send_acks(&acks)?;
            }
        }
    }
    Ok(RobotRun {
        simulated_s: nav.now().as_secs_f64(),
        denials,
    })
}
