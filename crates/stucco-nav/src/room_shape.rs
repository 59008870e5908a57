//! The shape of the room the room filter holds the robot in: each wall a
//! line `n·p = ρ` of the room frame, its outward normal `n = (cos φ,
//! sin φ)` and its offset `ρ` either fixed (they fix the frame) or rows of
//! the filter's state (estimated from the walls the laser sees).
//!
//! - A rectangle (paper A §3): walls on `x = 0`, `y = 0`, `x = xs`,
//!   `y = ys`, at right angles by construction, the sizes `xs`, `ys` in
//!   the state (rows 3 and 4).
//! - A polygon (a room of the building's drawing, corners counter-clockwise,
//!   wall `k` from corner `k` to corner `k + 1`): wall 0's line fixes the
//!   frame; every other wall's angle and offset are in the state, the
//!   drawing their prior. An L's notch walls, a chimney breast's walls and
//!   a wall at an angle are walls like the others; a wall is only paired
//!   with what the laser sees on its inner side and along its stretch.
//!
//! A door lies in a wall at a position along it: `centre = ρ n + s t`, `t`
//! the wall's direction signed so that its larger component is positive
//! (a rectangle's door is at its `y` in walls 0 and 2, its `x` in 1 and 3).

use crate::error::NavError;
use nalgebra::{DMatrix, DVector, Matrix2, Point2, Vector2};
use std::f64::consts::{FRAC_PI_2, PI};
use stucco_core::{Pose2, wrap_angle};

/// Least overlap, m, of a seen stretch with a polygon wall's stretch
/// (less: the line belongs to another wall in the same line, or to what
/// stands beyond a corner).
const ALONG_SLACK_M: f64 = 0.2;

/// The σ a polygon's frame-holding wall's offset starts with, m: held to
/// its drawn value, as a fixed one would be (a state row kept, so the
/// filter's layout is one for every wall after wall 0).
const FRAME_HELD_SIGMA_M: f64 = 1e-4;

/// An angle or offset of a wall: fixed, or a row of the state.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Param {
    Fixed(f64),
    Row(usize),
}

/// One wall of the shape.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ShapeWall {
    /// The outward normal's angle; when fixed, its exact components too
    /// (a rectangle's normals are exact axes).
    angle: Param,
    normal: Vector2<f64>,
    offset: Param,
    /// Sign making `(−n_y, n_x)` the wall's direction for doors.
    along_sign: f64,
}

/// A door's centre in the room, its derivative by its position along the
/// wall, and by the wall's rows of the state `(row, ∂)`.
pub type DoorCentre = (Vector2<f64>, Vector2<f64>, Vec<(usize, Vector2<f64>)>);

/// The walls of the room the filter holds the robot in.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomShape {
    walls: Vec<ShapeWall>,
    /// The drawing's values of the state's wall rows (rows 3 onwards), and
    /// their standard deviations.
    drawn: Vec<(f64, f64)>,
    /// Walls are paired only from their inner side and along their
    /// stretch (a rectangle's walls each span a side: no need).
    polygon: bool,
}

/// The wall direction for doors: the perpendicular of `n` whose larger
/// component is positive (ties: its x).
fn along_sign(n: &Vector2<f64>) -> f64 {
    let t = Vector2::new(-n.y, n.x);
    // Ties (a wall at 45°) go by x.
    let key = if t.y.abs() > t.x.abs() + 1e-12 {
        t.y
    } else {
        t.x
    };
    if key >= 0.0 { 1.0 } else { -1.0 }
}

impl RoomShape {
    /// The rectangle of paper A: walls 0–3 on `x = 0`, `y = 0`, `x = xs`
    /// (row 3), `y = ys` (row 4).
    pub fn rectangle() -> Self {
        let wall = |normal: Vector2<f64>, angle: f64, offset: Param| ShapeWall {
            angle: Param::Fixed(angle),
            normal,
            offset,
            along_sign: along_sign(&normal),
        };
        RoomShape {
            walls: vec![
                wall(Vector2::new(-1.0, 0.0), PI, Param::Fixed(0.0)),
                wall(Vector2::new(0.0, -1.0), -FRAC_PI_2, Param::Fixed(0.0)),
                wall(Vector2::new(1.0, 0.0), 0.0, Param::Row(3)),
                wall(Vector2::new(0.0, 1.0), FRAC_PI_2, Param::Row(4)),
            ],
            drawn: Vec::new(),
            polygon: false,
        }
    }

    /// A room of a drawing: `corners` counter-clockwise, each off by up to
    /// `corner_sigma_m` (σ) from the walls as built. Wall 0's line fixes
    /// the frame; each other wall's angle and offset join the state (rows
    /// 3, 4 for wall 1, then 5, 6 …), a wall of length `L` with σ
    /// `corner_sigma_m` on its offset and `√2·corner_sigma_m / L` on its
    /// angle.
    ///
    /// # Errors
    /// Fewer than three corners, a corner not finite, or two corners in
    /// one place.
    pub fn polygon(corners: &[[f64; 2]], corner_sigma_m: f64) -> Result<Self, NavError> {
        let n = corners.len();
        if n < 3 {
            return Err(NavError::InvalidConfig {
                field: "corners",
                reason: format!("a room needs three corners or more, not {n}"),
            });
        }
        if let Some(c) = corners.iter().find(|c| !c.iter().all(|v| v.is_finite())) {
            return Err(NavError::InvalidConfig {
                field: "corners",
                reason: format!("corner {c:?} is not a place"),
            });
        }
        let mut walls = Vec::with_capacity(n);
        let mut drawn = Vec::new();
        for k in 0..n {
            let (a, b) = (
                Vector2::from(corners[k]),
                Vector2::from(corners[(k + 1) % n]),
            );
            let len = (b - a).norm();
            if len < 1e-6 {
                return Err(NavError::InvalidConfig {
                    field: "corners",
                    reason: format!("corners {k} and {} are in one place", (k + 1) % n),
                });
            }
            let d = (b - a) / len;
            let normal = Vector2::new(d.y, -d.x);
            let angle = normal.y.atan2(normal.x);
            let offset = normal.dot(&a);
            let wall = if k == 0 {
                ShapeWall {
                    angle: Param::Fixed(angle),
                    normal,
                    offset: Param::Fixed(offset),
                    along_sign: along_sign(&normal),
                }
            } else {
                let row = 3 + drawn.len();
                drawn.push((angle, std::f64::consts::SQRT_2 * corner_sigma_m / len));
                drawn.push((offset, corner_sigma_m));
                ShapeWall {
                    angle: Param::Row(row),
                    normal,
                    offset: Param::Row(row + 1),
                    along_sign: along_sign(&normal),
                }
            };
            walls.push(wall);
        }
        // Wall 0's line leaves the frame free to slide along it: the walls
        // and the robot slid together look the same to the laser, held
        // only by the drawing (~15 mm in the generated rooms, the robot's
        // place loose by as much however long it looked). The wall most
        // square to wall 0 (of two alike, the longer) holds its drawn
        // offset, as a rectangle's south wall holds its frame across the
        // west's.
        if let Some(k) = (1..n)
            .map(|k| {
                let d = Vector2::from(corners[(k + 1) % n]) - Vector2::from(corners[k]);
                let d0 = Vector2::from(corners[1]) - Vector2::from(corners[0]);
                let square = (d0.x * d.y - d0.y * d.x).abs() / (d0.norm() * d.norm());
                (k, square, d.norm())
            })
            .filter(|&(_, square, _)| square > 0.5)
            .max_by(|a, b| {
                let alike = |s: f64| (s * 1e6).round();
                alike(a.1).total_cmp(&alike(b.1)).then(a.2.total_cmp(&b.2))
            })
            .map(|(k, ..)| k)
            && let Some(ShapeWall {
                offset: Param::Row(r),
                ..
            }) = walls.get(k)
        {
            drawn[r - 3].1 = FRAME_HELD_SIGMA_M;
        }
        Ok(RoomShape {
            walls,
            drawn,
            polygon: true,
        })
    }

    /// How many walls the room has.
    pub fn len(&self) -> usize {
        self.walls.len()
    }

    /// Whether the room has no walls (never: a shape has three or more).
    pub fn is_empty(&self) -> bool {
        self.walls.is_empty()
    }

    /// Whether the walls are a polygon's (not the rectangle of paper A).
    pub fn is_polygon(&self) -> bool {
        self.polygon
    }

    /// Rows of the state the walls take after the pose.
    pub fn rows(&self) -> usize {
        if self.polygon { self.drawn.len() } else { 2 }
    }

    /// The row of the state that holds wall `k`'s offset; `None` for a
    /// wall that fixes the frame (or no such wall).
    pub fn offset_row(&self, k: usize) -> Option<usize> {
        match self.walls.get(k)?.offset {
            Param::Row(r) => Some(r),
            Param::Fixed(_) => None,
        }
    }

    /// The row of the state that holds wall `k`'s normal's angle; `None`
    /// for a wall whose angle is fixed (a rectangle's, a polygon's wall 0).
    pub fn angle_row(&self, k: usize) -> Option<usize> {
        match self.walls.get(k)?.angle {
            Param::Row(r) => Some(r),
            Param::Fixed(_) => None,
        }
    }

    /// The drawing's values of the walls' rows and their σ (a polygon's;
    /// a rectangle's sizes are given with its state).
    pub fn drawn(&self) -> &[(f64, f64)] {
        &self.drawn
    }

    fn value(p: Param, x: &DVector<f64>) -> f64 {
        match p {
            Param::Fixed(v) => v,
            Param::Row(i) => x[i],
        }
    }

    /// Wall `q`'s outward normal and offset in state `x`.
    pub fn line(&self, x: &DVector<f64>, q: usize) -> (Vector2<f64>, f64) {
        let w = &self.walls[q];
        let n = match w.angle {
            Param::Fixed(_) => w.normal,
            Param::Row(i) => Vector2::new(x[i].cos(), x[i].sin()),
        };
        (n, Self::value(w.offset, x))
    }

    /// Wall `q`'s direction for doors in state `x`.
    pub fn along(&self, x: &DVector<f64>, q: usize) -> Vector2<f64> {
        let (n, _) = self.line(x, q);
        self.walls[q].along_sign * Vector2::new(-n.y, n.x)
    }

    /// The corners of the room in state `x`: corner `k` where walls
    /// `k − 1` and `k` meet (two walls in one line, either side of a
    /// chimney breast's face, meet at the end of the first's stretch as
    /// drawn: the point on it nearest the drawn corner).
    pub fn corners(&self, x: &DVector<f64>) -> Vec<[f64; 2]> {
        let n = self.walls.len();
        (0..n)
            .map(|k| {
                let (n0, r0) = self.line(x, (k + n - 1) % n);
                let (n1, r1) = self.line(x, k);
                let m = Matrix2::new(n0.x, n0.y, n1.x, n1.y);
                match m.try_inverse() {
                    Some(inv) if m.determinant().abs() > 1e-3 => {
                        let p = inv * Vector2::new(r0, r1);
                        [p.x, p.y]
                    }
                    // Parallel: the foot of the origin on the first line
                    // (a polygon's drawing never has them unless in one
                    // line, where any point of it will do as the meeting).
                    _ => {
                        let p = n0 * r0;
                        [p.x, p.y]
                    }
                }
            })
            .collect()
    }

    /// Whether the stretch `ends` (room frame) seen from the laser at `l`
    /// may be wall `q` in state `x` (`corners` its [`RoomShape::corners`],
    /// worked out once for all the walls): on the wall's inner side, and
    /// overlapping its stretch between its corners. A rectangle's walls
    /// take anything (each spans its side of the room).
    pub fn may_see(
        &self,
        x: &DVector<f64>,
        corners: &[[f64; 2]],
        q: usize,
        l: &Pose2,
        ends: [Point2<f64>; 2],
    ) -> bool {
        if !self.polygon {
            return true;
        }
        let (n, rho) = self.line(x, q);
        if rho - n.dot(&l.position().coords) <= 0.0 {
            return false;
        }
        let t = Vector2::new(-n.y, n.x);
        let k1 = (q + 1) % self.walls.len();
        let [a, b] = [corners[q], corners[k1]].map(|c| t.dot(&Vector2::from(c)));
        let [u, v] = ends.map(|e| t.dot(&e.coords));
        let (lo, hi) = (a.min(b), a.max(b));
        let (seen_lo, seen_hi) = (u.min(v), u.max(v));
        // Most of what is seen lies on the wall: a line fitted across two
        // walls in one line (either side of a chimney breast) is neither.
        let overlap = seen_hi.min(hi) - seen_lo.max(lo);
        overlap > ALONG_SLACK_M.min(0.5 * (hi - lo))
            && overlap >= 0.5 * (seen_hi - seen_lo) - ALONG_SLACK_M
    }

    /// The predicted observation `(d, γ)` of wall `q` from the laser at
    /// `l` (its position's derivative by the heading `dl`) in state `x`,
    /// and its Jacobian.
    pub fn observe_from(
        &self,
        x: &DVector<f64>,
        q: usize,
        l: &Pose2,
        dl: [f64; 2],
    ) -> (Vector2<f64>, DMatrix<f64>) {
        let w = &self.walls[q];
        let (n, rho) = self.line(x, q);
        let mut h = DMatrix::zeros(2, x.len());
        h[(1, 2)] = -1.0;
        // d = ρ − n·l (a rectangle's zeros left as they are, not −0).
        for (i, v) in [(0, -n.x), (1, -n.y), (2, -(n.x * dl[0] + n.y * dl[1]))] {
            if v != 0.0 {
                h[(0, i)] = v;
            }
        }
        if let Param::Row(i) = w.offset {
            h[(0, i)] = 1.0;
        }
        let angle = match w.angle {
            Param::Fixed(a) => a,
            Param::Row(i) => {
                h[(0, i)] = n.y * l.x - n.x * l.y;
                h[(1, i)] = 1.0;
                x[i]
            }
        };
        let d = rho - (n.x * l.x + n.y * l.y);
        (Vector2::new(d, wrap_angle(angle - l.theta)), h)
    }

    /// A door's centre in the room, at `s` along wall `q` in state `x`,
    /// and its derivatives.
    pub fn door_centre(&self, x: &DVector<f64>, q: usize, s: f64) -> DoorCentre {
        let w = &self.walls[q];
        let (n, rho) = self.line(x, q);
        let t = self.along(x, q);
        let mut by_rows = Vec::new();
        if let Param::Row(i) = w.offset {
            by_rows.push((i, n));
        }
        if let Param::Row(i) = w.angle {
            // ∂n/∂φ = (−n_y, n_x); ∂t/∂φ = −n (t turns with n).
            by_rows.push((i, rho * Vector2::new(-n.y, n.x) - s * w.along_sign * n));
        }
        (n * rho + t * s, t, by_rows)
    }

    /// How far along wall `q` in state `x` the point `p` lies (its
    /// position as a door of that wall).
    pub fn position_along(&self, x: &DVector<f64>, q: usize, p: &Point2<f64>) -> f64 {
        self.along(x, q).dot(&p.coords)
    }

    /// A door's position `s` along wall `q` in state `x` measured instead
    /// from the wall's first corner toward its second (as plans and
    /// reports give it; a rectangle's positions are the same both ways).
    pub fn from_first_corner(&self, x: &DVector<f64>, q: usize, s: f64) -> f64 {
        if !self.polygon {
            return s;
        }
        let (a, dir) = self.first_corner(x, q);
        (self.door_centre(x, q, s).0 - a).dot(&dir)
    }

    /// The inverse of [`RoomShape::from_first_corner`]: the position in
    /// the state of a door `m` from wall `q`'s first corner.
    pub fn to_state(&self, x: &DVector<f64>, q: usize, m: f64) -> f64 {
        if !self.polygon {
            return m;
        }
        let (a, dir) = self.first_corner(x, q);
        self.position_along(x, q, &Point2::from(a + dir * m))
    }

    /// Wall `q`'s first corner in state `x` and its direction toward the
    /// second.
    fn first_corner(&self, x: &DVector<f64>, q: usize) -> (Vector2<f64>, Vector2<f64>) {
        let (n, _) = self.line(x, q);
        let corners = self.corners(x);
        (Vector2::from(corners[q]), Vector2::new(-n.y, n.x))
    }

    /// The wall of the shape nearest `p` in state `x` within `within_m`
    /// (its distance to the wall's stretch), if any.
    pub fn wall_at(&self, x: &DVector<f64>, p: &Point2<f64>, within_m: f64) -> Option<usize> {
        let corners = self.corners(x);
        let n = self.walls.len();
        (0..n)
            .map(|q| {
                let (a, b) = (
                    Vector2::from(corners[q]),
                    Vector2::from(corners[(q + 1) % n]),
                );
                let ab = b - a;
                let f = ((p.coords - a).dot(&ab) / ab.norm_squared().max(1e-12)).clamp(0.0, 1.0);
                (q, (a + ab * f - p.coords).norm())
            })
            .filter(|(_, d)| *d <= within_m)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(q, _)| q)
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    fn ell() -> Vec<[f64; 2]> {
        vec![
            [0.0, 0.0],
            [6.0, 0.0],
            [6.0, 2.5],
            [3.5, 2.5],
            [3.5, 5.0],
            [0.0, 5.0],
        ]
    }

    fn drawn_state(shape: &RoomShape, pose: [f64; 3]) -> DVector<f64> {
        let mut x = DVector::zeros(3 + shape.rows());
        x.rows_mut(0, 3).copy_from_slice(&pose);
        for (i, (v, _)) in shape.drawn().iter().enumerate() {
            x[3 + i] = *v;
        }
        x
    }

    #[test]
    fn a_polygons_corners_come_back_from_its_walls() {
        let shape = RoomShape::polygon(&ell(), 0.03).expect("an L");
        assert_eq!((shape.len(), shape.rows()), (6, 10));
        let x = drawn_state(&shape, [1.0, 1.0, 0.0]);
        for (got, want) in shape.corners(&x).iter().zip(ell()) {
            assert!((got[0] - want[0]).abs() < 1e-9 && (got[1] - want[1]).abs() < 1e-9);
        }
        let x = DVector::from_vec(vec![1.0, 1.0, 0.0, 6.0, 5.0]);
        let rect = RoomShape::rectangle().corners(&x);
        assert_eq!(rect, vec![[0.0, 5.0], [0.0, 0.0], [6.0, 0.0], [6.0, 5.0]]);
    }

    #[test]
    fn a_wall_is_seen_only_from_its_inner_side_and_along_its_stretch() {
        let shape = RoomShape::polygon(&ell(), 0.03).expect("an L");
        let x = drawn_state(&shape, [1.0, 1.0, 0.0]);
        // The notch's wall y = 2.5 (wall 2), x from 3.5 to 6.
        let l = Pose2::new(1.0, 1.0, 0.0);
        let seg = |a: [f64; 2], b: [f64; 2]| [Point2::from(a), Point2::from(b)];
        let c = shape.corners(&x);
        assert!(shape.may_see(&x, &c, 2, &l, seg([4.0, 2.5], [5.5, 2.5])));
        // The far wall y = 5 left of the notch, in the notch wall's line
        // of sight but off its stretch.
        assert!(!shape.may_see(&x, &c, 2, &l, seg([0.5, 5.0], [3.0, 5.0])));
        // From above the notch's line the notch wall faces away.
        let above = Pose2::new(1.0, 4.0, 0.0);
        assert!(!shape.may_see(&x, &c, 2, &above, seg([4.0, 2.5], [5.5, 2.5])));
    }

    /// An L's frame: wall 0's line, and of the walls square to it the
    /// longest (wall 5, 5 m) holding its drawn offset; every other row
    /// starts as loose as drawn.
    #[test]
    fn a_polygons_frame_is_held_by_wall_0_and_the_longest_wall_square_to_it() {
        let l = [
            [0.0, 0.0],
            [6.0, 0.0],
            [6.0, 3.0],
            [3.0, 3.0],
            [3.0, 5.0],
            [0.0, 5.0],
        ];
        let shape = RoomShape::polygon(&l, 0.03).expect("an L");
        let held = shape.offset_row(5).expect("wall 5's offset") - 3;
        for (i, (_, sigma)) in shape.drawn().iter().enumerate() {
            if i == held {
                assert_eq!(*sigma, FRAME_HELD_SIGMA_M);
            } else {
                assert!(*sigma > 0.005, "row {i}: {sigma}");
            }
        }
        assert_eq!(shape.offset_row(0), None);
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let mut corners = ell();
        corners[3] = [3.2, 2.6];
        let shape = RoomShape::polygon(&corners, 0.03).expect("an L");
        let mut x = drawn_state(&shape, [1.2, 1.1, 0.4]);
        x[5] += 0.01;
        let mount = Pose2::new(0.35, 0.05, 0.02);
        let laser = |x: &DVector<f64>| {
            let (s, c) = x[2].sin_cos();
            (
                Pose2::new(
                    x[0] + c * mount.x - s * mount.y,
                    x[1] + s * mount.x + c * mount.y,
                    x[2] + mount.theta,
                ),
                [-s * mount.x - c * mount.y, c * mount.x - s * mount.y],
            )
        };
        for q in 0..shape.len() {
            let (l, dl) = laser(&x);
            let (z, h) = shape.observe_from(&x, q, &l, dl);
            let (c, ds, rows) = shape.door_centre(&x, q, 1.3);
            for i in 0..x.len() {
                let mut dx = x.clone();
                dx[i] += 1e-7;
                let (l2, dl2) = laser(&dx);
                let (z2, _) = shape.observe_from(&dx, q, &l2, dl2);
                let num = (z2 - z) / 1e-7;
                assert!((num.x - h[(0, i)]).abs() < 1e-5, "wall {q} row {i}");
                assert!((wrap_angle(num.y * 1e-7) / 1e-7 - h[(1, i)]).abs() < 1e-5);
                let (c2, _, _) = shape.door_centre(&dx, q, 1.3);
                let want = rows
                    .iter()
                    .find(|(r, _)| *r == i)
                    .map_or(Vector2::zeros(), |(_, d)| *d);
                assert!(
                    ((c2 - c) / 1e-7 - want).norm() < 1e-5,
                    "door wall {q} row {i}"
                );
            }
            let (c3, _, _) = shape.door_centre(&x, q, 1.3 + 1e-7);
            assert!(((c3 - c) / 1e-7 - ds).norm() < 1e-5);
        }
    }

    #[test]
    fn a_doors_position_from_its_walls_first_corner_comes_back() {
        let shape = RoomShape::polygon(&ell(), 0.03).expect("an L");
        let x = drawn_state(&shape, [1.0, 1.0, 0.0]);
        // Wall 3 runs from (3.5, 2.5) up to (3.5, 5): a door 1 m along it
        // is at (3.5, 3.5).
        let s = shape.to_state(&x, 3, 1.0);
        let (centre, _, _) = shape.door_centre(&x, 3, s);
        assert!((centre - Vector2::new(3.5, 3.5)).norm() < 1e-12, "{centre}");
        assert!((shape.from_first_corner(&x, 3, s) - 1.0).abs() < 1e-12);
        // Wall 2 runs west from (6, 2.5).
        let s = shape.to_state(&x, 2, 0.5);
        let (centre, _, _) = shape.door_centre(&x, 2, s);
        assert!((centre - Vector2::new(5.5, 2.5)).norm() < 1e-12, "{centre}");
    }

    #[test]
    fn a_rectangles_doors_lie_at_their_x_or_y() {
        let shape = RoomShape::rectangle();
        let x = DVector::from_vec(vec![1.0, 1.0, 0.0, 6.0, 5.0]);
        let at = |q: usize, s: f64| shape.door_centre(&x, q, s).0;
        assert_eq!(at(0, 2.0), Vector2::new(0.0, 2.0));
        assert_eq!(at(1, 2.0), Vector2::new(2.0, 0.0));
        assert_eq!(at(2, 2.0), Vector2::new(6.0, 2.0));
        assert_eq!(at(3, 2.0), Vector2::new(2.0, 5.0));
    }
}
