//! What the executive tells of what happened: the event log's entries.

use super::{Hazard, TaskFailure};
use crate::{OperatorCommand, Stamp, WallName};
use serde::{Deserialize, Serialize};

/// Something that happened, for the event log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// When.
    pub stamp: Stamp,
    /// What.
    #[serde(flatten)]
    pub kind: EventKind,
}

/// Why a plastering station was given up: what an operator can do about
/// it differs (clear the way, or let the robot see more of the walls).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GiveUpReason {
    /// No way to it keeps the body clear (a hall too narrow to turn
    /// across), or the way stayed held when tried again.
    #[default]
    NoWay,
    /// The position stayed known too loosely to spray there (the walls
    /// that hold it out of the laser's sight from the station).
    PositionLoose,
}

/// The kinds of events.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
        /// Where it drives to, in the room's frame: x, y (m) and heading
        /// (deg); a turn on the spot where the robot stands. None for a
        /// behaviour with no one goal (a path, a wall followed).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        goal: Option<[f64; 3]>,
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
        /// Why, in a sentence.
        reason: String,
        /// Why, for programs.
        failure: TaskFailure,
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
    /// A plastering station is left out of the plan, for `reason`, and
    /// what only it reached is reported unreachable.
    StationGivenUp {
        /// The task.
        task: usize,
        /// The station's index in the plan before it was left out.
        station: usize,
        /// Plasterable area lost with it, m².
        unreachable_m2: f64,
        /// Why (a log written before the reason was told: no way).
        #[serde(default)]
        reason: GiveUpReason,
    },
    /// The way to a plastering station stayed blocked (someone standing
    /// in it, a wall nearer the station than the field's margin): the
    /// station is put last, to be tried again when the rest are done.
    StationDeferred {
        /// The task.
        task: usize,
        /// The station's index in the plan before it was put last.
        station: usize,
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
    /// `map_room` leaves walls out: no place the robot reaches sees them
    /// (furniture stands before them along their length, or they are too
    /// short for the laser to take for a line). Their places stay the
    /// drawing's.
    WallsHidden {
        /// The task.
        task: usize,
        /// The walls.
        walls: Vec<WallName>,
    },
    /// `map_room`'s time is up with every wall seen but the room's size
    /// known less well than it asked; it is done with the size as known
    /// (its `on_loose_size` is `continue`, as in a job from the drawing).
    RoomSizeLoose {
        /// The task.
        task: usize,
        /// How well the size is known: the loosest wall's place, m (σ).
        sigma_m: f64,
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

impl EventKind {
    /// The kind's name, as the JSON's `event` writes it.
    pub fn name(&self) -> &'static str {
        match self {
            EventKind::MissionStarted { .. } => "mission_started",
            EventKind::TaskStarted { .. } => "task_started",
            EventKind::BehaviourStarted { .. } => "behaviour_started",
            EventKind::TaskDone { .. } => "task_done",
            EventKind::TaskSkipped { .. } => "task_skipped",
            EventKind::TaskFailed { .. } => "task_failed",
            EventKind::OperatorPrompt { .. } => "operator_prompt",
            EventKind::Paused { .. } => "paused",
            EventKind::Resumed => "resumed",
            EventKind::EStop => "e_stop",
            EventKind::SafetyStop { .. } => "safety_stop",
            EventKind::SafetyClear => "safety_clear",
            EventKind::Aborted => "aborted",
            EventKind::MissionDone => "mission_done",
            EventKind::MissionFailed { .. } => "mission_failed",
            EventKind::LinkLost => "link_lost",
            EventKind::LinkRestored => "link_restored",
            EventKind::StationStarted { .. } => "station_started",
            EventKind::WindowEdgeLook { .. } => "window_edge_look",
            EventKind::WindowFound { .. } => "window_found",
            EventKind::StationGivenUp { .. } => "station_given_up",
            EventKind::StationDeferred { .. } => "station_deferred",
            EventKind::PassDone { .. } => "pass_done",
            EventKind::RoomEntered { .. } => "room_entered",
            EventKind::WallsHidden { .. } => "walls_hidden",
            EventKind::RoomSizeLoose { .. } => "room_size_loose",
            EventKind::PlanMade { .. } => "plan_made",
            EventKind::CommandRefused { .. } => "command_refused",
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// What a robot writes a reader reads back the same, kind for kind:
    /// the tag beside the stamp, nested tags (a failure's code, a
    /// hazard's kind) and numbers included.
    #[test]
    fn events_read_back_as_written() {
        let kinds = [
            EventKind::MissionStarted {
                tasks: 4,
                first_task: 2,
            },
            EventKind::TaskFailed {
                task: 1,
                reason: TaskFailure::WayBlocked {
                    pose: [1.0, 2.0, 90.0],
                    obstacle_m: Some([1.0, 3.0]),
                    backing: false,
                }
                .to_string(),
                failure: TaskFailure::WallsNotSeen {
                    walls: vec![WallName::EAST, WallName::NORTH],
                    timeout_s: 180.0,
                },
            },
            EventKind::EStop,
            EventKind::SafetyStop {
                hazard: Hazard::Obstacle,
            },
            EventKind::WindowEdgeLook {
                task: 3,
                wall: WallName::NORTH,
                along_m: 1.25,
                sigma_m: 0.031,
            },
            EventKind::CommandRefused {
                command: OperatorCommand::Resume,
                reason: "not paused".to_owned(),
            },
            EventKind::StationDeferred {
                task: 2,
                station: 7,
            },
            EventKind::StationGivenUp {
                task: 2,
                station: 5,
                unreachable_m2: 3.25,
                reason: GiveUpReason::PositionLoose,
            },
            EventKind::BehaviourStarted {
                task: 2,
                behaviour: "reverse".to_owned(),
                goal: Some([1.5, 0.25, -90.0]),
            },
            EventKind::TaskFailed {
                task: 2,
                reason: "held".to_owned(),
                failure: TaskFailure::PositionTooLoose {
                    station: 3,
                    sigma_m: 0.015,
                    limit_m: 0.01,
                    waited_s: 10.0,
                },
            },
        ];
        for (k, kind) in kinds.into_iter().enumerate() {
            let event = Event {
                stamp: Stamp::from_nanos(1_000_000_007 * k as i64),
                kind,
            };
            let text = serde_json::to_string(&event).unwrap();
            assert!(
                text.contains(&format!("\"event\":\"{}\"", event.kind.name())),
                "{text}"
            );
            let back: Event = serde_json::from_str(&text).unwrap();
            assert_eq!(back, event, "{text}");
        }
    }

    /// A station given up in a log written before the reason was told
    /// reads as one no way reached, what the event meant then.
    #[test]
    fn a_station_given_up_without_a_reason_reads_as_no_way() {
        let text = r#"{"stamp":1000000000,"event":"station_given_up","task":1,"station":4,"unreachable_m2":2.5}"#;
        let back: Event = serde_json::from_str(text).unwrap();
        assert!(matches!(
            back.kind,
            EventKind::StationGivenUp {
                station: 4,
                reason: GiveUpReason::NoWay,
                ..
            }
        ));
    }
}
