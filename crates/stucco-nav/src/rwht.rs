//! Wall extraction with the range-weighted Hough transform: peaks found one
//! at a time, each refined by robust least squares, its measurements removed
//! before the next (paper A §2.1, paper B §2.2).
//!
//! The transform is voted by runs of echoes on one line
//! ([`crate::segments`]), not echo by echo: a wall's cell holds the same
//! range-weighted sum, the cells no wall reaches stay empty, and a scan
//! costs a few hundred votes instead of several thousand.

use crate::NavError;
use crate::extractor::WallExtractor;
use crate::hough::{HoughConfig, Weighting};
use crate::line_fit::{FitConfig, LineFitter, Untaken, mark_free_standing};
use crate::points::{ScanPoint, ScanPoints};
use crate::segments::{Segment, SegmentTransform, Segmenter};
use crate::wall::Wall;
use serde::{Deserialize, Serialize};
use stucco_core::LaserSpec;

/// Settings of the RWHT extractor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RwhtConfig {
    /// Grid, window and weighting of the transform. Its surface gate is
    /// not used: runs of echoes on one line vote instead of single echoes,
    /// and their lines are taken at `fit.noise_sigma_m`.
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
    /// transforms the segments no wall has taken yet.
    pub max_passes: usize,
    /// Fewest echoes in a run that votes.
    pub min_segment_points: usize,
    /// A run votes for the angles within three σ of its normal, but no
    /// farther than this either side, rad: a short run's direction says
    /// little, and spread over many rows its votes would add to no peak.
    pub segment_reach_rad: f64,
}

impl RwhtConfig {
    /// The extractor for scans of `laser`: the transform's surface noise
    /// and the fit's noise the laser's range σ.
    pub fn for_laser(laser: &LaserSpec) -> Self {
        RwhtConfig {
            hough: HoughConfig {
                surface_noise_m: laser.range_sigma_m,
                ..HoughConfig::default()
            },
            fit: FitConfig::for_laser(laser),
            ..RwhtConfig::default()
        }
    }
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
            min_segment_points: 4,
            segment_reach_rad: 0.1,
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
    /// The segment each echo is in (`u32::MAX` for none).
    segment_of: Vec<u32>,
    /// Echoes of each segment taken so far.
    held: Vec<u32>,
    /// The echoes no wall has taken yet.
    untaken: Untaken,
    /// The segments a peak's fit rested on, and the sets of them whose fit
    /// found no wall since a wall last took echoes (one after the other,
    /// each set's end in `failed_ends`): a fit on the same echoes, none
    /// taken since, finds none again.
    voters: Vec<u32>,
    failed: Vec<u32>,
    failed_ends: Vec<usize>,
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
            segment_of: Vec::new(),
            held: Vec::new(),
            untaken: Untaken::default(),
            voters: Vec::new(),
            failed: Vec::new(),
            failed_ends: Vec::new(),
            candidates: Vec::new(),
            seeds: Vec::new(),
        })
    }

    /// Its settings.
    pub fn config(&self) -> &RwhtConfig {
        &self.config
    }

    /// The transform of the last scan extracted.
    pub fn transform(&self) -> &SegmentTransform {
        &self.transform
    }

    /// The segments of the last scan extracted.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
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
        // A cell is below the threshold exactly when it is below the
        // smallest f32 that is not: the rows are searched in f32, a block
        // of cells at a time, and blocks with no cell that high skipped.
        let floor = f32_at_least(threshold);
        for k in 0..n {
            let row = h.voted_row(k);
            let voted = h.voted(k);
            // Cells without votes are zero, under any threshold.
            for (b, block) in row.chunks(BLOCK).enumerate() {
                if !block.iter().fold(false, |any, &v| any | (v >= floor)) {
                    continue;
                }
                let (prev, next) = ((k + n - 1) % n, (k + 1) % n);
                let start = voted.start + b * BLOCK;
                for (j, &v) in (start..).zip(block) {
                    if v < floor {
                        continue;
                    }
                    let lo = j.saturating_sub(1);
                    let hi = (j + 1).min(m - 1);
                    // Strictly above the neighbours before, at least the ones after:
                    // a plateau yields exactly one maximum.
                    let is_max = (lo..=hi).all(|jj| v > h.cell(prev, jj) && v >= h.cell(next, jj))
                        && (j == 0 || v > h.cell(k, j - 1))
                        && (j + 1 >= m || v >= h.cell(k, j + 1));
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
        }
        self.candidates.sort_by(|a, b| {
            b.score
                .total_cmp(&a.score)
                .then((a.k, a.j).cmp(&(b.k, b.j)))
        });
        self.candidates.truncate(self.config.max_candidates);
    }
}

/// Cells of a row the candidate search checks at once.
const BLOCK: usize = 16;

/// The smallest `f32` not below `x`: for every `f32` `v`,
/// `f64::from(v) < x` exactly when `v < f32_at_least(x)`.
fn f32_at_least(x: f64) -> f32 {
    let v = x as f32;
    if f64::from(v) < x { v.next_up() } else { v }
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
        // What each segment holds taken, kept up to date as walls take
        // echoes, so that a segment's share is not recounted after each.
        self.failed.clear();
        self.failed_ends.clear();
        self.segment_of.clear();
        self.segment_of.resize(pts.len(), u32::MAX);
        self.held.clear();
        for (s, seg) in self.segments.iter().enumerate() {
            self.segment_of[seg.first..seg.end].fill(s as u32);
            let held = self.taken[seg.first..seg.end]
                .iter()
                .filter(|&&t| t)
                .count();
            self.held.push(held as u32);
        }
        self.untaken.fill(pts, &self.taken);
        let threshold = self.threshold(points.angle_increment_rad());
        let mut walls = Vec::new();
        // A wall whose cell sits beside a stronger peak is no local maximum
        // until that peak's segments are gone: when the peaks of one
        // transform are used up, transform what is left and search again.
        for pass in 0..self.config.max_passes {
            let spent = &self.spent;
            if pass == 0 {
                self.transform.compute(&self.segments, |s| !spent[s]);
            } else {
                self.transform.keep_only(|s| !spent[s]);
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
            // The fit's seeds are the echoes of the live segments voting
            // for the cell (in scan order): the segments say which.
            self.voters.clear();
            for (s, _) in self.transform.votes_in(k, j) {
                if !self.spent[s] {
                    self.voters.push(s as u32);
                }
            }
            let mut from = 0;
            let tried = self.failed_ends.iter().any(|&end| {
                let same = self.failed[from..end] == self.voters[..];
                from = end;
                same
            });
            if tried {
                continue;
            }
            self.seeds.clear();
            for &s in &self.voters {
                let seg = &self.segments[s as usize];
                self.seeds.extend(seg.first..seg.end);
            }
            self.seeds.sort_unstable();
            let Some(fit) =
                self.fitter
                    .fit_within(pts, &self.untaken, &self.taken, self.seeds.iter().copied())
            else {
                self.failed.extend_from_slice(&self.voters);
                self.failed_ends.push(self.failed.len());
                continue;
            };
            self.failed.clear();
            self.failed_ends.clear();
            for &i in &fit.support {
                if !self.taken[i] {
                    self.taken[i] = true;
                    if let Some(held) = self.held.get_mut(self.segment_of[i] as usize) {
                        *held += 1;
                    }
                }
            }
            self.untaken.drop_taken(&self.taken);
            // A segment is spent once a wall holds most of its echoes.
            for ((seg, spent), &held) in self.segments.iter().zip(&mut self.spent).zip(&self.held) {
                if !*spent {
                    *spent = 2 * held as usize > seg.len();
                }
            }
            walls.push(fit.wall);
        }
    }
}
