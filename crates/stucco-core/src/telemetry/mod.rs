//! What a robot tells its operators while it works, typed: its state as
//! `stucco/NAME/state` publishes it, with the mission's mode, the
//! behaviour under way and what the supervisor holds the robot for. The
//! robot writes these and `stucco op` (or a console) reads them back as
//! the same types.

mod coverage;
mod event;
mod failure;
mod map;

pub use coverage::{PlasterCoverage, SurfaceCoverage};
pub use event::{Event, EventKind, GiveUpReason};
pub use failure::TaskFailure;
pub use map::{DoorEstimate, Estimate, Obstacle, WindowEstimate};

use crate::{DriveCommand, Pose2, Stamp, WallName};
use serde::{Deserialize, Serialize};

/// The robot's state, published every control period.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotState {
    /// The robot's time.
    pub stamp: Stamp,
    /// The robot's name.
    pub name: String,
    /// The mission's state.
    pub mission: MissionMode,
    /// The task under way: its index and its kind.
    pub task: Option<(usize, String)>,
    /// The behaviour under way.
    pub behaviour: Option<BehaviourKind>,
    /// The floor plan's room the robot is in (the pose's frame), when the
    /// mission has a plan.
    pub room: Option<String>,
    /// The estimated pose in the room.
    pub pose: Pose2,
    /// Its position σ, m.
    pub position_sigma_m: f64,
    /// What the supervisor holds the robot for.
    pub hazard: Option<Hazard>,
    /// The drive command going out, after the supervisor.
    pub drive: DriveCommand,
}

/// The mission's state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

impl MissionMode {
    /// Its name as the wire writes it (`running`, `paused`, …).
    pub fn name(&self) -> &'static str {
        match self {
            MissionMode::Running => "running",
            MissionMode::Paused { .. } => "paused",
            MissionMode::EStopped => "e_stopped",
            MissionMode::Done => "done",
            MissionMode::Failed { .. } => "failed",
            MissionMode::Aborted => "aborted",
        }
    }

    /// Why it paused or failed.
    pub fn reason(&self) -> Option<&str> {
        match self {
            MissionMode::Paused { reason } | MissionMode::Failed { reason } => Some(reason),
            _ => None,
        }
    }
}

/// The phases of a turn on the spot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PivotPhase {
    /// Standing, the front wheel turning to ±90°.
    Steer,
    /// Driving the wheel across: the robot turns about its rear axle.
    Turn,
    /// Standing, the wheel coming back straight.
    Straighten,
}

/// What a behaviour is doing, for the state report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "behaviour", rename_all = "snake_case")]
pub enum BehaviourKind {
    /// Standing still.
    Hold,
    /// Turning on the spot to `heading_rad`.
    Pivot {
        /// The heading, rad.
        heading_rad: f64,
        /// The phase.
        phase: PivotPhase,
    },
    /// Driving along the line through `goal` to it.
    Regulate {
        /// The goal pose.
        goal: Pose2,
    },
    /// Backing along the line through `goal` (the robot facing along its
    /// heading) to it.
    Reverse {
        /// The goal pose.
        goal: Pose2,
    },
    /// Following a wall at a standoff up to a position along it.
    FollowWall {
        /// The wall.
        wall: WallName,
        /// The standoff, m.
        standoff_m: f64,
        /// Where it stops along the wall, m.
        to_m: f64,
    },
    /// Following a path of segments.
    Path {
        /// The segment being followed.
        segment: usize,
        /// Segments in all.
        segments: usize,
    },
}

impl BehaviourKind {
    /// Its name as the wire writes it (`hold`, `pivot`, …).
    pub fn name(&self) -> &'static str {
        match self {
            BehaviourKind::Hold => "hold",
            BehaviourKind::Pivot { .. } => "pivot",
            BehaviourKind::Regulate { .. } => "regulate",
            BehaviourKind::Reverse { .. } => "reverse",
            BehaviourKind::FollowWall { .. } => "follow_wall",
            BehaviourKind::Path { .. } => "path",
        }
    }
}

/// Why the supervisor stopped the robot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hazard {
    /// Something in the protective field.
    Obstacle,
    /// The pose estimate is too uncertain to drive on.
    Lost,
    /// Something touched the robot (its bumper): it stands, the spray
    /// off, until the touch has been gone a while.
    Touch,
}

impl Hazard {
    /// Its name as the wire writes it.
    pub fn name(self) -> &'static str {
        match self {
            Hazard::Obstacle => "obstacle",
            Hazard::Lost => "lost",
            Hazard::Touch => "touch",
        }
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    /// What the robot writes, a reader gets back, every kind of each.
    #[test]
    fn a_state_reads_back_as_it_was_written() {
        let modes = [
            MissionMode::Running,
            MissionMode::Paused {
                reason: "link lost".into(),
            },
            MissionMode::EStopped,
            MissionMode::Done,
            MissionMode::Failed {
                reason: "blocked".into(),
            },
            MissionMode::Aborted,
        ];
        let behaviours = [
            None,
            Some(BehaviourKind::Hold),
            Some(BehaviourKind::Pivot {
                heading_rad: 1.0,
                phase: PivotPhase::Turn,
            }),
            Some(BehaviourKind::Regulate {
                goal: Pose2::new(1.0, 2.0, 0.5),
            }),
            Some(BehaviourKind::Reverse {
                goal: Pose2::new(1.0, 2.0, 0.5),
            }),
            Some(BehaviourKind::FollowWall {
                wall: WallName::SOUTH,
                standoff_m: 0.6,
                to_m: 3.0,
            }),
            Some(BehaviourKind::Path {
                segment: 1,
                segments: 4,
            }),
        ];
        for (k, (mission, behaviour)) in modes.iter().zip(behaviours.iter().cycle()).enumerate() {
            let state = RobotState {
                stamp: Stamp::from_nanos(20_000_000 * k as i64),
                name: "r1".into(),
                mission: mission.clone(),
                task: Some((k, "plaster".into())),
                behaviour: behaviour.clone(),
                room: (k % 2 == 0).then(|| "hall".into()),
                pose: Pose2::new(1.5, 0.25, -0.1),
                position_sigma_m: 0.004,
                hazard: [None, Some(Hazard::Obstacle), Some(Hazard::Lost)][k % 3],
                drive: DriveCommand {
                    speed_mps: 0.2,
                    steer_rad: -0.05,
                },
            };
            let json = serde_json::to_string(&state).expect("serialisable");
            let back: RobotState = serde_json::from_str(&json).expect("readable");
            assert_eq!(back, state, "{json}");
            let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
            assert_eq!(v["mission"]["state"], mission.name());
            if let Some(b) = behaviour {
                assert_eq!(v["behaviour"]["behaviour"], b.name());
            }
        }
    }
}
