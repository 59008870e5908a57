//! The robust line fit as it stood before the walls-speed work (commit
//! 990aea6), kept verbatim for the baseline extractor.

pub(crate) use crate::line_fit::FitConfig;
use crate::points::ScanPoint;
use crate::wall::Wall;
use nalgebra::{Matrix2, Point2, Vector2};
use stucco_core::wrap_angle;

/// A fitted wall and the measurements it took.
#[derive(Clone, Debug)]
pub(crate) struct LineFit {
    pub wall: Wall,
    /// Indices of every measurement the fit claimed (within the Tukey
    /// cut-off, in the kept run): what an extractor removes before the next.
    pub support: Vec<usize>,
}

/// Reusable buffers of the fitter.
#[derive(Clone, Debug, Default)]
pub(crate) struct LineFitter {
    pub config: FitConfig,
    candidates: Vec<usize>,
    weights: Vec<f64>,
    along: Vec<(f64, usize)>,
    /// The measurements not taken within `cut + margin` of `pool_line`:
    /// while the fit's line stays within `margin` of it over the scan's
    /// reach, every measurement within `cut` of the line is among them.
    pool: Vec<usize>,
    pool_line: Option<Line>,
    reach_m: f64,
}

/// A line in normal form, `n(γ)·p = d`, with its normal at hand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Line {
    pub d: f64,
    pub gamma: f64,
    normal: Vector2<f64>,
}

impl Line {
    /// The line `n(γ)·p = d`.
    pub fn new(d: f64, gamma: f64) -> Self {
        let (s, c) = gamma.sin_cos();
        Line {
            d,
            gamma,
            normal: Vector2::new(c, s),
        }
    }
    pub fn normal(&self) -> Vector2<f64> {
        self.normal
    }
    pub fn residual(&self, p: &Point2<f64>) -> f64 {
        self.normal.dot(&p.coords) - self.d
    }
}

impl LineFitter {
    pub fn new(config: FitConfig) -> Self {
        LineFitter {
            config,
            ..Default::default()
        }
    }

    /// Refines a line hypothesis on the points not yet `taken`: a first
    /// total-least-squares fit on the `seeds` (indices, in scan order: a
    /// Hough cell's voters, a RANSAC hypothesis' supporters), then Tukey
    /// reweighting around it.
    pub fn fit(
        &mut self,
        pts: &[ScanPoint],
        taken: &[bool],
        seeds: impl IntoIterator<Item = usize>,
    ) -> Option<LineFit> {
        let cfg = self.config.clone();
        let cut = cfg.tukey_c * cfg.noise_sigma_m;
        self.candidates.clear();
        self.candidates
            .extend(seeds.into_iter().filter(|&i| !taken[i]));
        self.pool_line = None;
        self.reach_m = pts.iter().fold(0.0, |m, p| m.max(p.range_m));
        if self.candidates.len() < cfg.min_points {
            return None;
        }
        self.weights.clear();
        self.weights.resize(self.candidates.len(), 1.0);
        let mut line = weighted_tls(pts, &self.candidates, &self.weights)?;
        // Tukey reweighting at the noise scale; after convergence keep the
        // heaviest gap-free run and refit on it.
        let mut chained = false;
        for _ in 0..cfg.max_iterations {
            self.select(pts, taken, line, cut, chained);
            if self.candidates.len() < cfg.min_points {
                return None;
            }
            let next = weighted_tls(pts, &self.candidates, &self.weights)?;
            let moved = (next.d - line.d).abs() + (wrap_angle(next.gamma - line.gamma)).abs() * 5.0;
            line = next;
            if moved < 1e-4 {
                if chained {
                    break;
                }
                if !self.keep_longest_run(pts, line) {
                    break;
                }
                chained = true;
            }
        }
        if !chained {
            // Unsettled (a few echoes at the cut-off going in and out): the
            // last line's gap-free run, refitted if cut.
            self.select(pts, taken, line, cut, false);
            if self.keep_longest_run(pts, line) {
                line = weighted_tls(pts, &self.candidates, &self.weights)?;
            }
        }
        self.finish(pts, line)
    }

    /// Candidates within `cut` of `line`, with their Tukey weights. With
    /// `within_run`, only the current candidates are reconsidered.
    fn select(
        &mut self,
        pts: &[ScanPoint],
        taken: &[bool],
        line: Line,
        cut: f64,
        within_run: bool,
    ) {
        if !within_run {
            let margin = cut;
            let stale = self.pool_line.is_none_or(|r| {
                (line.d - r.d).abs() + wrap_angle(line.gamma - r.gamma).abs() * self.reach_m
                    > margin
            });
            if stale {
                self.pool.clear();
                self.pool.extend(
                    (0..pts.len())
                        .filter(|&i| !taken[i] && line.residual(&pts[i].p).abs() < cut + margin),
                );
                self.pool_line = Some(line);
            }
            self.candidates.clear();
            self.candidates.extend(
                self.pool
                    .iter()
                    .copied()
                    .filter(|&i| line.residual(&pts[i].p).abs() < cut),
            );
        } else {
            self.candidates
                .retain(|&i| line.residual(&pts[i].p).abs() < cut);
        }
        self.weights.clear();
        self.weights.extend(self.candidates.iter().map(|&i| {
            let u = line.residual(&pts[i].p) / cut;
            let t = 1.0 - u * u;
            t * t
        }));
    }

    /// Keeps the candidates of the heaviest run without gaps longer than
    /// `max_gap_m` along the line, less fewer than `min_points` echoes
    /// within `free_standing_max_m` beyond a gap of `end_gap_m` at either
    /// end, when they would lengthen it by more than `end_growth_max`.
    /// Returns whether anything was dropped.
    fn keep_longest_run(&mut self, pts: &[ScanPoint], line: Line) -> bool {
        let u = line.normal();
        let dir = Vector2::new(-u.y, u.x);
        self.along.clear();
        self.along.extend(
            self.candidates
                .iter()
                .enumerate()
                .map(|(k, &i)| (dir.dot(&pts[i].p.coords), k)),
        );
        self.along.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (mut best, mut best_w) = ((0, 0), -1.0);
        let mut start = 0;
        let mut w = 0.0;
        for j in 0..self.along.len() {
            if j > start && self.along[j].0 - self.along[j - 1].0 > self.config.max_gap_m {
                start = j;
                w = 0.0;
            }
            w += self.weights[self.along[j].1];
            if w > best_w {
                best_w = w;
                best = (start, j + 1);
            }
        }
        // A few echoes close together beyond a gap at either end (a door
        // jamb's edge seen past the door) do not carry a wall on by more
        // than a share of its length.
        let (mut lo, mut hi) = best;
        let c = &self.config;
        let t = |j: usize| self.along[j].0;
        let few =
            |a: usize, b: usize| b - a < c.min_points && t(b - 1) - t(a) <= c.free_standing_max_m;
        if let Some(g) = (lo + 1..hi).find(|&j| t(j) - t(j - 1) > c.end_gap_m)
            && few(lo, g)
            && t(g) - t(lo) > c.end_growth_max * (t(hi - 1) - t(g))
        {
            lo = g;
        }
        if let Some(g) = (lo + 1..hi).rev().find(|&j| t(j) - t(j - 1) > c.end_gap_m)
            && few(g, hi)
            && t(hi - 1) - t(g - 1) > c.end_growth_max * (t(g - 1) - t(lo))
        {
            hi = g;
        }
        if hi - lo == self.along.len() {
            return false;
        }
        let keep: Vec<usize> = self.along[lo..hi].iter().map(|&(_, k)| k).collect();
        let mut keep_sorted = keep;
        keep_sorted.sort_unstable();
        self.candidates = keep_sorted.iter().map(|&k| self.candidates[k]).collect();
        self.weights = keep_sorted.iter().map(|&k| self.weights[k]).collect();
        true
    }

    /// The wall of the final fit: covariance from the residuals, extent from
    /// the outermost inliers.
    fn finish(&mut self, pts: &[ScanPoint], line: Line) -> Option<LineFit> {
        let cfg = &self.config;
        let inlier_cut = 3.0 * cfg.noise_sigma_m;
        let n_vec = line.normal();
        let dir = Vector2::new(-n_vec.y, n_vec.x);
        let inliers: Vec<usize> = self
            .candidates
            .iter()
            .copied()
            .filter(|&i| line.residual(&pts[i].p).abs() <= inlier_cut)
            .collect();
        let n = inliers.len();
        if n < cfg.min_points.max(3) {
            return None;
        }
        let mut t_min = f64::INFINITY;
        let mut t_max = f64::NEG_INFINITY;
        let (mut sum_t, mut sum_r2) = (0.0, 0.0);
        for &i in &inliers {
            let t = dir.dot(&pts[i].p.coords);
            t_min = t_min.min(t);
            t_max = t_max.max(t);
            sum_t += t;
            let r = line.residual(&pts[i].p);
            sum_r2 += r * r;
        }
        if t_max - t_min < cfg.min_length_m {
            return None;
        }
        let t_mean = sum_t / n as f64;
        let spread: f64 = inliers
            .iter()
            .map(|&i| (dir.dot(&pts[i].p.coords) - t_mean).powi(2))
            .sum();
        let sigma2 = (sum_r2 / (n as f64 - 2.0)).max(1e-10);
        // Offset at the centroid and rotation about it are independent;
        // d at the origin moves by t̄ per radian of rotation.
        let var_gamma = sigma2 / spread.max(1e-12);
        let var_offset = sigma2 / n as f64;
        let covariance = Matrix2::new(
            var_offset + t_mean * t_mean * var_gamma,
            t_mean * var_gamma,
            t_mean * var_gamma,
            var_gamma,
        );
        let foot = |t: f64| Point2::from(n_vec * line.d + dir * t);
        Some(LineFit {
            wall: Wall {
                d_m: line.d,
                gamma_rad: line.gamma,
                covariance,
                points: n,
                rms_residual_m: (sum_r2 / n as f64).sqrt(),
                ends: [foot(t_min), foot(t_max)],
            },
            support: self.candidates.clone(),
        })
    }
}

/// Marks in `taken` the echoes of things standing free before what is
/// behind them: runs of echoes of adjacent beams no wider than
/// `config.free_standing_max_m`, nearer by more than three noise scales
/// than the echoes on both sides (or with no echo on a side). No wall
/// rests on them: a line fitted along a bed's foot and the legs of the
/// desk beside it tilts.
pub(crate) fn mark_free_standing(pts: &[ScanPoint], config: &FitConfig, taken: &mut [bool]) {
    let jump = 3.0 * config.noise_sigma_m;
    let adjacent = |i: usize| pts[i + 1].beam == pts[i].beam + 1;
    let mut start = 0;
    while start < pts.len() {
        // The run of adjacent echoes with no jump in range.
        let mut end = start + 1;
        while end < pts.len()
            && adjacent(end - 1)
            && (pts[end].range_m - pts[end - 1].range_m).abs() <= jump
        {
            end += 1;
        }
        // The run's farthest echo.
        let near = pts[start..end]
            .iter()
            .fold(0.0, |m: f64, p| m.max(p.range_m));
        // Farther on a side: an echo there beyond the jump, or none at all
        // (a beam without echo sees nothing near).
        let before = start > 0 && (!adjacent(start - 1) || pts[start - 1].range_m > near + jump);
        let after = end < pts.len() && (!adjacent(end - 1) || pts[end].range_m > near + jump);
        let width = (pts[end - 1].p - pts[start].p).norm();
        if before && after && width <= config.free_standing_max_m {
            taken[start..end].iter_mut().for_each(|t| *t = true);
        }
        start = end;
    }
}

/// Weighted total least squares line through `pts[idx]`, with `d ≥ 0`.
pub(crate) fn weighted_tls(pts: &[ScanPoint], idx: &[usize], w: &[f64]) -> Option<Line> {
    let mut sw = 0.0;
    let mut c = Vector2::zeros();
    for (k, &i) in idx.iter().enumerate() {
        sw += w[k];
        c += pts[i].p.coords * w[k];
    }
    if sw <= 0.0 {
        return None;
    }
    c /= sw;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (k, &i) in idx.iter().enumerate() {
        let q = pts[i].p.coords - c;
        sxx += w[k] * q.x * q.x;
        syy += w[k] * q.y * q.y;
        sxy += w[k] * q.x * q.y;
    }
    // The normal is the direction of least scatter: angle of the principal
    // axis plus 90°.
    let axis = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let mut gamma = axis + std::f64::consts::FRAC_PI_2;
    let (s, co) = gamma.sin_cos();
    let mut d = co * c.x + s * c.y;
    if d < 0.0 {
        d = -d;
        gamma += std::f64::consts::PI;
    }
    Some(Line::new(d, wrap_angle(gamma)))
}
