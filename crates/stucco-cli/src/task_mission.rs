//! `stucco run` for task missions: the executive carries out the mission
//! file's tasks in the simulator, in simulated time as fast as the CPU
//! allows; the run is scored against the truth and written down — report,
//! events, a map, and a checkpoint after every finished task so a run
//! started again with `--resume` goes on where it stopped.

use crate::mission::{BadInput, Mission};
use crate::navigator::Navigator;
use crate::plan_view::{PlanPath, PlanSegment, draw_plan};
use crate::record::{RecordedMission, Recorder};
use anyhow::{Context, Result};
use nalgebra::{Matrix3, Point2, SVector, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::hash::Hasher;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;
use stucco_core::{Pose2, Stamp, wrap_angle};
use stucco_mission::{
    BehaviourKind, DoorEstimate, Event, EventKind, Executive, Inputs, MissionMode, Progress,
    TaskSpec, TaskStatus, WallGeometry, WallName,
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

/// The windows found in every room the robot has been in, the room it is
/// in first: the navigator's, and those of rooms a run resumed from
/// `resume` had left before it (unless the robot has been in them since).
fn windows_by_room<'a>(
    nav: &'a Navigator,
    resume: Option<&'a Checkpoint>,
) -> Vec<crate::navigator::RoomWindows<'a>> {
    let mut all = nav.windows_by_room();
    for (room, w) in resume.iter().flat_map(|cp| &cp.rooms_left) {
        if !all.iter().any(|(r, _)| *r == Some(room.as_str())) {
            all.push((Some(room.as_str()), w.clone()));
        }
    }
    all
}

/// The rooms of `mission`'s floor plan none of `plastered` is, each with
/// its drawn floor and why.
fn rooms_left(
    mission: &Mission,
    plastered: &[crate::plastering::RoomPlaster],
) -> Vec<crate::plastering::RoomLeft> {
    let Some(plan) = mission.floor_plan() else {
        return Vec::new();
    };
    plan.rooms()
        .iter()
        .enumerate()
        .filter(|(_, r)| !plastered.iter().any(|p| p.room == r.name))
        .map(|(i, r)| crate::plastering::RoomLeft {
            room: r.name.clone(),
            floor_m2: r.size_m[0] * r.size_m[1],
            why: if plan.doors_of(i).next().is_none() {
                "no open door leads there".to_owned()
            } else {
                "no plaster task".to_owned()
            },
        })
        .collect()
}

/// An opening the camera finds this near the floor is a door, m.
const DOOR_SILL_M: f64 = 0.1;
/// The plan a plastering run carries out, beside its checkpoint.
const PLAN_FILE: &str = "plan.json";
/// The world's plaster when the run stopped (kept for a resumed run).
const WORLD_FILE: &str = "world.json";
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
    /// Scans each wall (west, south, east, north) was used in.
    pub walls_seen: [usize; 4],
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
    /// Plasterable wall area the plan reaches within the coat's tolerance,
    /// on the true walls, % (plastering missions).
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

/// What a checkpoint file holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    /// The mission's name.
    pub mission: String,
    /// Digest of the mission file's text and its plan file's: a checkpoint
    /// of another version of either is refused.
    pub digest: String,
    /// The seed of the run.
    pub seed: u64,
    /// The tasks' states.
    pub progress: Progress,
    /// What the robot knew of the room.
    pub map: RoomMap,
    /// Where the simulated robot stood (world frame): a resumed run starts
    /// it there, as a robot switched off stays where it was.
    pub sim_pose: Pose2,
    /// Seconds each task started has taken, over every part of the run
    /// (one under way: so far), by task index: a resumed run reports the
    /// whole job's plastering time.
    #[serde(default)]
    pub task_seconds: std::collections::BTreeMap<usize, f64>,
    /// The windows found in each room the robot had left, by the plan's
    /// name of the room: a resumed run reports them with its own.
    #[serde(default)]
    pub rooms_left: Vec<(String, Vec<(WallName, stucco_nav::Window)>)>,
}

/// The room as the robot knew it at a checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomMap {
    /// Its size, m.
    pub room_m: [f64; 2],
    /// Its σ, m.
    pub room_sigma_m: [f64; 2],
    /// Its doors.
    pub doors: Vec<DoorEstimate>,
    /// The robot's estimated pose in it.
    pub pose: Pose2,
    /// The floor plan's room it is, when the mission has a plan.
    #[serde(default)]
    pub room: Option<String>,
    /// The windows the camera had found in it, wall by wall.
    #[serde(default)]
    pub windows: Vec<(WallName, stucco_nav::Window)>,
}

/// FNV-1a digest of what a checkpoint of `mission` must have been made
/// with: the mission file's text and, when it names one, its plan file's
/// (door numbers in a checkpoint are the plan's), each as the mission was
/// parsed from it, a newline between.
fn digest(mission: &Mission) -> String {
    let mut h = fnv::FnvHasher::default();
    h.write(mission.text().as_bytes());
    if let Some(plan) = mission.plan_text() {
        h.write(b"\n");
        h.write(plan.as_bytes());
    }
    format!("fnv1a64:{:016x}", h.finish())
}

/// Writes `bytes` to `path` atomically: a temporary file beside it,
/// flushed to disk, renamed over it, the folder flushed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp"));
    {
        let mut f = std::fs::File::create(&tmp)
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("cannot replace {}", path.display()))?;
    if let Ok(d) = std::fs::File::open(dir) {
        // Persists the rename; not every platform can sync a folder.
        let _ = d.sync_all();
    }
    Ok(())
}

/// Reads the checkpoint at `path` for `mission`, or says why it cannot be
/// used — leaving the file as it is.
fn read_checkpoint(path: &Path, mission: &Mission) -> Result<Checkpoint> {
    let raw = std::fs::read_to_string(path).map_err(|e| {
        BadInput(format!(
            "{}: cannot read the checkpoint: {e}",
            path.display()
        ))
    })?;
    let cp: Checkpoint = serde_json::from_str(&raw).map_err(|e| {
        BadInput(format!(
            "{}:{}:{}: the checkpoint is corrupt ({e}); it is left as it is",
            path.display(),
            e.line(),
            e.column()
        ))
    })?;
    let digest = digest(mission);
    if cp.mission != mission.name || cp.digest != digest {
        return Err(BadInput(format!(
            "{}: the checkpoint was written for mission {:?} ({}), not this file ({:?}, {}); it is left as it is",
            path.display(),
            cp.mission,
            cp.digest,
            mission.name,
            digest
        ))
        .into());
    }
    Ok(cp)
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
    let world = mission.load_world(&job.mission)?;
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
        let cp = read_checkpoint(&dir.join("checkpoint.json"), &mission)?;
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

/// The room a robot at `at` (world frame) stands in, as the simulator
/// knows it: its name, its south-west corner (the origin of the room frame
/// the robot's filter keeps) and its size.
#[derive(Clone, Debug)]
pub(crate) struct RoomFrame {
    pub name: String,
    pub origin: [f64; 2],
    pub size_m: [f64; 2],
}

impl RoomFrame {
    /// The room of `layout` named `name`.
    pub(crate) fn named(layout: &Layout, name: &str) -> Result<RoomFrame> {
        let room = layout
            .rooms
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| BadInput(format!("the plan's room {name:?} is not in the world")))?;
        let (lo, hi) = bounds(&room.corners);
        Ok(RoomFrame {
            name: room.name.clone(),
            origin: lo,
            size_m: [hi[0] - lo[0], hi[1] - lo[1]],
        })
    }

    /// The room of `layout` holding `at`.
    pub(crate) fn of(layout: &Layout, at: &Pose2) -> Result<RoomFrame> {
        let room = layout
            .rooms
            .iter()
            .find(|r| {
                let (lo, hi) = bounds(&r.corners);
                (lo[0]..=hi[0]).contains(&at.x) && (lo[1]..=hi[1]).contains(&at.y)
            })
            .ok_or_else(|| BadInput(format!("the robot's start {at:?} is in no room")))?;
        let (lo, hi) = bounds(&room.corners);
        Ok(RoomFrame {
            name: room.name.clone(),
            origin: lo,
            size_m: [hi[0] - lo[0], hi[1] - lo[1]],
        })
    }

    /// `p` (world frame) in the room frame.
    pub(crate) fn to_room(&self, p: &Pose2) -> Pose2 {
        Pose2::new(p.x - self.origin[0], p.y - self.origin[1], p.theta)
    }

    /// `p` (room frame) in the world frame.
    pub(crate) fn to_world(&self, p: &Pose2) -> Pose2 {
        Pose2::new(p.x + self.origin[0], p.y + self.origin[1], p.theta)
    }
}

fn bounds(points: &[Point2<f64>]) -> ([f64; 2], [f64; 2]) {
    points.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p.x), lo[1].min(p.y)],
                [hi[0].max(p.x), hi[1].max(p.y)],
            )
        },
    )
}

/// What every run of a job shares.
struct Setup<'a> {
    mission: &'a Mission,
    /// Where the mission file is.
    mission_path: &'a Path,
    /// Record each run to `run.mcap`.
    record: bool,
    world: &'a WorldSpec,
    resume: Option<&'a Checkpoint>,
    stop_after: Option<f64>,
}

/// One run of the mission with `seed`, writing into `out`.
fn run_once(
    setup: &Setup,
    seed: u64,
    out: Option<&Path>,
    progress: &(dyn Fn(f64, &str) + Sync),
) -> Result<MissionReport> {
    let Setup {
        mission,
        mission_path,
        record,
        world,
        resume,
        stop_after,
    } = *setup;
    let t0 = Instant::now();
    let layout = Layout::of(world);
    let mut world = world.clone();
    if let Some(cp) = resume {
        // Where the robot stopped, knowing what it knew.
        world.robot.at = [cp.sim_pose.x, cp.sim_pose.y];
        world.robot.heading_deg = cp.sim_pose.theta.to_degrees();
    }
    let (mut nav, start_frame) =
        mission_navigator(mission, &world, seed, resume.map(|cp| &cp.map))?;
    if resume.is_some() {
        // The plaster stays on the walls when the robot stops.
        if let Some(dir) = out
            && dir.join(WORLD_FILE).exists()
        {
            crate::plastering::WorldState::load(&dir.join(WORLD_FILE))?.restore(nav.sim_mut());
        }
    }
    // The truth in the frame of the room the robot is in (scoring only).
    let mut frame = start_frame;
    let true_frame = |nav: &Navigator, frame: &mut RoomFrame| -> Result<()> {
        if let Some(name) = nav.room_name()
            && name != frame.name
        {
            *frame = RoomFrame::named(&layout, name)?;
        }
        Ok(())
    };
    nav.discover_doors(true);
    let mut exec = mission.executive(true);
    if let Some(cp) = resume {
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
    let first_task = exec
        .status()
        .iter()
        .position(|s| *s == TaskStatus::Pending)
        .unwrap_or(exec.tasks().len());
    let mut events_file = match out {
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
            Some(std::io::BufWriter::new(f))
        }
        None => None,
    };
    let plan_written = std::cell::RefCell::new(String::new());
    let save = |exec: &Executive,
                nav: &Navigator,
                task_seconds: std::collections::BTreeMap<usize, f64>|
     -> Result<()> {
        if let Some(dir) = out {
            let progress = exec.progress();
            // The plan first, once: the checkpoint names it by digest.
            if let (Some(plan), Some(p)) = (exec.plaster_plan(), &progress.plaster)
                && *plan_written.borrow() != p.plan_digest
            {
                write_atomic(
                    &dir.join(PLAN_FILE),
                    serde_json::to_string(plan)?.as_bytes(),
                )?;
                *plan_written.borrow_mut() = p.plan_digest.clone();
            }
            let est = nav.mission_estimate();
            let rooms_left = windows_by_room(nav, resume)
                .into_iter()
                .skip(1)
                .filter_map(|(room, w)| Some((room?.to_owned(), w)))
                .collect();
            let cp = Checkpoint {
                mission: mission.name.clone(),
                digest: digest(mission),
                seed,
                progress,
                map: RoomMap {
                    room_m: est.room_m,
                    room_sigma_m: est.room_sigma_m,
                    doors: est.doors.clone(),
                    pose: est.pose,
                    room: nav.room_name().map(str::to_owned),
                    windows: nav.windows(),
                },
                sim_pose: nav.truth(),
                task_seconds,
                rooms_left,
            };
            write_atomic(
                &dir.join("checkpoint.json"),
                serde_json::to_string_pretty(&cp)?.as_bytes(),
            )?;
        }
        Ok(())
    };
    let mut trace = Trace::default();
    let mut bumper = false;
    let mut events = 0usize;
    let mut safety_stops = 0usize;
    let mut task_started: Vec<Option<Stamp>> = vec![None; exec.tasks().len()];
    let mut task_seconds: Vec<Option<f64>> = vec![None; exec.tasks().len()];
    // Each task's seconds over every part of the run up to `now`: the
    // parts before a resume, and this part's (a task under way: so far).
    let earlier = resume.map(|cp| cp.task_seconds.clone()).unwrap_or_default();
    let spent = |started: &[Option<Stamp>], ended: &[Option<f64>], now: Stamp| {
        let mut all = earlier.clone();
        for (t, (s, e)) in started.iter().zip(ended).enumerate() {
            if let Some(secs) = e.or_else(|| s.map(|s| now.seconds_since(s))) {
                *all.entry(t).or_insert(0.0) += secs;
            }
        }
        all
    };
    let mut time_out = None;
    let mut stopped = false;
    let mut recorder = match (out, record) {
        (Some(dir), true) => Some(Recorder::create(
            &dir.join("run.mcap"),
            &RecordedMission {
                path: mission_path.display().to_string(),
                text: mission.text().to_owned(),
                plan_text: mission.plan_text().map(str::to_owned),
                seed,
                resumed_from: resume.map(|cp| cp.progress.clone()),
            },
        )?),
        _ => None,
    };
    let mut scans_recorded = 0u64;
    let mut passes: std::collections::BTreeMap<usize, (WallName, f64, Vec<f64>)> =
        std::collections::BTreeMap::new();
    let limit = mission.time_limit_s;
    let mut step = 0usize;
    let mut room_changes = Vec::new();
    // Each plaster task's plan, the true frame of its room, and where the
    // robot stood when it was first made.
    let mut plans: std::collections::BTreeMap<usize, (RoomFrame, stucco_plan::Plan, Pose2)> =
        std::collections::BTreeMap::new();
    if let (Some(_), Some(dir)) = (resume, out)
        && dir.join(PLASTERED_FILE).exists()
    {
        let path = dir.join(PLASTERED_FILE);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
        let kept: Vec<PlasteredRoom> = serde_json::from_str(&text)
            .map_err(|e| BadInput(format!("{}: not the rooms plastered: {e}", path.display())))?;
        for r in kept {
            plans.insert(
                r.task,
                (RoomFrame::named(&layout, &r.room)?, r.plan, r.start),
            );
        }
    }
    // The estimate now, read once per control period: before the first
    // tick, then after each step of the robot.
    let mut est = nav.mission_estimate();
    loop {
        let now = nav.now();
        let inputs = Inputs {
            estimate: &est,
            obstacles: nav.obstacles(),
            bumper,
            estop: false,
            operator: &[],
            telecommands: &[],
        };
        let out_ = exec.tick(now, &inputs);
        if let Some(r) = recorder.as_mut() {
            let new_scan = nav.scans() != scans_recorded;
            scans_recorded = nav.scans();
            r.tick(
                &inputs,
                new_scan,
                out_.drive,
                out_.tool,
                &out_.events,
                &frame.to_room(&nav.truth()),
            )?;
        }
        for e in &out_.events {
            match &e.kind {
                EventKind::TaskStarted { task, .. } => task_started[*task] = Some(e.stamp),
                EventKind::TaskDone { task }
                | EventKind::TaskSkipped { task }
                | EventKind::TaskFailed { task, .. } => {
                    task_seconds[*task] = task_started[*task].map(|t| e.stamp.seconds_since(t));
                }
                EventKind::SafetyStop { .. } => safety_stops += 1,
                _ => {}
            }
            write_event(&mut events_file, e)?;
            events += 1;
        }
        if out_.checkpoint_due {
            save(&exec, &nav, spent(&task_started, &task_seconds, nav.now()))?;
        }
        // The plan scored is each task's last one (a survey makes it
        // again, a window the tool's camera finds is kept out of it, a
        // station no way leads to is left out of it); a resumed run's, the
        // one it took up.
        let made = out_.events.iter().find_map(|e| match e.kind {
            EventKind::PlanMade { task, .. }
            | EventKind::WindowFound { task, .. }
            | EventKind::StationGivenUp { task, .. } => Some(task),
            _ => None,
        });
        let taken_up = resume
            .and_then(|cp| cp.progress.plaster.as_ref())
            .map(|p| p.task)
            .filter(|t| !plans.contains_key(t));
        if let (Some(task), Some(plan)) = (made.or(taken_up), exec.plaster_plan()) {
            let start = plans.get(&task).map_or(est.pose, |p| p.2);
            plans.insert(task, (frame.clone(), plan.clone(), start));
            if let Some(dir) = out {
                let kept: Vec<PlasteredRoom> = plans
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
        if let Some(door) = out_.enter_room {
            // The executive checks on its next tick that the frame moved.
            if let Err(why) = nav.enter_through(door) {
                tracing::warn!(door, "the robot's frame stays: {why}");
            }
            true_frame(&nav, &mut frame)?;
            room_changes.push(RoomChange {
                stamp_s: now.as_secs_f64(),
                door,
                room: nav.room_name().map(str::to_owned),
                room_true: true_room(&layout, &nav.truth()),
            });
        }
        nav.tool(out_.tool);
        nav.tool_look(out_.tool_look);
        if exec.mode().is_final() {
            break;
        }
        if now.as_secs_f64() > limit {
            time_out = Some(format!("time limit: {limit} s of simulated time"));
            break;
        }
        if stop_after.is_some_and(|t| now.as_secs_f64() >= t) {
            stopped = true;
            break;
        }
        bumper = nav.drive(out_.drive);
        let truth = frame.to_room(&nav.truth());
        // A pass's standoff, on the truth, from where the pass starts.
        if let (
            Some((task, _)),
            Some(&BehaviourKind::FollowWall {
                wall, standoff_m, ..
            }),
        ) = (exec.current_task(), exec.current_behaviour())
            && let TaskSpec::FollowWall { from_m, to_m, .. } = exec.tasks()[task]
        {
            let g = WallGeometry::of(wall, frame.size_m);
            let p = truth.position().coords;
            let at = g.position(&p);
            if (to_m > from_m && at >= from_m) || (to_m < from_m && at <= from_m) {
                passes
                    .entry(task)
                    .or_insert_with(|| (wall, standoff_m, Vec::new()))
                    .2
                    .push(g.distance(&p) - standoff_m);
            }
        }
        // The trace in the world frame: the estimate placed by the true
        // corner of the room it is kept in.
        let (next, pose_covariance) = nav.mission_estimate_with_covariance();
        est = next;
        let (est_w, truth_w) = (frame.to_world(&est.pose), nav.truth());
        if step.is_multiple_of(5) {
            trace.push(&est_w, &truth_w);
        }
        trace.errors(&est_w, &truth_w, &pose_covariance);
        step += 1;
        if step.is_multiple_of(50) {
            let task = exec.current_task().map_or("", |t| t.1);
            progress(nav.now().as_secs_f64(), task);
        }
    }
    if let Some(w) = events_file.as_mut() {
        w.flush()?;
    }
    if let Some(r) = recorder {
        r.finish()?;
    }
    let task_spent = spent(&task_started, &task_seconds, nav.now());
    save(&exec, &nav, task_spent.clone())?;
    if let Some(dir) = out
        && mission.spray.is_some()
    {
        crate::plastering::WorldState::of(nav.sim()).save(&dir.join(WORLD_FILE))?;
    }
    let est = nav.mission_estimate();
    let (outcome, reason) = match (exec.mode(), time_out) {
        _ if stopped => (
            "stopped",
            Some(format!(
                "stopped after {:.1} s as asked",
                nav.now().as_secs_f64()
            )),
        ),
        (_, Some(r)) => ("failed", Some(r)),
        (MissionMode::Done, None) => ("done", None),
        (MissionMode::Aborted, None) => ("aborted", Some("aborted by the operator".to_owned())),
        (MissionMode::Failed { reason }, None) => ("failed", Some(reason.clone())),
        (other, None) => ("failed", Some(format!("stopped while {other:?}"))),
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
        .map(|d| {
            let g = WallGeometry::of(d.wall, est.room_m);
            let c = Point2::from(g.point(d.position_m, 0.0));
            DoorReport {
                wall: d.wall,
                position_m: d.position_m,
                width_m: d.width_m,
                error_m: true_doors
                    .iter()
                    .map(|t| (t - c).norm())
                    .fold(f64::INFINITY, f64::min),
            }
        })
        .collect();
    // Every room the robot has been in, each in its true frame.
    let mut windows = Vec::new();
    let (mut windows_found, mut windows_total) = (0, 0);
    for (room, found) in windows_by_room(&nav, resume) {
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
    let plastered = (!plans.is_empty()).then(|| {
        let rooms: Vec<(&RoomFrame, &stucco_plan::Plan)> =
            plans.values().map(|(f, p, _)| (f, p)).collect();
        let (score, each) = crate::plastering::score_run(nav.sim(), &layout, &rooms);
        let top = stucco_sim::SimConfig::default().vehicle.max_speed_mps;
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
    if let Some(dir) = out {
        for (frame, plan, _) in plans.values() {
            let prefix = if plans.len() > 1 {
                format!("{}-", frame.name)
            } else {
                String::new()
            };
            crate::plastering::draw_coats(dir, &prefix, &layout, frame, nav.sim(), &plan.tool)?;
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    let sim = nav.now().as_secs_f64();
    let n = trace.n.max(1) as f64;
    let report = MissionReport {
        outcome: outcome.to_owned(),
        reason,
        mission: mission.name.clone(),
        seed,
        sim_seconds: sim,
        wall_seconds: wall,
        real_time_factor: sim / wall.max(1e-9),
        tasks: exec
            .tasks()
            .iter()
            .zip(exec.status())
            .zip(&task_seconds)
            .map(|((t, s), secs)| TaskReport {
                name: t.name().to_owned(),
                status: s.clone(),
                seconds: *secs,
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
        room: nav.room_name().map(str::to_owned),
        room_true: true_room(&layout, &nav.truth()),
        room_changes,
        room_m: est.room_m,
        room_true_m: frame.size_m,
        room_sigma_m: est.room_sigma_m,
        walls_seen: est.walls_seen,
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
        events,
        wall_coverage_pct: plastered.as_ref().map(|p| p.0.wall_coverage_pct),
        ceiling_coverage_pct: plastered.as_ref().map(|p| p.0.ceiling_coverage_pct),
        overspray_pct: plastered.as_ref().map(|p| p.0.overspray_pct),
        thickness_cv: plastered.as_ref().map(|p| p.0.thickness_cv),
        double_sprayed_pct: plastered.as_ref().map(|p| p.0.over_pct),
        mission_time_s: plastered.as_ref().and_then(|p| p.2),
        mission_time_lower_bound_s: plastered.as_ref().map(|p| p.3),
        plaster: plastered.map(|(score, rooms, _, _)| {
            let rooms_left = rooms_left(mission, &rooms);
            crate::plastering::PlasterReport {
                stations: rooms.iter().map(|r| r.stations).sum(),
                unreachable_m2: rooms.iter().map(|r| r.unreachable_m2).sum(),
                sprayed_l: score.sprayed_l,
                rooms,
                rooms_left,
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

fn write_event(file: &mut Option<impl Write>, e: &Event) -> Result<()> {
    if let Some(f) = file {
        serde_json::to_writer(&mut *f, e)?;
        f.write_all(b"\n")?;
    }
    Ok(())
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
        .map(|d| {
            let c = WallGeometry::of(d.wall, est.room_m).point(d.position_m, 0.0);
            (c.x, c.y)
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

/// The robot of `mission` on `world` (put where `world` says) with
/// `seed`: its filter started as `[start]` says, or from the map a
/// checkpoint kept; and the true frame of the room it starts in.
pub(crate) fn mission_navigator(
    mission: &Mission,
    world: &WorldSpec,
    seed: u64,
    resume: Option<&RoomMap>,
) -> Result<(Navigator, RoomFrame)> {
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
    let sprayer = mission.spray.as_ref().map(crate::plastering::sprayer_of);
    let mut nav = Navigator::with_sprayer(world, seed, x0, size_sigma, sprayer)?;
    // The doors it knew, before the plan's (those it holds are not added
    // twice).
    for d in resume.iter().flat_map(|m| &m.doors) {
        nav.add_known_door(d);
    }
    for (wall, w) in resume.iter().flat_map(|m| &m.windows) {
        nav.add_known_window(*wall, *w);
    }
    if let (Some(plan), Some(room)) = (mission.floor_plan(), mission_room(mission, resume)?) {
        // Scoring follows the robot into each room by its name.
        for r in plan.rooms() {
            RoomFrame::named(&layout, &r.name)?;
        }
        nav.follow_plan(plan, room, known.room_sigma_m);
    }
    Ok((nav, frame))
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
