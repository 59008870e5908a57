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
        stucco_plan::WallLine::of(w, room_m).map(Self::from)
    }

    /// Wall `w` of the room the estimate `est` holds (its corners', or
    /// the rectangle's), when it has it.
    pub fn in_room(est: &Estimate, w: WallName) -> Option<Self> {
        Self::of_room(&est.corners, est.room_m, w)
    }

    /// Wall `w` of a room given by its `corners` (counter-clockwise; none:
    /// the rectangle `room_m`), when it has it.
    pub fn of_room(corners: &[[f64; 2]], room_m: [f64; 2], w: WallName) -> Option<Self> {
        stucco_plan::WallLine::of_room(corners, room_m)
            .get(w.index())
            .copied()
            .map(Self::from)
    }
}

impl From<stucco_plan::WallLine> for WallGeometry {
    fn from(line: stucco_plan::WallLine) -> Self {
        WallGeometry {
            origin: line.origin,
            along: line.along,
            inward: line.inward,
            length_m: line.length_m,
        }
    }
}

impl WallGeometry {
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
    WallGeometry::in_room(est, w).ok_or_else(|| TaskFailure::UnknownWall {
        task: task.to_owned(),
        wall: w,
        walls: room_walls(est).len(),
    })
}

/// How deep the room the estimate `est` holds reaches from wall `g`'s
/// line into the room, m (a rectangle's side across that wall).
pub fn depth_from(est: &Estimate, g: &WallGeometry) -> f64 {
    depth_of_room(&est.corners, est.room_m, g)
}

/// How deep a room given by its `corners` (none: the rectangle `room_m`)
/// reaches from wall `g`'s line into the room, m.
pub fn depth_of_room(corners: &[[f64; 2]], room_m: [f64; 2], g: &WallGeometry) -> f64 {
    let [xs, ys] = room_m;
    let rectangle = [[0.0, 0.0], [xs, 0.0], [xs, ys], [0.0, ys]];
    let corners = if corners.is_empty() {
        &rectangle[..]
    } else {
        corners
    };
    corners
        .iter()
        .map(|c| g.distance(&Vector2::from(*c)))
        .fold(0.0, f64::max)
}

/// Standard deviation of the place of wall `k` across it, m: as the
/// estimate `est` gives it; from an estimate that does not, a rectangle's
/// (its east and north walls' the size's, its west and south fixing the
/// frame).
pub fn wall_sigma(est: &Estimate, k: usize) -> f64 {
    est.walls_sigma_m.get(k).copied().unwrap_or(match k {
        2 => est.room_sigma_m[0],
        3 => est.room_sigma_m[1],
        _ => 0.0,
    })
}

/// The wall that fixes the frame across wall `k`: a rectangle's west
/// across its east, its south across its north (each its own); a
/// polygon's wall 0 for every wall (the wall most square to it holds
/// the frame along it). A wall's place is measured against it: its σ
/// falls only while both are seen.
pub fn anchor_wall(est: &Estimate, k: usize) -> usize {
    if est.corners.is_empty() { k % 2 } else { 0 }
}

/// The walls a task names (`Some`), or every wall of the room the
/// estimate `est` holds (`None`: a task's default).
pub fn walls_or_all(walls: Option<&[WallName]>, est: &Estimate) -> Vec<WallName> {
    match walls {
        Some(w) => w.to_vec(),
        None => room_walls(est).into_iter().map(|(w, _)| w).collect(),
    }
}

/// The walls of the room the estimate `est` holds, by name.
pub fn room_walls(est: &Estimate) -> Vec<(WallName, WallGeometry)> {
    walls_of_room(&est.corners, est.room_m)
}

/// The walls of a room given by its `corners` (none: the rectangle
/// `room_m`), by name.
pub fn walls_of_room(corners: &[[f64; 2]], room_m: [f64; 2]) -> Vec<(WallName, WallGeometry)> {
    stucco_plan::WallLine::of_room(corners, room_m)
        .into_iter()
        .enumerate()
        .filter_map(|(k, line)| Some((WallName::from_index(k)?, line.into())))
        .collect()
}

/// For the crate's tests: the robot at `pose` in a room `room_m` (the box
/// of `corners`, none for the rectangle), every wall seen and the pose
/// known to 3 mm, no door, window or furniture.
#[cfg(test)]
pub(crate) fn known_room(room_m: [f64; 2], corners: &[[f64; 2]], pose: Pose2) -> Estimate {
    let walls = if corners.is_empty() { 4 } else { corners.len() };
    Estimate {
        stamp: stucco_core::Stamp::ZERO,
        pose,
        position_sigma_m: 0.003,
        heading_sigma_rad: 0.001,
        room_m,
        room_sigma_m: [0.002; 2],
        corners: corners.to_vec(),
        walls_seen: vec![100; walls],
        walls_sigma_m: Vec::new(),
        doors: Vec::new(),
        height_m: 2.6,
        windows: Vec::new(),
        obstacles: Vec::new(),
        room: None,
    }
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
