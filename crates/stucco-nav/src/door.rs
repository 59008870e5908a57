//! Door openings: runs of consecutive measurements beyond a wall line (paper
//! A §2.2). The opening lies between the two door frames, each placed
//! halfway between the last beam on the wall and the first beyond it; the
//! angular step and the beam's footprint make each frame's position roughly
//! the sum of two uniform errors, approximated as Gaussian.

use crate::wall::Wall;
use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{BeamWidth, LaserSpec, Scan};

/// Settings of door detection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DoorConfig {
    /// Narrowest opening taken for a door, m.
    pub min_width_m: f64,
    /// Widest opening taken for a door, m.
    pub max_width_m: f64,
    /// Range noise of the sensor, m: a beam within 3σ of the wall line hits
    /// the wall; farther means beyond (or in front of) it.
    pub range_sigma_m: f64,
    /// Footprint of the beam.
    pub beam_width: BeamWidth,
    /// Openings whose frame positions are less certain than this are not
    /// reported (seen too obliquely or too far away), m.
    pub max_frame_sigma_m: f64,
    /// Fewest beams that must pass through the opening.
    pub min_beams_through: usize,
}

impl Default for DoorConfig {
    fn default() -> Self {
        DoorConfig::for_laser(&LaserSpec::ibeo_ladar_2d())
    }
}

impl DoorConfig {
    /// Door detection tuned to `laser`'s noise and footprint.
    pub fn for_laser(laser: &LaserSpec) -> Self {
        DoorConfig {
            min_width_m: 0.7,
            max_width_m: 1.2,
            range_sigma_m: laser.range_sigma_m,
            beam_width: laser.beam_width,
            max_frame_sigma_m: 0.08,
            min_beams_through: 2,
        }
    }
}

/// An open door seen in one scan, in the sensor frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DoorOpening {
    /// Index of the wall it opens in (into the walls it was searched in).
    pub wall: usize,
    /// Midpoint between the two frames, m.
    pub center: Point2<f64>,
    /// Covariance of `center`, m².
    pub covariance: Matrix2<f64>,
    /// Distance between the frames, m.
    pub width_m: f64,
    /// Standard deviation of the width, m.
    pub width_sigma_m: f64,
    /// The two frames, ordered along the wall's direction.
    pub frames: [Point2<f64>; 2],
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Hit {
    OnWall,
    Beyond,
    InFront,
}

/// Open doors in the walls of `scan`.
pub fn find_doors(scan: &Scan, walls: &[Wall], cfg: &DoorConfig) -> Vec<DoorOpening> {
    let mut doors = Vec::new();
    let gate = 3.0 * cfg.range_sigma_m;
    for (wi, wall) in walls.iter().enumerate() {
        let n = wall.normal();
        let u = wall.direction();
        let t_lo = u.dot(&wall.ends[0].coords) - cfg.max_width_m;
        let t_hi = u.dot(&wall.ends[1].coords) + cfg.max_width_m;
        // (beam, along-wall coordinate of its crossing, class, range to the wall)
        let mut run: Vec<(usize, f64, Hit, f64)> = Vec::new();
        let mut flush = |run: &mut Vec<(usize, f64, Hit, f64)>| {
            scan_run(run, wi, wall, cfg, &mut doors);
            run.clear();
        };
        for i in 0..scan.len() {
            let phi = scan.angle(i);
            let dir = Vector2::new(phi.cos(), phi.sin());
            let c = dir.dot(&n);
            if c < 0.05 {
                flush(&mut run);
                continue;
            }
            let r_wall = wall.d_m / c;
            let t = u.dot(&(dir * r_wall));
            if t < t_lo || t > t_hi {
                flush(&mut run);
                continue;
            }
            let r = scan.ranges_m[i];
            let class = if !r.is_finite() || r > r_wall + gate {
                Hit::Beyond
            } else if r < r_wall - gate {
                Hit::InFront
            } else {
                Hit::OnWall
            };
            run.push((i, t, class, r_wall));
        }
        flush(&mut run);
    }
    doors
}

/// Finds wall–beyond…beyond–wall patterns in a run of consecutive beams
/// crossing one wall.
fn scan_run(
    run: &[(usize, f64, Hit, f64)],
    wi: usize,
    wall: &Wall,
    cfg: &DoorConfig,
    out: &mut Vec<DoorOpening>,
) {
    let mut k = 0;
    while k + 1 < run.len() {
        if !(run[k].2 == Hit::OnWall && run[k + 1].2 == Hit::Beyond) {
            k += 1;
            continue;
        }
        let mut e = k + 1;
        while e < run.len() && run[e].2 == Hit::Beyond {
            e += 1;
        }
        if e < run.len() && run[e].2 == Hit::OnWall && e - (k + 1) >= cfg.min_beams_through {
            let frame = |on: &(usize, f64, Hit, f64), by: &(usize, f64, Hit, f64)| {
                let t = 0.5 * (on.1 + by.1);
                let step = (by.1 - on.1).abs();
                // Footprint across the beam, stretched along the wall by the incidence.
                let cos_inc = wall.d_m / on.3;
                let foot = cfg.beam_width.at(on.3) / cos_inc.max(0.05);
                (t, (step * step + foot * foot) / 12.0)
            };
            let (ta, va) = frame(&run[k], &run[k + 1]);
            let (tb, vb) = frame(&run[e], &run[e - 1]);
            let width = (tb - ta).abs();
            let frame_sigma = va.max(vb).sqrt();
            if width >= cfg.min_width_m
                && width <= cfg.max_width_m
                && frame_sigma <= cfg.max_frame_sigma_m
            {
                out.push(opening(wi, wall, ta.min(tb), ta.max(tb), va + vb));
            }
        }
        k = e;
    }
}

fn opening(wi: usize, wall: &Wall, ta: f64, tb: f64, var_sum: f64) -> DoorOpening {
    let n = wall.normal();
    let u = wall.direction();
    let t = 0.5 * (ta + tb);
    let at = |s: f64| Point2::from(n * wall.d_m + u * s);
    // p(d, γ, t) = d·n(γ) + t·u(γ): ∂p/∂d = n, ∂p/∂γ = d·u − t·n.
    let j = nalgebra::Matrix2::from_columns(&[n, u * wall.d_m - n * t]);
    let along = var_sum / 4.0;
    let covariance = j * wall.covariance * j.transpose() + u * u.transpose() * along;
    DoorOpening {
        wall: wi,
        center: at(t),
        covariance,
        width_m: tb - ta,
        width_sigma_m: var_sum.sqrt(),
        frames: [at(ta), at(tb)],
    }
}
