//! Spray deposition, shared by the planner (which predicts the thickness its
//! strokes leave) and the simulator (which deposits plaster on the true
//! surfaces): plane surfaces with their own `(u, v)` frame, the Gaussian
//! footprint integrated in closed form along a straight nozzle path, and
//! thickness grids.
//!
//! The footprint is an isotropic 2-D Gaussian on the surface: a nozzle
//! holding still for `dt` seconds at flow `Q` leaves `Q·dt·g(q − p)` of
//! thickness at `q`, `g` the normal density with standard deviation `σ`.
//! Moving at constant speed from `p0` to `p1`, it leaves the density's
//! mean over the path, which has a closed form (erf along the path, a
//! Gaussian across it), so a stroke's thickness is exact whatever the
//! time step.

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Where the nozzle points, in the robot's frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Aim {
    /// Horizontal, to the robot's left (walls).
    #[default]
    Left,
    /// Straight up (ceilings).
    Up,
}

impl Aim {
    /// Unit direction of the spray in the robot's frame.
    pub fn direction(self) -> Vector3<f64> {
        match self {
            Aim::Left => Vector3::new(0.0, 1.0, 0.0),
            Aim::Up => Vector3::new(0.0, 0.0, 1.0),
        }
    }
}

/// What the spray tool is asked to do: where the nozzle is, where it
/// points, whether plaster flows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolCommand {
    /// The nozzle's position in the robot's frame (x forward of the rear
    /// axle, y left, z up from the floor), m.
    pub nozzle_m: [f64; 3],
    /// Where it points.
    pub aim: Aim,
    /// Plaster flowing.
    pub spray: bool,
    /// Flow while spraying when it is not the sprayer's own (a task's own
    /// spray settings), m³/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flow_m3ps: Option<f64>,
}

impl ToolCommand {
    /// Spray off, nozzle wherever it was asked to be.
    pub fn off(self) -> ToolCommand {
        ToolCommand {
            spray: false,
            ..self
        }
    }
}

/// A plane rectangle in space with its own frame: `u` and `v` unit and
/// orthogonal, the surface spanning `[0, size_m[0]] × [0, size_m[1]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceFrame {
    /// The point `(u, v) = (0, 0)`.
    pub origin: Point3<f64>,
    /// Unit vector of `u`.
    pub u: Vector3<f64>,
    /// Unit vector of `v`.
    pub v: Vector3<f64>,
    /// Extent along `u` and `v`, m.
    pub size_m: [f64; 2],
}

/// Where a ray meets a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// The point hit, in the surface's frame, m.
    pub uv: [f64; 2],
    /// Distance from the ray's start, m.
    pub distance_m: f64,
}

impl SurfaceFrame {
    /// The point of the surface at `uv`.
    pub fn point(&self, uv: [f64; 2]) -> Point3<f64> {
        self.origin + self.u * uv[0] + self.v * uv[1]
    }

    /// The surface coordinates of `p` projected on the plane.
    pub fn uv(&self, p: &Point3<f64>) -> [f64; 2] {
        let d = p - self.origin;
        [d.dot(&self.u), d.dot(&self.v)]
    }

    /// Unit normal, `u × v`.
    pub fn normal(&self) -> Vector3<f64> {
        self.u.cross(&self.v)
    }

    /// Where the ray from `from` along the unit `dir` meets the plane, if
    /// it does ahead within the rectangle grown by `pad_m` on every side.
    pub fn hit(&self, from: &Point3<f64>, dir: &Vector3<f64>, pad_m: f64) -> Option<SurfaceHit> {
        let n = self.normal();
        let den = n.dot(dir);
        if den.abs() < 1e-9 {
            return None;
        }
        let t = n.dot(&(self.origin - from)) / den;
        if t <= 0.0 {
            return None;
        }
        let uv = self.uv(&(from + dir * t));
        let inside = |x: f64, size: f64| x >= -pad_m && x <= size + pad_m;
        (inside(uv[0], self.size_m[0]) && inside(uv[1], self.size_m[1]))
            .then_some(SurfaceHit { uv, distance_m: t })
    }
}

/// The standard normal distribution function.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// The mean, over the straight path from `p0` to `p1`, of the isotropic
/// Gaussian density of standard deviation `sigma_m` centred on the path,
/// evaluated at `q` (1/m²). Times the volume sprayed along the path, it is
/// the thickness left at `q`.
pub fn path_density(q: [f64; 2], p0: [f64; 2], p1: [f64; 2], sigma_m: f64) -> f64 {
    let (dx, dy) = (p1[0] - p0[0], p1[1] - p0[1]);
    let len = dx.hypot(dy);
    let (qx, qy) = (q[0] - p0[0], q[1] - p0[1]);
    let s2 = sigma_m * sigma_m;
    if len < 1e-3 * sigma_m {
        // Standing still.
        return (-(qx * qx + qy * qy) / (2.0 * s2)).exp() / (std::f64::consts::TAU * s2);
    }
    let (ex, ey) = (dx / len, dy / len);
    let along = qx * ex + qy * ey;
    let across = qx * ey - qy * ex;
    across_factor(across, sigma_m) * along_factor(along, len, sigma_m) / len
}

/// The factors of [`path_density`] for a path of length `len` (> 0)
/// along an axis: at a point `across` the path's line and `along` it from
/// its start (signed as `path_density` signs them, the path's unit
/// direction's component on the axis ±1), the density is
/// `across_factor * along_factor / len`.
fn across_factor(across: f64, sigma_m: f64) -> f64 {
    (-(across * across) / (2.0 * (sigma_m * sigma_m))).exp()
        / (sigma_m * (std::f64::consts::TAU).sqrt())
}

fn along_factor(along: f64, len: f64, sigma_m: f64) -> f64 {
    normal_cdf(along / sigma_m) - normal_cdf((along - len) / sigma_m)
}

/// How far from its path a footprint is worth adding, in standard
/// deviations (the density there is 3·10⁻⁴ of its peak).
pub const FOOTPRINT_REACH_SIGMAS: f64 = 4.0;

/// Thickness of plaster on a surface, sampled at the centres of square
/// cells covering `[0, size_m[0]] × [0, size_m[1]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThicknessGrid {
    /// Side of a cell, m.
    pub cell_m: f64,
    /// Cells along `u` and `v`.
    pub cells: [usize; 2],
    /// Thickness at each cell's centre, m, row by row (`v` major).
    pub thickness_m: Vec<f64>,
}

impl ThicknessGrid {
    /// A bare surface of `size_m`, in cells no larger than `cell_m`.
    pub fn new(size_m: [f64; 2], cell_m: f64) -> ThicknessGrid {
        let nu = ((size_m[0] / cell_m).ceil() as usize).max(1);
        let nv = ((size_m[1] / cell_m).ceil() as usize).max(1);
        ThicknessGrid {
            cell_m,
            cells: [nu, nv],
            thickness_m: vec![0.0; nu * nv],
        }
    }

    /// The centre of cell `(i, j)`, in the surface's frame.
    pub fn center(&self, i: usize, j: usize) -> [f64; 2] {
        [
            (i as f64 + 0.5) * self.cell_m,
            (j as f64 + 0.5) * self.cell_m,
        ]
    }

    /// Thickness at cell `(i, j)`, m.
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.thickness_m[j * self.cells[0] + i]
    }

    /// Area of one cell, m².
    pub fn cell_area_m2(&self) -> f64 {
        self.cell_m * self.cell_m
    }

    /// Every cell with its centre and thickness.
    pub fn iter(&self) -> impl Iterator<Item = ([f64; 2], f64)> + '_ {
        let nu = self.cells[0];
        self.thickness_m
            .iter()
            .enumerate()
            .map(move |(k, &t)| (self.center(k % nu, k / nu), t))
    }

    /// Volume of plaster on the grid, m³.
    pub fn volume_m3(&self) -> f64 {
        self.thickness_m.iter().sum::<f64>() * self.cell_area_m2()
    }

    /// [`ThicknessGrid::deposit`] for a path from `p0` to `p1` along `v`
    /// (`vertical`) or `u`, of length `len`, over the cells `iu` × `iv`.
    #[allow(clippy::too_many_arguments)]
    fn deposit_along_axis(
        &mut self,
        p0: [f64; 2],
        p1: [f64; 2],
        len: f64,
        vertical: bool,
        (iu, iv): (std::ops::Range<usize>, std::ops::Range<usize>),
        volume_m3: f64,
        sigma_m: f64,
    ) {
        // `path_density`'s unit direction is (0, ±1) or (±1, 0) exactly,
        // so of its across and along one term of each is an exact zero:
        // across = q_u·e_v and along = q_v·e_v up the `v` axis, along =
        // q_u·e_u and across = −q_v·e_u along `u`.
        let q_u = |i: usize| self.center(i, 0)[0] - p0[0];
        let q_v = |j: usize| self.center(0, j)[1] - p0[1];
        let (by_column, by_row): (Vec<f64>, Vec<f64>) = if vertical {
            let e = (p1[1] - p0[1]) / len;
            (
                iu.clone()
                    .map(|i| across_factor(q_u(i) * e, sigma_m))
                    .collect(),
                iv.clone()
                    .map(|j| along_factor(q_v(j) * e, len, sigma_m))
                    .collect(),
            )
        } else {
            let e = (p1[0] - p0[0]) / len;
            (
                iu.clone()
                    .map(|i| along_factor(q_u(i) * e, len, sigma_m))
                    .collect(),
                iv.clone()
                    .map(|j| across_factor(-(q_v(j) * e), sigma_m))
                    .collect(),
            )
        };
        for (j, row) in iv.zip(&by_row) {
            for (i, column) in iu.clone().zip(&by_column) {
                self.thickness_m[j * self.cells[0] + i] += volume_m3 * (column * row / len);
            }
        }
    }

    /// Spreads `volume_m3` of plaster sprayed while the footprint's centre
    /// moved at constant speed from `p0` to `p1`.
    pub fn deposit(&mut self, p0: [f64; 2], p1: [f64; 2], volume_m3: f64, sigma_m: f64) {
        if volume_m3 <= 0.0 {
            return;
        }
        let (iu, iv) = self.reach(p0, p1, sigma_m);
        // A stroke along a grid axis (a wall's vertical strokes, a
        // ceiling's rows): the density is a product of a factor across it,
        // one a column (or row), and one along it, one a row (or column) —
        // the same numbers as `path_density` gives cell by cell, with a
        // fraction of its exponentials.
        let (dx, dy) = (p1[0] - p0[0], p1[1] - p0[1]);
        let len = dx.hypot(dy);
        if len >= 1e-3 * sigma_m && (dx == 0.0 || dy == 0.0) {
            self.deposit_along_axis(p0, p1, len, dx == 0.0, (iu, iv), volume_m3, sigma_m);
        } else {
            self.deposit_on(p0, p1, (iu, iv), volume_m3, sigma_m);
        }
    }

    /// [`ThicknessGrid::deposit`] as it was before strokes along an axis
    /// were laid by their factors: [`path_density`] cell by cell, the
    /// benchmarks' baseline (the same numbers, bit for bit).
    pub fn deposit_cell_by_cell(
        &mut self,
        p0: [f64; 2],
        p1: [f64; 2],
        volume_m3: f64,
        sigma_m: f64,
    ) {
        if volume_m3 <= 0.0 {
            return;
        }
        let cells = self.reach(p0, p1, sigma_m);
        self.deposit_on(p0, p1, cells, volume_m3, sigma_m);
    }

    /// The cells within the footprint's reach of the path from `p0` to
    /// `p1`, along `u` and along `v`.
    fn reach(
        &self,
        p0: [f64; 2],
        p1: [f64; 2],
        sigma_m: f64,
    ) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let reach = FOOTPRINT_REACH_SIGMAS * sigma_m;
        let range = |a: f64, b: f64, n: usize| {
            let lo = ((a.min(b) - reach) / self.cell_m - 0.5).ceil().max(0.0) as usize;
            let hi = ((a.max(b) + reach) / self.cell_m - 0.5).floor();
            if hi < 0.0 {
                return lo..lo;
            }
            lo..((hi as usize) + 1).min(n)
        };
        (
            range(p0[0], p1[0], self.cells[0]),
            range(p0[1], p1[1], self.cells[1]),
        )
    }

    /// [`path_density`] cell by cell over `iu` × `iv`.
    fn deposit_on(
        &mut self,
        p0: [f64; 2],
        p1: [f64; 2],
        (iu, iv): (std::ops::Range<usize>, std::ops::Range<usize>),
        volume_m3: f64,
        sigma_m: f64,
    ) {
        for j in iv {
            for i in iu.clone() {
                let q = self.center(i, j);
                let k = j * self.cells[0] + i;
                self.thickness_m[k] += volume_m3 * path_density(q, p0, p1, sigma_m);
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    /// Strokes along either axis, either way, are laid by their factors:
    /// the same numbers, bit for bit, as the density cell by cell.
    #[test]
    fn a_stroke_along_an_axis_lays_what_the_density_gives_cell_by_cell() {
        for (p0, p1) in [
            ([0.5, 0.2], [0.5, 0.8]),
            ([0.5, 0.8], [0.5, 0.2]),
            ([0.2, 0.45], [0.9, 0.45]),
            ([0.9, 0.45], [0.2, 0.45]),
            ([0.3, 0.3], [0.3, 0.3003]),
        ] {
            let mut g = ThicknessGrid::new([1.0, 1.0], 0.01);
            g.deposit(p0, p1, 2e-3, 0.04);
            let mut cell_by_cell = ThicknessGrid::new([1.0, 1.0], 0.01);
            cell_by_cell.deposit_cell_by_cell(p0, p1, 2e-3, 0.04);
            assert!(g.volume_m3() > 1e-3, "{p0:?} → {p1:?}: nothing laid");
            assert_eq!(g, cell_by_cell, "{p0:?} → {p1:?}");
        }
    }

    #[test]
    fn a_footprint_integrates_to_one() {
        // Point-sampled at 1 cm, a 4 cm Gaussian sums to its volume.
        for (p0, p1) in [
            ([0.5, 0.5], [0.5, 0.5]),
            ([0.3, 0.4], [0.7, 0.55]),
            ([0.5, 0.2], [0.5, 0.8]),
        ] {
            let mut g = ThicknessGrid::new([1.0, 1.0], 0.01);
            g.deposit(p0, p1, 2e-3, 0.04);
            assert!(
                (g.volume_m3() - 2e-3).abs() < 2e-3 * 1e-3,
                "{}",
                g.volume_m3()
            );
        }
    }

    #[test]
    fn a_path_is_the_mean_of_its_points() {
        // The closed form against a fine sum of standing footprints.
        let (p0, p1, s) = ([0.1, 0.2], [0.4, -0.1], 0.05);
        for q in [[0.2, 0.1], [0.0, 0.25], [0.45, -0.12], [0.3, 0.3]] {
            let n = 20_000;
            let mean = (0..n)
                .map(|k| {
                    let t = (k as f64 + 0.5) / n as f64;
                    let p = [p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])];
                    path_density(q, p, p, s)
                })
                .sum::<f64>()
                / n as f64;
            let exact = path_density(q, p0, p1, s);
            assert!(
                (exact - mean).abs() < 1e-6 * mean.max(1.0),
                "{exact} {mean}"
            );
        }
    }

    #[test]
    fn even_strokes_leave_an_even_coat() {
        // Vertical strokes 1.5 σ apart: flat to better than 0.1% between
        // them; past the last, the coat falls as if each stroke laid an
        // even band one spacing wide.
        let s = 0.04;
        let mut g = ThicknessGrid::new([1.0, 1.0], 0.01);
        let spacing = 1.5 * s;
        for k in 0..=10 {
            let u = 0.2 + k as f64 * spacing;
            g.deposit([u, 0.0], [u, 1.0], 1e-3 * spacing, s);
        }
        let mid: Vec<f64> = (30..70).map(|i| g.at(i, 50)).collect();
        let (lo, hi) = mid
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &t| (a.min(t), b.max(t)));
        assert!((hi - lo) / hi < 1e-3, "{lo} {hi}");
        assert!((hi - 1e-3).abs() < 1e-5, "{hi}");
        for i in [79, 83, 90] {
            let u = g.center(i, 50)[0];
            let band = 1e-3 * normal_cdf((0.8 + spacing / 2.0 - u) / s);
            assert!((g.at(i, 50) - band).abs() < 0.04e-3, "{u} {}", g.at(i, 50));
        }
    }

    #[test]
    fn rays_meet_surfaces_ahead_within_their_bounds() {
        let wall = SurfaceFrame {
            origin: Point3::new(0.0, 0.0, 0.0),
            u: Vector3::new(1.0, 0.0, 0.0),
            v: Vector3::new(0.0, 0.0, 1.0),
            size_m: [5.0, 2.6],
        };
        let from = Point3::new(2.0, 0.3, 1.2);
        let hit = wall
            .hit(&from, &Vector3::new(0.0, -1.0, 0.0), 0.0)
            .expect("ahead");
        assert!((hit.distance_m - 0.3).abs() < 1e-12);
        assert!((hit.uv[0] - 2.0).abs() < 1e-12 && (hit.uv[1] - 1.2).abs() < 1e-12);
        assert!(wall.hit(&from, &Vector3::new(0.0, 1.0, 0.0), 0.0).is_none());
        let beyond = Point3::new(5.2, 0.3, 1.2);
        let down = Vector3::new(0.0, -1.0, 0.0);
        assert!(wall.hit(&beyond, &down, 0.0).is_none());
        assert!(wall.hit(&beyond, &down, 0.3).is_some());
    }
}
