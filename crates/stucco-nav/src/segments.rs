//! Runs of consecutive echoes on one line, and the Hough transform voted by
//! runs instead of by single echoes.
//!
//! The transform of paper A lets every echo vote for every line through
//! it; almost all of those votes land in cells no other echo reaches. A
//! wall's echoes lie next to each other in the scan, so a single pass can
//! group them first — grow a run while the next echo lies on the run's
//! line within the range noise — and let each run vote once per angle row
//! with its summed weight, spread along the distances its extent covers.
//! The cell of a wall then holds the same range-weighted sum the echo-wise
//! transform gives it, and a wall broken by people and table legs still
//! gathers all its pieces in one cell: that is what the Hough transform is
//! for. Echoes in no run (a leg, an edge, a lone echo between occluders)
//! vote for nothing; the robust fit still takes them when they lie on a
//! wall.

use crate::hough::{HoughConfig, Weighting};
use crate::points::ScanPoint;
use nalgebra::{Point2, Vector2};
use std::f64::consts::PI;

/// Running sums of a run's points, relative to its first point.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    origin: Vector2<f64>,
    m: f64,
    x: f64,
    y: f64,
    xx: f64,
    xy: f64,
    yy: f64,
}

impl Sums {
    fn start(p: &Point2<f64>) -> Self {
        Sums {
            origin: p.coords,
            m: 1.0,
            ..Sums::default()
        }
    }

    fn add(&mut self, p: &Point2<f64>) {
        let q = p.coords - self.origin;
        self.m += 1.0;
        self.x += q.x;
        self.y += q.y;
        self.xx += q.x * q.x;
        self.xy += q.x * q.y;
        self.yy += q.y * q.y;
    }

    /// Centroid (relative to the origin), unit normal of the line of least
    /// scatter, and the spread along it (Σ t², m²).
    fn line(&self) -> (Vector2<f64>, Vector2<f64>, f64) {
        let m = self.m;
        let c = Vector2::new(self.x / m, self.y / m);
        let a = self.xx / m - c.x * c.x;
        let b = self.xy / m - c.x * c.y;
        let d = self.yy / m - c.y * c.y;
        let mean = 0.5 * (a + d);
        let dev = (0.25 * (a - d).powi(2) + b * b).sqrt();
        let least = mean - dev;
        // Eigenvector of the least eigenvalue: of the two equivalent forms,
        // the longer is the better conditioned.
        let (u, v) = (Vector2::new(b, least - a), Vector2::new(least - d, b));
        let n = if u.norm_squared() >= v.norm_squared() {
            u
        } else {
            v
        };
        let len = n.norm();
        let normal = if len > 1e-12 {
            n / len
        } else if a >= d {
            // Isotropic or a single direction: the spread lies along x.
            Vector2::new(0.0, 1.0)
        } else {
            Vector2::new(1.0, 0.0)
        };
        (c, normal, (mean + dev) * m)
    }
}

/// A run of consecutive echoes lying on one line within the range noise.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// The run is `pts[first..end]`.
    pub first: usize,
    /// One past its last echo.
    pub end: usize,
    /// Its line `n(γ)·p = d`, `d ≥ 0`, m.
    pub d_m: f64,
    /// Normal of its line, rad.
    pub gamma_rad: f64,
    /// The unit normal, `(cos γ, sin γ)`.
    pub normal: Vector2<f64>,
    /// Standard deviation of `γ` from the range noise over its spread, rad.
    pub sigma_gamma_rad: f64,
    /// Its first and last echo projected on its line.
    pub ends: [Point2<f64>; 2],
    /// Its centroid.
    pub centroid: Point2<f64>,
    /// Sum of its echoes' ranges, m (the RWHT weight).
    pub range_sum_m: f64,
}

impl Segment {
    /// Number of echoes in the run.
    pub fn len(&self) -> usize {
        self.end - self.first
    }

    /// True when the run holds no echo (never, for a finished segment).
    pub fn is_empty(&self) -> bool {
        self.end == self.first
    }
}

/// Splits scans into [`Segment`]s.
#[derive(Clone, Debug)]
pub struct Segmenter {
    /// Range noise σ, m: an echo joins a run within 3σ of its line.
    pub noise_m: f64,
    /// Fewest echoes a segment holds.
    pub min_points: usize,
}

impl Segmenter {
    /// The runs of `pts` with at least `min_points` echoes, in scan order.
    pub fn split(&self, pts: &[ScanPoint], out: &mut Vec<Segment>) {
        out.clear();
        let Some(first) = pts.first() else {
            return;
        };
        let gate = 3.0 * self.noise_m;
        let mut start = 0;
        let mut sums = Sums::start(&first.p);
        // The run's line, refitted after every echo while the run is short
        // and every fourth echo after: a long run's line barely moves.
        let mut line = None;
        for j in 1..pts.len() {
            let (prev, p) = (&pts[j - 1], &pts[j]);
            let next_beam = p.beam == prev.beam + 1;
            let len = j - start;
            let joins = next_beam
                && if len < 3 {
                    self.step_ok(prev, p)
                } else {
                    let (c, n) = match line {
                        Some(l) if len >= 8 && len % 4 != 0 => l,
                        _ => {
                            let (c, n, _) = sums.line();
                            line = Some((c, n));
                            (c, n)
                        }
                    };
                    n.dot(&(p.p.coords - sums.origin - c)).abs() <= gate
                };
            if joins {
                sums.add(&p.p);
                continue;
            }
            line = None;
            self.close(pts, start, j, &sums, out);
            // A run too short to have a line of its own lends its last echo
            // to the next: two echoes of a wall after an edge start it.
            start = if len < 3 && next_beam && self.step_ok(prev, p) {
                j - 1
            } else {
                j
            };
            sums = Sums::start(&pts[start].p);
            if start < j {
                sums.add(&p.p);
            }
        }
        self.close(pts, start, pts.len(), &sums, out);
    }

    /// Two neighbouring echoes can lie on one surface: their gap is no
    /// larger than a surface at 80° incidence would leave, plus the noise.
    fn step_ok(&self, a: &ScanPoint, b: &ScanPoint) -> bool {
        let dphi = (b.bearing_rad - a.bearing_rad).abs();
        let reach = a.range_m.min(b.range_m) * dphi * 6.0 + 3.0 * self.noise_m;
        (b.p - a.p).norm() <= reach
    }

    fn close(&self, pts: &[ScanPoint], start: usize, end: usize, s: &Sums, out: &mut Vec<Segment>) {
        if end - start < self.min_points.max(3) {
            return;
        }
        let (c, mut n, along) = s.line();
        let centroid = Point2::from(s.origin + c);
        let mut d = n.dot(&centroid.coords);
        if d < 0.0 {
            d = -d;
            n = -n;
        }
        let dir = Vector2::new(-n.y, n.x);
        let foot = |p: &Point2<f64>| Point2::from(n * d + dir * dir.dot(&p.coords));
        out.push(Segment {
            first: start,
            end,
            d_m: d,
            gamma_rad: n.y.atan2(n.x),
            normal: n,
            sigma_gamma_rad: self.noise_m / along.max(1e-12).sqrt(),
            ends: [foot(&pts[start].p), foot(&pts[end - 1].p)],
            centroid,
            range_sum_m: pts[start..end].iter().map(|p| p.range_m).sum(),
        });
    }
}

/// One segment's vote in one row: the distances its lines cover there and
/// its weight, spread evenly over them.
#[derive(Clone, Copy, Debug)]
struct SegmentVote {
    segment: u32,
    lo: u32,
    hi: u32,
    rho: [f64; 2],
    weight: f64,
}

/// The transform `C(d, γ)` over the same grid as
/// [`crate::HoughTransform`], voted by segments.
///
/// A segment votes in the rows its normal can fall in (three σ of its
/// angle, at least the row holding it). In a row it takes the line of the
/// cell nearest its own angle; its echoes' distances along that normal then
/// run evenly from one end's to the other's, and a cell gets the share of
/// the segment's weight whose distances lie within the window `a` of it —
/// what the echo-wise transform would give, with the echoes spread evenly.
///
/// Only the cells a row's votes span are stored, row after row in one
/// buffer (a few hundred cells a scan, where the whole grid out to the
/// farthest echo holds a hundred thousand): every other cell is zero.
/// Votes are gathered first, then laid down row by row in the segments'
/// order, so that each cell sums the same weights in the same order as
/// over the whole grid.
#[derive(Clone, Debug)]
pub struct SegmentTransform {
    config: HoughConfig,
    distance_bins: usize,
    /// The voted cells, row after row: row `k`'s `voted[k]` from `start[k]`.
    cells: Vec<f32>,
    start: Vec<usize>,
    voted: Vec<(usize, usize)>,
    row_votes: Vec<Vec<SegmentVote>>,
    /// Unit normals at the lower edge of each angle bin, `γ_k − ½Δγ`.
    edges: Vec<Vector2<f64>>,
    max_reach_rad: f64,
}

impl SegmentTransform {
    /// An empty transform on `config`'s grid (validated by the caller),
    /// each segment voting for the angles within three σ of its normal's
    /// and within `max_reach_rad` of it.
    pub fn new(config: HoughConfig, max_reach_rad: f64) -> Self {
        let n = config.angle_bins;
        let step = config.angle_resolution_rad();
        SegmentTransform {
            edges: (0..n)
                .map(|k| {
                    let (s, c) = ((k as f64 - 0.5) * step).sin_cos();
                    Vector2::new(c, s)
                })
                .collect(),
            config,
            max_reach_rad,
            distance_bins: 0,
            cells: Vec::new(),
            start: vec![0; n],
            voted: vec![(0, 0); n],
            row_votes: vec![Vec::new(); n],
        }
    }

    /// Number of angle bins.
    pub fn angle_bins(&self) -> usize {
        self.config.angle_bins
    }

    /// Number of distance bins of the last transform.
    pub fn distance_bins(&self) -> usize {
        self.distance_bins
    }

    /// The cells of row `k` its votes span, [`SegmentTransform::voted`]:
    /// the rest of the row is zero.
    pub fn voted_row(&self, k: usize) -> &[f32] {
        let (lo, hi) = self.voted[k];
        &self.cells[self.start[k]..self.start[k] + (hi - lo)]
    }

    /// The distance bins of row `k` that hold votes.
    pub fn voted(&self, k: usize) -> std::ops::Range<usize> {
        let (lo, hi) = self.voted[k];
        lo..hi
    }

    /// The value of cell `(k, j)`, as stored.
    pub fn cell(&self, k: usize, j: usize) -> f32 {
        let (lo, hi) = self.voted[k];
        if (lo..hi).contains(&j) {
            self.cells[self.start[k] + j - lo]
        } else {
            0.0
        }
    }

    /// The value of cell `(k, j)`.
    pub fn value(&self, k: usize, j: usize) -> f64 {
        f64::from(self.cell(k, j))
    }

    /// Computes the transform of the segments `live` keeps.
    pub fn compute(&mut self, segs: &[Segment], live: impl Fn(usize) -> bool) {
        let cfg = &self.config;
        let n = cfg.angle_bins;
        let step = cfg.angle_resolution_rad();
        let res = cfg.distance_resolution_m;
        let a = cfg.half_window_m;
        let far = segs
            .iter()
            .flat_map(|s| s.ends.iter().map(|e| e.coords.norm()))
            .fold(0.0, f64::max);
        // The grid only grows (cells past the farthest segment stay zero).
        let bins = ((far + a) / res).ceil() as usize + 2;
        self.distance_bins = self.distance_bins.max(bins);
        let bins = self.distance_bins;
        self.voted.iter_mut().for_each(|v| *v = (usize::MAX, 0));
        self.row_votes.iter_mut().for_each(Vec::clear);
        for (s, seg) in segs.iter().enumerate() {
            if !live(s) {
                continue;
            }
            let reach = (3.0 * seg.sigma_gamma_rad).min(self.max_reach_rad);
            let own = floor_i64(seg.gamma_rad / step + 0.5);
            let first = floor_i64((seg.gamma_rad - reach) / step + 0.5);
            let last = floor_i64((seg.gamma_rad + reach) / step + 0.5);
            for kk in first..=last {
                let k = kk.rem_euclid(n as i64) as usize;
                // The line of the cell nearest the segment's own: its own
                // angle in its own row, else the row's nearer edge.
                let u = match kk.cmp(&own) {
                    std::cmp::Ordering::Equal => seg.normal,
                    std::cmp::Ordering::Less => self.edges[(k + 1) % n],
                    std::cmp::Ordering::Greater => self.edges[k],
                };
                let r0 = u.dot(&seg.ends[0].coords);
                let r1 = u.dot(&seg.ends[1].coords);
                let (rlo, rhi) = (r0.min(r1), r0.max(r1));
                if rhi <= 0.0 {
                    continue;
                }
                let weight = match cfg.weighting {
                    Weighting::Count => seg.len() as f64,
                    Weighting::Range => seg.range_sum_m,
                    Weighting::SurfaceSampling => {
                        seg.len() as f64 * u.dot(&seg.centroid.coords).max(0.0)
                    }
                };
                // The floor of a distance bin, as a cast: it truncates
                // toward zero and takes what is below zero (and NaN) to 0,
                // as the floor clamped at zero does.
                let lo = ((rlo - a) / res) as usize;
                let hi = (((rhi + a) / res) as usize).min(bins - 2);
                if hi < lo || weight <= 0.0 {
                    continue;
                }
                self.row_votes[k].push(SegmentVote {
                    segment: s as u32,
                    lo: lo as u32,
                    hi: hi as u32,
                    rho: [rlo, rhi],
                    weight,
                });
                let v = &mut self.voted[k];
                *v = (v.0.min(lo), v.1.max(hi + 1));
            }
        }
        self.lay_down();
    }

    /// The transform of the segments of the last [`SegmentTransform::compute`]
    /// that `live` still keeps: the same as computing it again with them
    /// (each kept vote is what it was, on the same grid), without working
    /// out their votes again.
    pub fn keep_only(&mut self, live: impl Fn(usize) -> bool) {
        for (votes, v) in self.row_votes.iter_mut().zip(&mut self.voted) {
            votes.retain(|vote| live(vote.segment as usize));
            *v = votes.iter().fold((usize::MAX, 0), |(lo, hi), vote| {
                (lo.min(vote.lo as usize), hi.max(vote.hi as usize + 1))
            });
        }
        self.lay_down();
    }

    /// Room for the cells each row's votes span, then the votes laid down
    /// row by row, each row's in the segments' order.
    fn lay_down(&mut self) {
        let (res, a) = (self.config.distance_resolution_m, self.config.half_window_m);
        let mut total = 0;
        for (v, start) in self.voted.iter_mut().zip(&mut self.start) {
            if v.0 >= v.1 {
                *v = (0, 0);
            }
            *start = total;
            total += v.1 - v.0;
        }
        self.cells.clear();
        self.cells.resize(total, 0.0);
        for (k, votes) in self.row_votes.iter().enumerate() {
            let (from, start) = (self.voted[k].0, self.start[k]);
            for vote in votes {
                let (lo, hi) = (vote.lo as usize, vote.hi as usize);
                let row = &mut self.cells[start + lo - from..=start + hi - from];
                for (j, cell) in (lo..).zip(row) {
                    *cell += share(vote, j, res, a) as f32;
                }
            }
        }
    }

    /// The segments voting for cell `(k, j)` and what each gives it.
    pub fn votes_in(&self, k: usize, j: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (res, a) = (self.config.distance_resolution_m, self.config.half_window_m);
        let jj = j as u32;
        self.row_votes[k]
            .iter()
            .filter(move |v| v.lo <= jj && jj <= v.hi)
            .map(move |v| (v.segment as usize, share(v, j, res, a)))
            .filter(|&(_, w)| w > 0.0)
    }

    /// The angle of row `k`, rad.
    pub fn gamma(&self, k: usize) -> f64 {
        let g = k as f64 * self.config.angle_resolution_rad();
        if g > PI { g - 2.0 * PI } else { g }
    }
}

/// `x.floor() as i64`, without a call to the C library's `floor`: the
/// truncation, one less for a negative fraction (the same for every `x`,
/// NaN and out of range ones included).
fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The part of `vote`'s weight cell `j` gets: the share of the segment's
/// distances within the window `a` of the cell `[jΔd, (j+1)Δd)`.
fn share(vote: &SegmentVote, j: usize, res: f64, a: f64) -> f64 {
    let (lo, hi) = (j as f64 * res - a, (j + 1) as f64 * res + a);
    let [rlo, rhi] = vote.rho;
    let span = rhi - rlo;
    if span < 1e-9 {
        return if (lo..hi).contains(&rlo) {
            vote.weight
        } else {
            0.0
        };
    }
    let overlap = (hi.min(rhi) - lo.max(rlo)).max(0.0);
    vote.weight * overlap / span
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    fn scan(points: &[(f64, f64)]) -> Vec<ScanPoint> {
        points
            .iter()
            .enumerate()
            .map(|(i, &(x, y))| ScanPoint {
                p: Point2::new(x, y),
                range_m: x.hypot(y),
                bearing_rad: y.atan2(x),
                beam: i,
            })
            .collect()
    }

    /// Beams at 0.5° from -30° to 60° on the wall x = 2 up to y = 1.5,
    /// then along the wall y = 1.5.
    fn corner() -> Vec<ScanPoint> {
        let mut pts = Vec::new();
        for i in 0..=180 {
            let phi = (-30.0 + 0.5 * i as f64).to_radians();
            let (c, s) = (phi.cos(), phi.sin());
            let r = (2.0 / c).min(if s > 0.0 { 1.5 / s } else { f64::INFINITY });
            pts.push((r * c, r * s));
        }
        scan(&pts)
    }

    #[test]
    fn a_corner_splits_into_its_two_walls() {
        let pts = corner();
        let mut segs = Vec::new();
        Segmenter {
            noise_m: 0.01,
            min_points: 4,
        }
        .split(&pts, &mut segs);
        assert_eq!(segs.len(), 2, "{segs:?}");
        // The echoes of the other wall within 3σ of the corner may join a
        // run: the lines are a segment's first guess, the fit refines them.
        assert!((segs[0].d_m - 2.0).abs() < 0.005, "{:?}", segs[0]);
        assert!(segs[0].gamma_rad.abs() < 0.01);
        assert!((segs[1].d_m - 1.5).abs() < 0.005, "{:?}", segs[1]);
        assert!((segs[1].gamma_rad - PI / 2.0).abs() < 0.01);
        // Every echo is in one of them, at most one of the corner's
        // neighbours taken by the wrong wall.
        assert_eq!(segs[0].first, 0);
        assert_eq!(segs[1].end, pts.len());
        assert!(segs[1].first.abs_diff(segs[0].end) <= 1);
    }

    #[test]
    fn a_gap_in_the_beams_ends_a_run() {
        let mut pts = corner();
        pts.truncate(60);
        for p in &mut pts[30..] {
            p.beam += 1;
        }
        let mut segs = Vec::new();
        Segmenter {
            noise_m: 0.01,
            min_points: 4,
        }
        .split(&pts, &mut segs);
        assert_eq!(
            segs.iter().map(|s| (s.first, s.end)).collect::<Vec<_>>(),
            [(0, 30), (30, 60)]
        );
    }

    #[test]
    fn the_wall_cell_holds_its_range_sum_and_pieces_add_up() {
        let pts = corner();
        let mut segs = Vec::new();
        Segmenter {
            noise_m: 0.01,
            min_points: 4,
        }
        .split(&pts, &mut segs);
        // The wall x = 2 in two pieces, as if a person stood in front.
        let whole = segs[0].clone();
        let mut halves = Vec::new();
        let mid = (whole.first + whole.end) / 2;
        let mut cut = pts[..whole.end].to_vec();
        for p in &mut cut[mid..] {
            p.beam += 5;
        }
        Segmenter {
            noise_m: 0.01,
            min_points: 4,
        }
        .split(&cut, &mut halves);
        assert_eq!(halves.len(), 2);
        let mut t = SegmentTransform::new(HoughConfig::default(), 0.2);
        t.compute(std::slice::from_ref(&whole), |_| true);
        // γ = 0 is row 0; d = 2.0 lies in bin 80; the window (4 cm) reaches
        // it from bins 78..=81.
        let at = |t: &SegmentTransform, j| t.value(0, j);
        for j in 78..=81 {
            assert!((at(&t, j) - whole.range_sum_m).abs() < 1e-3 * whole.range_sum_m);
        }
        assert_eq!(at(&t, 77), 0.0);
        let mut t2 = SegmentTransform::new(HoughConfig::default(), 0.2);
        t2.compute(&halves, |_| true);
        assert!((at(&t2, 80) - at(&t, 80)).abs() < 1e-3 * at(&t, 80));
        let voters: Vec<usize> = t2.votes_in(0, 80).map(|(s, _)| s).collect();
        assert_eq!(voters, [0, 1]);
        // Only the live segments vote.
        t2.compute(&halves, |s| s == 1);
        assert!((at(&t2, 80) - halves[1].range_sum_m).abs() < 1e-3 * at(&t, 80));
    }
}
