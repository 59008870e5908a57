//! The tasks of a mission, one module per kind, each a [`Task`]: started
//! from the estimate, stepped once a tick, its effects (the spray tool's
//! command, the tool camera's looks, a checkpoint due, a room entered)
//! handed back through [`Effects`], its progress frozen into a checkpoint
//! and thawed from one.
//!
//! [`TaskSpec::build`] — the mission file's enum — is the only place a
//! task is made from its kind.

mod door;
mod localize;
mod motion;
mod plaster;
mod survey;
mod wait;
mod wall;
mod ways;

use crate::behaviour::{Behaviour, BehaviourKind, Step};
use crate::executive::{Event, EventKind, ExecutiveConfig};
use crate::model::Estimate;
use crate::plaster::{PlasterCoverage, PlasterProgress};
use crate::supervisor::Hazard;
use crate::task::TaskSpec;
use std::collections::VecDeque;
use stucco_core::{DriveCommand, Pose2, Stamp, ToolCommand};
use stucco_plan::Plan;

pub(crate) use door::route;
pub use stucco_core::telemetry::TaskFailure;
pub(crate) use ways::{estimate_space, planned_way};

/// Why `spec` cannot be carried out in the room `est` knows, if it cannot:
/// a move that ends outside the room (or within half the body's width of
/// a wall), a place along a wall that is not on it, a door or a landmark
/// not known. Checked when an operator's command is taken, so an absurd
/// target is refused at once rather than failing the task later.
pub(crate) fn out_of_reach(
    spec: &TaskSpec,
    est: &Estimate,
    config: &ExecutiveConfig,
) -> Option<String> {
    use crate::model::{WallGeometry, depth_from, wall_in};
    let along = |key: &str, w, at: f64| match wall_in(est, w, spec.name()) {
        Err(e) => Some(e.to_string()),
        Ok(g) => (!(0.0..=g.length_m).contains(&at))
            .then(|| format!("{key}: {at:.2} m is not on {w} (0 to {:.2} m)", g.length_m)),
    };
    let standoff = |w, s: f64| {
        // The room across the wall, less the body's half width.
        let across = WallGeometry::in_room(est, w).map_or(0.0, |g| depth_from(est, &g));
        (s > across - 0.5 * config.vehicle.width_m)
            .then(|| format!("standoff_m: {s:.2} m reaches past a {across:.2} m room"))
    };
    match spec {
        TaskSpec::MoveRelative {
            dx_m,
            dy_m,
            dtheta_deg,
            landmark,
            ..
        } => {
            let goal = match motion::goal([*dx_m, *dy_m, *dtheta_deg], landmark.as_ref(), est) {
                Ok(g) => g,
                Err(e) => return Some(e.to_string()),
            };
            let half = 0.5 * config.vehicle.width_m;
            let inside = if est.corners.is_empty() {
                (half..=est.room_m[0] - half).contains(&goal.x)
                    && (half..=est.room_m[1] - half).contains(&goal.y)
            } else {
                let outline = stucco_plan::Outline::new(&est.corners);
                outline.contains(&goal.position()) && outline.clearance_m(&goal.position()) >= half
            };
            (!inside).then(|| {
                format!(
                    "the move ends at ({:.2}, {:.2}) m, outside the {:.2} × {:.2} m room (or                      within half the body's width of a wall)",
                    goal.x, goal.y, est.room_m[0], est.room_m[1]
                )
            })
        }
        TaskSpec::FollowWall {
            wall,
            standoff_m,
            from_m,
            to_m,
            ..
        } => along("from_m", *wall, *from_m)
            .or_else(|| along("to_m", *wall, *to_m))
            .or_else(|| standoff(*wall, *standoff_m)),
        TaskSpec::AlignToWall {
            wall,
            standoff_m,
            at_m,
            ..
        } => along("at_m", *wall, *at_m).or_else(|| standoff(*wall, *standoff_m)),
        TaskSpec::Plaster { walls, .. } => walls
            .iter()
            .flatten()
            .find_map(|&w| wall_in(est, w, spec.name()).err())
            .map(|e| e.to_string()),
        _ => None,
    }
}

/// Run-in along the wall before a pass starts, m: the line law's distance
/// to settle on the standoff from where the robot could turn (the offset
/// falls by e every ~0.4 m at a wall-following speed).
const RUN_IN_M: f64 = 2.0;
/// Seconds blocked on the way to a door (or a corner) before the way is
/// planned again.
const REPLAN_AFTER_S: f64 = 2.0;
/// Times the way to one door (or corner) may be planned again.
const MAX_REPLANS: usize = 3;

/// What a task sees of the executive while it starts, steps or is told it
/// is blocked.
#[derive(Debug)]
pub struct TaskCx<'a> {
    /// Now.
    pub now: Stamp,
    /// Seconds since the last tick.
    pub dt: f64,
    /// When the task started.
    pub started: Stamp,
    /// The task's index among the mission's.
    pub index: usize,
    /// The navigation core's estimate.
    pub est: &'a Estimate,
    /// The executive's settings.
    pub config: &'a ExecutiveConfig,
    /// What the supervisor held the robot for at the last tick.
    pub hazard: Option<Hazard>,
    /// The operator answered `continue`.
    pub answered: bool,
    /// Events for the log.
    pub events: &'a mut Vec<Event>,
    /// What the task does besides driving.
    pub effects: &'a mut Effects,
}

impl TaskCx<'_> {
    /// Logs `kind` now.
    pub fn emit(&mut self, kind: EventKind) {
        self.events.push(Event {
            stamp: self.now,
            kind,
        });
    }

    /// Seconds since the task started.
    pub fn elapsed_s(&self) -> f64 {
        self.now.seconds_since(self.started)
    }
}

/// What tasks do besides driving, kept by the executive from tick to tick.
#[derive(Clone, Debug, PartialEq)]
pub struct Effects {
    /// The spray tool's command (plaster flows only with the supervisor's
    /// leave).
    pub tool: ToolCommand,
    /// A unit of work is done: the progress should be written.
    pub checkpoint: bool,
    /// The robot has just gone through this door of the floor plan.
    pub enter_room: Option<usize>,
}

/// What a task's step comes to.
#[derive(Clone, Debug, PartialEq)]
pub enum TaskStep {
    /// Under way: this command for the drive.
    Drive(DriveCommand),
    /// Finished.
    Done,
    /// Failed, and why.
    Failed(TaskFailure),
}

/// A checkpoint's progress for a task to take up as it starts (the
/// `plaster` field of [`crate::Progress`]) and the plan kept beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct Thaw {
    /// How far the task got.
    pub progress: PlasterProgress,
    /// The plan it was carrying out.
    pub plan: Option<Plan>,
}

/// One task of a mission, carried out by the executive.
pub trait Task: std::fmt::Debug + Send {
    /// Plans the task from the estimate. A task that takes up a
    /// checkpoint's progress takes it out of `thaw`.
    fn start(&mut self, cx: &mut TaskCx<'_>, thaw: &mut Option<Thaw>) -> Result<(), TaskFailure>;

    /// One tick of the task.
    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep;

    /// The supervisor has held the robot for an obstacle for `blocked_s`:
    /// true when the task planned its way again (the time blocked starts
    /// again from zero).
    fn blocked(&mut self, _cx: &mut TaskCx<'_>, _blocked_s: f64) -> bool {
        false
    }

    /// The behaviour under way.
    fn behaviour(&self) -> Option<&BehaviourKind>;

    /// The progress a checkpoint keeps of task `index` (a plastering
    /// task's cursor in its plan).
    fn freeze(&self, _index: usize) -> Option<PlasterProgress> {
        None
    }

    /// The plastering plan carried out.
    fn plan(&self) -> Option<&Plan> {
        None
    }

    /// How far the plastering plan is carried out, as task `index`.
    fn coverage(&self, _index: usize) -> Option<PlasterCoverage> {
        None
    }

    /// The camera on the spray tool is looking along a wall: its profiles
    /// are to be searched for windows now.
    fn tool_look(&self) -> bool {
        false
    }

    /// A copy of the task.
    fn clone_box(&self) -> Box<dyn Task>;
}

impl Clone for Box<dyn Task> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

impl TaskSpec {
    /// The task this spec describes, not started.
    pub fn build(&self) -> Box<dyn Task> {
        match self.clone() {
            TaskSpec::MapRoom {
                path,
                walls,
                min_sightings,
                speed_mps,
                max_size_sigma_m,
                timeout_s,
                on_loose_size,
            } => Box::new(survey::MapRoom::new(
                path,
                walls,
                min_sightings,
                speed_mps,
                max_size_sigma_m,
                timeout_s,
                on_loose_size,
            )),
            TaskSpec::Localize {
                max_sigma_m,
                timeout_s,
            } => Box::new(localize::Localize::new(max_sigma_m, timeout_s)),
            TaskSpec::MoveRelative {
                dx_m,
                dy_m,
                dtheta_deg,
                landmark,
                speed_mps,
            } => Box::new(motion::MoveRelative::new(
                [dx_m, dy_m, dtheta_deg],
                landmark,
                speed_mps,
            )),
            TaskSpec::AlignToWall {
                wall,
                standoff_m,
                at_m,
                side,
                speed_mps,
            } => Box::new(wall::AlignToWall::new(
                wall, standoff_m, at_m, side, speed_mps,
            )),
            TaskSpec::FollowWall {
                wall,
                standoff_m,
                from_m,
                to_m,
                speed_mps,
            } => Box::new(wall::FollowWall::new(
                wall,
                standoff_m,
                [from_m, to_m],
                speed_mps,
            )),
            TaskSpec::PassDoor {
                door,
                approach_m,
                beyond_m,
                speed_mps,
            } => Box::new(door::DoorTask::pass_door(
                door,
                [approach_m, beyond_m, speed_mps],
            )),
            TaskSpec::GoToRoom {
                room,
                approach_m,
                beyond_m,
                speed_mps,
            } => Box::new(door::DoorTask::go_to_room(
                room,
                [approach_m, beyond_m, speed_mps],
            )),
            TaskSpec::Plaster {
                walls,
                ceiling,
                speed_mps,
                settle_s,
                survey,
                survey_speed_mps,
                region,
                spray,
                // Expanded at load into a task a room (`Mission::parse`).
                rooms: _,
            } => Box::new(plaster::Plaster::new(plaster::PlasterSpec {
                walls,
                ceiling,
                speed_mps,
                settle_s,
                survey,
                survey_speed_mps,
                region,
                spray,
            })),
            TaskSpec::WaitForOperator {
                prompt,
                timeout_s,
                on_timeout,
            } => Box::new(wait::WaitForOperator::new(prompt, timeout_s, on_timeout)),
        }
    }
}

/// Radius the body sweeps turning on the spot, with a margin for what
/// stands out of a wall (a radiator, a sill), m.
pub(crate) fn pivot_clearance(config: &ExecutiveConfig) -> f64 {
    let v = &config.vehicle;
    v.front_m().hypot(0.5 * v.width_m) + 0.2
}

/// A task's behaviours: the one under way and those queued after it.
#[derive(Clone, Debug, Default)]
pub(crate) struct Behaviours {
    pub queue: VecDeque<Behaviour>,
    pub current: Option<Behaviour>,
}

impl Behaviours {
    /// The command of the behaviour under way (the next ones started as
    /// each ends), or `None` when the queue is done.
    pub fn step(&mut self, cx: &mut TaskCx<'_>) -> Option<DriveCommand> {
        loop {
            if self.current.is_none() {
                let next = self.queue.pop_front()?;
                let at = |p: &Pose2, theta: f64| Some([p.x, p.y, theta.to_degrees()]);
                let goal = match *next.kind() {
                    BehaviourKind::Regulate { goal } | BehaviourKind::Reverse { goal } => {
                        at(&goal, goal.theta)
                    }
                    BehaviourKind::Pivot { heading_rad, .. } => at(&cx.est.pose, heading_rad),
                    _ => None,
                };
                cx.emit(EventKind::BehaviourStarted {
                    task: cx.index,
                    behaviour: next.name().to_owned(),
                    goal,
                });
                self.current = Some(next);
            }
            let b = self.current.as_mut()?;
            match b.step(cx.now, cx.est, &cx.config.vehicle) {
                Step::Drive(cmd) => return Some(cmd),
                Step::Done => self.current = None,
            }
        }
    }

    /// Nothing under way and nothing queued.
    pub fn idle(&self) -> bool {
        self.current.is_none() && self.queue.is_empty()
    }

    /// `way` in place of what was queued and under way.
    pub fn replace(&mut self, way: impl Into<VecDeque<Behaviour>>) {
        self.queue = way.into();
        self.current = None;
    }

    /// The behaviour under way.
    pub fn kind(&self) -> Option<&BehaviourKind> {
        self.current.as_ref().map(Behaviour::kind)
    }
}

/// Steps `ways`: a motion task ends with its last behaviour.
pub(crate) fn drive_through(ways: &mut Behaviours, cx: &mut TaskCx<'_>) -> TaskStep {
    match ways.step(cx) {
        Some(cmd) => TaskStep::Drive(cmd),
        None => TaskStep::Done,
    }
}
