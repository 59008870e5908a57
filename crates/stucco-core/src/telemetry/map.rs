//! The robot's map as it publishes it on `stucco/NAME/map`: the room as
//! the navigation core estimates it, in the room frame, with the doors,
//! windows and what stands on the floor. It is also what the executive
//! reads each control period.

use crate::{Pose2, Stamp, WallName};
use serde::{Deserialize, Serialize};

/// A door of the room as the robot knows it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DoorEstimate {
    /// The wall it is in.
    pub wall: WallName,
    /// Its centre along the wall, m.
    pub position_m: f64,
    /// Its width, m, when measured (a door given by a map may not be).
    pub width_m: Option<f64>,
    /// Standard deviation of its position, m.
    pub sigma_m: f64,
    /// The door of the floor plan it is, if the plan has it.
    #[serde(default)]
    pub plan_door: Option<usize>,
}

/// The navigation core's estimate, as the executive reads it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Estimate {
    /// When it holds.
    pub stamp: Stamp,
    /// The rear axle's pose in the room frame.
    pub pose: Pose2,
    /// Standard deviation of the position along its worst axis, m.
    pub position_sigma_m: f64,
    /// Standard deviation of the heading, rad.
    pub heading_sigma_rad: f64,
    /// The room's size, `(xs, ys)`, m: a rectangle's, or the box of a
    /// room of another shape (its corners within `[0, xs] × [0, ys]`).
    pub room_m: [f64; 2],
    /// Its standard deviation, m (a room of another shape: the least and
    /// the greatest of its walls' places' across them, of the walls that
    /// do not fix the frame: see `walls_sigma_m`).
    pub room_sigma_m: [f64; 2],
    /// A room that is not a rectangle: its corners, counter-clockwise,
    /// wall `k` from corner `k` to corner `k + 1` (empty: the rectangle
    /// `room_m`, walls 0–3 west, south, east, north).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub corners: Vec<[f64; 2]>,
    /// Scans each wall (in [`WallName::index`] order) has been used in.
    pub walls_seen: Vec<usize>,
    /// Standard deviation of each wall's place across it (in
    /// [`WallName::index`] order), at the worse of its two ends, m: 0 for
    /// the walls that fix the frame (a rectangle's west and south, a
    /// polygon's wall 0); a rectangle's east and north its size's; a
    /// polygon's other walls' as seen from the robot (given its pose: a
    /// frame one wall fixes slides along it, walls and robot together,
    /// held only by the drawing).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls_sigma_m: Vec<f64>,
    /// The doors known.
    pub doors: Vec<DoorEstimate>,
    /// Height of the ceiling, m.
    #[serde(default = "default_height")]
    pub height_m: f64,
    /// The windows known.
    #[serde(default)]
    pub windows: Vec<WindowEstimate>,
    /// What stands on the floor, as the scans show it.
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// The room of the floor plan the robot is in (the frame's room),
    /// when the mission has a plan.
    #[serde(default)]
    pub room: Option<usize>,
}

fn default_height() -> f64 {
    2.6
}

/// A window of the room as the robot knows it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowEstimate {
    /// The wall it is in.
    pub wall: WallName,
    /// Its edges along the wall, m.
    pub along_m: [f64; 2],
    /// Its sill and head above the floor, m.
    pub sill_head_m: [f64; 2],
    /// Standard deviation of each edge along the wall, m (0 where not
    /// known: the edges are then taken as found).
    #[serde(default)]
    pub along_sigma_m: [f64; 2],
}

/// Something standing on the floor: the robot cannot stand on it, and the
/// nozzle cannot reach below its top behind it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// Its footprint's south-west corner in the room frame, m.
    pub min_m: [f64; 2],
    /// Its footprint's north-east corner, m.
    pub max_m: [f64; 2],
    /// Its height, m.
    pub height_m: f64,
}
