//! RANSAC line extraction, the baseline of the sensor-precision paper
//! (Rogers et al., after Nguyen et al. 2005): max-range points dropped, pairs
//! of points drawn uniformly as line hypotheses, the best-supported one
//! refined on its inliers, its inliers removed, and again until no line has
//! enough support. It shares the robust refinement with the RWHT, so the two
//! differ only in how they find their hypotheses.

use crate::NavError;
use crate::extractor::WallExtractor;
use crate::line_fit::{FitConfig, Line, LineFitter, mark_free_standing};
use crate::points::{ScanPoint, ScanPoints};
use crate::wall::Wall;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use stucco_core::wrap_angle;

/// Settings of the RANSAC extractor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RansacConfig {
    /// Hypotheses drawn per line at most.
    pub max_iterations: usize,
    /// Stop drawing once a line this likely has been drawn (the adaptive
    /// iteration count of RANSAC).
    pub confidence: f64,
    /// A point within this distance of a hypothesis supports it, m.
    pub inlier_threshold_m: f64,
    /// A hypothesis needs this many supporters to become a line.
    pub min_inliers: usize,
    /// The robust refinement of each line.
    pub fit: FitConfig,
    /// Lines returned per scan, at most.
    pub max_walls: usize,
    /// Seed of the hypothesis draws.
    pub seed: u64,
}

impl Default for RansacConfig {
    fn default() -> Self {
        RansacConfig {
            max_iterations: 500,
            confidence: 0.99,
            inlier_threshold_m: 0.06,
            min_inliers: 10,
            fit: FitConfig::default(),
            max_walls: 24,
            seed: 0x5eed,
        }
    }
}

/// The RANSAC line extractor. Deterministic: its draws come from a seeded
/// generator, so the same scans in the same order give the same walls.
#[derive(Clone, Debug)]
pub struct RansacExtractor {
    config: RansacConfig,
    rng: ChaCha8Rng,
    fitter: LineFitter,
    taken: Vec<bool>,
    free: Vec<usize>,
}

impl RansacExtractor {
    /// An extractor with `config`.
    pub fn new(config: RansacConfig) -> Result<Self, NavError> {
        if config.inlier_threshold_m.is_nan() || config.inlier_threshold_m <= 0.0 {
            return Err(NavError::InvalidConfig {
                field: "inlier_threshold_m",
                reason: "must be positive".into(),
            });
        }
        if config.confidence.is_nan() || config.confidence <= 0.0 || config.confidence >= 1.0 {
            return Err(NavError::InvalidConfig {
                field: "confidence",
                reason: "must lie strictly between 0 and 1".into(),
            });
        }
        Ok(RansacExtractor {
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            fitter: LineFitter::new(config.fit.clone()),
            config,
            taken: Vec::new(),
            free: Vec::new(),
        })
    }

    /// The best two-point hypothesis on the free points, with its support.
    fn best_hypothesis(&mut self, pts: &[ScanPoint]) -> Option<(Line, usize)> {
        let m = self.free.len();
        let thr = self.config.inlier_threshold_m;
        let mut best: Option<(Line, usize)> = None;
        let mut needed = self.config.max_iterations;
        let mut it = 0;
        while it < needed.min(self.config.max_iterations) {
            it += 1;
            let a = self.free[self.rng.random_range(0..m)];
            let b = self.free[self.rng.random_range(0..m)];
            let (pa, pb) = (pts[a].p, pts[b].p);
            let dir = pb - pa;
            let len = dir.norm();
            if a == b || len < 1e-6 {
                continue;
            }
            let normal = nalgebra::Vector2::new(-dir.y, dir.x) / len;
            let mut d = normal.dot(&pa.coords);
            let mut gamma = normal.y.atan2(normal.x);
            if d < 0.0 {
                d = -d;
                gamma += std::f64::consts::PI;
            }
            let line = Line::new(d, wrap_angle(gamma));
            let support = self
                .free
                .iter()
                .filter(|&&i| line.residual(&pts[i].p).abs() < thr)
                .count();
            if best.is_none_or(|(_, n)| support > n) {
                best = Some((line, support));
                // Draws needed to see an all-inlier pair with the wanted confidence.
                let w = support as f64 / m as f64;
                let p_pair = (w * w).clamp(1e-9, 1.0 - 1e-12);
                needed =
                    ((1.0 - self.config.confidence).ln() / (1.0 - p_pair).ln()).ceil() as usize;
            }
        }
        best
    }
}

impl WallExtractor for RansacExtractor {
    fn name(&self) -> &'static str {
        "ransac"
    }

    fn extract(&mut self, points: &ScanPoints) -> Vec<Wall> {
        let pts = points.points();
        self.taken.clear();
        self.taken.resize(pts.len(), false);
        mark_free_standing(pts, &self.config.fit, &mut self.taken);
        let mut walls = Vec::new();
        let mut failures = 0;
        while walls.len() < self.config.max_walls && failures < 3 {
            self.free.clear();
            self.free.extend((0..pts.len()).filter(|&i| !self.taken[i]));
            if self.free.len() < self.config.min_inliers.max(2) {
                break;
            }
            let Some((line, support)) = self.best_hypothesis(pts) else {
                break;
            };
            if support < self.config.min_inliers {
                break;
            }
            let thr = self.config.inlier_threshold_m;
            let supports = |p: &ScanPoint| line.residual(&p.p).abs() < thr;
            let seeds = (0..pts.len()).filter(|&i| supports(&pts[i]));
            match self.fitter.fit(pts, &self.taken, seeds) {
                Some(fit) => {
                    for &i in &fit.support {
                        self.taken[i] = true;
                    }
                    walls.push(fit.wall);
                }
                None => {
                    // The hypothesis was clutter that happened to line up: retire
                    // its supporters so the next draw looks elsewhere.
                    for (i, p) in pts.iter().enumerate() {
                        if supports(p) {
                            self.taken[i] = true;
                        }
                    }
                    failures += 1;
                }
            }
        }
        walls
    }
}
