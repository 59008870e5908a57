//! The world cut at the laser's height: the static solids' outlines as
//! segments and circles in a uniform grid, so a horizontal beam is cast in
//! the plane by walking the grid cells it crosses. The laser's beams are
//! 90% of the simulator's queries; this is the same geometry rapier holds
//! (a test casts both and compares), at a fraction of the cost of a 3-D
//! ray through the whole bounding-volume tree.

use crate::grid::CellGrid;
use crate::layout::{Layout, Material, Solid};
use nalgebra::{Point2, Vector2};

/// Glass returns the laser only this close to normal incidence (cosine of
/// 10°).
const GLASS_MIN_COS: f64 = 0.984_807_753_012_208;

#[derive(Clone, Copy, Debug)]
enum Item {
    Segment {
        a: Point2<f64>,
        b: Point2<f64>,
        glass: bool,
    },
    Circle {
        c: Point2<f64>,
        r: f64,
    },
}

/// The static world in the plane `z = height`.
#[derive(Clone, Debug)]
pub struct PlaneCaster {
    items: Vec<Item>,
    grid: CellGrid,
}

/// Distance along the unit ray `o + s·d` to the circle `(c, r)`, if hit.
pub fn ray_circle(o: &Point2<f64>, d: &Vector2<f64>, c: &Point2<f64>, r: f64) -> Option<f64> {
    let w = c - o;
    let proj = w.dot(d);
    let perp2 = w.norm_squared() - proj * proj;
    let r2 = r * r;
    if perp2 > r2 {
        return None;
    }
    let s = proj - (r2 - perp2).sqrt();
    (s > 1e-9).then_some(s)
}

fn ray_segment(o: &Point2<f64>, d: &Vector2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> Option<f64> {
    let e = b - a;
    let denom = d.x * e.y - d.y * e.x;
    if denom.abs() < 1e-15 {
        return None;
    }
    let w = a - o;
    let s = (w.x * e.y - w.y * e.x) / denom;
    let u = (w.x * d.y - w.y * d.x) / denom;
    (s > 1e-9 && (-1e-12..=1.0 + 1e-12).contains(&u)).then_some(s)
}

impl PlaneCaster {
    /// The solids of `layout` that cross the plane `z = height_m`.
    pub fn new(layout: &Layout, height_m: f64) -> PlaneCaster {
        let mut items = Vec::new();
        for solid in &layout.solids {
            match *solid {
                Solid::Box {
                    center,
                    half,
                    yaw_rad,
                    material,
                } if (center[2] - height_m).abs() < half[2] => {
                    let (s, c) = yaw_rad.sin_cos();
                    let corner = |fx: f64, fy: f64| {
                        let (x, y) = (fx * half[0], fy * half[1]);
                        Point2::new(center[0] + c * x - s * y, center[1] + s * x + c * y)
                    };
                    let k = [
                        corner(-1.0, -1.0),
                        corner(1.0, -1.0),
                        corner(1.0, 1.0),
                        corner(-1.0, 1.0),
                    ];
                    for i in 0..4 {
                        items.push(Item::Segment {
                            a: k[i],
                            b: k[(i + 1) % 4],
                            glass: material == Material::Glass,
                        });
                    }
                }
                Solid::Cylinder { at, radius, z } if z[0] <= height_m && height_m <= z[1] => {
                    items.push(Item::Circle {
                        c: Point2::new(at[0], at[1]),
                        r: radius,
                    });
                }
                _ => {}
            }
        }
        let bounds: Vec<_> = items
            .iter()
            .map(|it| match *it {
                Item::Segment { a, b, .. } => (a.inf(&b), a.sup(&b)),
                Item::Circle { c, r } => (c - Vector2::new(r, r), c + Vector2::new(r, r)),
            })
            .collect();
        PlaneCaster {
            grid: CellGrid::new(&bounds),
            items,
        }
    }

    /// Distance along the unit ray `o + s·d` to the first static surface
    /// that returns the laser, up to `max_m`.
    pub fn cast(&self, o: &Point2<f64>, d: &Vector2<f64>, max_m: f64) -> Option<f64> {
        self.grid.nearest(o, d, max_m, |i| match self.items[i] {
            Item::Segment { a, b, glass } => ray_segment(o, d, &a, &b).filter(|_| {
                !glass || {
                    let e = (b - a).normalize();
                    // |cos| of the angle between ray and normal.
                    (d.x * e.y - d.y * e.x).abs() >= GLASS_MIN_COS
                }
            }),
            Item::Circle { c, r } => ray_circle(o, d, &c, r),
        })
    }
}
