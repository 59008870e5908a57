//! The port between the robot's software and a platform (the simulator or
//! a real robot): actuator commands in, sensor readings out, time advanced
//! by the caller.

use crate::{Scan, Stamp, ToolCommand};
use serde::{Deserialize, Serialize};

/// What the drive is asked to do: the front wheel's speed and steering.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveCommand {
    /// Speed of the front wheel along its own heading, m/s (negative:
    /// reverse).
    pub speed_mps: f64,
    /// Steering angle of the front wheel, rad, counter-clockwise.
    pub steer_rad: f64,
}

impl DriveCommand {
    /// Stand still, wheel straight.
    pub const STOP: DriveCommand = DriveCommand {
        speed_mps: 0.0,
        steer_rad: 0.0,
    };
}

/// One sample of the rear-wheel encoders: the ticks counted since start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EncoderSample {
    /// When the counters were read.
    pub stamp: Stamp,
    /// Ticks of the left rear wheel since start (forward counts up).
    pub left_ticks: i64,
    /// Ticks of the right rear wheel since start.
    pub right_ticks: i64,
}

/// One vertical profile of a range camera: ranges along a fan of rays in a
/// vertical plane through the sensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeProfile {
    /// When the profile was taken.
    pub stamp: Stamp,
    /// The sensor it came from.
    pub sensor: String,
    /// Where the sensor was in the robot's frame when it took the profile
    /// (x forward of the rear axle, y to the left, z up from the floor),
    /// m: a camera on the body stays put, one on the spray tool's carriage
    /// moves with it (its axes' encoders tell where).
    pub origin_m: [f64; 3],
    /// Heading of the fan's plane in the robot's frame, rad (π/2: to the
    /// left).
    pub azimuth_rad: f64,
    /// Elevation of each ray above the horizontal, rad.
    pub elevations_rad: Vec<f64>,
    /// Range along each ray, m; `INFINITY` for no return (`null` in
    /// JSON).
    #[serde(with = "crate::scan::no_return_as_null")]
    pub ranges_m: Vec<f64>,
}

/// What arrived from the platform's sensors since the last step.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Readings {
    /// Encoder samples, oldest first.
    pub encoders: Vec<EncoderSample>,
    /// Laser scans completed, oldest first, each stamped at its first beam.
    pub scans: Vec<Scan>,
    /// Range-camera profiles, oldest first.
    pub profiles: Vec<RangeProfile>,
    /// True when a bumper touched something during the step.
    pub bumper: bool,
}

/// A robot platform stepped by its caller: the simulator in simulated time,
/// a real robot's driver paced by the wall clock.
pub trait Platform {
    /// The platform's time now.
    fn now(&self) -> Stamp;

    /// The drive command to hold from now on.
    fn command(&mut self, drive: DriveCommand);

    /// The spray tool's command to hold from now on: where the nozzle
    /// goes (its axes move there at their own speed), where it points,
    /// whether plaster flows.
    fn tool(&mut self, cmd: ToolCommand);

    /// Advances the platform by `dt_s` seconds and returns what its sensors
    /// delivered meanwhile; fails when the platform is gone (its driver
    /// stopped, its link lost): the robot's loop stops.
    fn advance(&mut self, dt_s: f64) -> Result<Readings, PlatformError>;
}

/// Why a platform could not advance: what its driver or link said.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlatformError(pub String);

impl std::fmt::Display for PlatformError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the platform: {}", self.0)
    }
}

impl std::error::Error for PlatformError {}
