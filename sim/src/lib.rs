//! The simulator of stucco: a rapier3d world built from a world file, the
//! papers' tricycle with actuator limits, slip and skid, a scanning laser
//! cast beam by beam through rapier's query pipeline while the robot moves,
//! a range camera, rear-wheel encoders, injectable faults, and ground truth
//! kept apart from what the robot's software sees.
//!
//! - [`WorldSpec`]: a world file (`sim/worlds/*.toml`), parsed and checked.
//! - [`Layout`]: its solids and its truth (walls, openings, rooms).
//! - [`Simulator`]: implements [`stucco_core::Platform`]; [`Simulator::truth`]
//!   is the truth about the robot.
//! - [`Deposition`]: the sprayer's gantry and the plaster it lays on every
//!   true wall and ceiling ([`Coat`]), when [`SimConfig::sprayer`] is set.
//!
//! ```
//! use stucco_core::{DriveCommand, Platform};
//! use stucco_sim::{SimConfig, Simulator, WorldSpec};
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/worlds/reference-room.toml");
//! let world = WorldSpec::load(std::path::Path::new(path)).expect("a world");
//! let mut sim = Simulator::new(&world, SimConfig::default(), None);
//! sim.command(DriveCommand { speed_mps: 0.3, steer_rad: 0.0 });
//! let readings = sim.advance(0.5);
//! assert_eq!(readings.encoders.len(), 25); // 50 Hz
//! assert_eq!(readings.scans.len(), 4); // 8 Hz
//! assert!(sim.truth().drive.pose.x > world.robot.at[0]);
//! ```
#![warn(missing_docs)]

mod deposition;
mod error;
mod grid;
mod layout;
mod plane;
mod scene;
mod sensors;
mod simulator;
mod space;
mod tour;
mod trace;
mod truth;
mod vehicle;
mod world;
mod worldgen;

pub use deposition::{Coat, Deposition, SprayerSpec, SurfaceKind, ToolState};
pub use error::SimError;
pub use layout::{Layout, Material, OpeningKind, Piece, Solid, TrueOpening, TrueRoom, TrueWall};
pub use plane::{PlaneCaster, ray_circle};
pub use scene::Scene;
pub use sensors::{FaultConfig, Interval, StuckEncoder};
pub use sensors::{cast, cast_rapier};
pub use simulator::{SimConfig, Simulator, Truth};
pub use space::SpaceCaster;
pub use stucco_core::{CameraSpec, TOOL_CAMERA};
pub use tour::TourDriver;
pub use trace::TraceHash;
pub use truth::{
    Blocker, Finish, Reach, SHUT_DOOR, SurfaceTruth, Tally, TrueScore, edge_distance, inside,
    score_truth,
};
pub use vehicle::{DriveState, DynamicsConfig};
pub use world::{
    BoxSpec, ColumnSpec, DoorSpec, PersonSpec, RadiatorSpec, RobotStart, RoomSpec, TableSpec,
    TourSpec, WindowSpec, WorldSpec,
};
pub use worldgen::{Building, CORRIDOR, Drawing, DrawnDoor, DrawnWindow, generate};
