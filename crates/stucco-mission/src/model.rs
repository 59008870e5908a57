//! What the executive knows of the robot and the room: the navigation
//! core's estimate, in the room frame, and the geometry of the walls.

use crate::task::{Side, WallName};
use nalgebra::Vector2;
use stucco_core::Pose2;
use stucco_core::telemetry::TaskFailure;
pub use stucco_core::telemetry::{DoorEstimate, Estimate, WindowEstimate};

/// A wall of the rectangular room: where its axis starts, which way it
/// runs, and its normal into the room.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallGeometry {
    /// The point at position 0 along the wall.
    pub origin: Vector2<f64>,
    /// Unit vector along the wall (x or y).
    pub along: Vector2<f64>,
    /// Unit normal pointing into the room.
    pub inward: Vector2<f64>,
    /// Length of the wall, m.
    pub length_m: f64,
}

impl WallGeometry {
    /// The wall `w` of a rectangular room `room_m` in size (the planner's
    /// frame of it: one definition of the room's walls), when it has it.
    pub fn of(w: WallName, room_m: [f64; 2]) -> Option<Self> {
        let line = stucco_plan::WallLine::of(w, room_m)?;
        Some(WallGeometry {
            origin: line.origin,
            along: line.along,
            inward: line.inward,
            length_m: line.length_m,
        })
    }

    /// Distance of `p` from the wall, positive inside the room, m.
    pub fn distance(&self, p: &Vector2<f64>) -> f64 {
        self.inward.dot(&(p - self.origin))
    }

    /// Position of `p` along the wall, m.
    pub fn position(&self, p: &Vector2<f64>) -> f64 {
        self.along.dot(&(p - self.origin))
    }

    /// The point `standoff_m` into the room at `at_m` along the wall.
    pub fn point(&self, at_m: f64, standoff_m: f64) -> Vector2<f64> {
        self.origin + self.along * at_m + self.inward * standoff_m
    }

    /// The heading that keeps the wall on `side`.
    pub fn heading(&self, side: Side) -> f64 {
        let n = self.inward;
        // Left of a heading h is h turned +90°; the wall lies at −inward.
        let h = match side {
            Side::Left => Vector2::new(-n.y, n.x),
            Side::Right => Vector2::new(n.y, -n.x),
        };
        h.y.atan2(h.x)
    }

    /// The pose `standoff_m` from the wall at `at_m` along it, the wall on
    /// `side`.
    pub fn pose_at(&self, at_m: f64, standoff_m: f64, side: Side) -> Pose2 {
        let p = self.point(at_m, standoff_m);
        Pose2::new(p.x, p.y, self.heading(side))
    }

    /// The side the wall is on for a robot running toward increasing
    /// (`forward`) or decreasing positions along it.
    pub fn side_for(&self, forward: bool) -> Side {
        let h_left = self.heading(Side::Left);
        let left_runs_forward = self.along.dot(&Vector2::new(h_left.cos(), h_left.sin())) > 0.0;
        if left_runs_forward == forward {
            Side::Left
        } else {
            Side::Right
        }
    }

    /// The wall as the line `n(γ)·p = d` seen from `pose` (its rear axle,
    /// robot frame): `d` the distance, `γ` the direction toward it.
    pub fn seen_from(&self, pose: &Pose2) -> (f64, f64) {
        let p = pose.position().coords;
        let d = self.distance(&p);
        let toward = -self.inward;
        let gamma = toward.y.atan2(toward.x) - pose.theta;
        (d, stucco_core::wrap_angle(gamma))
    }
}

/// Wall `w` of the room `est` knows, or a failure of `task` naming it.
pub fn wall_in(est: &Estimate, w: WallName, task: &str) -> Result<WallGeometry, TaskFailure> {
    WallGeometry::of(w, est.room_m).ok_or_else(|| TaskFailure::UnknownWall {
        task: task.to_owned(),
        wall: w,
        walls: WallName::ALL.len(),
    })
}

/// The walls of a rectangular room `room_m` in size, by name.
pub fn rectangle_walls(room_m: [f64; 2]) -> impl Iterator<Item = (WallName, WallGeometry)> {
    WallName::ALL
        .into_iter()
        .filter_map(move |w| Some((w, WallGeometry::of(w, room_m)?)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn walls_know_their_sides() {
        let room = [5.0, 3.0];
        // Along the south wall eastward, the wall is on the right.
        let s = WallGeometry::of(WallName::SOUTH, room).unwrap();
        assert_eq!(s.side_for(true), Side::Right);
        assert!((s.heading(Side::Right) - 0.0).abs() < 1e-12);
        // Along the north wall westward, the wall is on the right too.
        let n = WallGeometry::of(WallName::NORTH, room).unwrap();
        assert_eq!(n.side_for(false), Side::Right);
        assert!((n.heading(Side::Right).abs() - PI).abs() < 1e-12);
        // The west wall northward is on the left.
        let w = WallGeometry::of(WallName::WEST, room).unwrap();
        assert_eq!(w.side_for(true), Side::Left);
        assert!((w.heading(Side::Left) - FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn a_wall_seen_from_the_robot() {
        let e = WallGeometry::of(WallName::EAST, [5.0, 3.0]).unwrap();
        // 1 m from the east wall, facing north: the wall is on the right.
        let (d, g) = e.seen_from(&Pose2::new(4.0, 1.0, FRAC_PI_2));
        assert!((d - 1.0).abs() < 1e-12);
        assert!((g + FRAC_PI_2).abs() < 1e-12);
        let p = e.pose_at(2.0, 0.6, Side::Right);
        assert!((p.x - 4.4).abs() < 1e-12 && (p.y - 2.0).abs() < 1e-12);
        assert!((p.theta - FRAC_PI_2).abs() < 1e-12);
    }
}
