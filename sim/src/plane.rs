//! The world cut at the laser's height: the static solids' outlines as
//! segments and circles in a uniform grid, so a horizontal beam is cast in
//! the plane by walking the grid cells it crosses. The laser's beams are
//! 90% of the simulator's queries; this is the same geometry rapier holds
//! (a test casts both and compares), at a fraction of the cost of a 3-D
//! ray through the whole bounding-volume tree.

use crate::layout::{Layout, Material, Solid};
use nalgebra::{Point2, Vector2};

/// Side of a grid cell, m.
const CELL_M: f64 = 0.5;
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
    origin: Point2<f64>,
    cols: usize,
    rows: usize,
    /// Items of each cell (row-major), as ranges into `index`.
    cells: Vec<(u32, u32)>,
    index: Vec<u32>,
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
        let (mut lo, mut hi) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        let bounds = |it: &Item| match *it {
            Item::Segment { a, b, .. } => (a.inf(&b), a.sup(&b)),
            Item::Circle { c, r } => (c - Vector2::new(r, r), c + Vector2::new(r, r)),
        };
        for it in &items {
            let (a, b) = bounds(it);
            lo = lo.inf(&a);
            hi = hi.sup(&b);
        }
        if items.is_empty() {
            lo = Point2::origin();
            hi = Point2::origin();
        }
        let origin = lo - Vector2::new(CELL_M, CELL_M);
        let cols = ((hi.x - origin.x) / CELL_M).ceil() as usize + 2;
        let rows = ((hi.y - origin.y) / CELL_M).ceil() as usize + 2;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); cols * rows];
        for (i, it) in items.iter().enumerate() {
            let (a, b) = bounds(it);
            let (c0, r0) = cell_of(&origin, &a);
            let (c1, r1) = cell_of(&origin, &b);
            for r in r0..=r1.min(rows - 1) {
                for c in c0..=c1.min(cols - 1) {
                    lists[r * cols + c].push(i as u32);
                }
            }
        }
        let mut cells = Vec::with_capacity(lists.len());
        let mut index = Vec::new();
        for l in lists {
            cells.push((index.len() as u32, (index.len() + l.len()) as u32));
            index.extend(l);
        }
        PlaneCaster {
            items,
            origin,
            cols,
            rows,
            cells,
            index,
        }
    }

    /// Distance along the unit ray `o + s·d` to the first static surface
    /// that returns the laser, up to `max_m`.
    pub fn cast(&self, o: &Point2<f64>, d: &Vector2<f64>, max_m: f64) -> Option<f64> {
        // Walk the cells the ray crosses (Amanatides–Woo), nearest first;
        // a hit counts once the walk has passed its distance.
        let (mut cx, mut cy) = cell_of(&self.origin, o);
        let step_x: isize = if d.x >= 0.0 { 1 } else { -1 };
        let step_y: isize = if d.y >= 0.0 { 1 } else { -1 };
        let next_edge = |c: usize, step: isize, o: f64, base: f64| {
            base + (c as f64 + if step > 0 { 1.0 } else { 0.0 }) * CELL_M - o
        };
        let mut t_max_x = if d.x.abs() > 1e-15 {
            next_edge(cx, step_x, o.x, self.origin.x) / d.x
        } else {
            f64::INFINITY
        };
        let mut t_max_y = if d.y.abs() > 1e-15 {
            next_edge(cy, step_y, o.y, self.origin.y) / d.y
        } else {
            f64::INFINITY
        };
        let t_dx = if d.x.abs() > 1e-15 {
            CELL_M / d.x.abs()
        } else {
            f64::INFINITY
        };
        let t_dy = if d.y.abs() > 1e-15 {
            CELL_M / d.y.abs()
        } else {
            f64::INFINITY
        };
        let mut best = max_m;
        let mut hit = false;
        loop {
            if cx >= self.cols || cy >= self.rows {
                break;
            }
            let (from, to) = self.cells[cy * self.cols + cx];
            for &i in &self.index[from as usize..to as usize] {
                let s = match self.items[i as usize] {
                    Item::Segment { a, b, glass } => {
                        ray_segment(o, d, &a, &b).filter(|_| {
                            !glass || {
                                let e = (b - a).normalize();
                                // |cos| of the angle between ray and normal.
                                (d.x * e.y - d.y * e.x).abs() >= GLASS_MIN_COS
                            }
                        })
                    }
                    Item::Circle { c, r } => ray_circle(o, d, &c, r),
                };
                if let Some(s) = s.filter(|&s| s < best) {
                    best = s;
                    hit = true;
                }
            }
            let t_exit = t_max_x.min(t_max_y);
            if (hit && best <= t_exit) || t_exit > max_m {
                break;
            }
            if t_max_x < t_max_y {
                t_max_x += t_dx;
                cx = cx.wrapping_add_signed(step_x);
            } else {
                t_max_y += t_dy;
                cy = cy.wrapping_add_signed(step_y);
            }
        }
        hit.then_some(best)
    }
}

fn cell_of(origin: &Point2<f64>, p: &Point2<f64>) -> (usize, usize) {
    (
        ((p.x - origin.x) / CELL_M).max(0.0) as usize,
        ((p.y - origin.y) / CELL_M).max(0.0) as usize,
    )
}
