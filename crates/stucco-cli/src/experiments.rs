//! `stucco run` for experiment missions: paper A's navigation experiments
//! in the simulator, seeds in parallel, scored against the truth.

use crate::sim_robot::LawDriven;
use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use stucco_control::{GainSchedule, LineFollower};
use stucco_core::{Pose2, wrap_angle};
use stucco_nav::RoomState;
use stucco_runtime::{Corridor, DoorPassage, Mission, RoomSize};
use stucco_sim::{Layout, OpeningKind, TourDriver, WorldSpec};

/// Control periods an experiment may take before it is called stuck.
const MAX_STEPS: usize = 6000;

/// What `stucco run` was asked to do.
#[derive(Clone, Debug)]
pub struct RunJob {
    /// The mission file.
    pub mission: PathBuf,
    /// Seed of the first run, instead of the mission's.
    pub seed: Option<u64>,
    /// Runs, instead of the mission's.
    pub runs: Option<u64>,
}

/// One experimental condition over its runs.
#[derive(Clone, Debug, Serialize)]
pub struct ConditionReport {
    /// Its name (`easy 0.5 m/s`).
    pub name: String,
    /// Runs.
    pub runs: usize,
    /// Standard deviation over runs of the lateral offset at the door
    /// plane (or over the corridor's scored stretch), m.
    pub lateral_std_m: f64,
    /// Same for the heading, rad.
    pub heading_std_rad: f64,
    /// Mean lateral offset, m.
    pub lateral_mean_m: f64,
    /// Mean heading, rad.
    pub heading_mean_rad: f64,
    /// RMS error of the filter's door estimate at the door plane, m (door
    /// passage only).
    pub door_estimate_rms_m: Option<f64>,
}

/// The summary `stucco run --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// The mission's name.
    pub mission: String,
    /// Seed of the first run.
    pub seed: u64,
    /// Runs per condition.
    pub runs: u64,
    /// The conditions (door passage, corridor).
    pub conditions: Vec<ConditionReport>,
    /// Standard deviation over runs of the room's size learnt, m (the
    /// larger of its two sides; room-size missions only).
    pub room_size_std_m: Option<f64>,
    /// The room's size learnt, mean over runs, m.
    pub room_size_mean_m: Option<[f64; 2]>,
    /// RMS error of the estimated position over the tour, m (room-size
    /// missions only).
    pub pose_rms_m: Option<f64>,
    /// RMS error of the estimated heading over the tour, rad (room-size
    /// missions only).
    pub heading_rms_rad: Option<f64>,
}

fn stats(v: &[f64]) -> (f64, f64) {
    let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len().max(1) as f64;
    (m, var.sqrt())
}

/// Runs the mission.
pub fn run_mission(job: &RunJob) -> Result<RunReport> {
    let mission = Mission::load(&job.mission)?;
    let world_path = mission.world_path(&job.mission)?;
    let world = WorldSpec::load(&world_path)
        .with_context(|| format!("the world of {}", job.mission.display()))?;
    let seed = job.seed.unwrap_or(mission.seed);
    let runs = job.runs.unwrap_or(mission.runs);
    if runs == 0 {
        bail!("{}: runs: at least one", job.mission.display());
    }
    let mut report = RunReport {
        mission: mission.name.clone(),
        seed,
        runs,
        conditions: Vec::new(),
        room_size_std_m: None,
        room_size_mean_m: None,
        pose_rms_m: None,
        heading_rms_rad: None,
    };
    if let Some(d) = &mission.door_passage {
        report.conditions = door_passage(&world, d, seed, runs)?;
    } else if let Some(c) = &mission.corridor {
        report.conditions = vec![corridor(&world, c, seed, runs)?];
    } else if let Some(r) = &mission.room_size {
        let out: Vec<RoomSizeRun> = (0..runs)
            .into_par_iter()
            .map(|k| room_size(&world, r, seed + k))
            .collect::<Result<_>>()?;
        let (mw, sw) = stats(&out.iter().map(|o| o.size_m[0]).collect::<Vec<_>>());
        let (mh, sh) = stats(&out.iter().map(|o| o.size_m[1]).collect::<Vec<_>>());
        report.room_size_std_m = Some(sw.max(sh));
        report.room_size_mean_m = Some([mw, mh]);
        let n = out.len() as f64;
        let pos = out.iter().map(|o| o.pose_ms_m2).sum::<f64>() / n;
        let head = out.iter().map(|o| o.heading_ms_rad2).sum::<f64>() / n;
        report.pose_rms_m = Some(pos.sqrt());
        report.heading_rms_rad = Some(head.sqrt());
    }
    Ok(report)
}

/// The filter's start: near the truth (2 cm, a degree) and the map's room.
fn start_state(start: &Pose2, room_m: [f64; 2]) -> RoomState {
    RoomState::new(
        start.x + 0.02,
        start.y - 0.02,
        start.theta + 0.015,
        room_m[0],
        room_m[1],
    )
}

fn pose_of(s: &stucco_runtime::Start) -> Pose2 {
    Pose2::new(s.at[0], s.at[1], s.heading_deg.to_radians())
}

/// The bounding box `[x0, x1, y0, y1]` of `points`.
fn bounds(points: &[[f64; 2]]) -> [f64; 4] {
    points
        .iter()
        .fold([f64::MAX, f64::MIN, f64::MAX, f64::MIN], |b, q| {
            [
                b[0].min(q[0]),
                b[1].max(q[0]),
                b[2].min(q[1]),
                b[3].max(q[1]),
            ]
        })
}

/// The world with the robot at `start` and the people whose paths cross
/// the box `x0..x1 × y0..y1` taken out (they would stop the robot).
fn world_for(world: &WorldSpec, start: &Pose2, lane: [f64; 4]) -> WorldSpec {
    let mut w = world.clone();
    w.robot.at = [start.x, start.y];
    w.robot.heading_deg = start.theta.to_degrees();
    w.people.retain(|p| {
        let [x0, x1, y0, y1] = bounds(&p.path);
        x1 < lane[0] || x0 > lane[1] || y1 < lane[2] || y0 > lane[3]
    });
    w
}

fn door_passage(
    world: &WorldSpec,
    d: &DoorPassage,
    seed: u64,
    runs: u64,
) -> Result<Vec<ConditionReport>> {
    let truth = true_door(world, d.door_m)?;
    let mut out = Vec::new();
    for &speed in &d.speeds_mps {
        for s in &d.start {
            let start = pose_of(s);
            let lane = [
                start.x.min(d.door_m[0]) - 1.0,
                d.door_m[0] + 1.6,
                d.door_m[1] - 0.75,
                d.door_m[1] + 0.75,
            ];
            let w = world_for(world, &start, lane);
            let results: Vec<(f64, f64, f64)> = (0..runs)
                .into_par_iter()
                .map(|k| passage(&w, d, truth, &start, speed, seed + k))
                .collect::<Result<_>>()?;
            let (ml, sl) = stats(&results.iter().map(|r| r.0).collect::<Vec<_>>());
            let (mh, sh) = stats(&results.iter().map(|r| r.1).collect::<Vec<_>>());
            let door_rms = (results.iter().map(|r| r.2 * r.2).sum::<f64>()
                / results.len().max(1) as f64)
                .sqrt();
            out.push(ConditionReport {
                name: format!("{} {} m/s", s.name, speed),
                runs: results.len(),
                lateral_std_m: sl,
                heading_std_rad: sh,
                lateral_mean_m: ml,
                heading_mean_rad: mh,
                door_estimate_rms_m: Some(door_rms),
            });
        }
    }
    Ok(out)
}

/// The centre of the world's open door nearest the mission's `door_m`:
/// the passage is scored against the door as built.
fn true_door(world: &WorldSpec, door_m: [f64; 2]) -> Result<[f64; 2]> {
    let near = Layout::of(world)
        .openings
        .iter()
        .filter(|o| o.kind == OpeningKind::OpenDoor)
        .map(|o| {
            let c = nalgebra::center(&o.edges[0], &o.edges[1]);
            [c.x, c.y]
        })
        .min_by(|a, b| {
            let dist = |c: &[f64; 2]| (c[0] - door_m[0]).hypot(c[1] - door_m[1]);
            dist(a).total_cmp(&dist(b))
        });
    match near {
        Some(c) if (c[0] - door_m[0]).hypot(c[1] - door_m[1]) <= 0.3 => Ok(c),
        _ => bail!("door_passage.door_m {door_m:?}: no open door of the world within 0.3 m of it"),
    }
}

/// One passage: lateral offset and heading of the rear axle as it crosses
/// the true door's plane (from the truth), and the door estimate's error
/// then.
fn passage(
    world: &WorldSpec,
    d: &DoorPassage,
    [door_x, door_y]: [f64; 2],
    start: &Pose2,
    speed: f64,
    seed: u64,
) -> Result<(f64, f64, f64)> {
    let mut nav = LawDriven::new(world, seed, start_state(start, d.room_m), [0.2, 0.2])?;
    // The map's door, `door_map_error_m` off: the filter places it.
    let door = nav.add_door(2, d.door_m[1] - d.door_map_error_m, 0.1);
    let law = LineFollower::new(GainSchedule::default());
    let mut before = nav.truth();
    for _ in 0..MAX_STEPS {
        let x = nav.estimate();
        // The law aims at the filter's door, as the paper's ŷd: the map
        // only seeds it, `door_map_error_m` off.
        let Some(now) = nav.step(speed, law.steer(x[1] - x[door], x[2], speed))? else {
            bail!(
                "seed {seed}: the robot touched something at {:?}",
                nav.truth()
            );
        };
        if now.x >= door_x {
            let f = (door_x - before.x) / (now.x - before.x);
            let y = before.y + f * (now.y - before.y);
            let th = before.theta + f * wrap_angle(now.theta - before.theta);
            return Ok((y - door_y, th, nav.estimate()[door] - door_y));
        }
        before = now;
    }
    bail!("seed {seed}: never reached the door from {start:?} at {speed} m/s")
}

fn corridor(world: &WorldSpec, c: &Corridor, seed: u64, runs: u64) -> Result<ConditionReport> {
    let start = pose_of(&c.start);
    let w = world_for(
        world,
        &start,
        [start.x, c.score_x_m[1] + 1.0, -1.0, c.room_m[1] + 1.0],
    );
    let middle = true_middle_y(world, &start)?;
    let samples: Vec<Vec<(f64, f64)>> = (0..runs)
        .into_par_iter()
        .map(|k| corridor_run(&w, c, &start, middle, seed + k))
        .collect::<Result<_>>()?;
    let all: Vec<(f64, f64)> = samples.into_iter().flatten().collect();
    let (ml, sl) = stats(&all.iter().map(|s| s.0).collect::<Vec<_>>());
    let (mh, sh) = stats(&all.iter().map(|s| s.1).collect::<Vec<_>>());
    Ok(ConditionReport {
        name: format!("corridor {} m/s", c.speed_mps),
        runs: runs as usize,
        lateral_std_m: sl,
        heading_std_rad: sh,
        lateral_mean_m: ml,
        heading_mean_rad: mh,
        door_estimate_rms_m: None,
    })
}

/// The true middle (in y) of the world's room the robot starts in: the
/// score is against the built corridor, not against the map's idea of it.
fn true_middle_y(world: &WorldSpec, start: &Pose2) -> Result<f64> {
    world
        .rooms
        .iter()
        .map(|r| bounds(&r.corners))
        .find(|b| (b[0]..=b[1]).contains(&start.x) && (b[2]..=b[3]).contains(&start.y))
        .map(|b| 0.5 * (b[2] + b[3]))
        .ok_or_else(|| anyhow::anyhow!("the start {start:?} lies in no room of the world"))
}

/// Lateral offsets from the corridor's true middle and headings over the
/// scored stretch.
fn corridor_run(
    w: &WorldSpec,
    c: &Corridor,
    start: &Pose2,
    middle: f64,
    seed: u64,
) -> Result<Vec<(f64, f64)>> {
    let mut nav = LawDriven::new(w, seed, start_state(start, c.room_m), [0.5, 0.1])?;
    let law = LineFollower::new(GainSchedule::default());
    let mut out = Vec::new();
    for _ in 0..MAX_STEPS {
        let x = nav.estimate();
        let Some(now) = nav.step(c.speed_mps, law.steer(x[1] - 0.5 * x[4], x[2], c.speed_mps))?
        else {
            bail!(
                "seed {seed}: the robot touched something at {:?}",
                nav.truth()
            );
        };
        if now.x > c.score_x_m[1] {
            return Ok(out);
        }
        if now.x > c.score_x_m[0] {
            out.push((now.y - middle, now.theta));
        }
    }
    bail!("seed {seed}: never reached x = {} m", c.score_x_m[1])
}

/// One room-size run.
struct RoomSizeRun {
    /// The room's size learnt by the end of the tour, m.
    size_m: [f64; 2],
    /// Mean squared position error over the tour's second half, m².
    pose_ms_m2: f64,
    /// Mean squared heading error over the tour's second half, rad².
    heading_ms_rad2: f64,
}

/// The room's size learnt after touring, and the pose errors over the
/// tour's second half.
fn room_size(world: &WorldSpec, r: &RoomSize, seed: u64) -> Result<RoomSizeRun> {
    let start = Pose2::new(
        world.robot.at[0],
        world.robot.at[1],
        world.robot.heading_deg.to_radians(),
    );
    let mut nav = LawDriven::new(
        world,
        seed,
        start_state(&start, r.room_m),
        [r.room_sigma_m; 2],
    )?;
    let mut driver = TourDriver::new(world.tour.clone(), r.speed_mps);
    let vehicle = stucco_sim::SimConfig::default().vehicle;
    let steps = (r.seconds / stucco_runtime::DT_S).round() as usize;
    let (mut pos, mut head, mut n) = (0.0, 0.0, 0usize);
    for k in 0..steps {
        let x = nav.estimate();
        // The tour driven on the filter's estimate, not on the truth.
        let cmd = driver.command(&Pose2::new(x[0], x[1], x[2]), &vehicle);
        let Some(now) = nav.step(cmd.speed_mps, cmd.steer_rad)? else {
            bail!(
                "seed {seed}: the robot touched something at {:?}",
                nav.truth()
            );
        };
        if 2 * k >= steps {
            let x = nav.estimate();
            pos += (x[0] - now.x).powi(2) + (x[1] - now.y).powi(2);
            head += wrap_angle(x[2] - now.theta).powi(2);
            n += 1;
        }
    }
    let x = nav.estimate();
    let n = n.max(1) as f64;
    Ok(RoomSizeRun {
        size_m: [x[3], x[4]],
        pose_ms_m2: pos / n,
        heading_ms_rad2: head / n,
    })
}

/// Every mission file in `dir`, parsed (for tests and `--check`).
pub fn load_all(dir: &Path) -> Result<Vec<Mission>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        if path.extension().is_some_and(|e| e == "toml") {
            let m = Mission::load(&path)?;
            WorldSpec::load(&m.world_path(&path)?)
                .with_context(|| format!("the world of {}", path.display()))?;
            out.push(m);
        }
    }
    Ok(out)
}
