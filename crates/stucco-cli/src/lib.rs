//! The `stucco` command-line tool as a library, so acceptance tests can call
//! its jobs without spawning a process.
//!
//! - [`read_carmen_file`], [`CarmenReader`]: CARMEN laser logs.
//! - [`run_walls`]: the `stucco walls` job.
//! - [`run_simbench`]: the `stucco simbench` job.
//! - [`run_mission`]: the `stucco run` job for experiment missions
//!   ([`Mission`]), closing the loop through the runtime's robot on the simulator
//!   ([`LawDriven`]).
//! - [`run_task_mission`]: the `stucco run` job for task missions: the
//!   executive of `stucco-mission` in the simulator, with report, events,
//!   map and checkpoints; [`Recorder`] and [`replay_run`] record a run as
//!   MCAP and replay it through the executive.
//! - [`run_study`]: the `stucco study` job: the sensor-precision paper's
//!   de-featured lasers and scanner comparison ([`Study`]).
//! - [`bench_stop`], [`bench_commands`]: the operator link's figures.
//! - [`run_robot`]: the `stucco robot` process (the executive and the
//!   simulator paced to the wall clock, on zenoh); [`Operator`]: the
//!   `stucco op` console.
#![warn(missing_docs)]

mod buildings;
mod carmen;
mod experiments;
mod floor;
mod link_bench;
mod log_replay;
mod logging;
mod op;
mod plan_view;
mod plastering;
mod record;
mod robot;
mod room_frame;
mod sim_robot;
mod sim_serve;
mod simbench;
mod study;
mod study_plot;
mod task_mission;
mod walls;

pub use buildings::{BuildingRow, buildings_table, run_buildings, write_building};
pub use carmen::*;
pub use experiments::{ConditionReport, RunJob, RunReport, load_all, run_mission};
pub use floor::{FloorRun, map_floor};
pub use link_bench::{
    CommandsBenchJob, CommandsBenchReport, StopBenchJob, StopBenchReport, bench_commands,
    bench_stop,
};
pub use log_replay::{
    LogReplayJob, LogReplayReport, OdomNoise, OdometrySource, OdometryTrust, RPE_PAIR_DISTANCE_M,
    Reference, run_log_replay,
};
pub use logging::init_logging;
pub use op::{BenchReport, CommandResult, Feed, Operator};
pub use plastering::{
    BlockerReport, PlasterReport, PredictedScores, RoomPlaster, TruthReport, WORLD_FILE,
    WorldState, sprayer_of, time_lower_bound, true_terms,
};
pub use record::{RecordedMission, Recorder, ReplayReport, replay_run};
pub use robot::{PlatformKind, RobotJob, RobotRun, run_robot};
pub use sim_robot::{
    LawDriven, Served, SimRobot, Simulated, WorldKeeper, load_world, mission_sim_config,
    mission_simulator, robot_on, robot_spec,
};
pub use sim_serve::{ServeJob, ServeRun, serve};
pub use simbench::{SimbenchJob, SimbenchReport, run_simbench};
pub use stucco_link::{Denial, Faults, FaultyRelay, LinkConfig, Mode as LinkMode, router};
pub use stucco_runtime::{
    BadInput, Checkpoint, Corridor, DT_S, DoorPassage, Mission, RoomSize, Start, StartKnowledge,
    write_atomic,
};
pub use study::{Axes, Axis, Compare, SettingReport, Study, StudyJob, StudyReport, run_study};
pub use study_plot::rasterise;
pub use task_mission::{
    DoorReport, MissionReport, MissionSummary, RoomChange, TaskMissionJob, TaskReport,
    run_task_mission,
};
pub use walls::{
    ExtractorKind, MIN_REOBSERVATIONS, WallsJob, WallsReport, make_extractor, run_walls,
};
