//! Checkpoints: what a robot switched off in the middle of a job needs
//! to go on where it stopped — the mission's progress, what it knew of the
//! room, the plan it was carrying out — written atomically after every
//! unit of work, read back with `--resume`.

use crate::perception::{Perception, RoomWindows};
use crate::robot::{Robot, Sink, SinkError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use stucco_core::{Platform, Stamp};
use stucco_mission::{
    CHECKPOINT_FILE, Checkpoint, EventKind, Executive, Inputs, Mission, Outputs, PLAN_FILE,
    RoomMap, WallName, digest, write_atomic,
};

/// The windows found in every room the robot has been in, the room it is
/// in first: `perception`'s, and those of rooms a run resumed from
/// `resume` had left before it (unless the robot has been in them since).
pub fn windows_by_room<'a>(
    perception: &'a Perception,
    resume: Option<&'a Checkpoint>,
) -> Vec<RoomWindows<'a>> {
    let mut all = perception.windows_by_room();
    for (room, w) in resume.iter().flat_map(|cp| &cp.rooms_left) {
        if !all.iter().any(|(r, _)| *r == Some(room.as_str())) {
            all.push((Some(room.as_str()), w.clone()));
        }
    }
    all
}

/// When each task started and how long each took, from the executive's
/// events, over every part of a job (the parts before a resume too).
#[derive(Clone, Debug, Default)]
pub struct TaskTimes {
    /// Seconds each task took in the parts before this one.
    earlier: BTreeMap<usize, f64>,
    /// When each task started in this part.
    started: Vec<Option<Stamp>>,
    /// Seconds each task took in this part, once it ended.
    ended: Vec<Option<f64>>,
}

impl TaskTimes {
    /// The times of `tasks` tasks, `earlier` seconds spent before.
    pub fn new(tasks: usize, earlier: BTreeMap<usize, f64>) -> Self {
        TaskTimes {
            earlier,
            started: vec![None; tasks],
            ended: vec![None; tasks],
        }
    }

    /// Takes in a tick's events (tasks the operator added on the way
    /// counted as they come).
    pub fn hear(&mut self, outputs: &Outputs) {
        for e in &outputs.events {
            if let EventKind::TaskStarted { task, .. }
            | EventKind::TaskDone { task }
            | EventKind::TaskSkipped { task }
            | EventKind::TaskFailed { task, .. } = &e.kind
                && *task >= self.started.len()
            {
                self.started.resize(task + 1, None);
                self.ended.resize(task + 1, None);
            }
            match &e.kind {
                EventKind::TaskStarted { task, .. } => self.started[*task] = Some(e.stamp),
                EventKind::TaskDone { task }
                | EventKind::TaskSkipped { task }
                | EventKind::TaskFailed { task, .. } => {
                    self.ended[*task] = self.started[*task].map(|t| e.stamp.seconds_since(t));
                }
                _ => {}
            }
        }
    }

    /// Seconds each task took in this part (none: it did not end in it).
    pub fn this_part(&self) -> &[Option<f64>] {
        &self.ended
    }

    /// Each task's seconds over every part of the job up to `now`: the
    /// parts before a resume, and this part's (a task under way: so far).
    pub fn spent(&self, now: Stamp) -> BTreeMap<usize, f64> {
        let mut all = self.earlier.clone();
        for (t, (s, e)) in self.started.iter().zip(&self.ended).enumerate() {
            if let Some(secs) = e.or_else(|| s.map(|s| now.seconds_since(s))) {
                *all.entry(t).or_insert(0.0) += secs;
            }
        }
        all
    }
}

/// Writes a job's checkpoint into its folder whenever the executive says
/// a unit of work is done, and the plan it carries out beside it (once
/// per plan: the checkpoint names it by digest).
pub struct Checkpointer {
    dir: PathBuf,
    mission: String,
    digest: String,
    seed: u64,
    /// The digest of the plan last written.
    plan_written: String,
    times: TaskTimes,
    /// The windows of rooms left before a resume, by room.
    rooms_left: Vec<(String, Vec<(WallName, stucco_nav::Window)>)>,
}

impl Checkpointer {
    /// Checkpoints of `mission` run with `seed` into `dir` (made if it is
    /// not there), going on from `resume`'s when given.
    pub fn new(
        dir: &Path,
        mission: &Mission,
        seed: u64,
        resume: Option<&Checkpoint>,
    ) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| {
            std::io::Error::new(e.kind(), format!("cannot create {}: {e}", dir.display()))
        })?;
        Ok(Checkpointer {
            dir: dir.to_owned(),
            mission: mission.name.clone(),
            digest: digest(mission),
            seed,
            plan_written: String::new(),
            times: TaskTimes::new(
                mission.tasks.len(),
                resume.map(|cp| cp.task_seconds.clone()).unwrap_or_default(),
            ),
            rooms_left: resume.map(|cp| cp.rooms_left.clone()).unwrap_or_default(),
        })
    }

    /// Writes the checkpoint of `robot` as it stands now.
    pub fn save<P: Platform>(&mut self, robot: &Robot<P>) -> Result<(), SinkError> {
        let exec: &Executive = robot.executive();
        let perception = robot.perception();
        let progress = exec.progress();
        // The plan first, once: the checkpoint names it by digest.
        if let (Some(plan), Some(p)) = (exec.plaster_plan(), &progress.plaster)
            && self.plan_written != p.plan_digest
        {
            write_atomic(
                &self.dir.join(PLAN_FILE),
                serde_json::to_string(plan)?.as_bytes(),
            )?;
            self.plan_written = p.plan_digest.clone();
        }
        let est = robot.estimate();
        let mut rooms_left: Vec<(String, Vec<(WallName, stucco_nav::Window)>)> = perception
            .windows_by_room()
            .into_iter()
            .skip(1)
            .filter_map(|(room, w)| Some((room?.to_owned(), w)))
            .collect();
        let here = perception.room_name();
        for (room, w) in &self.rooms_left {
            if here != Some(room.as_str()) && !rooms_left.iter().any(|(r, _)| r == room) {
                rooms_left.push((room.clone(), w.clone()));
            }
        }
        let cp = Checkpoint {
            mission: self.mission.clone(),
            digest: self.digest.clone(),
            seed: self.seed,
            progress,
            map: RoomMap {
                room_m: est.room_m,
                room_sigma_m: est.room_sigma_m,
                doors: est.doors.clone(),
                pose: est.pose,
                room: here.map(str::to_owned),
                windows: perception.windows(),
            },
            task_seconds: self.times.spent(robot.now()),
            rooms_left,
        };
        write_atomic(
            &self.dir.join(CHECKPOINT_FILE),
            serde_json::to_string_pretty(&cp)?.as_bytes(),
        )?;
        Ok(())
    }
}

impl<P: Platform> Sink<P> for Checkpointer {
    fn ticked(
        &mut self,
        robot: &Robot<P>,
        _inputs: &Inputs<'_>,
        outputs: &Outputs,
    ) -> Result<(), SinkError> {
        self.times.hear(outputs);
        if outputs.checkpoint_due {
            self.save(robot)?;
        }
        Ok(())
    }
}
