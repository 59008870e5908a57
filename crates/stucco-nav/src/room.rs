//! The rectangular-room search of paper A: one group of four peaks at 90°
//! intervals, scored together, instead of peaks one by one. Orthogonal and
//! parallel walls support each other, and one search gives all four walls
//! and the room's orientation.

use crate::NavError;
use crate::hough::{HoughConfig, HoughTransform};
use crate::line_fit::{FitConfig, LineFit, LineFitter};
use crate::points::{ScanPoint, ScanPoints};
use crate::wall::Wall;
use nalgebra::{Matrix2, Point2, Rotation2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};
use stucco_core::wrap_angle;

/// Settings of the room search.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoomConfig {
    /// The transform; its `angle_bins / 4` are the orientation steps over
    /// 90° (paper: 30, i.e. 3°).
    pub hough: HoughConfig,
    /// The robust refinement of each wall.
    pub fit: FitConfig,
}

/// A rectangular room seen from the sensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RectangularRoom {
    /// The walls at `orientation`, `+90°`, `+180°`, `+270°` in the sensor
    /// frame; `None` where the peak could not be confirmed by a fit.
    pub walls: [Option<Wall>; 4],
    /// Direction of the first wall's normal, rad, in `[0, π/2)`: the room's
    /// orientation relative to the sensor.
    pub orientation_rad: f64,
    /// Standard deviation of the orientation, rad. The walls are fitted
    /// together as a rectangle: they share this orientation, and their
    /// covariances hold its uncertainty.
    pub orientation_sigma_rad: f64,
    /// Sum of the four peaks of the transform.
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

/// Finds the four walls of a rectangular room in a scan.
#[derive(Clone, Debug)]
pub struct RoomSearch {
    hough: HoughTransform,
    fitter: LineFitter,
    taken: Vec<bool>,
    row_max: Vec<(f32, usize)>,
}

impl RoomSearch {
    /// A search with `config`.
    pub fn new(config: RoomConfig) -> Result<Self, NavError> {
        Ok(RoomSearch {
            hough: HoughTransform::new(config.hough)?,
            fitter: LineFitter::new(config.fit),
            taken: Vec::new(),
            row_max: Vec::new(),
        })
    }

    /// The room in `points`, or `None` when the scan shows no walls at all.
    pub fn find(&mut self, points: &ScanPoints) -> Option<RectangularRoom> {
        let pts = points.points();
        self.hough.compute(pts);
        let n = self.hough.angle_bins();
        let quarter = n / 4;
        self.row_max.clear();
        for k in 0..n {
            let best = self
                .hough
                .row(k)
                .iter()
                .enumerate()
                .fold(
                    (0.0f32, 0usize),
                    |b, (j, &v)| if v > b.0 { (v, j) } else { b },
                );
            self.row_max.push(best);
        }
        let (g0, score) = (0..quarter)
            .map(|g| {
                (
                    g,
                    (0..4)
                        .map(|q| f64::from(self.row_max[g + q * quarter].0))
                        .sum::<f64>(),
                )
            })
            .fold((0, -1.0), |b, (g, s)| if s > b.1 { (g, s) } else { b });
        if score <= 0.0 {
            return None;
        }
        self.taken.clear();
        self.taken.extend(pts.iter().map(|p| !self.hough.uses(p)));
        let cfg = self.hough.config().clone();
        let mut fits: [Option<LineFit>; 4] = Default::default();
        for (q, slot) in fits.iter_mut().enumerate() {
            let k = g0 + q * quarter;
            let (v, j) = self.row_max[k];
            if v <= 0.0 {
                continue;
            }
            let hough = &self.hough;
            *slot = self
                .fitter
                .fit(pts, &self.taken, |p| hough.votes_for(p, k, j));
        }
        let centre = self.hough.gamma(g0);
        let (walls, orientation, sigma) =
            match joint_fit(pts, &fits, centre, self.fitter.config.noise_sigma_m) {
                Some(joint) => joint,
                None => (
                    fits.map(|f| f.map(|f| f.wall)),
                    centre,
                    cfg.angle_resolution_rad() / 12f64.sqrt(),
                ),
            };
        let mut walls = walls;
        // Keep the orientation in [0, π/2) and the walls in step with it.
        let turns = (orientation / FRAC_PI_2).floor();
        let shift = (-turns).rem_euclid(4.0) as usize;
        walls.rotate_left(shift);
        Some(RectangularRoom {
            walls,
            orientation_rad: orientation - turns * FRAC_PI_2,
            orientation_sigma_rad: sigma,
            score,
        })
    }
}

/// The walls refitted together as a rectangle: one orientation shared by
/// all four (each wall's measurements turned back by its multiple of 90°
/// and pooled), one distance each. Returns the walls, the orientation of
/// the first and its standard deviation.
fn joint_fit(
    pts: &[ScanPoint],
    fits: &[Option<LineFit>; 4],
    centre: f64,
    noise_sigma_m: f64,
) -> Option<([Option<Wall>; 4], f64, f64)> {
    let cut = 3.0 * noise_sigma_m;
    // The rectangle's orientation from the walls' own fits, robustly: the
    // weighted mean of the angles that agree with their weighted median.
    let angles: Vec<(f64, f64)> = fits
        .iter()
        .enumerate()
        .filter_map(|(q, f)| {
            let w = &f.as_ref()?.wall;
            Some((
                centre + wrap_angle(w.gamma_rad - q as f64 * FRAC_PI_2 - centre),
                1.0 / w.covariance[(1, 1)].max(1e-12),
            ))
        })
        .collect();
    let mut sorted = angles.clone();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half: f64 = sorted.iter().map(|a| a.1).sum::<f64>() / 2.0;
    let mut acc = 0.0;
    let median = sorted
        .iter()
        .find(|a| {
            acc += a.1;
            acc >= half
        })?
        .0;
    let agree = |a: &&(f64, f64)| (a.0 - median).abs() <= 3.0 / a.1.sqrt() + 0.2f64.to_radians();
    let (sw, sa) = angles
        .iter()
        .filter(agree)
        .fold((0.0, 0.0), |s, a| (s.0 + a.1, s.1 + a.1 * a.0));
    let theta0 = sa / sw;
    // With the orientation fixed, each wall is the strongest mode of the
    // measurements' distances along its normal near its own fit: a radiator
    // 10 cm in front of its wall is a separate mode, never a compromise.
    let mut groups: [Vec<Vector2<f64>>; 4] = Default::default();
    for (q, fit) in fits.iter().enumerate() {
        if fit.is_none() {
            continue;
        }
        let gamma = theta0 + q as f64 * FRAC_PI_2;
        let n_q = Vector2::new(gamma.cos(), gamma.sin());
        let max_rho = pts.iter().fold(0.0f64, |m, p| m.max(n_q.dot(&p.p.coords)));
        let window = 0.5 * max_rho + 0.05;
        let d_fit = window;
        let near: Vec<(f64, f64, Vector2<f64>)> = pts
            .iter()
            .map(|p| (n_q.dot(&p.p.coords), p.range_m, p.p.coords))
            .filter(|(rho, _, _)| *rho > 0.0)
            .collect();
        // Range-weighted histogram at 1 cm, smoothed over ±1.5σ.
        let bins = (2.0 * window / 0.01) as usize + 1;
        let mut hist = vec![0.0; bins];
        for (rho, r, _) in &near {
            hist[(((rho - d_fit + window) / 0.01) as usize).min(bins - 1)] += r;
        }
        let reach = ((1.5 * noise_sigma_m) / 0.01).ceil() as usize;
        let peak = (0..bins)
            .map(|b| {
                (
                    b,
                    hist[b.saturating_sub(reach)..(b + reach + 1).min(bins)]
                        .iter()
                        .sum::<f64>(),
                )
            })
            .fold((0, -1.0), |m, x| if x.1 > m.1 { x } else { m })
            .0;
        let mut d = d_fit - window + (peak as f64 + 0.5) * 0.01;
        // Tukey location from the mode.
        let c = 4.0 * noise_sigma_m;
        for _ in 0..10 {
            let (mut sw, mut sd) = (0.0, 0.0);
            for (rho, _, _) in &near {
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
            d = sd / sw;
        }
        let turn = Rotation2::new(-(q as f64) * FRAC_PI_2);
        groups[q] = near
            .iter()
            .filter(|(rho, _, _)| (rho - d).abs() <= cut)
            .map(|(_, _, v)| turn * v)
            .collect();
    }
    let centroids = groups
        .clone()
        .map(|g| (!g.is_empty()).then(|| g.iter().sum::<Vector2<f64>>() / g.len() as f64));
    let (mut sxx, mut syy, mut sxy, mut count) = (0.0, 0.0, 0.0, 0usize);
    for (g, c) in groups.iter().zip(&centroids) {
        let Some(c) = c else { continue };
        for v in g {
            let e = v - c;
            sxx += e.x * e.x;
            syy += e.y * e.y;
            sxy += e.x * e.y;
        }
        count += g.len();
    }
    if count < 3 {
        return None;
    }
    // Normal of the pooled, centred scatter, taken on the side of the winning bin.
    let mut theta = 0.5 * (2.0 * sxy).atan2(sxx - syy) + FRAC_PI_2;
    if wrap_angle(theta - theta0).abs() > FRAC_PI_2 {
        theta += PI;
    }
    let theta = wrap_angle(theta);
    let normal = Vector2::new(theta.cos(), theta.sin());
    let along = Vector2::new(-normal.y, normal.x);
    let (mut spread, mut sum_r2) = (0.0, 0.0);
    let mut stats = [(0.0, 0.0, 0usize); 4]; // (d, t̄, n) per wall
    for (q, (g, c)) in groups.iter().zip(&centroids).enumerate() {
        let Some(c) = c else { continue };
        let d = normal.dot(c);
        let t_mean = along.dot(c);
        for v in g {
            spread += (along.dot(v) - t_mean).powi(2);
            sum_r2 += (normal.dot(v) - d).powi(2);
        }
        stats[q] = (d, t_mean, g.len());
    }
    let groups_used = centroids.iter().flatten().count();
    let sigma2 = (sum_r2 / (count as f64 - groups_used as f64 - 1.0).max(1.0)).max(1e-10);
    let var_theta = sigma2 / spread.max(1e-12);
    let walls = std::array::from_fn(|q| {
        let fit = fits[q].as_ref()?;
        let (d, t_mean, n) = stats[q];
        if n < 2 || d <= 0.0 {
            return Some(fit.wall.clone());
        }
        let gamma = wrap_angle(theta + q as f64 * FRAC_PI_2);
        let turn = Rotation2::new(q as f64 * FRAC_PI_2);
        let (n_q, u_q) = (turn * normal, turn * along);
        let foot = |p: &Point2<f64>| Point2::from(n_q * d + u_q * u_q.dot(&p.coords));
        let covariance = Matrix2::new(
            sigma2 / n as f64 + t_mean * t_mean * var_theta,
            t_mean * var_theta,
            t_mean * var_theta,
            var_theta,
        );
        Some(Wall {
            d_m: d,
            gamma_rad: gamma,
            covariance,
            points: n,
            rms_residual_m: fit.wall.rms_residual_m,
            ends: [foot(&fit.wall.ends[0]), foot(&fit.wall.ends[1])],
        })
    });
    Some((walls, theta, var_theta.sqrt()))
}
