//! Door openings: runs of consecutive measurements beyond a wall line (paper
//! A §2.2).
//!
//! Every beam crossing a wall's line is classed by where its echo lies
//! relative to the line: on the wall, in front of it (clutter), on a jamb
//! (a little beyond: the wall's thickness, a radiator's wall behind its
//! front), or through it (far beyond, or no echo). An opening is a run of
//! jamb and through beams, with at least `min_beams_through` through beams,
//! between two stretches of wall each at least `min_side_m` long, so a line
//! through furniture legs or a row of radiators is never taken for a door.
//!
//! Each frame lies half a beam step past the last echo on the wall (less
//! the part of the footprint that may overhang the edge); where the beams
//! meet the jamb's face instead (the far frame of an opening seen at an
//! angle), the jamb hits place the frame directly. The angular step and the
//! footprint make a frame's position roughly the sum of two uniform errors,
//! approximated as Gaussian. Only well-fitted walls (enough measurements,
//! residuals no rougher than the range noise allows) are searched, and a
//! person's rounded front never makes a wall there.

use crate::wall::Wall;
use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{BeamWidth, LaserSpec, Scan, Twist2};

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
    /// Echoes up to this far behind the wall line are the wall's own depth
    /// (jambs, what a radiator stands in front of); a beam passes through
    /// the opening only when its echo lies deeper, m.
    pub max_jamb_depth_m: f64,
    /// Length of wall seen on each side of an opening, at least, m.
    pub min_side_m: f64,
    /// ... or this much, when the stretch of wall ends in something nearer
    /// than the wall (the next wall at a corner, an object hiding the rest),
    /// not in free space as the rounded side of a person does, m.
    pub min_closed_side_m: f64,
    /// Walls resting on fewer measurements are not searched for doors.
    pub min_wall_points: usize,
    /// Walls whose measurements scatter about the fitted line more than
    /// this many range sigmas (RMS) are not searched for doors: a line
    /// through the fronts of people or furniture is rougher than a wall.
    pub max_wall_rms_sigmas: f64,
    /// Share of a beam's footprint that must fall on a surface for the echo
    /// to come from it: a beam grazing a door frame reports the frame while
    /// its axis is still up to `(½ − share)` of a footprint inside the
    /// opening, and the frames are placed accordingly.
    pub mixed_echo_fraction: f64,
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
            max_jamb_depth_m: 0.35,
            min_side_m: 0.4,
            min_closed_side_m: 0.2,
            min_wall_points: 20,
            max_wall_rms_sigmas: 1.35,
            mixed_echo_fraction: 1.0 / 3.0,
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
    InFront,
    /// A little beyond the line: the wall's own depth.
    Jamb,
    /// Far beyond the line, or no echo.
    Through,
}

/// One beam crossing a wall's line.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    /// Along-wall coordinate where the beam crosses the line, m.
    t_cross: f64,
    /// Along-wall coordinate of the echo (`t_cross` for no echo), m.
    t_echo: f64,
    class: Hit,
    /// Range to the wall line along the beam, m.
    r_wall: f64,
    /// Cosine of the beam's incidence on the wall.
    cos_inc: f64,
}

/// Open doors in the walls of `scan`, each reported once (on the wall that
/// rests on the most measurements when walls overlap).
pub fn find_doors(scan: &Scan, walls: &[Wall], cfg: &DoorConfig) -> Vec<DoorOpening> {
    find_doors_moving(scan, &Twist2::default(), walls, cfg)
}

thread_local! {
    /// The beams of the scans this thread last searched for doors.
    static BEAMS: std::cell::RefCell<Beams> = std::cell::RefCell::default();
}

/// Each beam's origin and direction in the frame at the stamp, kept for
/// scans of the same geometry swept with the same straight motion.
#[derive(Default)]
struct Beams {
    bearings: crate::points::Bearings,
    /// What the beams were cast for: the scan's geometry (first bearing,
    /// step, beams, sweep time) and the twist; `None` after a turning
    /// sweep, whose beams are not kept.
    key: Option<[u64; 7]>,
    rays: Vec<(Vector2<f64>, Vector2<f64>)>,
    /// Every ray starts at the laser's origin at the stamp.
    from_origin: bool,
    /// Index ranges of the rays to search along one wall.
    near: Vec<std::ops::Range<usize>>,
}

impl Beams {
    /// Casts `scan`'s beams for a laser moving with `twist`, or keeps the
    /// last scan's when they are the same.
    fn cast(&mut self, scan: &Scan, twist: &Twist2) {
        let key = [
            scan.angle_min_rad.to_bits(),
            scan.angle_increment_rad.to_bits(),
            scan.len() as u64,
            scan.sweep_duration_s.to_bits(),
            twist.vx_mps.to_bits(),
            twist.vy_mps.to_bits(),
            twist.omega_radps.to_bits(),
        ];
        if self.key == Some(key) && self.rays.len() == scan.len() {
            return;
        }
        self.rays.clear();
        if twist.omega_radps == 0.0 {
            // Not turning, the laser keeps its heading: each beam's
            // bearing's own sine and cosine, worked out once for scans of
            // its geometry.
            let sin_cos = self.bearings.of(scan);
            self.rays
                .extend(sin_cos.iter().enumerate().map(|(i, &(s, c))| {
                    let at = twist.displacement(scan.beam_time_s(i));
                    (Vector2::new(at.x, at.y), Vector2::new(c, s))
                }));
            self.key = Some(key);
        } else {
            self.rays.extend((0..scan.len()).map(|i| {
                let at = twist.displacement(scan.beam_time_s(i));
                let phi = scan.angle(i) + at.theta;
                (Vector2::new(at.x, at.y), Vector2::new(phi.cos(), phi.sin()))
            }));
            self.key = None;
        }
        self.from_origin = self.rays.iter().all(|(o, _)| o.x == 0.0 && o.y == 0.0);
    }

    /// The index ranges, in order, that hold every ray meeting `wall`'s
    /// line facing it (`cos` of the incidence at least `MIN_COS_INC`)
    /// between `t_lo` and `t_hi` along it: the others would only end the
    /// run of crossings, and need not be cast at all. Rays from the
    /// laser's origin meet the line at `d·tan δ` along it, `δ` the beam's
    /// angle from the wall's normal; the ranges hold the beams within two
    /// steps of the angles that can, far beyond any rounding. All rays
    /// when they do not start at the origin.
    fn near(&mut self, scan: &Scan, wall: &Wall, t_lo: f64, t_hi: f64) {
        self.near.clear();
        let n = self.rays.len();
        let step = scan.angle_increment_rad;
        let usable = self.from_origin
            && step != 0.0
            && step.is_finite()
            && scan.angle_min_rad.is_finite()
            && wall.d_m > 0.0
            && wall.gamma_rad.is_finite()
            && t_lo.is_finite()
            && t_hi.is_finite();
        if !usable {
            self.near.push(0..n);
            return;
        }
        let half = MIN_COS_INC.acos();
        let margin = 2.0 * step.abs() + 1e-6;
        let from = t_lo.atan2(wall.d_m).max(-half) - margin;
        let to = t_hi.atan2(wall.d_m).min(half) + margin;
        if from > to {
            return;
        }
        for turns in -2..=2 {
            let shift = wall.gamma_rad + f64::from(turns) * std::f64::consts::TAU;
            let a = (shift + from - scan.angle_min_rad) / step;
            let b = (shift + to - scan.angle_min_rad) / step;
            let (lo, hi) = (a.min(b).floor() - 1.0, a.max(b).ceil() + 1.0);
            if hi < 0.0 || lo > (n as f64 - 1.0) {
                continue;
            }
            self.near
                .push(lo.max(0.0) as usize..(hi as usize + 1).min(n));
        }
        self.near.sort_by_key(|r| r.start);
        // Touching ranges joined: a run of crossings goes on from one
        // beam to the next.
        let mut merged = 0;
        for k in 1..self.near.len() {
            if self.near[k].start <= self.near[merged].end {
                self.near[merged].end = self.near[merged].end.max(self.near[k].end);
            } else {
                merged += 1;
                self.near[merged] = self.near[k].clone();
            }
        }
        self.near.truncate(merged + 1);
    }
}

/// A beam meeting a wall's line more obliquely than this (cosine of the
/// incidence) crosses it nowhere useful.
const MIN_COS_INC: f64 = 0.05;

/// [`find_doors`] for a laser moving with `twist` (its own frame) during
/// the sweep, with `walls` in its frame at the scan's stamp (as the walls
/// found in deskewed points are): each beam is cast from where the laser
/// was when it fired. At 0.8 m/s an IBEO sweep moves the laser 10 cm; a
/// door's frames read from the raw beams would move with it.
pub fn find_doors_moving(
    scan: &Scan,
    twist: &Twist2,
    walls: &[Wall],
    cfg: &DoorConfig,
) -> Vec<DoorOpening> {
    let searched = |w: &Wall| {
        w.points >= cfg.min_wall_points
            && w.rms_residual_m <= cfg.max_wall_rms_sigmas * cfg.range_sigma_m
    };
    if !walls.iter().any(searched) {
        return Vec::new();
    }
    BEAMS.with_borrow_mut(|beams| {
        beams.cast(scan, twist);
        let mut doors = Vec::new();
        let gate = 3.0 * cfg.range_sigma_m;
        let mut run: Vec<Crossing> = Vec::with_capacity(scan.len());
        let mut order: Vec<usize> = (0..walls.len()).collect();
        order.sort_by_key(|&w| std::cmp::Reverse(walls[w].points));
        for wi in order {
            let wall = &walls[wi];
            if !searched(wall) {
                continue;
            }
            let n = wall.normal();
            let u = wall.direction();
            let t_lo = u.dot(&wall.ends[0].coords) - cfg.max_width_m;
            let t_hi = u.dot(&wall.ends[1].coords) + cfg.max_width_m;
            let flush = |run: &mut Vec<Crossing>, doors: &mut Vec<DoorOpening>| {
                scan_run(run, wi, wall, cfg, doors);
                run.clear();
            };
            beams.near(scan, wall, t_lo, t_hi);
            for range in &beams.near {
                for (i, (origin, dir)) in beams.rays[range.clone()]
                    .iter()
                    .enumerate()
                    .map(|(k, ray)| (range.start + k, ray))
                {
                    let c = dir.dot(&n);
                    // Distance from where the beam starts to the wall's line.
                    let to_line = wall.d_m - n.dot(origin);
                    if c < MIN_COS_INC || to_line <= 0.0 {
                        flush(&mut run, &mut doors);
                        continue;
                    }
                    let r_wall = to_line / c;
                    let t_cross = u.dot(&(origin + dir * r_wall));
                    if t_cross < t_lo || t_cross > t_hi {
                        flush(&mut run, &mut doors);
                        continue;
                    }
                    let r = scan.ranges_m[i];
                    let depth = (r - r_wall) * c;
                    let class = if r.is_finite() && r < r_wall - gate {
                        Hit::InFront
                    } else if r.is_finite() && r <= r_wall + gate {
                        Hit::OnWall
                    } else if r.is_finite() && depth <= cfg.max_jamb_depth_m {
                        Hit::Jamb
                    } else {
                        Hit::Through
                    };
                    let t_echo = if r.is_finite() {
                        u.dot(&(origin + dir * r))
                    } else {
                        t_cross
                    };
                    run.push(Crossing {
                        t_cross,
                        t_echo,
                        class,
                        r_wall,
                        cos_inc: c,
                    });
                }
                // The beams between ranges cross nowhere near: the run ends.
                flush(&mut run, &mut doors);
            }
        }
        doors
    })
}

/// Stray beams through a wall (noise, a mixed echo) that do not end a
/// stretch of it.
const MAX_STRAY_BEAMS: usize = 2;

/// A stretch of wall in a run: beams on the wall from `first` to `last`,
/// with at most `MAX_STRAY_BEAMS` in a row through it, and any number in
/// front of it or within its depth.
#[derive(Clone, Copy, Debug)]
struct Stretch {
    first: usize,
    last: usize,
}

/// Finds the openings between consecutive stretches of wall in a run of
/// beams crossing one wall, and keeps those that look like doors.
fn scan_run(
    run: &[Crossing],
    wi: usize,
    wall: &Wall,
    cfg: &DoorConfig,
    out: &mut Vec<DoorOpening>,
) {
    // Beams in front of the wall hide it without ending it (a table leg
    // before a wall), and so do echoes within the wall's depth (a jamb seen
    // at a slant); beams through it end a stretch after a few strays.
    let mut stretches: Vec<Stretch> = Vec::new();
    let mut strays = 0;
    for (i, c) in run.iter().enumerate() {
        match c.class {
            Hit::OnWall => {
                match stretches.last_mut() {
                    Some(s) if strays <= MAX_STRAY_BEAMS => s.last = i,
                    _ => stretches.push(Stretch { first: i, last: i }),
                }
                strays = 0;
            }
            Hit::InFront | Hit::Jamb => {}
            Hit::Through => strays += 1,
        }
    }
    for pair in stretches.windows(2) {
        if let Some(door) = opening_between(run, pair[0], pair[1], wi, wall, cfg) {
            let duplicate = out
                .iter()
                .any(|d| (d.center - door.center).norm() < 0.5 * cfg.min_width_m);
            if !duplicate {
                out.push(door);
            }
        }
    }
}

/// The opening between two stretches of wall, if it is a door.
fn opening_between(
    run: &[Crossing],
    a: Stretch,
    b: Stretch,
    wi: usize,
    wall: &Wall,
    cfg: &DoorConfig,
) -> Option<DoorOpening> {
    let gap = &run[a.last + 1..b.first];
    // Something in front of the opening may hide part of it (a table leg),
    // but not its frames.
    let frame_hidden = |c: &Crossing| c.class == Hit::InFront;
    if gap.first().is_none_or(frame_hidden) || gap.last().is_none_or(frame_hidden) {
        return None;
    }
    let through: Vec<usize> = (0..gap.len())
        .filter(|&i| gap[i].class == Hit::Through)
        .collect();
    let (&first, &last) = (through.first()?, through.last()?);
    if through.len() < cfg.min_beams_through {
        return None;
    }
    // Wall on both sides, long enough to be a wall and not a leg or a
    // person. A short stretch must end in something nearer (the next wall
    // at a corner, or an object hiding the rest): one that ends with free
    // space behind it is the rounded side of a person or a post.
    let side_ok = |s: Stretch, frame: usize, outside: Option<usize>| {
        let reach = (s.first..=s.last)
            .filter(|&i| run[i].class == Hit::OnWall)
            .map(|i| (run[i].t_echo - run[frame].t_echo).abs())
            .fold(0.0, f64::max);
        let closed = outside.is_some_and(|i| run[i].class == Hit::InFront);
        reach >= cfg.min_side_m || (reach >= cfg.min_closed_side_m && closed)
    };
    let before = side_ok(a, a.last, a.first.checked_sub(1));
    let after = side_ok(b, b.first, Some(b.last + 1).filter(|&i| i < run.len()));
    if !before || !after {
        return None;
    }
    // One frame per side: from the jamb's face where beams hit it, else
    // half a beam step past the last echo on the wall. Jamb
    // echoes spread along the wall are a wall behind something standing in
    // front of it (a radiator), not a jamb: no door there.
    let max_jamb_spread = 0.1f64.max(4.0 * cfg.range_sigma_m);
    let frame = |solid: &Crossing, jambs: &[Crossing], next: &Crossing| {
        let cos_inc = solid.cos_inc;
        if jambs.is_empty() {
            // The edge lies between the last echo on the wall and where the
            // next beam would have met it: half a step on. (The next beam's
            // own crossing is no bound: it may clear the jamb's back edge
            // well inside the opening.)
            let step = next.t_cross - solid.t_cross;
            // Footprint across the beam, stretched along the wall by the incidence.
            let foot = cfg.beam_width.at(solid.r_wall) / cos_inc.max(0.05);
            let mixed = (0.5 - cfg.mixed_echo_fraction).max(0.0) * foot;
            Some((
                solid.t_echo + 0.5 * step - mixed * step.signum(),
                (step * step + foot * foot) / 12.0,
            ))
        } else {
            if jambs.iter().any(frame_hidden) {
                return None;
            }
            let mut t: Vec<f64> = jambs.iter().map(|j| j.t_echo).collect();
            t.sort_by(f64::total_cmp);
            if t[t.len() - 1] - t[0] > max_jamb_spread {
                return None;
            }
            let sin_inc = (1.0 - cos_inc * cos_inc).max(0.0).sqrt();
            let s = cfg.range_sigma_m * sin_inc;
            let foot = cfg.beam_width.at(solid.r_wall);
            Some((
                t[t.len() / 2],
                (s * s + foot * foot / 12.0) / t.len() as f64,
            ))
        }
    };
    let (ta, va) = frame(&run[a.last], &gap[..first], &gap[0])?;
    let (tb, vb) = frame(&run[b.first], &gap[last + 1..], &gap[gap.len() - 1])?;
    let width = (tb - ta).abs();
    let width_sigma = (va + vb).sqrt();
    let frame_sigma = va.max(vb).sqrt();
    // The width gate allows for the measurement's own uncertainty.
    let door_sized = width + 2.0 * width_sigma >= cfg.min_width_m
        && width - 2.0 * width_sigma <= cfg.max_width_m;
    (door_sized && frame_sigma <= cfg.max_frame_sigma_m)
        .then(|| opening(wi, wall, ta.min(tb), ta.max(tb), va + vb))
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
