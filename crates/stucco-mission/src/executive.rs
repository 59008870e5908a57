//! The layered executive: mission → task → behaviour → control law, stepped
//! by `tick(now, inputs) -> outputs`, with the safety supervisor over every
//! layer.

use crate::behaviour::{Behaviour, BehaviourKind, Step, go_to};
use crate::floor::FloorPlan;
use crate::manoeuvre::{self, Space};
use crate::model::{DoorEstimate, Estimate, WallGeometry, pose_at_wall};
use crate::plaster::{Cursor, Phase, PlasterCoverage, PlasterProgress, PlasterRun, plan_digest};
use crate::route::{Floor, route};
use crate::supervisor::{Hazard, LinkLossPolicy, LostPolicy, SafetyConfig, Supervisor};
use crate::task::{OnTimeout, TaskSpec, WallName};
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};
use stucco_control::GainSchedule;
use stucco_core::{
    Ack, Command, DriveCommand, Pose2, Reply, Stamp, Telecommand, ToolCommand, VehicleSpec,
    wrap_angle,
};
use stucco_plan::{OpeningKind, Plan, RoomModel, SprayTool, SurfaceId, WallOpening};

/// Spraying time between checkpoints within a stroke, s.
const CHECKPOINT_SPRAY_S: f64 = 1.0;
/// Time the nozzle is given past its travel to be at a pass's first point,
/// s (a few control periods).
const NOZZLE_SETTLE_S: f64 = 0.1;
/// Heading off a station the gantry's geometry takes without a second
/// approach, rad (2°).
const HEADING_SPARE_RAD: f64 = 0.035;
/// How far a robot turned on its station backs off to come on again, m.
const REALIGN_M: f64 = 1.0;
/// An opening whose bottom the camera finds this near the floor is a
/// door, m.
const DOOR_SILL_M: f64 = 0.1;

/// Lowest height on the wall the aim runs at while the tool's camera
/// looks, m: its fan (35° below the horizontal to straight up) meets the
/// wall from 20 cm under it to the ceiling, past every sill above 0.6 m.
/// Behind furniture the look runs where the strokes start, above it.
const LOOK_HEIGHT_M: f64 = 0.8;
/// Speed of the aim along the wall while the tool's camera looks, m/s
/// (the axes' fastest): a profile every 2.5 cm at 20 a second, a window's
/// edge placed within half that.
const LOOK_SPEED_MPS: f64 = 0.5;
/// How far past what a station's passes reach on its wall the look runs
/// (as far as the rail goes), m.
const LOOK_SPARE_M: f64 = 0.15;

/// Where the nozzle waits while the robot drives, robot frame, m: over
/// the body.
pub const PARK_NOZZLE_M: [f64; 3] = [0.3, 0.0, 1.2];

/// Run-in along the wall before a pass starts, m: the line law's distance
/// to settle on the standoff from where the robot could turn (the offset
/// falls by e every ~0.4 m at a wall-following speed).
const RUN_IN_M: f64 = 2.0;
/// The shortest run-in accepted near a corner, m (a 0.3 m offset settles
/// to about a centimetre).
const MIN_RUN_IN_M: f64 = 1.5;
/// A robot this near a door's line and this near its heading is on it,
/// m and rad.
const ON_LINE_M: f64 = 0.03;
const ON_LINE_RAD: f64 = 0.05;
/// How far beyond a door's wall line a robot backing through it stops
/// with its laser, m: through a wall's thickness and the laser's shortest
/// range.
const BACKED_LASER_BEYOND_M: f64 = 0.5;
/// Seconds blocked on the way to a door before the way is planned again.
const REPLAN_AFTER_S: f64 = 2.0;
/// Times the way to one door may be planned again.
const MAX_REPLANS: usize = 3;
/// Room left between the body and the far wall at a door's approach and
/// beyond it, m (the apartment's missions set the protective field's
/// margin to 3 cm; a mission with a longer field may be stopped there).
const DOOR_FIT_M: f64 = 0.1;

/// What the operator (or a script standing in for one) asks of the
/// executive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OperatorCommand {
    /// Stop where you are and wait.
    Pause,
    /// Go on after a pause or a released e-stop.
    Resume,
    /// Give the mission up.
    Abort,
    /// Give the current task up and go on with the next.
    Skip,
    /// The answer a `wait_for_operator` task waits for.
    Continue,
}

/// The mission's state.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum MissionMode {
    /// Carrying out its tasks.
    Running,
    /// Stopped by the operator or a fault, waiting for `resume`.
    Paused {
        /// Why.
        reason: String,
    },
    /// Stopped by the e-stop; waits for its release and `resume`.
    EStopped,
    /// Every task done or skipped.
    Done,
    /// A task failed.
    Failed {
        /// Why.
        reason: String,
    },
    /// Given up by the operator.
    Aborted,
}

impl MissionMode {
    /// True once the mission is over.
    pub fn is_final(&self) -> bool {
        matches!(
            self,
            MissionMode::Done | MissionMode::Failed { .. } | MissionMode::Aborted
        )
    }
}

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

/// Something that happened, for the event log.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Event {
    /// When.
    pub stamp: Stamp,
    /// What.
    #[serde(flatten)]
    pub kind: EventKind,
}

/// The kinds of events.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum EventKind {
    /// The mission began (or resumed from a checkpoint at `first_task`).
    MissionStarted {
        /// Tasks in all.
        tasks: usize,
        /// The first task to carry out.
        first_task: usize,
    },
    /// A task began.
    TaskStarted {
        /// Its index.
        task: usize,
        /// Its name.
        name: String,
    },
    /// A behaviour began.
    BehaviourStarted {
        /// The task.
        task: usize,
        /// The behaviour's name.
        behaviour: String,
    },
    /// A task finished.
    TaskDone {
        /// Its index.
        task: usize,
    },
    /// A task was skipped.
    TaskSkipped {
        /// Its index.
        task: usize,
    },
    /// A task failed.
    TaskFailed {
        /// Its index.
        task: usize,
        /// Why.
        reason: String,
    },
    /// The operator was asked something.
    OperatorPrompt {
        /// The task.
        task: usize,
        /// The question.
        prompt: String,
    },
    /// The mission paused.
    Paused {
        /// Why.
        reason: String,
    },
    /// The mission resumed.
    Resumed,
    /// The e-stop was pressed.
    EStop,
    /// The supervisor stopped the robot.
    SafetyStop {
        /// What for.
        hazard: Hazard,
    },
    /// The supervisor let it go on.
    SafetyClear,
    /// The operator gave the mission up.
    Aborted,
    /// Every task done or skipped.
    MissionDone,
    /// The mission failed.
    MissionFailed {
        /// Why.
        reason: String,
    },
    /// The operator's heartbeat stopped.
    LinkLost,
    /// It came back.
    LinkRestored,
    /// The robot stands at a plastering station and starts spraying.
    StationStarted {
        /// The task.
        task: usize,
        /// The station's index in the plan.
        station: usize,
        /// Stations in the plan.
        stations: usize,
        /// Where the robot stands from the station's pose (forward, left),
        /// m.
        offset_m: [f64; 2],
        /// Its heading from the station's, rad.
        heading_off_rad: f64,
    },
    /// A plastering survey looks again at a window's edge it bracketed
    /// loosely: the body's camera swept slowly across it.
    WindowEdgeLook {
        /// The task.
        task: usize,
        /// The wall.
        wall: WallName,
        /// Where the edge was, along the wall, m.
        along_m: f64,
        /// How uncertain it was, m (standard deviation).
        sigma_m: f64,
    },
    /// The camera on the tool found a window the plan did not know, at a
    /// station: the plan keeps it out of the coat from that station on.
    WindowFound {
        /// The task.
        task: usize,
        /// The station.
        station: usize,
        /// The wall.
        wall: String,
        /// Its edges along the wall, m.
        along_m: [f64; 2],
        /// Its sill and head, m.
        sill_head_m: [f64; 2],
    },
    /// No way to a plastering station keeps the body clear (a hall too
    /// narrow to turn across): the station is left out of the plan, and
    /// what only it reached is reported unreachable.
    StationGivenUp {
        /// The task.
        task: usize,
        /// The station's index in the plan before it was left out.
        station: usize,
        /// Plasterable area lost with it, m².
        unreachable_m2: f64,
    },
    /// A surface's pass at a station is sprayed.
    PassDone {
        /// The task.
        task: usize,
        /// The station.
        station: usize,
        /// The surface.
        surface: String,
    },
    /// The robot went through a door of the floor plan and its frame is
    /// now the room beyond it.
    RoomEntered {
        /// The door of the plan.
        door: usize,
        /// The room, by its name on the plan.
        room: String,
    },
    /// A plastering plan was made (again, after a survey).
    PlanMade {
        /// The task.
        task: usize,
        /// Its stations.
        stations: usize,
        /// Plasterable area it cannot reach, m².
        unreachable_m2: f64,
    },
    /// An operator command could not be followed.
    CommandRefused {
        /// The command.
        command: OperatorCommand,
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
    queue: VecDeque<Behaviour>,
    current: Option<Behaviour>,
    /// A `map_room` loop driven corner to corner.
    legs: Option<Legs>,
    /// Seconds the way has been blocked.
    blocked_s: f64,
    /// A `plaster` task's plan and where it is in it.
    plaster: Option<PlasterRun>,
    /// A way through doors of the floor plan (`go_to_room`, or a
    /// `pass_door` through a door the plan has).
    doorway: Option<Doorway>,
    /// A plastering survey has looked again at the window edges it
    /// bracketed loosely.
    edges_looked_at: bool,
}

/// A loop driven corner to corner (a `map_room`'s, or a plastering
/// survey's where the room is too small to turn its corners on the move),
/// each leg planned as it starts, on what the laser has found on the floor
/// by then.
#[derive(Clone, Debug)]
struct Legs {
    corners: Vec<[f64; 2]>,
    /// A survey's loop: its corners are fitted again, as each leg starts,
    /// to what the laser has found on the floor by then (a column in a
    /// corner seen only once the loop is under way), with the margins and
    /// the body's reach of `survey_rect`. None: a mission's own corners.
    refit: Option<([f64; 2], [f64; 2])>,
    /// Legs to drive in all; none: round and round until the task ends.
    count: Option<usize>,
    /// The leg under way (the first to the first corner); none before it.
    under_way: Option<usize>,
    /// Times the leg under way was planned again.
    replans: usize,
    /// Legs in a row that no clear way reached.
    unreached: usize,
    speed_mps: f64,
}

impl Legs {
    fn new(corners: Vec<[f64; 2]>, count: Option<usize>, speed_mps: f64) -> Legs {
        Legs {
            corners,
            refit: None,
            count,
            under_way: None,
            replans: 0,
            unreached: 0,
            speed_mps,
        }
    }

    /// True when no clear way reached any corner the last time round.
    fn stuck(&self) -> bool {
        self.unreached >= self.corners.len().max(1)
    }

    /// The next leg's way from where the robot stands; `None` when every
    /// leg is driven. A corner no clear way reaches is left out (an
    /// empty way).
    fn next(&mut self, config: &ExecutiveConfig, est: &Estimate) -> Option<Vec<Behaviour>> {
        let next = self.under_way.map_or(0, |k| k + 1);
        if self.count.is_some_and(|c| next >= c) {
            return None;
        }
        self.under_way = Some(next);
        self.replans = 0;
        if let Some((margins, half)) = self.refit
            && let Some(corners) = survey_rect(est, margins, half, SURVEY_LEGS_MIN_M)
        {
            self.corners = corners.to_vec();
        }
        let way = self.leg(config, est, next);
        self.unreached = if way.is_empty() {
            self.unreached + 1
        } else {
            0
        };
        Some(way)
    }

    /// The leg under way planned again (something the map did not hold
    /// blocks it), at most `MAX_REPLANS` times.
    fn again(&mut self, config: &ExecutiveConfig, est: &Estimate) -> Option<Vec<Behaviour>> {
        let k = self.under_way?;
        (self.replans < MAX_REPLANS).then(|| {
            self.replans += 1;
            self.leg(config, est, k)
        })
    }

    /// Leg `leg`: to corner `leg` (modulo their number), arriving faced to
    /// the next, by the planned way.
    fn leg(&self, config: &ExecutiveConfig, est: &Estimate, leg: usize) -> Vec<Behaviour> {
        let n = self.corners.len();
        if n == 0 {
            return Vec::new();
        }
        let (a, b) = (self.corners[leg % n], self.corners[(leg + 1) % n]);
        let goal = Pose2::new(a[0], a[1], (b[1] - a[1]).atan2(b[0] - a[0]));
        planned_way(config, est, &est.pose, &goal, self.speed_mps).map_or_else(Vec::new, |w| w.1)
    }
}

/// A task's way through doors of the floor plan, one at a time.
#[derive(Clone, Debug)]
struct Doorway {
    /// The door being driven through.
    through: Option<usize>,
    /// The doors after it.
    hops: VecDeque<usize>,
    /// The room the robot was said to have entered, until the estimate
    /// is in it.
    entering: Option<usize>,
    /// The door it went through last.
    passed: Option<usize>,
    approach_m: f64,
    beyond_m: f64,
    speed_mps: f64,
    /// Times the way to the door was planned again.
    replans: usize,
}

impl Doorway {
    /// Through `door` first, then `hops`, each passage from `approach_m`
    /// before to `beyond_m` beyond at `speed_mps`.
    fn through(
        door: usize,
        hops: VecDeque<usize>,
        [approach_m, beyond_m, speed_mps]: [f64; 3],
    ) -> Self {
        Doorway {
            through: Some(door),
            hops,
            entering: None,
            passed: None,
            approach_m,
            beyond_m,
            speed_mps,
            replans: 0,
        }
    }
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
    continue_asked: bool,
    /// True for the tasks of the mission file (a checkpoint keeps those),
    /// false for the operator's.
    scripted: Vec<bool>,
    /// The last reply to every telecommand taken: a retry gets it again.
    replies: BTreeMap<String, Reply>,
    /// Operator tasks by index, and the telecommand each answers.
    waiting: BTreeMap<usize, String>,
    /// Direct driving until a deadline, for a telecommand.
    jog: Option<(DriveCommand, Stamp, String)>,
    /// Whether the operator's link is up (none: no operator yet).
    link_up: Option<bool>,
    acks: Vec<Ack>,
    /// The spray tool's command.
    tool: ToolCommand,
    /// Seconds since the last tick.
    dt: f64,
    /// A stroke was finished this tick: the progress should be written.
    stroke_done: bool,
    /// A checkpoint's plastering progress and the plan beside it, for the
    /// `plaster` task to take up.
    resume_plaster: Option<(PlasterProgress, Option<Plan>)>,
    /// The door of the plan the robot has just gone through.
    enter_room: Option<usize>,
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
            continue_asked: false,
            scripted: vec![true; n],
            replies: BTreeMap::new(),
            waiting: BTreeMap::new(),
            jog: None,
            link_up: None,
            acks: Vec::new(),
            tool: ToolCommand {
                nozzle_m: PARK_NOZZLE_M,
                ..ToolCommand::default()
            },
            dt: 0.0,
            stroke_done: false,
            resume_plaster: None,
            enter_room: None,
        }
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
                Reply::Failed {
                    reason: "the operator's link was lost".to_owned(),
                },
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
            let plan = self.resume_plaster.take().and_then(|(_, plan)| plan);
            self.resume_plaster = Some((p.clone(), plan));
        }
        Ok(())
    }

    /// Hands over the plan a checkpoint's `plaster` task was carrying out
    /// (kept beside the checkpoint): the task takes it up from its cursor.
    pub fn resume_plan(&mut self, plan: Plan) {
        match &mut self.resume_plaster {
            Some((_, p)) => *p = Some(plan),
            None => {
                self.resume_plaster = Some((
                    PlasterProgress {
                        task: usize::MAX,
                        cursor: Cursor::default(),
                        in_move_s: 0.0,
                        plan_digest: String::new(),
                    },
                    Some(plan),
                ))
            }
        }
    }

    /// The plan of the `plaster` task under way.
    pub fn plaster_plan(&self) -> Option<&Plan> {
        self.active
            .as_ref()
            .and_then(|a| a.plaster.as_ref())
            .map(|r| &r.plan)
    }

    /// How far the `plaster` task under way has got over its plan.
    pub fn coverage(&self) -> Option<PlasterCoverage> {
        let a = self.active.as_ref()?;
        a.plaster.as_ref().map(|r| r.coverage(a.index))
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
            plaster: self.active.as_ref().and_then(|a| {
                a.plaster.as_ref().map(|r| PlasterProgress {
                    task: a.index,
                    cursor: r.cursor,
                    in_move_s: match r.phase {
                        Phase::Spraying { in_move_s } => in_move_s,
                        _ => r.resume_s,
                    },
                    plan_digest: r.digest.clone(),
                })
            }),
        }
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
        self.active
            .as_ref()
            .and_then(|a| a.current.as_ref())
            .map(Behaviour::kind)
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
            if self.config.unattended {
                self.fail(now, "e-stop pressed".to_owned());
                checkpoint_due = true;
            } else {
                self.mode = MissionMode::EStopped;
            }
        }
        if inputs.bumper && self.mode == MissionMode::Running {
            if self.config.unattended {
                self.fail(now, "bumper: the robot touched something".to_owned());
                checkpoint_due = true;
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
        if self.mode == MissionMode::Running {
            let (cmd, unit_done) = match &self.jog {
                // Jogging holds the task where it is.
                Some((cmd, _, _)) => (*cmd, false),
                None => self.run(now, inputs.estimate),
            };
            checkpoint_due |= unit_done | std::mem::take(&mut self.stroke_done);
            drive = self.supervise(now, cmd, inputs, dt, &mut checkpoint_due);
        } else {
            // Standing (done, paused, waiting for an e-stop's release):
            // what the supervisor holds the robot for is still told as it
            // changes — a hold that has gone is cleared — with no timers
            // run (a lost estimate fails nothing that is not running).
            let verdict =
                self.supervisor
                    .check(DriveCommand::STOP, inputs.obstacles, inputs.estimate, dt);
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
        let tool = if spraying { self.tool } else { self.tool.off() };
        let tool_look = self
            .active
            .as_ref()
            .and_then(|a| a.plaster.as_ref())
            .is_some_and(|r| matches!(r.phase, Phase::Looking { left_s, .. } if left_s == 0.0));
        Outputs {
            drive,
            tool,
            events: std::mem::take(&mut self.events),
            checkpoint_due,
            acks: std::mem::take(&mut self.acks),
            enter_room: self.enter_room.take(),
            tool_look,
        }
    }

    /// Takes telecommands between ticks (as soon as they arrive) and
    /// returns the replies: acceptance never waits for the next control
    /// period. The effects (a stop, a queued task, a jog) show in the next
    /// tick's command.
    pub fn telecommands(&mut self, now: Stamp, cmds: &[Telecommand], est: &Estimate) -> Vec<Ack> {
        for t in cmds {
            self.telecommand(now, t, est);
        }
        std::mem::take(&mut self.acks)
    }

    /// Follows an operator command: whether the progress changed, or why
    /// it cannot be followed.
    fn operator(&mut self, now: Stamp, cmd: OperatorCommand) -> Result<bool, String> {
        let result = self.follow(now, cmd);
        if let Err(reason) = &result {
            self.emit(
                now,
                EventKind::CommandRefused {
                    command: cmd,
                    reason: reason.clone(),
                },
            );
        }
        result
    }

    fn follow(&mut self, now: Stamp, cmd: OperatorCommand) -> Result<bool, String> {
        if self.mode.is_final() {
            return Err("the mission is over".to_owned());
        }
        match cmd {
            OperatorCommand::Pause => {
                if self.mode != MissionMode::Running {
                    return Err("not running".to_owned());
                }
                self.pause(now, "operator".to_owned());
                Ok(false)
            }
            OperatorCommand::Resume => match self.mode {
                MissionMode::Paused { .. } | MissionMode::EStopped => {
                    self.mode = MissionMode::Running;
                    self.emit(now, EventKind::Resumed);
                    Ok(false)
                }
                _ => Err("not paused".to_owned()),
            },
            OperatorCommand::Abort => {
                if let Some(a) = self.active.take() {
                    self.status[a.index] = TaskStatus::Pending;
                    self.answer(
                        now,
                        a.index,
                        Reply::Failed {
                            reason: "the mission was aborted".to_owned(),
                        },
                    );
                }
                self.mode = MissionMode::Aborted;
                self.emit(now, EventKind::Aborted);
                Ok(true)
            }
            OperatorCommand::Skip => {
                let Some(a) = self.active.take() else {
                    return Err("no task under way".to_owned());
                };
                self.status[a.index] = TaskStatus::Skipped;
                self.emit(now, EventKind::TaskSkipped { task: a.index });
                self.answer(
                    now,
                    a.index,
                    Reply::Failed {
                        reason: "skipped".to_owned(),
                    },
                );
                Ok(true)
            }
            OperatorCommand::Continue => {
                let waiting = self.active.as_ref().is_some_and(|a| {
                    matches!(self.tasks[a.index], TaskSpec::WaitForOperator { .. })
                });
                if !waiting {
                    return Err("no task is waiting for the operator".to_owned());
                }
                self.continue_asked = true;
                Ok(false)
            }
        }
    }

    /// Sends `reply` to telecommand `id` (and keeps it for retries).
    fn reply(&mut self, now: Stamp, id: &str, reply: Reply) {
        self.replies.insert(id.to_owned(), reply.clone());
        self.acks.push(Ack {
            id: id.to_owned(),
            stamp: now,
            reply,
        });
    }

    /// Answers the telecommand behind operator task `index`, if any.
    fn answer(&mut self, now: Stamp, index: usize, reply: Reply) {
        if let Some(id) = self.waiting.remove(&index) {
            self.reply(now, &id, reply);
        }
    }

    /// Takes a telecommand: a retry gets the last reply again and is not
    /// carried out twice; a stale one is refused; `stop` acts at once.
    fn telecommand(&mut self, now: Stamp, t: &Telecommand, est: &Estimate) {
        if let Some(last) = self.replies.get(&t.id).cloned() {
            self.acks.push(Ack {
                id: t.id.clone(),
                stamp: now,
                reply: last,
            });
            return;
        }
        if now > t.deadline {
            let late = now.seconds_since(t.deadline);
            self.reply(
                now,
                &t.id,
                Reply::Rejected {
                    reason: format!("stale: {late:.3} s past its deadline"),
                },
            );
            return;
        }
        let follow = |s: &mut Self, cmd: OperatorCommand| match s.operator(now, cmd) {
            Ok(_) => Reply::Done,
            Err(reason) => Reply::Rejected { reason },
        };
        let reply = match &t.command {
            Command::Stop => {
                self.jog = None;
                if !self.mode.is_final() && self.mode == MissionMode::Running {
                    self.pause(now, format!("stop from {}", t.operator));
                }
                Reply::Done
            }
            Command::Status => Reply::Done,
            Command::Pause => follow(self, OperatorCommand::Pause),
            Command::Resume => follow(self, OperatorCommand::Resume),
            Command::Abort => follow(self, OperatorCommand::Abort),
            Command::Skip => follow(self, OperatorCommand::Skip),
            Command::Continue => follow(self, OperatorCommand::Continue),
            Command::Jog {
                speed_mps,
                steer_rad,
                ttl_s,
            } => {
                let v = &self.config.vehicle;
                if self.mode.is_final() {
                    Reply::Rejected {
                        reason: "the mission is over".to_owned(),
                    }
                } else if !(ttl_s.is_finite() && *ttl_s > 0.0 && *ttl_s <= 2.0) {
                    Reply::Rejected {
                        reason: "ttl_s: more than 0 and at most 2 s".to_owned(),
                    }
                } else if !(speed_mps.abs() <= v.max_speed_mps
                    && steer_rad.abs() <= v.max_steer_rad)
                {
                    Reply::Rejected {
                        reason: "speed or steering beyond the robot's limits".to_owned(),
                    }
                } else {
                    // A newer jog takes over an older one.
                    if let Some((_, _, old)) = self.jog.take() {
                        self.reply(now, &old, Reply::Done);
                    }
                    let drive = DriveCommand {
                        speed_mps: *speed_mps,
                        steer_rad: *steer_rad,
                    };
                    self.jog = Some((drive, now.offset_secs(*ttl_s), t.id.clone()));
                    Reply::Accepted
                }
            }
            task => match TaskSpec::from_command(task) {
                None => Reply::Rejected {
                    reason: "not a task".to_owned(),
                },
                Some(spec) => self.accept_task(t, spec, est),
            },
        };
        self.reply(now, &t.id, reply);
    }

    /// Queues an operator's task to run next, or says why it cannot run.
    fn accept_task(&mut self, t: &Telecommand, spec: TaskSpec, est: &Estimate) -> Reply {
        if matches!(self.mode, MissionMode::Failed { .. } | MissionMode::Aborted) {
            return Reply::Rejected {
                reason: "the mission is over".to_owned(),
            };
        }
        if let Some((key, why)) = spec.invalid() {
            return Reply::Rejected {
                reason: format!("{key}: {why}"),
            };
        }
        if matches!(spec, TaskSpec::Plaster { .. }) && self.config.spray.is_none() {
            return Reply::Rejected {
                reason: "this robot carries no spray tool (the mission has no [spray])".to_owned(),
            };
        }
        if let TaskSpec::PassDoor { door, .. } = spec
            && door >= est.doors.len()
        {
            return Reply::Rejected {
                reason: format!("door {door} is not known ({} found)", est.doors.len()),
            };
        }
        if let TaskSpec::GoToRoom { room, .. } = &spec
            && let Err(reason) = self.route(room, est)
        {
            return Reply::Rejected { reason };
        }
        // Next after the task under way; a task waiting for the operator
        // has its answer.
        let at = match &self.active {
            Some(a) => {
                if matches!(self.tasks[a.index], TaskSpec::WaitForOperator { .. }) {
                    self.continue_asked = true;
                }
                a.index + 1
            }
            None => self
                .status
                .iter()
                .position(|s| *s == TaskStatus::Pending)
                .unwrap_or(self.tasks.len()),
        };
        self.tasks.insert(at, spec);
        self.status.insert(at, TaskStatus::Pending);
        self.scripted.insert(at, false);
        self.waiting = std::mem::take(&mut self.waiting)
            .into_iter()
            .map(|(i, id)| (if i >= at { i + 1 } else { i }, id))
            .collect();
        self.waiting.insert(at, t.id.clone());
        // Work done so far does not end the robot's day: a new task
        // reopens the mission.
        if self.mode == MissionMode::Done {
            self.mode = MissionMode::Running;
        }
        Reply::Accepted
    }

    fn pause(&mut self, now: Stamp, reason: String) {
        self.mode = MissionMode::Paused {
            reason: reason.clone(),
        };
        self.emit(now, EventKind::Paused { reason });
    }

    fn fail(&mut self, now: Stamp, reason: String) {
        if let Some(a) = self.active.take() {
            self.status[a.index] = TaskStatus::Failed {
                reason: reason.clone(),
            };
            self.answer(
                now,
                a.index,
                Reply::Failed {
                    reason: reason.clone(),
                },
            );
            self.emit(
                now,
                EventKind::TaskFailed {
                    task: a.index,
                    reason: reason.clone(),
                },
            );
        }
        self.mode = MissionMode::Failed {
            reason: reason.clone(),
        };
        self.emit(now, EventKind::MissionFailed { reason });
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

    /// The supervisor over the task's command.
    fn supervise(
        &mut self,
        now: Stamp,
        cmd: DriveCommand,
        inputs: &Inputs,
        dt: f64,
        checkpoint_due: &mut bool,
    ) -> DriveCommand {
        let verdict = self
            .supervisor
            .check(cmd, inputs.obstacles, inputs.estimate, dt);
        self.note_hazard(now, verdict.hazard);
        let safety = self.config.safety.clone();
        let clearance = self.pivot_clearance();
        match verdict.hazard {
            Some(Hazard::Lost) => {
                let since = *self.lost_since.get_or_insert(now);
                if safety.on_lost == LostPolicy::Fail
                    || now.seconds_since(since) > safety.lost_timeout_s
                {
                    self.fail(now, "the pose estimate is lost".to_owned());
                    *checkpoint_due = true;
                }
            }
            Some(Hazard::Obstacle) => {
                self.lost_since = None;
                if let Some(a) = self.active.as_mut() {
                    a.blocked_s += dt;
                    // On the way to a door, something the room's map did
                    // not hold when the way was planned (furniture first
                    // seen from the doorway): the way is planned again on
                    // what the map holds now.
                    if a.blocked_s > REPLAN_AFTER_S
                        && !a.queue.is_empty()
                        && let Some(w) = a.doorway.as_mut()
                        && w.entering.is_none()
                        && w.replans < MAX_REPLANS
                        && let Some(door) = w.through
                        && let Ok(q) = plan_door_pass(
                            &self.config,
                            inputs.estimate,
                            door,
                            [w.approach_m, w.beyond_m],
                            w.speed_mps,
                        )
                    {
                        w.replans += 1;
                        a.queue = q.into();
                        a.current = None;
                        a.blocked_s = 0.0;
                    }
                    // So on a leg of a loop driven corner to corner.
                    if a.blocked_s > REPLAN_AFTER_S
                        && let Some(legs) = a.legs.as_mut()
                        && let Some(q) = legs.again(&self.config, inputs.estimate)
                    {
                        a.queue = q.into();
                        a.current = None;
                        a.blocked_s = 0.0;
                    }
                    // A plastering survey's loop turned on the move that
                    // something blocks (it runs near the furniture it goes
                    // round): the survey goes on corner to corner from the
                    // end of the side it was on (the legs' sides are the
                    // loop's, in the same order), each leg the planned way
                    // round what the map holds.
                    if a.blocked_s > SURVEY_BLOCKED_S
                        && a.legs.is_none()
                        && a.plaster
                            .as_ref()
                            .is_some_and(|r| matches!(r.phase, Phase::Surveying))
                        && let TaskSpec::Plaster {
                            survey_speed_mps, ..
                        } = self.tasks[a.index]
                        && let Some(mut legs) =
                            survey_legs(&self.config.vehicle, inputs.estimate, survey_speed_mps)
                    {
                        legs.under_way = match a.current.as_ref().map(Behaviour::kind) {
                            Some(BehaviourKind::Path { segment, .. }) => Some(*segment),
                            _ => None,
                        };
                        a.legs = Some(legs);
                        a.queue.clear();
                        a.current = None;
                        a.blocked_s = 0.0;
                    }
                    // On the way to a plastering station that no way
                    // was found clear to (a hall too narrow to turn
                    // across): the station is given up, what only it
                    // reached reported unreachable, and the way to the
                    // next one planned.
                    if a.blocked_s > REPLAN_AFTER_S
                        && let TaskSpec::Plaster { speed_mps, .. } = self.tasks[a.index]
                        && let Some(run) = a.plaster.as_mut()
                        && matches!(run.phase, Phase::Moving)
                        && run.way_unchecked
                    {
                        let station = run.cursor.station;
                        if let Some(lost) = run.give_up_station() {
                            self.events.push(Event {
                                stamp: now,
                                kind: EventKind::StationGivenUp {
                                    task: a.index,
                                    station,
                                    unreachable_m2: lost,
                                },
                            });
                        }
                        let from = inputs.estimate.pose;
                        a.queue =
                            next_station_way(&self.config, clearance, run, &from, speed_mps).into();
                        // None left: the task ends where the robot
                        // stands, and the next task's way starts there.
                        if run.finished() {
                            run.phase = Phase::Leaving;
                        }
                        a.current = None;
                        a.blocked_s = 0.0;
                        // The plan on disk and the checkpoint's cursor
                        // must name the same stations.
                        *checkpoint_due = true;
                    }
                    if a.blocked_s > safety.blocked_timeout_s {
                        self.fail(now, "the way stayed blocked".to_owned());
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
                let Some(next) = self.status.iter().position(|s| *s == TaskStatus::Pending) else {
                    self.mode = MissionMode::Done;
                    self.emit(now, EventKind::MissionDone);
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
                    Err(reason) => {
                        self.status[next] = TaskStatus::Active;
                        self.active = Some(ActiveTask {
                            index: next,
                            started: now,
                            queue: VecDeque::new(),
                            current: None,
                            legs: None,
                            blocked_s: 0.0,
                            plaster: None,
                            doorway: None,
                            edges_looked_at: false,
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

    /// Plans task `index` from the estimate.
    fn start(&mut self, now: Stamp, index: usize, est: &Estimate) -> Result<ActiveTask, String> {
        let clearance = self.pivot_clearance();
        let pose = est.pose;
        let mut queue = VecDeque::new();
        let mut plaster = None;
        let mut doorway = None;
        let mut legs = None;
        if let TaskSpec::Plaster {
            walls,
            ceiling,
            speed_mps,
            survey,
            survey_speed_mps,
            region,
            ..
        } = self.tasks[index].clone()
        {
            let resumed = self
                .resume_plaster
                .as_ref()
                .is_some_and(|(p, _)| p.task == index);
            let mut run = self.plaster_run(index, &walls, ceiling, region.as_ref(), est)?;
            self.emit(
                now,
                EventKind::PlanMade {
                    task: index,
                    stations: run.plan.stations.len(),
                    unreachable_m2: run.plan.unreachable_m2(),
                },
            );
            if survey && !resumed {
                let (way, corner_to_corner) =
                    survey_way(&self.config, clearance, est, survey_speed_mps);
                queue.extend(way);
                legs = corner_to_corner;
                run.phase = Phase::Surveying;
            } else {
                queue.extend(next_station_way(
                    &self.config,
                    clearance,
                    &mut run,
                    &pose,
                    speed_mps,
                ));
            }
            plaster = Some(run);
        }
        let gains = &self.config.gains;
        match &self.tasks[index] {
            TaskSpec::Plaster { .. } => {}
            TaskSpec::MapRoom {
                path,
                inset_m,
                speed_mps,
                ..
            } => {
                let corners = survey_loop(path.as_deref(), *inset_m, est.room_m)?;
                if turns_on_the_move(&corners, est.room_m, &self.config.vehicle) {
                    let loop_ = closed(&corners);
                    let (a, b) = (loop_[0], loop_[1]);
                    let towards = (b[1] - a[1]).atan2(b[0] - a[0]);
                    queue.extend(way(
                        &self.config,
                        est,
                        &pose,
                        &Pose2::new(a[0], a[1], towards),
                        *speed_mps,
                    ));
                    queue.push_back(Behaviour::path(gains, loop_, *speed_mps));
                } else {
                    legs = Some(Legs::new(corners, None, *speed_mps));
                }
            }
            TaskSpec::Localize { .. } | TaskSpec::WaitForOperator { .. } => {
                queue.push_back(Behaviour::hold());
            }
            TaskSpec::MoveRelative {
                dx_m,
                dy_m,
                dtheta_deg,
                speed_mps,
                landmark,
            } => {
                let frame = match landmark {
                    None => pose,
                    Some(l) => landmark_frame(l, est)?,
                };
                let goal = frame * Pose2::new(*dx_m, *dy_m, dtheta_deg.to_radians());
                queue.extend(way(&self.config, est, &pose, &goal, *speed_mps));
            }
            TaskSpec::AlignToWall {
                wall,
                standoff_m,
                at_m,
                side,
                speed_mps,
            } => {
                let goal = pose_at_wall(*wall, est.room_m, *at_m, *standoff_m, *side);
                queue.extend(
                    self.approach(&pose, &goal, *wall, est, clearance, *speed_mps)?
                        .0,
                );
                let g = WallGeometry::of(*wall, est.room_m);
                let forward = g
                    .along
                    .dot(&nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin()))
                    > 0.0;
                queue.push_back(Behaviour::follow_wall(
                    gains,
                    *wall,
                    *side,
                    *standoff_m,
                    *at_m,
                    forward,
                    *speed_mps,
                ));
            }
            TaskSpec::FollowWall {
                wall,
                standoff_m,
                from_m,
                to_m,
                speed_mps,
            } => {
                let g = WallGeometry::of(*wall, est.room_m);
                let forward = to_m > from_m;
                let front = self.config.vehicle.front_m();
                let room_left = if forward { g.length_m - to_m } else { *to_m };
                if room_left < front + 0.1 {
                    return Err(format!(
                        "follow_wall: the pass ends {room_left:.2} m from the wall's end; the body reaches {front:.2} m ahead"
                    ));
                }
                let side = g.side_for(forward);
                let start = pose_at_wall(*wall, est.room_m, *from_m, *standoff_m, side);
                let (way, turn_at) =
                    self.approach(&pose, &start, *wall, est, clearance, *speed_mps)?;
                queue.extend(way);
                queue.push_back(Behaviour::follow_wall(
                    gains,
                    *wall,
                    side,
                    *standoff_m,
                    *to_m,
                    forward,
                    *speed_mps,
                ));
                // A pass ends too near the wall to turn on the spot: back out
                // along the standoff to where the robot turned in, then drive
                // forward out to a lane as far from the wall as that turn
                // point (the front leads away from the wall; backing out of
                // the line would swing it into the wall).
                let g = WallGeometry::of(*wall, est.room_m);
                let dir = if forward { 1.0 } else { -1.0 };
                let turned_at = g.position(&turn_at.position().coords);
                let back = g.point(turned_at, *standoff_m);
                queue.push_back(Behaviour::reverse_to(
                    gains,
                    Pose2::new(back.x, back.y, start.theta),
                    *speed_mps,
                ));
                let lane = g.distance(&turn_at.position().coords);
                let out = g.point(turned_at + dir * RUN_IN_M, lane);
                queue.push_back(Behaviour::regulate(
                    gains,
                    Pose2::new(out.x, out.y, start.theta),
                    *speed_mps,
                ));
            }
            TaskSpec::PassDoor {
                door,
                approach_m,
                beyond_m,
                speed_mps,
            } => {
                let Some(d) = est.doors.get(*door) else {
                    return Err(format!(
                        "pass_door: door {door} is not known ({} doors found)",
                        est.doors.len()
                    ));
                };
                let next_depth = d
                    .plan_door
                    .and_then(|p| next_room_depth(&self.config, est, p));
                queue.extend(door_pass(
                    &self.config,
                    est,
                    d,
                    [*approach_m, *beyond_m],
                    next_depth,
                    *speed_mps,
                ));
                // Through a door of the plan, the frame moves on.
                if let (Some(plan_door), Some(_), Some(_)) =
                    (d.plan_door, &self.config.floor, est.room)
                {
                    doorway = Some(Doorway::through(
                        plan_door,
                        VecDeque::new(),
                        [*approach_m, *beyond_m, *speed_mps],
                    ));
                }
            }
            TaskSpec::GoToRoom {
                room,
                approach_m,
                beyond_m,
                speed_mps,
            } => {
                let mut hops: VecDeque<usize> = self.route(room, est)?.into();
                if let Some(first) = hops.pop_front() {
                    queue.extend(plan_door_pass(
                        &self.config,
                        est,
                        first,
                        [*approach_m, *beyond_m],
                        *speed_mps,
                    )?);
                    doorway = Some(Doorway::through(
                        first,
                        hops,
                        [*approach_m, *beyond_m, *speed_mps],
                    ));
                }
            }
        }
        self.continue_asked = false;
        if let TaskSpec::WaitForOperator { prompt, .. } = &self.tasks[index] {
            let prompt = prompt.clone();
            self.emit(
                now,
                EventKind::OperatorPrompt {
                    task: index,
                    prompt,
                },
            );
        }
        Ok(ActiveTask {
            index,
            started: now,
            queue,
            current: None,
            legs,
            blocked_s: 0.0,
            plaster,
            doorway,
            edges_looked_at: false,
        })
    }

    /// The doors of the plan's way from the robot's room to `room`.
    fn route(&self, room: &str, est: &Estimate) -> Result<Vec<usize>, String> {
        let Some(floor) = &self.config.floor else {
            return Err("go_to_room: the mission has no floor plan ([[room]], [[door]])".into());
        };
        let Some(to) = floor.room(room) else {
            let names: Vec<&str> = floor.rooms().iter().map(|r| r.name.as_str()).collect();
            return Err(format!(
                "go_to_room: no room {room:?} on the plan (it has {})",
                names.join(", ")
            ));
        };
        let Some(here) = est.room else {
            return Err("go_to_room: the robot does not know which room it is in".into());
        };
        floor.route(here, to).ok_or_else(|| {
            let from = floor.rooms().get(here).map_or("here", |r| r.name.as_str());
            format!("go_to_room: no way on the plan from {from} to {room}")
        })
    }

    /// A doorway's step before its behaviours: once the robot was said to
    /// have gone through a door, the estimate must be in the room beyond
    /// it; then the next door's passage is planned, or the task is done.
    fn step_doorway(&mut self, now: Stamp, est: &Estimate) -> Option<TaskStep> {
        let a = self.active.as_mut()?;
        let w = a.doorway.as_mut()?;
        let room = w.entering?;
        let name = |r: usize| {
            self.config
                .floor
                .as_ref()
                .and_then(|f| f.rooms().get(r))
                .map_or_else(|| format!("room {r}"), |r| r.name.clone())
        };
        if est.room != Some(room) {
            return Some(TaskStep::Failed(format!(
                "{}: the robot went through the door into {} but its estimate did not follow \
                 (it is not beyond the door)",
                self.tasks[a.index].name(),
                name(room)
            )));
        }
        w.entering = None;
        if let Some(door) = w.passed {
            self.events.push(Event {
                stamp: now,
                kind: EventKind::RoomEntered {
                    door,
                    room: name(room),
                },
            });
        }
        let Some(next) = w.hops.pop_front() else {
            return Some(TaskStep::Done);
        };
        match plan_door_pass(
            &self.config,
            est,
            next,
            [w.approach_m, w.beyond_m],
            w.speed_mps,
        ) {
            Ok(q) => {
                w.through = Some(next);
                w.replans = 0;
                a.queue.extend(q);
                None
            }
            Err(e) => Some(TaskStep::Failed(e)),
        }
    }

    /// Radius the body sweeps turning on the spot, with a margin for what
    /// stands out of a wall (a radiator, a sill), m.
    fn pivot_clearance(&self) -> f64 {
        let v = &self.config.vehicle;
        v.front_m().hypot(0.5 * v.width_m) + 0.2
    }

    /// The way onto a pose beside `wall`: to a point `RUN_IN_M` before it,
    /// far enough from every wall to turn on the spot, turned to the
    /// goal's heading there; the wall law takes it from there.
    fn approach(
        &self,
        from: &Pose2,
        goal: &Pose2,
        wall: crate::task::WallName,
        est: &Estimate,
        clearance: f64,
        speed_mps: f64,
    ) -> Result<(Vec<Behaviour>, Pose2), String> {
        let g = WallGeometry::of(wall, est.room_m);
        let gp = goal.position().coords;
        let dir = nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin());
        let forward = g.along.dot(&dir) > 0.0;
        let at = g.position(&gp);
        let standoff = g.distance(&gp);
        let lo = clearance;
        let hi = g.length_m - clearance;
        let want = if forward {
            at - RUN_IN_M
        } else {
            at + RUN_IN_M
        };
        if lo > hi {
            return Err("the room is too small to turn in".to_owned());
        }
        let p_at = want.clamp(lo, hi);
        let run_in = (at - p_at).abs();
        if run_in < MIN_RUN_IN_M || (forward && p_at > at) || (!forward && p_at < at) {
            return Err(format!(
                "the pass starts {at:.2} m along the wall: too near the corner to turn onto it \
                 (a turn needs {clearance:.2} m from the walls and {MIN_RUN_IN_M:.1} m of run-in)"
            ));
        }
        let p = g.point(p_at, standoff.max(clearance));
        let turn_at = Pose2::new(p.x, p.y, goal.theta);
        // The plain way when it is clear, else a manoeuvre: a robot
        // stopped on the standoff mid-pass (a run resumed there) is too
        // near the wall to turn back on the spot.
        Ok((way(&self.config, est, from, &turn_at, speed_mps), turn_at))
    }

    /// The plan a `plaster` task carries out: the one a checkpoint left
    /// (from its cursor), or a new one on the room as the robot knows it.
    fn plaster_run(
        &mut self,
        index: usize,
        walls: &[WallName],
        ceiling: bool,
        region: Option<&crate::task::Region>,
        est: &Estimate,
    ) -> Result<PlasterRun, String> {
        if let Some((p, plan)) = self.resume_plaster.take()
            && p.task == index
        {
            let Some(plan) = plan else {
                return Err(format!(
                    "plaster: the checkpoint stopped at station {} but the plan it was \
                     carrying out is missing",
                    p.cursor.station
                ));
            };
            let digest = plan_digest(&plan);
            if digest != p.plan_digest {
                return Err(format!(
                    "plaster: the plan beside the checkpoint ({digest}) is not the one it was \
                     carrying out ({})",
                    p.plan_digest
                ));
            }
            let mut run = PlasterRun::new(plan, p.cursor);
            run.resume_s = p.in_move_s.max(0.0);
            return Ok(run);
        }
        let plan = plan_room(&self.config, (walls, ceiling, region), est)?;
        Ok(PlasterRun::new(plan, Cursor::default()))
    }

    /// Steps a `plaster` task: the way to a station, settling there, the
    /// nozzle to its first point, then the pass's moves in time.
    fn step_plaster(
        &mut self,
        now: Stamp,
        est: &Estimate,
        speed: f64,
        settle: f64,
        (walls, ceiling, region): (&[WallName], bool, Option<&crate::task::Region>),
    ) -> TaskStep {
        let vehicle = self.config.vehicle.clone();
        let gains = self.config.gains.clone();
        let clearance = self.pivot_clearance();
        let dt = self.dt;
        let spray_ok =
            est.position_sigma_m <= self.config.safety.spray_max_sigma_m && self.hazard.is_none();
        let Some(a) = self.active.as_mut() else {
            return TaskStep::Done;
        };
        let index = a.index;
        let Some(run) = a.plaster.as_mut() else {
            return TaskStep::Failed("plaster: no plan".to_owned());
        };
        if run.finished() && !matches!(run.phase, Phase::Leaving) {
            return TaskStep::Done;
        }
        let park = ToolCommand {
            nozzle_m: PARK_NOZZLE_M,
            ..ToolCommand::default()
        };
        match run.phase {
            Phase::Surveying => {
                if let Some(cmd) = step_behaviours(a, now, est, &vehicle, &mut self.events) {
                    self.tool = park;
                    return TaskStep::Drive(cmd);
                }
                // The survey's legs, while a clear way reaches a corner;
                // then they are done with (a way blocked later in the
                // task must not be taken for one of them).
                match a.legs.as_mut() {
                    Some(l) if !l.stuck() => {
                        if let Some(way) = l.next(&self.config, est) {
                            a.queue.extend(way);
                            self.tool = park;
                            return TaskStep::Drive(DriveCommand::STOP);
                        }
                        a.legs = None;
                    }
                    Some(_) => a.legs = None,
                    None => {}
                }
                // A window edge the survey's camera bracketed loosely (seen
                // across the room, in a pivot) is looked at again, slowly,
                // before the plan keeps plaster out of the window.
                if !a.edges_looked_at {
                    a.edges_looked_at = true;
                    let looks = edge_looks(&self.config, est, speed);
                    if !looks.is_empty() {
                        for (wall, along_m, sigma_m, way) in looks {
                            self.events.push(Event {
                                stamp: now,
                                kind: EventKind::WindowEdgeLook {
                                    task: a.index,
                                    wall,
                                    along_m,
                                    sigma_m,
                                },
                            });
                            a.queue.extend(way);
                        }
                        self.tool = park;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                }
                // Every wall seen from its standoff: plan on what was found.
                let plan = match plan_room(&self.config, (walls, ceiling, region), est) {
                    Ok(p) => p,
                    Err(e) => return TaskStep::Failed(e),
                };
                let Some(run) = a.plaster.as_mut() else {
                    return TaskStep::Failed("plaster: no plan".to_owned());
                };
                self.events.push(Event {
                    stamp: now,
                    kind: EventKind::PlanMade {
                        task: index,
                        stations: plan.stations.len(),
                        unreachable_m2: plan.unreachable_m2(),
                    },
                });
                run.replan(plan);
                let way = next_station_way(&self.config, clearance, run, &est.pose, speed);
                a.queue.extend(way);
                self.tool = park;
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Leaving => {
                self.tool = park;
                match step_behaviours(a, now, est, &vehicle, &mut self.events) {
                    Some(cmd) => TaskStep::Drive(cmd),
                    None => TaskStep::Done,
                }
            }
            Phase::Moving => {
                if let Some(cmd) = step_behaviours(a, now, est, &vehicle, &mut self.events) {
                    self.tool = park;
                    return TaskStep::Drive(cmd);
                }
                if let Some(r) = a.plaster.as_mut() {
                    r.phase = Phase::Settling { left_s: settle };
                }
                self.tool = park;
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Settling { left_s } => {
                let left_s = left_s - dt;
                if left_s > 0.0 {
                    run.phase = Phase::Settling { left_s };
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                let station = run.cursor.station;
                let base = run.plan.stations[station].base;
                let off = base.inverse() * est.pose;
                // Off the station by more than the gantry has spare: once
                // or twice more onto it, along the lane.
                let spare = run.plan.tool.position_tolerance_m;
                if run.retries < 2 {
                    if off.theta.abs() > HEADING_SPARE_RAD || off.y.abs() > spare {
                        // Turned or beside the station: back off along the
                        // lane and come on again, the line law taking out
                        // the heading and the offset.
                        run.retries += 1;
                        a.queue
                            .extend(realign_way(&self.config, run, &est.pose, &base, speed));
                        run.phase = Phase::Moving;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if off.x.abs() > spare {
                        run.retries += 1;
                        a.queue.push_back(if off.x > 0.0 {
                            Behaviour::reverse_to(&gains, base, 0.1)
                        } else {
                            Behaviour::regulate(&gains, base, 0.1)
                        });
                        run.phase = Phase::Moving;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                }
                run.retries = 0;
                let stations = run.plan.stations.len();
                self.events.push(Event {
                    stamp: now,
                    kind: EventKind::StationStarted {
                        task: index,
                        station,
                        stations,
                        offset_m: [off.x, off.y],
                        heading_off_rad: off.theta,
                    },
                });
                let look = run
                    .look(station, LOOK_SPARE_M, LOOK_HEIGHT_M)
                    .filter(|_| run.plan.tool.camera);
                run.phase = match look {
                    Some(look) => Phase::Looking {
                        look,
                        left_s: -1.0,
                        t_s: 0.0,
                    },
                    None => Phase::Positioning { left_s: -1.0 },
                };
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Looking { look, left_s, t_s } => {
                let station = run.cursor.station;
                let (surface, [u0, u1], v) = (look.surface, look.u_m, look.height_m);
                let sweep_s = (u1 - u0).abs() / LOOK_SPEED_MPS;
                let u = u0 + (u1 - u0) * (t_s / sweep_s.max(1e-9)).clamp(0.0, 1.0);
                let Some(aim) = run.nozzle_for(surface, [u, v], &est.pose, false) else {
                    run.phase = Phase::Positioning { left_s: -1.0 };
                    return TaskStep::Drive(DriveCommand::STOP);
                };
                if left_s != 0.0 {
                    // To the look's start first, as to a pass's.
                    let left_s = if left_s < 0.0 {
                        travel_s(&self.tool, &aim, run.plan.tool.axis_speed_mps)
                    } else {
                        left_s - dt
                    };
                    self.tool = aim;
                    run.phase = Phase::Looking {
                        look,
                        left_s: left_s.max(0.0),
                        t_s: 0.0,
                    };
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                self.tool = aim;
                if t_s < sweep_s {
                    run.phase = Phase::Looking {
                        look,
                        left_s: 0.0,
                        t_s: t_s + dt,
                    };
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                // Looked: windows the plan does not know are kept out of
                // this station's coat and the rest of the wall's.
                if let SurfaceId::Wall(wall) = surface {
                    for w in est
                        .windows
                        .iter()
                        .filter(|w| w.wall == wall && w.sill_head_m[0] >= DOOR_SILL_M)
                    {
                        if run.plan.add_window(wall, w.along_m, w.sill_head_m, station) {
                            self.events.push(Event {
                                stamp: now,
                                kind: EventKind::WindowFound {
                                    task: index,
                                    station,
                                    wall: surface_name(surface),
                                    along_m: w.along_m,
                                    sill_head_m: w.sill_head_m,
                                },
                            });
                            run.digest = plan_digest(&run.plan);
                        }
                    }
                }
                run.phase = Phase::Positioning { left_s: -1.0 };
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Positioning { left_s } => {
                let Some(first) = run.first_point(est) else {
                    return TaskStep::Failed(format!(
                        "plaster: the robot does not face the surface of station {}",
                        run.cursor.station
                    ));
                };
                let left_s = if left_s < 0.0 {
                    // Newly here: the axes travel at their speed.
                    travel_s(&self.tool, &first, run.plan.tool.axis_speed_mps)
                } else {
                    left_s - dt
                };
                self.tool = first;
                run.phase = if left_s > 0.0 {
                    Phase::Positioning { left_s }
                } else {
                    let in_move_s = std::mem::take(&mut run.resume_s);
                    Phase::Spraying { in_move_s }
                };
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Spraying { in_move_s } => {
                let mut t = in_move_s + if spray_ok { dt } else { 0.0 };
                // A checkpoint every second of spraying: a run killed
                // mid-stroke takes it up within a second of where it
                // stopped.
                if spray_ok {
                    run.unsaved_s += dt;
                    if run.unsaved_s >= CHECKPOINT_SPRAY_S {
                        run.unsaved_s = 0.0;
                        self.stroke_done = true;
                    }
                }
                loop {
                    let c = run.cursor;
                    let Some(pass) = run
                        .plan
                        .stations
                        .get(c.station)
                        .and_then(|s| s.passes.get(c.pass))
                    else {
                        return TaskStep::Done;
                    };
                    let surface = pass.surface;
                    let Some(duration) = pass.moves.get(c.step).map(|m| m.duration_s()) else {
                        return TaskStep::Done;
                    };
                    if t < duration {
                        break;
                    }
                    t -= duration;
                    if pass.moves[c.step].spray {
                        self.stroke_done = true;
                    }
                    let station_done = run.advance();
                    if run.cursor.pass != c.pass || station_done {
                        self.events.push(Event {
                            stamp: now,
                            kind: EventKind::PassDone {
                                task: index,
                                station: c.station,
                                surface: surface_name(surface),
                            },
                        });
                        self.stroke_done = true;
                    }
                    if run.finished() {
                        self.tool = park;
                        let last = run.plan.stations.len().saturating_sub(1);
                        let floor = floor_of(run, &vehicle, clearance);
                        a.queue.extend(lane_exit(
                            &self.config,
                            &floor,
                            run,
                            last,
                            &est.pose,
                            speed,
                        ));
                        run.phase = Phase::Leaving;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if station_done {
                        let k = run.cursor.station;
                        let floor = floor_of(run, &vehicle, clearance);
                        let mut way = Vec::new();
                        // Along the lane to the next station only when
                        // the body passes clear; out of it otherwise.
                        let along_clear = run.plan.stations.get(k).is_some_and(|s| {
                            let h =
                                nalgebra::Vector2::new(est.pose.theta.cos(), est.pose.theta.sin());
                            floor.sweep_clear(
                                &est.pose.position().coords,
                                &s.base.position().coords,
                                &h,
                            )
                        });
                        if run.lane(k) != run.lane(k - 1) || !along_clear {
                            way.extend(lane_exit(
                                &self.config,
                                &floor,
                                run,
                                k - 1,
                                &est.pose,
                                speed,
                            ));
                        }
                        let from = way
                            .last()
                            .and_then(|b| match b.kind() {
                                BehaviourKind::Regulate { goal } => Some(*goal),
                                _ => None,
                            })
                            .unwrap_or(est.pose);
                        way.extend(next_station_way(&self.config, clearance, run, &from, speed));
                        run.phase = Phase::Moving;
                        a.queue.extend(way);
                        self.tool = park;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if run.cursor.pass != c.pass {
                        run.phase = Phase::Positioning { left_s: -1.0 };
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                }
                run.phase = Phase::Spraying { in_move_s: t };
                if let Some(cmd) = run.command(t, est) {
                    self.tool = ToolCommand {
                        spray: cmd.spray && spray_ok,
                        ..cmd
                    };
                }
                TaskStep::Drive(DriveCommand::STOP)
            }
        }
    }

    /// Steps the active task.
    fn step_task(&mut self, now: Stamp, est: &Estimate) -> TaskStep {
        let vehicle = self.config.vehicle.clone();
        let gains = self.config.gains.clone();
        let continue_asked = self.continue_asked;
        let Some(a) = self.active.as_mut() else {
            return TaskStep::Done;
        };
        let spec = &self.tasks[a.index];
        if let TaskSpec::Plaster {
            speed_mps,
            settle_s,
            walls,
            ceiling,
            region,
            ..
        } = spec
        {
            let (speed, settle) = (*speed_mps, *settle_s);
            let (walls, ceiling, region) = (walls.clone(), *ceiling, *region);
            return self.step_plaster(now, est, speed, settle, (&walls, ceiling, region.as_ref()));
        }
        if a.doorway.as_ref().is_some_and(|w| w.entering.is_some()) {
            if let Some(step) = self.step_doorway(now, est) {
                return step;
            }
            return self.step_task(now, est);
        }
        let elapsed = now.seconds_since(a.started);
        // Task-level ends: timeouts and the conditions behaviours do not see.
        match spec {
            TaskSpec::MapRoom {
                timeout_s,
                max_size_sigma_m,
                path,
                walls,
                min_sightings,
                inset_m,
                speed_mps,
            } => {
                let unseen: Vec<WallName> = walls
                    .iter()
                    .copied()
                    .filter(|w| est.walls_seen[w.index()] < *min_sightings)
                    .collect();
                // A side of the room is measured when both its walls are.
                let listed = |a: WallName, b: WallName| walls.contains(&a) && walls.contains(&b);
                let sides = [
                    listed(WallName::West, WallName::East),
                    listed(WallName::South, WallName::North),
                ];
                let loose: Vec<f64> = (0..2)
                    .filter(|&i| sides[i] && est.room_sigma_m[i] > *max_size_sigma_m)
                    .map(|i| est.room_sigma_m[i])
                    .collect();
                if elapsed > *timeout_s {
                    return TaskStep::Failed(if unseen.is_empty() {
                        format!(
                            "map_room: the room's size is known to {:.1} mm after {timeout_s} s",
                            1e3 * loose.iter().fold(0.0f64, |m, &s| m.max(s))
                        )
                    } else {
                        format!("map_room: walls {unseen:?} not seen in {timeout_s} s")
                    });
                }
                if let (None, true, Some(legs)) = (&a.current, a.queue.is_empty(), a.legs.as_mut())
                {
                    // The first leg waits for the laser to have found what
                    // stands on the floor near the robot (the plan that
                    // follows stands on it too).
                    if legs.under_way.is_none() && elapsed < LOOK_ROUND_S {
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    // Corner to corner: done at any corner once the walls
                    // are known.
                    if unseen.is_empty() && loose.is_empty() {
                        return TaskStep::Done;
                    }
                    if legs.stuck() {
                        return TaskStep::Failed(
                            "map_room: no clear way reaches any corner of the loop".to_owned(),
                        );
                    }
                    let way = legs.next(&self.config, est).unwrap_or_default();
                    if way.is_empty() {
                        // No clear way to this corner: the next one, next
                        // tick.
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    a.queue.extend(way);
                }
                if a.legs.is_none() && a.current.is_none() && a.queue.is_empty() {
                    if unseen.is_empty() && loose.is_empty() {
                        return TaskStep::Done;
                    }
                    // Another loop, from where the last one ended: each one
                    // sees the walls again.
                    match survey_loop(path.as_deref(), *inset_m, est.room_m) {
                        Ok(l) => {
                            let l = closed(&l);
                            let towards = (l[1][1] - l[0][1]).atan2(l[1][0] - l[0][0]);
                            let start = Pose2::new(l[0][0], l[0][1], towards);
                            a.queue.extend(go_to(&gains, &est.pose, &start, *speed_mps));
                            a.queue.push_back(Behaviour::path(&gains, l, *speed_mps));
                        }
                        Err(e) => return TaskStep::Failed(e),
                    }
                }
            }
            TaskSpec::Localize {
                max_sigma_m,
                timeout_s,
            } => {
                if est.position_sigma_m <= *max_sigma_m {
                    return TaskStep::Done;
                }
                if elapsed > *timeout_s {
                    return TaskStep::Failed(format!(
                        "localize: the position is known to {:.1} mm after {timeout_s} s",
                        1e3 * est.position_sigma_m
                    ));
                }
            }
            TaskSpec::WaitForOperator {
                timeout_s,
                on_timeout,
                ..
            } => {
                if continue_asked {
                    return TaskStep::Done;
                }
                if timeout_s.is_some_and(|t| elapsed > t) {
                    return match on_timeout {
                        OnTimeout::Continue => TaskStep::Done,
                        OnTimeout::Fail => {
                            TaskStep::Failed("wait_for_operator: nobody answered".to_owned())
                        }
                    };
                }
            }
            _ => {}
        }
        loop {
            if a.current.is_none() {
                let Some(next) = a.queue.pop_front() else {
                    // Motion tasks end with their last behaviour.
                    return TaskStep::Done;
                };
                self.events.push(Event {
                    stamp: now,
                    kind: EventKind::BehaviourStarted {
                        task: a.index,
                        behaviour: next.name().to_owned(),
                    },
                });
                a.current = Some(next);
            }
            let Some(b) = a.current.as_mut() else {
                continue;
            };
            match b.step(now, est, &vehicle) {
                Step::Drive(cmd) => return TaskStep::Drive(cmd),
                Step::Done => {
                    a.current = None;
                    if a.queue.is_empty()
                        && let Some(w) = a.doorway.as_mut()
                        && let Some(door) = w.through.take()
                    {
                        // Beyond the door: the frame moves to the next
                        // room, and the next tick checks it did.
                        let beyond = est.room.and_then(|r| {
                            self.config.floor.as_ref().and_then(|f| f.beyond(door, r))
                        });
                        let Some(beyond) = beyond else {
                            return TaskStep::Failed(format!(
                                "{}: door {door} of the plan is not a door of the robot's room",
                                spec.name()
                            ));
                        };
                        w.entering = Some(beyond);
                        w.passed = Some(door);
                        self.enter_room = Some(door);
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if a.queue.is_empty() {
                        // Let the task-level check decide on the next tick
                        // (a survey may loop again); stand still meanwhile.
                        if matches!(spec, TaskSpec::MapRoom { .. }) {
                            return TaskStep::Drive(DriveCommand::STOP);
                        }
                        return TaskStep::Done;
                    }
                }
            }
        }
    }
}

/// A window edge more uncertain than this after a survey is looked at
/// again, m (standard deviation): the plan keeps plaster 2 cm of a window
/// or more, which such an edge misses 2.5 times in a hundred.
const LOOK_EDGE_SIGMA_M: f64 = 0.008;

/// How fast a look sweeps the body camera's fan along the wall, m/s: a
/// profile every centimetre at the camera's 20 a second.
const LOOK_SWEEP_MPS: f64 = 0.2;

/// How far a look sweeps either side of the edge, m (at least three of
/// its standard deviations): the turn onto the sweep's start stops within
/// 0.01 rad of it, 3 cm at 3 m.
const LOOK_REACH_M: f64 = 0.08;

/// Largest angle between the body camera's fan and a wall's normal a look
/// is made at, rad (the window finder takes profiles to 25°).
const LOOK_INCIDENCE_RAD: f64 = 0.26;

/// The looks at the window edges `est` knows loosely (not doors): for each, the way to
/// a place the robot can stand and turn, from which the body's camera
/// meets the edge squarely enough, and a slow turn sweeping the camera's
/// fan across it. Each with the wall, the edge and its spread. An edge no
/// clear way leads to a place for is left as it is; a body without a
/// camera makes none.
fn edge_looks(
    config: &ExecutiveConfig,
    est: &Estimate,
    speed: f64,
) -> Vec<(WallName, f64, f64, Vec<Behaviour>)> {
    let Some(camera_azimuth) = config.body_camera_azimuth_rad else {
        return Vec::new();
    };
    let space = estimate_space(config, est, speed);
    let mut from = est.pose;
    let mut out = Vec::new();
    // Doors are the laser's to measure (the camera finds them as openings
    // down to the floor too).
    for w in est
        .windows
        .iter()
        .filter(|w| w.sill_head_m[0] > DOOR_SILL_M)
    {
        let g = WallGeometry::of(w.wall, est.room_m);
        for k in 0..2 {
            let sigma = w.along_sigma_m[k];
            if sigma <= LOOK_EDGE_SIGMA_M {
                continue;
            }
            let edge = g.origin + g.along * w.along_m[k];
            // Places in front of the edge, nearest the robot's own
            // distance from the wall first, squarely before it first.
            let here = g.distance(&from.position().coords);
            let mut places: Vec<(f64, f64)> = Vec::new();
            for d in [here, 0.8, 1.2, 1.6, 2.0, 2.4, 2.8, 3.2] {
                for off in [0.0, -0.15, 0.15, -0.3, 0.3] {
                    places.push((d, off));
                }
            }
            let look = places.into_iter().find_map(|(d, off)| {
                let at = g.origin + g.along * (w.along_m[k] + off * d) + g.inward * d;
                let to_edge = edge - at;
                let across = to_edge.norm();
                let incidence = (-g.inward.dot(&to_edge) / across).clamp(-1.0, 1.0).acos();
                if !(d > 0.3 && incidence <= LOOK_INCIDENCE_RAD) {
                    return None;
                }
                let aim = to_edge.y.atan2(to_edge.x) - camera_azimuth;
                let reach = (LOOK_REACH_M.max(3.0 * sigma) / across).atan();
                let start = Pose2::new(at.x, at.y, aim - reach);
                let end = Pose2::new(at.x, at.y, aim + reach);
                if !(space.pose_clear(&start) && space.pose_clear(&end)) {
                    return None;
                }
                // The way ends near the heading (a small last turn is left
                // to the line law); the sweep starts on it.
                let (_, mut way) = planned_way(config, est, &from, &start, speed)?;
                way.push(Behaviour::pivot(start.theta));
                way.push(Behaviour::pivot_slowly(end.theta, LOOK_SWEEP_MPS / across));
                Some((end, way))
            });
            if let Some((end, way)) = look {
                out.push((w.wall, w.along_m[k], sigma, way));
                from = end;
            }
        }
    }
    out
}

/// A plastering plan for `walls` (and the ceiling) on the room as `est`
/// knows it. Openings the camera found come with their own top (one
/// reaching the floor is a door); a door only the laser found has the top
/// the floor plan gives it, else the tool's `door_head_m`, and so has a
/// door the plan gives shut, or the camera's top where it saw higher.
fn plan_room(
    config: &ExecutiveConfig,
    (walls, ceiling, region): (&[WallName], bool, Option<&crate::task::Region>),
    est: &Estimate,
) -> Result<Plan, String> {
    let (Some(tool), vehicle) = (config.spray.as_ref(), &config.vehicle) else {
        return Err("plaster: the mission has no [spray] tool".to_owned());
    };
    let mut openings: Vec<WallOpening> = est
        .windows
        .iter()
        .map(|w| WallOpening {
            wall: w.wall,
            kind: if w.sill_head_m[0] < DOOR_SILL_M {
                OpeningKind::Door
            } else {
                OpeningKind::Window
            },
            along_m: w.along_m,
            sill_head_m: if w.sill_head_m[0] < DOOR_SILL_M {
                [0.0, w.sill_head_m[1]]
            } else {
                w.sill_head_m
            },
        })
        .collect();
    // A door's top as the drawing gives it, else the tool's guess.
    let drawn_head = |door: Option<usize>| {
        door.and_then(|i| config.floor.as_ref()?.doors().get(i)?.height_m)
            .unwrap_or(tool.door_head_m)
    };
    for d in &est.doors {
        let half = d.width_m.unwrap_or(0.9) / 2.0;
        let along = [d.position_m - half, d.position_m + half];
        // The laser and the camera may each see part of a door: the
        // opening is what either saw, as high as the camera saw it.
        match openings
            .iter_mut()
            .find(|o| o.wall == d.wall && o.along_m[0] < along[1] && along[0] < o.along_m[1])
        {
            Some(o) => {
                o.kind = OpeningKind::Door;
                o.along_m = [o.along_m[0].min(along[0]), o.along_m[1].max(along[1])];
                o.sill_head_m[0] = 0.0;
            }
            None => openings.push(WallOpening {
                wall: d.wall,
                kind: OpeningKind::Door,
                along_m: along,
                sill_head_m: [0.0, drawn_head(d.plan_door)],
            }),
        }
    }
    // A shut door is no gap in a scan: the drawing gives it. What the
    // camera saw of it (its frame, its leaf's edge) is taken in.
    if let (Some(floor), Some(room)) = (config.floor.as_ref(), est.room) {
        for (door, side) in floor.shut_doors_of(room) {
            let half = floor.doors()[door].width_m / 2.0;
            let mut shut = WallOpening {
                wall: side.wall,
                kind: OpeningKind::ShutDoor,
                along_m: [side.along_m - half, side.along_m + half],
                sill_head_m: [0.0, drawn_head(Some(door))],
            };
            openings.retain(|o| {
                let apart = o.wall != shut.wall
                    || o.along_m[1] <= shut.along_m[0]
                    || shut.along_m[1] <= o.along_m[0];
                if !apart {
                    shut.along_m = [
                        shut.along_m[0].min(o.along_m[0]),
                        shut.along_m[1].max(o.along_m[1]),
                    ];
                    shut.sill_head_m[1] = shut.sill_head_m[1].max(o.sill_head_m[1]);
                }
                apart
            });
            openings.push(shut);
        }
    }
    // A region of one wall: the rest of that wall is kept out of the plan
    // as openings are (its edges get the tool's margin).
    if let (Some(r), [wall]) = (region, walls) {
        let length = WallGeometry::of(*wall, est.room_m).length_m;
        let (a, z, h) = (r.along_m, r.height_m, est.height_m);
        let keep_out = [
            ([0.0, a[0]], [0.0, h]),
            ([a[1], length], [0.0, h]),
            ([a[0], a[1]], [0.0, z[0]]),
            ([a[0], a[1]], [z[1], h]),
        ];
        openings.extend(
            keep_out
                .into_iter()
                .filter(|(along, z)| along[1] - along[0] > 1e-6 && z[1] - z[0] > 1e-6)
                .map(|(along_m, sill_head_m)| WallOpening {
                    wall: *wall,
                    kind: OpeningKind::Window,
                    along_m,
                    sill_head_m,
                }),
        );
    }
    let room = RoomModel {
        size_m: est.room_m,
        height_m: est.height_m,
        openings,
        obstacles: est.obstacles.clone(),
    };
    let mut plan =
        stucco_plan::plan(&room, tool, vehicle, &est.pose).map_err(|e| format!("plaster: {e}"))?;
    let wanted = |s: SurfaceId| match s {
        SurfaceId::Wall(w) => walls.contains(&w),
        SurfaceId::Ceiling => ceiling,
    };
    for station in &mut plan.stations {
        station.passes.retain(|p| wanted(p.surface));
    }
    plan.stations.retain(|s| !s.passes.is_empty());
    Ok(plan)
}

/// The way from `from` to station `k`: along its lane when the robot is
/// on it already (forward or backing), else onto the lane and along it to
/// the station — onto the lane's own line by a manoeuvre when the lane is
/// nearer its wall than a turn on the spot allows, else where the robot
/// can turn (`clearance` from every wall). The second of the pair is
/// false when the way found does not keep the body and the field clear
/// as the map holds them: it is then driven all the same, the supervisor
/// watching (a way not tried at all, none being needed or found, is
/// empty and true).
fn station_way(
    config: &ExecutiveConfig,
    floor: &Floor,
    run: &PlasterRun,
    k: usize,
    from: &Pose2,
    speed: f64,
) -> (Vec<Behaviour>, bool) {
    let (Some(station), Some((line, dist))) = (run.plan.stations.get(k), run.lane_line(k)) else {
        return (Vec::new(), true);
    };
    let gains = &config.gains;
    let goal = station.base;
    let heading = nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin());
    let p = from.position().coords;
    let off = line.inward.dot(&(p - line.origin)) - dist;
    let on_lane = off.abs() < 0.15 && wrap_angle(from.theta - goal.theta).abs() < 0.2;
    if on_lane && floor.sweep_clear(&p, &goal.position().coords, &heading) {
        let ahead = heading.dot(&(goal.position().coords - p));
        return (
            vec![if ahead >= 0.0 {
                Behaviour::regulate(gains, goal, speed)
            } else {
                Behaviour::reverse_to(gains, goal, speed)
            }],
            true,
        );
    }
    let Some((entry, forward)) = lane_entry(floor, run, k) else {
        return (Vec::new(), true);
    };
    // A lane nearer its wall than a turn on the spot allows is entered
    // on its own line, in the moves that get there: from the turning
    // line, the run-in would end short of the lane and the robot would
    // come back for the station.
    let space = plaster_space(config, run, speed);
    let at = line.along.dot(&(entry.position().coords - line.origin));
    let on = line.point(at, dist);
    let onto = Pose2::new(on.x, on.y, entry.theta);
    let moves = (line.inward.dot(&(entry.position().coords - line.origin)) - dist > 0.01)
        .then(|| space.manoeuvre(from, &onto))
        .flatten();
    let mut way = match moves {
        Some((_, moves)) => manoeuvre::behaviours(gains, &moves, speed),
        None => route(gains, floor, from, &entry, speed),
    };
    way.push(if forward {
        Behaviour::regulate(gains, goal, speed)
    } else {
        Behaviour::reverse_to(gains, goal, speed)
    });
    // The way as it will be driven must keep the body and the field
    // clear; where the turning places are too few (a small room with a
    // counter along one wall), the manoeuvre onto the station itself.
    if space.way_cost(from, &way).is_some() {
        return (way, true);
    }
    match space.manoeuvre(from, &goal) {
        Some((_, moves)) => (manoeuvre::behaviours(gains, &moves, speed), true),
        None => (way, false),
    }
}

/// The way from `from` to the plan's next station; notes in `run`
/// whether it was found clear.
fn next_station_way(
    config: &ExecutiveConfig,
    floor_clearance: f64,
    run: &mut PlasterRun,
    from: &Pose2,
    speed: f64,
) -> Vec<Behaviour> {
    let floor = floor_of(run, &config.vehicle, floor_clearance);
    let (way, clear) = station_way(config, &floor, run, run.cursor.station, from, speed);
    run.way_unchecked = !clear;
    way
}

/// The space the way between stations is checked in: the plan's room,
/// what stands on its floor and its doorways (a room too narrow to turn
/// in, a hall, is turned in with the front in a doorway).
fn plaster_space<'a>(config: &'a ExecutiveConfig, run: &'a PlasterRun, speed: f64) -> Space<'a> {
    let doors: Vec<DoorEstimate> = run
        .plan
        .room
        .openings
        .iter()
        .filter(|o| o.kind == OpeningKind::Door)
        .map(|o| DoorEstimate {
            wall: o.wall,
            position_m: 0.5 * (o.along_m[0] + o.along_m[1]),
            width_m: Some(o.along_m[1] - o.along_m[0]),
            sigma_m: 0.0,
            plan_door: None,
        })
        .collect();
    Space::new(
        run.plan.room.size_m,
        &doors,
        &run.plan.room.obstacles,
        &config.vehicle,
        &config.safety,
        speed,
    )
}

/// Onto station `base` again from `from` beside it or turned on it: back
/// off along the lane (as far as `REALIGN_M`) and come on again, the line
/// law taking out the heading and the offset; where the lane is too short
/// behind the station (furniture, a corner), on past it and back onto it;
/// where neither is clear, the manoeuvre onto it; and where none is, no
/// second approach (the gantry sprays from where the robot stands).
fn realign_way(
    config: &ExecutiveConfig,
    run: &PlasterRun,
    from: &Pose2,
    base: &Pose2,
    speed: f64,
) -> Vec<Behaviour> {
    let gains = &config.gains;
    let space = plaster_space(config, run, speed);
    let runs = [1.0, 0.8, 0.6, 0.4].map(|f| f * REALIGN_M);
    let back = runs.iter().map(|&d| {
        vec![
            Behaviour::reverse_to(gains, *base * Pose2::new(-d, 0.0, 0.0), speed),
            Behaviour::regulate(gains, *base, 0.1),
        ]
    });
    let on = runs.iter().map(|&d| {
        vec![
            Behaviour::regulate(gains, *base * Pose2::new(d, 0.0, 0.0), speed),
            Behaviour::reverse_to(gains, *base, 0.1),
        ]
    });
    if let Some(way) = back.chain(on).find(|w| space.way_cost(from, w).is_some()) {
        return way;
    }
    space
        .manoeuvre(from, base)
        .map(|(_, moves)| manoeuvre::behaviours(gains, &moves, 0.1))
        .unwrap_or_default()
}

/// Where the robot comes onto the lane of station `k`: a place to turn,
/// `clearance` from every wall and from what stands on the floor, from
/// where the body runs clear along the lane to the station — a run-in
/// before it (driving on), or failing that, beyond it (backing onto it:
/// the second of the pair is false).
fn lane_entry(floor: &Floor, run: &PlasterRun, k: usize) -> Option<(Pose2, bool)> {
    let clearance = floor.clearance_m;
    let goal = run.plan.stations.get(k)?.base;
    let (line, dist) = run.lane_line(k)?;
    let heading = nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin());
    let dir = line.along.dot(&heading).signum();
    let at = line.along.dot(&(goal.position().coords - line.origin));
    let (lo, hi) = (
        clearance.min(line.length_m - clearance),
        (line.length_m - clearance).max(clearance),
    );
    let want = (at - dir * RUN_IN_M).clamp(lo, hi);
    // The robot turns there: nothing may stand within its sweep, and the
    // way along the lane to the station must be clear.
    let off = dist.max(clearance);
    let clear = |a: f64| {
        let e = line.point(a, off);
        floor.turnable_among_obstacles(&e)
            && floor.sweep_clear(&e, &goal.position().coords, &heading)
    };
    let candidates = (0..200)
        .flat_map(|k| [want - dir * 0.05 * k as f64, want + dir * 0.05 * k as f64])
        .filter(|a| (lo..=hi).contains(a) && (at - a) * dir > 0.05);
    let before = candidates
        .clone()
        .find(|&a| (at - a) * dir >= MIN_RUN_IN_M && clear(a))
        .or_else(|| candidates.clone().find(|&a| clear(a)));
    let pose = |a: f64| {
        let e = line.point(a, off);
        Pose2::new(e.x, e.y, goal.theta)
    };
    if let Some(a) = before {
        return Some((pose(a), true));
    }
    let beyond = (1..200)
        .map(|k| at + dir * 0.05 * k as f64)
        .filter(|a| (lo..=hi).contains(a))
        .find(|&a| clear(a));
    Some(match beyond {
        Some(a) => (pose(a), false),
        None => (pose(want), true),
    })
}

/// Out of the lane of station `k` (the robot at `from` on it) to where it
/// can turn: along the lane and away from its wall, to the place nearest
/// a run-in ahead (the front leading, as a pass along a wall ends) whose
/// way, forward or backing, is clear as it will be driven; nothing when
/// none is (a lane ending at a counter): the way on starts from the lane.
fn lane_exit(
    config: &ExecutiveConfig,
    floor: &Floor,
    run: &PlasterRun,
    k: usize,
    from: &Pose2,
    speed: f64,
) -> Vec<Behaviour> {
    let clearance = floor.clearance_m;
    let Some((line, dist)) = run.lane_line(k) else {
        return Vec::new();
    };
    let heading = nalgebra::Vector2::new(from.theta.cos(), from.theta.sin());
    let dir = line.along.dot(&heading).signum();
    let p = from.position().coords;
    let at = line.along.dot(&(p - line.origin));
    let (lo, hi) = (clearance, line.length_m - clearance);
    let (lo, hi) = (lo.min(hi), hi.max(lo));
    let want = (at + dir * RUN_IN_M).clamp(lo, hi);
    // The robot will turn there: the nearest place along the lane where
    // nothing stands within its sweep, reached with the body clear.
    let off = dist.max(clearance);
    let space = plaster_space(config, run, speed);
    (0..200)
        .flat_map(|k| [want + 0.05 * k as f64, want - 0.05 * k as f64])
        .filter(|a| (lo..=hi).contains(a))
        .find_map(|a| {
            let o = line.point(a, off);
            if !(floor.turnable_among_obstacles(&o) && floor.sweep_clear(&p, &o, &heading)) {
                return None;
            }
            let goal = Pose2::new(o.x, o.y, from.theta);
            let way = vec![if heading.dot(&(o - p)) >= 0.0 {
                Behaviour::regulate(&config.gains, goal, speed)
            } else {
                Behaviour::reverse_to(&config.gains, goal, speed)
            }];
            space.way_cost(from, &way).is_some().then_some(way)
        })
        .unwrap_or_default()
}

/// The floor of the plan's room as the way between stations sees it.
fn floor_of<'a>(run: &'a PlasterRun, vehicle: &VehicleSpec, clearance: f64) -> Floor<'a> {
    Floor::new(
        run.plan.room.size_m,
        &run.plan.room.obstacles,
        vehicle,
        clearance,
    )
}

/// A look at every wall before the plan is made again on what the camera
/// found: one loop round the room, clockwise so the camera (looking left)
/// faces each wall in turn. Where the room leaves room for it, the loop
/// stands `clearance` from the walls and is turned on the move; where it
/// does not (a small kitchen, a furnished bedroom), it runs nearer the
/// walls, at `SURVEY_LEG_STANDOFF_M`, corner to corner, each leg the
/// planned way as it starts (the legs returned). Either keeps clear of
/// what stands on the floor; its start is reached by the planned way.
fn survey_way(
    config: &ExecutiveConfig,
    clearance: f64,
    est: &Estimate,
    speed: f64,
) -> (Vec<Behaviour>, Option<Legs>) {
    let vehicle = &config.vehicle;
    let [xs, ys] = est.room_m;
    // What the body reaches toward the furniture beside the loop's long
    // sides (half its width) and at its ends (its front, turning).
    let side = survey_side_reach(vehicle);
    let front = vehicle.front_m() + 0.15;
    let half = if xs >= ys {
        [front, side]
    } else {
        [side, front]
    };
    // The loop's ends stand off a little more: its corners are turned
    // on the move, the front swinging out past them.
    let ends = clearance + 0.2;
    let margins = if xs >= ys {
        [ends, clearance]
    } else {
        [clearance, ends]
    };
    if let Some(corners) = survey_rect(est, margins, half, SURVEY_LOOP_MIN_M) {
        let path = closed(&corners);
        let (a, b) = (path[0], path[1]);
        let start = Pose2::new(a[0], a[1], (b[1] - a[1]).atan2(b[0] - a[0]));
        let mut way = self::way(config, est, &est.pose, &start, speed);
        way.push(Behaviour::path(&config.gains, path, speed));
        return (way, None);
    }
    (Vec::new(), survey_legs(vehicle, est, speed))
}

/// What the body reaches toward the furniture beside a survey loop's
/// side: half its width and 0.15 m, m.
fn survey_side_reach(vehicle: &VehicleSpec) -> f64 {
    0.5 * vehicle.width_m + 0.15
}

/// A survey loop driven corner to corner, `SURVEY_LEG_STANDOFF_M` off the
/// walls, stopping at each: to the first, then round to it, each leg the
/// planned way, the corners fitted again to the floor map as each starts.
/// None: the room leaves no loop.
fn survey_legs(vehicle: &VehicleSpec, est: &Estimate, speed: f64) -> Option<Legs> {
    let side = survey_side_reach(vehicle);
    let fit = ([SURVEY_LEG_STANDOFF_M; 2], [side, side]);
    let corners = survey_rect(est, fit.0, fit.1, SURVEY_LEGS_MIN_M)?;
    let mut legs = Legs::new(corners.to_vec(), Some(corners.len() + 1), speed);
    legs.refit = Some(fit);
    Some(legs)
}

/// A plastering survey's loop turned on the move, stopped this long by
/// something in its way, goes on corner to corner, s: the stops it meets
/// at furniture it passes near mostly clear within 3.5 s (the two
/// offices' table), and going on corner to corner costs ten times that.
const SURVEY_BLOCKED_S: f64 = 5.0;

/// Time the nozzle takes from `from` to `to`, each axis at `speed_mps`,
/// and a few control periods more to be there, s.
fn travel_s(from: &ToolCommand, to: &ToolCommand, speed_mps: f64) -> f64 {
    let far = (0..3)
        .map(|k| (to.nozzle_m[k] - from.nozzle_m[k]).abs())
        .fold(0.0, f64::max);
    far / speed_mps + NOZZLE_SETTLE_S
}

/// Shortest side of a survey loop driven corner to corner, m.
const SURVEY_LEGS_MIN_M: f64 = 0.3;

/// Sides shorter than this make the survey loop, turned on the move, too
/// small to see a window whole (a kitchen's 0.4 m): it is driven corner to
/// corner nearer the walls instead, m.
const SURVEY_LOOP_MIN_M: f64 = 0.6;

/// How far from the walls a survey loop driven corner to corner runs, m.
const SURVEY_LEG_STANDOFF_M: f64 = 0.6;

/// The corners of a survey loop `margins` (along x, along y) inside the
/// walls, moved off the furniture near the walls (each piece moves the
/// side it stands before in by `half` — what the body reaches toward it
/// across x and across y; of two, the one that costs the loop least), in
/// the order it is driven: west along the south side first, the camera
/// on the south wall. `None` when a side is shorter than `min_side`.
fn survey_rect(
    est: &Estimate,
    margins: [f64; 2],
    half: [f64; 2],
    min_side: f64,
) -> Option<[[f64; 2]; 4]> {
    let [xs, ys] = est.room_m;
    let [half_x, half_y] = half;
    let (mut x0, mut x1, mut y0, mut y1) =
        (margins[0], xs - margins[0], margins[1], ys - margins[1]);
    for o in &est.obstacles {
        let (cx, cy) = (
            0.5 * (o.min_m[0] + o.max_m[0]),
            0.5 * (o.min_m[1] + o.max_m[1]),
        );
        let (w, h) = (x1 - x0, y1 - y0);
        // (loss of area, side, new place)
        let mut moves: Vec<(f64, usize, f64)> = Vec::new();
        if cx < 0.5 * xs && o.max_m[0] + half_x > x0 && o.max_m[0] < 0.5 * xs {
            moves.push(((o.max_m[0] + half_x - x0) * h, 0, o.max_m[0] + half_x));
        }
        if cx > 0.5 * xs && o.min_m[0] - half_x < x1 && o.min_m[0] > 0.5 * xs {
            moves.push(((x1 - (o.min_m[0] - half_x)) * h, 1, o.min_m[0] - half_x));
        }
        if cy < 0.5 * ys && o.max_m[1] + half_y > y0 && o.max_m[1] < 0.5 * ys {
            moves.push(((o.max_m[1] + half_y - y0) * w, 2, o.max_m[1] + half_y));
        }
        if cy > 0.5 * ys && o.min_m[1] - half_y < y1 && o.min_m[1] > 0.5 * ys {
            moves.push(((y1 - (o.min_m[1] - half_y)) * w, 3, o.min_m[1] - half_y));
        }
        // A piece reaching across the middle (a bed and a desk along a
        // bedroom) that the body would meet: whichever side it cuts least.
        // (Within the loop, clear of its sides by the body's half width
        // and more, it is driven round.)
        let r = half_x.min(half_y);
        let meets = o.max_m[0] + r > x0
            && o.min_m[0] - r < x1
            && o.max_m[1] + r > y0
            && o.min_m[1] - r < y1
            && !(o.min_m[0] - r > x0
                && o.max_m[0] + r < x1
                && o.min_m[1] - r > y0
                && o.max_m[1] + r < y1);
        if moves.is_empty() && meets {
            let cuts = [
                (0, o.max_m[0] + half_x, x1 - (o.max_m[0] + half_x)),
                (1, o.min_m[0] - half_x, (o.min_m[0] - half_x) - x0),
                (2, o.max_m[1] + half_y, y1 - (o.max_m[1] + half_y)),
                (3, o.min_m[1] - half_y, (o.min_m[1] - half_y) - y0),
            ];
            // On the robot's side of it, when it stands clear of it one
            // way or the other (a piece across the whole room leaves no
            // way to the other side).
            let p = est.pose.position();
            let robots_side = |side: usize| match side {
                0 => p.x > o.max_m[0],
                1 => p.x < o.min_m[0],
                2 => p.y > o.max_m[1],
                _ => p.y < o.min_m[1],
            };
            let any_side = cuts.iter().any(|c| c.2 > 0.0 && robots_side(c.0));
            moves.extend(
                cuts.into_iter()
                    .filter(|c| c.2 > 0.0 && (!any_side || robots_side(c.0)))
                    .map(|(side, at, left)| {
                        let loss = if side < 2 {
                            (w - left) * h
                        } else {
                            (h - left) * w
                        };
                        (loss, side, at)
                    }),
            );
        }
        if let Some(&(_, side, at)) = moves.iter().min_by(|a, b| a.0.total_cmp(&b.0)) {
            match side {
                0 => x0 = at,
                1 => x1 = at,
                2 => y0 = at,
                _ => y1 = at,
            }
        }
    }
    (x1 - x0 >= min_side && y1 - y0 >= min_side).then_some([[x1, y0], [x0, y0], [x0, y1], [x1, y1]])
}

/// Runs the behaviours of `a`'s queue: the command of the one under way,
/// or `None` when the queue is done.
fn step_behaviours(
    a: &mut ActiveTask,
    now: Stamp,
    est: &Estimate,
    vehicle: &VehicleSpec,
    events: &mut Vec<Event>,
) -> Option<DriveCommand> {
    loop {
        if a.current.is_none() {
            let next = a.queue.pop_front()?;
            events.push(Event {
                stamp: now,
                kind: EventKind::BehaviourStarted {
                    task: a.index,
                    behaviour: next.name().to_owned(),
                },
            });
            a.current = Some(next);
        }
        let b = a.current.as_mut()?;
        match b.step(now, est, vehicle) {
            Step::Drive(cmd) => return Some(cmd),
            Step::Done => a.current = None,
        }
    }
}

fn surface_name(s: SurfaceId) -> String {
    s.name().to_owned()
}

enum TaskStep {
    Drive(DriveCommand),
    Done,
    Failed(String),
}

/// The survey loop: the given path or a rectangle `inset_m` inside the
/// room.
fn survey_loop(
    path: Option<&[[f64; 2]]>,
    inset_m: f64,
    room_m: [f64; 2],
) -> Result<Vec<[f64; 2]>, String> {
    if let Some(p) = path {
        return Ok(p.to_vec());
    }
    let [xs, ys] = room_m;
    if 2.0 * inset_m >= xs.min(ys) {
        return Err(format!(
            "map_room: an inset of {inset_m} m leaves no loop in a {xs:.2} × {ys:.2} m room"
        ));
    }
    Ok(vec![
        [inset_m, inset_m],
        [xs - inset_m, inset_m],
        [xs - inset_m, ys - inset_m],
        [inset_m, ys - inset_m],
    ])
}

/// Margin a loop's corners keep from the walls beyond the front's reach
/// ahead of the rear axle, for the loop to be turned on the move, m.
const ON_THE_MOVE_SPARE_M: f64 = 0.1;

/// True when a `map_room` loop through `corners` can be driven as one path,
/// its corners turned on the move: the front swings out past each corner
/// by as much as its reach ahead of the rear axle, and every corner stands
/// that far and `ON_THE_MOVE_SPARE_M` more from every wall. A loop in a
/// furnished bedroom, between the bed and the wall, does not.
fn turns_on_the_move(corners: &[[f64; 2]], room_m: [f64; 2], vehicle: &VehicleSpec) -> bool {
    let reach = vehicle.front_m() + ON_THE_MOVE_SPARE_M;
    corners
        .iter()
        .all(|&[x, y]| x.min(room_m[0] - x) >= reach && y.min(room_m[1] - y) >= reach)
}

/// The loop through `points` as a path that starts and ends halfway along
/// its first side: every corner is turned on the move, and the next loop
/// goes on from where this one ends, heading its way.
fn closed(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let (Some(&a), Some(&b)) = (points.first(), points.get(1)) else {
        return points.to_vec();
    };
    let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    let mut p = vec![mid];
    p.extend_from_slice(&points[1..]);
    p.push(a);
    p.push(mid);
    p
}

/// The behaviours through door `d` of the room `est` knows: onto the line
/// through its middle `approach` before it, facing out, then along the
/// line to `beyond` past it. Standing on that line facing into the room
/// (just come in through the door), the robot may back out instead, when
/// that is quicker than turning round (a bedroom cramped by its door).
/// Both distances
/// are fitted to the rooms: at the approach the body must be in this
/// room, and beyond, in the next, whose depth across the door is
/// `next_depth_m` when the plan gives it.
fn door_pass(
    config: &ExecutiveConfig,
    est: &Estimate,
    d: &DoorEstimate,
    [approach_m, beyond_m]: [f64; 2],
    next_depth_m: Option<f64>,
    speed_mps: f64,
) -> Vec<Behaviour> {
    let v = &config.vehicle;
    let (rear, front) = (v.rear_overhang_m, v.front_m());
    let g = WallGeometry::of(d.wall, est.room_m);
    let depth = if g.along.x.abs() > 0.5 {
        est.room_m[1]
    } else {
        est.room_m[0]
    };
    let out_heading = (-g.inward.y).atan2(-g.inward.x);
    // Already on the door's line, facing along the passage, the robot
    // needs no approach from further in than where it stands.
    let here = est.pose.position().coords;
    let (off_line, standing) = (g.position(&here) - d.position_m, g.distance(&here));
    let pass = |forward: bool| {
        // The end of the body that leads and the one that trails.
        let (leads, trails) = if forward {
            (front, rear)
        } else {
            (rear, front)
        };
        let heading = if forward {
            out_heading
        } else {
            wrap_angle(out_heading + std::f64::consts::PI)
        };
        let on_line = off_line.abs() < ON_LINE_M
            && wrap_angle(est.pose.theta - heading).abs() < ON_LINE_RAD
            && standing > 0.0;
        let mut approach = approach_m.min(depth - trails - DOOR_FIT_M);
        if on_line {
            approach = approach.min(standing);
        }
        // Backing, the laser trails: the robot stops with it through the
        // wall and past the laser's shortest range, so that the next
        // room's filter starts on that room's walls, not on the room
        // left seen through the door.
        let beyond = if forward {
            beyond_m
        } else {
            beyond_m.max(v.laser_mount.x + BACKED_LASER_BEYOND_M)
        };
        let beyond = next_depth_m.map_or(beyond, |n| beyond.min(n - leads - DOOR_FIT_M));
        let (a, b) = (
            g.point(d.position_m, approach),
            g.point(d.position_m, -beyond),
        );
        (
            on_line,
            Pose2::new(a.x, a.y, heading),
            Pose2::new(b.x, b.y, heading),
        )
    };
    let through = |forward: bool, b: Pose2| {
        if forward {
            Behaviour::regulate(&config.gains, b, speed_mps)
        } else {
            Behaviour::reverse_to(&config.gains, b, speed_mps)
        }
    };
    // Facing out, or backing out the way it came in when it stands on the
    // door's line facing into the room (the laser looks ahead: the robot
    // backs only where it has just driven), whichever is the quicker.
    let best = [true, false]
        .into_iter()
        .filter_map(|forward| {
            let (on_line, a, b) = pass(forward);
            if !forward && !on_line {
                return None;
            }
            let (cost, way) = planned_way(config, est, &est.pose, &a, speed_mps)?;
            Some((cost, forward, way, b))
        })
        .min_by(|x, y| x.0.total_cmp(&y.0));
    if let Some((_, forward, mut out, b)) = best {
        out.push(through(forward, b));
        return out;
    }
    let (_, a, b) = pass(true);
    let mut out = go_to(&config.gains, &est.pose, &a, speed_mps);
    out.push(through(true, b));
    out
}

/// [`door_pass`] through door `door` of the floor plan, as the robot knows
/// it in its room.
fn plan_door_pass(
    config: &ExecutiveConfig,
    est: &Estimate,
    door: usize,
    approach_beyond_m: [f64; 2],
    speed_mps: f64,
) -> Result<Vec<Behaviour>, String> {
    let d = est
        .doors
        .iter()
        .find(|d| d.plan_door == Some(door))
        .ok_or_else(|| format!("go_to_room: door {door} of the plan is not known in this room"))?;
    Ok(door_pass(
        config,
        est,
        d,
        approach_beyond_m,
        next_room_depth(config, est, door),
        speed_mps,
    ))
}

/// The depth across door `door` of the plan of the room beyond it from
/// the robot's room, m.
fn next_room_depth(config: &ExecutiveConfig, est: &Estimate, door: usize) -> Option<f64> {
    let floor = config.floor.as_ref()?;
    let next = floor.beyond(door, est.room?)?;
    let side = floor.side(door, next)?;
    let size = floor.rooms().get(next)?.size_m;
    Some(match side.wall {
        WallName::South | WallName::North => size[1],
        WallName::East | WallName::West => size[0],
    })
}

/// The room as `est` knows it, for checking ways at `speed_mps`: its
/// doors and what stands on its floor.
fn estimate_space<'a>(config: &'a ExecutiveConfig, est: &'a Estimate, speed_mps: f64) -> Space<'a> {
    Space::new(
        est.room_m,
        &est.doors,
        &est.obstacles,
        &config.vehicle,
        &config.safety,
        speed_mps,
    )
}

/// The way from `from` to `goal` in the room `est` knows: the plain one
/// (turn toward the goal, drive, turn to its heading) when the body and
/// the supervisor's field keep clear of the walls, the doorways and what
/// stands on the floor all along it; else the manoeuvre in partial turns
/// and short runs that does; `None` when neither does. With it, the time
/// it is reckoned to take, s.
fn planned_way(
    config: &ExecutiveConfig,
    est: &Estimate,
    from: &Pose2,
    goal: &Pose2,
    speed_mps: f64,
) -> Option<(f64, Vec<Behaviour>)> {
    let space = estimate_space(config, est, speed_mps);
    // The plain way is checked as it will be driven.
    let plain = go_to(&config.gains, from, goal, speed_mps);
    if let Some(cost) = space.way_cost(from, &plain) {
        return Some((cost, plain));
    }
    if let Some((cost, moves)) = space.manoeuvre(from, goal) {
        return Some((
            cost,
            manoeuvre::behaviours(&config.gains, &moves, speed_mps),
        ));
    }
    if space.pose_clear(from) {
        return None;
    }
    // Standing nearer something than the body's margins allow (it was
    // seen only on the way here): back out along the way the robot came,
    // as little as frees it, and go on from there.
    BACK_OUT_M.iter().find_map(|&d| {
        let back = *from * Pose2::new(-d, 0.0, 0.0);
        if !space.pose_clear(&back) {
            return None;
        }
        let (cost, moves) = space.manoeuvre(&back, goal)?;
        let mut way = vec![Behaviour::reverse_to(&config.gains, back, speed_mps)];
        way.extend(manoeuvre::behaviours(&config.gains, &moves, speed_mps));
        Some((cost + 0.5 + d / speed_mps, way))
    })
}

/// Seconds a `map_room` loop driven corner to corner stands before its
/// first leg: the floor map needs a score of echoes in a cell (the scans
/// come at 10 Hz) to take something as standing there.
const LOOK_ROUND_S: f64 = 6.0;

/// How far a robot standing too near something may back out before its
/// way is planned, m (tried in turn).
const BACK_OUT_M: [f64; 4] = [0.1, 0.2, 0.3, 0.4];

/// [`planned_way`], or failing that the plain way, the supervisor
/// stopping the robot before it touches anything.
fn way(
    config: &ExecutiveConfig,
    est: &Estimate,
    from: &Pose2,
    goal: &Pose2,
    speed_mps: f64,
) -> Vec<Behaviour> {
    planned_way(config, est, from, goal, speed_mps)
        .map_or_else(|| go_to(&config.gains, from, goal, speed_mps), |(_, w)| w)
}

/// The frame of `landmark` in the room as `est` knows it: facing it from
/// inside, its origin at its middle on the wall's line, x out of the room.
fn landmark_frame(landmark: &crate::task::Landmark, est: &Estimate) -> Result<Pose2, String> {
    let (wall, along) = match *landmark {
        crate::task::Landmark::Wall(w) => (w, WallGeometry::of(w, est.room_m).length_m / 2.0),
        crate::task::Landmark::Door(i) => {
            let d = est.doors.get(i).ok_or_else(|| {
                format!(
                    "move_relative: door {i} is not known ({} doors found)",
                    est.doors.len()
                )
            })?;
            (d.wall, d.position_m)
        }
    };
    let g = WallGeometry::of(wall, est.room_m);
    let o = g.point(along, 0.0);
    Ok(Pose2::new(o.x, o.y, (-g.inward.y).atan2(-g.inward.x)))
}
