//! The robot's runtime as a library: what runs on the robot, whichever
//! platform it is.
//!
//! - [`Perception`]: the platform's readings (encoders, laser scans,
//!   range-camera profiles) turned into the [`Estimate`](stucco_mission::Estimate)
//!   the executive reads: deskew, wall and door extraction, the room
//!   filter, windows, the ceiling, what stands on the floor.
//! - [`Robot`]: a [`Platform`](stucco_core::Platform), its perception, the
//!   executive and its supervisor, stepped once per control period
//!   ([`DT_S`]); what the loop produces leaves it through [`Sink`]s
//!   (events, checkpoints, recordings, telemetry, scores).
//! - [`Mission`]: a mission file (`missions/*.toml`), checked with the
//!   file, line and field of each fault ([`BadInput`]) — stucco-mission's,
//!   re-exported.
//! - [`EventLog`]: the executive's events as JSON lines.
//! - [`Checkpointer`]: a job's progress written after every unit of work
//!   ([`Checkpoint`], stucco-mission's file) and read back to resume.
//!
//! Nothing here knows the simulator, zenoh or the terminal: the simulator
//! is one platform (`stucco-sim`), a robot on zenoh another.
//!
//! ```
//! use stucco_core::{
//!     DriveCommand, Platform, PlatformError, Readings, RobotSpec, Stamp, ToolCommand,
//! };
//! use stucco_runtime::{Perception, Robot, DT_S};
//!
//! /// A platform that stands still and sees nothing.
//! struct Still(Stamp);
//! impl Platform for Still {
//!     fn now(&self) -> Stamp { self.0 }
//!     fn command(&mut self, _: DriveCommand) {}
//!     fn tool(&mut self, _: ToolCommand) {}
//!     fn advance(&mut self, dt_s: f64) -> Result<Readings, PlatformError> {
//!         self.0 = self.0.offset_secs(dt_s);
//!         Ok(Readings::default())
//!     }
//! }
//!
//! let spec = RobotSpec::default();
//! let x0 = stucco_nav::RoomState::new(1.0, 1.0, 0.0, 4.0, 3.0);
//! let perception = Perception::new(&spec, x0, [0.01, 0.01], Stamp::ZERO).expect("settings");
//! let mission = stucco_runtime::Mission::parse(
//!     r#"name = "waiting"
//!        [start]
//!        room_m = [4.0, 3.0]
//!        room_sigma_m = 0.05
//!        [[task]]
//!        task = "wait_for_operator"
//!        prompt = "ready?""#,
//!     std::path::Path::new("waiting.toml"),
//! ).expect("a mission");
//! let exec = mission.executive(&spec, true);
//! let mut robot = Robot::new(Still(Stamp::ZERO), perception, exec,
//!     stucco_control::Limiter::new(&spec.vehicle));
//! robot.step(&[], &mut []).expect("no sink to fail");
//! assert!((robot.now().as_secs_f64() - DT_S).abs() < 1e-9);
//! // The executive waits for its operator, the robot stands.
//! assert_eq!(robot.executive().current_task(), Some((0, "wait_for_operator")));
//! ```
#![warn(missing_docs)]

mod checkpoint;
mod echoes;
mod event_log;
mod movers;
mod perception;
mod robot;

pub use checkpoint::{Checkpointer, TaskTimes, windows_by_room};
pub use echoes::{EchoMemory, RecentScans};
pub use event_log::EventLog;
pub use movers::Movers;
pub use perception::{DT_S, OBSTACLE_HEIGHT_M, Perception, RoomWindows};
pub use robot::{Robot, Sink, SinkError};
// The job's files are stucco-mission's; here for the runtime's users.
pub use stucco_mission::{
    BadInput, CHECKPOINT_FILE, Checkpoint, Corridor, DoorPassage, Mission, PLAN_FILE, RoomMap,
    RoomSize, Start, StartKnowledge, digest, line_of, parse_toml, read_checkpoint, write_atomic,
};
