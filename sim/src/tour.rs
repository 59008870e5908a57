//! A driver for benches and demos: pure pursuit around a world's tour on
//! the true pose (it is not navigation — it may look at the truth).

use stucco_core::{DriveCommand, Pose2, VehicleSpec};

use crate::TourSpec;

/// Fastest backing, m/s: the laser looks forwards.
const MAX_REVERSE_MPS: f64 = 0.5;

/// Pure pursuit around a closed loop of waypoints, forwards or, on the
/// legs marked so, backwards.
#[derive(Clone, Debug)]
pub struct TourDriver {
    points: Vec<[f64; 2]>,
    /// Legs driven backwards (leg `i` from point `i` to point `i + 1`).
    reverse: Vec<usize>,
    lookahead_m: f64,
    speed_mps: f64,
    /// Index of the segment the robot is on.
    segment: usize,
}

impl TourDriver {
    /// A driver around `points` (closed: the last leads to the first) at
    /// `speed_mps`, forwards all the way.
    pub fn new(points: Vec<[f64; 2]>, speed_mps: f64) -> Self {
        TourDriver::along(&TourSpec::forwards(points), speed_mps)
    }

    /// A driver along `tour` at `speed_mps` (backwards at 0.5 m/s at
    /// most).
    pub fn along(tour: &TourSpec, speed_mps: f64) -> Self {
        TourDriver {
            points: tour.points.clone(),
            reverse: tour.reverse.clone(),
            lookahead_m: 0.7,
            speed_mps,
            segment: 0,
        }
    }

    /// The command for a robot at `pose`.
    pub fn command(&mut self, pose: &Pose2, vehicle: &VehicleSpec) -> DriveCommand {
        let n = self.points.len();
        if n < 2 {
            return DriveCommand::STOP;
        }
        // Move on to the next segment once its start is behind.
        for _ in 0..n {
            let b = self.points[(self.segment + 1) % n];
            if (b[0] - pose.x).hypot(b[1] - pose.y) < self.lookahead_m {
                self.segment = (self.segment + 1) % n;
            } else {
                break;
            }
        }
        // The lookahead point: on the current segment, `lookahead_m` from
        // the robot, or the segment's end.
        let a = self.points[self.segment];
        let b = self.points[(self.segment + 1) % n];
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy).max(1e-9);
        let (ux, uy) = (dx / len, dy / len);
        let along = ((pose.x - a[0]) * ux + (pose.y - a[1]) * uy).clamp(0.0, len);
        let ahead = (along + self.lookahead_m).min(len);
        let target = [a[0] + ux * ahead, a[1] + uy * ahead];
        let local = pose
            .inverse()
            .transform_point(&nalgebra::Point2::new(target[0], target[1]));
        let ld2 = local.coords.norm_squared().max(1e-6);
        // Pure pursuit for a vehicle steered about its rear axle: the arc
        // tangent to the heading through the target, whichever way it is
        // driven (backing along it, the same steer holds the arc).
        let curvature = 2.0 * local.y / ld2;
        let steer = (curvature * vehicle.wheelbase_m).atan();
        let slow = 1.0 - 0.6 * (steer.abs() / vehicle.max_steer_rad).min(1.0);
        if self.reverse.contains(&self.segment) {
            if local.x > 0.0 {
                // Ahead while backing: stop rather than turn about.
                return DriveCommand::STOP;
            }
            return DriveCommand {
                speed_mps: -self.speed_mps.min(MAX_REVERSE_MPS) * slow,
                steer_rad: steer,
            };
        }
        let speed = self.speed_mps * slow;
        if local.x < 0.0 {
            // Behind: turn on the spot toward it.
            return DriveCommand {
                speed_mps: 0.3 * self.speed_mps,
                steer_rad: vehicle.max_steer_rad * local.y.signum(),
            };
        }
        DriveCommand {
            speed_mps: speed,
            steer_rad: steer,
        }
    }
}
