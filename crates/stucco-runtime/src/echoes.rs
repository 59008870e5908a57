//! What the laser saw and no longer sees: the echoes of recent scans kept
//! in the room frame, so the protective field guards a robot reversing
//! into what is behind it (a laser at the front sees nothing there).
//!
//! Echoes are kept on a grid of [`CELL_M`], for [`KEEP_S`], within
//! [`RADIUS_M`] of the robot, so the memory is bounded by the surfaces
//! around the robot. An echo where a later
//! beam passed through (a person who walked away) is forgotten.
//!
//! An echo of the room's own walls is kept on the wall, where the room
//! filter holds it to the millimetre, not where the laser's range noise
//! scattered it: kept as it came, the memory held for minutes the rare
//! echo that fell 4–9 cm inside a wall, and a way planned to back past
//! that wall with the field's margin stayed blocked (the end walls of
//! generated corridors, seen in their failures). A jog
//! backwards is still stopped by the wall.

use nalgebra::Point2;
use std::collections::BTreeMap;
use stucco_core::{Pose2, Scan, Stamp};

/// The grid an echo is kept on, m.
pub const CELL_M: f64 = 0.05;
/// How long an echo is kept, s: what the laser cannot see again may
/// have gone (a person who walked off), and is forgotten after this.
pub const KEEP_S: f64 = 300.0;
/// How far from the robot an echo is kept, m: a robot reversing at its
/// top speed for a minute gets no nearer to an echo it forgot.
pub const RADIUS_M: f64 = 8.0;
/// How long an echo of something moving (a person walking or waiting,
/// followed as a mover, or touched by the bumper) is kept once the
/// laser no longer sees it, s: long enough for someone the robot backed
/// into to step away, short of a task's patience for a blocked way.
/// Kept for minutes, a person who walked off behind a robot in a corridor
/// held it there.
pub const MOVING_KEEP_S: f64 = 10.0;
/// Scans [`RecentScans`] keeps: half a second of the IBEO's.
pub const RECENT_SCANS: usize = 4;

/// The echoes of recent scans, and those out of the laser's view now.
#[derive(Clone, Debug, Default)]
pub struct EchoMemory {
    /// Each cell's latest echo in the room frame, and when it was seen.
    /// Ordered, so the points handed out are in the same order every run.
    cells: BTreeMap<(i64, i64), Kept>,
    /// The kept echoes the last scan's fan does not cover, in the robot's
    /// frame at that scan.
    unseen: Vec<Point2<f64>>,
}

/// An echo kept: where (room frame), when it was seen, and whether it
/// was of something moving.
#[derive(Clone, Copy, Debug)]
struct Kept {
    at: Point2<f64>,
    seen: Stamp,
    moving: bool,
    /// Touched by the bumper: kept past its time while the robot's rear
    /// axle stays this near it, m (0: not touched).
    near_m: f64,
}

impl EchoMemory {
    /// Forgets everything (the room frame moved).
    pub fn clear(&mut self) {
        self.cells.clear();
        self.unseen.clear();
    }

    /// Takes in a scan: `sensor` is the laser's pose in the room frame and
    /// `pose` the rear axle's, `echoes` the scan's echoes in the sensor's
    /// frame; `wall` places an echo of the room's own walls on the wall
    /// (room frame; `None` for any other echo), and `moving` tells, echo
    /// by echo, those of something moving, kept [`MOVING_KEEP_S`].
    pub fn scan(
        &mut self,
        pose: &Pose2,
        sensor: &Pose2,
        scan: &Scan,
        echoes: &[Point2<f64>],
        wall: impl Fn(&Point2<f64>) -> Option<Point2<f64>>,
        moving: &[bool],
    ) {
        let to_sensor = sensor.inverse();
        let centre = Point2::new(pose.x, pose.y);
        let fan = Fan::of(scan);
        self.cells.retain(|_, k| {
            let keep_s = if k.moving { MOVING_KEEP_S } else { KEEP_S };
            let off = (k.at - centre).norm();
            if (scan.stamp.seconds_since(k.seen) > keep_s && off > k.near_m) || off > RADIUS_M {
                return false;
            }
            // Kept before its wall was known (or better known).
            if let Some(on) = wall(&k.at) {
                k.at = on;
            }
            // A beam that went past the echo: nothing is there now.
            let q = to_sensor.transform_point(&k.at);
            fan.range_at(q.y.atan2(q.x))
                .is_none_or(|range| range <= q.coords.norm() + 2.0 * CELL_M)
        });
        for (k, e) in echoes.iter().enumerate() {
            let p = sensor.transform_point(e);
            let moving = moving.get(k).copied().unwrap_or(false);
            let at = wall(&p).unwrap_or(p);
            let key = (
                (at.x / CELL_M).floor() as i64,
                (at.y / CELL_M).floor() as i64,
            );
            self.cells.insert(
                key,
                Kept {
                    at,
                    seen: scan.stamp,
                    moving,
                    near_m: 0.0,
                },
            );
        }
        let to_robot = pose.inverse();
        self.unseen.clear();
        self.unseen
            .extend(self.cells.values().filter_map(|&Kept { at: p, .. }| {
                let q = to_sensor.transform_point(&p);
                fan.range_at(q.y.atan2(q.x))
                    .is_none()
                    .then(|| to_robot.transform_point(&p))
            }));
    }

    /// Something the bumper touched at `at` (room frame, seen at
    /// `stamp`, the robot at `pose`): kept as the echo of something
    /// moving, out of view until a scan tells otherwise, and for
    /// [`MOVING_KEEP_S`] — or for as long as the robot stays within
    /// `away_m` further of it than it was. Behind the robot nothing tells
    /// that what it touched has gone: forgotten while the robot stood by,
    /// someone cornered behind it was pushed again every
    /// [`MOVING_KEEP_S`] until the touches failed the job, the task never
    /// held long enough to go elsewhere.
    pub fn touched(&mut self, stamp: Stamp, pose: &Pose2, at: &[Point2<f64>], away_m: f64) {
        let to_robot = pose.inverse();
        let centre = Point2::new(pose.x, pose.y);
        for &p in at {
            let key = ((p.x / CELL_M).floor() as i64, (p.y / CELL_M).floor() as i64);
            self.cells.insert(
                key,
                Kept {
                    at: p,
                    seen: stamp,
                    moving: true,
                    near_m: (p - centre).norm() + away_m,
                },
            );
            self.unseen.push(to_robot.transform_point(&p));
        }
    }

    /// The kept echoes out of the laser's view at the last scan, in the
    /// robot's frame then (rear axle at the origin).
    pub fn unseen(&self) -> &[Point2<f64>] {
        &self.unseen
    }

    /// Every echo kept, in the room frame.
    pub fn kept(&self) -> impl Iterator<Item = Point2<f64>> + '_ {
        self.cells.values().map(|k| k.at)
    }

    /// Echoes kept.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// True when nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }
}

/// The last few scans with the laser's pose at each (room frame): where
/// their beams passed, the room was free then. An echo where one of them
/// saw through is of something that moved there since (scan
/// differencing): a person walking, not the room.
#[derive(Clone, Debug)]
pub struct RecentScans {
    /// Each scan with the room frame in the laser's frame then.
    scans: std::collections::VecDeque<(Pose2, Scan)>,
    /// How far beyond an echo the beams of a scan must have reached to
    /// have seen through it, m: its range noise, both ways, and more.
    margin_m: f64,
}

impl RecentScans {
    /// For a laser whose range noise is `range_sigma_m` (σ).
    pub fn new(range_sigma_m: f64) -> Self {
        RecentScans {
            scans: std::collections::VecDeque::new(),
            margin_m: 0.1 + 3.0 * std::f64::consts::SQRT_2 * range_sigma_m,
        }
    }

    /// Forgets every scan (the room frame moved).
    pub fn clear(&mut self) {
        self.scans.clear();
    }

    /// Keeps `scan`, taken with the laser at `sensor` (room frame).
    pub fn push(&mut self, sensor: Pose2, scan: &Scan) {
        if self.scans.len() == RECENT_SCANS {
            self.scans.pop_front();
        }
        self.scans.push_back((sensor.inverse(), scan.clone()));
    }

    /// True when a kept scan saw through `p` (room frame): its beam
    /// toward it and the beams either side reached past it by the margin.
    pub fn saw_through(&self, p: &Point2<f64>) -> bool {
        self.scans.iter().any(|(to_sensor, scan)| {
            let q = to_sensor.transform_point(p);
            let (bearing, range) = (q.y.atan2(q.x), q.coords.norm());
            let step = scan.angle_increment_rad;
            let fan = Fan::of(scan);
            [-step, 0.0, step].iter().all(|d| {
                fan.range_at(bearing + d)
                    .is_some_and(|r| r > range + self.margin_m)
            })
        })
    }
}

/// A scan's fan of beams.
struct Fan<'a> {
    scan: &'a Scan,
}

impl<'a> Fan<'a> {
    fn of(scan: &'a Scan) -> Self {
        Fan { scan }
    }

    /// The range the beam at `bearing` (sensor frame, rad) measured
    /// (infinite when it saw nothing); `None` outside the fan.
    fn range_at(&self, bearing: f64) -> Option<f64> {
        let s = self.scan;
        let n = s.ranges_m.len();
        if n == 0 || s.angle_increment_rad == 0.0 {
            return None;
        }
        let mut k =
            (stucco_core::wrap_angle(bearing - s.angle_min_rad) / s.angle_increment_rad).round();
        // A bearing just short of the first beam wraps to the far end.
        if k < -0.5 {
            k += (std::f64::consts::TAU / s.angle_increment_rad.abs()).round();
        }
        (k >= 0.0 && (k as usize) < n).then(|| s.ranges_m[k as usize])
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A 180° fan ahead (beams every degree), each beam's range given.
    fn scan(at: f64, range: impl Fn(f64) -> f64) -> Scan {
        let inc = 1f64.to_radians();
        let min = -std::f64::consts::FRAC_PI_2;
        Scan {
            stamp: Stamp::from_secs_f64(at),
            sensor: "test".into(),
            angle_min_rad: min,
            angle_increment_rad: inc,
            sweep_duration_s: 0.0,
            max_range_m: 10.0,
            ranges_m: (0..=180).map(|k| range(min + k as f64 * inc)).collect(),
        }
    }

    /// A box seen ahead is remembered once the robot has turned its back
    /// on it, and forgotten when a beam passes where it was.
    #[test]
    fn an_echo_out_of_view_is_kept_until_a_beam_passes_through_it() {
        let mut m = EchoMemory::default();
        let ahead = Pose2::new(1.0, 1.0, 0.0);
        // An echo 1 m ahead.
        let s = scan(0.0, |b| if b.abs() < 1e-9 { 1.0 } else { f64::INFINITY });
        m.scan(&ahead, &ahead, &s, &[Point2::new(1.0, 0.0)], |_| None, &[]);
        assert!(m.unseen().is_empty(), "in view: not handed out");
        // Turned round: the echo is 1 m behind the robot.
        let back = Pose2::new(1.0, 1.0, std::f64::consts::PI);
        m.scan(
            &back,
            &back,
            &scan(1.0, |_| f64::INFINITY),
            &[],
            |_| None,
            &[],
        );
        assert_eq!(m.unseen().len(), 1);
        let p = m.unseen()[0];
        assert!((p.x + 1.0).abs() < 1e-9 && p.y.abs() < 1e-9, "{p}");
        // Turned again, the beam goes past where it was: gone.
        m.scan(&ahead, &ahead, &scan(2.0, |_| 5.0), &[], |_| None, &[]);
        assert!(m.is_empty());
    }

    /// Old echoes and far ones are forgotten: the memory is bounded by the
    /// area round the robot.
    #[test]
    fn old_and_far_echoes_are_forgotten() {
        let mut m = EchoMemory::default();
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let wall: Vec<Point2<f64>> = (0..40)
            .map(|k| Point2::new(0.5, -1.0 + 0.05 * k as f64))
            .collect();
        m.scan(&pose, &pose, &scan(0.0, |_| 0.5), &wall, |_| None, &[]);
        assert_eq!(m.len(), 40);
        let away = Pose2::new(-(RADIUS_M + 2.0), 0.0, std::f64::consts::PI);
        m.scan(
            &away,
            &away,
            &scan(1.0, |_| f64::INFINITY),
            &[],
            |_| None,
            &[],
        );
        assert!(m.is_empty(), "far");
        m.scan(&pose, &pose, &scan(2.0, |_| 0.5), &wall, |_| None, &[]);
        let behind = Pose2::new(0.0, 0.0, std::f64::consts::PI);
        m.scan(
            &behind,
            &behind,
            &scan(2.0 + KEEP_S + 1.0, |_| f64::INFINITY),
            &[],
            |_| None,
            &[],
        );
        assert!(m.is_empty(), "old");
    }

    /// What a scan half a second ago saw through is something that moved
    /// there; a wall, or a post seen from a little further on (its edge
    /// grazed by a beam), is not.
    #[test]
    fn an_echo_where_a_recent_scan_saw_through_is_of_something_moving() {
        let mut recent = RecentScans::new(0.02);
        // A wall 3 m ahead and a post (5 cm wide) 1 m ahead, slightly left.
        // `right`: the laser that far to the right of the first place.
        let post = |right: f64| {
            move |b: f64| {
                let y = b.tan() - right;
                if (0.15..=0.2).contains(&y) {
                    1.0
                } else {
                    3.0 / b.cos()
                }
            }
        };
        let at = Pose2::new(0.0, 0.0, 0.0);
        recent.push(at, &scan(0.0, post(0.0)));
        assert!(!recent.saw_through(&Point2::new(3.0, 0.5)), "the wall");
        assert!(!recent.saw_through(&Point2::new(1.0, 0.17)), "the post");
        // Seen from 10 cm to the right, the post's edge.
        let moved = Pose2::new(0.0, -0.1, 0.0);
        recent.push(moved, &scan(0.125, post(0.1)));
        assert!(!recent.saw_through(&Point2::new(1.0, 0.151)), "its edge");
        // A person stepping into the way 1.5 m ahead: the beams saw the wall.
        assert!(recent.saw_through(&Point2::new(1.5, 0.0)));
        // Four scans on, the first is forgotten.
        for k in 0..RECENT_SCANS {
            recent.push(at, &scan(1.0 + k as f64, |_| 1.4));
        }
        assert!(!recent.saw_through(&Point2::new(1.5, 0.0)));
    }

    /// An echo of something moving is forgotten a few seconds after the
    /// laser stops seeing it; a still one is kept.
    #[test]
    fn a_moving_echo_out_of_view_is_forgotten_after_a_few_seconds() {
        let mut m = EchoMemory::default();
        let ahead = Pose2::new(1.0, 1.0, 0.0);
        let s = scan(0.0, |b| if b.abs() < 0.3 { 1.0 } else { f64::INFINITY });
        let echoes = [Point2::new(1.0, 0.0), Point2::new(1.0, 0.2)];
        m.scan(&ahead, &ahead, &s, &echoes, |_| None, &[false, true]);
        let back = Pose2::new(1.0, 1.0, std::f64::consts::PI);
        let empty = |t: f64| scan(t, |_| f64::INFINITY);
        m.scan(&back, &back, &empty(1.0), &[], |_| None, &[]);
        assert_eq!(m.unseen().len(), 2);
        m.scan(
            &back,
            &back,
            &empty(MOVING_KEEP_S + 0.5),
            &[],
            |_| None,
            &[],
        );
        let kept: Vec<Point2<f64>> = m.kept().collect();
        assert_eq!(kept, vec![Point2::new(2.0, 1.0)], "the still one");
    }

    /// Echoes of the room's walls are kept on the wall, and so are those
    /// kept before the wall was known; a box before the wall where it
    /// stands.
    #[test]
    fn the_rooms_own_walls_are_kept_where_the_wall_is() {
        let mut m = EchoMemory::default();
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let wall_at =
            |p: &Point2<f64>| ((p.x - 1.0).abs() <= 0.06).then_some(Point2::new(1.0, p.y));
        // A wall 1 m ahead, its echoes scattered 5 cm either way, and a
        // box 20 cm before it.
        let echoes: Vec<Point2<f64>> = (0..20)
            .map(|k| Point2::new(1.0 + if k % 2 == 0 { 0.05 } else { -0.05 }, 0.05 * k as f64))
            .chain([Point2::new(0.8, -0.3)])
            .collect();
        m.scan(&pose, &pose, &scan(0.0, |_| 1.0), &echoes, |_| None, &[]);
        let nearest = |m: &EchoMemory| m.kept().map(|p| p.x).fold(f64::INFINITY, f64::min);
        assert!(
            m.kept().filter(|p| p.y >= 0.0).any(|p| p.x < 0.96),
            "the wall not known yet: as the laser saw it"
        );
        m.scan(&pose, &pose, &scan(1.0, |_| 1.0), &echoes, wall_at, &[]);
        assert!(m.kept().filter(|p| p.y >= 0.0).all(|p| p.x == 1.0));
        assert_eq!(nearest(&m), 0.8, "the box");
        assert!(m.kept().filter(|p| p.y >= 0.0).count() >= 20);
    }
}
