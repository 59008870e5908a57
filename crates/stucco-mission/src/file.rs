//! Mission files (`missions/*.toml`): a world, seeds, and either a list of
//! tasks for the executive (`[[task]]`, with `[start]` and `[failsafe]`) or
//! one of the navigation experiments of paper A, run by `stucco run`. Every
//! table is `deny_unknown_fields`; errors name the file, line and column.

use crate::{Executive, ExecutiveConfig, FloorPlan, PlanDoor, PlanRoom, SafetyConfig, TaskSpec};
use nalgebra::SVector;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use stucco_control::GainSchedule;
use stucco_core::{Pose2, RobotSpec};

/// Input that cannot be used as it is (a mission file, a checkpoint):
/// `stucco run` exits with 2 on it.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// What a mission file's reading gives: the value, or what is wrong with
/// the file and where.
pub type Result<T, E = BadInput> = std::result::Result<T, E>;

/// Fails with [`BadInput`].
macro_rules! bad {
    ($($arg:tt)*) => {
        return Err(BadInput(format!($($arg)*)))
    };
}

/// A mission file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mission {
    /// Name, for reports.
    pub name: String,
    /// The simulated world the mission runs in, relative to the mission
    /// file (a job in the simulator needs one; a real robot's does not).
    #[serde(default)]
    pub world: Option<PathBuf>,
    /// Seed of the first simulated run; run `k` uses `seed + k`.
    #[serde(default)]
    pub seed: u64,
    /// Runs when `--runs` is not given.
    #[serde(default = "one")]
    pub runs: u64,
    /// Door passage (Table III).
    pub door_passage: Option<DoorPassage>,
    /// Corridor centring.
    pub corridor: Option<Corridor>,
    /// The room's size learnt while touring it.
    pub room_size: Option<RoomSize>,
    /// What the robot knows when a task mission starts.
    pub start: Option<StartKnowledge>,
    /// The safety supervisor's settings.
    #[serde(default)]
    pub failsafe: SafetyConfig,
    /// The spray tool and the coat (`plaster` tasks need it).
    #[serde(default)]
    pub spray: Option<stucco_plan::SprayTool>,
    /// The tasks, in order (`[[task]]`).
    #[serde(default, rename = "task")]
    pub tasks: Vec<TaskSpec>,
    /// A file holding the building's plan (its `[[room]]` and `[[door]]`
    /// tables), relative to the mission file: one drawing for the
    /// missions of a building.
    #[serde(default)]
    pub plan: Option<PathBuf>,
    /// The building's rooms as its plan draws them (`[[room]]`), for
    /// `go_to_room` and for the robot's frame to follow it from room to
    /// room.
    #[serde(default, rename = "room")]
    pub rooms: Vec<PlanRoom>,
    /// The plan's doors between those rooms (`[[door]]`).
    #[serde(default, rename = "door")]
    pub doors: Vec<PlanDoor>,
    /// The windows the plan gives (`[[window]]`), if it gives them.
    #[serde(default, rename = "window")]
    pub windows: Vec<crate::PlanWindow>,
    /// The plan of `rooms` and `doors`, checked once at load.
    #[serde(skip)]
    floor: Option<FloorPlan>,
    /// The drawing's rooms the `plaster` tasks plaster ([`Mission::plaster_rooms`]).
    #[serde(skip)]
    named_rooms: Vec<String>,
    /// For each task, the room whose share of a job over rooms it is
    /// (going there, mapping it, plastering it) and that share's number
    /// ([`Mission::task_room`]).
    #[serde(skip)]
    task_rooms: Vec<Option<(usize, String)>>,
    /// The mission file's text as it was parsed.
    #[serde(skip)]
    text: String,
    /// The text of the plan file it names, as it was parsed.
    #[serde(skip)]
    plan_text: Option<String>,
    /// A task mission fails when it takes longer than this, simulated s.
    #[serde(default = "time_limit")]
    pub time_limit_s: f64,
    /// Whether the world's people walk about during a task mission (false:
    /// the site is closed while the robot works).
    #[serde(default = "yes")]
    pub people: bool,
}

fn yes() -> bool {
    true
}

fn time_limit() -> f64 {
    1800.0
}

/// A plan's own file: the building's rooms and doors.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanFile {
    #[serde(default, rename = "room")]
    rooms: Vec<PlanRoom>,
    #[serde(default, rename = "door")]
    doors: Vec<PlanDoor>,
    #[serde(default, rename = "window")]
    windows: Vec<crate::PlanWindow>,
}

/// What the robot knows of its start in a task mission: it stands at the
/// world's start pose, in the room frame (the room's south-west corner),
/// within `pose_sigma_m`; the room's size is known to `room_sigma_m`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartKnowledge {
    /// The room's size as a plan gives it, m (without a floor plan).
    #[serde(default)]
    pub room_m: Option<[f64; 2]>,
    /// The floor plan's room the robot starts in (with a floor plan: the
    /// size is the plan's).
    #[serde(default)]
    pub room: Option<String>,
    /// How far off the sizes (and the plan's doors) may be, m (σ); by
    /// default 3 cm, a drawing's slack.
    #[serde(default = "drawing_sigma")]
    pub room_sigma_m: f64,
    /// How far off the start position may be, m (σ).
    #[serde(default = "start_sigma")]
    pub pose_sigma_m: f64,
}

fn start_sigma() -> f64 {
    0.02
}

fn drawing_sigma() -> f64 {
    0.03
}

impl StartKnowledge {
    /// The room filter's first state for a robot put at `at` (room frame):
    /// off by the start's uncertainty (`pose_sigma_m` along x and against
    /// y, 0.01 rad in heading), the room `size_m` as planned.
    pub fn filter_start(&self, at: &Pose2, size_m: [f64; 2]) -> SVector<f64, 5> {
        let off = self.pose_sigma_m;
        SVector::<f64, 5>::new(
            at.x + off,
            at.y - off,
            at.theta + 0.01,
            size_m[0],
            size_m[1],
        )
    }
}

fn one() -> u64 {
    1
}

/// Passing the door in the room's wall `x = xs` (the room frame has its
/// origin in a corner), heading +x.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DoorPassage {
    /// The room's size as a map gives it, m (the filter refines it).
    pub room_m: [f64; 2],
    /// The door's centre as the map gives it, m: on the wall `x = xs`.
    /// The passage is scored against the world's open door nearest it
    /// (there must be one within 0.3 m).
    pub door_m: [f64; 2],
    /// How far off the map's door is, m (the filter places it).
    #[serde(default)]
    pub door_map_error_m: f64,
    /// Speeds, m/s: each start is run at each.
    pub speeds_mps: Vec<f64>,
    /// Starts.
    pub start: Vec<Start>,
}

/// A named start pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Start {
    /// Name (`easy`, `difficult`).
    pub name: String,
    /// Position of the rear axle, m.
    pub at: [f64; 2],
    /// Heading, degrees.
    pub heading_deg: f64,
}

/// Driving a straight corridor (the room `x ∈ [0, xs]`, `y ∈ [0, ys]`)
/// along +x on its middle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Corridor {
    /// The corridor's size as a map gives it, m.
    pub room_m: [f64; 2],
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Start.
    pub start: Start,
    /// The stretch scored, m along x.
    pub score_x_m: [f64; 2],
}

/// Touring a rectangular room on the filter's estimate while it learns
/// the room's size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomSize {
    /// The size the filter starts from, m.
    pub room_m: [f64; 2],
    /// Its uncertainty, m (σ).
    pub room_sigma_m: f64,
    /// Simulated seconds of touring.
    pub seconds: f64,
    /// Speed, m/s.
    pub speed_mps: f64,
}

impl Mission {
    /// Reads and checks the mission file at `path`.
    pub fn load(path: &Path) -> Result<Mission> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| BadInput(format!("cannot read {}: {e}", path.display())))?;
        Self::parse(&text, path)
    }

    /// Parses and checks the text of a mission file (`path` names it in
    /// errors).
    pub fn parse(text: &str, path: &Path) -> Result<Mission> {
        Self::parse_with_plan(text, path, None)
    }

    /// As [`Mission::parse`], the text of the plan file the mission names
    /// given (as a recording keeps it) instead of read from the disk;
    /// `None`: read it.
    pub fn parse_with_plan(text: &str, path: &Path, plan_text: Option<&str>) -> Result<Mission> {
        let text = text.to_owned();
        let mut mission: Mission = parse_toml(&text, path)?;
        // The plan's own file, when it has one: its faults are named there.
        let plan_file = match &mission.plan {
            None => None,
            Some(_)
                if !(mission.rooms.is_empty()
                    && mission.doors.is_empty()
                    && mission.windows.is_empty()) =>
            {
                bad!(
                    "{}:{}: plan: the plan is in its file or in [[room]], [[door]] and [[window]] \
                     here, not both",
                    path.display(),
                    line_of(&text, "", "plan")
                )
            }
            Some(file) => {
                let plan_path = path.parent().map_or_else(|| file.clone(), |d| d.join(file));
                // A plan given is named as the copy it is in errors.
                let (plan_text, plan_path) = match plan_text {
                    Some(given) => (
                        given.to_owned(),
                        PathBuf::from(format!("{} (as recorded)", plan_path.display())),
                    ),
                    None => (
                        std::fs::read_to_string(&plan_path).map_err(|e| {
                            BadInput(format!(
                                "{}:{}: plan: cannot read {}: {e}",
                                path.display(),
                                line_of(&text, "", "plan"),
                                plan_path.display()
                            ))
                        })?,
                        plan_path,
                    ),
                };
                let drawn: PlanFile = parse_toml(&plan_text, &plan_path)?;
                mission.rooms = drawn.rooms;
                mission.doors = drawn.doors;
                mission.windows = drawn.windows;
                Some((plan_text, plan_path))
            }
        };
        let kinds = usize::from(mission.door_passage.is_some())
            + usize::from(mission.corridor.is_some())
            + usize::from(mission.room_size.is_some())
            + usize::from(!mission.tasks.is_empty());
        if kinds != 1 {
            bad!(
                "{}: a mission holds exactly one of [[task]], [door_passage], [corridor], [room_size]",
                path.display()
            );
        }
        if mission.runs == 0 {
            bad!(
                "{}:{}: runs: at least one",
                path.display(),
                line_of(&text, "", "runs")
            );
        }
        if !mission.tasks.is_empty() && mission.start.is_none() {
            bad!(
                "{}: a task mission needs [start] (the room's size as planned and how sure it is)",
                path.display()
            );
        }
        if let Some((table, key, why)) = mission.invalid() {
            bad!(
                "{}:{}: [{table}] {key}: {why}",
                path.display(),
                line_of(&text, table, key)
            );
        }
        if let Some(tool) = &mission.spray
            && let Err(stucco_plan::PlanError::Tool { field, why }) =
                tool.validate(RobotSpec::default().vehicle.width_m)
        {
            bad!(
                "{}:{}: [spray] {field}: {why}",
                path.display(),
                line_of(&text, "spray", field)
            );
        }
        let plan = match &plan_file {
            Some((plan_text, plan_path)) => mission.checked_plan(plan_text, plan_path)?,
            None => mission.checked_plan(&text, path)?,
        };
        mission.floor = plan.clone();
        if let (Some(plan), Some(name)) =
            (&plan, mission.start.as_ref().and_then(|s| s.room.as_ref()))
            && plan.room(name).is_none()
        {
            bad!(
                "{}:{}: [start] room: no room {name:?} on the floor plan",
                path.display(),
                line_of(&text, "start", "room")
            );
        }
        // The room the robot is in, task by task, while it can be told (a
        // pass_door leads where its door does, known only when it runs).
        let mut here = plan
            .as_ref()
            .zip(mission.start.as_ref().and_then(|s| s.room.as_ref()))
            .and_then(|(p, name)| p.room(name));
        for (i, task) in mission.tasks.iter().enumerate() {
            if let TaskSpec::GoToRoom { room, .. } = task {
                let Some(to) = plan.as_ref().and_then(|p| p.room(room)) else {
                    bad!(
                        "{}:{}: task {} (go_to_room): room: no room {room:?} on the floor plan",
                        path.display(),
                        line_of_array(&text, "task", i, "room"),
                        i + 1
                    );
                };
                let fits = mission.door_width_m();
                if let (Some(p), Some(from)) = (&plan, here)
                    && p.route_for(from, to, fits).is_none()
                {
                    bad!(
                        "{}:{}: task {} (go_to_room): room: no way through the plan's open doors \
                         {fits:.2} m wide or more (the robot with its field's sides) from {:?} to \
                         {room:?}",
                        path.display(),
                        line_of_array(&text, "task", i, "room"),
                        i + 1,
                        p.rooms()[from].name
                    );
                }
                here = Some(to);
            }
            if matches!(task, TaskSpec::PassDoor { .. }) {
                here = None;
            }
            if matches!(task, TaskSpec::Plaster { .. }) && mission.spray.is_none() {
                bad!(
                    "{}:{}: task {} (plaster): the mission has no [spray] table (the tool and the coat)",
                    path.display(),
                    line_of_task(&text, i, "task"),
                    i + 1
                );
            }
            // A plaster task's own spray settings over the mission's
            // make a tool of their own, checked as [spray] is.
            if let (
                TaskSpec::Plaster {
                    spray: Some(settings),
                    ..
                },
                Some(base),
            ) = (task, &mission.spray)
            {
                let line = line_of_task(&text, i, "spray");
                match crate::spray_with(base, settings) {
                    Err(why) => bad!(
                        "{}:{line}: task {} (plaster): spray: {why}",
                        path.display(),
                        i + 1
                    ),
                    Ok(tool) => {
                        if let Err(stucco_plan::PlanError::Tool { field, why }) =
                            tool.validate(RobotSpec::default().vehicle.width_m)
                        {
                            bad!(
                                "{}:{line}: task {} (plaster): spray {field}: {why}",
                                path.display(),
                                i + 1
                            );
                        }
                    }
                }
            }
            if let Some((key, why)) = task.invalid() {
                bad!(
                    "{}:{}: task {} ({}): {key}: {why}",
                    path.display(),
                    line_of_task(&text, i, key),
                    i + 1,
                    task.name()
                );
            }
        }
        mission.expand_rooms(&text, path)?;
        mission.plan_text = plan_file.map(|(plan_text, _)| plan_text);
        mission.text = text;
        Ok(mission)
    }

    /// Each `plaster` task naming the drawing's rooms becomes, room by
    /// room, going there (`go_to_room`), mapping it (`map_room`, its
    /// default loop) and plastering it; the rooms in the order that goes
    /// each time to the nearest left (fewest doors). A room no open door
    /// leads to is left out of the tasks and stays named: the report
    /// scores it, and lists it among the rooms left.
    fn expand_rooms(&mut self, text: &str, path: &Path) -> Result<()> {
        let plan = self.floor.clone();
        let mut here = plan
            .as_ref()
            .zip(self.start.as_ref().and_then(|s| s.room.as_ref()))
            .and_then(|(p, name)| p.room(name));
        let mut named: Vec<String> = Vec::new();
        let mut name = |room: usize, plan: &FloorPlan| {
            let n = &plan.rooms()[room].name;
            if !named.contains(n) {
                named.push(n.clone());
            }
        };
        let mut tasks = Vec::with_capacity(self.tasks.len());
        let mut task_rooms = Vec::with_capacity(self.tasks.len());
        let mut shares = 0;
        for (i, task) in std::mem::take(&mut self.tasks).into_iter().enumerate() {
            let (
                TaskSpec::Plaster {
                    rooms: Some(rooms), ..
                },
                Some(plan),
            ) = (&task, &plan)
            else {
                if let TaskSpec::Plaster { rooms: Some(_), .. } = task {
                    bad!(
                        "{}:{}: task {} (plaster): rooms: names rooms of the building's drawing, \
                         and the mission has none ([[room]], or plan = FILE)",
                        path.display(),
                        line_of_array(text, "task", i, "rooms"),
                        i + 1
                    );
                }
                match &task {
                    TaskSpec::GoToRoom { room, .. } => {
                        here = plan.as_ref().and_then(|p| p.room(room));
                    }
                    TaskSpec::PassDoor { .. } => here = None,
                    TaskSpec::Plaster { .. } => {
                        if let (Some(h), Some(p)) = (here, &plan) {
                            name(h, p);
                        }
                    }
                    _ => {}
                }
                tasks.push(task);
                task_rooms.push(None);
                continue;
            };
            let mut left: Vec<usize> = match rooms {
                crate::Rooms::All(_) => (0..plan.rooms().len()).collect(),
                crate::Rooms::Named(names) => {
                    let mut out = Vec::new();
                    for n in names {
                        let Some(k) = plan.room(n) else {
                            bad!(
                                "{}:{}: task {} (plaster): rooms: no room {n:?} on the floor plan",
                                path.display(),
                                line_of_array(text, "task", i, "rooms"),
                                i + 1
                            );
                        };
                        if !out.contains(&k) {
                            out.push(k);
                        }
                    }
                    out
                }
            };
            for &k in &left {
                name(k, plan);
            }
            // The same task, a room at a time.
            let mut each = task.clone();
            if let TaskSpec::Plaster { rooms, .. } = &mut each {
                *rooms = None;
            }
            // The nearest room left, by doors passed (the room the robot is
            // in first); those no way leads to through doors the robot
            // fits through are left named.
            let fits = self.door_width_m();
            while let Some((_, j)) = left
                .iter()
                .enumerate()
                .filter_map(|(j, &k)| match here {
                    Some(h) => Some((plan.route_for(h, k, fits)?.len(), j)),
                    None => Some((usize::MAX, j)),
                })
                .min()
            {
                let room = left.remove(j);
                let share = Some((shares, plan.rooms()[room].name.clone()));
                shares += 1;
                if here != Some(room) {
                    tasks.push(TaskSpec::go_to_room(&plan.rooms()[room].name));
                    task_rooms.push(share.clone());
                }
                tasks.push(TaskSpec::map_room_to_plaster());
                tasks.push(each.clone());
                task_rooms.extend([share.clone(), share]);
                here = Some(room);
            }
        }
        self.named_rooms = named;
        self.tasks = tasks;
        self.task_rooms = task_rooms;
        Ok(())
    }

    /// The narrowest door the robot drives through with the mission's
    /// failsafe, m ([`SafetyConfig::door_width_m`] of the default robot,
    /// as the spray tool is checked against it): the routes between the
    /// drawing's rooms go through none narrower.
    pub fn door_width_m(&self) -> f64 {
        self.failsafe.door_width_m(&RobotSpec::default().vehicle)
    }

    /// The room task `k` is a share of, when it is one of a job over rooms
    /// (`plaster` with `rooms`: going there, mapping it, plastering it).
    pub fn task_room(&self, k: usize) -> Option<&str> {
        self.task_rooms.get(k)?.as_ref().map(|(_, r)| r.as_str())
    }

    /// The drawing's rooms the mission's `plaster` tasks plaster: each
    /// task's room where the tasks before it tell it, and every room a
    /// task's `rooms` names, whether a way leads there or not.
    pub fn plaster_rooms(&self) -> &[String] {
        &self.named_rooms
    }

    /// The mission file's text, as the mission was parsed from it.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The text of the plan file it names, as the mission was parsed from
    /// it.
    pub fn plan_text(&self) -> Option<&str> {
        self.plan_text.as_deref()
    }

    /// The floor plan, checked (a door must lie in a wall of each of its
    /// rooms): `None` when the mission has none.
    fn checked_plan(&self, text: &str, path: &Path) -> Result<Option<FloorPlan>> {
        if self.rooms.is_empty() && self.doors.is_empty() && self.windows.is_empty() {
            return Ok(None);
        }
        match FloorPlan::new(self.rooms.clone(), self.doors.clone())
            .and_then(|p| p.with_windows(self.windows.clone()))
        {
            Ok(plan) => Ok(Some(plan)),
            Err(e) => {
                let which = match self.rooms.get(e.index).filter(|_| e.table == "room") {
                    Some(r) => format!("{} ({:?})", e.index + 1, r.name),
                    None => (e.index + 1).to_string(),
                };
                bad!(
                    "{}:{}: [[{}]] {which}: {}: {}",
                    path.display(),
                    line_of_array(text, e.table, e.index, e.field),
                    e.table,
                    e.field,
                    e.why
                )
            }
        }
    }

    /// The floor plan (`[[room]]`, `[[door]]`), when the mission has one.
    pub fn floor_plan(&self) -> Option<FloorPlan> {
        self.floor.clone()
    }

    /// The size of the room the robot starts in, as planned, and the
    /// plan's room it is, if there is a plan.
    pub fn start_room(&self) -> Option<([f64; 2], Option<usize>)> {
        let s = self.start.as_ref()?;
        match (self.floor_plan(), &s.room) {
            (Some(plan), Some(name)) => {
                let room = plan.room(name)?;
                Some((plan.rooms()[room].size_m, Some(room)))
            }
            _ => Some((s.room_m?, None)),
        }
    }

    /// The first value out of its range: its table, its key and why.
    fn invalid(&self) -> Option<(&'static str, &'static str, &'static str)> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let size = |r: &[f64; 2]| r.iter().all(|&v| positive(v));
        if let Some(d) = &self.door_passage {
            let t = "door_passage";
            if !size(&d.room_m) {
                return Some((t, "room_m", "sides must be positive"));
            }
            if d.speeds_mps.is_empty() || !d.speeds_mps.iter().all(|&v| positive(v)) {
                return Some((t, "speeds_mps", "at least one speed, each positive"));
            }
            if d.start.is_empty() {
                return Some((t, "start", "at least one [[door_passage.start]]"));
            }
            if !d.door_map_error_m.is_finite() {
                return Some((t, "door_map_error_m", "must be a number"));
            }
        }
        if let Some(c) = &self.corridor {
            let t = "corridor";
            if !size(&c.room_m) {
                return Some((t, "room_m", "sides must be positive"));
            }
            if !positive(c.speed_mps) {
                return Some((t, "speed_mps", "must be positive"));
            }
            if c.score_x_m[0].partial_cmp(&c.score_x_m[1]) != Some(std::cmp::Ordering::Less) {
                return Some((t, "score_x_m", "the stretch must run forward"));
            }
        }
        if let Some(s) = &self.start {
            let t = "start";
            match (&s.room_m, &s.room, self.rooms.is_empty()) {
                (_, Some(_), true) => {
                    return Some((t, "room", "no floor plan ([[room]], [[door]])"));
                }
                (Some(r), None, true) if !size(r) => {
                    return Some((t, "room_m", "sides must be positive"));
                }
                (Some(_), None, true) => {}
                (None, _, true) => {
                    return Some((t, "room_m", "the room's size as planned (no floor plan)"));
                }
                (_, None, false) => {
                    return Some((t, "room", "the floor plan's room the robot starts in"));
                }
                (Some(_), Some(_), false) => {
                    return Some((t, "room_m", "the floor plan gives the room's size"));
                }
                (None, Some(_), false) => {}
            }
            if !(s.room_sigma_m.is_finite() && s.room_sigma_m >= 0.0) {
                return Some((t, "room_sigma_m", "must not be negative"));
            }
            if !(s.pose_sigma_m.is_finite() && s.pose_sigma_m > 0.0) {
                return Some((t, "pose_sigma_m", "must be positive"));
            }
        }
        if let Some((key, why)) = self.failsafe.invalid() {
            return Some(("failsafe", key, why));
        }
        if !positive(self.time_limit_s) {
            return Some(("", "time_limit_s", "must be positive"));
        }
        if let Some(r) = &self.room_size {
            let t = "room_size";
            if !size(&r.room_m) {
                return Some((t, "room_m", "sides must be positive"));
            }
            if !(r.room_sigma_m.is_finite() && r.room_sigma_m >= 0.0) {
                return Some((t, "room_sigma_m", "must not be negative"));
            }
            if !positive(r.seconds) {
                return Some((t, "seconds", "must be positive"));
            }
            if !positive(r.speed_mps) {
                return Some((t, "speed_mps", "must be positive"));
            }
        }
        None
    }

    /// The executive for the mission's tasks and its failsafe, on `robot`;
    /// `unattended` when no operator is there to answer.
    pub fn executive(&self, robot: &RobotSpec, unattended: bool) -> Executive {
        let robot = robot.clone();
        Executive::new(
            ExecutiveConfig {
                vehicle: robot.vehicle,
                gains: GainSchedule::default(),
                safety: self.failsafe.clone(),
                unattended,
                spray: self.spray.clone(),
                floor: self.floor_plan(),
                body_camera_azimuth_rad: robot.camera.map(|c| c.azimuth_rad),
            },
            self.tasks.clone(),
        )
        .with_rooms(
            self.task_rooms
                .iter()
                .map(|r| r.as_ref().map(|(share, _)| *share))
                .collect(),
        )
    }

    /// The world file, resolved against the mission file's folder; a
    /// mission naming none cannot run in the simulator.
    pub fn world_path(&self, mission_path: &Path) -> Result<PathBuf> {
        let Some(world) = &self.world else {
            bad!(
                "{}: no `world`: a job in the simulator needs the world file it runs in",
                mission_path.display()
            )
        };
        Ok(mission_path
            .parent()
            .map_or_else(|| world.clone(), |d| d.join(world)))
    }
}

/// The line of `key` in the `n`-th `[[task]]` table, or of its header.
fn line_of_task(text: &str, n: usize, key: &str) -> usize {
    line_of_array(text, "task", n, key)
}

/// The line of `key` in the `n`-th `[[table]]`, or of its header.
fn line_of_array(text: &str, table: &str, n: usize, key: &str) -> usize {
    let header_text = format!("[[{table}]]");
    let mut seen = 0;
    let mut header = 0;
    let mut inside = false;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with('[') {
            inside = line == header_text && {
                seen += 1;
                seen == n + 1
            };
            if inside {
                header = i + 1;
            }
            continue;
        }
        if inside && line.split_once('=').is_some_and(|(k, _)| k.trim() == key) {
            return i + 1;
        }
    }
    header
}

/// `text` (the file at `path`) read as a `T`; a fault is [`BadInput`]
/// naming `PATH:LINE:COL`, the key written there when the fault is in its
/// value (toml's message gives only the type it expected), and what was
/// expected. TOML reads `nan` and `inf`; no number in these files may be
/// one (every range check compares false with `nan`).
pub fn parse_toml<T: serde::de::DeserializeOwned>(text: &str, path: &Path) -> Result<T> {
    let parsed = toml::from_str(text).map_err(|e| {
        let (line, column) = e
            .span()
            .map(|s| named_place(text, s.start, e.message()).unwrap_or(s.start))
            .map(|at| stucco_core::line_column(text, at))
            .unwrap_or((0, 0));
        let key = text
            .lines()
            .nth(line.saturating_sub(1))
            .and_then(|l| l.split_once('='))
            .filter(|(k, _)| k.len() < column)
            .map(|(k, _)| k.trim())
            .filter(|k| !k.is_empty() && !e.message().contains(k));
        let at = format!("{}:{line}:{column}", path.display());
        BadInput(match key {
            Some(k) => format!("{at}: `{k}`: {}", e.message()),
            None => format!("{at}: {}", e.message()),
        })
    })?;
    match stucco_core::first_non_finite(text) {
        Some(bad) => Err(BadInput(format!(
            "{}:{}:{}: `{}`: numbers must be finite",
            path.display(),
            bad.line,
            bad.column,
            bad.field
        ))),
        None => Ok(parsed),
    }
}

/// Where the value or key an error names is written, at or after `start`.
/// serde reads a table tagged by one of its keys (a `[[task]]`) from a copy
/// that keeps no places, so toml puts a fault in any task at the first
/// `[[task]]`; the unknown value or key the message names, first written
/// after that, is the fault's place. `None` when the message names none, or
/// it is written on `start`'s own line (the place is right already).
fn named_place(text: &str, start: usize, message: &str) -> Option<usize> {
    let named = |kind: &str| {
        let rest = &message[message.find(kind)? + kind.len()..];
        rest.find('`').map(|end| &rest[..end])
    };
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let after = |pattern: &str| text[start..].find(pattern).map(|i| start + i);
    let at = if let Some(value) = named("unknown variant `") {
        after(&format!("\"{value}\"")).or_else(|| after(&format!("'{value}'")))?
    } else {
        let key = named("unknown field `")?;
        text[start..]
            .match_indices(key)
            .map(|(i, _)| start + i)
            .find(|&i| {
                let before = text[..i].chars().next_back();
                let boundary = before.is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
                boundary
                    && text[i + key.len()..]
                        .trim_start_matches([' ', '\t'])
                        .starts_with('=')
            })?
    };
    (at > line_end).then_some(at)
}

/// The line of `key` in `table` (`""`: the top level; its sub-tables count
/// as inside it), or of the table's header when the key is not written
/// there; 0 when neither is.
pub fn line_of(text: &str, table: &str, key: &str) -> usize {
    let mut current = String::new();
    let mut header = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with('[') {
            current = line
                .trim_matches(|c| c == '[' || c == ']')
                .trim()
                .to_owned();
            if current == table {
                header = i + 1;
            }
            continue;
        }
        let inside = current == table || current.starts_with(&format!("{table}."));
        let written = line.split_once('=').is_some_and(|(k, _)| k.trim() == key);
        if inside && written {
            return i + 1;
        }
    }
    header
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    const TWO_COATS: &str = r#"
name = "two coats"

[start]
room_m = [5.0, 3.0]
room_sigma_m = 0.1

[spray]
thickness_mm = 10.0

[[task]]
task = "plaster"

[[task]]
task = "plaster"
spray = { thickness_mm = 5.0, flow_l_per_min = 6.0 }
"#;

    #[test]
    fn a_second_coat_carries_its_own_spray_settings() {
        let m = Mission::parse(TWO_COATS, Path::new("two-coats.toml")).expect("a mission");
        let base = m.spray.as_ref().expect("[spray]");
        let coats: Vec<f64> = m
            .tasks
            .iter()
            .map(|t| match t {
                TaskSpec::Plaster { spray: None, .. } => base.thickness_mm,
                TaskSpec::Plaster { spray: Some(s), .. } => {
                    crate::spray_with(base, s).expect("settings").thickness_mm
                }
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(coats, [10.0, 5.0]);
    }

    #[test]
    fn a_task_s_bad_spray_settings_are_named_with_their_line() {
        // Not a setting of the tool.
        let text = TWO_COATS.replace("thickness_mm = 5.0,", "thick_mm = 5.0,");
        let e = Mission::parse(&text, Path::new("two-coats.toml"))
            .expect_err("no such setting")
            .to_string();
        assert!(e.starts_with("two-coats.toml:16:"), "{e}");
        assert!(e.contains("thick_mm"), "{e}");
        // A coat the tool cannot lay at its flow.
        let text = TWO_COATS.replace(", flow_l_per_min = 6.0", "");
        let e = Mission::parse(&text, Path::new("two-coats.toml"))
            .expect_err("strokes too fast")
            .to_string();
        assert!(e.starts_with("two-coats.toml:16:"), "{e}");
        assert!(e.contains("flow_l_per_min"), "{e}");
    }

    /// The error a mission whose fault is on its last line is refused
    /// with, named `file` and that line.
    fn refused_at_last_line(text: &str, file: &str) -> String {
        let e = Mission::parse(text, Path::new(file))
            .expect_err("a fault on the last line")
            .to_string();
        let line = text.lines().count();
        assert!(e.starts_with(&format!("{file}:{line}:")), "{e}");
        e
    }

    #[test]
    fn a_failure_policy_it_does_not_know_is_named_with_its_line() {
        let text = format!("{TWO_COATS}\n[failsafe]\non_task_failure = \"carry_on\"\n");
        let e = refused_at_last_line(&text, "policy.toml");
        assert!(e.contains("carry_on"), "{e}");
        let text = format!("{TWO_COATS}\n[failsafe]\non_task_failure = \"continue\"\n");
        let m = Mission::parse(&text, Path::new("policy.toml")).expect("a mission");
        assert_eq!(m.failsafe.on_task_failure, crate::FailurePolicy::Continue);
    }

    #[test]
    fn a_loose_size_policy_it_does_not_know_is_named_with_its_line() {
        let task = |policy: &str| {
            format!("{TWO_COATS}\n[[task]]\ntask = \"map_room\"\non_loose_size = \"{policy}\"\n")
        };
        let e = refused_at_last_line(&task("spray_anyway"), "loose.toml");
        assert!(
            e.contains("spray_anyway") && e.contains("on_loose_size"),
            "{e}"
        );
        // A key no task has, in the third task: named there, not at the first.
        let text = task("continue").replace("on_loose_size", "on_loose_sise");
        let e = refused_at_last_line(&text, "loose.toml");
        assert!(e.contains("on_loose_sise"), "{e}");
        let m = Mission::parse(&task("continue"), Path::new("loose.toml")).expect("a mission");
        match m.tasks.last() {
            Some(TaskSpec::MapRoom { on_loose_size, .. }) => {
                assert_eq!(*on_loose_size, crate::OnTimeout::Continue)
            }
            other => panic!("{other:?}"),
        }
    }

    /// A hall and an office drawn by their corners (the office's each off
    /// by up to 2 cm, as a drawing is), a door between them, a window.
    const DRAWN: &str = r#"
name = "drawn"

[start]
room = "hall"
room_sigma_m = 0.03

[[room]]
name = "hall"
corners = [[0.0, 0.0], [6.0, 0.0], [6.0, 1.5], [0.0, 1.5]]

[[room]]
name = "office"
corners = [[0.01, 1.65], [4.0, 1.66], [3.98, 5.0], [0.0, 4.99]]

[[door]]
rooms = ["hall", "office"]
at_m = [2.0, 1.575]
width_m = 0.9

[[window]]
room = "office"
at_m = [2.0, 5.0]
width_m = 1.2
sill_m = 0.9
head_m = 2.1

[[task]]
task = "go_to_room"
room = "office"
"#;

    #[test]
    fn rooms_drawn_by_their_corners_are_the_rectangles_they_span() {
        let m = Mission::parse(DRAWN, Path::new("drawn.toml")).expect("a mission");
        let plan = m.floor_plan().expect("a plan");
        // Each side the mean of its two corners.
        let office = &plan.rooms()[1];
        let near =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12;
        assert!(near(office.origin_m, [0.005, 1.655]), "{office:?}");
        assert!(near(office.size_m, [3.985, 3.34]), "{office:?}");
        // Off by 3 cm each way at every corner, still the rectangle.
        let rough = DRAWN.replace(
            "[[0.01, 1.65], [4.0, 1.66], [3.98, 5.0], [0.0, 4.99]]",
            "[[0.03, 1.62], [3.97, 1.68], [4.03, 4.97], [-0.03, 5.03]]",
        );
        assert!(Mission::parse(&rough, Path::new("drawn.toml")).is_ok());
        assert_eq!(plan.doors_of(1).count(), 1);
        assert_eq!(plan.windows().len(), 1);
        // Written back and read again, it is the same plan.
        let json = serde_json::to_string(&plan).expect("json");
        let again: FloorPlan = serde_json::from_str(&json).expect("a plan");
        assert_eq!(again, plan);
    }

    #[test]
    fn a_drawing_s_faults_are_named_with_their_line() {
        let fault = |text: &str| {
            Mission::parse(text, Path::new("drawn.toml"))
                .expect_err("a fault")
                .to_string()
        };
        let line = |key: &str, nth: usize| {
            DRAWN
                .lines()
                .enumerate()
                .filter(|(_, l)| l.starts_with(key))
                .nth(nth)
                .map(|(i, _)| i + 1)
                .expect("the line")
        };
        // An L-shaped office is a room of six walls, not its box; a door
        // drawn in the notch's wall, which the hall does not build, is
        // refused naming its line.
        let l_room = DRAWN
            .replace(
                "[[0.01, 1.65], [4.0, 1.66], [3.98, 5.0], [0.0, 4.99]]",
                "[[0.0, 1.65], [4.0, 1.65], [4.0, 3.5], [2.0, 3.5], [2.0, 5.0], [0.0, 5.0]]",
            )
            .replace("at_m = [2.0, 5.0]", "at_m = [1.0, 5.0]");
        let m = Mission::parse(&l_room, Path::new("drawn.toml")).expect("an L-shaped office");
        let plan = m.floor_plan().expect("a plan");
        let office = &plan.rooms()[1];
        assert_eq!(office.outline().len(), 6);
        assert_eq!(office.walls().len(), 6);
        let (_, side) = plan.doors_of(1).next().expect("its door");
        assert_eq!(
            (side.wall, side.along_m),
            (stucco_core::WallName::new(0), 2.0)
        );
        let in_notch = l_room.replace("at_m = [2.0, 1.575]", "at_m = [3.0, 3.5]");
        let e = fault(&in_notch);
        assert!(
            e.starts_with(&format!("drawn.toml:{}:", line("at_m", 0))),
            "{e}"
        );
        assert!(e.contains("\"hall\""), "{e}");
        // Three corners of a square and a fourth near the first: not one.
        let folded = DRAWN.replace(
            "[[0.01, 1.65], [4.0, 1.66], [3.98, 5.0], [0.0, 4.99]]",
            "[[0.0, 1.65], [4.0, 1.65], [4.0, 5.0], [0.01, 1.66]]",
        );
        assert!(fault(&folded).contains("corners"), "{}", fault(&folded));
        assert!(fault(&folded).contains("drawn twice"), "{}", fault(&folded));
        // Clockwise.
        let cw = DRAWN.replace(
            "[[0.0, 0.0], [6.0, 0.0], [6.0, 1.5], [0.0, 1.5]]",
            "[[0.0, 0.0], [0.0, 1.5], [6.0, 1.5], [6.0, 0.0]]",
        );
        let e = fault(&cw);
        assert!(
            e.starts_with(&format!("drawn.toml:{}:", line("corners", 0))),
            "{e}"
        );
        assert!(e.contains("counter-clockwise"), "{e}");
        // Corners and a size that disagree.
        let both = DRAWN.replace(
            "name = \"hall\"\ncorners",
            "name = \"hall\"\nsize_m = [5.0, 1.5]\ncorners",
        );
        assert!(fault(&both).contains("not both"), "{}", fault(&both));
        // A window off every wall of its room, one whose head is below its
        // sill.
        let off = DRAWN.replace("at_m = [2.0, 5.0]", "at_m = [2.0, 3.0]");
        let e = fault(&off);
        assert!(
            e.starts_with(&format!("drawn.toml:{}:", line("at_m", 1))),
            "{e}"
        );
        assert!(e.contains("[[window]] 1: at_m"), "{e}");
        let low = DRAWN.replace("head_m = 2.1", "head_m = 0.5");
        assert!(fault(&low).contains("head_m"), "{}", fault(&low));
        // A door the drawing puts in no wall of one of its rooms.
        let door = DRAWN.replace("at_m = [2.0, 1.575]", "at_m = [2.0, 0.75]");
        let e = fault(&door);
        assert!(
            e.starts_with(&format!("drawn.toml:{}:", line("at_m", 0))),
            "{e}"
        );
    }

    /// The drawing with a store room off the hall behind a shut door, and
    /// one plaster task for its rooms.
    fn plaster_rooms(rooms: &str) -> String {
        let tasks = DRAWN.replace(
            "[[task]]\ntask = \"go_to_room\"\nroom = \"office\"\n",
            &format!("[spray]\n\n[[task]]\ntask = \"plaster\"\nrooms = {rooms}\n"),
        );
        format!(
            "{tasks}\n[[room]]\nname = \"store\"\norigin_m = [6.15, 0.0]\nsize_m = [2.0, 1.5]\n\n\
             [[door]]\nrooms = [\"hall\", \"store\"]\nat_m = [6.075, 0.75]\nwidth_m = 0.8\nshut = true\n"
        )
    }

    /// A door narrower than the robot's body and its field's sides (0.62
    /// m and 5 cm either side, and a centimetre of tracking: 0.74 m) is no
    /// way, as a shut one: the room behind is named but not gone to, and
    /// a `go_to_room` there is refused at load, saying what width it
    /// needs. With the field's sides set narrower, it is a way.
    #[test]
    fn a_door_too_narrow_for_the_robot_and_its_field_is_no_way() {
        let narrow =
            plaster_rooms("\"all\"").replace("width_m = 0.8\nshut = true\n", "width_m = 0.7\n");
        let m = Mission::parse(&narrow, Path::new("drawn.toml")).expect("a mission");
        let gone_to: Vec<&str> = m
            .tasks
            .iter()
            .filter_map(|t| match t {
                TaskSpec::GoToRoom { room, .. } => Some(room.as_str()),
                _ => None,
            })
            .collect();
        assert_eq!(gone_to, ["office"]);
        assert_eq!(m.plaster_rooms(), ["hall", "office", "store"]);
        let sides = narrow.replace("[spray]", "[failsafe]\nlateral_margin_m = 0.02\n\n[spray]");
        let m = Mission::parse(&sides, Path::new("drawn.toml")).expect("a mission");
        assert_eq!(
            m.tasks
                .iter()
                .filter(|t| matches!(t, TaskSpec::GoToRoom { room, .. } if room == "store"))
                .count(),
            1
        );
        let to_store = narrow.replace(
            "[[task]]\ntask = \"plaster\"\nrooms = \"all\"\n",
            "[[task]]\ntask = \"go_to_room\"\nroom = \"store\"\n",
        );
        let e = Mission::parse(&to_store, Path::new("drawn.toml"))
            .expect_err("no way the robot fits")
            .to_string();
        assert!(e.contains("0.74 m wide or more"), "{e}");
        let line = to_store
            .lines()
            .position(|l| l == "room = \"store\"")
            .expect("the line")
            + 1;
        assert!(
            e.starts_with(&format!("drawn.toml:{line}: task 1 (go_to_room): room:")),
            "{e}"
        );
    }

    #[test]
    fn a_plaster_task_naming_rooms_goes_to_each_maps_it_and_plasters_it() {
        let names = |m: &Mission| -> Vec<String> {
            m.tasks
                .iter()
                .map(|t| match t {
                    TaskSpec::GoToRoom { room, .. } => format!("go_to_room {room}"),
                    TaskSpec::Plaster { rooms, .. } => {
                        assert!(rooms.is_none());
                        "plaster".to_owned()
                    }
                    other => other.name().to_owned(),
                })
                .collect()
        };
        let m =
            Mission::parse(&plaster_rooms("\"all\""), Path::new("drawn.toml")).expect("a mission");
        // The hall it starts in first, then the office; the store, shut,
        // named but not gone to.
        assert_eq!(
            names(&m),
            [
                "map_room",
                "plaster",
                "go_to_room office",
                "map_room",
                "plaster"
            ]
        );
        assert_eq!(m.plaster_rooms(), ["hall", "office", "store"]);
        // Each task is of its room's share: a failure gives up that room.
        assert_eq!(
            (0..6).map(|k| m.task_room(k)).collect::<Vec<_>>(),
            [
                Some("hall"),
                Some("hall"),
                Some("office"),
                Some("office"),
                Some("office"),
                None
            ]
        );
        let m = Mission::parse(&plaster_rooms("[\"office\"]"), Path::new("drawn.toml"))
            .expect("a mission");
        assert_eq!(names(&m), ["go_to_room office", "map_room", "plaster"]);
        assert_eq!(m.plaster_rooms(), ["office"]);
        // A room the drawing does not have, named with its line.
        let text = plaster_rooms("[\"attic\"]");
        let line = text
            .lines()
            .position(|l| l.starts_with("rooms = [\"attic"))
            .expect("the line")
            + 1;
        let e = Mission::parse(&text, Path::new("drawn.toml"))
            .expect_err("no attic")
            .to_string();
        assert!(e.starts_with(&format!("drawn.toml:{line}:")), "{e}");
        assert!(e.contains("attic"), "{e}");
        // Neither "all" nor a list: named with its line.
        let e = Mission::parse(&plaster_rooms("\"every\""), Path::new("drawn.toml"))
            .expect_err("not a word it knows")
            .to_string();
        assert!(
            e.contains("rooms: \"all\" or a list") && e.contains("every"),
            "{e}"
        );
        assert!(e.starts_with("drawn.toml:"), "{e}");
        // Rooms without a drawing.
        let e = Mission::parse(
            "name = \"x\"\n[start]\nroom_m = [4.0, 3.0]\n[spray]\n[[task]]\ntask = \"plaster\"\nrooms = \"all\"\n",
            Path::new("bare.toml"),
        )
        .expect_err("no drawing")
        .to_string();
        assert!(
            e.starts_with("bare.toml:7:") && e.contains("drawing"),
            "{e}"
        );
    }
}
