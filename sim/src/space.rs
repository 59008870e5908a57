//! The static world in three dimensions for the cameras' rays: every
//! solid (boxes turned about the vertical, upright cylinders) listed in the
//! floor plan's grid cells its footprint overlaps, a ray cast by walking
//! the cells its horizontal projection crosses. The same geometry rapier
//! holds (a test casts both and compares), without a query through the
//! whole bounding-volume tree per ray: the cameras' rays were a quarter of
//! a whole job's time.

use crate::grid::CellGrid;
use crate::layout::{Layout, Material, Solid};
use crate::scene::Upright;
use nalgebra::{Point2, Vector2};

#[derive(Clone, Copy, Debug)]
enum Item {
    /// A box: its centre, half extents along its own axes, the sine and
    /// cosine of its heading, and whether it is glass.
    Box {
        center: [f64; 3],
        half: [f64; 3],
        sin_cos: (f64, f64),
        glass: bool,
    },
    Cylinder(Upright),
}

/// Where the unit ray `o + s·d` enters the box, and the |cosine| of its
/// incidence on the face it enters by; a ray from inside meets it at 0
/// (as rapier's solid casts do).
fn ray_box(
    o: [f64; 3],
    d: [f64; 3],
    center: [f64; 3],
    half: [f64; 3],
    (sin, cos): (f64, f64),
) -> Option<(f64, f64)> {
    let (px, py, pz) = (o[0] - center[0], o[1] - center[1], o[2] - center[2]);
    let lo = [cos * px + sin * py, -sin * px + cos * py, pz];
    let ld = [cos * d[0] + sin * d[1], -sin * d[0] + cos * d[1], d[2]];
    let (mut near, mut far, mut axis) = (f64::NEG_INFINITY, f64::INFINITY, 0);
    for k in 0..3 {
        if ld[k].abs() < 1e-15 {
            if lo[k].abs() > half[k] {
                return None;
            }
            continue;
        }
        let (t1, t2) = ((-half[k] - lo[k]) / ld[k], (half[k] - lo[k]) / ld[k]);
        let (a, b) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
        if a > near {
            near = a;
            axis = k;
        }
        far = far.min(b);
    }
    if near > far || far < 0.0 {
        return None;
    }
    if near < 0.0 {
        return Some((0.0, 0.0));
    }
    Some((near, ld[axis].abs()))
}

/// A solid whose footprint is wider or deeper than this is met once per
/// ray, not in every cell it covers (a floor, a ceiling), m.
const LARGE_M: f64 = 2.0;

/// The static solids of a layout, for rays in any direction.
#[derive(Clone, Debug)]
pub struct SpaceCaster {
    /// The solids listed in the grid.
    items: Vec<Item>,
    grid: CellGrid,
    /// The large ones, met by every ray before the grid is walked.
    large: Vec<Item>,
}

impl SpaceCaster {
    /// Every solid of `layout`.
    pub fn new(layout: &Layout) -> Self {
        let items: Vec<Item> = layout
            .solids
            .iter()
            .map(|solid| match *solid {
                Solid::Box {
                    center,
                    half,
                    yaw_rad,
                    material,
                } => Item::Box {
                    center,
                    half,
                    sin_cos: yaw_rad.sin_cos(),
                    glass: material == Material::Glass,
                },
                Solid::Cylinder { at, radius, z } => Item::Cylinder(Upright {
                    at: Point2::new(at[0], at[1]),
                    radius,
                    z,
                }),
            })
            .collect();
        let footprint = |it: &Item| match *it {
            Item::Box {
                center,
                half,
                sin_cos: (s, c),
                ..
            } => {
                // The turned box's footprint's bounding rectangle.
                let (ex, ey) = (
                    (c * half[0]).abs() + (s * half[1]).abs(),
                    (s * half[0]).abs() + (c * half[1]).abs(),
                );
                let m = Point2::new(center[0], center[1]);
                (m - Vector2::new(ex, ey), m + Vector2::new(ex, ey))
            }
            Item::Cylinder(u) => (
                u.at - Vector2::new(u.radius, u.radius),
                u.at + Vector2::new(u.radius, u.radius),
            ),
        };
        let (large, items): (Vec<Item>, Vec<Item>) = items.into_iter().partition(|it| {
            let (a, b) = footprint(it);
            (b - a).min() > LARGE_M
        });
        let bounds: Vec<_> = items.iter().map(footprint).collect();
        SpaceCaster {
            grid: CellGrid::new(&bounds),
            items,
            large,
        }
    }

    /// Where the unit ray `o + s·d` meets `item`, if it returns the light.
    fn meet(item: &Item, o: [f64; 3], d: [f64; 3], glass_min_cos: f64) -> Option<f64> {
        match *item {
            Item::Box {
                center,
                half,
                sin_cos,
                glass,
            } => ray_box(o, d, center, half, sin_cos)
                .filter(|&(_, cos)| !glass || cos >= glass_min_cos)
                .map(|(s, _)| s),
            Item::Cylinder(u) => u.cast(o, d),
        }
    }

    /// Distance along the unit ray `o + s·d` to the first static surface
    /// that returns the light, up to `max_m`: glass only when met within
    /// `glass_min_cos` of normal incidence (at a slant the ray goes
    /// through it).
    pub fn cast(&self, o: [f64; 3], d: [f64; 3], max_m: f64, glass_min_cos: f64) -> Option<f64> {
        let large = self
            .large
            .iter()
            .filter_map(|it| Self::meet(it, o, d, glass_min_cos))
            .filter(|&s| s < max_m)
            .min_by(f64::total_cmp);
        let o2 = Point2::new(o[0], o[1]);
        let d2 = Vector2::new(d[0], d[1]);
        self.grid
            .nearest(&o2, &d2, large.unwrap_or(max_m), |i| {
                Self::meet(&self.items[i], o, d, glass_min_cos)
            })
            .or(large)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_meets_a_turned_box_on_the_face_it_enters_by() {
        let quarter = std::f64::consts::FRAC_PI_4.sin_cos();
        // A 2 × 2 × 2 box at (5, 0, 1), turned 45°: its corner nearest the
        // origin at x = 5 − √2.
        let hit = ray_box(
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [5.0, 0.0, 1.0],
            [1.0; 3],
            quarter,
        );
        let (s, cos) = hit.unwrap_or_default();
        assert!((s - (5.0 - 2f64.sqrt())).abs() < 1e-12, "{s}");
        assert!((cos - quarter.1).abs() < 1e-12, "{cos}");
        // Straight down onto its top, face-on.
        let hit = ray_box(
            [5.0, 0.0, 4.0],
            [0.0, 0.0, -1.0],
            [5.0, 0.0, 1.0],
            [1.0; 3],
            quarter,
        );
        assert_eq!(hit, Some((2.0, 1.0)));
        // Past it, and from inside.
        let past = ray_box(
            [0.0, 3.0, 1.0],
            [1.0, 0.0, 0.0],
            [5.0, 0.0, 1.0],
            [1.0; 3],
            quarter,
        );
        assert_eq!(past, None);
        let inside = ray_box(
            [5.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [5.0, 0.0, 1.0],
            [1.0; 3],
            quarter,
        );
        assert_eq!(inside.map(|h| h.0), Some(0.0));
    }
}
