//! `stucco walls`: wall and door extraction over a whole laser log, the
//! walls placed in the world with the log's poses, and a consistency figure.

use crate::carmen::{LoggedScan, open_carmen_file};
use crate::plan_view::{PlanPath, draw_plan};
use anyhow::{Context, Result};
use nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use stucco_core::{LaserSpec, Pose2, wrap_angle};
use stucco_nav::{
    DoorConfig, DoorOpening, FitConfig, RansacConfig, RansacExtractor, RwhtConfig, RwhtExtractor,
    ScanPoints, Wall, WallExtractor, baseline, find_doors,
};

/// Which wall extractor `stucco walls` runs, or a study maps on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExtractorKind {
    /// The range-weighted Hough transform.
    #[default]
    Rwht,
    /// The RANSAC baseline.
    Ransac,
}

impl std::fmt::Display for ExtractorKind {
    /// Its name as files and the command line spell it (clap's, which
    /// serde's `lowercase` agrees with).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use clap::ValueEnum;
        match self.to_possible_value() {
            Some(v) => f.write_str(v.get_name()),
            None => Ok(()),
        }
    }
}

/// What `stucco walls` was asked to do.
#[derive(Clone, Debug)]
pub struct WallsJob {
    /// The CARMEN log.
    pub log: PathBuf,
    /// The extractor.
    pub extractor: ExtractorKind,
    /// Where to write `walls.jsonl` and `walls.svg`, if anywhere.
    pub out: Option<PathBuf>,
    /// Run the implementation the RWHT extractor and the door search
    /// replaced (`stucco_nav::baseline`) instead, to time them side by
    /// side and compare what they write.
    pub baseline: bool,
}

/// The summary `stucco walls --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct WallsReport {
    /// The log read.
    pub log: String,
    /// The extractor run.
    pub extractor: ExtractorKind,
    /// True when it was the previous implementation (`--baseline`).
    pub baseline: bool,
    /// Scans processed.
    pub scans: usize,
    /// Mean number of walls per scan.
    pub walls_per_scan: f64,
    /// Mean number of door openings per scan.
    pub doors_per_scan: f64,
    /// Median time to extract walls and doors from one scan, µs.
    pub median_extract_us: f64,
    /// 99th percentile of that time, µs.
    pub p99_extract_us: f64,
    /// Spread of re-observations of the same world wall across scans: RMS
    /// perpendicular offset of each observation's midpoint from the wall's
    /// mean line, m.
    pub wall_spread_m: f64,
    /// RMS angle between each re-observation and the wall's mean line, rad.
    pub wall_spread_rad: f64,
    /// World walls seen at least `MIN_REOBSERVATIONS` times (the walls the
    /// spread is computed over).
    pub world_walls: usize,
    /// Observations those world walls gathered.
    pub reobservations: usize,
}

/// A world wall needs this many observations to count in the spread.
pub const MIN_REOBSERVATIONS: usize = 5;

/// Extraction tuned to the SICK scanners of the CARMEN logs (σ ≈ 1.5 cm).
pub(crate) fn laser_for_logs() -> LaserSpec {
    LaserSpec {
        range_sigma_m: 0.015,
        ..LaserSpec::sick_lms291()
    }
}

/// Builds the extractor `kind` for scans of `laser`.
pub fn make_extractor(kind: ExtractorKind, laser: &LaserSpec) -> Result<Box<dyn WallExtractor>> {
    Ok(match kind {
        ExtractorKind::Rwht => Box::new(RwhtExtractor::new(RwhtConfig::for_laser(laser))?),
        ExtractorKind::Ransac => Box::new(RansacExtractor::new(RansacConfig {
            fit: FitConfig::for_laser(laser),
            ..RansacConfig::default()
        })?),
    })
}

#[derive(Serialize)]
struct WallLine<'a> {
    line: usize,
    stamp_s: f64,
    walls: Vec<WallRecord>,
    doors: &'a [DoorOpening],
}

#[derive(Serialize)]
struct WallRecord {
    d_m: f64,
    gamma_rad: f64,
    sigma_d_m: f64,
    sigma_gamma_rad: f64,
    points: usize,
    ends: [[f64; 2]; 2],
}

impl From<&Wall> for WallRecord {
    fn from(w: &Wall) -> Self {
        WallRecord {
            d_m: w.d_m,
            gamma_rad: w.gamma_rad,
            sigma_d_m: w.sigma_d_m(),
            sigma_gamma_rad: w.sigma_gamma_rad(),
            points: w.points,
            ends: w.ends.map(|e| [e.x, e.y]),
        }
    }
}

/// Runs the job; `progress(done, line)` is called after every scan.
pub fn run_walls(job: &WallsJob, mut progress: impl FnMut(usize)) -> Result<WallsReport> {
    let laser = laser_for_logs();
    let mut extractor: Box<dyn WallExtractor> = if job.baseline {
        anyhow::ensure!(
            job.extractor == ExtractorKind::Rwht,
            "--baseline is the RWHT extractor's previous implementation, not {}'s",
            job.extractor
        );
        Box::new(baseline::RwhtExtractor::new(RwhtConfig::for_laser(&laser))?)
    } else {
        make_extractor(job.extractor, &laser)?
    };
    let doors_of: fn(&stucco_core::Scan, &[Wall], &DoorConfig) -> Vec<DoorOpening> = if job.baseline
    {
        baseline::find_doors
    } else {
        find_doors
    };
    let doors_cfg = DoorConfig::for_laser(&laser);
    let reader = open_carmen_file(&job.log)?;
    let mut jsonl = match &job.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            let path = dir.join("walls.jsonl");
            Some(BufWriter::new(
                File::create(&path).with_context(|| format!("creating {}", path.display()))?,
            ))
        }
        None => None,
    };
    let mut points = ScanPoints::default();
    let mut times_us = Vec::new();
    let (mut n_walls, mut n_doors) = (0usize, 0usize);
    let mut map = WorldWalls::default();
    let mut trajectory = Vec::new();
    let mut world_doors = Vec::new();
    for record in reader {
        let LoggedScan {
            line,
            scan,
            laser_pose,
            ..
        } = match record? {
            crate::carmen::Record::Laser(s) => s,
            _ => continue,
        };
        let start = Instant::now();
        points.fill(&scan);
        let walls = extractor.extract(&points);
        let doors = doors_of(&scan, &walls, &doors_cfg);
        times_us.push(start.elapsed().as_secs_f64() * 1e6);
        n_walls += walls.len();
        n_doors += doors.len();
        trajectory.push(laser_pose);
        for w in &walls {
            map.add(&w.transformed(&laser_pose));
        }
        world_doors.extend(doors.iter().map(|d| laser_pose.transform_point(&d.center)));
        if let Some(out) = jsonl.as_mut() {
            let rec = WallLine {
                line,
                stamp_s: scan.stamp.as_secs_f64(),
                walls: walls.iter().map(WallRecord::from).collect(),
                doors: &doors,
            };
            serde_json::to_writer(&mut *out, &rec)?;
            out.write_all(b"\n")?;
        }
        progress(times_us.len());
    }
    if let Some(mut out) = jsonl {
        out.flush()?;
    }
    let scans = times_us.len();
    anyhow::ensure!(
        scans > 0,
        "{}: the log holds no laser scans",
        job.log.display()
    );
    let spread = map.spread();
    if let Some(dir) = &job.out {
        let path = dir.join("walls.svg");
        draw_map(&path, &map, &trajectory, &world_doors)?;
    }
    times_us.sort_by(f64::total_cmp);
    let pct = |q: f64| times_us[((scans - 1) as f64 * q).round() as usize];
    Ok(WallsReport {
        log: job.log.display().to_string(),
        extractor: job.extractor,
        baseline: job.baseline,
        scans,
        walls_per_scan: n_walls as f64 / scans as f64,
        doors_per_scan: n_doors as f64 / scans as f64,
        median_extract_us: pct(0.5),
        p99_extract_us: pct(0.99),
        wall_spread_m: spread.offset_m,
        wall_spread_rad: spread.angle_rad,
        world_walls: spread.walls,
        reobservations: spread.observations,
    })
}

/// Observations of world walls, grouped greedily into the walls they see.
#[derive(Default)]
struct WorldWalls {
    clusters: Vec<Cluster>,
}

struct Cluster {
    gamma: f64,
    d: f64,
    lo: f64,
    hi: f64,
    /// Each observation: its normal angle and the midpoint of its seen part.
    obs: Vec<(f64, Point2<f64>)>,
}

struct Spread {
    offset_m: f64,
    angle_rad: f64,
    walls: usize,
    observations: usize,
}

const SAME_ANGLE_RAD: f64 = 0.05;
const SAME_OFFSET_M: f64 = 0.10;
const GAP_M: f64 = 0.5;

impl WorldWalls {
    fn add(&mut self, w: &Wall) {
        let mid = Point2::from((w.ends[0].coords + w.ends[1].coords) / 2.0);
        let fits = |c: &Cluster| {
            let n = Vector2::new(c.gamma.cos(), c.gamma.sin());
            let u = Vector2::new(-n.y, n.x);
            let (a, b) = (u.dot(&w.ends[0].coords), u.dot(&w.ends[1].coords));
            wrap_angle(w.gamma_rad - c.gamma).abs() < SAME_ANGLE_RAD
                && (n.dot(&mid.coords) - c.d).abs() < SAME_OFFSET_M
                && a.min(b) < c.hi + GAP_M
                && a.max(b) > c.lo - GAP_M
        };
        match self.clusters.iter_mut().find(|c| fits(c)) {
            Some(c) => {
                c.obs.push((w.gamma_rad, mid));
                let k = c.obs.len() as f64;
                c.gamma = wrap_angle(c.gamma + wrap_angle(w.gamma_rad - c.gamma) / k);
                let n = Vector2::new(c.gamma.cos(), c.gamma.sin());
                c.d += (n.dot(&mid.coords) - c.d) / k;
                let u = Vector2::new(-n.y, n.x);
                for e in &w.ends {
                    c.lo = c.lo.min(u.dot(&e.coords));
                    c.hi = c.hi.max(u.dot(&e.coords));
                }
            }
            None => {
                let n = Vector2::new(w.gamma_rad.cos(), w.gamma_rad.sin());
                let u = Vector2::new(-n.y, n.x);
                let (a, b) = (u.dot(&w.ends[0].coords), u.dot(&w.ends[1].coords));
                self.clusters.push(Cluster {
                    gamma: w.gamma_rad,
                    d: n.dot(&mid.coords),
                    lo: a.min(b),
                    hi: a.max(b),
                    obs: vec![(w.gamma_rad, mid)],
                });
            }
        }
    }

    fn spread(&self) -> Spread {
        let (mut s_off, mut s_ang, mut count, mut walls) = (0.0, 0.0, 0usize, 0usize);
        for c in self
            .clusters
            .iter()
            .filter(|c| c.obs.len() >= MIN_REOBSERVATIONS)
        {
            // The wall's mean line: mean angle, then mean offset of the midpoints.
            let k = c.obs.len() as f64;
            let gamma = c.obs.iter().fold(0.0, |s, o| s + wrap_angle(o.0 - c.gamma)) / k + c.gamma;
            let n = Vector2::new(gamma.cos(), gamma.sin());
            let d = c.obs.iter().map(|o| n.dot(&o.1.coords)).sum::<f64>() / k;
            for (g, m) in &c.obs {
                s_off += (n.dot(&m.coords) - d).powi(2);
                s_ang += wrap_angle(g - gamma).powi(2);
            }
            count += c.obs.len();
            walls += 1;
        }
        let rms = |s: f64| {
            if count > 0 {
                (s / count as f64).sqrt()
            } else {
                0.0
            }
        };
        Spread {
            offset_m: rms(s_off),
            angle_rad: rms(s_ang),
            walls,
            observations: count,
        }
    }
}

/// Writes the wall map: world walls seen often enough, the laser's path and
/// the doors found.
fn draw_map(
    path: &Path,
    map: &WorldWalls,
    trajectory: &[Pose2],
    doors: &[Point2<f64>],
) -> Result<()> {
    let mut segments = Vec::new();
    for c in map
        .clusters
        .iter()
        .filter(|c| c.obs.len() >= MIN_REOBSERVATIONS)
    {
        let n = Vector2::new(c.gamma.cos(), c.gamma.sin());
        let u = Vector2::new(-n.y, n.x);
        let a = n * c.d + u * c.lo;
        let b = n * c.d + u * c.hi;
        segments.push(((a.x, a.y), (b.x, b.y), false));
    }
    let laser: Vec<(f64, f64)> = trajectory.iter().map(|p| (p.x, p.y)).collect();
    let marks: Vec<(f64, f64)> = doors.iter().map(|d| (d.x, d.y)).collect();
    draw_plan(
        path,
        "stucco walls: world walls, laser path (blue), doors (red)",
        &segments,
        &[PlanPath {
            points: &laser,
            color: plotters::style::BLUE,
        }],
        &marks,
    )
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn an_extractor_is_spelt_one_way_in_files_and_on_the_command_line() {
        for kind in [ExtractorKind::Rwht, ExtractorKind::Ransac] {
            let name = kind.to_string();
            let json = serde_json::to_string(&kind).unwrap();
            assert_eq!(json, format!("\"{name}\""));
            assert_eq!(serde_json::from_str::<ExtractorKind>(&json).unwrap(), kind);
            let parsed = <ExtractorKind as clap::ValueEnum>::from_str(&name, false).unwrap();
            assert_eq!(parsed, kind);
        }
    }
}
