//! A map of walls as landmarks (paper B): each wall an infinite line with
//! the side it faces, the stretch of it that has been seen, and how it has
//! been judged.

use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::Pose2;

/// Stable name of a wall in the map (never reused within one map).
pub type WallId = u32;

/// What a line in the map is taken to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallRole {
    /// A wall of the building.
    Wall,
    /// A face standing close in front of a wall of the building (a row of
    /// table legs, a cabinet, a glass wall's frames): still a landmark,
    /// but no room's boundary (the "large false door" of paper A,
    /// corrected once the wall behind was seen across it).
    InFront,
    /// A line fitted across a surface and what is recessed in it, stands
    /// before it or lies past its end (a shut door's leaf, seen far off
    /// through a door; a bed's foot and the desk's legs beside it), a few
    /// degrees askew along it: still a landmark, no room's boundary.
    Across,
}

/// One wall of the map: the line `{p : p·n(α) = ρ}` where `n(α) =
/// (cos α, sin α)` points from the free side into the wall, so the wall is
/// seen only from where `p·n < ρ`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapWall {
    /// Its name.
    pub id: WallId,
    /// Offset of the line along its normal, m.
    pub rho_m: f64,
    /// Direction of the normal, rad, in `(-π, π]`.
    pub alpha_rad: f64,
    /// Covariance of `(ρ, α)` (its own block of the filter's covariance).
    pub covariance: Matrix2<f64>,
    /// The stretch seen, as positions along [`MapWall::direction`], m.
    pub extent_m: [f64; 2],
    /// How many scans it was matched in.
    pub observations: u32,
    /// How many scans saw a wall close behind it, across its stretch.
    pub wall_behind_scans: u32,
    /// What it is taken to be.
    pub role: WallRole,
}

impl MapWall {
    /// Unit normal, from the free side into the wall.
    pub fn normal(&self) -> Vector2<f64> {
        let (s, c) = self.alpha_rad.sin_cos();
        Vector2::new(c, s)
    }

    /// Unit direction along the wall (the normal turned +90°).
    pub fn direction(&self) -> Vector2<f64> {
        let (s, c) = self.alpha_rad.sin_cos();
        Vector2::new(-s, c)
    }

    /// Position of `p` along the wall, m.
    pub fn along(&self, p: &Point2<f64>) -> f64 {
        self.direction().dot(&p.coords)
    }

    /// Distance of `p` in front of the wall (positive on its free side), m.
    pub fn in_front(&self, p: &Point2<f64>) -> f64 {
        self.rho_m - self.normal().dot(&p.coords)
    }

    /// The ends of the seen stretch.
    pub fn ends(&self) -> [Point2<f64>; 2] {
        let foot = self.normal() * self.rho_m;
        self.extent_m
            .map(|t| Point2::from(foot + self.direction() * t))
    }

    /// Length of the seen stretch, m.
    pub fn length_m(&self) -> f64 {
        self.extent_m[1] - self.extent_m[0]
    }

    /// Gap between the seen stretch and `[a, b]` along the wall (negative
    /// when they overlap, by as much), m.
    pub fn gap_to(&self, a: f64, b: f64) -> f64 {
        self.extent_m[0].max(a.min(b)) - self.extent_m[1].min(a.max(b))
    }

    /// The wall moved with its frame by `pose` (a point `p` of the line
    /// goes to `pose · p`): its line, its stretch and the covariance of
    /// `(ρ, α)`, whose `ρ` now also moves with `α` about the new origin.
    pub fn transformed(&self, pose: &Pose2) -> MapWall {
        let mut moved = self.clone();
        moved.alpha_rad = stucco_core::wrap_angle(self.alpha_rad + pose.theta);
        let t = Vector2::new(pose.x, pose.y);
        moved.rho_m = self.rho_m + moved.normal().dot(&t);
        let shift = moved.direction().dot(&t);
        moved.extent_m = self.extent_m.map(|e| e + shift);
        let j = Matrix2::new(1.0, shift, 0.0, 1.0);
        moved.covariance = j * self.covariance * j.transpose();
        moved
    }
}

/// A map that can be saved and loaded: the walls, the robot's pose when it
/// was saved, and the frame's name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallMap {
    /// The walls, by id.
    pub walls: Vec<MapWall>,
    /// Where the robot was when the map was saved.
    pub pose: Pose2,
}

impl WallMap {
    /// The walls of the building (not what stands in front of them).
    pub fn building_walls(&self) -> impl Iterator<Item = &MapWall> {
        building(&self.walls)
    }
}

/// The walls of the building among `walls` (not what stands in front of
/// them).
pub(crate) fn building(walls: &[MapWall]) -> impl Iterator<Item = &MapWall> {
    walls.iter().filter(|w| w.role == WallRole::Wall)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_faces_its_free_side() {
        // The wall x = 3 seen from the origin: normal +x, ρ = 3.
        let w = MapWall {
            id: 0,
            rho_m: 3.0,
            alpha_rad: 0.0,
            covariance: Matrix2::identity(),
            extent_m: [-1.0, 2.0],
            observations: 1,
            wall_behind_scans: 0,
            role: WallRole::Wall,
        };
        assert_eq!(w.in_front(&Point2::origin()), 3.0);
        assert!(w.in_front(&Point2::new(4.0, 0.0)) < 0.0);
        let [a, b] = w.ends();
        assert!((a - Point2::new(3.0, -1.0)).norm() < 1e-12);
        assert!((b - Point2::new(3.0, 2.0)).norm() < 1e-12);
        assert_eq!(w.gap_to(2.5, 4.0), 0.5);
        assert_eq!(w.gap_to(1.0, 0.0), -1.0);
    }

    #[test]
    fn a_moved_wall_keeps_its_ends_and_its_free_side() {
        let w = MapWall {
            id: 0,
            rho_m: 3.0,
            alpha_rad: 0.3,
            covariance: Matrix2::new(1e-4, 2e-6, 2e-6, 1e-5),
            extent_m: [-1.0, 2.0],
            observations: 1,
            wall_behind_scans: 0,
            role: WallRole::Wall,
        };
        let pose = Pose2::new(1.5, -0.7, 2.9);
        let moved = w.transformed(&pose);
        for (e, m) in w.ends().iter().zip(moved.ends()) {
            assert!((pose.transform_point(e) - m).norm() < 1e-12);
        }
        let free = Point2::new(0.5, 0.2);
        assert!(w.in_front(&free) > 0.0);
        let in_front = moved.in_front(&pose.transform_point(&free));
        assert!((in_front - w.in_front(&free)).abs() < 1e-12);
        // ρ's variance grows by α's times the lever arm squared.
        let arm = moved.direction().dot(&Vector2::new(pose.x, pose.y));
        let var = 1e-4 + 2.0 * arm * 2e-6 + arm * arm * 1e-5;
        assert!((moved.covariance[(0, 0)] - var).abs() < 1e-15);
        assert_eq!(moved.covariance[(1, 1)], 1e-5);
        let back = moved.transformed(&pose.inverse());
        assert!((back.rho_m - w.rho_m).abs() < 1e-12);
        assert!((back.covariance - w.covariance).norm() < 1e-15);
    }
}
