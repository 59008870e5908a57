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
//! scattered it: kept as it came, the memory would hold for minutes the
//! one echo in a hundred that fell 4–5 cm inside a wall, and a way
//! planned to back past that wall with the field's margin would stay
//! blocked (measured: the end walls of generated corridors). A jog
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

/// The echoes of recent scans, and those out of the laser's view now.
#[derive(Clone, Debug, Default)]
pub struct EchoMemory {
    /// Each cell's latest echo in the room frame, and when it was seen.
    /// Ordered, so the points handed out are in the same order every run.
    cells: BTreeMap<(i64, i64), (Point2<f64>, Stamp)>,
    /// The kept echoes the last scan's fan does not cover, in the robot's
    /// frame at that scan.
    unseen: Vec<Point2<f64>>,
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
    /// (room frame; `None` for any other echo).
    pub fn scan(
        &mut self,
        pose: &Pose2,
        sensor: &Pose2,
        scan: &Scan,
        echoes: &[Point2<f64>],
        wall: impl Fn(&Point2<f64>) -> Option<Point2<f64>>,
    ) {
        let to_sensor = sensor.inverse();
        let centre = Point2::new(pose.x, pose.y);
        let fan = Fan::of(scan);
        self.cells.retain(|_, (p, seen)| {
            if scan.stamp.seconds_since(*seen) > KEEP_S || (*p - centre).norm() > RADIUS_M {
                return false;
            }
            // Kept before its wall was known (or better known).
            if let Some(on) = wall(p) {
                *p = on;
            }
            // A beam that went past the echo: nothing is there now.
            let q = to_sensor.transform_point(p);
            fan.range_at(q.y.atan2(q.x))
                .is_none_or(|range| range <= q.coords.norm() + 2.0 * CELL_M)
        });
        for e in echoes {
            let p = sensor.transform_point(e);
            let p = wall(&p).unwrap_or(p);
            let key = ((p.x / CELL_M).floor() as i64, (p.y / CELL_M).floor() as i64);
            self.cells.insert(key, (p, scan.stamp));
        }
        let to_robot = pose.inverse();
        self.unseen.clear();
        self.unseen.extend(self.cells.values().filter_map(|(p, _)| {
            let q = to_sensor.transform_point(p);
            fan.range_at(q.y.atan2(q.x))
                .is_none()
                .then(|| to_robot.transform_point(p))
        }));
    }

    /// The kept echoes out of the laser's view at the last scan, in the
    /// robot's frame then (rear axle at the origin).
    pub fn unseen(&self) -> &[Point2<f64>] {
        &self.unseen
    }

    /// Every echo kept, in the room frame.
    pub fn kept(&self) -> impl Iterator<Item = Point2<f64>> + '_ {
        self.cells.values().map(|(p, _)| *p)
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
        m.scan(&ahead, &ahead, &s, &[Point2::new(1.0, 0.0)], |_| None);
        assert!(m.unseen().is_empty(), "in view: not handed out");
        // Turned round: the echo is 1 m behind the robot.
        let back = Pose2::new(1.0, 1.0, std::f64::consts::PI);
        m.scan(&back, &back, &scan(1.0, |_| f64::INFINITY), &[], |_| None);
        assert_eq!(m.unseen().len(), 1);
        let p = m.unseen()[0];
        assert!((p.x + 1.0).abs() < 1e-9 && p.y.abs() < 1e-9, "{p}");
        // Turned again, the beam goes past where it was: gone.
        m.scan(&ahead, &ahead, &scan(2.0, |_| 5.0), &[], |_| None);
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
        m.scan(&pose, &pose, &scan(0.0, |_| 0.5), &wall, |_| None);
        assert_eq!(m.len(), 40);
        let away = Pose2::new(-(RADIUS_M + 2.0), 0.0, std::f64::consts::PI);
        m.scan(&away, &away, &scan(1.0, |_| f64::INFINITY), &[], |_| None);
        assert!(m.is_empty(), "far");
        m.scan(&pose, &pose, &scan(2.0, |_| 0.5), &wall, |_| None);
        let behind = Pose2::new(0.0, 0.0, std::f64::consts::PI);
        m.scan(
            &behind,
            &behind,
            &scan(2.0 + KEEP_S + 1.0, |_| f64::INFINITY),
            &[],
            |_| None,
        );
        assert!(m.is_empty(), "old");
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
        m.scan(&pose, &pose, &scan(0.0, |_| 1.0), &echoes, |_| None);
        let nearest = |m: &EchoMemory| m.kept().map(|p| p.x).fold(f64::INFINITY, f64::min);
        assert!(
            m.kept().filter(|p| p.y >= 0.0).any(|p| p.x < 0.96),
            "the wall not known yet: as the laser saw it"
        );
        m.scan(&pose, &pose, &scan(1.0, |_| 1.0), &echoes, wall_at);
        assert!(m.kept().filter(|p| p.y >= 0.0).all(|p| p.x == 1.0));
        assert_eq!(nearest(&m), 0.8, "the box");
        assert!(m.kept().filter(|p| p.y >= 0.0).count() >= 20);
    }
}
