//! The tricycle of the source papers: the front wheel steers and drives,
//! the two passive rear wheels carry the encoders.

use crate::Pose2;
use serde::{Deserialize, Serialize};

/// Geometry, limits and sensors' mounting of a tricycle robot.
///
/// The robot's frame has its origin in the middle of the rear axle, x
/// forward, y to the left.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VehicleSpec {
    /// Distance from the rear axle to the front wheel, m.
    pub wheelbase_m: f64,
    /// Distance between the rear wheels, m.
    pub track_m: f64,
    /// Radius of the rear (encoder) wheels, m.
    pub rear_wheel_radius_m: f64,
    /// Encoder ticks per turn of a rear wheel.
    pub ticks_per_rev: u32,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Fastest the front wheel drives, m/s.
    pub max_speed_mps: f64,
    /// Largest steering angle either way, rad.
    pub max_steer_rad: f64,
    /// Largest change of the front wheel's speed, m/s².
    pub max_accel_mps2: f64,
    /// Fastest the steering turns, rad/s.
    pub max_steer_rate_radps: f64,
    /// Length of the body's footprint, m, from `rear_overhang_m` behind
    /// the rear axle forward.
    pub length_m: f64,
    /// Width of the body's footprint, m.
    pub width_m: f64,
    /// How far the body reaches behind the rear axle, m.
    pub rear_overhang_m: f64,
    /// Height of the body, m.
    pub height_m: f64,
    /// Pose of the scanning laser in the robot's frame.
    pub laser_mount: Pose2,
    /// Height of the laser's scanning plane above the floor, m.
    pub laser_height_m: f64,
    /// Odometry (encoder) samples per second.
    pub odometry_rate_hz: f64,
}

impl Default for VehicleSpec {
    /// The Luleå robot: a 0.8 m/s tricycle with ±90° steering, the laser
    /// 0.3 m above the floor.
    fn default() -> Self {
        VehicleSpec {
            wheelbase_m: 0.6,
            track_m: 0.5,
            rear_wheel_radius_m: 0.1,
            ticks_per_rev: 2048,
            mass_kg: 90.0,
            max_speed_mps: 0.8,
            max_steer_rad: std::f64::consts::FRAC_PI_2,
            max_accel_mps2: 0.8,
            max_steer_rate_radps: 2.0,
            length_m: 0.9,
            width_m: 0.62,
            rear_overhang_m: 0.15,
            height_m: 0.5,
            laser_mount: Pose2::new(0.35, 0.0, 0.0),
            laser_height_m: 0.3,
            odometry_rate_hz: 50.0,
        }
    }
}

impl VehicleSpec {
    /// How far the body reaches ahead of the rear axle, m: what its front
    /// sweeps turning on the spot, and swings out past a corner turned on
    /// the move.
    pub fn front_m(&self) -> f64 {
        self.length_m - self.rear_overhang_m
    }

    /// Distance travelled along the wheel's rim per encoder tick, m.
    pub fn metres_per_tick(&self) -> f64 {
        std::f64::consts::TAU * self.rear_wheel_radius_m / f64::from(self.ticks_per_rev)
    }
}
