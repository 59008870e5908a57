//! A uniform grid over the floor plan that lists, for each cell, the items
//! whose footprint overlaps it, and walks a ray's cells nearest first:
//! what the laser's plane caster and the cameras' caster share.

use nalgebra::{Point2, Vector2};

/// Side of a grid cell, m.
const CELL_M: f64 = 0.5;

/// Items (by index) listed in the cells their footprints overlap.
#[derive(Clone, Debug)]
pub(crate) struct CellGrid {
    origin: Point2<f64>,
    cols: usize,
    rows: usize,
    /// Items of each cell (row-major), as ranges into `index`.
    cells: Vec<(u32, u32)>,
    index: Vec<u32>,
}

impl CellGrid {
    /// A grid over the footprints `bounds` (lower and upper corners), item
    /// `i` listed in every cell its footprint overlaps.
    pub fn new(bounds: &[(Point2<f64>, Point2<f64>)]) -> Self {
        let (mut lo, mut hi) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for (a, b) in bounds {
            lo = lo.inf(a);
            hi = hi.sup(b);
        }
        if bounds.is_empty() {
            lo = Point2::origin();
            hi = Point2::origin();
        }
        let origin = lo - Vector2::new(CELL_M, CELL_M);
        let cols = ((hi.x - origin.x) / CELL_M).ceil() as usize + 2;
        let rows = ((hi.y - origin.y) / CELL_M).ceil() as usize + 2;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); cols * rows];
        for (i, (a, b)) in bounds.iter().enumerate() {
            let (c0, r0) = cell_of(&origin, a);
            let (c1, r1) = cell_of(&origin, b);
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
        CellGrid {
            origin,
            cols,
            rows,
            cells,
            index,
        }
    }

    /// The nearest hit along the ray `o + s·(d, ·)` up to `max_m`: `hit`
    /// tells where the ray meets item `i`, if it does, in the ray's own
    /// parameter `s`; `d` is the horizontal part of the ray's direction
    /// (a 3-D ray's, not made unit: `s` stays the 3-D distance). The cells
    /// the ray crosses are walked nearest first (Amanatides–Woo); a hit
    /// counts once the walk has passed its distance, and an item listed in
    /// several cells may be asked more than once.
    pub fn nearest(
        &self,
        o: &Point2<f64>,
        d: &Vector2<f64>,
        max_m: f64,
        mut hit: impl FnMut(usize) -> Option<f64>,
    ) -> Option<f64> {
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
        let mut found = false;
        loop {
            if cx >= self.cols || cy >= self.rows {
                break;
            }
            let (from, to) = self.cells[cy * self.cols + cx];
            for &i in &self.index[from as usize..to as usize] {
                if let Some(s) = hit(i as usize).filter(|&s| s < best) {
                    best = s;
                    found = true;
                }
            }
            let t_exit = t_max_x.min(t_max_y);
            if (found && best <= t_exit) || t_exit > max_m {
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
        found.then_some(best)
    }
}

impl CellGrid {
    /// Items listed in the cells the box `lo`–`hi` overlaps (an item may
    /// come more than once: it is listed in every cell it covers).
    pub fn overlapping(
        &self,
        lo: &Point2<f64>,
        hi: &Point2<f64>,
    ) -> impl Iterator<Item = usize> + '_ {
        let (c0, r0) = cell_of(&self.origin, lo);
        let (c1, r1) = cell_of(&self.origin, hi);
        let (c1, r1) = (c1.min(self.cols - 1), r1.min(self.rows - 1));
        (r0..=r1).flat_map(move |r| {
            (c0..=c1).flat_map(move |c| {
                let (from, to) = self.cells[r * self.cols + c];
                self.index[from as usize..to as usize]
                    .iter()
                    .map(|&i| i as usize)
            })
        })
    }
}

fn cell_of(origin: &Point2<f64>, p: &Point2<f64>) -> (usize, usize) {
    (
        ((p.x - origin.x) / CELL_M).max(0.0) as usize,
        ((p.y - origin.y) / CELL_M).max(0.0) as usize,
    )
}
