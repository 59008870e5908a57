//! The rooms of the simulated world as the robot's filter frames them:
//! what scoring, recording and the kept world place the truth in.

use anyhow::Result;
use nalgebra::Point2;
use stucco_core::Pose2;
use stucco_runtime::BadInput;
use stucco_sim::Layout;

/// The room a robot at `at` (world frame) stands in, as the simulator
/// knows it: its name, its south-west corner (the origin of the room frame
/// the robot's filter keeps) and its size.
#[derive(Clone, Debug)]
pub(crate) struct RoomFrame {
    pub name: String,
    pub origin: [f64; 2],
    pub size_m: [f64; 2],
}

impl RoomFrame {
    /// The room of `layout` named `name`.
    pub(crate) fn named(layout: &Layout, name: &str) -> Result<RoomFrame> {
        let room = layout
            .rooms
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| BadInput(format!("the plan's room {name:?} is not in the world")))?;
        let (lo, hi) = bounds(&room.corners);
        Ok(RoomFrame {
            name: room.name.clone(),
            origin: lo,
            size_m: [hi[0] - lo[0], hi[1] - lo[1]],
        })
    }

    /// The room of `layout` holding `at`.
    pub(crate) fn of(layout: &Layout, at: &Pose2) -> Result<RoomFrame> {
        let room = layout
            .rooms
            .iter()
            .find(|r| {
                let (lo, hi) = bounds(&r.corners);
                (lo[0]..=hi[0]).contains(&at.x) && (lo[1]..=hi[1]).contains(&at.y)
            })
            .ok_or_else(|| BadInput(format!("the robot's start {at:?} is in no room")))?;
        let (lo, hi) = bounds(&room.corners);
        Ok(RoomFrame {
            name: room.name.clone(),
            origin: lo,
            size_m: [hi[0] - lo[0], hi[1] - lo[1]],
        })
    }

    /// Follows the robot's frame into the room it now keeps, `room`
    /// (its name on the plan; none: it stays).
    pub(crate) fn follow(&mut self, layout: &Layout, room: Option<&str>) -> Result<()> {
        if let Some(name) = room
            && name != self.name
        {
            *self = RoomFrame::named(layout, name)?;
        }
        Ok(())
    }

    /// `p` (world frame) in the room frame.
    pub(crate) fn to_room(&self, p: &Pose2) -> Pose2 {
        Pose2::new(p.x - self.origin[0], p.y - self.origin[1], p.theta)
    }

    /// `p` (room frame) in the world frame.
    pub(crate) fn to_world(&self, p: &Pose2) -> Pose2 {
        Pose2::new(p.x + self.origin[0], p.y + self.origin[1], p.theta)
    }
}

fn bounds(points: &[Point2<f64>]) -> ([f64; 2], [f64; 2]) {
    points.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p.x), lo[1].min(p.y)],
                [hi[0].max(p.x), hi[1].max(p.y)],
            )
        },
    )
}
