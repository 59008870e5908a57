//! `move_relative`: a move in the robot's frame at the task's start, or
//! in the frame of a wall or a door.

use super::ways::way;
use super::{Behaviours, Task, TaskCx, TaskFailure, TaskStep, Thaw, drive_through};
use crate::behaviour::BehaviourKind;
use crate::model::{Estimate, wall_in};
use crate::task::Landmark;
use stucco_core::Pose2;

/// Moves by `(dx, dy, dθ)` in a frame.
#[derive(Clone, Debug)]
pub(crate) struct MoveRelative {
    /// Forward, left (m) and the turn (degrees).
    by: [f64; 3],
    landmark: Option<Landmark>,
    speed_mps: f64,
    ways: Behaviours,
}

impl MoveRelative {
    pub fn new(by: [f64; 3], landmark: Option<Landmark>, speed_mps: f64) -> Self {
        MoveRelative {
            by,
            landmark,
            speed_mps,
            ways: Behaviours::default(),
        }
    }
}

impl Task for MoveRelative {
    fn start(&mut self, cx: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        let (est, pose) = (cx.est, cx.est.pose);
        let goal = goal(self.by, self.landmark.as_ref(), est)?;
        self.ways
            .queue
            .extend(way(cx.config, est, &pose, &goal, self.speed_mps));
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        drive_through(&mut self.ways, cx)
    }

    fn behaviour(&self) -> Option<&BehaviourKind> {
        self.ways.kind()
    }

    fn clone_box(&self) -> Box<dyn Task> {
        Box::new(self.clone())
    }
}

/// Where a move by `(dx, dy, dθ)` (m, m, degrees) ends, in the room
/// frame: in the robot's frame now, or in `landmark`'s.
pub(crate) fn goal(
    [dx_m, dy_m, dtheta_deg]: [f64; 3],
    landmark: Option<&Landmark>,
    est: &Estimate,
) -> Result<Pose2, TaskFailure> {
    let frame = match landmark {
        None => est.pose,
        Some(l) => landmark_frame(l, est)?,
    };
    Ok(frame * Pose2::new(dx_m, dy_m, dtheta_deg.to_radians()))
}

/// The frame of `landmark` in the room as `est` knows it: facing it from
/// inside, its origin at its middle on the wall's line, x out of the room.
fn landmark_frame(landmark: &Landmark, est: &Estimate) -> Result<Pose2, TaskFailure> {
    let (wall, along) = match *landmark {
        Landmark::Wall(w) => (w, wall_in(est, w, "move_relative")?.length_m / 2.0),
        Landmark::Door(i) => {
            let d = est.doors.get(i).ok_or_else(|| TaskFailure::UnknownDoor {
                task: "move_relative".to_owned(),
                door: i,
                found: est.doors.len(),
            })?;
            (d.wall, d.position_m)
        }
    };
    let g = wall_in(est, wall, "move_relative")?;
    let o = g.point(along, 0.0);
    Ok(Pose2::new(o.x, o.y, (-g.inward.y).atan2(-g.inward.x)))
}
