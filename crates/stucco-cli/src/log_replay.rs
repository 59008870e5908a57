//! `stucco replay LOG`: the map-building EKF ([`WallMapEkf`]) run on a
//! CARMEN log from its odometry and its front laser's scans, the walls of
//! each scan found by the RWHT; the trajectory and the map written out, and
//! with a reference trajectory the relative pose error of the filter and of
//! the odometry it was fed.
//!
//! The filter is moved from scan to scan by the odometry corrected by scan
//! matching ([`LaserOdometry`]: each scan's echoes registered on the last
//! few, the odometry as the prior), then updated by the walls it sees.
//! Walls alone leave the pose to the odometry wherever a scan holds no
//! long wall the map knows, which in the cluttered Intel lab is most of
//! the time (`--no-scan-matching` shows it).
//!
//! The Radish "corrected" logs hold corrected poses only, so their
//! odometry is made worse on purpose with `--odom-noise` (a scale error, a
//! heading drift, random noise: [`OdomNoise`]) and the filter must recover
//! the corrected trajectory. A log with raw odometry (`ODOM` lines, as in
//! `intel.gfs.log.gz`) is replayed with `--odometry odom`.

use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use clap::ValueEnum;
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;
use stucco_core::{Pose2, Stamp, wrap_angle};
use stucco_nav::{
    Displacement, LaserOdometry, LaserOdometryConfig, Pairs, Rpe, ScanPoints, WallMapConfig,
    WallMapEkf, WallRole, relative_pose_error,
};

use crate::carmen::{LaserKind, LoggedScan, OdomRecord, read_carmen_file};
use crate::plan_view::{PlanPath, draw_plan};
use crate::walls::{ExtractorKind, laser_for_logs, make_extractor};

/// Pairs of the relative pose error by default: each pose with the first
/// one at least this far along the reference path, m.
pub const RPE_PAIR_DISTANCE_M: f64 = 1.0;

/// Where the odometry comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum OdometrySource {
    /// The odometry pose written on each laser line (in the corrected logs,
    /// the corrected pose).
    Scan,
    /// The log's `ODOM` lines, interpolated at each scan's stamp.
    Odom,
}

/// Where the reference trajectory comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// None: no error is computed.
    None,
    /// The robot poses written on the log's own laser lines.
    FromLog,
    /// The robot poses of another log's laser lines, matched by stamp.
    Log(PathBuf),
}

/// Odometry made worse on purpose: each step between two scans is
/// lengthened by `scale`, turned by `drift_deg_per_m` per metre travelled
/// (unequal wheels), and blurred by Gaussian noise growing with the square
/// root of the distance. Written `scale=0.02,drift_deg_per_m=1,…`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OdomNoise {
    /// Relative error of the distance travelled.
    pub scale: f64,
    /// Heading error per metre travelled, degrees.
    pub drift_deg_per_m: f64,
    /// Standard deviation of the position noise per √m travelled, m.
    pub trans_sigma_m: f64,
    /// Standard deviation of the heading noise per √m travelled, degrees.
    pub rot_sigma_deg: f64,
    /// Seed of the noise.
    pub seed: u64,
}

const NOISE_KEYS: &str = "scale, drift_deg_per_m, trans_sigma_m, rot_sigma_deg, seed";

impl FromStr for OdomNoise {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut noise = OdomNoise {
            scale: 0.0,
            drift_deg_per_m: 0.0,
            trans_sigma_m: 0.0,
            rot_sigma_deg: 0.0,
            seed: 0,
        };
        for item in s.split(',').filter(|i| !i.trim().is_empty()) {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| format!("`{item}`: expected key=value (keys: {NOISE_KEYS})"))?;
            let (key, value) = (key.trim(), value.trim());
            let number = || {
                value
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("`{key}`: `{value}` is not a number"))
            };
            match key {
                "scale" => noise.scale = number()?,
                "drift_deg_per_m" => noise.drift_deg_per_m = number()?,
                "trans_sigma_m" => noise.trans_sigma_m = number()?.abs(),
                "rot_sigma_deg" => noise.rot_sigma_deg = number()?.abs(),
                "seed" => {
                    noise.seed = value
                        .parse()
                        .map_err(|_| format!("`seed`: `{value}` is not a whole number"))?
                }
                _ => return Err(format!("unknown key `{key}` (keys: {NOISE_KEYS})")),
            }
        }
        Ok(noise)
    }
}

impl fmt::Display for OdomNoise {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "scale={},drift_deg_per_m={},trans_sigma_m={},rot_sigma_deg={},seed={}",
            self.scale, self.drift_deg_per_m, self.trans_sigma_m, self.rot_sigma_deg, self.seed
        )
    }
}

/// How much the filter trusts the odometry between two scans: standard
/// deviations growing with the distance travelled and the turn, above a
/// floor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OdometryTrust {
    /// Along the motion, per metre, m/m.
    pub along_per_m: f64,
    /// Across the motion, per metre, m/m.
    pub across_per_m: f64,
    /// Heading, per metre travelled, rad/m.
    pub heading_per_m: f64,
    /// Heading, per radian turned.
    pub heading_per_rad: f64,
    /// Floor of the position's standard deviation, m.
    pub floor_m: f64,
    /// Floor of the heading's standard deviation, rad.
    pub floor_rad: f64,
}

impl Default for OdometryTrust {
    fn default() -> Self {
        OdometryTrust {
            along_per_m: 0.05,
            across_per_m: 0.03,
            heading_per_m: 2f64.to_radians(),
            heading_per_rad: 0.05,
            floor_m: 0.005,
            floor_rad: 0.25f64.to_radians(),
        }
    }
}

impl OdometryTrust {
    /// The displacement `step` with its covariance.
    fn displacement(&self, step: Pose2, since: Stamp, until: Stamp) -> Displacement {
        let dist = step.x.hypot(step.y);
        let sd = Vector3::new(
            self.along_per_m * dist + self.floor_m,
            self.across_per_m * dist + self.floor_m,
            self.heading_per_m * dist + self.heading_per_rad * step.theta.abs() + self.floor_rad,
        );
        Displacement {
            since,
            until,
            pose: step,
            covariance: Matrix3::from_diagonal(&sd.component_mul(&sd)),
        }
    }
}

/// What `stucco replay` is asked to do.
#[derive(Clone, Debug)]
pub struct LogReplayJob {
    /// The CARMEN log.
    pub log: PathBuf,
    /// The reference trajectory.
    pub reference: Reference,
    /// Where the odometry comes from.
    pub odometry: OdometrySource,
    /// Odometry made worse on purpose, if at all.
    pub odom_noise: Option<OdomNoise>,
    /// Where to write `trajectory.csv`, `map.json` and `map.svg`.
    pub out: Option<PathBuf>,
    /// How far apart along the reference path the poses of each RPE pair
    /// are, m.
    pub rpe_distance_m: f64,
    /// Whether the odometry is corrected by scan matching
    /// ([`LaserOdometry`]) before it moves the filter; without it, only the
    /// walls do.
    pub scan_matching: bool,
}

/// What `stucco replay --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct LogReplayReport {
    /// The log replayed.
    pub log: String,
    /// Front-laser scans used.
    pub scans: usize,
    /// Where the odometry came from.
    pub odometry: OdometrySource,
    /// The noise added to it, as given to `--odom-noise`.
    pub odom_noise: Option<String>,
    /// How far apart the poses of each RPE pair are along the reference, m.
    pub rpe_pair_distance_m: f64,
    /// Relative pose error of the filter's trajectory against the reference.
    pub rpe: Option<Rpe>,
    /// Relative pose error of the odometry fed to the filter, against the
    /// same reference.
    pub odom_rpe: Option<Rpe>,
    /// Walls in the final map.
    pub map_walls: usize,
    /// Of those, walls of the building (not standing in front of one).
    pub building_walls: usize,
    /// Mean observations matched per scan.
    pub matched_per_scan: f64,
    /// Mean observations discarded as doubtful per scan.
    pub doubtful_per_scan: f64,
    /// Mean walls found per scan.
    pub walls_per_scan: f64,
    /// Whether scan matching corrected the odometry.
    pub scan_matching: bool,
    /// Share of the scans (after the first) registered on a keyframe.
    pub scans_matched_share: f64,
    /// Walls that joined the map.
    pub walls_added: usize,
    /// Pairs of map walls merged into one.
    pub walls_merged: usize,
    /// Median time of one scan (extraction, classification, update), µs.
    pub median_scan_us: f64,
    /// 99th percentile of that time, µs.
    pub p99_scan_us: f64,
}

/// The odometry pose at `t`, interpolated in `odom` (sorted by stamp).
fn odometry_at(odom: &[OdomRecord], t: Stamp) -> Option<Pose2> {
    let k = odom.partition_point(|o| o.stamp <= t);
    let (a, b) = match (k.checked_sub(1).map(|i| &odom[i]), odom.get(k)) {
        (Some(a), Some(b)) => (a, b),
        (Some(a), None) => return Some(a.pose),
        (None, Some(b)) => return Some(b.pose),
        (None, None) => return None,
    };
    let span = b.stamp.seconds_since(a.stamp);
    let f = if span > 0.0 {
        (t.seconds_since(a.stamp) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    Some(Pose2::new(
        a.pose.x + f * (b.pose.x - a.pose.x),
        a.pose.y + f * (b.pose.y - a.pose.y),
        wrap_angle(a.pose.theta + f * wrap_angle(b.pose.theta - a.pose.theta)),
    ))
}

/// The front-laser scans and the `ODOM` readings (by stamp) of a log.
fn read_log(path: &Path) -> Result<(Vec<LoggedScan>, Vec<OdomRecord>)> {
    let mut log = read_carmen_file(path)?;
    log.scans.retain(|s| s.kind != LaserKind::Rear);
    ensure!(
        !log.scans.is_empty(),
        "{}: the log holds no front-laser scans",
        path.display()
    );
    log.odometry.sort_by_key(|o| o.stamp);
    Ok((log.scans, log.odometry))
}

/// `odometry` made worse by `noise`, step by step.
fn degrade(odometry: &[Pose2], noise: &OdomNoise) -> Vec<Pose2> {
    let mut rng = ChaCha8Rng::seed_from_u64(noise.seed);
    let mut out = Vec::with_capacity(odometry.len());
    let Some(&first) = odometry.first() else {
        return out;
    };
    let mut at = first;
    out.push(at);
    for pair in odometry.windows(2) {
        let step = pair[0].inverse() * pair[1];
        let dist = step.x.hypot(step.y);
        let root = dist.sqrt();
        let mut g = || -> f64 { StandardNormal.sample(&mut rng) };
        let noisy = Pose2::new(
            step.x * (1.0 + noise.scale) + noise.trans_sigma_m * root * g(),
            step.y * (1.0 + noise.scale) + noise.trans_sigma_m * root * g(),
            step.theta
                + (noise.drift_deg_per_m * dist + noise.rot_sigma_deg * root * g()).to_radians(),
        );
        at = at * noisy;
        out.push(at);
    }
    out
}

/// The reference pose of each of `scans`.
fn reference_poses(reference: &Reference, scans: &[LoggedScan]) -> Result<Option<Vec<Pose2>>> {
    match reference {
        Reference::None => Ok(None),
        Reference::FromLog => Ok(Some(scans.iter().map(|s| s.robot_pose).collect())),
        Reference::Log(path) => {
            let (other, _) = read_log(path)?;
            let mut poses = Vec::with_capacity(scans.len());
            for s in scans {
                let k = other.partition_point(|o| o.scan.stamp < s.scan.stamp);
                let apart = |o: &LoggedScan| o.scan.stamp.seconds_since(s.scan.stamp).abs();
                let near = [k.checked_sub(1), Some(k)]
                    .into_iter()
                    .flatten()
                    .filter_map(|i| other.get(i))
                    .min_by(|a, b| apart(a).total_cmp(&apart(b)));
                match near {
                    Some(o) if apart(o) < 0.005 => poses.push(o.robot_pose),
                    _ => bail!(
                        "{}: no scan within 5 ms of the scan on line {} (stamp {} s)",
                        path.display(),
                        s.line,
                        s.scan.stamp
                    ),
                }
            }
            Ok(Some(poses))
        }
    }
}

/// Runs the job; `progress(done, total)` after every scan.
pub fn run_log_replay(
    job: &LogReplayJob,
    mut progress: impl FnMut(usize, usize),
) -> Result<LogReplayReport> {
    let (scans, odom) = read_log(&job.log)?;
    let raw: Vec<Pose2> = match job.odometry {
        OdometrySource::Scan => scans.iter().map(|s| s.odom_pose).collect(),
        OdometrySource::Odom => {
            ensure!(
                !odom.is_empty(),
                "{}: --odometry odom, but the log has no ODOM lines",
                job.log.display()
            );
            scans
                .iter()
                .map(|s| odometry_at(&odom, s.scan.stamp).unwrap_or(s.odom_pose))
                .collect()
        }
    };
    let odometry = match &job.odom_noise {
        Some(n) => degrade(&raw, n),
        None => raw,
    };
    let reference = reference_poses(&job.reference, &scans)?;
    let mount = scans[0].robot_pose.inverse() * scans[0].laser_pose;
    let start = reference.as_ref().map_or(odometry[0], |r| r[0]);
    let mut filter = WallMapEkf::new(
        WallMapConfig {
            laser_mount: mount,
            // Walls re-observed in these logs scatter by 2.8–3.4 cm and
            // 0.66–0.75° about their mean line (`stucco walls`: clutter,
            // the corrected poses' own error); the fits' covariances do not
            // know it.
            min_sigma_d_m: 0.03,
            min_sigma_gamma_rad: 1f64.to_radians(),
            ..WallMapConfig::default()
        },
        start,
        Matrix3::zeros(),
    );
    let trust = OdometryTrust::default();
    let mut laser_odometry = LaserOdometry::new(LaserOdometryConfig::default(), mount);
    let mut registered = 0usize;
    let mut extractor = make_extractor(ExtractorKind::Rwht, &laser_for_logs())?;
    let mut points = ScanPoints::default();
    let mut estimate = Vec::with_capacity(scans.len());
    let mut times_us = Vec::with_capacity(scans.len());
    let (mut matched, mut doubtful, mut found, mut added, mut merged) = (0, 0, 0, 0, 0);
    for (i, s) in scans.iter().enumerate() {
        let started = Instant::now();
        points.fill(&s.scan);
        let wheels = if i > 0 {
            let step = odometry[i - 1].inverse() * odometry[i];
            trust.displacement(step, scans[i - 1].scan.stamp, s.scan.stamp)
        } else {
            Displacement::zero(s.scan.stamp)
        };
        let moved = if job.scan_matching {
            let step = laser_odometry.step(points.points().iter().map(|p| p.p), &wheels);
            registered += usize::from(step.matched.is_some());
            step.displacement
        } else {
            wheels
        };
        if i > 0 {
            filter.predict(&moved);
        }
        let walls = extractor.extract(&points);
        let update = filter.scan(&walls);
        times_us.push(started.elapsed().as_secs_f64() * 1e6);
        matched += update.matched.len();
        doubtful += update.doubtful.len();
        found += walls.len();
        added += update.added.len();
        merged += update.merged.len();
        estimate.push(filter.pose());
        progress(i + 1, scans.len());
    }
    let (rpe, odom_rpe) = match &reference {
        Some(r) => (
            relative_pose_error(&estimate, r, Pairs::Distance(job.rpe_distance_m)),
            relative_pose_error(&odometry, r, Pairs::Distance(job.rpe_distance_m)),
        ),
        None => (None, None),
    };
    if let Some(dir) = &job.out {
        write_outputs(
            dir,
            &scans,
            &estimate,
            &odometry,
            reference.as_deref(),
            &filter,
        )?;
    }
    times_us.sort_by(f64::total_cmp);
    let n = scans.len();
    let pct = |q: f64| times_us[((n - 1) as f64 * q).round() as usize];
    let map = filter.map();
    Ok(LogReplayReport {
        log: job.log.display().to_string(),
        scans: n,
        odometry: job.odometry,
        odom_noise: job.odom_noise.map(|n| n.to_string()),
        rpe_pair_distance_m: job.rpe_distance_m,
        rpe,
        odom_rpe,
        map_walls: map.walls.len(),
        building_walls: map.building_walls().count(),
        matched_per_scan: matched as f64 / n as f64,
        doubtful_per_scan: doubtful as f64 / n as f64,
        walls_per_scan: found as f64 / n as f64,
        scan_matching: job.scan_matching,
        scans_matched_share: registered as f64 / n.saturating_sub(1).max(1) as f64,
        walls_added: added,
        walls_merged: merged,
        median_scan_us: pct(0.5),
        p99_scan_us: pct(0.99),
    })
}

/// `trajectory.csv`, `map.json` and `map.svg` in `dir`.
fn write_outputs(
    dir: &Path,
    scans: &[LoggedScan],
    estimate: &[Pose2],
    odometry: &[Pose2],
    reference: Option<&[Pose2]>,
    filter: &WallMapEkf,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join("trajectory.csv");
    let mut csv = BufWriter::new(
        File::create(&path).with_context(|| format!("creating {}", path.display()))?,
    );
    writeln!(
        csv,
        "line,stamp_s,x_m,y_m,theta_rad,odom_x_m,odom_y_m,odom_theta_rad,ref_x_m,ref_y_m,ref_theta_rad"
    )?;
    for (i, s) in scans.iter().enumerate() {
        let (e, o) = (estimate[i], odometry[i]);
        let r = reference.map_or(String::from(",,"), |r| {
            format!("{},{},{}", r[i].x, r[i].y, r[i].theta)
        });
        writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{r}",
            s.line,
            s.scan.stamp.as_secs_f64(),
            e.x,
            e.y,
            e.theta,
            o.x,
            o.y,
            o.theta
        )?;
    }
    csv.flush()?;
    let map = filter.map();
    let path = dir.join("map.json");
    std::fs::write(&path, serde_json::to_vec_pretty(&map)?)
        .with_context(|| format!("writing {}", path.display()))?;
    let segments: Vec<_> = map
        .walls
        .iter()
        .map(|w| {
            let [a, b] = w.ends();
            ((a.x, a.y), (b.x, b.y), w.role != WallRole::Wall)
        })
        .collect();
    let xy = |p: &[Pose2]| p.iter().map(|q| (q.x, q.y)).collect::<Vec<_>>();
    let (est, odo) = (xy(estimate), xy(odometry));
    let refp = reference.map(xy).unwrap_or_default();
    draw_plan(
        &dir.join("map.svg"),
        "stucco replay: walls (grey: in front of a wall), filter (blue), odometry (red), reference (green)",
        &segments,
        &[
            PlanPath {
                points: &odo,
                color: plotters::style::RED,
            },
            PlanPath {
                points: &refp,
                color: plotters::style::GREEN,
            },
            PlanPath {
                points: &est,
                color: plotters::style::BLUE,
            },
        ],
        &[],
    )
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn odometry_noise_is_read_with_its_keys_and_refused_with_a_reason() {
        let n: OdomNoise =
            "scale=0.02, drift_deg_per_m=1,trans_sigma_m=0.01,rot_sigma_deg=0.5,seed=3"
                .parse()
                .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            n,
            OdomNoise {
                scale: 0.02,
                drift_deg_per_m: 1.0,
                trans_sigma_m: 0.01,
                rot_sigma_deg: 0.5,
                seed: 3
            }
        );
        assert_eq!(n.to_string().parse::<OdomNoise>(), Ok(n));
        let bad = "scale=0.02,drift=1".parse::<OdomNoise>().unwrap_err();
        assert!(
            bad.contains("unknown key `drift`") && bad.contains("drift_deg_per_m"),
            "{bad}"
        );
        let bad = "scale=lots".parse::<OdomNoise>().unwrap_err();
        assert!(bad.contains("`scale`: `lots` is not a number"), "{bad}");
    }

    #[test]
    fn degraded_odometry_drifts_as_specified() {
        // 10 m straight in 1 m steps, 2 % long and drifting 1°/m, no noise.
        let straight: Vec<Pose2> = (0..=10).map(|i| Pose2::new(i as f64, 0.0, 0.0)).collect();
        let noise = OdomNoise {
            scale: 0.02,
            drift_deg_per_m: 1.0,
            trans_sigma_m: 0.0,
            rot_sigma_deg: 0.0,
            seed: 0,
        };
        let bent = degrade(&straight, &noise);
        assert!((bent[10].theta - 10f64.to_radians()).abs() < 1e-12);
        let travelled: f64 = bent
            .windows(2)
            .map(|p| (p[1].position() - p[0].position()).norm())
            .sum();
        assert!((travelled - 10.2).abs() < 1e-9, "{travelled}");
    }

    #[test]
    fn odometry_is_interpolated_between_readings() {
        let rec = |t: f64, x: f64, th: f64| OdomRecord {
            line: 0,
            stamp: Stamp::from_secs_f64(t),
            pose: Pose2::new(x, 0.0, th),
            tv_mps: 0.0,
            rv_radps: 0.0,
            accel_mps2: 0.0,
        };
        let odom = [rec(1.0, 0.0, 3.0), rec(2.0, 1.0, -3.0)];
        let mid = odometry_at(&odom, Stamp::from_secs_f64(1.5)).unwrap_or(Pose2::IDENTITY);
        assert!((mid.x - 0.5).abs() < 1e-9);
        // Across ±π the heading takes the short way.
        assert!(
            (mid.theta.abs() - std::f64::consts::PI).abs() < 0.2,
            "{mid:?}"
        );
        assert_eq!(
            odometry_at(&odom, Stamp::from_secs_f64(5.0)),
            Some(odom[1].pose)
        );
    }
}
