//! Robust least-squares refinement of a line hypothesis: the step that turns
//! a Hough peak (or a RANSAC hypothesis) into a wall with a covariance.
//!
//! The Hough cell only gates the measurements (the papers' "cluster gate");
//! the resolution comes from the fit. Iteratively reweighted total least
//! squares with Tukey's biweight rejects the clutter inside the gate — a
//! radiator 10 cm in front of its wall, a person's legs — and the seen part
//! is split at gaps, so collinear but separate walls are not merged. What
//! stands free before the surface behind it (a table's leg) is no wall's:
//! a line fitted along a face and the legs beside it tilts.

use crate::points::ScanPoint;
use crate::wall::Wall;
use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{LaserSpec, wrap_angle};

/// Settings of the robust line fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FitConfig {
    /// Scale of the perpendicular noise, m (the sensor's range σ).
    pub noise_sigma_m: f64,
    /// Tukey biweight cut-off in units of `noise_sigma_m`.
    pub tukey_c: f64,
    /// Largest number of reweighting iterations.
    pub max_iterations: usize,
    /// Fewest measurements a wall may rest on.
    pub min_points: usize,
    /// Shortest seen length a wall may have, m.
    pub min_length_m: f64,
    /// A gap longer than this along the line splits it into separate walls, m
    /// (longer than the widest door, so a door does not split its wall).
    pub max_gap_m: f64,
    /// Widest run of echoes taken for a thing standing free (a table's or
    /// a chair's leg, a person's), m: no wall rests on it.
    pub free_standing_max_m: f64,
    /// Fewer than `min_points` echoes within `free_standing_max_m` beyond
    /// a gap this long at a fit's end (a door jamb's edge seen past the
    /// door) are not part of it, m…
    pub end_gap_m: f64,
    /// …when they would lengthen it by more than this share of the rest.
    pub end_growth_max: f64,
}

impl FitConfig {
    /// The fit for scans of `laser`: its noise the laser's range σ.
    pub fn for_laser(laser: &LaserSpec) -> Self {
        FitConfig {
            noise_sigma_m: laser.range_sigma_m,
            ..FitConfig::default()
        }
    }
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig {
            noise_sigma_m: 0.02,
            tukey_c: 4.0,
            max_iterations: 12,
            min_points: 8,
            min_length_m: 0.4,
            max_gap_m: 1.5,
            free_standing_max_m: 0.15,
            end_gap_m: 0.3,
            end_growth_max: 0.5,
        }
    }
}

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
    /// The pool's points, in its order.
    pool_coords: Vec<Vector2<f64>>,
    pool_line: Option<Line>,
    reach_m: f64,
    /// The candidates' points, in their order, and the weighted sums of
    /// the last selection (Σw, Σw·p): the first half of the line's fit,
    /// taken while selecting.
    coords: Vec<Vector2<f64>>,
    sums: (f64, Vector2<f64>),
    /// The candidates before the last selection, and the inliers of the
    /// final fit (buffers).
    previous: Vec<usize>,
    previous_coords: Vec<Vector2<f64>>,
    inliers: Vec<usize>,
    keep: Vec<usize>,
    /// What [`LineFitter::fit`] fits on.
    untaken: Untaken,
}

/// The measurements of a scan no wall has taken yet, in scan order, with
/// their points, and the scan's reach: what a fit may take.
#[derive(Clone, Debug, Default)]
pub(crate) struct Untaken {
    idx: Vec<usize>,
    coords: Vec<Vector2<f64>>,
    /// The farthest measurement's range (taken or not), m.
    reach_m: f64,
}

impl Untaken {
    /// The measurements of `pts` not `taken`.
    pub fn fill(&mut self, pts: &[ScanPoint], taken: &[bool]) {
        self.idx.clear();
        self.coords.clear();
        for (i, (p, &t)) in pts.iter().zip(taken).enumerate() {
            if !t {
                self.idx.push(i);
                self.coords.push(p.p.coords);
            }
        }
        self.reach_m = reach_m(pts);
    }

    /// Drops those `taken` since.
    pub fn drop_taken(&mut self, taken: &[bool]) {
        let mut kept = 0;
        for k in 0..self.idx.len() {
            let i = self.idx[k];
            if !taken[i] {
                self.idx[kept] = i;
                self.coords[kept] = self.coords[k];
                kept += 1;
            }
        }
        self.idx.truncate(kept);
        self.coords.truncate(kept);
    }
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
        let mut untaken = std::mem::take(&mut self.untaken);
        untaken.fill(pts, taken);
        let fit = self.fit_within(pts, &untaken, taken, seeds);
        self.untaken = untaken;
        fit
    }

    /// [`LineFitter::fit`] with the measurements not `taken` listed
    /// ([`Untaken::fill`]), once for all the fits of a scan between two
    /// walls taken.
    pub fn fit_within(
        &mut self,
        pts: &[ScanPoint],
        untaken: &Untaken,
        taken: &[bool],
        seeds: impl IntoIterator<Item = usize>,
    ) -> Option<LineFit> {
        let cfg = &self.config;
        let (cut, min_points, max_iterations) = (
            cfg.tukey_c * cfg.noise_sigma_m,
            cfg.min_points,
            cfg.max_iterations,
        );
        self.candidates.clear();
        self.candidates
            .extend(seeds.into_iter().filter(|&i| !taken[i]));
        self.pool_line = None;
        self.reach_m = untaken.reach_m;
        if self.candidates.len() < min_points {
            return None;
        }
        self.weights.clear();
        self.weights.resize(self.candidates.len(), 1.0);
        let mut line = weighted_tls(pts, &self.candidates, &self.weights)?;
        // Tukey reweighting at the noise scale; after convergence keep the
        // heaviest gap-free run and refit on it.
        let mut chained = false;
        for _ in 0..max_iterations {
            self.select(untaken, line, cut, chained);
            if self.candidates.len() < min_points {
                return None;
            }
            let next = self.selected_tls()?;
            let moved = (next.d - line.d).abs() + (wrap_angle(next.gamma - line.gamma)).abs() * 5.0;
            line = next;
            if moved < 1e-4 {
                if chained {
                    break;
                }
                if !self.keep_longest_run(line) {
                    break;
                }
                chained = true;
            }
        }
        if !chained {
            // Unsettled (a few echoes at the cut-off going in and out): the
            // last line's gap-free run, refitted if cut.
            self.select(untaken, line, cut, false);
            if self.keep_longest_run(line) {
                line = weighted_tls(pts, &self.candidates, &self.weights)?;
            }
        }
        self.finish(pts, line)
    }

    /// Candidates within `cut` of `line`, with their Tukey weights, their
    /// points and the weighted sums of them. With `within_run`, only the
    /// current candidates are reconsidered.
    fn select(&mut self, untaken: &Untaken, line: Line, cut: f64, within_run: bool) {
        if !within_run {
            let margin = cut;
            let stale = self.pool_line.is_none_or(|r| {
                (line.d - r.d).abs() + wrap_angle(line.gamma - r.gamma).abs() * self.reach_m
                    > margin
            });
            if stale {
                // Written in place whether kept or not, and cut to those
                // kept: whether an echo is near the line is no branch to
                // predict.
                let n = untaken.idx.len();
                self.pool.resize(n, 0);
                self.pool_coords.resize(n, Vector2::zeros());
                let (pool, coords) = (&mut self.pool[..n], &mut self.pool_coords[..n]);
                let reach = cut + margin;
                let mut kept = 0;
                for (&i, &p) in untaken.idx.iter().zip(&untaken.coords) {
                    let near = (line.normal.dot(&p) - line.d).abs() < reach;
                    pool[kept] = i;
                    coords[kept] = p;
                    kept += usize::from(near);
                }
                self.pool.truncate(kept);
                self.pool_coords.truncate(kept);
                self.pool_line = Some(line);
            }
        }
        // One pass over the measurements that may stay: the residual, the
        // weight, the point and the sums the fit's centroid needs, in the
        // order the fit takes them.
        std::mem::swap(&mut self.previous, &mut self.candidates);
        std::mem::swap(&mut self.previous_coords, &mut self.coords);
        let (source, source_coords) = if within_run {
            (&self.previous, &self.previous_coords)
        } else {
            (&self.pool, &self.pool_coords)
        };
        // Room for every one, written in place whether kept or not and cut
        // to those kept (no branch to predict). An echo dropped adds a
        // weight of zero to the sums: +0 or −0, which leaves a sum that
        // starts at +0 as it is, bit for bit.
        let n = source.len();
        self.candidates.resize(n, 0);
        self.weights.resize(n, 0.0);
        self.coords.resize(n, Vector2::zeros());
        let (candidates, weights, coords) = (
            &mut self.candidates[..n],
            &mut self.weights[..n],
            &mut self.coords[..n],
        );
        let mut kept = 0;
        let mut sw = 0.0;
        let mut c = Vector2::zeros();
        for (&i, &p) in source.iter().zip(source_coords) {
            let r = line.normal.dot(&p) - line.d;
            let inside = r.abs() < cut;
            let u = r / cut;
            let t = 1.0 - u * u;
            let w = if inside { t * t } else { 0.0 };
            candidates[kept] = i;
            weights[kept] = w;
            coords[kept] = p;
            kept += usize::from(inside);
            sw += w;
            c += p * w;
        }
        self.candidates.truncate(kept);
        self.weights.truncate(kept);
        self.coords.truncate(kept);
        self.sums = (sw, c);
    }

    /// The total-least-squares line of the last selection: what
    /// [`weighted_tls`] gives for its candidates and weights.
    fn selected_tls(&self) -> Option<Line> {
        let (sw, c) = self.sums;
        tls_about(
            sw,
            c,
            self.coords
                .iter()
                .copied()
                .zip(self.weights.iter().copied()),
        )
    }

    /// Keeps the candidates of the heaviest run without gaps longer than
    /// `max_gap_m` along the line, less fewer than `min_points` echoes
    /// within `free_standing_max_m` beyond a gap of `end_gap_m` at either
    /// end, when they would lengthen it by more than `end_growth_max`.
    /// Returns whether anything was dropped.
    fn keep_longest_run(&mut self, line: Line) -> bool {
        let u = line.normal();
        let dir = Vector2::new(-u.y, u.x);
        self.along.clear();
        // The candidates' points, taken with them in the last selection.
        self.along
            .extend(self.coords.iter().enumerate().map(|(k, p)| (dir.dot(p), k)));
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
        self.keep.clear();
        self.keep.extend(self.along[lo..hi].iter().map(|&(_, k)| k));
        self.keep.sort_unstable();
        // The kept candidates in their order: each lands at or before its
        // old place.
        for (to, &k) in self.keep.iter().enumerate() {
            self.candidates[to] = self.candidates[k];
            self.weights[to] = self.weights[k];
            self.coords[to] = self.coords[k];
        }
        self.candidates.truncate(self.keep.len());
        self.weights.truncate(self.keep.len());
        self.coords.truncate(self.keep.len());
        true
    }

    /// The wall of the final fit: covariance from the residuals, extent from
    /// the outermost inliers.
    fn finish(&mut self, pts: &[ScanPoint], line: Line) -> Option<LineFit> {
        let inlier_cut = 3.0 * self.config.noise_sigma_m;
        let mut inliers = std::mem::take(&mut self.inliers);
        inliers.clear();
        inliers.extend(
            self.candidates
                .iter()
                .copied()
                .filter(|&i| line.residual(&pts[i].p).abs() <= inlier_cut),
        );
        let fit = self.wall_on(pts, line, &inliers);
        self.inliers = inliers;
        fit
    }

    /// The wall of `line` resting on `inliers`.
    fn wall_on(&self, pts: &[ScanPoint], line: Line, inliers: &[usize]) -> Option<LineFit> {
        let cfg = &self.config;
        let n_vec = line.normal();
        let dir = Vector2::new(-n_vec.y, n_vec.x);
        let n = inliers.len();
        if n < cfg.min_points.max(3) {
            return None;
        }
        let mut t_min = f64::INFINITY;
        let mut t_max = f64::NEG_INFINITY;
        let (mut sum_t, mut sum_r2) = (0.0, 0.0);
        for &i in inliers {
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

/// The reach of a scan for [`LineFitter::fit_within`]: its farthest
/// measurement's range, m.
pub(crate) fn reach_m(pts: &[ScanPoint]) -> f64 {
    pts.iter().fold(0.0, |m, p| m.max(p.range_m))
}

/// Weighted total least squares line through `pts[idx]`, with `d ≥ 0`.
pub(crate) fn weighted_tls(pts: &[ScanPoint], idx: &[usize], w: &[f64]) -> Option<Line> {
    let mut sw = 0.0;
    let mut c = Vector2::zeros();
    for (k, &i) in idx.iter().enumerate() {
        sw += w[k];
        c += pts[i].p.coords * w[k];
    }
    tls_about(
        sw,
        c,
        idx.iter().zip(w).map(|(&i, &w)| (pts[i].p.coords, w)),
    )
}

/// The weighted total least squares line through `points` (each with its
/// weight), given their weighted sums `sw = Σw` and `c = Σw·p` taken in
/// the same order.
fn tls_about(
    sw: f64,
    mut c: Vector2<f64>,
    points: impl Iterator<Item = (Vector2<f64>, f64)>,
) -> Option<Line> {
    if sw <= 0.0 {
        return None;
    }
    c /= sw;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (p, w) in points {
        let q = p - c;
        sxx += w * q.x * q.x;
        syy += w * q.y * q.y;
        sxy += w * q.x * q.y;
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

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// Echoes of a laser at the origin on the faces `x = depth` from `y0`
    /// to `y1`, every 2 cm, in beam order, with 5 mm of noise along x.
    fn faces(parts: &[(f64, f64, f64)], seed: u64) -> Vec<ScanPoint> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.005).unwrap();
        let mut pts = Vec::new();
        for &(depth, y0, y1) in parts {
            let mut y = y0;
            while y <= y1 {
                let p = Point2::new(depth + noise.sample(&mut rng), y);
                pts.push(ScanPoint {
                    p,
                    range_m: p.coords.norm(),
                    bearing_rad: p.y.atan2(p.x),
                    beam: pts.len(),
                });
                y += 0.02;
            }
        }
        pts
    }

    fn fit(pts: &[ScanPoint]) -> LineFit {
        let mut fitter = LineFitter::new(FitConfig {
            noise_sigma_m: 0.01,
            ..FitConfig::default()
        });
        fitter
            .fit(pts, &vec![false; pts.len()], 0..pts.len())
            .unwrap()
    }

    #[test]
    fn one_flat_face_is_not_split() {
        for seed in 0..10 {
            let pts = faces(&[(2.0, -1.0, 0.9)], seed);
            let f = fit(&pts);
            assert_eq!(f.support.len(), pts.len(), "seed {seed}");
            assert!(f.wall.length_m() > 1.85);
        }
    }

    #[test]
    fn a_few_echoes_beyond_a_gap_do_not_carry_a_wall_on() {
        // A door's jamb edge 0.5 m past the end of a wall seen 0.6 m long,
        // on its line.
        let mut pts = faces(&[(2.0, -0.4, 0.2), (2.0, 0.7, 0.76)], 3);
        let f = fit(&pts);
        assert!(f.wall.length_m() < 0.65, "{:?}", f.wall);
        // Past a wall seen 1.2 m long it adds less than half: kept.
        pts = faces(&[(2.0, -1.0, 0.2), (2.0, 0.7, 0.76)], 3);
        assert!(fit(&pts).wall.length_m() > 1.7);
        // Eight echoes or more beyond the gap are the wall's next piece.
        pts = faces(&[(2.0, -0.4, 0.2), (2.0, 0.7, 0.9)], 3);
        assert!(fit(&pts).wall.length_m() > 1.25);
    }

    #[test]
    fn legs_before_a_face_are_marked_and_the_face_is_not() {
        let mut pts = faces(&[(2.0, -1.0, 0.2)], 4);
        // Two echoes of a leg 15 cm before the face, in the middle.
        for k in [30, 31] {
            pts[k].p.x -= 0.15;
            pts[k].range_m = pts[k].p.coords.norm();
        }
        let mut taken = vec![false; pts.len()];
        let config = FitConfig {
            noise_sigma_m: 0.01,
            ..FitConfig::default()
        };
        mark_free_standing(&pts, &config, &mut taken);
        let marked: Vec<usize> = (0..pts.len()).filter(|&i| taken[i]).collect();
        assert_eq!(marked, [30, 31]);
    }
}
