//! The tasks a mission is made of, as a mission file writes them
//! (`[[task]]` tables with `task = "follow_wall"` and the task's fields).

use serde::{Deserialize, Serialize};
pub use stucco_core::{Landmark, Region, Side, WallName};
use stucco_plan::SprayTool;

/// A `plaster` task's own spray settings: fields of the `[spray]` table
/// (see [`SprayTool`]), each over the mission's.
pub type SpraySettings = serde_json::Map<String, serde_json::Value>;

/// `base` with `settings` over it, field by field; why not, when a
/// setting is not one of the tool's or its value is of the wrong kind.
pub fn spray_with(base: &SprayTool, settings: &SpraySettings) -> Result<SprayTool, String> {
    let mut tool = serde_json::to_value(base).map_err(|e| e.to_string())?;
    let Some(fields) = tool.as_object_mut() else {
        return Err("the spray tool is not a table".to_owned());
    };
    for (key, value) in settings {
        if !fields.contains_key(key) {
            return Err(format!("{key}: not a setting of the spray tool"));
        }
        fields.insert(key.clone(), value.clone());
    }
    serde_json::from_value(tool).map_err(|e| e.to_string())
}

/// What a [`TaskSpec::WaitForOperator`] does when nobody answers in time,
/// and a [`TaskSpec::MapRoom`] when its time is up with every wall seen
/// but the room's size not yet known to its bound.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnTimeout {
    /// The mission goes on (for unattended runs).
    Continue,
    /// The task fails, and with it the mission.
    #[default]
    Fail,
}

fn survey_speed() -> f64 {
    0.4
}
fn sightings() -> usize {
    20
}
fn size_sigma() -> f64 {
    0.005
}
fn map_timeout() -> f64 {
    180.0
}
fn localize_sigma() -> f64 {
    0.02
}
fn localize_timeout() -> f64 {
    20.0
}
fn drive_speed() -> f64 {
    0.3
}
fn follow_speed() -> f64 {
    0.25
}
fn approach() -> f64 {
    1.0
}
fn beyond() -> f64 {
    1.0
}
fn yes() -> bool {
    true
}
fn settle() -> f64 {
    1.0
}
fn survey_loop_speed() -> f64 {
    0.3
}

/// One task of a mission. Positions are in the room frame (see
/// [`WallName`]); a position along a wall runs along its axis (y for the
/// west and east walls, x for the south and north ones).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "task", rename_all = "snake_case", deny_unknown_fields)]
pub enum TaskSpec {
    /// Observes the room's walls from the places view planning chooses (or
    /// while driving a loop given), until each of `walls` has been seen in
    /// `min_sightings` scans and each one's place, measured against the
    /// wall that fixes the frame across it, is known to
    /// `max_size_sigma_m`: walls, size, and the doors seen on the way. A
    /// wall no place the robot reaches sees (furniture before it along its
    /// length, too short for a line) is left out and reported
    /// (`walls_hidden`); its place stays the drawing's.
    MapRoom {
        /// A loop to drive, room frame, m; by default none: the walls are
        /// looked at from the places view planning chooses.
        #[serde(default)]
        path: Option<Vec<[f64; 2]>>,
        /// The walls to observe (by default every wall of the room).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        walls: Option<Vec<WallName>>,
        /// Scans each must have been used in.
        #[serde(default = "sightings")]
        min_sightings: usize,
        /// Speed, m/s.
        #[serde(default = "survey_speed")]
        speed_mps: f64,
        /// Done when both sides of the room are known to this, m (σ).
        #[serde(default = "size_sigma")]
        max_size_sigma_m: f64,
        /// Fails after this long, s.
        #[serde(default = "map_timeout")]
        timeout_s: f64,
        /// At the timeout, every wall seen but the size not yet known to
        /// `max_size_sigma_m`: fail (by default), or be done with the
        /// size as known then (a `room_size_loose` event tells how well).
        /// A job from the drawing goes on: the plaster task sprays only
        /// where the robot's place is known to its own bound.
        #[serde(default)]
        on_loose_size: OnTimeout,
    },
    /// Stands still until the pose is known to `max_sigma_m` in the known
    /// map.
    Localize {
        /// Done when the position is known to this, m (σ, the larger axis).
        #[serde(default = "localize_sigma")]
        max_sigma_m: f64,
        /// Fails after this long, s.
        #[serde(default = "localize_timeout")]
        timeout_s: f64,
    },
    /// Moves by `(dx, dy, dθ)` in the robot's frame at the task's start,
    /// or to `(dx, dy, dθ)` in the frame of `landmark` (a wall or a door,
    /// faced from inside the room: see [`Landmark`]).
    MoveRelative {
        /// Forward, m.
        dx_m: f64,
        /// To the left, m.
        #[serde(default)]
        dy_m: f64,
        /// Turn, degrees counter-clockwise.
        #[serde(default)]
        dtheta_deg: f64,
        /// The thing the move is relative to (the robot, without it).
        #[serde(default)]
        landmark: Option<Landmark>,
        /// Speed, m/s.
        #[serde(default = "drive_speed")]
        speed_mps: f64,
    },
    /// Stops parallel to `wall` at `standoff_m`, at `at_m` along it, the
    /// wall on `side`.
    AlignToWall {
        /// The wall.
        wall: WallName,
        /// Distance from the wall to the rear axle's middle, m.
        standoff_m: f64,
        /// Position along the wall, m.
        at_m: f64,
        /// Which side of the robot the wall ends up on.
        #[serde(default)]
        side: Side,
        /// Speed, m/s.
        #[serde(default = "drive_speed")]
        speed_mps: f64,
    },
    /// Follows `wall` at `standoff_m` from `from_m` to `to_m` along it (the
    /// direction sets which side the wall is on).
    FollowWall {
        /// The wall.
        wall: WallName,
        /// Distance from the wall to the rear axle's middle, m.
        standoff_m: f64,
        /// Where the pass starts, m along the wall.
        from_m: f64,
        /// Where it ends, m along the wall.
        to_m: f64,
        /// Speed, m/s.
        #[serde(default = "follow_speed")]
        speed_mps: f64,
    },
    /// Drives through a door of the room (by its index among the doors the
    /// robot knows, in the order they were found or given).
    PassDoor {
        /// The door.
        door: usize,
        /// Distance before the door where the approach line starts, m.
        #[serde(default = "approach")]
        approach_m: f64,
        /// Distance beyond the door where the task ends, m.
        #[serde(default = "beyond")]
        beyond_m: f64,
        /// Speed, m/s.
        #[serde(default = "drive_speed")]
        speed_mps: f64,
    },
    /// Goes to the room of the floor plan named `room`: through each door
    /// of the plan's shortest way in turn, as [`TaskSpec::PassDoor`] does,
    /// the robot's frame moving to the next room beyond each. Done at once
    /// when the robot is there already.
    GoToRoom {
        /// The room.
        room: String,
        /// Distance before each door where the approach line starts, m.
        #[serde(default = "approach")]
        approach_m: f64,
        /// Distance beyond each door where its passage ends, m.
        #[serde(default = "beyond")]
        beyond_m: f64,
        /// Speed, m/s.
        #[serde(default = "drive_speed")]
        speed_mps: f64,
    },
    /// Plasters the room's walls and ceiling with the mission's spray tool:
    /// plans stations and strokes on the room as the robot knows it (its
    /// size, doors, windows, what stands on the floor), then drives from
    /// station to station and sprays. Done strokes are kept in the
    /// checkpoint; a resumed run carries out the same plan from the next
    /// stroke.
    Plaster {
        /// The walls to plaster (by default every wall of the room).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        walls: Option<Vec<WallName>>,
        /// Plaster the ceiling too.
        #[serde(default = "yes")]
        ceiling: bool,
        /// Driving speed between stations, m/s.
        #[serde(default = "follow_speed")]
        speed_mps: f64,
        /// Standing time at a station before spraying, for the estimate to
        /// settle, s.
        #[serde(default = "settle")]
        settle_s: f64,
        /// First drive a loop round the room, the camera finding the
        /// walls' windows and doors, and plan on what it found.
        #[serde(default = "yes")]
        survey: bool,
        /// Speed of that loop, m/s (the camera's profiles fall this far
        /// apart over a twentieth of a second).
        #[serde(default = "survey_loop_speed")]
        survey_speed_mps: f64,
        /// Only this part of the one wall listed (`walls = ["south"]`,
        /// `ceiling = false`).
        #[serde(default)]
        region: Option<Region>,
        /// This task's own spray settings over the mission's `[spray]`,
        /// field by field (`spray = { thickness_mm = 5.0 }`: a thinner
        /// second coat is a task of its own).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        spray: Option<SpraySettings>,
        /// The drawing's rooms to plaster, one after the other (`"all"`, or
        /// a list of names): the mission expands it at load into going to
        /// each room, mapping it and plastering it ([`Rooms`]). Without
        /// it: the room the robot is in.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rooms: Option<Rooms>,
    },
    /// Stops and waits for the operator's `continue`.
    WaitForOperator {
        /// What the operator is asked.
        prompt: String,
        /// Gives up after this long, s (never, without it).
        #[serde(default)]
        timeout_s: Option<f64>,
        /// What giving up means.
        #[serde(default)]
        on_timeout: OnTimeout,
    },
}

/// The rooms a `plaster` task names: every room of the drawing, or these.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, try_from = "RoomsText")]
pub enum Rooms {
    /// `"all"`: every room of the drawing.
    All(AllRooms),
    /// The rooms by name, plastered in the order a route through them
    /// finds shortest.
    Named(Vec<String>),
}

/// The word `all`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AllRooms {
    /// Every room.
    All,
}

/// `rooms` as a mission file writes it: a word or a list.
#[derive(Deserialize)]
#[serde(untagged)]
enum RoomsText {
    Word(String),
    Names(Vec<String>),
}

impl TryFrom<RoomsText> for Rooms {
    type Error = String;
    fn try_from(t: RoomsText) -> Result<Self, String> {
        match t {
            RoomsText::Word(w) if w == "all" => Ok(Rooms::All(AllRooms::All)),
            RoomsText::Word(w) => Err(format!(
                "rooms: \"all\" or a list of the drawing's room names, not {w:?}"
            )),
            RoomsText::Names(n) => Ok(Rooms::Named(n)),
        }
    }
}

impl TaskSpec {
    /// A `go_to_room` task with a mission file's defaults.
    pub fn go_to_room(room: &str) -> TaskSpec {
        TaskSpec::GoToRoom {
            room: room.to_owned(),
            approach_m: approach(),
            beyond_m: beyond(),
            speed_mps: drive_speed(),
        }
    }

    /// A `map_room` task with a mission file's defaults (the loop inside
    /// the walls).
    pub fn map_room() -> TaskSpec {
        TaskSpec::MapRoom {
            path: None,
            walls: None,
            min_sightings: sightings(),
            speed_mps: survey_speed(),
            max_size_sigma_m: size_sigma(),
            timeout_s: map_timeout(),
            on_loose_size: OnTimeout::default(),
        }
    }

    /// The `map_room` a job from the drawing puts before each room's
    /// plastering: [`TaskSpec::map_room`], but a room whose walls are all
    /// seen is not given up for a size known a few millimetres less well
    /// than asked (the plaster task guards its spraying itself).
    pub fn map_room_to_plaster() -> TaskSpec {
        let mut task = TaskSpec::map_room();
        if let TaskSpec::MapRoom { on_loose_size, .. } = &mut task {
            *on_loose_size = OnTimeout::Continue;
        }
        task
    }

    /// The task a telecommand asks for, with the defaults a mission file
    /// would give it; `None` for commands that are not tasks.
    pub fn from_command(c: &stucco_core::Command) -> Option<TaskSpec> {
        use stucco_core::Command as C;
        Some(match c {
            C::GoToRoom { room } => TaskSpec::go_to_room(room),
            C::MapRoom => TaskSpec::map_room(),
            C::PassDoor { door } => TaskSpec::PassDoor {
                door: *door,
                approach_m: approach(),
                beyond_m: beyond(),
                speed_mps: drive_speed(),
            },
            C::FollowWall {
                wall,
                standoff_m,
                from_m,
                to_m,
            } => TaskSpec::FollowWall {
                wall: *wall,
                standoff_m: *standoff_m,
                from_m: *from_m,
                to_m: *to_m,
                speed_mps: follow_speed(),
            },
            C::MoveRelative {
                dx_m,
                dy_m,
                dtheta_deg,
                landmark,
            } => TaskSpec::MoveRelative {
                dx_m: *dx_m,
                dy_m: *dy_m,
                dtheta_deg: *dtheta_deg,
                landmark: *landmark,
                speed_mps: drive_speed(),
            },
            C::AlignToWall {
                wall,
                standoff_m,
                at_m,
                side,
            } => TaskSpec::AlignToWall {
                wall: *wall,
                standoff_m: *standoff_m,
                at_m: *at_m,
                side: *side,
                speed_mps: drive_speed(),
            },
            C::PlasterSurface { surface, region } => TaskSpec::Plaster {
                walls: Some(match surface {
                    stucco_core::SurfaceId::Wall(w) => vec![*w],
                    stucco_core::SurfaceId::Ceiling => Vec::new(),
                }),
                ceiling: *surface == stucco_core::SurfaceId::Ceiling,
                speed_mps: follow_speed(),
                settle_s: settle(),
                survey: true,
                survey_speed_mps: survey_loop_speed(),
                region: *region,
                spray: None,
                rooms: None,
            },
            _ => return None,
        })
    }

    /// The task's name as the mission file writes it.
    pub fn name(&self) -> &'static str {
        match self {
            TaskSpec::MapRoom { .. } => "map_room",
            TaskSpec::Localize { .. } => "localize",
            TaskSpec::MoveRelative { .. } => "move_relative",
            TaskSpec::AlignToWall { .. } => "align_to_wall",
            TaskSpec::FollowWall { .. } => "follow_wall",
            TaskSpec::PassDoor { .. } => "pass_door",
            TaskSpec::GoToRoom { .. } => "go_to_room",
            TaskSpec::Plaster { .. } => "plaster",
            TaskSpec::WaitForOperator { .. } => "wait_for_operator",
        }
    }

    /// The first value out of its range: the key and why.
    pub fn invalid(&self) -> Option<(&'static str, &'static str)> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let finite = |v: f64| v.is_finite();
        let speed = |v: f64| positive(v) && v <= 0.8;
        const SPEED: &str = "must be positive and at most the robot's 0.8 m/s";
        match self {
            TaskSpec::MapRoom {
                path,
                walls,
                speed_mps,
                max_size_sigma_m,
                timeout_s,
                ..
            } => {
                if walls.as_ref().is_some_and(Vec::is_empty) {
                    return Some(("walls", "at least one wall to observe"));
                }
                if let Some(p) = path
                    && (p.len() < 3 || !p.iter().flatten().all(|&v| finite(v)))
                {
                    return Some(("path", "at least three points, each finite"));
                }
                if !speed(*speed_mps) {
                    return Some(("speed_mps", SPEED));
                }
                if !positive(*max_size_sigma_m) {
                    return Some(("max_size_sigma_m", "must be positive"));
                }
                if !positive(*timeout_s) {
                    return Some(("timeout_s", "must be positive"));
                }
            }
            TaskSpec::Localize {
                max_sigma_m,
                timeout_s,
            } => {
                if !positive(*max_sigma_m) {
                    return Some(("max_sigma_m", "must be positive"));
                }
                if !positive(*timeout_s) {
                    return Some(("timeout_s", "must be positive"));
                }
            }
            TaskSpec::Plaster {
                walls,
                ceiling,
                speed_mps,
                settle_s,
                survey_speed_mps,
                region,
                ..
            } => {
                if walls.as_ref().is_some_and(Vec::is_empty) && !ceiling {
                    return Some(("walls", "nothing to plaster: no walls and no ceiling"));
                }
                if let Some(r) = region {
                    if walls.as_ref().is_none_or(|w| w.len() != 1) || *ceiling {
                        return Some((
                            "region",
                            "a region is part of one wall: walls = [that wall], ceiling = false",
                        ));
                    }
                    let span = |v: &[f64; 2]| v[0].is_finite() && v[1].is_finite() && v[1] > v[0];
                    if !span(&r.along_m) || !span(&r.height_m) || r.height_m[0] < 0.0 {
                        return Some((
                            "region",
                            "along_m and height_m each from a lower to a higher value, heights not below the floor",
                        ));
                    }
                }
                if !speed(*survey_speed_mps) {
                    return Some(("survey_speed_mps", SPEED));
                }
                if !speed(*speed_mps) {
                    return Some(("speed_mps", SPEED));
                }
                if !(finite(*settle_s) && *settle_s >= 0.0) {
                    return Some(("settle_s", "must be zero or more"));
                }
            }
            TaskSpec::MoveRelative {
                dx_m,
                dy_m,
                dtheta_deg,
                speed_mps,
                ..
            } => {
                if !(finite(*dx_m) && finite(*dy_m) && finite(*dtheta_deg)) {
                    return Some(("dx_m", "the motion must be finite"));
                }
                if !speed(*speed_mps) {
                    return Some(("speed_mps", SPEED));
                }
            }
            TaskSpec::AlignToWall {
                standoff_m,
                at_m,
                speed_mps,
                ..
            } => {
                if !positive(*standoff_m) {
                    return Some(("standoff_m", "must be positive"));
                }
                if !finite(*at_m) {
                    return Some(("at_m", "must be a number"));
                }
                if !speed(*speed_mps) {
                    return Some(("speed_mps", SPEED));
                }
            }
            TaskSpec::FollowWall {
                standoff_m,
                from_m,
                to_m,
                speed_mps,
                ..
            } => {
                if !positive(*standoff_m) {
                    return Some(("standoff_m", "must be positive"));
                }
                if !(finite(*from_m) && finite(*to_m)) || (from_m - to_m).abs() < 0.1 {
                    return Some(("to_m", "the pass must be at least 0.1 m long"));
                }
                if !speed(*speed_mps) {
                    return Some(("speed_mps", SPEED));
                }
            }
            TaskSpec::PassDoor {
                approach_m,
                beyond_m,
                speed_mps,
                ..
            }
            | TaskSpec::GoToRoom {
                approach_m,
                beyond_m,
                speed_mps,
                ..
            } => {
                if !positive(*approach_m) {
                    return Some(("approach_m", "must be positive"));
                }
                if !positive(*beyond_m) {
                    return Some(("beyond_m", "must be positive"));
                }
                if !speed(*speed_mps) {
                    return Some(("speed_mps", SPEED));
                }
            }
            TaskSpec::WaitForOperator { timeout_s, .. } => {
                if timeout_s.is_some_and(|t| !positive(t)) {
                    return Some(("timeout_s", "must be positive"));
                }
            }
        }
        None
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        task: Vec<TaskSpec>,
    }

    #[test]
    fn tasks_read_from_toml_with_their_defaults() {
        let f: File = toml::from_str(
            r#"
            [[task]]
            task = "map_room"

            [[task]]
            task = "follow_wall"
            wall = "south"
            standoff_m = 0.6
            from_m = 2.4
            to_m = 4.0

            [[task]]
            task = "wait_for_operator"
            prompt = "check the first pass"
            timeout_s = 5.0
            on_timeout = "continue"
            "#,
        )
        .expect("valid");
        assert_eq!(f.task.len(), 3);
        assert!(matches!(f.task[0], TaskSpec::MapRoom { path: None, .. }));
        assert_eq!(f.task[1].name(), "follow_wall");
        assert!(f.task.iter().all(|t| t.invalid().is_none()));
    }

    #[test]
    fn unknown_tasks_and_fields_are_refused() {
        let bad_task = toml::from_str::<File>("[[task]]\ntask = \"fly\"\n");
        assert!(bad_task.is_err());
        let bad_field =
            toml::from_str::<File>("[[task]]\ntask = \"move_relative\"\ndx_m = 1.0\nspeed = 0.3\n");
        let msg = bad_field.expect_err("unknown field").to_string();
        assert!(msg.contains("speed"), "{msg}");
    }

    #[test]
    fn values_out_of_range_are_named() {
        let t = TaskSpec::FollowWall {
            wall: WallName::NORTH,
            standoff_m: 0.6,
            from_m: 2.0,
            to_m: 2.05,
            speed_mps: 0.25,
        };
        assert_eq!(t.invalid().map(|(k, _)| k), Some("to_m"));
        let t = TaskSpec::MoveRelative {
            dx_m: 1.0,
            dy_m: 0.0,
            dtheta_deg: 0.0,
            landmark: None,
            speed_mps: 2.0,
        };
        assert_eq!(t.invalid().map(|(k, _)| k), Some("speed_mps"));
    }
}
