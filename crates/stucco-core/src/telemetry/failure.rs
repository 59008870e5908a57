//! Why a task (and with it the mission) failed: typed, for programs, and
//! each with the sentence a person reads.

use crate::WallName;
use serde::{Deserialize, Serialize};

/// Why a task failed. New kinds may come: match with a wildcard.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "code", rename_all = "snake_case")]
#[non_exhaustive]
pub enum TaskFailure {
    /// The pose estimate was lost (past the supervisor's timeout).
    EstimateLost,
    /// The way stayed blocked past the supervisor's timeout.
    WayBlocked {
        /// Where the robot stood: x, y (m) and heading (deg), in its
        /// room's frame.
        #[serde(default)]
        pose: [f64; 3],
        /// What held it last, in the same frame, m.
        #[serde(default)]
        obstacle_m: Option<[f64; 2]>,
        /// It was backing.
        #[serde(default)]
        backing: bool,
    },
    /// The e-stop was pressed with no operator there.
    EStop,
    /// A bumper touched something with no operator there.
    Bumper,
    /// `follow_wall`: the pass ends nearer the wall's end than the body
    /// reaches ahead.
    PassEndsAtCorner {
        /// Room left to the wall's end, m.
        room_left_m: f64,
        /// What the body reaches ahead of the rear axle, m.
        front_m: f64,
    },
    /// The room is too small to turn in onto a wall.
    RoomTooSmallToTurn,
    /// A pass starts too near a corner to turn onto it.
    PassStartsAtCorner {
        /// Where the pass starts, m along the wall.
        at_m: f64,
        /// What a turn on the spot needs from the walls, m.
        clearance_m: f64,
        /// The run-in it needs, m.
        run_in_m: f64,
    },
    /// A door of the room, by its index among those found, is not known.
    UnknownDoor {
        /// The task.
        task: String,
        /// The door.
        door: usize,
        /// Doors found.
        found: usize,
    },
    /// A wall the room does not have, by its index.
    UnknownWall {
        /// The task.
        task: String,
        /// The wall.
        wall: WallName,
        /// How many walls the room has.
        walls: usize,
    },
    /// `go_to_room` with no floor plan in the mission.
    NoFloorPlan,
    /// `go_to_room` to a room the plan does not have.
    UnknownRoom {
        /// The room asked for.
        room: String,
        /// The plan's rooms.
        rooms: Vec<String>,
    },
    /// The robot does not know which room of the plan it is in.
    RoomNotKnown,
    /// No way on the plan from the robot's room to the one asked for.
    NoRoute {
        /// The robot's room.
        from: String,
        /// The room asked for.
        to: String,
    },
    /// A door of the plan on the way is not known in the robot's room.
    PlanDoorNotSeen {
        /// The door of the plan.
        door: usize,
    },
    /// Through a door, the estimate did not move into the room beyond.
    EstimateNotBeyondDoor {
        /// The task.
        task: String,
        /// The room beyond.
        room: String,
    },
    /// A door of the plan is not a door of the robot's room.
    DoorNotOfThisRoom {
        /// The task.
        task: String,
        /// The door of the plan.
        door: usize,
    },
    /// `map_room`: the room's size not known well enough in time.
    RoomSizeLoose {
        /// The loosest side's uncertainty, m (σ).
        sigma_m: f64,
        /// The task's time, s.
        timeout_s: f64,
    },
    /// `map_room`: walls not seen often enough in time.
    WallsNotSeen {
        /// The walls.
        walls: Vec<WallName>,
        /// The task's time, s.
        timeout_s: f64,
    },
    /// `map_room`: no clear way reaches any corner of its loop.
    NoWayToCorners,
    /// `map_room`: no clear way reaches any place the walls still unseen
    /// are seen from.
    NoWayToViews,
    /// `localize`: the position not known well enough in time.
    NotLocalized {
        /// How well it is known, m (σ).
        sigma_m: f64,
        /// The task's time, s.
        timeout_s: f64,
    },
    /// `wait_for_operator`: nobody answered in time.
    NobodyAnswered,
    /// `plaster`: the mission has no spray tool.
    NoSprayTool,
    /// `plaster`: no plan to carry out.
    NoPlan,
    /// `plaster`: the planner found no plan.
    Planning {
        /// The planner's words.
        error: String,
    },
    /// `plaster`: every one of the plan's stations was given up (no way
    /// reached it, or the position stayed too loose to spray there) and
    /// nothing was plastered.
    AllStationsGivenUp {
        /// The stations given up.
        stations: usize,
        /// How many of them for a position too loose to spray there (the
        /// rest no way reached).
        #[serde(default)]
        loose: usize,
        /// The plasterable area they were to reach, m².
        unreachable_m2: f64,
    },
    /// `plaster`: the plan made on what the robot found has no station:
    /// nowhere the robot can stand reaches any of the surface asked for.
    NothingReachable {
        /// The plasterable area asked for, all of it out of reach, m².
        unreachable_m2: f64,
    },
    /// `plaster`: a checkpoint's plan is missing.
    CheckpointPlanMissing {
        /// The station the checkpoint stopped at.
        station: usize,
    },
    /// `plaster`: the plan beside a checkpoint is not the one it was
    /// carrying out.
    CheckpointPlanDiffers {
        /// The digest of the plan found.
        found: String,
        /// The digest the checkpoint names.
        expected: String,
    },
    /// `plaster`: the robot does not face the surface of its station.
    NotFacingSurface {
        /// The station.
        station: usize,
    },
    /// `plaster`: at a station the position stayed known too loosely to
    /// spray on for as long as the supervisor waits for the estimate.
    PositionTooLoose {
        /// The station.
        station: usize,
        /// The position's σ when the task gave up waiting, m.
        sigma_m: f64,
        /// The σ spraying needs (`spray_max_sigma_m`), m.
        limit_m: f64,
        /// How long it waited (`lost_timeout_s`), s.
        waited_s: f64,
    },
    /// `plaster`: the task's own spray settings do not make a tool.
    SpraySettings {
        /// Why.
        error: String,
    },
}

impl TaskFailure {
    /// The kind's name, as the JSON's `code` writes it.
    pub fn code(&self) -> &'static str {
        match self {
            TaskFailure::EstimateLost => "estimate_lost",
            TaskFailure::WayBlocked { .. } => "way_blocked",
            TaskFailure::EStop => "e_stop",
            TaskFailure::Bumper => "bumper",
            TaskFailure::PassEndsAtCorner { .. } => "pass_ends_at_corner",
            TaskFailure::RoomTooSmallToTurn => "room_too_small_to_turn",
            TaskFailure::PassStartsAtCorner { .. } => "pass_starts_at_corner",
            TaskFailure::UnknownDoor { .. } => "unknown_door",
            TaskFailure::UnknownWall { .. } => "unknown_wall",
            TaskFailure::NoFloorPlan => "no_floor_plan",
            TaskFailure::UnknownRoom { .. } => "unknown_room",
            TaskFailure::RoomNotKnown => "room_not_known",
            TaskFailure::NoRoute { .. } => "no_route",
            TaskFailure::PlanDoorNotSeen { .. } => "plan_door_not_seen",
            TaskFailure::EstimateNotBeyondDoor { .. } => "estimate_not_beyond_door",
            TaskFailure::DoorNotOfThisRoom { .. } => "door_not_of_this_room",
            TaskFailure::RoomSizeLoose { .. } => "room_size_loose",
            TaskFailure::WallsNotSeen { .. } => "walls_not_seen",
            TaskFailure::NoWayToCorners => "no_way_to_corners",
            TaskFailure::NoWayToViews => "no_way_to_views",
            TaskFailure::NotLocalized { .. } => "not_localized",
            TaskFailure::NobodyAnswered => "nobody_answered",
            TaskFailure::NoSprayTool => "no_spray_tool",
            TaskFailure::NoPlan => "no_plan",
            TaskFailure::Planning { .. } => "planning",
            TaskFailure::AllStationsGivenUp { .. } => "all_stations_given_up",
            TaskFailure::NothingReachable { .. } => "nothing_reachable",
            TaskFailure::CheckpointPlanMissing { .. } => "checkpoint_plan_missing",
            TaskFailure::CheckpointPlanDiffers { .. } => "checkpoint_plan_differs",
            TaskFailure::NotFacingSurface { .. } => "not_facing_surface",
            TaskFailure::PositionTooLoose { .. } => "position_too_loose",
            TaskFailure::SpraySettings { .. } => "spray_settings",
        }
    }
}

impl std::fmt::Display for TaskFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TaskFailure::EstimateLost => write!(f, "the pose estimate is lost"),
            TaskFailure::WayBlocked {
                pose: [x, y, deg],
                obstacle_m,
                backing,
            } => {
                let how = if *backing { "backing" } else { "driving" };
                write!(
                    f,
                    "the way stayed blocked: {how} at ({x:.2}, {y:.2}) m heading {deg:.0}°"
                )?;
                match obstacle_m {
                    Some([ox, oy]) => write!(f, ", held for an echo at ({ox:.2}, {oy:.2}) m"),
                    None => Ok(()),
                }
            }
            TaskFailure::EStop => write!(f, "e-stop pressed"),
            TaskFailure::Bumper => write!(f, "bumper: the robot touched something"),
            TaskFailure::PassEndsAtCorner {
                room_left_m,
                front_m,
            } => write!(
                f,
                "follow_wall: the pass ends {room_left_m:.2} m from the wall's end; the body \
                 reaches {front_m:.2} m ahead"
            ),
            TaskFailure::RoomTooSmallToTurn => write!(f, "the room is too small to turn in"),
            TaskFailure::PassStartsAtCorner {
                at_m,
                clearance_m,
                run_in_m,
            } => write!(
                f,
                "the pass starts {at_m:.2} m along the wall: too near the corner to turn onto it \
                 (a turn needs {clearance_m:.2} m from the walls and {run_in_m:.1} m of run-in)"
            ),
            TaskFailure::UnknownDoor { task, door, found } => {
                write!(f, "{task}: door {door} is not known ({found} doors found)")
            }
            TaskFailure::UnknownWall { task, wall, walls } => write!(
                f,
                "{task}: the room has no {wall} (its walls are 0 to {})",
                walls.saturating_sub(1)
            ),
            TaskFailure::NoFloorPlan => write!(
                f,
                "go_to_room: the mission has no floor plan ([[room]], [[door]])"
            ),
            TaskFailure::UnknownRoom { room, rooms } => write!(
                f,
                "go_to_room: no room {room:?} on the plan (it has {})",
                rooms.join(", ")
            ),
            TaskFailure::RoomNotKnown => {
                write!(f, "go_to_room: the robot does not know which room it is in")
            }
            TaskFailure::NoRoute { from, to } => {
                write!(
                    f,
                    "go_to_room: no way on the plan from {from} to {to} through open doors the \
                     robot fits through with its field"
                )
            }
            TaskFailure::PlanDoorNotSeen { door } => write!(
                f,
                "go_to_room: door {door} of the plan is not known in this room"
            ),
            TaskFailure::EstimateNotBeyondDoor { task, room } => write!(
                f,
                "{task}: the robot went through the door into {room} but its estimate did not \
                 follow (it is not beyond the door)"
            ),
            TaskFailure::DoorNotOfThisRoom { task, door } => write!(
                f,
                "{task}: door {door} of the plan is not a door of the robot's room"
            ),
            TaskFailure::RoomSizeLoose { sigma_m, timeout_s } => write!(
                f,
                "map_room: the room's size is known to {:.1} mm after {timeout_s} s",
                1e3 * sigma_m
            ),
            TaskFailure::WallsNotSeen { walls, timeout_s } => {
                let names: Vec<String> = walls.iter().map(|w| w.index().to_string()).collect();
                write!(
                    f,
                    "map_room: walls {} not seen in {timeout_s} s",
                    names.join(", ")
                )
            }
            TaskFailure::NoWayToCorners => {
                write!(f, "map_room: no clear way reaches any corner of the loop")
            }
            TaskFailure::NoWayToViews => write!(
                f,
                "map_room: no clear way reaches a place the walls still unseen are seen from"
            ),
            TaskFailure::NotLocalized { sigma_m, timeout_s } => write!(
                f,
                "localize: the position is known to {:.1} mm after {timeout_s} s",
                1e3 * sigma_m
            ),
            TaskFailure::NobodyAnswered => write!(f, "wait_for_operator: nobody answered"),
            TaskFailure::NoSprayTool => write!(f, "plaster: the mission has no [spray] tool"),
            TaskFailure::NoPlan => write!(f, "plaster: no plan"),
            TaskFailure::Planning { error } => write!(f, "plaster: {error}"),
            TaskFailure::AllStationsGivenUp {
                stations,
                loose: 0,
                unreachable_m2,
            } => write!(
                f,
                "plaster: no way reached any of its {stations} stations: nothing plastered \
                 ({unreachable_m2:.1} m² left unreachable)"
            ),
            TaskFailure::AllStationsGivenUp {
                stations,
                loose,
                unreachable_m2,
            } => write!(
                f,
                "plaster: all {stations} stations given up, {loose} for a position too loose \
                 to spray there and {} no way reached: nothing plastered ({unreachable_m2:.1} m² \
                 left unreachable)",
                stations - loose
            ),
            TaskFailure::NothingReachable { unreachable_m2 } => write!(
                f,
                "plaster: no station reaches any of the surface from where the robot can \
                 stand ({unreachable_m2:.1} m² unreachable)"
            ),
            TaskFailure::CheckpointPlanMissing { station } => write!(
                f,
                "plaster: the checkpoint stopped at station {station} but the plan it was \
                 carrying out is missing"
            ),
            TaskFailure::CheckpointPlanDiffers { found, expected } => write!(
                f,
                "plaster: the plan beside the checkpoint ({found}) is not the one it was \
                 carrying out ({expected})"
            ),
            TaskFailure::NotFacingSurface { station } => write!(
                f,
                "plaster: the robot does not face the surface of station {station}"
            ),
            TaskFailure::PositionTooLoose {
                station,
                sigma_m,
                limit_m,
                waited_s,
            } => write!(
                f,
                "plaster: at station {station} the position stayed known to {:.1} mm for \
                 {waited_s} s; spraying needs {:.1} mm",
                1e3 * sigma_m,
                1e3 * limit_m
            ),
            TaskFailure::SpraySettings { error } => write!(f, "plaster: spray: {error}"),
        }
    }
}

impl std::error::Error for TaskFailure {}

#[cfg(test)]
mod tests {
    use super::*;

    /// A task whose stations were all given up tells how many for a
    /// position too loose and how many no way reached: an operator clears
    /// a way for the one, not the other.
    #[test]
    fn stations_all_given_up_say_why() {
        let words = |stations, loose| {
            TaskFailure::AllStationsGivenUp {
                stations,
                loose,
                unreachable_m2: 4.0,
            }
            .to_string()
        };
        let no_way = words(3, 0);
        assert!(
            no_way.contains("no way reached any of its 3 stations"),
            "{no_way}"
        );
        let mixed = words(14, 12);
        assert!(
            mixed.contains("12 for a position too loose") && mixed.contains("2 no way reached"),
            "{mixed}"
        );
    }
}
