//! The mission executive of stucco: the layer the users touch.
//!
//! A mission is a list of tasks ([`TaskSpec`], from a mission file or the
//! operator). The [`Executive`] carries them out in layers, each explicit
//! in the code and in the state it reports:
//!
//! - mission: [`MissionMode`] — running, paused, e-stopped, done, failed,
//!   aborted — and each task's [`TaskStatus`];
//! - task: plans its behaviours from the estimate when it starts, and
//!   decides when it is done (a room's size known, an operator's answer);
//! - behaviour ([`Behaviour`]): a turn on the spot, a line to a pose, a
//!   wall followed at a standoff, a path — each one law of
//!   `stucco-control`, reused by every task that needs it;
//! - control law: the command.
//!
//! Telecommands (`stucco_core::Telecommand`) come in with the inputs and
//! are answered in the outputs: a task command is queued to run next and
//! replied `accepted`, then `done` or `failed`; `stop` acts in the same
//! tick; a `jog` drives directly until its time to live; a retried id gets
//! its last reply again and is never carried out twice; a stale one is
//! refused.
//!
//! The [`Supervisor`] sees every command last and may stop it: an obstacle
//! in the protective field, the estimate lost, a bumper, the e-stop.
//! [`Progress`] is what a checkpoint keeps, so a mission started again
//! resumes where it stopped.
//!
//! The files a job is written in live here too: the mission file
//! ([`Mission`], checked with the file, line and column of each fault) and
//! the checkpoint ([`Checkpoint`], written atomically, refused when made
//! for another mission) — the crate's only I/O. The executive itself is
//! pure: time comes in with each [`Executive::tick`], nothing is read from
//! a clock.
#![warn(missing_docs)]

mod behaviour;
mod checkpoint;
mod executive;
mod file;
mod floor;
mod ledger;
mod manoeuvre;
mod model;
mod plaster;
mod route;
mod supervisor;
mod task;
mod tasks;
mod views;

pub use behaviour::{Behaviour, BehaviourKind, PivotPhase, Step, go_to};
pub use checkpoint::{
    CHECKPOINT_FILE, Checkpoint, PLAN_FILE, RoomMap, digest, read_checkpoint, write_atomic,
};
pub use executive::{
    Event, EventKind, Executive, ExecutiveConfig, GiveUpReason, Inputs, MissionMode,
    OperatorCommand, Outputs, PARK_NOZZLE_M, Progress, ProgressMismatch, TaskStatus,
};
pub use file::{
    BadInput, Corridor, DoorPassage, Mission, RoomSize, Start, StartKnowledge, line_of, parse_toml,
};
pub use floor::{DoorSide, FloorPlan, PlanDoor, PlanFault, PlanRoom, PlanWindow};
pub use ledger::{MAX_DEADLINE_AHEAD_S, MAX_ID_BYTES, MAX_KEPT, MAX_OPERATOR_BYTES};
pub use model::{
    DoorEstimate, Estimate, WallGeometry, WindowEstimate, room_walls, wall_in, wall_sigma,
    walls_of_room,
};
pub use plaster::{Cursor, PlasterCoverage, PlasterProgress, SurfaceCoverage, plan_digest};
pub use supervisor::{
    FailurePolicy, Hazard, LinkLossPolicy, LostPolicy, SafetyConfig, Supervisor, Verdict,
};
pub use task::{
    AllRooms, Landmark, OnTimeout, Region, Rooms, Side, SpraySettings, TaskSpec, WallName,
    spray_with,
};
pub use tasks::{Effects, Task, TaskCx, TaskFailure, TaskStep, Thaw};
