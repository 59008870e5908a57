//! `stucco run` for task missions: the executive carries out the mission
//! file's tasks in the simulator, in simulated time as fast as the CPU
//! allows; the run is scored against the truth and written down — report,
//! events, a map, and a checkpoint after every finished task so a run
//! started again with `--resume` goes on where it stopped.

use crate::plan_view::{PlanPath, PlanSegment, draw_plan};
use crate::plastering::{WORLD_FILE, WorldState};
use crate::record::Recording;
use crate::record::{RecordedMission, Recorder};
pub(crate) use crate::room_frame::RoomFrame;
use crate::sim_robot::{Simulated, WorldKeeper, mission_simulator, robot_on, robot_spec};
use anyhow::{Context, Result};
use nalgebra::{Matrix3, Point2, SVector, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use stucco_core::{Platform, Pose2, wrap_angle};
use stucco_mission::{
    BehaviourKind, EventKind, Inputs, MissionMode, Outputs, TaskSpec, TaskStatus, WallGeometry,
    WallName,
};
use stucco_runtime::Robot;
use stucco_runtime::{
    BadInput, Checkpoint, Checkpointer, EventLog, Mission, PLAN_FILE, RoomMap, Sink, SinkError,
    TaskTimes, read_checkpoint, windows_by_room, write_atomic,
};
use stucco_sim::{Layout, OpeningKind, WorldSpec};

/// What `stucco run` was asked to do with a task mission.
#[derive(Clone, Debug)]
pub struct TaskMissionJob {
    /// The mission file.
    pub mission: PathBuf,
    /// Seed of the first run, instead of the mission's.
    pub seed: Option<u64>,
    /// Runs, instead of the mission's.
    pub runs: Option<u64>,
    /// Where the report, the events, the map and the checkpoint go.
    pub out: Option<PathBuf>,
    /// Go on from the checkpoint in `out`.
    pub resume: bool,
    /// Stop after this much simulated time, as if the robot were switched
    /// off (the checkpoint keeps what was finished).
    pub stop_after_s: Option<f64>,
    /// Record each run to `run.mcap` in its folder.
    pub record: bool,
}

/// How well the filter's covariance covered its errors over a run, the
/// means taken on every control period.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FilterConsistency {
    /// Mean NEES of the position: 2 when the covariance is honest.
    pub position_nees: f64,
    /// Mean NEES of the heading: 1 when the covariance is honest.
    pub heading_nees: f64,
    /// RMS of the heading's standard deviation as the filter gave it, rad.
    pub heading_sigma_rms_rad: f64,
}

/// One task as the run left it.
#[derive(Clone, Debug, Serialize)]
pub struct TaskReport {
    /// Its name.
    pub name: String,
    /// How it ended.
    pub status: TaskStatus,
    /// Simulated seconds it took in this run (none if it did not run).
    pub seconds: Option<f64>,
}

/// A door the robot found, against the nearest true door.
#[derive(Clone, Debug, Serialize)]
pub struct DoorReport {
    /// The wall (`west`, `south`, `east`, `north`).
    pub wall: stucco_mission::WallName,
    /// Estimated centre along the wall, m.
    pub position_m: f64,
    /// Estimated width, m (none for a door given by the map).
    pub width_m: Option<f64>,
    /// Distance from the nearest true door's centre, m.
    pub error_m: f64,
}

/// A window the camera found, against the true window it overlaps.
#[derive(Clone, Debug, Serialize)]
pub struct WindowReport {
    /// The room (the world's name for it).
    pub room: String,
    /// The wall.
    pub wall: WallName,
    /// Its edges along the wall, m.
    pub along_m: [f64; 2],
    /// Its sill and head, m.
    pub sill_head_m: [f64; 2],
    /// Passes fused into it.
    pub observations: usize,
    /// Largest error of its four edges against the true window it overlaps
    /// (none: it overlaps no true window), m.
    pub edge_error_m: Option<f64>,
}

/// How well a wall pass held its standoff, measured on the true pose
/// against the true wall, from the pass's start to its end.
#[derive(Clone, Debug, Serialize)]
pub struct PassReport {
    /// The task.
    pub task: usize,
    /// The wall.
    pub wall: stucco_mission::WallName,
    /// The standoff asked for, m.
    pub standoff_m: f64,
    /// Mean of the true standoff's error, m.
    pub mean_error_m: f64,
    /// Its RMS, m.
    pub rms_error_m: f64,
    /// Its largest magnitude, m.
    pub max_error_m: f64,
    /// Control periods measured.
    pub samples: usize,
}

/// The rooms of `mission`'s floor plan none of `plastered` is, each with
/// its drawn floor and why; `status` is each of the mission's tasks' (a
/// room given up names its task's failure).
fn rooms_left(
    mission: &Mission,
    plastered: &[crate::plastering::RoomPlaster],
    status: &[TaskStatus],
) -> Vec<crate::plastering::RoomLeft> {
    let Some(plan) = mission.floor_plan() else {
        return Vec::new();
    };
    let start = mission
        .start
        .as_ref()
        .and_then(|s| s.room.as_deref())
        .and_then(|name| plan.room(name));
    let fits = mission.door_width_m();
    plan.rooms()
        .iter()
        .enumerate()
        .filter(|(_, r)| !plastered.iter().any(|p| p.room == r.name))
        .map(|(i, r)| crate::plastering::RoomLeft {
            room: r.name.clone(),
            floor_m2: r.size_m[0] * r.size_m[1],
            why: if start.map_or(plan.doors_of(i).next().is_none(), |s| {
                plan.route(s, i).is_none()
            }) {
                "no open door leads there".to_owned()
            } else if start.is_some_and(|s| plan.route_for(s, i, fits).is_none()) {
                format!(
                    "no door the robot fits through with its field leads there (it needs \
                     {fits:.2} m)"
                )
            } else if let Some((k, reason)) = status.iter().enumerate().find_map(|(k, s)| match s {
                TaskStatus::Failed { reason } if mission.task_room(k) == Some(&r.name) => {
                    Some((k, reason))
                }
                _ => None,
            }) {
                format!(
                    "given up: task {} ({}) failed: {reason}",
                    k + 1,
                    mission.tasks[k].name()
                )
            } else if mission.plaster_rooms().contains(&r.name) {
                "the job ended before it".to_owned()
            } else {
                "no plaster task".to_owned()
            },
        })
        .collect()
}

/// An opening the camera finds this near the floor is a door, m.
const DOOR_SILL_M: f64 = 0.1;
/// Every room's plan a run has plastered on (beside the checkpoint): a
/// resumed run scores the whole job, rooms done before the stop too.
const PLASTERED_FILE: &str = "plastered.json";

/// One `plaster` task's plan as kept in [`PLASTERED_FILE`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlasteredRoom {
    task: usize,
    /// The world's name of the room.
    room: String,
    plan: stucco_plan::Plan,
    /// Where the robot stood when the plan was first made.
    start: Pose2,
}

/// The report of one run (`DIR/report.json`).
#[derive(Clone, Debug, Serialize)]
pub struct MissionReport {
    /// `done`, `failed`, `aborted`, or `stopped` (by `--stop-after`).
    pub outcome: String,
    /// Why it failed.
    pub reason: Option<String>,
    /// Why it failed, typed (a task's failure: its `code` and details).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<stucco_mission::TaskFailure>,
    /// The mission's name.
    pub mission: String,
    /// The seed.
    pub seed: u64,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// The tasks.
    pub tasks: Vec<TaskReport>,
    /// The first task this run carried out (after a checkpoint).
    pub first_task: usize,
    /// RMS of the estimated position's error over the run, m.
    pub pose_rms_m: f64,
    /// Largest position error, m.
    pub pose_max_m: f64,
    /// RMS of the heading error, rad.
    pub heading_rms_rad: f64,
    /// How well the filter's covariance covered its errors over the run.
    pub consistency: Option<FilterConsistency>,
    /// Relative pose error over pairs of poses 1 m apart along the true
    /// path (none if the robot did not drive 1 m).
    pub rpe_1m: Option<stucco_nav::Rpe>,
    /// The floor plan's room the robot's frame is in at the end (missions
    /// with a plan).
    pub room: Option<String>,
    /// The room the robot truly stands in at the end.
    pub room_true: Option<String>,
    /// Each move of the robot's frame into the next room of the plan.
    pub room_changes: Vec<RoomChange>,
    /// The room's size as estimated at the end, m.
    pub room_m: [f64; 2],
    /// Its true size, m.
    pub room_true_m: [f64; 2],
    /// Its σ at the end, m.
    pub room_sigma_m: [f64; 2],
    /// Scans each wall (by index) was used in.
    pub walls_seen: Vec<usize>,
    /// The doors found or given.
    pub doors: Vec<DoorReport>,
    /// The wall passes.
    pub passes: Vec<PassReport>,
    /// The windows found by the camera.
    pub windows: Vec<WindowReport>,
    /// True windows of the room found (a reported window overlaps them).
    pub windows_found: usize,
    /// True windows in the room.
    pub windows_total: usize,
    /// Largest edge error over the windows found, m.
    pub window_edge_err_max_m: Option<f64>,
    /// Distance driven, m.
    pub path_length_m: f64,
    /// Times the supervisor stopped the robot.
    pub safety_stops: usize,
    /// Events written.
    pub events: usize,
    /// Every true plasterable wall area of the rooms the job names
    /// (openings and the bands left to the hand excepted) within the
    /// coat's tolerance, as a share of what is not blocked, % (plastering
    /// missions; none when nothing could be reached). What the robot did
    /// not plan counts as unreached.
    pub true_wall_coverage_pct: Option<f64>,
    /// The same for the ceilings, %.
    pub true_ceiling_coverage_pct: Option<f64>,
    /// Plasterable area left bare that the tool cannot physically reach
    /// for the true furniture and the rooms' shape, m² (from the truth,
    /// not the robot's belief; `plaster.truth.blockers` says what blocks
    /// it).
    pub blocked_m2: Option<f64>,
    /// The rest not within tolerance: bare, thin or thick where the tool
    /// could have sprayed, m².
    pub unreached_m2: Option<f64>,
    /// Plasterable wall area the plan reaches within the coat's tolerance,
    /// on the true walls, % (plastering missions): the plan's own reach,
    /// the truth's figures are `true_wall_coverage_pct`.
    pub wall_coverage_pct: Option<f64>,
    /// The same for the ceiling, %.
    pub ceiling_coverage_pct: Option<f64>,
    /// Plaster sprayed that landed in doors and windows, %.
    pub overspray_pct: Option<f64>,
    /// Coefficient of variation of the thickness over the plasterable
    /// area.
    pub thickness_cv: Option<f64>,
    /// Plasterable area thicker than the tolerance allows (sprayed twice),
    /// %.
    pub double_sprayed_pct: Option<f64>,
    /// Time the `plaster` tasks took, over every part of the run (a
    /// resumed run counts the parts before it), s.
    pub mission_time_s: Option<f64>,
    /// The least it could take: area at the tool's rate plus straight
    /// travel between stations at top speed, s.
    pub mission_time_lower_bound_s: Option<f64>,
    /// The plastering's details.
    pub plaster: Option<crate::plastering::PlasterReport>,
}

/// The robot's frame moved into the next room of the floor plan.
#[derive(Clone, Debug, Serialize)]
pub struct RoomChange {
    /// When, simulated s.
    pub stamp_s: f64,
    /// Through this door of the plan.
    pub door: usize,
    /// The room the frame is in after it (unchanged when the move was
    /// refused).
    pub room: Option<String>,
    /// The room the robot truly stood in then.
    pub room_true: Option<String>,
}

/// The report of `--runs N` (`DIR/report.json`): the runs and their sum.
#[derive(Clone, Debug, Serialize)]
pub struct MissionSummary {
    /// `done` when every run was.
    pub outcome: String,
    /// The first failing run's reason.
    pub reason: Option<String>,
    /// The mission's name.
    pub mission: String,
    /// Seed of the first run.
    pub seed: u64,
    /// Simulated seconds, all runs.
    pub sim_seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Simulated seconds per wall-clock second, all runs together.
    pub real_time_factor: f64,
    /// Runs done.
    pub done: usize,
    /// Each run.
    pub runs: Vec<MissionReport>,
}

/// Runs the task mission of `job`; `progress` hears the simulated time and
/// the task under way of the first run.
pub fn run_task_mission(
    job: &TaskMissionJob,
    progress: &(dyn Fn(f64, &str) + Sync),
) -> Result<MissionSummary> {
    let mission = Mission::load(&job.mission)?;
    if mission.tasks.is_empty() {
        return Err(BadInput(format!("{}: no [[task]] in it", job.mission.display())).into());
    }
    let world = crate::sim_robot::load_world(&mission, &job.mission)?;
    let runs = job.runs.unwrap_or(mission.runs);
    if runs == 0 {
        return Err(BadInput(format!("{}: runs: at least one", job.mission.display())).into());
    }
    if job.record && job.out.is_none() {
        return Err(BadInput("--record writes DIR/run.mcap: it needs --out DIR".to_owned()).into());
    }
    if job.resume && (job.out.is_none() || runs != 1) {
        return Err(BadInput(
            "--resume goes on from DIR/checkpoint.json: it needs --out DIR and one run".to_owned(),
        )
        .into());
    }
    let mut seed = job.seed.unwrap_or(mission.seed);
    let mut resume = None;
    if job.resume
        && let Some(dir) = &job.out
    {
        let cp = read_checkpoint(&dir.join(stucco_runtime::CHECKPOINT_FILE), &mission)?;
        seed = job.seed.unwrap_or(cp.seed);
        resume = Some(cp);
    }
    let setup = Setup {
        mission: &mission,
        mission_path: &job.mission,
        record: job.record,
        world: &world,
        resume: resume.as_ref(),
        stop_after: job.stop_after_s,
    };
    let t0 = Instant::now();
    let reports: Vec<MissionReport> = (0..runs)
        .into_par_iter()
        .map(|k| {
            let out = job.out.as_ref().map(|d| {
                if runs == 1 {
                    d.clone()
                } else {
                    d.join(format!("seed-{}", seed + k))
                }
            });
            let quiet = |_: f64, _: &str| {};
            let hear: &(dyn Fn(f64, &str) + Sync) = if k == 0 { progress } else { &quiet };
            run_once(&setup, seed + k, out.as_deref(), hear)
        })
        .collect::<Result<_>>()?;
    let wall = t0.elapsed().as_secs_f64();
    let sim: f64 = reports.iter().map(|r| r.sim_seconds).sum();
    let done = reports.iter().filter(|r| r.outcome == "done").count();
    let first_bad = reports.iter().find(|r| r.outcome != "done");
    let summary = MissionSummary {
        outcome: first_bad.map_or("done", |r| r.outcome.as_str()).to_owned(),
        reason: first_bad.and_then(|r| r.reason.clone()),
        mission: mission.name.clone(),
        seed,
        sim_seconds: sim,
        wall_seconds: wall,
        real_time_factor: sim / wall.max(1e-9),
        done,
        runs: reports,
    };
    if runs > 1
        && let Some(dir) = &job.out
    {
        write_atomic(
            &dir.join("report.json"),
            serde_json::to_string_pretty(&summary)?.as_bytes(),
        )?;
    }
    Ok(summary)
}

/// What every run of a job shares.
pub(crate) struct Setup<'a> {
    pub(crate) mission: &'a Mission,
    /// Where the mission file is.
    pub(crate) mission_path: &'a Path,
    /// Record each run to `run.mcap`.
    pub(crate) record: bool,
    pub(crate) world: &'a WorldSpec,
    pub(crate) resume: Option<&'a Checkpoint>,
    pub(crate) stop_after: Option<f64>,
}

/// What a simulated run is scored on: the truth read beside the robot's
/// estimate (the trace, the passes, the plans and the rooms), and the
/// progress heard. It reads the simulator through the robot's platform; nothing
/// of it reaches the executive.
struct SimRun<'a> {
    layout: Arc<Layout>,
    out: Option<&'a Path>,
    resume: Option<&'a Checkpoint>,
    /// The true frame of the room the robot's frame is in.
    frame: RoomFrame,
    trace: Trace,
    times: TaskTimes,
    passes: std::collections::BTreeMap<usize, (WallName, f64, Vec<f64>)>,
    room_changes: Vec<RoomChange>,
    /// Each plaster task's plan, the true frame of its room, and where the
    /// robot stood when it was first made.
    plans: std::collections::BTreeMap<usize, (RoomFrame, stucco_plan::Plan, Pose2)>,
    progress: &'a (dyn Fn(f64, &str) + Sync),
}

impl SimRun<'_> {
    /// The true pose (world frame).
    fn truth<P: Simulated>(robot: &Robot<P>) -> Pose2 {
        robot.platform().true_pose()
    }
}

impl<P: Simulated> Sink<P> for SimRun<'_> {
    fn ticked(
        &mut self,
        robot: &Robot<P>,
        inputs: &Inputs<'_>,
        out: &Outputs,
    ) -> std::result::Result<(), SinkError> {
        self.times.hear(out);
        // The plan scored is each task's last one (a survey makes it
        // again, a window the tool's camera finds is kept out of it, a
        // station no way leads to is left out of it); a resumed run's, the
        // one it took up.
        let made = out.events.iter().find_map(|e| match e.kind {
            EventKind::PlanMade { task, .. }
            | EventKind::WindowFound { task, .. }
            | EventKind::StationGivenUp { task, .. }
            | EventKind::StationDeferred { task, .. } => Some(task),
            _ => None,
        });
        let taken_up = self
            .resume
            .and_then(|cp| cp.progress.plaster.as_ref())
            .map(|p| p.task)
            .filter(|t| !self.plans.contains_key(t));
        if let (Some(task), Some(plan)) = (made.or(taken_up), robot.executive().plaster_plan()) {
            let start = self.plans.get(&task).map_or(inputs.estimate.pose, |p| p.2);
            self.plans
                .insert(task, (self.frame.clone(), plan.clone(), start));
            if let Some(dir) = self.out {
                let kept: Vec<PlasteredRoom> = self
                    .plans
                    .iter()
                    .map(|(&task, (f, plan, start))| PlasteredRoom {
                        task,
                        room: f.name.clone(),
                        plan: plan.clone(),
                        start: *start,
                    })
                    .collect();
                write_atomic(
                    &dir.join(PLASTERED_FILE),
                    serde_json::to_string(&kept)?.as_bytes(),
                )?;
            }
        }
        Ok(())
    }

    fn entered(
        &mut self,
        robot: &Robot<P>,
        door: usize,
        _moved: &std::result::Result<(), String>,
    ) -> std::result::Result<(), SinkError> {
        let perception = robot.perception();
        self.frame.follow(&self.layout, perception.room_name())?;
        self.room_changes.push(RoomChange {
            stamp_s: robot.now().as_secs_f64(),
            door,
            room: perception.room_name().map(str::to_owned),
            room_true: true_room(&self.layout, &Self::truth(robot)),
        });
        Ok(())
    }

    fn stepped(&mut self, robot: &Robot<P>) -> std::result::Result<(), SinkError> {
        let exec = robot.executive();
        let truth_w = Self::truth(robot);
        let truth = self.frame.to_room(&truth_w);
        // A pass's standoff, on the truth, from where the pass starts.
        if let (
            Some((task, _)),
            Some(&BehaviourKind::FollowWall {
                wall, standoff_m, ..
            }),
        ) = (exec.current_task(), exec.current_behaviour())
            && let TaskSpec::FollowWall { from_m, to_m, .. } = exec.tasks()[task]
            && let Some(g) = WallGeometry::of(wall, self.frame.size_m)
        {
            let p = truth.position().coords;
            let at = g.position(&p);
            if (to_m > from_m && at >= from_m) || (to_m < from_m && at <= from_m) {
                self.passes
                    .entry(task)
                    .or_insert_with(|| (wall, standoff_m, Vec::new()))
                    .2
                    .push(g.distance(&p) - standoff_m);
            }
        }
        // The trace in the world frame: the estimate placed by the true
        // corner of the room it is kept in.
        let est_w = self.frame.to_world(&robot.estimate().pose);
        let period = robot.periods() - 1;
        if period.is_multiple_of(5) {
            self.trace.push(&est_w, &truth_w);
        }
        self.trace.errors(&est_w, &truth_w, robot.pose_covariance());
        if robot.periods().is_multiple_of(50) {
            let task = exec.current_task().map_or("", |t| t.1);
            (self.progress)(robot.now().as_secs_f64(), task);
        }
        Ok(())
    }
}

/// A sink's failure as the job's.
fn sunk(e: SinkError) -> anyhow::Error {
    anyhow::Error::from_boxed(e)
}

/// One run of the mission with `seed`, writing into `out`.
fn run_once(
    setup: &Setup,
    seed: u64,
    out: Option<&Path>,
    progress: &(dyn Fn(f64, &str) + Sync),
) -> Result<MissionReport> {
    // A run is cut at a control period's end (`--stop-after`): the world is
    // written when it stops, not beside every checkpoint.
    let mut job = SimJob::start(setup, seed, out, progress, true, false, |world| {
        Ok((mission_simulator(setup.mission, world, seed), robot_spec()))
    })?;
    let limit = setup.mission.time_limit_s;
    let ending = loop {
        let now = job.robot.now();
        job.tick(&[], None)?;
        if job.robot.executive().mode().is_final() {
            break Ending::Over;
        }
        if now.as_secs_f64() > limit {
            break Ending::TimedOut(format!("time limit: {limit} s of simulated time"));
        }
        if setup.stop_after.is_some_and(|t| now.as_secs_f64() >= t) {
            break Ending::Stopped;
        }
        job.act(None)?;
    };
    job.finish(ending)
}

/// How a job's loop ended.
pub(crate) enum Ending {
    /// The mission came to its end (done, failed, aborted).
    Over,
    /// It ran out of time.
    TimedOut(String),
    /// It was stopped as asked.
    Stopped,
}

/// A mission's job on a simulated robot (in this process or served over
/// zenoh): the robot and every sink its loop feeds (events, checkpoints,
/// the world kept beside them, the recording, the scoring), stepped by
/// `stucco run` as fast as it goes and by `stucco robot` paced to the
/// clock.
pub(crate) struct SimJob<'a, P: Simulated> {
    setup: &'a Setup<'a>,
    seed: u64,
    out: Option<&'a Path>,
    t0: Instant,
    layout: Arc<Layout>,
    pub(crate) robot: Robot<P>,
    first_task: usize,
    sinks: JobSinks<'a>,
}

/// Where a job's loop writes: events, checkpoints, the world kept beside
/// them, the recording, the scoring.
struct JobSinks<'a> {
    events: EventLog<Box<dyn Write + Send>>,
    checkpoints: Option<Checkpointer>,
    keeper: Option<WorldKeeper>,
    recording: Option<Recording>,
    run: SimRun<'a>,
}

impl<'a> JobSinks<'a> {
    /// Every sink, then `extra`.
    fn all<'s, P: Simulated>(
        &'s mut self,
        extra: Option<&'s mut (dyn Sink<P> + 's)>,
    ) -> Vec<&'s mut (dyn Sink<P> + 's)> {
        let mut sinks: Vec<&mut dyn Sink<P>> = vec![&mut self.events];
        if let Some(c) = self.checkpoints.as_mut() {
            sinks.push(c);
        }
        if let Some(k) = self.keeper.as_mut() {
            sinks.push(k);
        }
        if let Some(r) = self.recording.as_mut() {
            sinks.push(r);
        }
        sinks.push(&mut self.run);
        sinks.extend(extra);
        sinks
    }
}

impl<'a, P: Simulated> SimJob<'a, P> {
    /// The job of `setup` with `seed` writing into `out`: the robot on the
    /// platform `platform` makes of its world (where a checkpoint left it
    /// when resuming a simulator in this process), with what the platform
    /// carries, its executive `unattended` or not, the sinks opened. With
    /// `keep_world` the simulated world is written beside every checkpoint
    /// (a process that may be killed; 2 MB a checkpoint for a plastered
    /// room), else when the job stops.
    pub(crate) fn start(
        setup: &'a Setup<'a>,
        seed: u64,
        out: Option<&'a Path>,
        progress: &'a (dyn Fn(f64, &str) + Sync),
        unattended: bool,
        keep_world: bool,
        platform: impl FnOnce(&WorldSpec) -> Result<(P, stucco_core::RobotSpec)>,
    ) -> Result<Self> {
        let Setup {
            mission,
            mission_path,
            record,
            world,
            resume,
            ..
        } = *setup;
        let t0 = Instant::now();
        let layout = Arc::new(Layout::of(world));
        let mut world = world.clone();
        // A resumed run goes on in the world as it was left: the robot where
        // it stopped, the plaster on the walls (a served simulator keeps its
        // own).
        let kept_world = match (resume, out) {
            (Some(_), Some(dir)) if P::IN_PROCESS => {
                Some(WorldState::load(&dir.join(WORLD_FILE)).map_err(|e| {
                    BadInput(format!(
                        "{}: the simulated world beside the checkpoint: {e:#}",
                        dir.join(WORLD_FILE).display()
                    ))
                })?)
            }
            _ => None,
        };
        if let Some(w) = &kept_world {
            world.robot.at = [w.robot.x, w.robot.y];
            world.robot.heading_deg = w.robot.theta.to_degrees();
        }
        let (platform, spec) = platform(&world)?;
        let (mut robot, frame) = mission_robot(
            mission,
            &world,
            resume.map(|cp| &cp.map),
            unattended,
            platform,
            &spec,
        )?;
        if let Some(w) = &kept_world {
            robot.platform_mut().restore(w);
        }
        robot.perception_mut().discover_doors(true);
        if let Some(cp) = resume {
            let exec = robot.executive_mut();
            if cp.progress.plaster.is_some()
                && let Some(dir) = out
            {
                let path = dir.join(PLAN_FILE);
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    BadInput(format!(
                        "{}: the plan the checkpoint was carrying out: {e}",
                        path.display()
                    ))
                })?;
                let plan: stucco_plan::Plan = serde_json::from_str(&text)
                    .map_err(|e| BadInput(format!("{}: not a plan: {e}", path.display())))?;
                exec.resume_plan(plan);
            }
            exec.resume_from(&cp.progress)
                .map_err(|e| BadInput(format!("the checkpoint does not fit the mission: {e}")))?;
        }
        let tasks = robot.executive().tasks().len();
        let first_task = robot
            .executive()
            .status()
            .iter()
            .position(|s| *s == TaskStatus::Pending)
            .unwrap_or(tasks);
        let events = match out {
            Some(dir) => {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("cannot create {}", dir.display()))?;
                let path = dir.join("events.jsonl");
                let f = std::fs::OpenOptions::new()
                    .create(true)
                    .append(resume.is_some())
                    .write(true)
                    .truncate(resume.is_none())
                    .open(&path)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                EventLog::new(Box::new(std::io::BufWriter::new(f)) as Box<dyn Write + Send>)
            }
            None => EventLog::new(Box::new(std::io::sink()) as Box<dyn Write + Send>),
        };
        let checkpoints = match out {
            Some(dir) => Some(Checkpointer::new(dir, mission, seed, resume)?),
            None => None,
        };
        let recording = match (out, record) {
            (Some(dir), true) => Some(Recording::new(
                Recorder::create(
                    &dir.join("run.mcap"),
                    &RecordedMission {
                        path: mission_path.display().to_string(),
                        text: mission.text().to_owned(),
                        plan_text: mission.plan_text().map(str::to_owned),
                        seed,
                        resumed_from: resume.map(|cp| cp.progress.clone()),
                    },
                )?,
                layout.clone(),
                frame.clone(),
            )),
            _ => None,
        };
        let keeper = out.filter(|_| keep_world).map(WorldKeeper::new);
        let mut plans = std::collections::BTreeMap::new();
        if let (Some(_), Some(dir)) = (resume, out)
            && dir.join(PLASTERED_FILE).exists()
        {
            let path = dir.join(PLASTERED_FILE);
            let text = std::fs::read_to_string(&path)
                .map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
            let kept: Vec<PlasteredRoom> = serde_json::from_str(&text).map_err(|e| {
                BadInput(format!("{}: not the rooms plastered: {e}", path.display()))
            })?;
            for r in kept {
                plans.insert(
                    r.task,
                    (RoomFrame::named(&layout, &r.room)?, r.plan, r.start),
                );
            }
        }
        let run = SimRun {
            layout: layout.clone(),
            out,
            resume,
            frame,
            trace: Trace::default(),
            times: TaskTimes::new(
                tasks,
                resume.map(|cp| cp.task_seconds.clone()).unwrap_or_default(),
            ),
            passes: std::collections::BTreeMap::new(),
            room_changes: Vec::new(),
            plans,
            progress,
        };
        Ok(SimJob {
            setup,
            seed,
            out,
            t0,
            layout,
            robot,
            first_task,
            sinks: JobSinks {
                events,
                checkpoints,
                keeper,
                recording,
                run,
            },
        })
    }

    /// [`Robot::tick`](stucco_runtime::Robot::tick) with the job's sinks
    /// and `extra`.
    pub(crate) fn tick<'s>(
        &'s mut self,
        telecommands: &[stucco_core::Telecommand],
        extra: Option<&'s mut (dyn Sink<P> + 's)>,
    ) -> Result<Outputs> {
        let mut sinks = self.sinks.all(extra);
        self.robot
            .tick(telecommands, false, &mut sinks)
            .map_err(sunk)
    }

    /// [`Robot::act`](stucco_runtime::Robot::act) with the job's sinks and
    /// `extra`.
    pub(crate) fn act<'s>(&'s mut self, extra: Option<&'s mut (dyn Sink<P> + 's)>) -> Result<()> {
        let mut sinks = self.sinks.all(extra);
        self.robot.act(&mut sinks).map_err(sunk)
    }

    /// Ends the job as `ending` says: the last checkpoint and the world
    /// beside it written, the run scored against the truth, its report
    /// (and map, and coats) written into the job's folder.
    pub(crate) fn finish(self, ending: Ending) -> Result<MissionReport> {
        let SimJob {
            setup,
            seed,
            out,
            t0,
            layout,
            robot,
            first_task,
            sinks:
                JobSinks {
                    events,
                    mut checkpoints,
                    recording,
                    run,
                    ..
                },
        } = self;
        let Setup {
            mission,
            resume,
            world: start_world,
            ..
        } = *setup;
        let (events_written, safety_stops) = (events.events(), events.safety_stops());
        events.finish()?;
        if let Some(r) = recording {
            r.finish()?;
        }
        let SimRun {
            frame,
            trace,
            times,
            passes,
            room_changes,
            plans,
            ..
        } = run;
        let task_spent = times.spent(robot.now());
        if let Some(c) = checkpoints.as_mut() {
            c.save(&robot).map_err(sunk)?;
        }
        // The world as the job leaves it, read once (a served simulator's
        // over the link): kept beside the checkpoint, and scored.
        let world = match out {
            Some(dir) => {
                let world = robot.platform().world_state()?;
                world.save(&dir.join(WORLD_FILE))?;
                Some(world)
            }
            None => None,
        };
        let exec = robot.executive();
        let est = robot.perception().mission_estimate();
        let over = matches!(ending, Ending::Over);
        let (outcome, reason) = match (exec.mode(), ending) {
            (_, Ending::Stopped) => (
                "stopped",
                Some(format!(
                    "stopped after {:.1} s as asked",
                    robot.now().as_secs_f64()
                )),
            ),
            (_, Ending::TimedOut(r)) => ("failed", Some(r)),
            (MissionMode::Done, Ending::Over) => ("done", None),
            (MissionMode::Aborted, Ending::Over) => {
                ("aborted", Some("aborted by the operator".to_owned()))
            }
            (MissionMode::Failed { reason }, Ending::Over) => ("failed", Some(reason.clone())),
            (other, Ending::Over) => ("failed", Some(format!("stopped while {other:?}"))),
        };
        let true_doors: Vec<Point2<f64>> = layout
            .openings
            .iter()
            .filter(|o| o.kind == OpeningKind::OpenDoor)
            .map(|o| Point2::from((o.edges[0].coords + o.edges[1].coords) / 2.0))
            .map(|c| Point2::new(c.x - frame.origin[0], c.y - frame.origin[1]))
            .collect();
        let doors = est
            .doors
            .iter()
            .filter_map(|d| {
                let g = WallGeometry::in_room(&est, d.wall)?;
                let c = Point2::from(g.point(d.position_m, 0.0));
                Some(DoorReport {
                    wall: d.wall,
                    position_m: d.position_m,
                    width_m: d.width_m,
                    error_m: true_doors
                        .iter()
                        .map(|t| (t - c).norm())
                        .fold(f64::INFINITY, f64::min),
                })
            })
            .collect();
        // Every room the robot has been in, each in its true frame.
        let mut windows = Vec::new();
        let (mut windows_found, mut windows_total) = (0, 0);
        for (room, found) in windows_by_room(robot.perception(), resume) {
            let room_frame = match room {
                Some(name) => RoomFrame::named(&layout, name)?,
                None => frame.clone(),
            };
            let (reports, hit, total) = score_windows(&layout, &room_frame, found);
            windows.extend(reports);
            windows_found += hit;
            windows_total += total;
        }
        let window_edge_err_max_m = windows
            .iter()
            .filter_map(|w| w.edge_error_m)
            .reduce(f64::max);
        let rooms: Vec<(&RoomFrame, &stucco_plan::Plan)> =
            plans.values().map(|(f, p, _)| (f, p)).collect();
        // The plaster scored and drawn, from the simulator in this process
        // or the served one's world.
        let scored = if plans.is_empty() {
            None
        } else {
            Some(robot.platform().with_plaster(world.as_ref(), |sim| {
                if let Some(dir) = out {
                    for (frame, plan, _) in plans.values() {
                        let prefix = if plans.len() > 1 {
                            format!("{}-", frame.name)
                        } else {
                            String::new()
                        };
                        crate::plastering::draw_coats(
                            dir, &prefix, &layout, frame, sim, &plan.tool,
                        )?;
                    }
                }
                Ok(crate::plastering::score_run(sim, &layout, &rooms))
            })?)
        };
        // Every true surface of the rooms the job names, whatever was
        // planned: what was not is bare or blocked, never left out.
        let start = Pose2::new(
            start_world.robot.at[0],
            start_world.robot.at[1],
            start_world.robot.heading_deg.to_radians(),
        );
        let named = job_rooms(
            mission,
            &layout,
            &start,
            plans.values().map(|(f, _, _)| f.name.clone()),
        );
        let truth = match &mission.spray {
            Some(tool) if !named.is_empty() => {
                Some(robot.platform().with_plaster(world.as_ref(), |sim| {
                    Ok(crate::plastering::TruthReport::of(
                        sim,
                        named,
                        &start,
                        tool,
                        &robot_spec().vehicle,
                    ))
                })?)
            }
            _ => None,
        };
        let plastered = scored.map(|(score, each)| {
            let top = robot_spec().vehicle.max_speed_mps;
            // The plastering time over every part of the run (a task stopped
            // under way: so far).
            let seconds = plans
                .keys()
                .filter_map(|t| task_spent.get(t).copied())
                .reduce(|a, b| a + b);
            let bound: f64 = plans
                .values()
                .map(|(_, plan, start)| crate::plastering::time_lower_bound(plan, start, top))
                .sum();
            let rooms: Vec<crate::plastering::RoomPlaster> = plans
                .iter()
                .zip(each)
                .map(|((&task, (frame, plan, _)), surfaces)| {
                    let predicted = stucco_plan::predicted_score(plan);
                    crate::plastering::RoomPlaster {
                        room: frame.name.clone(),
                        task,
                        stations: plan.stations.len(),
                        unreachable_m2: plan.unreachable_m2(),
                        surfaces,
                        predicted: crate::plastering::PredictedScores {
                            wall_coverage_pct: predicted.wall_coverage_pct,
                            ceiling_coverage_pct: predicted.ceiling_coverage_pct,
                            thickness_cv: predicted.thickness_cv,
                        },
                    }
                })
                .collect();
            (score, rooms, seconds, bound)
        });
        let wall = t0.elapsed().as_secs_f64();
        let sim = robot.now().as_secs_f64();
        let n = trace.n.max(1) as f64;
        let report = MissionReport {
            outcome: outcome.to_owned(),
            reason,
            failure: exec.failure().cloned().filter(|_| over),
            mission: mission.name.clone(),
            seed,
            sim_seconds: sim,
            wall_seconds: wall,
            real_time_factor: sim / wall.max(1e-9),
            tasks: exec
                .tasks()
                .iter()
                .zip(exec.status())
                .enumerate()
                .map(|(k, (t, s))| TaskReport {
                    name: t.name().to_owned(),
                    status: s.clone(),
                    seconds: times.this_part().get(k).copied().flatten(),
                })
                .collect(),
            first_task,
            pose_rms_m: (trace.pos2 / n).sqrt(),
            pose_max_m: trace.pos_max,
            heading_rms_rad: (trace.head2 / n).sqrt(),
            consistency: trace.consistency.report(),
            rpe_1m: stucco_nav::relative_pose_error(
                &trace.poses.0,
                &trace.poses.1,
                stucco_nav::Pairs::Distance(1.0),
            ),
            room: robot.perception().room_name().map(str::to_owned),
            room_true: true_room(&layout, &SimRun::truth(&robot)),
            room_changes,
            room_m: est.room_m,
            room_true_m: frame.size_m,
            room_sigma_m: est.room_sigma_m,
            walls_seen: est.walls_seen.clone(),
            doors,
            passes: passes
                .into_iter()
                .map(|(task, (wall, standoff_m, errs))| {
                    let n = errs.len().max(1) as f64;
                    PassReport {
                        task,
                        wall,
                        standoff_m,
                        mean_error_m: errs.iter().sum::<f64>() / n,
                        rms_error_m: (errs.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
                        max_error_m: errs.iter().fold(0.0, |m: f64, e| m.max(e.abs())),
                        samples: errs.len(),
                    }
                })
                .collect(),
            windows,
            windows_found,
            windows_total,
            window_edge_err_max_m,
            path_length_m: trace.length,
            safety_stops,
            events: events_written,
            true_wall_coverage_pct: truth.as_ref().and_then(|t| t.walls.coverage_pct()),
            true_ceiling_coverage_pct: truth.as_ref().and_then(|t| t.ceilings.coverage_pct()),
            blocked_m2: truth
                .as_ref()
                .map(|t| t.walls.blocked_m2 + t.ceilings.blocked_m2),
            unreached_m2: truth
                .as_ref()
                .map(|t| t.walls.unreached_m2 + t.ceilings.unreached_m2),
            wall_coverage_pct: plastered.as_ref().map(|p| p.0.wall_coverage_pct),
            ceiling_coverage_pct: plastered.as_ref().map(|p| p.0.ceiling_coverage_pct),
            overspray_pct: plastered.as_ref().map(|p| p.0.overspray_pct),
            thickness_cv: plastered.as_ref().map(|p| p.0.thickness_cv),
            double_sprayed_pct: plastered.as_ref().map(|p| p.0.over_pct),
            mission_time_s: plastered.as_ref().and_then(|p| p.2),
            mission_time_lower_bound_s: plastered.as_ref().map(|p| p.3),
            plaster: plastered.map(|(score, rooms, _, _)| {
                let rooms_left = rooms_left(mission, &rooms, &exec.progress().status);
                crate::plastering::PlasterReport {
                    stations: rooms.iter().map(|r| r.stations).sum(),
                    unreachable_m2: rooms.iter().map(|r| r.unreachable_m2).sum(),
                    sprayed_l: score.sprayed_l,
                    rooms,
                    rooms_left,
                    truth: truth.clone(),
                }
            }),
        };
        if let Some(dir) = out {
            write_atomic(
                &dir.join("report.json"),
                serde_json::to_string_pretty(&report)?.as_bytes(),
            )?;
            draw_run(&dir.join("map.svg"), &layout, frame.origin, &trace, &est)?;
        }
        Ok(report)
    }
}

/// The estimated and true trajectories (world frame) and their errors.
#[derive(Default)]
struct Trace {
    estimated: Vec<[f64; 2]>,
    truth: Vec<[f64; 2]>,
    /// The poses behind them, for the relative pose error.
    poses: (Vec<Pose2>, Vec<Pose2>),
    pos2: f64,
    head2: f64,
    pos_max: f64,
    consistency: Consistency,
    n: usize,
    length: f64,
    last: Option<Pose2>,
}

/// How well a filter's covariance covers its errors: the mean normalized
/// estimation error squared (NEES) of its position and of its heading, and
/// the RMS of the heading's σ. A filter whose covariance is honest has
/// mean NEES 2 for the position (two degrees of freedom) and 1 for the
/// heading; one much larger believes itself better than it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Consistency {
    position: f64,
    heading: f64,
    heading_var: f64,
    n: usize,
}

impl Consistency {
    /// Takes one error `(x, y, θ)` with the filter's covariance of it;
    /// a covariance that cannot be inverted is left out.
    fn add(&mut self, error: &Vector3<f64>, cov: &Matrix3<f64>) {
        let xy = cov.fixed_view::<2, 2>(0, 0).into_owned();
        let (Some(inv), true) = (xy.try_inverse(), cov[(2, 2)] > 0.0) else {
            return;
        };
        let d = error.fixed_rows::<2>(0).into_owned();
        self.position += (d.transpose() * inv * d)[(0, 0)];
        self.heading += error.z * error.z / cov[(2, 2)];
        self.heading_var += cov[(2, 2)];
        self.n += 1;
    }

    /// The figures for the report (`None` with no sample).
    fn report(&self) -> Option<FilterConsistency> {
        let n = (self.n > 0).then_some(self.n as f64)?;
        Some(FilterConsistency {
            position_nees: self.position / n,
            heading_nees: self.heading / n,
            heading_sigma_rms_rad: (self.heading_var / n).sqrt(),
        })
    }
}

impl Trace {
    fn push(&mut self, est: &Pose2, truth: &Pose2) {
        self.estimated.push([est.x, est.y]);
        self.truth.push([truth.x, truth.y]);
        self.poses.0.push(*est);
        self.poses.1.push(*truth);
    }

    /// Takes the error of `est` against `truth`, with the covariance the
    /// filter gives `est` (the room frame is the world's, shifted).
    fn errors(&mut self, est: &Pose2, truth: &Pose2, cov: &Matrix3<f64>) {
        let d = est.position() - truth.position();
        let e = d.norm();
        self.pos2 += e * e;
        self.pos_max = self.pos_max.max(e);
        let h = wrap_angle(est.theta - truth.theta);
        self.head2 += h * h;
        self.consistency.add(&Vector3::new(d.x, d.y, h), cov);
        self.n += 1;
        if let Some(l) = self.last {
            self.length += (truth.position() - l.position()).norm();
        }
        self.last = Some(*truth);
    }
}

/// The map of a run: the true walls, the room as estimated, the true
/// (blue) and estimated (red) paths, the doors found.
fn draw_run(
    path: &Path,
    layout: &Layout,
    origin: [f64; 2],
    trace: &Trace,
    est: &stucco_mission::Estimate,
) -> Result<()> {
    let walls: Vec<PlanSegment> = layout
        .walls
        .iter()
        .map(|w| {
            (
                (w.a.x - origin[0], w.a.y - origin[1]),
                (w.b.x - origin[0], w.b.y - origin[1]),
                false,
            )
        })
        .collect();
    let [xs, ys] = est.room_m;
    let room = [(0.0, 0.0), (xs, 0.0), (xs, ys), (0.0, ys), (0.0, 0.0)];
    let xy = |p: &[[f64; 2]]| {
        p.iter()
            .map(|q| (q[0] - origin[0], q[1] - origin[1]))
            .collect::<Vec<_>>()
    };
    let (truth, estimated) = (xy(&trace.truth), xy(&trace.estimated));
    let doors: Vec<(f64, f64)> = est
        .doors
        .iter()
        .filter_map(|d| {
            let c = WallGeometry::in_room(est, d.wall)?.point(d.position_m, 0.0);
            Some((c.x, c.y))
        })
        .collect();
    draw_plan(
        path,
        "stucco run: true walls (black), room estimated (green), true path (blue), estimated path (red), doors found (red dots)",
        &walls,
        &[
            PlanPath {
                points: &room,
                color: plotters::style::GREEN,
            },
            PlanPath {
                points: &truth,
                color: plotters::style::BLUE,
            },
            PlanPath {
                points: &estimated,
                color: plotters::style::RED,
            },
        ],
        &doors,
    )
}

/// The robot of `mission` on `platform` (carrying what `spec` says), put
/// where `world` says: its filter started as `[start]` says, or from the
/// map a checkpoint kept, its executive `unattended` or not; and the true
/// frame of the room it starts in.
pub(crate) fn mission_robot<P: Platform>(
    mission: &Mission,
    world: &WorldSpec,
    resume: Option<&RoomMap>,
    unattended: bool,
    platform: P,
    spec: &stucco_core::RobotSpec,
) -> Result<(Robot<P>, RoomFrame)> {
    let known = mission
        .start
        .as_ref()
        .ok_or_else(|| BadInput(format!("mission {:?}: no [start]", mission.name)))?;
    let (size, plan_room) = mission
        .start_room()
        .ok_or_else(|| BadInput(format!("mission {:?}: no room to start in", mission.name)))?;
    let layout = Layout::of(world);
    let at = Pose2::new(
        world.robot.at[0],
        world.robot.at[1],
        world.robot.heading_deg.to_radians(),
    );
    let frame = match (resume.and_then(|m| m.room.as_deref()), plan_room) {
        (Some(name), _) => RoomFrame::named(&layout, name)?,
        (None, Some(room)) => {
            let frame = RoomFrame::of(&layout, &at)?;
            let name = mission.rooms[room].name.as_str();
            if frame.name != name {
                return Err(BadInput(format!(
                    "[start] room: the robot stands in {:?}, not {name:?}",
                    frame.name
                ))
                .into());
            }
            frame
        }
        (None, None) => RoomFrame::of(&layout, &at)?,
    };
    let (x0, size_sigma) = match resume {
        Some(m) => (
            SVector::<f64, 5>::new(m.pose.x, m.pose.y, m.pose.theta, m.room_m[0], m.room_m[1]),
            m.room_sigma_m,
        ),
        // Where it was put, off by a known amount, the room as planned.
        None => (
            known.filter_start(&frame.to_room(&at), size),
            [known.room_sigma_m; 2],
        ),
    };
    let exec = mission.executive(spec, unattended);
    let mut robot = robot_on(platform, spec, x0, size_sigma, exec)?;
    let nav = robot.perception_mut();
    let room = mission_room(mission, resume)?;
    // A room that is not a rectangle is kept in its drawing's polygon.
    if let (Some(plan), Some(room)) = (mission.floor_plan(), room) {
        let outline = plan
            .rooms()
            .get(room)
            .map(|r| r.outline())
            .unwrap_or_default();
        nav.keep_room_drawn(&outline, known.room_sigma_m)
            .map_err(|e| anyhow::anyhow!("the start room's drawing: {e}"))?;
    }
    // The doors it knew, before the plan's (those it holds are not added
    // twice).
    for d in resume.iter().flat_map(|m| &m.doors) {
        nav.add_known_door(d);
    }
    for (wall, w) in resume.iter().flat_map(|m| &m.windows) {
        nav.add_known_window(*wall, *w);
    }
    if let (Some(plan), Some(room)) = (mission.floor_plan(), room) {
        // Scoring follows the robot into each room by its name.
        for r in plan.rooms() {
            RoomFrame::named(&layout, &r.name)?;
        }
        nav.follow_plan(plan, room, known.room_sigma_m);
    }
    Ok((robot, frame))
}

/// The plan's room the robot is in at the start (or was in at a
/// checkpoint), when the mission has a plan.
pub(crate) fn mission_room(mission: &Mission, resume: Option<&RoomMap>) -> Result<Option<usize>> {
    let Some(plan) = mission.floor_plan() else {
        return Ok(None);
    };
    match resume.and_then(|m| m.room.as_deref()) {
        Some(name) => plan.room(name).map(Some).ok_or_else(|| {
            BadInput(format!("the checkpoint's room {name:?} is not on the plan")).into()
        }),
        None => Ok(mission.start_room().and_then(|(_, r)| r)),
    }
}

/// The rooms a job names for plastering, by their world names: the
/// drawing's rooms its `plaster` tasks plaster ([`Mission::plaster_rooms`]),
/// and every room a plaster task planned in; a mission without a drawing
/// plasters the room it starts in.
fn job_rooms(
    mission: &Mission,
    layout: &Layout,
    start: &Pose2,
    planned: impl Iterator<Item = String>,
) -> Vec<String> {
    let plasters = mission
        .tasks
        .iter()
        .any(|t| matches!(t, TaskSpec::Plaster { .. }));
    let mut rooms: Vec<String> = mission.plaster_rooms().to_vec();
    if mission.floor_plan().is_none() && plasters {
        rooms.extend(true_room(layout, start));
    }
    rooms.extend(planned);
    let mut seen = std::collections::BTreeSet::new();
    rooms.retain(|r| seen.insert(r.clone()));
    rooms
}

/// The room of `layout` that `at` (world frame) stands in (none in a
/// doorway's thickness).
fn true_room(layout: &Layout, at: &Pose2) -> Option<String> {
    RoomFrame::of(layout, at).ok().map(|f| f.name)
}

/// The windows the camera found in the room of `frame` (its frame)
/// against the room's true windows: each one's report, and how many of
/// the true ones were found out of how many there are. A true window is
/// found when a reported one overlaps it; openings reaching the floor are
/// doors, not windows.
fn score_windows(
    layout: &Layout,
    frame: &RoomFrame,
    found: Vec<(WallName, stucco_nav::Window)>,
) -> (Vec<WindowReport>, usize, usize) {
    // Wall, along-range, z.
    let truth: Vec<(WallName, [f64; 2], [f64; 2])> =
        crate::plastering::room_openings(layout, frame)
            .filter(|(o, _, _)| matches!(o.kind, OpeningKind::Window | OpeningKind::GlazedWindow))
            .map(|(o, wall, along)| (wall, along, o.z))
            .collect();
    let overlaps = |tw: WallName, a: &[f64; 2], z: &[f64; 2], wall, w: &stucco_nav::Window| {
        tw == wall
            && a[0] < w.along_m[1]
            && w.along_m[0] < a[1]
            && z[0] < w.sill_head_m[1]
            && w.sill_head_m[0] < z[1]
    };
    let windows: Vec<(WallName, stucco_nav::Window)> = found
        .into_iter()
        .filter(|(_, w)| w.sill_head_m[0] >= DOOR_SILL_M)
        .collect();
    let reports = windows
        .iter()
        .map(|(wall, w)| {
            let hit = truth
                .iter()
                .find(|(tw, a, z)| overlaps(*tw, a, z, *wall, w));
            WindowReport {
                room: frame.name.clone(),
                wall: *wall,
                along_m: w.along_m,
                sill_head_m: w.sill_head_m,
                observations: w.observations,
                edge_error_m: hit.map(|(_, a, z)| {
                    [
                        w.along_m[0] - a[0],
                        w.along_m[1] - a[1],
                        w.sill_head_m[0] - z[0],
                        w.sill_head_m[1] - z[1],
                    ]
                    .iter()
                    .fold(0.0, |m: f64, e| m.max(e.abs()))
                }),
            }
        })
        .collect();
    let hit = truth
        .iter()
        .filter(|(tw, a, z)| {
            windows
                .iter()
                .any(|(wall, w)| overlaps(*tw, a, z, *wall, w))
        })
        .count();
    (reports, hit, truth.len())
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// `n` errors drawn from the normal distribution of covariance `cov`.
    fn errors(cov: &Matrix3<f64>, n: usize, seed: u64) -> Vec<Vector3<f64>> {
        let l = cov.cholesky().expect("positive definite").l();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let w = Vector3::from_fn(|_, _| StandardNormal.sample(&mut rng));
                l * w
            })
            .collect()
    }

    #[test]
    fn a_covariance_that_covers_its_errors_scores_its_degrees_of_freedom() {
        // Position errors of 3 and 1 mm across each other, heading 0.5 mrad.
        let cov = Matrix3::new(
            9e-6, 2e-6, 0.0, //
            2e-6, 1e-6, 0.0, //
            0.0, 0.0, 2.5e-7,
        );
        let drawn = errors(&cov, 20_000, 7);
        let mut honest = Consistency::default();
        let mut proud = Consistency::default();
        for e in &drawn {
            honest.add(e, &cov);
            proud.add(e, &(cov / 100.0));
        }
        let honest = honest.report().expect("samples");
        assert!((honest.position_nees - 2.0).abs() < 0.1, "{honest:?}");
        assert!((honest.heading_nees - 1.0).abs() < 0.05, "{honest:?}");
        assert!((honest.heading_sigma_rms_rad - 5e-4).abs() < 1e-9);
        // A filter ten times surer than it is scores a hundred times more.
        let proud = proud.report().expect("samples");
        assert!((proud.position_nees / honest.position_nees - 100.0).abs() < 1e-6);
        assert!((proud.heading_nees / honest.heading_nees - 100.0).abs() < 1e-6);
    }

    #[test]
    fn a_covariance_that_cannot_be_inverted_is_left_out() {
        let mut c = Consistency::default();
        c.add(&Vector3::new(0.01, 0.0, 0.0), &Matrix3::zeros());
        assert_eq!(c.report(), None);
        c.add(
            &Vector3::new(0.001, 0.0, 0.0),
            &Matrix3::from_diagonal_element(1e-6),
        );
        let r = c.report().expect("one sample");
        assert!((r.position_nees - 1.0).abs() < 1e-9, "{r:?}");
        assert_eq!(r.heading_nees, 0.0);
    }
}
