//! `stucco robot`: the executive on the simulator in this process, paced
//! to the wall clock (or faster), or on a platform served over zenoh;
//! commanded and watched over zenoh through `stucco-link`.

use crate::sim_robot::{Served, Simulated, mission_sim_config, mission_simulator, robot_spec};
use crate::task_mission::{Ending, Setup, SimJob};
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use stucco_core::{Platform, RobotState};
use stucco_link::{Denial, LinkConfig, RobotLink, ScanFrame, Session, ZenohPlatform};
use stucco_mission::{Inputs, Outputs};
use stucco_runtime::{BadInput, DT_S, Mission, Robot, Sink, SinkError, read_checkpoint};

/// The robot's body.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PlatformKind {
    /// The simulator, in this process, in the mission's world.
    #[default]
    Sim,
    /// A platform on zenoh under `stucco/NAME/platform/` (`stucco sim
    /// serve`, or a real robot's driver).
    Zenoh,
}

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
    /// Leave when the mission's tasks are over (a scripted job), instead
    /// of waiting for the operator's commands.
    pub exit_when_done: bool,
    /// The job's folder: its checkpoint after every unit of work, its
    /// events, the simulated world beside the checkpoint, the report when
    /// the robot stops (none: nothing written).
    pub out: Option<PathBuf>,
    /// Go on from the checkpoint in `out`.
    pub resume: bool,
    /// Record the run to `out/run.mcap`.
    pub record: bool,
    /// The robot's body.
    pub platform: PlatformKind,
    /// How long a platform on zenoh may stay silent (to be found, or in a
    /// period) before the robot stops.
    pub platform_timeout: Duration,
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
    /// How the mission stood when the robot stopped: `done`, `failed`,
    /// `aborted` or `stopped`.
    pub outcome: String,
    /// What zenoh's access control refused on the robot's keys, in order
    /// (each one also logged as it came).
    pub denials: Vec<Denial>,
}

/// What the robot's loop tells the operators over zenoh: replies,
/// events, the state every control period, scans ten times a second, the
/// map, the coverage and a heartbeat once a second.
struct Telemetry<'a> {
    link: &'a mut RobotLink,
    name: &'a str,
}

impl<P: Platform> Sink<P> for Telemetry<'_> {
    fn ticked(
        &mut self,
        robot: &Robot<P>,
        inputs: &Inputs<'_>,
        out: &Outputs,
    ) -> Result<(), SinkError> {
        let (exec, est, now) = (robot.executive(), inputs.estimate, robot.now());
        let step = robot.periods();
        self.link.send_acks(&out.acks)?;
        self.link.publish_events(&out.events)?;
        // State every control period (50 Hz of the robot's time): a
        // watcher sees a stop when it happens.
        self.link.publish_state(&RobotState {
            stamp: now,
            name: self.name.to_owned(),
            mission: exec.mode().clone(),
            task: exec.current_task().map(|(k, t)| (k, t.to_owned())),
            behaviour: exec.current_behaviour().cloned(),
            room: robot.perception().room_name().map(str::to_owned),
            pose: est.pose,
            position_sigma_m: est.position_sigma_m,
            hazard: exec.hazard(),
            drive: out.drive,
        })?;
        // Scans 10 a second; the map, the coverage and the heartbeat once.
        if step.is_multiple_of(SCAN_EVERY) {
            self.link.publish_scan(&ScanFrame {
                stamp: now,
                points: inputs
                    .obstacles
                    .iter()
                    .map(|p| [p.x as f32, p.y as f32])
                    .collect(),
            })?;
        }
        if step.is_multiple_of(ONCE_A_SECOND) {
            self.link.heartbeat(now)?;
            self.link.publish_map(est)?;
            if let Some(c) = exec.coverage() {
                self.link.publish_coverage(&c)?;
            }
        }
        Ok(())
    }
}

/// Runs the robot until `stop` is set or the job's time is up (or, with
/// `exit_when_done`, its mission's tasks are over). Installs the process's
/// log ([`crate::init_logging`]) if none is installed.
pub fn run_robot(job: &RobotJob, stop: &Arc<AtomicBool>) -> Result<RobotRun> {
    crate::init_logging();
    let mission = Mission::load(&job.mission)?;
    let world = crate::sim_robot::load_world(&mission, &job.mission)?;
    if !(job.speed.is_finite() && job.speed > 0.0) {
        return Err(BadInput("--speed: a positive number".to_owned()).into());
    }
    if (job.resume || job.record) && job.out.is_none() {
        return Err(BadInput(
            "--resume and --record use the job's folder: they need --out DIR".to_owned(),
        )
        .into());
    }
    let mut seed = mission.seed;
    let resume = match (&job.out, job.resume) {
        (Some(dir), true) => {
            let cp = read_checkpoint(&dir.join(stucco_runtime::CHECKPOINT_FILE), &mission)?;
            seed = cp.seed;
            Some(cp)
        }
        _ => None,
    };
    let setup = Setup {
        mission: &mission,
        mission_path: &job.mission,
        record: job.record,
        world: &world,
        resume: resume.as_ref(),
        stop_after: job.stop_after_s,
    };
    let session = match stucco_link::open(&job.link) {
        Ok(s) => s,
        Err(e @ stucco_link::LinkError::Config { .. }) => {
            return Err(BadInput(format!("--zenoh-config: {e}")).into());
        }
        Err(e) => return Err(anyhow::Error::from(e).context("joining the zenoh network")),
    };
    // The robot is put at the world's start (or where a checkpoint left
    // it), in the room frame of the room it stands in. The process may be
    // killed at any moment: a simulated world in this process is kept
    // beside every checkpoint, as the plaster stays on a real wall.
    let quiet = |_: f64, _: &str| {};
    let out = job.out.as_deref();
    match job.platform {
        PlatformKind::Sim => {
            let sim = SimJob::start(&setup, seed, out, &quiet, false, true, |world| {
                Ok((mission_simulator(&mission, world, seed), robot_spec()))
            })?;
            drive(job, &mission, &session, sim, stop)
        }
        PlatformKind::Zenoh => {
            let sim = SimJob::start(&setup, seed, out, &quiet, false, true, |world| {
                let platform = ZenohPlatform::connect(&session, &job.name, job.platform_timeout)
                    .with_context(|| {
                        format!(
                            "finding the platform {} (stucco/{}/platform/info)",
                            job.name, job.name
                        )
                    })?;
                let spec = platform.info().spec.clone();
                tracing::info!(
                    robot = %job.name,
                    lockstep = platform.info().lockstep,
                    "on the platform stucco/{}/platform/",
                    job.name
                );
                Ok((
                    Served::new(platform, world.clone(), mission_sim_config(&mission)),
                    spec,
                ))
            })?;
            drive(job, &mission, &session, sim, stop)
        }
    }
}

/// The robot's loop: the job stepped paced to the clock, the operators'
/// commands taken as they come, until it stops.
fn drive<P: Simulated>(
    job: &RobotJob,
    mission: &Mission,
    session: &Session,
    mut sim: SimJob<'_, P>,
    stop: &Arc<AtomicBool>,
) -> Result<RobotRun> {
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
    let mut link = RobotLink::new(session, &job.name)?;
    let t0 = Instant::now();
    let sim_t0 = sim.robot.now().as_secs_f64();
    let mut heard: Option<Instant> = None;
    let mut denials = Vec::new();
    // The link's timeout on the wall clock.
    let link_timeout = Duration::from_secs_f64(mission.failsafe.link_timeout_s / job.speed);
    let ending = loop {
        let now = sim.robot.now();
        let sim_s = now.as_secs_f64();
        if link.operator_heartbeat() {
            heard = Some(Instant::now());
        }
        for d in link.denials() {
            tracing::warn!(robot = %job.name, zid = %d.zid, "{d}");
            denials.push(d);
        }
        if let Some(h) = heard {
            sim.robot
                .executive_mut()
                .link(now, h.elapsed() <= link_timeout);
        }
        if stop.load(Ordering::Relaxed) {
            break Ending::Stopped;
        }
        let telecommands = link.take_commands(now);
        let mut telemetry = Telemetry {
            link: &mut link,
            name: &job.name,
        };
        sim.tick(&telecommands, Some(&mut telemetry))?;
        // Where `stucco run` stops, after the period's tick: the same job
        // gives the same report.
        if job.exit_when_done && sim.robot.executive().mode().is_final() {
            break Ending::Over;
        }
        if job.stop_after_s.is_some_and(|t| sim_s >= t) {
            break Ending::Stopped;
        }
        sim.act(None)?;
        // Paced: simulated time runs `speed` times the wall clock. Until the
        // next period, commands are taken as they come and answered at once.
        let due = t0 + Duration::from_secs_f64((sim_s - sim_t0 + DT_S) / job.speed);
        while let Some(wait) = due.checked_duration_since(Instant::now()) {
            let now = sim.robot.now();
            let cmds = link.wait_commands(now, wait);
            if !cmds.is_empty() {
                let acks = sim.robot.telecommands(&cmds);
                link.send_acks(&acks)?;
            }
        }
    };
    let simulated_s = sim.robot.now().as_secs_f64();
    let report = sim.finish(ending)?;
    Ok(RobotRun {
        simulated_s,
        outcome: report.outcome,
        denials,
    })
}
