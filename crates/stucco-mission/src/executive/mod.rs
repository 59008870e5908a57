//! The layered executive: mission → task → behaviour → control law, stepped
//! by `tick(now, inputs) -> outputs`, with the safety supervisor over every
//! layer.

use crate::behaviour::BehaviourKind;
use crate::floor::FloorPlan;
use crate::ledger::Ledger;
use crate::model::Estimate;
use crate::plaster::{Cursor, PlasterCoverage, PlasterProgress};
use crate::supervisor::{
    FailurePolicy, Hazard, LinkLossPolicy, LostPolicy, SafetyConfig, Supervisor,
};
use crate::task::TaskSpec;
mod commands;

use crate::tasks::{Effects, Task, TaskCx, TaskFailure, TaskStep, Thaw};
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use stucco_control::GainSchedule;
pub use stucco_core::MissionMode;
pub use stucco_core::OperatorCommand;
pub use stucco_core::telemetry::{Event, EventKind, GiveUpReason};
use stucco_core::{Ack, DriveCommand, Reply, Stamp, Telecommand, ToolCommand, VehicleSpec};
use stucco_plan::{Plan, SprayTool};

/// Where the nozzle waits while the robot drives, robot frame, m: over
/// the body.
pub const PARK_NOZZLE_M: [f64; 3] = [0.3, 0.0, 1.2];

/// A task's state.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum TaskStatus {
    /// Not started.
    Pending,
    /// Being carried out.
    Active,
    /// Finished.
    Done,
    /// Given up by the operator.
    Skipped,
    /// Failed.
    Failed {
        /// Why.
        reason: String,
    },
}

/// What the executive reads each tick.
#[derive(Clone, Copy, Debug)]
pub struct Inputs<'a> {
    /// The navigation core's estimate.
    pub estimate: &'a Estimate,
    /// The last scan's echoes in the robot's frame (rear axle at the
    /// origin), for the protective field.
    pub obstacles: &'a [Point2<f64>],
    /// Echoes seen before where the laser does not look now (behind the
    /// robot), in the robot's frame: a reversing robot stops for them.
    pub unseen: &'a [Point2<f64>],
    /// A bumper touched something.
    pub bumper: bool,
    /// The e-stop is pressed.
    pub estop: bool,
    /// Operator commands that arrived since the last tick.
    pub operator: &'a [OperatorCommand],
    /// Telecommands that arrived since the last tick.
    pub telecommands: &'a [Telecommand],
}

/// What the executive hands back each tick.
#[derive(Clone, Debug, PartialEq)]
pub struct Outputs {
    /// The drive command (after the supervisor).
    pub drive: DriveCommand,
    /// The spray tool's command (plaster flows only with the
    /// supervisor's leave).
    pub tool: ToolCommand,
    /// Events since the last tick.
    pub events: Vec<Event>,
    /// A unit of work completed: the progress should be written now.
    pub checkpoint_due: bool,
    /// Replies to telecommands.
    pub acks: Vec<Ack>,
    /// The robot has just gone through this door of the floor plan: the
    /// navigation core should move its frame to the room beyond it (the
    /// task waits for the estimate to say so).
    pub enter_room: Option<usize>,
    /// The camera on the spray tool is looking along a wall before it is
    /// sprayed: its profiles are to be searched for windows now (not while
    /// the nozzle sprays or travels).
    pub tool_look: bool,
}

/// The executive's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ExecutiveConfig {
    /// The robot.
    pub vehicle: VehicleSpec,
    /// The line law's gains.
    pub gains: GainSchedule,
    /// The supervisor's settings.
    pub safety: SafetyConfig,
    /// No operator is there to answer: what would wait for one fails
    /// the mission instead (a bumper, an e-stop).
    pub unattended: bool,
    /// The spray tool and the coat, for `plaster` tasks.
    pub spray: Option<SprayTool>,
    /// The building's rooms and doors, for `go_to_room` (and for
    /// `pass_door` to move the frame into the next room).
    pub floor: Option<FloorPlan>,
    /// Heading of the fan of the range camera on the robot's body in the
    /// robot's frame, rad (π/2: to the left), as the camera's profiles
    /// carry it; `None`: the body has no camera, and a plastering survey
    /// makes no looks at the window edges it bracketed loosely.
    pub body_camera_azimuth_rad: Option<f64>,
}

impl ExecutiveConfig {
    /// `vehicle` that only drives, unattended: the default gains and
    /// safety, no spray tool, no building, no camera on its body.
    pub fn driving(vehicle: VehicleSpec) -> Self {
        ExecutiveConfig {
            vehicle,
            gains: GainSchedule::default(),
            safety: SafetyConfig::default(),
            unattended: true,
            spray: None,
            floor: None,
            body_camera_azimuth_rad: None,
        }
    }
}

/// The mission's progress as a checkpoint keeps it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Progress {
    /// The task names, in order (a checkpoint of another mission is
    /// refused).
    pub tasks: Vec<String>,
    /// Each task's state.
    pub status: Vec<TaskStatus>,
    /// The `plaster` task under way: how far it got.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plaster: Option<PlasterProgress>,
}

/// Why a checkpoint cannot be resumed from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProgressMismatch(pub String);

impl std::fmt::Display for ProgressMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ProgressMismatch {}

/// The task being carried out.
#[derive(Clone, Debug)]
struct ActiveTask {
    index: usize,
    started: Stamp,
    task: Box<dyn Task>,
    /// Seconds the way has been blocked.
    blocked_s: f64,
}

/// The executive.
#[derive(Clone, Debug)]
pub struct Executive {
    config: ExecutiveConfig,
    tasks: Vec<TaskSpec>,
    status: Vec<TaskStatus>,
    mode: MissionMode,
    active: Option<ActiveTask>,
    supervisor: Supervisor,
    events: Vec<Event>,
    started: bool,
    last_tick: Option<Stamp>,
    hazard: Option<Hazard>,
    lost_since: Option<Stamp>,
    /// The touches with nobody there: when they began, and the last one
    /// (holding the robot for `clear_s`).
    touch: Option<(Stamp, Stamp)>,
    continue_asked: bool,
    /// True for the tasks of the mission file (a checkpoint keeps those),
    /// false for the operator's.
    scripted: Vec<bool>,
    /// The share of a job over rooms each task is of (one room's going
    /// there, mapping it, plastering it), for [`FailurePolicy::NextRoom`].
    rooms: Vec<Option<usize>>,
    /// The telecommands taken and their replies, while a retry may come.
    ledger: Ledger,
    /// How the scripted mission ended (failed or aborted) while the
    /// operator's tasks run: the state it returns to when they are over.
    closed: Option<MissionMode>,
    /// The scripted task whose failure stopped the mission: `resume`
    /// tries it again.
    failed_task: Option<usize>,
    /// Operator tasks by index, and the telecommand each answers.
    waiting: BTreeMap<usize, String>,
    /// Why the mission failed, when it did.
    failure: Option<TaskFailure>,
    /// Direct driving until a deadline, for a telecommand.
    jog: Option<(DriveCommand, Stamp, String)>,
    /// Whether the operator's link is up (none: no operator yet).
    link_up: Option<bool>,
    acks: Vec<Ack>,
    /// What the tasks do besides driving: the spray tool's command, a
    /// unit of work done, a door of the plan gone through.
    effects: Effects,
    /// Seconds since the last tick.
    dt: f64,
    /// A checkpoint's progress and the plan beside it, for its task to
    /// take up.
    thaw: Option<Thaw>,
}

impl Executive {
    /// An executive for `tasks`, none done yet.
    pub fn new(config: ExecutiveConfig, tasks: Vec<TaskSpec>) -> Self {
        let n = tasks.len();
        Executive {
            supervisor: Supervisor::new(config.safety.clone(), config.vehicle.clone()),
            config,
            tasks,
            status: vec![TaskStatus::Pending; n],
            mode: MissionMode::Running,
            active: None,
            events: Vec::new(),
            started: false,
            last_tick: None,
            hazard: None,
            lost_since: None,
            touch: None,
            continue_asked: false,
            scripted: vec![true; n],
            rooms: vec![None; n],
            ledger: Ledger::default(),
            closed: None,
            failed_task: None,
            waiting: BTreeMap::new(),
            jog: None,
            failure: None,
            link_up: None,
            acks: Vec::new(),
            effects: Effects {
                tool: ToolCommand {
                    nozzle_m: PARK_NOZZLE_M,
                    ..ToolCommand::default()
                },
                checkpoint: false,
                enter_room: None,
            },
            dt: 0.0,
            thaw: None,
        }
    }

    /// The same executive with `rooms[k]` the share of a job over rooms
    /// task `k` is of, when it is (one room's going there, mapping it,
    /// plastering it: [`FailurePolicy::NextRoom`] gives up what is left of
    /// a share when one of its tasks fails); tasks beyond `rooms` are of
    /// none.
    pub fn with_rooms(mut self, rooms: Vec<Option<usize>>) -> Self {
        for (k, room) in rooms.into_iter().enumerate().take(self.rooms.len()) {
            self.rooms[k] = room;
        }
        self
    }

    /// Tells the executive whether the operator's link is up (their
    /// heartbeat came within the failsafe's `link_timeout_s`). When it goes
    /// down, a jog stops at once and the failsafe's policy applies.
    pub fn link(&mut self, now: Stamp, up: bool) {
        if self.link_up == Some(up) || (self.link_up.is_none() && !up) {
            return;
        }
        self.link_up = Some(up);
        if up {
            self.emit(now, EventKind::LinkRestored);
            return;
        }
        self.emit(now, EventKind::LinkLost);
        if let Some((_, _, id)) = self.jog.take() {
            self.reply(
                now,
                &id,
                Reply::failed("link_lost", "the operator's link was lost"),
            );
        }
        if self.config.safety.on_link_loss == LinkLossPolicy::Pause
            && self.mode == MissionMode::Running
        {
            self.pause(now, "the operator's link was lost".to_owned());
        }
    }

    /// Takes up the progress of a checkpoint: tasks done, skipped or
    /// failed stay so; a task that was under way starts again.
    pub fn resume_from(&mut self, progress: &Progress) -> Result<(), ProgressMismatch> {
        let mine: Vec<usize> = (0..self.tasks.len())
            .filter(|&i| self.scripted[i])
            .collect();
        let names: Vec<&str> = mine.iter().map(|&i| self.tasks[i].name()).collect();
        if progress.tasks != names || progress.status.len() != names.len() {
            return Err(ProgressMismatch(format!(
                "the checkpoint holds tasks {:?}, the mission {:?}",
                progress.tasks, names
            )));
        }
        for (&i, s) in mine.iter().zip(&progress.status) {
            self.status[i] = match s {
                TaskStatus::Active => TaskStatus::Pending,
                other => other.clone(),
            };
        }
        if let Some(p) = &progress.plaster {
            if !matches!(self.tasks.get(p.task), Some(TaskSpec::Plaster { .. })) {
                return Err(ProgressMismatch(format!(
                    "the checkpoint's plastering progress is for task {}, which is not a \
                     plaster task",
                    p.task
                )));
            }
            let plan = self.thaw.take().and_then(|t| t.plan);
            self.thaw = Some(Thaw {
                progress: p.clone(),
                plan,
            });
        }
        Ok(())
    }

    /// Hands over the plan a checkpoint's `plaster` task was carrying out
    /// (kept beside the checkpoint): the task takes it up from its cursor.
    pub fn resume_plan(&mut self, plan: Plan) {
        match &mut self.thaw {
            Some(t) => t.plan = Some(plan),
            None => {
                self.thaw = Some(Thaw {
                    progress: PlasterProgress {
                        task: usize::MAX,
                        cursor: Cursor::default(),
                        in_move_s: 0.0,
                        plan_digest: String::new(),
                    },
                    plan: Some(plan),
                })
            }
        }
    }

    /// The plan of the `plaster` task under way.
    pub fn plaster_plan(&self) -> Option<&Plan> {
        self.active.as_ref().and_then(|a| a.task.plan())
    }

    /// How far the `plaster` task under way has got over its plan.
    pub fn coverage(&self) -> Option<PlasterCoverage> {
        let a = self.active.as_ref()?;
        a.task.coverage(a.index)
    }

    /// The progress to keep in a checkpoint: the mission file's tasks (the
    /// operator's die with the run).
    pub fn progress(&self) -> Progress {
        let mine = (0..self.tasks.len()).filter(|&i| self.scripted[i]);
        Progress {
            tasks: mine
                .clone()
                .map(|i| self.tasks[i].name().to_owned())
                .collect(),
            status: mine.map(|i| self.status[i].clone()).collect(),
            plaster: self.active.as_ref().and_then(|a| a.task.freeze(a.index)),
        }
    }

    /// Telecommand ids remembered for their retries (bounded: see
    /// [`crate::MAX_KEPT`]).
    pub fn remembered_commands(&self) -> usize {
        self.ledger.len()
    }

    /// Why the mission failed (the sentence is in its mode's reason).
    pub fn failure(&self) -> Option<&TaskFailure> {
        self.failure.as_ref()
    }

    /// The mission's state.
    pub fn mode(&self) -> &MissionMode {
        &self.mode
    }

    /// Each task's state.
    pub fn status(&self) -> &[TaskStatus] {
        &self.status
    }

    /// The tasks.
    pub fn tasks(&self) -> &[TaskSpec] {
        &self.tasks
    }

    /// The task under way: its index and name.
    pub fn current_task(&self) -> Option<(usize, &'static str)> {
        self.active
            .as_ref()
            .map(|a| (a.index, self.tasks[a.index].name()))
    }

    /// The behaviour under way.
    pub fn current_behaviour(&self) -> Option<&BehaviourKind> {
        self.active.as_ref().and_then(|a| a.task.behaviour())
    }

    /// What the supervisor is holding the robot for.
    pub fn hazard(&self) -> Option<Hazard> {
        self.hazard
    }

    fn emit(&mut self, stamp: Stamp, kind: EventKind) {
        self.events.push(Event { stamp, kind });
    }

    /// One step of the executive at `now`.
    pub fn tick(&mut self, now: Stamp, inputs: &Inputs) -> Outputs {
        let dt = self
            .last_tick
            .map_or(0.0, |t| now.seconds_since(t).max(0.0));
        self.last_tick = Some(now);
        self.dt = dt;
        let mut checkpoint_due = false;
        if !self.started {
            self.started = true;
            let first_task = self
                .status
                .iter()
                .position(|s| *s == TaskStatus::Pending)
                .unwrap_or(self.tasks.len());
            self.emit(
                now,
                EventKind::MissionStarted {
                    tasks: self.tasks.len(),
                    first_task,
                },
            );
        }
        for &cmd in inputs.operator {
            checkpoint_due |= self.operator(now, cmd).unwrap_or(false);
        }
        for t in inputs.telecommands {
            self.telecommand(now, t, inputs.estimate);
        }
        // The e-stop overrides everything, at once.
        if inputs.estop && !self.mode.is_final() && self.mode != MissionMode::EStopped {
            self.emit(now, EventKind::EStop);
            if let Some((_, _, id)) = self.jog.take() {
                self.reply(now, &id, Reply::failed("e_stop", "e-stop pressed"));
            }
            if self.config.unattended {
                self.fail(now, TaskFailure::EStop);
                checkpoint_due = true;
            } else {
                self.mode = MissionMode::EStopped;
            }
        }
        if inputs.bumper && self.mode == MissionMode::Running {
            if self.config.unattended {
                // Held where it is (a person walking into it, a hand on
                // it); the task fails only when the touches go on: each
                // within the timeout of the last (the hold lets go between
                // them) counts from the first.
                let timeout = self.config.safety.touch_timeout_s;
                let since = match self.touch {
                    Some((since, last)) if now.seconds_since(last) <= timeout => since,
                    _ => now,
                };
                self.touch = Some((since, now));
                self.note_hazard(now, Some(Hazard::Touch));
                if now.seconds_since(since) > self.config.safety.touch_timeout_s {
                    self.touch = None;
                    self.fail(now, TaskFailure::Bumper);
                    checkpoint_due = true;
                }
            } else {
                self.pause(now, "bumper: the robot touched something".to_owned());
            }
        }
        let mut drive = DriveCommand::STOP;
        if let Some((_, until, id)) = &self.jog
            && now >= *until
        {
            let id = id.clone();
            self.jog = None;
            self.reply(now, &id, Reply::Done);
        }
        if let Some((cmd, _, _)) = self.jog {
            // The operator drives, in any mode but the e-stop's (a jog is
            // refused then): the task is held where it is, and the
            // supervisor guards the jog as any command, backwards too.
            let verdict =
                self.supervisor
                    .check(cmd, inputs.obstacles, inputs.unseen, inputs.estimate, dt);
            self.note_hazard(now, verdict.hazard);
            drive = verdict.drive;
        } else if self.mode == MissionMode::Running {
            // Touched: the task stands where it is (no stroke goes on, no
            // new aim for the nozzle) until the bumper has been free a
            // while.
            if !self.touch_holds(now, dt) {
                let (cmd, unit_done) = self.run(now, inputs.estimate);
                checkpoint_due |= unit_done | std::mem::take(&mut self.effects.checkpoint);
                drive = self.supervise(now, cmd, inputs, dt, &mut checkpoint_due);
            }
        } else {
            // Standing (done, paused, waiting for an e-stop's release):
            // what the supervisor holds the robot for is still told as it
            // changes — a hold that has gone is cleared — with no timers
            // run (a lost estimate fails nothing that is not running).
            let verdict = self.supervisor.check(
                DriveCommand::STOP,
                inputs.obstacles,
                inputs.unseen,
                inputs.estimate,
                dt,
            );
            // A standing robot's path is empty: an obstacle hold stays as
            // it was until the robot would move again.
            if self.hazard != Some(Hazard::Obstacle) {
                self.note_hazard(now, verdict.hazard);
            }
        }
        // Plaster flows only while the mission runs and the supervisor
        // lets the robot be.
        let spraying = self.mode == MissionMode::Running
            && self.jog.is_none()
            && self.hazard.is_none()
            && !inputs.estop;
        let tool = if spraying {
            self.effects.tool
        } else {
            self.effects.tool.off()
        };
        let tool_look = self.active.as_ref().is_some_and(|a| a.task.tool_look());
        Outputs {
            drive,
            tool,
            events: std::mem::take(&mut self.events),
            checkpoint_due,
            acks: std::mem::take(&mut self.acks),
            enter_room: self.effects.enter_room.take(),
            tool_look,
        }
    }

    /// True while a touch holds the robot: until the bumper has been free
    /// for the field's clearing time.
    fn touch_holds(&mut self, now: Stamp, dt: f64) -> bool {
        let Some((_, last)) = self.touch else {
            return false;
        };
        if now.seconds_since(last) < self.config.safety.clear_s.max(dt) {
            self.note_hazard(now, Some(Hazard::Touch));
            return true;
        }
        false
    }

    fn pause(&mut self, now: Stamp, reason: String) {
        self.mode = MissionMode::Paused {
            reason: reason.clone(),
        };
        self.emit(now, EventKind::Paused { reason });
    }

    /// The task under way fails for `failure`. An operator's task fails
    /// alone: the robot stands ready for the next command. A scripted
    /// task stops the mission, or not, as the failsafe's `on_task_failure`
    /// says (with `next_room`, a room's share of a job over rooms is
    /// given up and the job goes on); with nothing under way (an e-stop,
    /// a bumper with nobody there), the mission fails.
    fn fail(&mut self, now: Stamp, failure: TaskFailure) {
        let reason = failure.to_string();
        let index = self.active.as_ref().map(|a| a.index);
        let scripted = index.map(|k| self.scripted[k]);
        if let Some(a) = self.active.take() {
            self.status[a.index] = TaskStatus::Failed {
                reason: reason.clone(),
            };
            self.answer(now, a.index, Reply::failed(failure.code(), &reason));
            self.emit(
                now,
                EventKind::TaskFailed {
                    task: a.index,
                    reason: reason.clone(),
                    failure: failure.clone(),
                },
            );
        }
        // Touching something, or the e-stop, with nobody there ends the
        // mission whatever the policy.
        let unattended_stop = matches!(failure, TaskFailure::EStop | TaskFailure::Bumper);
        let room = index.and_then(|k| self.rooms[k]);
        let stops = match scripted {
            _ if unattended_stop => true,
            Some(false) => false,
            Some(true) => match self.config.safety.on_task_failure {
                FailurePolicy::Stop => true,
                FailurePolicy::Continue => false,
                // No room is reached from where the robot does not
                // know it is.
                FailurePolicy::NextRoom => room.is_none() || failure == TaskFailure::EstimateLost,
            },
            None => true,
        };
        if !stops
            && self.config.safety.on_task_failure == FailurePolicy::NextRoom
            && let Some(room) = room
        {
            // The room is given up: what is left of it would start where
            // its share did not get the robot (mapping the room it is in
            // as another, plastering a room not mapped).
            for k in 0..self.tasks.len() {
                if self.rooms[k] == Some(room) && self.status[k] == TaskStatus::Pending {
                    self.status[k] = TaskStatus::Skipped;
                    self.emit(now, EventKind::TaskSkipped { task: k });
                }
            }
        }
        let failed = MissionMode::Failed {
            reason: reason.clone(),
        };
        if stops {
            self.failed_task = index.filter(|_| scripted == Some(true));
            self.failure = Some(failure);
            self.emit(now, EventKind::MissionFailed { reason });
            // The operator's tasks still queued run first.
            if self.closed.is_some() || self.next_task(true).is_some() {
                self.closed = Some(failed);
            } else {
                self.mode = failed;
            }
        } else if self.failure.is_none() && scripted == Some(true) {
            // The mission goes on, and ends failed for this one.
            self.failure = Some(failure);
        }
    }

    /// The next task to start: the first pending one (the operator's only,
    /// while the mission's own are held, or when `operators_only`).
    fn next_task(&self, operators_only: bool) -> Option<usize> {
        let held = operators_only || self.closed.is_some();
        (0..self.status.len())
            .find(|&k| self.status[k] == TaskStatus::Pending && !(held && self.scripted[k]))
    }

    /// What the supervisor holds the robot for now, told when it changes.
    fn note_hazard(&mut self, now: Stamp, hazard: Option<Hazard>) {
        if hazard != self.hazard {
            match hazard {
                Some(h) => self.emit(now, EventKind::SafetyStop { hazard: h }),
                None => self.emit(now, EventKind::SafetyClear),
            }
            self.hazard = hazard;
        }
    }

    /// The supervisor over the task's command. A task's reversing
    /// manoeuvres are planned on the map with the body's clearance; the
    /// echoes kept from earlier scans guard the operator's jogs (a planned
    /// reverse in a narrow room came nearer to them than the field's
    /// margin, and its way stayed blocked).
    fn supervise(
        &mut self,
        now: Stamp,
        cmd: DriveCommand,
        inputs: &Inputs,
        dt: f64,
        checkpoint_due: &mut bool,
    ) -> DriveCommand {
        let verdict =
            self.supervisor
                .check(cmd, inputs.obstacles, inputs.unseen, inputs.estimate, dt);
        let safety = self.config.safety.clone();
        self.note_hazard(now, verdict.hazard);
        match verdict.hazard {
            Some(Hazard::Lost) => {
                let since = *self.lost_since.get_or_insert(now);
                if safety.on_lost == LostPolicy::Fail
                    || now.seconds_since(since) > safety.lost_timeout_s
                {
                    self.fail(now, TaskFailure::EstimateLost);
                    *checkpoint_due = true;
                }
            }
            Some(Hazard::Obstacle) => {
                self.lost_since = None;
                if let Some(a) = self.active.as_mut() {
                    a.blocked_s += dt;
                    // The task may plan its way again round what the map
                    // holds now (or give up what no clear way reaches).
                    let mut cx = TaskCx {
                        now,
                        dt,
                        started: a.started,
                        index: a.index,
                        est: inputs.estimate,
                        config: &self.config,
                        hazard: self.hazard,
                        answered: self.continue_asked,
                        events: &mut self.events,
                        effects: &mut self.effects,
                    };
                    if a.task.blocked(&mut cx, a.blocked_s) {
                        a.blocked_s = 0.0;
                    }
                    *checkpoint_due |= std::mem::take(&mut self.effects.checkpoint);
                    if a.blocked_s > safety.blocked_timeout_s {
                        let pose = inputs.estimate.pose;
                        let held = self.supervisor.last_block();
                        let failure = TaskFailure::WayBlocked {
                            pose: [pose.x, pose.y, pose.theta.to_degrees()],
                            obstacle_m: held.map(|(p, _)| {
                                let p = pose.transform_point(&p);
                                [p.x, p.y]
                            }),
                            backing: held.is_some_and(|(_, b)| b),
                        };
                        self.fail(now, failure);
                        *checkpoint_due = true;
                    }
                }
            }
            None => {
                self.lost_since = None;
                if let Some(a) = self.active.as_mut() {
                    a.blocked_s = 0.0;
                }
            }
            // The bumper's, held above: the field does not tell it.
            Some(Hazard::Touch) => {}
        }
        if self.mode == MissionMode::Running {
            verdict.drive
        } else {
            DriveCommand::STOP
        }
    }

    /// The task layer: starts tasks, steps their behaviours, decides when
    /// they are done. Returns the command and whether a task ended.
    fn run(&mut self, now: Stamp, est: &Estimate) -> (DriveCommand, bool) {
        let mut ended = false;
        // A few rounds: a behaviour or task that ends at once hands over
        // to the next within the same tick.
        for _ in 0..8 {
            if self.active.is_none() {
                let Some(next) = self.next_task(false) else {
                    self.mode = match (self.closed.take(), &self.failure) {
                        // The operator's tasks are over: back to how the
                        // mission ended.
                        (Some(closed), _) => closed,
                        (None, Some(f)) => {
                            let reason = f.to_string();
                            self.emit(
                                now,
                                EventKind::MissionFailed {
                                    reason: reason.clone(),
                                },
                            );
                            MissionMode::Failed { reason }
                        }
                        (None, None) => {
                            self.emit(now, EventKind::MissionDone);
                            MissionMode::Done
                        }
                    };
                    return (DriveCommand::STOP, ended);
                };
                match self.start(now, next, est) {
                    Ok(task) => {
                        self.status[next] = TaskStatus::Active;
                        self.emit(
                            now,
                            EventKind::TaskStarted {
                                task: next,
                                name: self.tasks[next].name().to_owned(),
                            },
                        );
                        self.active = Some(task);
                    }
                    Err((task, reason)) => {
                        self.status[next] = TaskStatus::Active;
                        self.active = Some(ActiveTask {
                            index: next,
                            started: now,
                            task,
                            blocked_s: 0.0,
                        });
                        self.fail(now, reason);
                        return (DriveCommand::STOP, true);
                    }
                }
            }
            match self.step_task(now, est) {
                TaskStep::Drive(cmd) => return (cmd, ended),
                TaskStep::Done => {
                    if let Some(a) = self.active.take() {
                        self.status[a.index] = TaskStatus::Done;
                        self.emit(now, EventKind::TaskDone { task: a.index });
                        self.answer(now, a.index, Reply::Done);
                    }
                    ended = true;
                }
                TaskStep::Failed(reason) => {
                    self.fail(now, reason);
                    return (DriveCommand::STOP, true);
                }
            }
        }
        (DriveCommand::STOP, ended)
    }

    /// Builds task `index` and plans it from the estimate.
    fn start(
        &mut self,
        now: Stamp,
        index: usize,
        est: &Estimate,
    ) -> Result<ActiveTask, (Box<dyn Task>, TaskFailure)> {
        let mut task = self.tasks[index].build();
        let mut cx = TaskCx {
            now,
            dt: self.dt,
            started: now,
            index,
            est,
            config: &self.config,
            hazard: self.hazard,
            answered: false,
            events: &mut self.events,
            effects: &mut self.effects,
        };
        match task.start(&mut cx, &mut self.thaw) {
            Ok(()) => {
                self.continue_asked = false;
                Ok(ActiveTask {
                    index,
                    started: now,
                    task,
                    blocked_s: 0.0,
                })
            }
            Err(e) => Err((task, e)),
        }
    }

    /// Steps the active task.
    fn step_task(&mut self, now: Stamp, est: &Estimate) -> TaskStep {
        let Some(a) = self.active.as_mut() else {
            return TaskStep::Done;
        };
        let mut cx = TaskCx {
            now,
            dt: self.dt,
            started: a.started,
            index: a.index,
            est,
            config: &self.config,
            hazard: self.hazard,
            answered: self.continue_asked,
            events: &mut self.events,
            effects: &mut self.effects,
        };
        a.task.step(&mut cx)
    }
}
