//! The rectangular-room search of paper A: one group of four walls at 90°
//! intervals, found together instead of peak by peak. Orthogonal and
//! parallel walls support each other, and one search gives all four walls
//! and the room's orientation.
//!
//! 1. Coarse orientation: the transform's rows four at a time (paper: 30
//!    steps over 90°), the group with the largest sum of row maxima.
//! 2. Fine orientation: within ±1½ steps, the angle under which the
//!    measurements pile up most sharply along both axes.
//! 3. Each wall: along each of the four normals, the modes of the
//!    measurements' distances are the candidate lines; the wall is the one
//!    with the most evidence (surface seen on it, less surface seen through
//!    it), never a line seen only through a gap in a nearer one (the next
//!    room's wall through an open door). People, furniture and radiators
//!    stand in front of walls: a line through them is seen through where
//!    the wall behind shows.
//! 4. The orientation is refined on the pooled measurements of the four
//!    walls, the distances by a Tukey location on each.

use crate::NavError;
use crate::hough::{HoughConfig, HoughTransform};
use crate::line_fit::FitConfig;
use crate::points::{ScanPoint, ScanPoints};
use crate::wall::Wall;
use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};
use stucco_core::wrap_angle;

/// Settings of the room search.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoomConfig {
    /// The transform; its `angle_bins / 4` are the coarse orientation steps
    /// over 90° (paper: 30, i.e. 3°).
    pub hough: HoughConfig,
    /// Range noise (`noise_sigma_m`) and the shortest wall
    /// (`min_points`, `min_length_m`); a gap longer than `max_gap_m` ends
    /// the seen part of a wall.
    pub fit: FitConfig,
    /// A candidate line must hold at least this much wall seen face-on, m.
    pub min_wall_m: f64,
    /// An echo farther than this past a line counts against it being a
    /// wall: a wall hides what lies behind it, m.
    pub beyond_m: f64,
}

impl Default for RoomConfig {
    fn default() -> Self {
        RoomConfig {
            hough: HoughConfig::default(),
            fit: FitConfig::default(),
            min_wall_m: 0.3,
            beyond_m: 0.08,
        }
    }
}

/// A rectangular room seen from the sensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RectangularRoom {
    /// The walls at `orientation`, `+90°`, `+180°`, `+270°` in the sensor
    /// frame; `None` where no wall was seen in that direction.
    pub walls: [Option<Wall>; 4],
    /// Direction of the first wall's normal, rad, in `[0, π/2)`: the room's
    /// orientation relative to the sensor.
    pub orientation_rad: f64,
    /// Standard deviation of the orientation, rad. The walls are fitted
    /// together as a rectangle: they share this orientation, and their
    /// covariances hold its uncertainty.
    pub orientation_sigma_rad: f64,
    /// Sum of the four row maxima of the transform at the coarse orientation.
    pub score: f64,
}

impl RectangularRoom {
    /// True when all four walls were found.
    pub fn complete(&self) -> bool {
        self.walls.iter().all(Option::is_some)
    }

    /// Room size along the first wall's normal and along the second's, m,
    /// when both pairs of opposite walls were found.
    pub fn size_m(&self) -> Option<(f64, f64)> {
        match &self.walls {
            [Some(a), Some(b), Some(c), Some(d)] => Some((a.d_m + c.d_m, b.d_m + d.d_m)),
            _ => None,
        }
    }
}

/// Histogram bin of distances along a normal, m.
const BIN_M: f64 = 0.01;
/// Fine orientations tried about the coarse one: this many steps each way...
const ORIENTATION_STEPS: i32 = 18;
/// ... of this size, rad (0.25°).
const ORIENTATION_STEP_RAD: f64 = 0.25 * PI / 180.0;
/// Refinements of the orientation on the walls' pooled measurements.
const ORIENTATION_ROUNDS: usize = 3;
/// A line this far behind a nearer one may be seen through a gap in it, m.
const SEEN_THROUGH_M: f64 = 0.5;
/// Widest opening a wall is seen through, m.
const MAX_OPENING_M: f64 = 1.5;

/// Cut-off of the Tukey location, in range sigmas: narrow enough that a
/// radiator 10 cm in front of its wall never pulls the wall's distance.
const TUKEY_SIGMAS: f64 = 2.5;
/// Candidate lines weighed per direction, strongest first.
const MAX_CANDIDATES: usize = 12;

/// Finds the four walls of a rectangular room in a scan.
#[derive(Clone, Debug)]
pub struct RoomSearch {
    config: RoomConfig,
    hough: HoughTransform,
    hist: Vec<f64>,
    /// The orientation search's two histograms, all zero between uses.
    align_hist: Vec<f64>,
}

impl RoomSearch {
    /// A search with `config`.
    pub fn new(config: RoomConfig) -> Result<Self, NavError> {
        Ok(RoomSearch {
            hough: HoughTransform::new(config.hough.clone())?,
            config,
            hist: Vec::new(),
            align_hist: Vec::new(),
        })
    }

    /// The room in `points`, or `None` when the scan shows no walls at all.
    pub fn find(&mut self, points: &ScanPoints) -> Option<RectangularRoom> {
        let pts = points.points();
        let step = points.angle_increment_rad().max(1e-6);
        self.hough.compute(pts);
        let n = self.hough.angle_bins();
        let quarter = n / 4;
        let row_max: Vec<f64> = (0..n)
            .map(|k| {
                let row = &self.hough.row(k)[self.hough.voted(k)];
                f64::from(row.iter().copied().fold(0.0f32, f32::max))
            })
            .collect();
        let (g0, score) = (0..quarter)
            .map(|g| (g, (0..4).map(|q| row_max[g + q * quarter]).sum::<f64>()))
            .fold((0, -1.0), |b, x| if x.1 > b.1 { x } else { b });
        if score <= 0.0 {
            return None;
        }
        let centre = self.hough.gamma(g0);
        // Every other step first, then the steps either side of the best:
        // a wall's measurements stay within a few bins over two steps, so
        // the best of the coarse pass is next to the best of all.
        let at = |i: i32| centre + f64::from(i) * ORIENTATION_STEP_RAD;
        let (coarse, _) = (-ORIENTATION_STEPS..=ORIENTATION_STEPS)
            .step_by(2)
            .map(|i| (i, self.alignment(pts, at(i))))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        let (best, _) = [coarse - 1, coarse, coarse + 1]
            .into_iter()
            .filter(|i| i.abs() <= ORIENTATION_STEPS)
            .map(|i| (i, self.alignment(pts, at(i))))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        let mut theta = at(best);
        let sigma = self.config.fit.noise_sigma_m;
        let mut d: [Option<f64>; 4] =
            std::array::from_fn(|q| self.wall_distance(pts, theta + q as f64 * FRAC_PI_2, step));
        for _ in 0..ORIENTATION_ROUNDS {
            let groups = groups(pts, theta, &d, sigma);
            let Some(t) = pooled_normal(&groups, theta) else {
                break;
            };
            theta = t;
            for (q, dq) in d.iter_mut().enumerate() {
                if let Some(x) = dq {
                    let n_q = normal(theta + q as f64 * FRAC_PI_2);
                    *x = tukey_location(pts, &n_q, *x, sigma);
                }
            }
        }
        let groups = groups(pts, theta, &d, sigma);
        let (mut walls, sigma_theta) = self.walls(&groups, theta, &d);
        // Keep the orientation in [0, π/2) and the walls in step with it.
        let turns = (theta / FRAC_PI_2).floor();
        walls.rotate_left((-turns).rem_euclid(4.0) as usize);
        Some(RectangularRoom {
            walls,
            orientation_rad: theta - turns * FRAC_PI_2,
            orientation_sigma_rad: sigma_theta,
            score,
        })
    }

    /// How well the measurements line up on lines of orientation `theta`
    /// and `theta + 90°`: the sum of squares of their range-weighted
    /// histograms of distance along both normals. Walls pile up in a few
    /// bins when the orientation is right; people and furniture spread
    /// whatever it is.
    fn alignment(&mut self, pts: &[ScanPoint], theta: f64) -> f64 {
        let (s, c) = theta.sin_cos();
        let reach = pts.iter().fold(0.0f64, |m, p| m.max(p.range_m));
        let bins = (2.0 * reach / BIN_M) as usize + 2;
        // The histogram is left zeroed after each use: only the bins the
        // points fill are visited, and the sum of squares grows as they do
        // ((v + w)² − v² = w·(2v + w)).
        if self.align_hist.len() < 2 * bins {
            self.align_hist.clear();
            self.align_hist.resize(2 * bins, 0.0);
        }
        let bin = |rho: f64| (((rho + reach) / BIN_M) as usize).min(bins - 1);
        let mut squares = 0.0;
        for p in pts {
            let (x, y) = (p.p.x, p.p.y);
            let w = p.range_m;
            for b in [bin(c * x + s * y), bins + bin(-s * x + c * y)] {
                let v = &mut self.align_hist[b];
                squares += w * (2.0 * *v + w);
                *v += w;
            }
        }
        for p in pts {
            let (x, y) = (p.p.x, p.p.y);
            self.align_hist[bin(c * x + s * y)] = 0.0;
            self.align_hist[bins + bin(-s * x + c * y)] = 0.0;
        }
        squares
    }

    /// The wall along normal direction `gamma`: of the modes of the
    /// measurements' distances, the line with the most evidence that is not
    /// seen through a gap in a nearer one.
    fn wall_distance(&mut self, pts: &[ScanPoint], gamma: f64, step: f64) -> Option<f64> {
        let n = normal(gamma);
        let sigma = self.config.fit.noise_sigma_m;
        let gate = 3.0 * sigma;
        let reach = pts.iter().fold(0.0f64, |m, p| m.max(p.range_m));
        let bins = (reach / BIN_M) as usize + 2;
        self.hist.clear();
        self.hist.resize(bins, 0.0);
        for p in pts {
            let rho = n.dot(&p.p.coords);
            if rho > 0.0 {
                self.hist[((rho / BIN_M) as usize).min(bins - 1)] += p.range_m;
            }
        }
        // Smoothed over ±1.5σ: a wall's measurements in one mode.
        let half = ((1.5 * sigma) / BIN_M).ceil() as usize;
        let mut prefix = Vec::with_capacity(bins + 1);
        prefix.push(0.0);
        for &h in &self.hist {
            prefix.push(prefix[prefix.len() - 1] + h);
        }
        let smooth: Vec<f64> = (0..bins)
            .map(|b| prefix[(b + half + 1).min(bins)] - prefix[b.saturating_sub(half)])
            .collect();
        // Candidate lines: the strongest modes, down to half a wall's worth
        // (a wall behind a radiator shows little of itself).
        let floor = 0.5 * self.config.min_wall_m / step;
        let mut modes: Vec<usize> = (1..bins - 1)
            .filter(|&b| {
                smooth[b] >= floor && smooth[b] >= smooth[b - 1] && smooth[b] > smooth[b + 1]
            })
            .collect();
        modes.sort_by(|&a, &b| smooth[b].total_cmp(&smooth[a]).then(a.cmp(&b)));
        modes.truncate(MAX_CANDIDATES);
        let lines: Vec<Line> = modes
            .iter()
            .map(|&b| tukey_location(pts, &n, (b as f64 + 0.5) * BIN_M, sigma))
            .map(|d| line_evidence(pts, &n, d, gate, self.config.beyond_m, step))
            .filter(|l| l.on >= 0.5 * self.config.min_wall_m)
            .fold(Vec::<Line>::new(), |mut v, l| {
                if v.iter().all(|m| (m.d - l.d).abs() > gate) {
                    v.push(l);
                }
                v
            });
        let min = self.config.min_wall_m;
        // The wall is the line seen on more than through with the most
        // evidence (surface seen on it less surface seen through it),
        // unless it is seen only through a gap in a nearer wall-like line
        // (the next room's wall through the open door of this one's).
        let seen_through_a_door = |far: &Line| {
            lines.iter().any(|near| {
                near.evidence > 0.0
                    && far.d - near.d > SEEN_THROUGH_M
                    && wall_behind_scans(pts, &n, near.d, far.d, gate)
            })
        };
        let walls: Vec<&Line> = lines
            .iter()
            .filter(|l| l.evidence > 0.0 && !seen_through_a_door(l))
            .collect();
        let mut best = *walls
            .iter()
            .filter(|l| l.on >= min)
            .max_by(|a, b| a.evidence.total_cmp(&b.evidence))?;
        // What stands just in front of a wall (a radiator) can outweigh the
        // wall it hides; of two such lines the wall is the one behind.
        while let Some(behind) = walls
            .iter()
            .filter(|w| w.d > best.d + gate && w.d - best.d < SEEN_THROUGH_M)
            .min_by(|a, b| a.d.total_cmp(&b.d))
        {
            best = behind;
        }
        Some(best.d)
    }

    /// The four walls from their measurements, with covariances, and the
    /// standard deviation of the shared orientation.
    fn walls(
        &self,
        groups: &[Vec<Vector2<f64>>; 4],
        theta: f64,
        d: &[Option<f64>; 4],
    ) -> ([Option<Wall>; 4], f64) {
        let cfg = &self.config.fit;
        let (mut spread, mut sum_r2, mut count, mut used) = (0.0, 0.0, 0usize, 0usize);
        let stats: [Option<(f64, f64, usize)>; 4] = std::array::from_fn(|q| {
            let g = &groups[q];
            if g.len() < cfg.min_points.max(2) || d[q].is_none() {
                return None;
            }
            let n_q = normal(theta + q as f64 * FRAC_PI_2);
            let u_q = Vector2::new(-n_q.y, n_q.x);
            let c = g.iter().sum::<Vector2<f64>>() / g.len() as f64;
            Some((n_q.dot(&c), u_q.dot(&c), g.len()))
        });
        for (q, s) in stats.iter().enumerate() {
            let Some((dq, t_mean, _)) = s else { continue };
            let n_q = normal(theta + q as f64 * FRAC_PI_2);
            let u_q = Vector2::new(-n_q.y, n_q.x);
            for v in &groups[q] {
                spread += (u_q.dot(v) - t_mean).powi(2);
                sum_r2 += (n_q.dot(v) - dq).powi(2);
            }
            count += groups[q].len();
            used += 1;
        }
        let sigma2 = (sum_r2 / (count as f64 - used as f64 - 1.0).max(1.0)).max(1e-10);
        let var_theta = sigma2 / spread.max(1e-12);
        let walls = std::array::from_fn(|q| {
            let (dq, t_mean, n) = stats[q]?;
            let gamma = wrap_angle(theta + q as f64 * FRAC_PI_2);
            let n_q = normal(gamma);
            let u_q = Vector2::new(-n_q.y, n_q.x);
            // A room's wall is one surface however much of it people hide:
            // its ends are the outermost echoes on it, and what counts is
            // the length of it actually seen.
            let (t0, t1, seen) = seen_extent(&groups[q], &u_q, cfg.max_gap_m)?;
            if seen < cfg.min_length_m {
                return None;
            }
            let rms = (groups[q]
                .iter()
                .map(|v| (n_q.dot(v) - dq).powi(2))
                .sum::<f64>()
                / n as f64)
                .sqrt();
            Some(Wall {
                d_m: dq,
                gamma_rad: gamma,
                covariance: Matrix2::new(
                    sigma2 / n as f64 + t_mean * t_mean * var_theta,
                    t_mean * var_theta,
                    t_mean * var_theta,
                    var_theta,
                ),
                points: n,
                rms_residual_m: rms,
                ends: [
                    Point2::from(n_q * dq + u_q * t0),
                    Point2::from(n_q * dq + u_q * t1),
                ],
            })
        });
        (walls, var_theta.sqrt())
    }
}

fn normal(gamma: f64) -> Vector2<f64> {
    Vector2::new(gamma.cos(), gamma.sin())
}

/// Tukey location of the measurements' distances along `n`, from `d`.
fn tukey_location(pts: &[ScanPoint], n: &Vector2<f64>, mut d: f64, sigma: f64) -> f64 {
    let c = TUKEY_SIGMAS * sigma;
    // The distances within reach of the start, taken again only if the
    // location walks out of that reach: the same sums over far fewer
    // measurements.
    let reach = 4.0 * c;
    let near = |d: f64| -> Vec<f64> {
        pts.iter()
            .map(|p| n.dot(&p.p.coords))
            .filter(|rho| (rho - d).abs() < reach)
            .collect()
    };
    let mut from = d;
    let mut rhos = near(d);
    for _ in 0..10 {
        if (d - from).abs() > reach - c {
            from = d;
            rhos = near(d);
        }
        let (mut sw, mut sd) = (0.0, 0.0);
        for &rho in &rhos {
            let u = (rho - d) / c;
            if u.abs() < 1.0 {
                let w = (1.0 - u * u).powi(2);
                sw += w;
                sd += w * rho;
            }
        }
        if sw <= 0.0 {
            break;
        }
        let next = sd / sw;
        let done = (next - d).abs() < 1e-6;
        d = next;
        if done {
            break;
        }
    }
    d
}

/// A candidate wall along one direction, with what the scan says of it
/// (all per radian of scan step, in metres of surface).
#[derive(Clone, Copy, Debug)]
struct Line {
    d: f64,
    /// Surface seen on it.
    on: f64,
    /// `on` less the surface seen through it.
    evidence: f64,
}

/// The evidence of the line `n·p = d`: each echo within `gate` of it counts
/// its range as surface seen on it, each echo more than `beyond_m` past it
/// as surface seen through it.
fn line_evidence(
    pts: &[ScanPoint],
    n: &Vector2<f64>,
    d: f64,
    gate: f64,
    beyond_m: f64,
    step: f64,
) -> Line {
    let (mut on, mut passed) = (0.0, 0.0);
    for p in pts {
        let c = n.dot(&p.p.coords) / p.range_m;
        if c < 0.05 {
            continue;
        }
        let r_line = d / c;
        if (p.range_m - r_line).abs() <= gate {
            on += r_line;
        } else if p.range_m > r_line + beyond_m {
            passed += r_line;
        }
    }
    Line {
        d,
        on: on * step,
        evidence: (on - passed) * step,
    }
}

/// True when most of the echoes on the line at `far` passed the line at
/// `near` within an opening's width of where `near` itself was seen: `far`
/// is seen through a gap in `near` (an open door).
fn wall_behind_scans(pts: &[ScanPoint], n: &Vector2<f64>, near: f64, far: f64, gate: f64) -> bool {
    let u = Vector2::new(-n.y, n.x);
    let on_near: Vec<f64> = pts
        .iter()
        .filter(|p| (n.dot(&p.p.coords) - near).abs() <= gate)
        .map(|p| u.dot(&p.p.coords))
        .collect();
    let Some((t0, t1)) = extent(&on_near) else {
        return false;
    };
    let (mut on, mut inside) = (0usize, 0usize);
    for p in pts {
        if (n.dot(&p.p.coords) - far).abs() > gate {
            continue;
        }
        on += 1;
        // Where the beam to this echo crossed the nearer line.
        let t = u.dot(&p.p.coords) * near / far;
        inside += usize::from(t >= t0 - MAX_OPENING_M && t <= t1 + MAX_OPENING_M);
    }
    on > 0 && inside * 5 >= on * 4
}

fn extent(t: &[f64]) -> Option<(f64, f64)> {
    let lo = t.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo <= hi).then_some((lo, hi))
}

/// The ends of a wall's measurements along `u`, and the length of it seen:
/// the steps between neighbouring echoes, each counted up to a tenth of
/// `max_gap_m` (a step longer than that is something hiding the wall).
fn seen_extent(g: &[Vector2<f64>], u: &Vector2<f64>, max_gap_m: f64) -> Option<(f64, f64, f64)> {
    let mut t: Vec<f64> = g.iter().map(|v| u.dot(v)).collect();
    t.sort_by(f64::total_cmp);
    let seen = t
        .windows(2)
        .map(|w| (w[1] - w[0]).min(0.1 * max_gap_m))
        .sum();
    Some((*t.first()?, *t.last()?, seen))
}

/// The measurements of each wall (within 3σ of its line), turned back by
/// the wall's multiple of 90° so that all four share one direction.
fn groups(
    pts: &[ScanPoint],
    theta: f64,
    d: &[Option<f64>; 4],
    sigma: f64,
) -> [Vec<Vector2<f64>>; 4] {
    let cut = 3.0 * sigma;
    std::array::from_fn(|q| {
        let Some(dq) = d[q] else {
            return Vec::new();
        };
        let n_q = normal(theta + q as f64 * FRAC_PI_2);
        pts.iter()
            .filter(|p| (n_q.dot(&p.p.coords) - dq).abs() <= cut)
            .map(|p| p.p.coords)
            .collect()
    })
}

/// The common orientation of the four walls' measurements (each wall
/// centred on its own mean and turned back by its multiple of 90°), on the
/// side of `near`.
fn pooled_normal(groups: &[Vec<Vector2<f64>>; 4], near: f64) -> Option<f64> {
    let (mut sxx, mut syy, mut sxy, mut count) = (0.0, 0.0, 0.0, 0usize);
    for (q, g) in groups.iter().enumerate().filter(|(_, g)| !g.is_empty()) {
        let (s, c) = (-(q as f64) * FRAC_PI_2).sin_cos();
        let turn = |v: &Vector2<f64>| Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y);
        let m = g.iter().map(turn).sum::<Vector2<f64>>() / g.len() as f64;
        for v in g {
            let e = turn(v) - m;
            sxx += e.x * e.x;
            syy += e.y * e.y;
            sxy += e.x * e.y;
        }
        count += g.len();
    }
    if count < 3 {
        return None;
    }
    let mut theta = 0.5 * (2.0 * sxy).atan2(sxx - syy) + FRAC_PI_2;
    if wrap_angle(theta - near).abs() > FRAC_PI_2 {
        theta += PI;
    }
    Some(near + wrap_angle(theta - near))
}
