//! A room's floor as a polygon: its corners counter-clockwise, wall `k`
//! from corner `k` to corner `k + 1`. What the planner asks of it: is a
//! point inside, how far is it from the nearest wall, where does a row
//! across the room run inside it, and does a body fit.

use nalgebra::{Point2, Vector2};
use std::borrow::Cow;

/// Shortest wall a room may have, m: a shorter one is a corner drawn
/// twice.
const SHORTEST_WALL_M: f64 = 0.05;

/// A simple polygon, its corners counter-clockwise, m. It borrows the
/// corners it is made of: asking a ceiling's outline whether a cell is
/// plastered, cell after cell, copies nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct Outline<'a> {
    corners: Cow<'a, [[f64; 2]]>,
}

impl<'a> Outline<'a> {
    /// The polygon of `corners` (counter-clockwise).
    pub fn new(corners: &'a [[f64; 2]]) -> Outline<'a> {
        Outline {
            corners: Cow::Borrowed(corners),
        }
    }

    /// The polygon of `corners`, kept.
    pub fn owned(corners: Vec<[f64; 2]>) -> Outline<'static> {
        Outline {
            corners: Cow::Owned(corners),
        }
    }

    /// Its corners.
    pub fn corners(&self) -> &[[f64; 2]] {
        &self.corners
    }

    /// Its edges, wall by wall.
    pub fn edges(&self) -> impl Iterator<Item = (Point2<f64>, Point2<f64>)> + '_ {
        let n = self.corners.len();
        let at = move |k: usize| Point2::from(self.corners[k % n]);
        (0..n).map(move |k| (at(k), at(k + 1)))
    }

    /// Twice its signed area: positive when counter-clockwise.
    pub fn signed_area_m2(&self) -> f64 {
        self.edges()
            .map(|(a, b)| a.x * b.y - b.x * a.y)
            .sum::<f64>()
            / 2.0
    }

    /// Why the corners make no room, if they do not: fewer than three, a
    /// number that is not finite, a wall shorter than 5 cm, two walls that
    /// cross, or corners running clockwise or enclosing nothing.
    pub fn fault(&self) -> Option<String> {
        let n = self.corners.len();
        if n < 3 {
            return Some(format!("{n} corners: a room has three or more"));
        }
        if self
            .corners
            .iter()
            .any(|c| !(c[0].is_finite() && c[1].is_finite()))
        {
            return Some("a corner is not a finite number".into());
        }
        let edges: Vec<_> = self.edges().collect();
        if let Some((k, (a, b))) = edges
            .iter()
            .enumerate()
            .find(|(_, (a, b))| (b - a).norm() < SHORTEST_WALL_M)
        {
            return Some(format!(
                "wall {k} is {:.3} m long: a wall is {SHORTEST_WALL_M} m or more (a corner drawn \
                 twice?)",
                (b - a).norm()
            ));
        }
        for i in 0..n {
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                let ((a, b), (c, d)) = (edges[i], edges[j]);
                if segments_touch(&a, &b, &c, &d) {
                    return Some(format!("walls {i} and {j} cross or touch"));
                }
            }
        }
        if self.signed_area_m2() <= 0.0 {
            return Some("the corners must run counter-clockwise and enclose an area".into());
        }
        None
    }

    /// True when `p` lies inside (the even-odd rule; a point on an edge
    /// may fall either way).
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        let mut inside = false;
        for (a, b) in self.edges() {
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Distance from `p` to the nearest edge, m.
    pub fn distance_m(&self, p: &Point2<f64>) -> f64 {
        self.edge_distances_m(p).fold(f64::INFINITY, f64::min)
    }

    /// Distance from `p` to each edge, wall by wall, m.
    pub fn edge_distances_m<'p>(&'p self, p: &'p Point2<f64>) -> impl Iterator<Item = f64> + 'p {
        self.edges().map(move |(a, b)| segment_distance(&a, &b, p))
    }

    /// How far `p` stands inside: its distance to the nearest edge, or
    /// minus it when outside.
    pub fn clearance_m(&self, p: &Point2<f64>) -> f64 {
        let d = self.distance_m(p);
        if self.contains(p) { d } else { -d }
    }

    /// The stretches of the row at `y` that lie inside, `inset_m` or more
    /// from every edge, as `[x0, x1]` in increasing x.
    pub fn row_spans(&self, y: f64, inset_m: f64) -> Vec<[f64; 2]> {
        let mut xs: Vec<f64> = self
            .edges()
            .filter(|(a, b)| (a.y > y) != (b.y > y))
            .map(|(a, b)| a.x + (y - a.y) / (b.y - a.y) * (b.x - a.x))
            .collect();
        xs.sort_by(f64::total_cmp);
        let mut spans: Vec<[f64; 2]> = xs.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        for (a, b) in self.edges() {
            if let Some(near) = capsule_row(&a, &b, inset_m, y) {
                cut_spans(&mut spans, near);
            }
        }
        spans
    }

    /// True when the convex polygon `body` lies inside with `clearance_m`
    /// or more to every edge.
    pub fn holds(&self, body: &[Point2<f64>], clearance_m: f64) -> bool {
        body.iter().all(|p| self.contains(p))
            && self
                .edges()
                .all(|(a, b)| polygon_segment_distance(body, &a, &b) >= clearance_m - 1e-9)
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub fn segment_distance(a: &Point2<f64>, b: &Point2<f64>, p: &Point2<f64>) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// True when the segments `a`–`b` and `c`–`d` cross or touch.
pub fn segments_meet(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>, d: &Point2<f64>) -> bool {
    let cross = |o: &Point2<f64>, p: &Point2<f64>, q: &Point2<f64>| {
        let (u, v): (Vector2<f64>, Vector2<f64>) = (p - o, q - o);
        u.x * v.y - u.y * v.x
    };
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

/// True when the segments `a`–`b` and `c`–`d` share a point: they cross,
/// or an end of one lies on the other (collinear segments apart do not).
fn segments_touch(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>, d: &Point2<f64>) -> bool {
    const EPS: f64 = 1e-12;
    let cross = |o: &Point2<f64>, p: &Point2<f64>, q: &Point2<f64>| {
        let (u, v): (Vector2<f64>, Vector2<f64>) = (p - o, q - o);
        u.x * v.y - u.y * v.x
    };
    // `q`, on the line through `p`–`r`, lies between them.
    let on = |p: &Point2<f64>, q: &Point2<f64>, r: &Point2<f64>| {
        q.x >= p.x.min(r.x) - EPS
            && q.x <= p.x.max(r.x) + EPS
            && q.y >= p.y.min(r.y) - EPS
            && q.y <= p.y.max(r.y) + EPS
    };
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    if ((d1 > EPS && d2 < -EPS) || (d1 < -EPS && d2 > EPS))
        && ((d3 > EPS && d4 < -EPS) || (d3 < -EPS && d4 > EPS))
    {
        return true;
    }
    (d1.abs() <= EPS && on(c, a, d))
        || (d2.abs() <= EPS && on(c, b, d))
        || (d3.abs() <= EPS && on(a, c, b))
        || (d4.abs() <= EPS && on(a, d, b))
}

/// Distance from the convex polygon `body` (its outline) to the segment
/// `a`–`b`: zero when they meet, the segment inside the body included.
fn polygon_segment_distance(body: &[Point2<f64>], a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let n = body.len();
    let edges = (0..n).map(|k| (body[k], body[(k + 1) % n]));
    let mut d = f64::INFINITY;
    for (p, q) in edges {
        if segments_meet(&p, &q, a, b) {
            return 0.0;
        }
        d = d
            .min(segment_distance(a, b, &p))
            .min(segment_distance(&p, &q, a))
            .min(segment_distance(&p, &q, b));
    }
    d
}

/// The stretch of the row at `y` lying less than `r` from the segment
/// `a`–`b` (the capsule about it, which is convex), if any.
fn capsule_row(a: &Point2<f64>, b: &Point2<f64>, r: f64, y: f64) -> Option<[f64; 2]> {
    // A row `r` from the segment (a ceiling's first row, at the gap) is
    // kept, whatever the rounding of its place.
    let r = r - 1e-9;
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut take = |x0: f64, x1: f64| {
        lo = lo.min(x0);
        hi = hi.max(x1);
    };
    // The discs at the ends.
    for c in [a, b] {
        let dy = y - c.y;
        let h2 = r * r - dy * dy;
        if h2 > 0.0 {
            let h = h2.sqrt();
            take(c.x - h, c.x + h);
        }
    }
    // The band along the segment: points whose foot falls on it.
    let ab = b - a;
    let l = ab.norm();
    if l > 0.0 {
        let t = ab / l;
        let n = Vector2::new(-t.y, t.x);
        // Along the row x ↦ (x, y): the foot's position s and the
        // distance d are affine in x; the band is 0 ≤ s ≤ l, |d| < r.
        let s0 = (Point2::new(0.0, y) - a).dot(&t);
        let d0 = (Point2::new(0.0, y) - a).dot(&n);
        let mut x0 = f64::NEG_INFINITY;
        let mut x1 = f64::INFINITY;
        let mut clip = |c0: f64, slope: f64, lo_v: f64, hi_v: f64, strict: bool| -> bool {
            // lo_v ≤ c0 + slope·x ≤ hi_v.
            if slope.abs() < 1e-12 {
                return if strict {
                    c0 > lo_v && c0 < hi_v
                } else {
                    c0 >= lo_v && c0 <= hi_v
                };
            }
            let (p, q) = ((lo_v - c0) / slope, (hi_v - c0) / slope);
            x0 = x0.max(p.min(q));
            x1 = x1.min(p.max(q));
            true
        };
        if clip(s0, t.x, 0.0, l, false) && clip(d0, n.x, -r, r, true) && x1 > x0 {
            take(x0, x1);
        }
    }
    (hi - lo > 1e-9).then_some([lo, hi])
}

/// Removes the open stretch `cut` from `spans`.
pub(crate) fn cut_spans(spans: &mut Vec<[f64; 2]>, cut: [f64; 2]) {
    let mut out = Vec::with_capacity(spans.len() + 1);
    for s in spans.drain(..) {
        if cut[1] <= s[0] || cut[0] >= s[1] {
            out.push(s);
            continue;
        }
        if cut[0] > s[0] {
            out.push([s[0], cut[0]]);
        }
        if cut[1] < s[1] {
            out.push([cut[1], s[1]]);
        }
    }
    out.retain(|s| s[1] - s[0] > 1e-9);
    *spans = out;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L: 4 × 3 less its north-east 2 × 1.5.
    fn l_room() -> Outline<'static> {
        Outline::new(&[
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 1.5],
            [2.0, 1.5],
            [2.0, 3.0],
            [0.0, 3.0],
        ])
    }

    #[test]
    fn an_l_room_holds_its_inside_and_not_its_notch() {
        let l = l_room();
        assert!((l.signed_area_m2() - 9.0).abs() < 1e-12);
        assert!(l.contains(&Point2::new(1.0, 2.5)));
        assert!(l.contains(&Point2::new(3.5, 1.0)));
        assert!(!l.contains(&Point2::new(3.0, 2.5)));
        assert!((l.clearance_m(&Point2::new(1.5, 2.5)) - 0.5).abs() < 1e-12);
        assert!((l.clearance_m(&Point2::new(3.0, 2.0)) + 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_row_runs_inside_clear_of_the_walls() {
        let l = l_room();
        // Below the notch the row crosses the whole room.
        let close = |s: &[[f64; 2]], want: &[[f64; 2]]| {
            s.len() == want.len()
                && s.iter()
                    .zip(want)
                    .all(|(a, b)| (a[0] - b[0]).abs() < 1e-8 && (a[1] - b[1]).abs() < 1e-8)
        };
        assert!(close(&l.row_spans(1.0, 0.1), &[[0.1, 3.9]]));
        // Above it, only the west part; the inner corner's wall is kept
        // clear of too.
        assert!(close(&l.row_spans(2.0, 0.1), &[[0.1, 1.9]]));
        // Just below the notch's wall, the inner corner's disc bites.
        let s = l.row_spans(1.45, 0.1);
        assert!(
            (s[0][1] - (2.0 - (0.01f64 - 0.0025).sqrt())).abs() < 1e-8,
            "{s:?}"
        );
        // A rectangle's rows at the inset are kept whole.
        let r = Outline::new(&[[0.0, 0.0], [5.0, 0.0], [5.0, 3.0], [0.0, 3.0]]);
        assert!(close(&r.row_spans(0.1, 0.1), &[[0.1, 4.9]]));
    }

    #[test]
    fn corners_that_make_no_room_say_why() {
        assert_eq!(l_room().fault(), None);
        let mut cw: Vec<[f64; 2]> = l_room().corners().to_vec();
        cw.reverse();
        let e = Outline::new(&cw).fault().unwrap_or_default();
        assert!(e.contains("counter-clockwise"), "{e}");
        // A bow tie: its walls 1 and 3 cross.
        let e = Outline::new(&[[0.0, 0.0], [4.0, 0.0], [0.0, 3.0], [4.0, 3.0]])
            .fault()
            .unwrap_or_default();
        assert!(e.contains("walls 1 and 3 cross"), "bow tie: {e}");
        // A chimney breast's two walls in one line, apart, are no fault;
        // a pinch, two walls meeting at a point, is.
        let breast = [
            [0.0, 0.0],
            [4.5, 0.0],
            [4.5, 4.0],
            [2.8, 4.0],
            [2.8, 3.5],
            [1.6, 3.5],
            [1.6, 4.0],
            [0.0, 4.0],
        ];
        assert_eq!(Outline::new(&breast).fault(), None);
        let pinch = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 2.0],
            [4.0, 2.0],
            [4.0, 4.0],
            [2.0, 2.0],
            [0.0, 2.0],
        ];
        let e = Outline::new(&pinch).fault().unwrap_or_default();
        assert!(e.contains("touch"), "pinch: {e}");
        let e = Outline::new(&[[0.0, 0.0], [1.0, 0.0]])
            .fault()
            .unwrap_or_default();
        assert!(e.contains("three"), "{e}");
    }

    #[test]
    fn a_body_fits_only_clear_of_every_wall() {
        let l = l_room();
        let body = |x: f64, y: f64| {
            [
                Point2::new(x - 0.3, y - 0.2),
                Point2::new(x + 0.3, y - 0.2),
                Point2::new(x + 0.3, y + 0.2),
                Point2::new(x - 0.3, y + 0.2),
            ]
        };
        assert!(l.holds(&body(1.0, 1.0), 0.1));
        // Its corner reaches into the notch past the inner corner.
        assert!(!l.holds(&body(2.2, 1.5), 0.0));
        // Inside, but the inner corner is within the clearance.
        assert!(l.holds(&body(1.65, 1.0), 0.0));
        assert!(!l.holds(&body(1.65, 1.25), 0.1));
    }
}
