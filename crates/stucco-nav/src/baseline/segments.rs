//! Runs of echoes and the transform voted by them as they stood before the
//! walls-speed work (commit 990aea6), kept verbatim for the baseline
//! extractor.

use crate::hough::{HoughConfig, Weighting};
use crate::points::ScanPoint;
use nalgebra::{Point2, Vector2};

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
pub(crate) struct Segment {
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
}

/// Splits scans into [`Segment`]s.
#[derive(Clone, Debug)]
pub(crate) struct Segmenter {
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
#[derive(Clone, Debug)]
pub(crate) struct SegmentTransform {
    config: HoughConfig,
    distance_bins: usize,
    acc: Vec<f32>,
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
            acc: Vec::new(),
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

    /// One row of the accumulator.
    pub fn row(&self, k: usize) -> &[f32] {
        &self.acc[k * self.distance_bins..(k + 1) * self.distance_bins]
    }

    /// The distance bins of row `k` that hold votes.
    pub fn voted(&self, k: usize) -> std::ops::Range<usize> {
        let (lo, hi) = self.voted[k];
        lo..hi
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
        // The grid only grows: cells past the farthest segment stay zero,
        // and clearing what the last scan voted for is cheaper than the
        // whole accumulator.
        let bins = ((far + a) / res).ceil() as usize + 2;
        if bins > self.distance_bins {
            self.distance_bins = bins;
            self.acc.clear();
            self.acc.resize(bins * n, 0.0);
        } else {
            let m = self.distance_bins;
            for (k, &(lo, hi)) in self.voted.iter().enumerate() {
                self.acc[k * m + lo..k * m + hi].fill(0.0);
            }
        }
        let bins = self.distance_bins;
        self.voted.iter_mut().for_each(|v| *v = (usize::MAX, 0));
        self.row_votes.iter_mut().for_each(Vec::clear);
        for (s, seg) in segs.iter().enumerate() {
            if !live(s) {
                continue;
            }
            let reach = (3.0 * seg.sigma_gamma_rad).min(self.max_reach_rad);
            let own = (seg.gamma_rad / step + 0.5).floor() as i64;
            let first = ((seg.gamma_rad - reach) / step + 0.5).floor() as i64;
            let last = ((seg.gamma_rad + reach) / step + 0.5).floor() as i64;
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
                let lo = ((rlo - a) / res).floor().max(0.0) as usize;
                let hi = (((rhi + a) / res).floor() as usize).min(bins - 2);
                if hi < lo || weight <= 0.0 {
                    continue;
                }
                let vote = SegmentVote {
                    segment: s as u32,
                    lo: lo as u32,
                    hi: hi as u32,
                    rho: [rlo, rhi],
                    weight,
                };
                let row = &mut self.acc[k * bins..(k + 1) * bins];
                for (j, cell) in row.iter_mut().enumerate().take(hi + 1).skip(lo) {
                    *cell += share(&vote, j, res, a) as f32;
                }
                self.row_votes[k].push(vote);
                let v = &mut self.voted[k];
                *v = (v.0.min(lo), v.1.max(hi + 1));
            }
        }
        for v in &mut self.voted {
            if v.0 >= v.1 {
                *v = (0, 0);
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
