//! The RWHT extractor as it stood before the walls-speed work (commit
//! 990aea6), kept verbatim as the reference the extractor is measured and
//! tested against.

use super::line_fit::{LineFitter, mark_free_standing};
use super::segments::{Segment, SegmentTransform, Segmenter};
use crate::NavError;
use crate::extractor::WallExtractor;
use crate::hough::Weighting;
use crate::points::{ScanPoint, ScanPoints};
use crate::rwht::RwhtConfig;
use crate::wall::Wall;

#[derive(Clone, Copy, Debug)]
struct Candidate {
    k: usize,
    j: usize,
    score: f64,
    alive: bool,
}

/// The RWHT wall extractor as it was (or C1 / C2 with another
/// [`Weighting`]): the reference for [`crate::RwhtExtractor`].
///
/// Peaks are the local maxima of the transform; a peak's score is recounted
/// from the segments not yet taken when it comes up, which is the paper's
/// "remove the measurements and search again" without recomputing the
/// transform.
#[derive(Clone, Debug)]
pub struct RwhtExtractor {
    config: RwhtConfig,
    segmenter: Segmenter,
    transform: SegmentTransform,
    fitter: LineFitter,
    segments: Vec<Segment>,
    /// Segments a wall has taken (most of their echoes).
    spent: Vec<bool>,
    taken: Vec<bool>,
    candidates: Vec<Candidate>,
    seeds: Vec<usize>,
}

impl RwhtExtractor {
    /// An extractor with `config`.
    pub fn new(config: RwhtConfig) -> Result<Self, NavError> {
        config.hough.validate()?;
        if config.min_segment_points < 3 {
            return Err(NavError::InvalidConfig {
                field: "min_segment_points",
                reason: "must be at least 3: two echoes make no line".to_owned(),
            });
        }
        let segmenter = Segmenter {
            noise_m: config.fit.noise_sigma_m,
            min_points: config.min_segment_points,
        };
        Ok(RwhtExtractor {
            transform: SegmentTransform::new(config.hough.clone(), config.segment_reach_rad),
            fitter: LineFitter::new(config.fit.clone()),
            segmenter,
            config,
            segments: Vec::new(),
            spent: Vec::new(),
            taken: Vec::new(),
            candidates: Vec::new(),
            seeds: Vec::new(),
        })
    }

    /// Its settings.
    pub fn config(&self) -> &RwhtConfig {
        &self.config
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
        let h = &self.transform;
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
        let max_range = self.config.hough.max_range_m;
        self.taken.clear();
        self.taken.extend(pts.iter().map(|p| p.range_m > max_range));
        self.segmenter.split(pts, &mut self.segments);
        let taken = &self.taken;
        self.segments
            .retain(|s| (s.first..s.end).all(|i| !taken[i]));
        // What stands free votes in no run; no wall takes it either.
        mark_free_standing(pts, &self.config.fit, &mut self.taken);
        self.spent.clear();
        self.spent.resize(self.segments.len(), false);
        let threshold = self.threshold(points.angle_increment_rad());
        let mut walls = Vec::new();
        // A wall whose cell sits beside a stronger peak is no local maximum
        // until that peak's segments are gone: when the peaks of one
        // transform are used up, transform what is left and search again.
        for _ in 0..self.config.max_passes {
            let spent = &self.spent;
            self.transform.compute(&self.segments, |s| !spent[s]);
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
    /// Fits the candidates of the current transform, strongest first. A
    /// candidate's score only falls as walls take segments, so the scores
    /// are refreshed lazily: the highest stored score is recounted from its
    /// cell's segments not yet taken, and it is the strongest peak when its
    /// fresh score still beats every other stored one.
    fn take_peaks(&mut self, pts: &[ScanPoint], threshold: f64, walls: &mut Vec<Wall>) {
        while walls.len() < self.config.max_walls {
            let mut order = self
                .candidates
                .iter()
                .enumerate()
                .filter(|(_, c)| c.alive && c.score >= threshold)
                .map(|(i, c)| (i, c.score));
            let Some(first) = order.next() else {
                break;
            };
            // The highest stored score and the one after it (ties to the
            // earlier candidate, as the candidates are sorted).
            let (best, runner_up) = order.fold((first, None::<f64>), |(b, r), (i, s)| {
                if s > b.1 {
                    ((i, s), Some(b.1))
                } else {
                    (b, Some(r.map_or(s, |r: f64| r.max(s))))
                }
            });
            let Candidate { k, j, .. } = self.candidates[best.0];
            let spent = &self.spent;
            let fresh: f64 = self
                .transform
                .votes_in(k, j)
                .filter(|&(s, _)| !spent[s])
                .map(|(_, g)| g)
                .sum();
            self.candidates[best.0].score = fresh;
            if fresh < threshold || runner_up.is_some_and(|r| fresh < r) {
                continue;
            }
            self.candidates[best.0].alive = false;
            self.seeds.clear();
            for (s, _) in self.transform.votes_in(k, j) {
                if !self.spent[s] {
                    let seg = &self.segments[s];
                    self.seeds.extend(seg.first..seg.end);
                }
            }
            self.seeds.sort_unstable();
            let Some(fit) = self
                .fitter
                .fit(pts, &self.taken, self.seeds.iter().copied())
            else {
                continue;
            };
            for &i in &fit.support {
                self.taken[i] = true;
            }
            // A segment is spent once a wall holds most of its echoes.
            for (seg, spent) in self.segments.iter().zip(&mut self.spent) {
                if !*spent {
                    let held = (seg.first..seg.end).filter(|&i| self.taken[i]).count();
                    *spent = 2 * held > seg.len();
                }
            }
            walls.push(fit.wall);
        }
    }
}
