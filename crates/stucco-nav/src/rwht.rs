//! Wall extraction with the range-weighted Hough transform: peaks found one
//! at a time, each refined by robust least squares, its measurements removed
//! before the next (paper A §2.1, paper B §2.2).

use crate::NavError;
use crate::extractor::WallExtractor;
use crate::hough::{HoughConfig, HoughTransform, Weighting};
use crate::line_fit::{FitConfig, LineFitter};
use crate::points::{ScanPoint, ScanPoints};
use crate::wall::Wall;
use serde::{Deserialize, Serialize};

/// Settings of the RWHT extractor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RwhtConfig {
    /// The transform.
    pub hough: HoughConfig,
    /// The robust refinement of each peak.
    pub fit: FitConfig,
    /// A peak is "major" when it amounts to at least this much wall seen
    /// face-on, m (for the range weightings: score × angular step). For the
    /// counting transform, a peak must hold `fit.min_points` measurements.
    pub min_peak_m: f64,
    /// Local maxima of the transform considered as peaks, at most.
    pub max_candidates: usize,
    /// Walls returned per scan, at most.
    pub max_walls: usize,
    /// Transforms computed per scan, at most: after the first, each one
    /// transforms the measurements no wall has taken yet.
    pub max_passes: usize,
}

impl Default for RwhtConfig {
    fn default() -> Self {
        RwhtConfig {
            hough: HoughConfig::default(),
            fit: FitConfig::default(),
            min_peak_m: 0.3,
            max_candidates: 48,
            max_walls: 24,
            max_passes: 2,
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Candidate {
    k: usize,
    j: usize,
    score: f64,
    alive: bool,
}

/// The RWHT wall extractor (or C1 / C2 with another [`Weighting`]).
///
/// Peaks are the local maxima of the transform; their scores are kept exact
/// as measurements are removed, which is the paper's "remove the
/// measurements and search again" without recomputing the transform.
#[derive(Clone, Debug)]
pub struct RwhtExtractor {
    config: RwhtConfig,
    hough: HoughTransform,
    fitter: LineFitter,
    taken: Vec<bool>,
    candidates: Vec<Candidate>,
    /// The measurements not yet taken by a wall, for later passes.
    left: Vec<ScanPoint>,
    /// Where each measurement the transform was computed on sits in the
    /// scan.
    in_scan: Vec<usize>,
}

impl RwhtExtractor {
    /// An extractor with `config`.
    pub fn new(config: RwhtConfig) -> Result<Self, NavError> {
        let hough = HoughTransform::new(config.hough.clone())?;
        let fitter = LineFitter::new(config.fit.clone());
        Ok(RwhtExtractor {
            config,
            hough,
            fitter,
            taken: Vec::new(),
            candidates: Vec::new(),
            left: Vec::new(),
            in_scan: Vec::new(),
        })
    }

    /// Its settings.
    pub fn config(&self) -> &RwhtConfig {
        &self.config
    }

    /// The transform of the last scan extracted.
    pub fn transform(&self) -> &HoughTransform {
        &self.hough
    }

    fn threshold(&self, angle_increment_rad: f64) -> f64 {
        match self.config.hough.weighting {
            Weighting::Count => self.config.fit.min_points as f64,
            _ => self.config.min_peak_m / angle_increment_rad.max(1e-6),
        }
    }

    /// Local maxima of the accumulator above `threshold`, strongest first.
    fn find_candidates(&mut self, threshold: f64) {
        self.candidates.clear();
        let h = &self.hough;
        let (n, m) = (h.angle_bins(), h.distance_bins());
        for k in 0..n {
            let row = h.row(k);
            let prev = h.row((k + n - 1) % n);
            let next = h.row((k + 1) % n);
            // Cells without votes are zero, under any threshold.
            for j in h.voted(k) {
                let v = row[j];
                if f64::from(v) < threshold {
                    continue;
                }
                let lo = j.saturating_sub(1);
                let hi = (j + 1).min(m - 1);
                // Strictly above the neighbours before, at least the ones after:
                // a plateau yields exactly one maximum.
                let is_max = (lo..=hi).all(|jj| v > prev[jj] && v >= next[jj])
                    && (j == 0 || v > row[j - 1])
                    && (j + 1 >= m || v >= row[j + 1]);
                if is_max {
                    self.candidates.push(Candidate {
                        k,
                        j,
                        score: f64::from(v),
                        alive: true,
                    });
                }
            }
        }
        self.candidates.sort_by(|a, b| {
            b.score
                .total_cmp(&a.score)
                .then((a.k, a.j).cmp(&(b.k, b.j)))
        });
        self.candidates.truncate(self.config.max_candidates);
    }
}

impl WallExtractor for RwhtExtractor {
    fn name(&self) -> &'static str {
        match self.config.hough.weighting {
            Weighting::Range => "rwht",
            Weighting::Count => "hough-count",
            Weighting::SurfaceSampling => "hough-surface",
        }
    }

    fn extract(&mut self, points: &ScanPoints) -> Vec<Wall> {
        let pts = points.points();
        self.taken.clear();
        self.taken.extend(pts.iter().map(|p| !self.hough.uses(p)));
        let threshold = self.threshold(points.angle_increment_rad());
        let mut walls = Vec::new();
        // A wall whose cell sits beside a stronger peak is no local maximum
        // until that peak's measurements are gone: when the peaks of one
        // transform are used up, transform what is left and search again.
        for pass in 0..self.config.max_passes {
            self.in_scan.clear();
            if pass == 0 {
                self.in_scan.extend(0..pts.len());
                self.hough.compute(pts);
            } else {
                self.in_scan
                    .extend((0..pts.len()).filter(|&i| !self.taken[i]));
                self.left.clear();
                self.left.extend(self.in_scan.iter().map(|&i| pts[i]));
                self.hough.compute(&self.left);
            }
            self.find_candidates(threshold);
            let before = walls.len();
            self.take_peaks(pts, threshold, &mut walls);
            if walls.len() == before || walls.len() >= self.config.max_walls {
                break;
            }
        }
        walls
    }
}

impl RwhtExtractor {
    /// Fits the candidates of the current transform, strongest first,
    /// removing each wall's measurements from the scores of the rest.
    fn take_peaks(&mut self, pts: &[ScanPoint], threshold: f64, walls: &mut Vec<Wall>) {
        while walls.len() < self.config.max_walls {
            let Some(best) = self
                .candidates
                .iter()
                .enumerate()
                .filter(|(_, c)| c.alive && c.score >= threshold)
                .max_by(|a, b| a.1.score.total_cmp(&b.1.score).then(b.0.cmp(&a.0)))
                .map(|(i, _)| i)
            else {
                break;
            };
            let Candidate { k, j, .. } = self.candidates[best];
            self.candidates[best].alive = false;
            let in_scan = &self.in_scan;
            let seeds = self.hough.voters(k, j).map(|i| in_scan[i]);
            let Some(fit) = self.fitter.fit(pts, &self.taken, seeds) else {
                continue;
            };
            for &i in &fit.support {
                self.taken[i] = true;
                for c in self.candidates.iter_mut().filter(|c| c.alive) {
                    c.score -= self.hough.contribution(&pts[i], c.k, c.j);
                }
            }
            walls.push(fit.wall);
        }
    }
}
