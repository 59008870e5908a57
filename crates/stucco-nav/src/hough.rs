//! The g-weighted Hough transform of a range scan (Forsberg, Larsson and
//! Wernersson, paper A §2.1):
//!
//! ```text
//! C(d, γ) = Σᵢ w(rᵢ cos(φᵢ − γ) − d) · g(rᵢ, φᵢ, γ)
//! ```
//!
//! with `w` the rectangular window of width `2a` on the point-to-line
//! distance and three weightings: `g = 1` counts (C1), `g = r cos(φ − γ)`
//! compensates the surface sampling rate (C2), and `g = r` is the
//! range-weighted Hough transform, RWHT (C3).
//!
//! Each cell is a gate, as paper B reads it: a measurement votes for cell
//! `(d_j, γ_k)` when some line inside the cell — any angle within half a bin
//! of `γ_k`, any distance within half a bin of `d_j` — passes within `a` of
//! it. A wall near the sensor then puts all its measurements in the one cell
//! that holds it, whatever its angle within the bin; with point-sampled
//! angles a 3° grid splits a long near wall between two cells and a line
//! slanted across a radiator and its wall can win. Votes are laid down as
//! differences and summed once per row, so a vote costs two writes whatever
//! its span. Only lines facing the sensor (`d > 0`) are voted for.
//!
//! A measurement whose neighbours lie on a line with it (within the range
//! noise) votes only for the angles that line's normal can have: its votes
//! for lines across its own surface would gather no others. Measurements
//! at edges and on round things vote for every angle they face. The peaks
//! stay where they were, and the transform costs a third less.

use crate::NavError;
use crate::points::ScanPoint;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Length of surface across the beams over which a measurement's surface
/// normal is taken, m.
const SURFACE_SPAN_M: f64 = 0.3;

/// The weighting `g` of the transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    /// C1: every measurement counts one; the transform is a histogram.
    Count,
    /// C2: weighted by the surface sampling rate, `r cos(φ − γ)`.
    SurfaceSampling,
    /// C3, the RWHT: weighted by range, `r`.
    Range,
}

/// Resolution, window and weighting of the transform.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HoughConfig {
    /// Number of angle bins over the full circle (paper: 120, i.e. 3°).
    pub angle_bins: usize,
    /// Distance resolution, m (paper: 2.5 cm).
    pub distance_resolution_m: f64,
    /// Half-width `a` of the rectangular window, m.
    pub half_window_m: f64,
    /// The weighting `g`.
    pub weighting: Weighting,
    /// Measurements farther than this are ignored, m (the paper leans on
    /// its laser's 30 m limit to bound the influence of far spurious echoes).
    pub max_range_m: f64,
    /// Range noise of the sensor, m. With it the transform gates each
    /// measurement by its surface: where the measurements around it lie on
    /// a line (within the noise), it votes only for the angles that line's
    /// normal can have, not for every line through it — the lines it does
    /// not lie along would gather no other votes anyway. Zero votes every
    /// measurement for every angle, as the paper does.
    pub surface_noise_m: f64,
}

impl Default for HoughConfig {
    fn default() -> Self {
        HoughConfig {
            angle_bins: 120,
            distance_resolution_m: 0.025,
            half_window_m: 0.04,
            weighting: Weighting::Range,
            max_range_m: 32.0,
            surface_noise_m: 0.02,
        }
    }
}

impl HoughConfig {
    /// Checks that the settings describe a usable transform.
    pub fn validate(&self) -> Result<(), NavError> {
        let bad = |field: &'static str, reason: &str| {
            Err(NavError::InvalidConfig {
                field,
                reason: reason.to_owned(),
            })
        };
        if self.angle_bins < 8 || !self.angle_bins.is_multiple_of(4) {
            return bad("angle_bins", "must be a multiple of 4, at least 8");
        }
        if self.distance_resolution_m.is_nan() || self.distance_resolution_m <= 0.0 {
            return bad("distance_resolution_m", "must be positive");
        }
        if self.half_window_m.is_nan() || self.half_window_m < self.distance_resolution_m / 2.0 {
            return bad(
                "half_window_m",
                "must be at least half the distance resolution, so every measurement votes",
            );
        }
        if self.max_range_m.is_nan() || self.max_range_m <= 0.0 {
            return bad("max_range_m", "must be positive");
        }
        if self.surface_noise_m.is_nan() || self.surface_noise_m < 0.0 {
            return bad("surface_noise_m", "must not be negative");
        }
        Ok(())
    }

    /// Angle bin width, rad.
    pub fn angle_resolution_rad(&self) -> f64 {
        TAU / self.angle_bins as f64
    }
}

/// The accumulator `C(d, γ)` over `γ = k·Δγ` and `d = (j + ½)·Δd`.
#[derive(Clone, Debug)]
pub struct HoughTransform {
    config: HoughConfig,
    distance_bins: usize,
    acc: Vec<f32>,
    /// Unit normals at the lower edge of each angle bin, `γ_k − ½Δγ`: the
    /// distance of a point along them bounds its votes without trigonometry.
    edges: Vec<[f64; 2]>,
    /// Unit normals at the bins' centres.
    centres: Vec<[f64; 2]>,
    /// The angle bins each measurement of the last transform voted for,
    /// by beam: first bin and count.
    gates: Vec<(u16, u16)>,
    /// Running sums of x, y, x², xy, y² over the measurements, for the
    /// surface around each one.
    sums: Vec<[f64; 5]>,
    /// Each row's votes in measurement order: the measurement's index and
    /// the distance bins `lo..=hi` it voted for.
    row_votes: Vec<Vec<(u32, u32, u32)>>,
    /// The distance bins each row received votes in, `lo..hi` (empty when
    /// none): the rest of the row is zero, and neither the running sum nor
    /// the peak search need visit it.
    voted: Vec<(usize, usize)>,
}

impl HoughTransform {
    /// An empty transform.
    pub fn new(config: HoughConfig) -> Result<Self, NavError> {
        config.validate()?;
        let n = config.angle_bins;
        let step = config.angle_resolution_rad();
        let unit = |a: f64| [a.cos(), a.sin()];
        Ok(HoughTransform {
            edges: (0..n).map(|k| unit((k as f64 - 0.5) * step)).collect(),
            centres: (0..n).map(|k| unit(k as f64 * step)).collect(),
            config,
            distance_bins: 0,
            acc: Vec::new(),
            gates: Vec::new(),
            sums: Vec::new(),
            row_votes: vec![Vec::new(); n],
            voted: Vec::new(),
        })
    }

    /// Its settings.
    pub fn config(&self) -> &HoughConfig {
        &self.config
    }

    /// Number of angle bins.
    pub fn angle_bins(&self) -> usize {
        self.config.angle_bins
    }

    /// Number of distance bins of the last transform.
    pub fn distance_bins(&self) -> usize {
        self.distance_bins
    }

    /// Angle of bin `k`, rad.
    pub fn gamma(&self, k: usize) -> f64 {
        k as f64 * self.config.angle_resolution_rad()
    }

    /// Distance at the centre of bin `j`, m.
    pub fn distance(&self, j: usize) -> f64 {
        (j as f64 + 0.5) * self.config.distance_resolution_m
    }

    /// `C(d_j, γ_k)`.
    pub fn value(&self, k: usize, j: usize) -> f64 {
        f64::from(self.acc[k * self.distance_bins + j])
    }

    /// One row of the accumulator: `C(·, γ_k)`.
    pub fn row(&self, k: usize) -> &[f32] {
        &self.acc[k * self.distance_bins..(k + 1) * self.distance_bins]
    }

    /// The distance bins of row `k` that hold votes, `lo..hi`; the row is
    /// zero outside them.
    pub fn voted(&self, k: usize) -> std::ops::Range<usize> {
        let (lo, hi) = self.voted[k];
        lo..hi
    }

    /// True when `p` is used at all (inside the range limit).
    pub fn uses(&self, p: &ScanPoint) -> bool {
        p.range_m <= self.config.max_range_m
    }

    /// Computes the transform of `pts`.
    pub fn compute(&mut self, pts: &[ScanPoint]) {
        let cfg = &self.config;
        let max_r = pts
            .iter()
            .filter(|p| p.range_m <= cfg.max_range_m)
            .fold(0.0f64, |m, p| m.max(p.range_m));
        self.distance_bins =
            ((max_r + cfg.half_window_m) / cfg.distance_resolution_m).ceil() as usize + 2;
        self.acc.clear();
        self.acc.resize(self.distance_bins * cfg.angle_bins, 0.0);
        let n = cfg.angle_bins;
        self.voted.clear();
        self.voted.resize(n, (usize::MAX, 0));
        self.gate(pts);
        self.row_votes.iter_mut().for_each(Vec::clear);
        for (i, p) in pts.iter().enumerate() {
            if !self.uses(p) {
                continue;
            }
            let (first, count) = self.gates[p.beam];
            let mut k = usize::from(first);
            for _ in 0..count {
                if let Some((lo, hi, g)) = self.span(p, k) {
                    let row = &mut self.acc[k * self.distance_bins..(k + 1) * self.distance_bins];
                    row[lo] += g as f32;
                    row[hi + 1] -= g as f32;
                    if g > 0.0 {
                        self.row_votes[k].push((i as u32, lo as u32, hi as u32));
                    }
                    let v = &mut self.voted[k];
                    *v = (v.0.min(lo), v.1.max(hi + 1));
                }
                k += 1;
                if k == n {
                    k = 0;
                }
            }
        }
        let m = self.distance_bins;
        for (row, voted) in self.acc.chunks_exact_mut(m).zip(&mut self.voted) {
            if voted.0 >= voted.1 {
                *voted = (0, 0);
                continue;
            }
            let mut run = 0.0f32;
            for cell in &mut row[voted.0..voted.1] {
                run += *cell;
                *cell = run;
            }
            // Past the last vote the sum is back to nothing (the f32
            // remainder of adding and taking the same weights is dropped).
            row[voted.1] = 0.0;
        }
    }

    /// The angle bins each measurement votes for: within 90° (and half a
    /// bin) of its bearing, the lines it can face; narrowed to the angles
    /// the normal of its surface can have when the measurements around it
    /// lie on a line.
    fn gate(&mut self, pts: &[ScanPoint]) {
        let n = self.config.angle_bins;
        let step = self.config.angle_resolution_rad();
        let beams = pts.iter().map(|p| p.beam + 1).max().unwrap_or(0);
        self.gates.clear();
        self.gates.resize(beams, (0, 0));
        self.sums.clear();
        self.sums.push([0.0; 5]);
        for p in pts {
            let [a, b, c, d, e] = self.sums[self.sums.len() - 1];
            let (x, y) = (p.p.x, p.p.y);
            self.sums
                .push([a + x, b + y, c + x * x, d + x * y, e + y * y]);
        }
        let noise = self.config.surface_noise_m;
        let half_turn = (n / 2 + 2) as u16;
        for (i, p) in pts.iter().enumerate() {
            let first = ((p.bearing_rad - PI / 2.0) / step - 0.5).ceil() as i64;
            let full = (first.rem_euclid(n as i64) as u16, half_turn);
            self.gates[p.beam] = if noise > 0.0 {
                self.surface_gate(pts, i, step).unwrap_or(full)
            } else {
                full
            };
        }
    }

    /// The bins the normal of the surface around measurement `i` can fall
    /// in, when the measurements spanning `SURFACE_SPAN_M` of it across
    /// the beams lie on a line within the noise: centred on it, or, at the
    /// end of a surface (a corner, a door's frame, a person in front), on
    /// the side where the surface goes on.
    fn surface_gate(&self, pts: &[ScanPoint], i: usize, step: f64) -> Option<(u16, u16)> {
        let p = &pts[i];
        let beam_step = if i > 0 {
            (p.bearing_rad - pts[i - 1].bearing_rad).abs()
        } else {
            (pts.get(1)?.bearing_rad - p.bearing_rad).abs()
        }
        .max(1e-6);
        let k = ((SURFACE_SPAN_M / 2.0 / (p.range_m * beam_step)).ceil() as usize).clamp(2, 64);
        // Last, a short centred window: a round thing (a person, a post)
        // is flat over a few centimetres and votes only for its tangents.
        let short = (k / 3).max(2);
        [
            i.checked_sub(k).map(|a| (a, i + k)),
            i.checked_sub(2 * k).map(|a| (a, i)),
            Some((i, i + 2 * k)),
            i.checked_sub(short).map(|a| (a, i + short)),
        ]
        .into_iter()
        .flatten()
        .find_map(|(a, b)| self.window_gate(pts, i, a, b, step))
    }

    /// The gate of measurement `i` from the line through measurements
    /// `a..=b`, when they are consecutive beams on a line within the noise
    /// and `i` lies on it.
    fn window_gate(
        &self,
        pts: &[ScanPoint],
        i: usize,
        a: usize,
        b: usize,
        step: f64,
    ) -> Option<(u16, u16)> {
        let n = self.config.angle_bins;
        let q = pts.get(b)?;
        // Consecutive beams only: a gap is an edge or a no-return.
        if q.beam - pts[a].beam != b - a {
            return None;
        }
        let m = (b - a + 1) as f64;
        let lo = self.sums[a];
        let hi = self.sums[b + 1];
        let [sx, sy, sxx, sxy, syy] = std::array::from_fn(|t| hi[t] - lo[t]);
        let (cx, cy) = (sx / m, sy / m);
        let (vxx, vxy, vyy) = (sxx / m - cx * cx, sxy / m - cx * cy, syy / m - cy * cy);
        // Eigenvalues of the window's scatter: spread along the surface and
        // across it.
        let mean = 0.5 * (vxx + vyy);
        let dev = (0.25 * (vxx - vyy).powi(2) + vxy * vxy).sqrt();
        let (along, across) = (mean + dev, (mean - dev).max(0.0));
        let noise = self.config.surface_noise_m;
        if across > 4.0 * noise * noise || along <= 0.0 {
            return None;
        }
        // Normal: perpendicular to the principal axis, facing away from the
        // sensor.
        let axis = 0.5 * (2.0 * vxy).atan2(vxx - vyy);
        let mut gamma = axis + PI / 2.0;
        let (sg, cg) = gamma.sin_cos();
        // The measurement itself on the line (a window may end on it).
        let p = &pts[i].p;
        if (cg * (p.x - cx) + sg * (p.y - cy)).abs() > 3.0 * noise {
            return None;
        }
        if cg * cx + sg * cy < 0.0 {
            gamma += PI;
        }
        // Its uncertainty: the noise over the spread of the window along the
        // surface; three sigmas, and half a bin, either side.
        let sigma = noise / (along * m).sqrt();
        let reach = (3.0 * sigma / step + 0.5).ceil() as i64 + 1;
        let centre = (gamma / step).round() as i64;
        let count = (2 * reach + 1).min((n / 2 + 2) as i64);
        Some(((centre - reach).rem_euclid(n as i64) as u16, count as u16))
    }

    /// The distance bins `lo..=hi` of row `k` that `p` votes for, and the
    /// weight of its vote; `None` when it votes for none.
    #[inline]
    fn span(&self, p: &ScanPoint, k: usize) -> Option<(usize, usize, f64)> {
        let cfg = &self.config;
        let n = self.edges.len();
        let (x, y) = (p.p.x, p.p.y);
        // ρ(γ) = x·cos γ + y·sin γ at the cell's two edges; inside the cell
        // it peaks at r where γ meets the bearing.
        let [c1, s1] = self.edges[k];
        let [c2, s2] = self.edges[(k + 1) % n];
        let (rho1, rho2) = (x * c1 + y * s1, x * c2 + y * s2);
        // The bearing lies between the edges: (x, y) is left of edge 1 and
        // right of edge 2.
        let inside = c1 * y - s1 * x >= 0.0 && c2 * y - s2 * x <= 0.0;
        let rho_max = if inside { p.range_m } else { rho1.max(rho2) };
        if rho_max <= 0.0 {
            return None;
        }
        let rho_min = rho1.min(rho2).max(0.0);
        let inv_res = 1.0 / cfg.distance_resolution_m;
        // Bin j covers distances [j·Δd, (j+1)·Δd).
        // Both are non-negative: truncation is the floor, and much cheaper.
        let lo = ((rho_min - cfg.half_window_m) * inv_res).max(0.0) as usize;
        let hi = (((rho_max + cfg.half_window_m) * inv_res) as usize).min(self.distance_bins - 2);
        if hi < lo {
            return None;
        }
        let g = match cfg.weighting {
            Weighting::Count => 1.0,
            Weighting::SurfaceSampling => {
                let [c, s] = self.centres[k];
                (x * c + y * s).max(0.0)
            }
            Weighting::Range => p.range_m,
        };
        Some((lo, hi, g))
    }

    /// The contribution of `p` to cell `(k, j)`: what removing it subtracts.
    pub fn contribution(&self, p: &ScanPoint, k: usize, j: usize) -> f64 {
        if !self.uses(p) || !self.gated_in(p, k) {
            return 0.0;
        }
        match self.span(p, k) {
            Some((lo, hi, g)) if (lo..=hi).contains(&j) => g,
            _ => 0.0,
        }
    }

    /// True when row `k` is among the angles `p` voted for.
    fn gated_in(&self, p: &ScanPoint, k: usize) -> bool {
        let Some(&(first, count)) = self.gates.get(p.beam) else {
            return false;
        };
        let n = self.config.angle_bins;
        (k + n - usize::from(first)) % n < usize::from(count)
    }

    /// The measurements of the last transform (indices into its points,
    /// in order) that vote for cell `(k, j)`: the same as
    /// [`HoughTransform::votes_for`] picks, from the row's own votes.
    pub fn voters(&self, k: usize, j: usize) -> impl Iterator<Item = usize> + '_ {
        let j = j as u32;
        self.row_votes[k]
            .iter()
            .filter(move |&&(_, lo, hi)| lo <= j && j <= hi)
            .map(|&(i, _, _)| i as usize)
    }

    /// True when `p` votes for cell `(k, j)`: some line of the cell passes
    /// within the window of it.
    pub fn votes_for(&self, p: &ScanPoint, k: usize, j: usize) -> bool {
        self.contribution(p, k, j) > 0.0
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    fn point(x: f64, y: f64) -> ScanPoint {
        ScanPoint {
            p: Point2::new(x, y),
            range_m: x.hypot(y),
            bearing_rad: y.atan2(x),
            beam: 0,
        }
    }

    #[test]
    fn the_three_weightings_differ_as_the_paper_defines() {
        // Two points on the wall x = 2: one straight ahead, one 45° off.
        let pts = [point(2.0, 0.0), point(2.0, 2.0)];
        let cell = |w: Weighting| {
            let mut t = HoughTransform::new(HoughConfig {
                weighting: w,
                half_window_m: 0.0125,
                ..HoughConfig::default()
            })
            .expect("valid");
            t.compute(&pts);
            // γ = 0 is bin 0; bin 80 holds d ∈ [2.0, 2.025): both points vote there once.
            t.value(0, 80)
        };
        assert!((cell(Weighting::Count) - 2.0).abs() < 1e-6);
        assert!((cell(Weighting::Range) - (2.0 + 8f64.sqrt())).abs() < 1e-5);
        assert!((cell(Weighting::SurfaceSampling) - 4.0).abs() < 1e-5);
    }

    #[test]
    fn window_spans_the_bins_within_a() {
        let mut t = HoughTransform::new(HoughConfig {
            weighting: Weighting::Count,
            half_window_m: 0.05,
            ..HoughConfig::default()
        })
        .expect("valid");
        t.compute(&[point(1.0, 0.0)]);
        let hit: Vec<usize> = (0..t.distance_bins())
            .filter(|&j| t.value(0, j) > 0.0)
            .collect();
        // Lines of bin 0 (γ within ±1.5°) pass the point at ρ ∈ [cos 1.5°, 1];
        // the window widens that by 5 cm: bins [0.9497/0.025] = 37 … [1.05/0.025] = 42.
        assert_eq!(hit, (37..=42).collect::<Vec<_>>());
        for &j in &hit {
            assert_eq!(t.contribution(&point(1.0, 0.0), 0, j), 1.0);
        }
        // Lines facing away from the point get no vote.
        assert_eq!(
            (0..t.distance_bins()).map(|j| t.value(60, j)).sum::<f64>(),
            0.0
        );
    }

    #[test]
    fn surface_gating_keeps_the_wall_peak_and_drops_the_crossing_votes() {
        // 61 beams at 0.5° on the wall x = 2, noise-free.
        let pts: Vec<ScanPoint> = (0..61)
            .map(|i| {
                let phi = (i as f64 - 30.0) * 0.5f64.to_radians();
                ScanPoint {
                    beam: i,
                    ..point(2.0, 2.0 * phi.tan())
                }
            })
            .collect();
        let transform = |noise: f64| {
            let mut t = HoughTransform::new(HoughConfig {
                surface_noise_m: noise,
                ..HoughConfig::default()
            })
            .expect("valid");
            t.compute(&pts);
            t
        };
        let (gated, full) = (transform(0.02), transform(0.0));
        let peak = |t: &HoughTransform| {
            (0..t.angle_bins())
                .flat_map(|k| (0..t.distance_bins()).map(move |j| (k, j)))
                .max_by(|a, b| t.value(a.0, a.1).total_cmp(&t.value(b.0, b.1)))
                .expect("cells")
        };
        assert_eq!(peak(&gated), peak(&full));
        let (k, j) = peak(&full);
        assert!((gated.value(k, j) - full.value(k, j)).abs() < 1e-3);
        // Lines at 45° get votes from the measurements in the wall's middle
        // only without gating (those near its ends, without neighbours on
        // both sides, vote for every angle either way).
        let total =
            |t: &HoughTransform| (0..t.distance_bins()).map(|j| t.value(15, j)).sum::<f64>();
        assert!(
            total(&gated) < 0.5 * total(&full),
            "{} vs {}",
            total(&gated),
            total(&full)
        );
    }

    #[test]
    fn a_cells_voters_are_the_measurements_that_vote_for_it() {
        // A wall, a corner and a post: gated and ungated measurements.
        let mut pts: Vec<ScanPoint> = (0..40)
            .map(|i| point(2.0, -1.0 + 0.05 * i as f64))
            .chain((0..20).map(|i| point(2.0 - 0.05 * i as f64, 1.0)))
            .chain(
                (0..6).map(|i| point(1.0 + 0.02 * (i as f64 * 0.8).cos(), -1.5 + 0.02 * i as f64)),
            )
            .collect();
        for (i, p) in pts.iter_mut().enumerate() {
            p.beam = i;
        }
        let mut t = HoughTransform::new(HoughConfig::default()).expect("valid");
        t.compute(&pts);
        let mut cells = 0;
        for k in 0..t.angle_bins() {
            for j in 0..t.distance_bins() {
                let want: Vec<usize> = (0..pts.len())
                    .filter(|&i| t.votes_for(&pts[i], k, j))
                    .collect();
                assert_eq!(t.voters(k, j).collect::<Vec<_>>(), want, "cell ({k}, {j})");
                cells += usize::from(!want.is_empty());
            }
        }
        assert!(cells > 100, "{cells} cells voted for");
    }

    #[test]
    fn rejects_unusable_settings() {
        let err = HoughTransform::new(HoughConfig {
            angle_bins: 10,
            ..HoughConfig::default()
        });
        assert!(matches!(
            err,
            Err(NavError::InvalidConfig {
                field: "angle_bins",
                ..
            })
        ));
    }
}
