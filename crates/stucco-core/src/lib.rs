//! Shared types of stucco, the software of an autonomous spray-plastering
//! robot: the bottom of the crate graph, with no I/O and no clock.
//!
//! - [`Stamp`]: time, always passed in as an argument.
//! - [`Pose2`], [`Twist2`]: rigid motions and velocities of the plane.
//! - [`Scan`], [`Beam`]: one sweep of a scanning range-finder, with explicit
//!   no-return marking.
//! - [`LaserSpec`]: the range-finders of the source papers as presets
//!   (IBEO Ladar-2D, Hokuyo URG, Hokuyo UTM-30, SICK LMS291).
//! - [`VehicleSpec`]: the papers' tricycle, its limits and sensor mounts;
//!   [`CameraSpec`]: a range camera; [`RobotSpec`]: all a robot carries.
//! - [`Platform`]: the port to a robot or the simulator — [`DriveCommand`]
//!   in, [`Readings`] ([`EncoderSample`], [`Scan`], [`RangeProfile`],
//!   bumper) out, time advanced by the caller.
//! - [`Telecommand`], [`Command`], [`Ack`], [`Reply`]: the operator's
//!   semiautonomous vocabulary and the robot's replies; [`WallName`],
//!   [`Side`]: the walls of a room as commands name them.
//!
//! ```
//! use stucco_core::{LaserSpec, Pose2, Scan, Stamp};
//!
//! let ibeo = LaserSpec::ibeo_ladar_2d();
//! let scan = Scan::from_spec(&ibeo, Stamp::from_secs_f64(1.5), vec![2.0; ibeo.beams]);
//! let robot = Pose2::new(1.0, 2.0, 0.0);
//! let first = scan.returns().next().expect("a return");
//! let in_world = robot.transform_point(&first.point());
//! assert!((in_world - robot.position()).norm() - 2.0 < 1e-12);
//! ```
#![warn(missing_docs)]

mod laser;
mod operator;
mod platform;
mod pose;
mod robot;
mod scan;
mod spray;
mod stamp;
pub mod telemetry;
mod text;
mod vehicle;

pub use laser::{BeamWidth, LaserSpec};
pub use operator::{
    Ack, Command, Landmark, OperatorCommand, Region, Reply, Side, SurfaceId, Telecommand, WallName,
};
pub use platform::{DriveCommand, EncoderSample, Platform, PlatformError, RangeProfile, Readings};
pub use pose::{Pose2, Twist2, wrap_angle};
pub use robot::{CameraSpec, RobotSpec, TOOL_CAMERA};
pub use scan::{Beam, Scan};
pub use spray::{
    Aim, FOOTPRINT_REACH_SIGMAS, SurfaceFrame, SurfaceHit, ThicknessGrid, ToolCommand, normal_cdf,
    path_density,
};
pub use stamp::{ParseStampError, Stamp};
pub use telemetry::{BehaviourKind, Hazard, MissionMode, Obstacle, PivotPhase, RobotState};
pub use text::{NonFinite, first_non_finite, line_column};
pub use vehicle::VehicleSpec;

/// Re-export of the linear-algebra crate the public API uses.
pub use nalgebra;
