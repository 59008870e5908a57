//! The navigation core of stucco: walls and door openings found in laser
//! range scans with the Range Weighted Hough Transform (RWHT) of Forsberg,
//! Larsson and Wernersson.
//!
//! - [`ScanPoints`]: a scan's returns as points, optionally corrected for the
//!   sensor's motion during the sweep.
//! - [`HoughTransform`]: the g-weighted transform `C(d, γ)` with the three
//!   weightings of the paper ([`Weighting`]).
//! - [`WallExtractor`]: the extractor interface; [`RwhtExtractor`] finds
//!   peaks one by one in the transform voted by runs of echoes on one line
//!   ([`Segmenter`], [`SegmentTransform`]) and refines each by robust
//!   least squares,
//!   [`RansacExtractor`] is the baseline of the sensor-precision paper.
//! - [`RoomSearch`]: the four walls of a rectangular room as one group of
//!   peaks 90° apart, and the room's orientation.
//! - [`find_doors`]: open doors as runs of beams beyond a wall ([`find_doors_moving`] for a laser moving during its sweep).
//! - [`DeadReckoning`]: the tricycle's pose from its rear-wheel encoders,
//!   as a [`Displacement`] with covariance since the last scan.
//! - [`RoomEkf`]: the robot's pose and the room's size in an EKF fed by the
//!   encoders and by walls, each scan applied at its own stamp.
//! - [`WallMapEkf`]: a map of walls built while moving (paper B): the pose
//!   and every wall in one EKF, each scan's walls matched by a
//!   decision-directed Bayesian classifier; the [`WallMap`] saved and
//!   loaded for localisation in a known map.
//! - [`LaserOdometry`]: the wheels' displacement between scans corrected
//!   by registering each scan's echoes on a recent scan's
//!   ([`ScanReference`]: point-to-line ICP with the wheels as prior).
//! - [`DefeaturedLaser`]: a laser preset made worse on purpose (range,
//!   resolution, field of view, noise), as the sensor-precision paper does.
//! - [`RoomGraph`]: the room-and-door map — rooms as nodes, doors as
//!   edges — built on the map of walls as the robot passes doors, and
//!   routes between named rooms.
//! - [`relative_pose_error`]: RPE (Kümmerle et al. 2009) of a trajectory.
//! - [`WindowFinder`]: windows in the range camera's profiles.
//! - [`synthetic`]: exact ray-cast scans of rooms with clutter, for tests.
//!
//! ```
//! use rand::SeedableRng;
//! use stucco_core::{LaserSpec, Pose2, Stamp, Twist2};
//! use stucco_nav::{synthetic, RwhtConfig, RwhtExtractor, ScanPoints, WallExtractor};
//!
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
//! let robot = Pose2::new(2.0, 2.5, 0.4);
//! let room = synthetic::reference_room(robot.position(), 12, &mut rng);
//! let laser = synthetic::SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
//! let scan = laser.scan(&room.world, &robot, &Twist2::default(), Stamp::ZERO, &mut rng);
//!
//! let mut rwht = RwhtExtractor::new(RwhtConfig::default()).expect("valid settings");
//! let walls = rwht.extract(&ScanPoints::from_scan(&scan));
//! let (d, _) = room.wall_in_sensor_frame(0, &robot); // the wall x = 0
//! assert!(walls.iter().any(|w| (w.d_m - d).abs() < 0.02));
//! ```
#![warn(missing_docs)]

mod association;
pub mod baseline;
mod calibration;
mod defeature;
mod door;
mod error;
mod extractor;
mod hough;
mod line_fit;
mod map_ekf;
mod odometry;
mod points;
mod ransac;
mod room;
mod room_ekf;
mod room_graph;
mod room_shape;
mod rpe;
mod rwht;
mod scan_match;
mod segments;
pub mod synthetic;
mod wall;
mod wall_map;
mod windows;

pub use calibration::{Calibration, CalibratorConfig, OnlineCalibrator};
pub use defeature::{Defeature, DefeaturedLaser};
pub use door::{DoorConfig, DoorOpening, find_doors, find_doors_moving};
pub use error::NavError;
pub use extractor::WallExtractor;
pub use hough::{HoughConfig, HoughTransform, Weighting};
pub use line_fit::FitConfig;
pub use map_ekf::{MapUpdate, WallMapConfig, WallMapEkf};
pub use odometry::{
    DeadReckoning, Displacement, OdometryConfig, sensor_twist, twist_at, wheel_steps,
    wheel_travel_at,
};
pub use points::{ScanPoint, ScanPoints};
pub use ransac::{RansacConfig, RansacExtractor};
pub use room::{RectangularRoom, RoomConfig, RoomSearch};
pub use room_ekf::{
    RoomCovariance, RoomDoor, RoomEkf, RoomEkfConfig, RoomState, ScanUpdate, observe, observe_door,
    predict,
};
pub use room_graph::{
    Door, DoorPlace, Room, RoomEvent, RoomGraph, RoomGraphConfig, RoomSide, Route,
};
pub use room_shape::RoomShape;
pub use rpe::{Pairs, Rpe, relative_pose_error};
pub use rwht::{RwhtConfig, RwhtExtractor};
pub use scan_match::{
    LaserOdometry, LaserOdometryConfig, LaserStep, ScanMatch, ScanMatchConfig, ScanReference,
};
pub use segments::{Segment, SegmentTransform, Segmenter};
pub use wall::Wall;
pub use wall_map::{MapWall, WallId, WallMap, WallRole};
pub use windows::{ProfilePose, Window, WindowConfig, WindowFinder};
