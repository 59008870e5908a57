//! The laws. Poses are the rear axle's, in whatever frame the reference is
//! given in; angles counter-clockwise.

use serde::{Deserialize, Serialize};
use stucco_core::{DriveCommand, Pose2, wrap_angle};

/// Gains of the line-following law by speed, interpolated linearly.
///
/// On the kinematic tricycle the law gives `ë + (v(1+k2)/L)ė + (v²k1/L)e
/// = 0` for small errors: in distance travelled the response does not
/// depend on the speed, but the steering rate it needs grows with it, so
/// the gains soften as the speed rises. The defaults damp at ζ ≈ 0.9 for
/// a 0.6 m wheelbase and settle within about 1.3 m of travel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GainSchedule {
    /// Speeds the gains are given at, m/s, increasing.
    pub speeds_mps: Vec<f64>,
    /// `k1` at each speed, 1/m.
    pub k1: Vec<f64>,
    /// `k2` at each speed.
    pub k2: Vec<f64>,
}

impl Default for GainSchedule {
    fn default() -> Self {
        GainSchedule {
            speeds_mps: vec![0.2, 0.5, 0.8],
            k1: vec![7.0, 6.0, 5.5],
            k2: vec![2.69, 2.42, 2.27],
        }
    }
}

impl GainSchedule {
    /// `(k1, k2)` at `speed_mps`.
    pub fn at(&self, speed_mps: f64) -> (f64, f64) {
        let v = speed_mps.abs();
        let s = &self.speeds_mps;
        let n = s.len().min(self.k1.len()).min(self.k2.len());
        if n == 0 {
            return (1.0, 0.5);
        }
        if v <= s[0] {
            return (self.k1[0], self.k2[0]);
        }
        for i in 1..n {
            if v <= s[i] {
                let f = (v - s[i - 1]) / (s[i] - s[i - 1]);
                return (
                    self.k1[i - 1] + f * (self.k1[i] - self.k1[i - 1]),
                    self.k2[i - 1] + f * (self.k2[i] - self.k2[i - 1]),
                );
            }
        }
        (self.k1[n - 1], self.k2[n - 1])
    }
}

/// Follows a straight line: the papers' law.
#[derive(Clone, Debug, PartialEq)]
pub struct LineFollower {
    gains: GainSchedule,
}

impl LineFollower {
    /// The law with `gains`.
    pub fn new(gains: GainSchedule) -> Self {
        LineFollower { gains }
    }

    /// The steering angle for a rear axle `offset_m` to the left of the
    /// line, heading `heading_rad` relative to it, at `speed_mps`.
    pub fn steer(&self, offset_m: f64, heading_rad: f64, speed_mps: f64) -> f64 {
        let (k1, k2) = self.gains.at(speed_mps);
        -(k1 * offset_m + k2 * heading_rad.sin()).atan() - heading_rad
    }

    /// The steering angle to follow the line through `origin` along its
    /// heading, for a robot at `pose` (same frame).
    pub fn steer_to_line(&self, pose: &Pose2, origin: &Pose2, speed_mps: f64) -> f64 {
        let rel = origin.inverse() * *pose;
        self.steer(rel.y, rel.theta, speed_mps)
    }
}

/// Keeps to the middle of a corridor seen as two walls.
#[derive(Clone, Debug, PartialEq)]
pub struct CorridorCentring {
    law: LineFollower,
}

impl CorridorCentring {
    /// The law with `gains`.
    pub fn new(gains: GainSchedule) -> Self {
        CorridorCentring {
            law: LineFollower::new(gains),
        }
    }

    /// The steering angle from the two walls as seen from the rear axle:
    /// distances to the left and right walls, m, and the corridor's
    /// direction relative to the robot's heading, rad (from the walls'
    /// normals).
    pub fn steer(
        &self,
        left_m: f64,
        right_m: f64,
        corridor_heading_rad: f64,
        speed_mps: f64,
    ) -> f64 {
        // Offset to the left of the middle; heading relative to the corridor.
        let offset = 0.5 * (right_m - left_m);
        self.law.steer(offset, -corridor_heading_rad, speed_mps)
    }
}

/// Which side a followed wall is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallSide {
    /// The wall is on the robot's left.
    Left,
    /// The wall is on the robot's right.
    Right,
}

/// Follows a wall at a standoff: the plastering robot's main motion.
#[derive(Clone, Debug, PartialEq)]
pub struct WallFollower {
    law: LineFollower,
    /// Which side the wall is on.
    pub side: WallSide,
    /// Distance to keep from the wall, m.
    pub standoff_m: f64,
    /// Steepest angle the law heads toward the standoff line from far off
    /// it, rad: the body's front corner must not dive at the wall (or a
    /// radiator on it) while the robot settles on its standoff.
    pub max_approach_rad: f64,
}

impl WallFollower {
    /// The law keeping `standoff_m` from a wall on `side`, approaching it
    /// at 20° at most.
    pub fn new(gains: GainSchedule, side: WallSide, standoff_m: f64) -> Self {
        WallFollower {
            law: LineFollower::new(gains),
            side,
            standoff_m,
            max_approach_rad: 20f64.to_radians(),
        }
    }

    /// The steering angle from the wall `(d, γ)` as seen from the rear
    /// axle (the line `n(γ)·p = d`).
    pub fn steer(&self, d_m: f64, gamma_rad: f64, speed_mps: f64) -> f64 {
        // The wall runs along the robot when γ = ±π/2 (left: +π/2).
        let (sign, along) = match self.side {
            WallSide::Left => (-1.0, std::f64::consts::FRAC_PI_2),
            WallSide::Right => (1.0, -std::f64::consts::FRAC_PI_2),
        };
        let heading = wrap_angle(along - gamma_rad);
        // Offset to the left of the line at the standoff: farther than the
        // standoff from a wall on the left is to the line's right. Far off
        // the line, the law sees no more offset than holds it heading in at
        // `max_approach_rad` (where its steering is zero:
        // k1·y + k2·sin θ = tan θ).
        let (k1, k2) = self.law.gains.at(speed_mps);
        let a = self.max_approach_rad;
        let cap = (a.tan() + k2 * a.sin()) / k1.max(1e-9);
        let offset = (sign * (d_m - self.standoff_m)).clamp(-cap, cap);
        self.law.steer(offset, heading, speed_mps)
    }
}

/// Deceleration the laws plan their stops with, m/s²: half what the
/// drive can brake, so the wheel is sure to follow.
pub const STOP_DECEL_MPS2: f64 = 0.4;

/// The speed `to_go_m` short of a stop: cruising, until braking at
/// `decel_mps2` from here would just stop on the spot (v = √(2·a·d)),
/// and never under a twentieth of cruising (the last millimetres).
pub fn stopping_speed(cruise_mps: f64, to_go_m: f64, decel_mps2: f64) -> f64 {
    (2.0 * decel_mps2 * to_go_m.max(0.0))
        .sqrt()
        .min(cruise_mps)
        .max(0.05 * cruise_mps)
}

/// Reaches a goal pose: follows the line through the goal along its
/// heading, braking evenly near it, and stops there.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseRegulator {
    law: LineFollower,
    /// Cruising speed, m/s.
    pub speed_mps: f64,
    /// Deceleration it stops with, m/s².
    pub decel_mps2: f64,
    /// Close enough, m.
    pub tolerance_m: f64,
}

impl PoseRegulator {
    /// The law at `speed_mps`.
    pub fn new(gains: GainSchedule, speed_mps: f64) -> Self {
        PoseRegulator {
            law: LineFollower::new(gains),
            speed_mps,
            decel_mps2: STOP_DECEL_MPS2,
            tolerance_m: 0.002,
        }
    }

    /// The command for a robot at `pose` going to `goal`; stops once the
    /// goal is reached (or passed along its heading).
    pub fn command(&self, pose: &Pose2, goal: &Pose2) -> DriveCommand {
        let rel = goal.inverse() * *pose;
        let to_go = -rel.x;
        if to_go <= self.tolerance_m {
            return DriveCommand::STOP;
        }
        let speed = stopping_speed(self.speed_mps, to_go, self.decel_mps2);
        DriveCommand {
            speed_mps: speed,
            steer_rad: self.law.steer(rel.y, rel.theta, speed),
        }
    }
}

/// Follows a path of straight segments through waypoints.
#[derive(Clone, Debug, PartialEq)]
pub struct PathFollower {
    law: LineFollower,
    points: Vec<[f64; 2]>,
    segment: usize,
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Switch to the next segment this far before the corner, m.
    pub switch_m: f64,
}

impl PathFollower {
    /// Following the open path through `points` at `speed_mps`.
    pub fn new(gains: GainSchedule, points: Vec<[f64; 2]>, speed_mps: f64) -> Self {
        PathFollower {
            law: LineFollower::new(gains),
            points,
            segment: 0,
            speed_mps,
            switch_m: 0.4,
        }
    }

    /// The segment being followed.
    pub fn segment(&self) -> usize {
        self.segment
    }

    /// The command for a robot at `pose`; stops at the path's end.
    pub fn command(&mut self, pose: &Pose2) -> DriveCommand {
        loop {
            let (Some(a), Some(b)) = (
                self.points.get(self.segment),
                self.points.get(self.segment + 1),
            ) else {
                return DriveCommand::STOP;
            };
            let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
            let end = Pose2::new(b[0], b[1], heading);
            let rel = end.inverse() * *pose;
            let last = self.segment + 2 >= self.points.len();
            let remaining = -rel.x;
            if (!last && remaining < self.switch_m) || (last && remaining <= 0.002) {
                self.segment += 1;
                continue;
            }
            let speed = if last {
                stopping_speed(self.speed_mps, remaining, STOP_DECEL_MPS2)
            } else {
                self.speed_mps
            };
            return DriveCommand {
                speed_mps: speed,
                steer_rad: self.law.steer(rel.y, rel.theta, speed),
            };
        }
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use crate::Limiter;
    use stucco_core::VehicleSpec;

    /// The kinematic tricycle, the rear axle's pose, 10 ms steps.
    fn step(pose: &mut Pose2, cmd: &DriveCommand, spec: &VehicleSpec, dt: f64) {
        let v = cmd.speed_mps * cmd.steer_rad.cos();
        let w = cmd.speed_mps * cmd.steer_rad.sin() / spec.wheelbase_m;
        *pose = *pose * stucco_core::Twist2::new(v, 0.0, w).displacement(dt);
    }

    fn drive(
        start: Pose2,
        seconds: f64,
        mut law: impl FnMut(&Pose2) -> DriveCommand,
    ) -> Vec<Pose2> {
        let spec = VehicleSpec::default();
        let mut limiter = Limiter::new(&spec);
        let mut pose = start;
        let mut out = vec![pose];
        for _ in 0..(seconds / 0.01) as usize {
            let cmd = limiter.limit(law(&pose), 0.01);
            step(&mut pose, &cmd, &spec, 0.01);
            out.push(pose);
        }
        out
    }

    #[test]
    fn the_line_law_brings_easy_and_difficult_starts_onto_the_line() {
        let law = LineFollower::new(GainSchedule::default());
        for speed in [0.2, 0.5, 0.8] {
            // "Easy": 3 m before the door, 20° off; "difficult": closer,
            // 2 m before it and 30 cm to the side (paper A, Table III).
            for start in [
                Pose2::new(-3.0, 0.2, 20f64.to_radians()),
                Pose2::new(-2.0, 0.3, 0.0),
            ] {
                let path = drive(start, 4.5 / speed + 1.0, |p| DriveCommand {
                    speed_mps: speed,
                    steer_rad: law.steer(p.y, p.theta, speed),
                });
                // At the door plane (x = 0), and a metre past it.
                let at = |x: f64| *path.iter().find(|p| p.x >= x).expect("gets there");
                let (door, past) = (at(0.0), at(1.0));
                let easy = start.x <= -3.0;
                let (tol_y, tol_th) = if easy { (0.005, 0.004) } else { (0.01, 0.015) };
                assert!(
                    door.y.abs() < tol_y && door.theta.abs() < tol_th,
                    "{speed} m/s from {start:?}: at the door {door:?}"
                );
                assert!(
                    past.y.abs() < 0.002 && past.theta.abs() < 0.004,
                    "{speed} m/s from {start:?}: past the door {past:?}"
                );
            }
        }
    }

    #[test]
    fn gains_interpolate_and_hold_at_the_ends() {
        let g = GainSchedule::default();
        assert_eq!(g.at(0.1), (7.0, 2.69));
        assert_eq!(g.at(1.0), (5.5, 2.27));
        let (k1, _) = g.at(0.35);
        assert!((k1 - 6.5).abs() < 1e-12);
    }

    #[test]
    fn corridor_centring_finds_the_middle() {
        let law = CorridorCentring::new(GainSchedule::default());
        // Walls at y = ±1; the robot starts 40 cm off the middle, 10° off.
        let path = drive(Pose2::new(0.0, 0.4, 0.17), 12.0, |p| {
            let (left, right) = (1.0 - p.y, 1.0 + p.y);
            DriveCommand {
                speed_mps: 0.8,
                steer_rad: law.steer(left, right, -p.theta, 0.8),
            }
        });
        let end = path.last().expect("a path");
        assert!(end.y.abs() < 0.002 && end.theta.abs() < 0.002, "{end:?}");
    }

    #[test]
    fn wall_following_holds_the_standoff_on_either_side() {
        for side in [WallSide::Left, WallSide::Right] {
            let law = WallFollower::new(GainSchedule::default(), side, 0.8);
            // The wall y = 2 (left) or y = -2 (right); start 1.5 m from it.
            let wall_y: f64 = if side == WallSide::Left { 2.0 } else { -2.0 };
            let path = drive(Pose2::new(0.0, 0.0, 0.0), 15.0, |p| {
                let d = (wall_y - p.y).abs();
                let gamma = wrap_angle(wall_y.signum() * std::f64::consts::FRAC_PI_2 - p.theta);
                DriveCommand {
                    speed_mps: 0.4,
                    steer_rad: law.steer(d, gamma, 0.4),
                }
            });
            let end = path.last().expect("a path");
            assert!(
                ((wall_y - end.y).abs() - 0.8).abs() < 0.002,
                "{side:?}: {end:?}"
            );
        }
    }

    #[test]
    fn pose_regulation_stops_on_the_goal() {
        let law = PoseRegulator::new(GainSchedule::default(), 0.5);
        let goal = Pose2::new(4.0, 1.0, 0.3);
        let path = drive(Pose2::new(0.0, 0.0, 0.0), 30.0, |p| law.command(p, &goal));
        let end = path.last().expect("a path");
        let rel = goal.inverse() * *end;
        assert!(
            rel.x.abs() < 0.01 && rel.y.abs() < 0.01 && rel.theta.abs() < 0.01,
            "{rel:?}"
        );
    }

    #[test]
    fn a_stop_brakes_evenly_and_lands_on_the_goal() {
        let law = PoseRegulator::new(GainSchedule::default(), 0.8);
        let goal = Pose2::new(2.0, 0.0, 0.0);
        let mut speeds = Vec::new();
        let path = drive(Pose2::new(0.0, 0.0, 0.0), 10.0, |p| {
            let cmd = law.command(p, &goal);
            speeds.push(cmd.speed_mps);
            cmd
        });
        let end = path.last().expect("a path");
        assert!(
            (end.x - 2.0).abs() < 0.005 && end.y.abs() < 0.005,
            "{end:?}"
        );
        // No step asks for harder braking than planned, until the stop at
        // the goal itself.
        let moving: Vec<f64> = speeds.iter().copied().take_while(|&v| v > 0.0).collect();
        for w in moving.windows(2) {
            assert!(w[0] - w[1] <= 1.1 * STOP_DECEL_MPS2 * 0.01, "{w:?}");
        }
        // On at 0.8 m/s, braking over the last 0.8 m: 3.4 s (this drive's
        // limiter bounds speed and steering, not acceleration), where
        // slowing in proportion to the distance left over the last 0.6 m
        // crept up on the goal in 4.7 s.
        let arrived_s = moving.len() as f64 * 0.01;
        assert!(arrived_s < 4.0, "{arrived_s} s");
    }

    #[test]
    fn path_following_turns_the_corners_and_stops_at_the_end() {
        let mut law = PathFollower::new(
            GainSchedule::default(),
            vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]],
            0.5,
        );
        let path = drive(Pose2::new(0.0, 0.0, 0.0), 40.0, |p| law.command(p));
        let end = path.last().expect("a path");
        assert!(
            (end.x).abs() < 0.01 && (end.y - 3.0).abs() < 0.01,
            "{end:?}"
        );
        // Mid-segment the robot is on its line.
        let mid = path
            .iter()
            .find(|p| (p.x - 4.0).abs() < 0.05 && (p.y - 1.5).abs() < 0.05)
            .expect("passes the second segment's middle");
        assert!((mid.x - 4.0).abs() < 0.02, "{mid:?}");
        assert_eq!(law.segment(), 3);
    }
}
