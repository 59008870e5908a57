//! The simulator as the robot's platform, in this process or served over
//! zenoh: a [`Robot`] of the runtime on it, what scoring reads of its
//! truth ([`Simulated`]), and the experiments' robot, driven by a control
//! law from outside the executive.

use crate::plastering::{WORLD_FILE, WorldState};
use anyhow::{Context, Result};
use nalgebra::DVector;
use std::path::{Path, PathBuf};
use stucco_control::Limiter;
use stucco_core::{
    DriveCommand, Platform, PlatformError, Pose2, Readings, RobotSpec, Stamp, ToolCommand,
};
use stucco_link::ZenohPlatform;
use stucco_mission::{Executive, ExecutiveConfig};
use stucco_mission::{Inputs, Outputs};
use stucco_nav::RoomState;
use stucco_runtime::{BadInput, Mission, Perception, Robot, Sink, SinkError};
use stucco_sim::{SimConfig, Simulator, WorldSpec};

/// A robot of the runtime on the simulator.
pub type SimRobot = Robot<Simulator>;

/// A simulated robot's platform as a job scores it: the simulator in this
/// process, or one served over zenoh ([`Served`]). Scoring and the files
/// kept beside a job read the truth through it; the robot's perception
/// never does.
pub trait Simulated: Platform {
    /// The simulator runs in this process: its world is kept beside the
    /// job's checkpoints and put back when the job resumes (a served one
    /// keeps its own).
    const IN_PROCESS: bool;

    /// The true pose (world frame) at the platform's time.
    fn true_pose(&self) -> Pose2;

    /// The simulated world's state now: where the robot stands, the
    /// plaster laid.
    fn world_state(&self) -> Result<WorldState>;

    /// Puts a kept world's plaster back (only when [`Self::IN_PROCESS`]).
    fn restore(&mut self, state: &WorldState);

    /// `f` on a simulator carrying the world's plaster now: this one, or
    /// one rebuilt from a served world's state (`known`, when it has just
    /// been read; else read now).
    fn with_plaster<R>(
        &self,
        known: Option<&WorldState>,
        f: impl FnOnce(&Simulator) -> Result<R>,
    ) -> Result<R>;
}

impl Simulated for Simulator {
    const IN_PROCESS: bool = true;

    fn true_pose(&self) -> Pose2 {
        self.truth().drive.pose
    }

    fn world_state(&self) -> Result<WorldState> {
        Ok(WorldState::of(self))
    }

    fn restore(&mut self, state: &WorldState) {
        state.restore(self);
    }

    fn with_plaster<R>(
        &self,
        _known: Option<&WorldState>,
        f: impl FnOnce(&Simulator) -> Result<R>,
    ) -> Result<R> {
        f(self)
    }
}

/// A simulator served over zenoh (`stucco sim serve`), reached through
/// its platform keys: what it publishes is all the robot perceives; its
/// true pose comes beside the readings and its world's state on request,
/// for scoring.
pub struct Served {
    platform: ZenohPlatform,
    /// The world it simulates and how, to rebuild its plaster for
    /// scoring.
    world: WorldSpec,
    config: SimConfig,
}

impl Served {
    /// The served `platform`, simulating `world` with `config`.
    pub fn new(platform: ZenohPlatform, world: WorldSpec, config: SimConfig) -> Self {
        Served {
            platform,
            world,
            config,
        }
    }
}

impl Platform for Served {
    fn now(&self) -> Stamp {
        self.platform.now()
    }

    fn command(&mut self, drive: DriveCommand) {
        self.platform.command(drive);
    }

    fn tool(&mut self, cmd: ToolCommand) {
        self.platform.tool(cmd);
    }

    fn advance(&mut self, dt_s: f64) -> std::result::Result<Readings, PlatformError> {
        self.platform.advance(dt_s)
    }
}

impl Simulated for Served {
    const IN_PROCESS: bool = false;

    /// The served simulator's true pose at the last period's end; the
    /// world's start before the first.
    fn true_pose(&self) -> Pose2 {
        self.platform.truth().unwrap_or_else(|| {
            let r = &self.world.robot;
            Pose2::new(r.at[0], r.at[1], r.heading_deg.to_radians())
        })
    }

    fn world_state(&self) -> Result<WorldState> {
        let json = self.platform.world()?;
        serde_json::from_slice(&json).context("the served simulator's world state")
    }

    fn restore(&mut self, _state: &WorldState) {}

    fn with_plaster<R>(
        &self,
        known: Option<&WorldState>,
        f: impl FnOnce(&Simulator) -> Result<R>,
    ) -> Result<R> {
        let mut sim = Simulator::new(&self.world, self.config.clone(), None);
        match known {
            Some(w) => w.restore(&mut sim),
            None => self.world_state()?.restore(&mut sim),
        }
        f(&sim)
    }
}

/// The simulator of `mission`'s robot in `world` with `seed`: the sprayer
/// the mission's `[spray]` makes, if any. `stucco run`, `stucco robot`
/// and `stucco sim serve` make the same one.
pub fn mission_simulator(mission: &Mission, world: &WorldSpec, seed: u64) -> Simulator {
    Simulator::new(world, mission_sim_config(mission), Some(seed))
}

/// How the simulator of `mission`'s robot is set up.
pub fn mission_sim_config(mission: &Mission) -> SimConfig {
    SimConfig {
        sprayer: mission.spray.as_ref().map(crate::plastering::sprayer_of),
        ..SimConfig::default()
    }
}

/// The robot on `platform`, which carries what `spec` says, its filter
/// starting at `x0` (room frame) with `size_sigma_m` on the room's size,
/// carrying out `executive`.
pub fn robot_on<P: Platform>(
    platform: P,
    spec: &RobotSpec,
    x0: RoomState,
    size_sigma_m: [f64; 2],
    executive: Executive,
) -> Result<Robot<P>> {
    let perception = Perception::new(spec, x0, size_sigma_m, platform.now())?;
    Ok(Robot::new(
        platform,
        perception,
        executive,
        Limiter::new(&spec.vehicle),
    ))
}

/// The simulated robot as its software knows it.
pub fn robot_spec() -> stucco_core::RobotSpec {
    SimConfig::default().robot()
}

/// A robot in the simulator driven by an experiment's control law, not
/// by the executive (which idles): the runtime's loop, read the way paper
/// A's experiments read it (the filter's state vector, the true pose).
pub struct LawDriven {
    robot: SimRobot,
}

impl LawDriven {
    /// The robot of `world` with `seed`, its filter starting at `x0` with
    /// `size_sigma_m` on the room's size.
    pub fn new(
        world: &WorldSpec,
        seed: u64,
        x0: RoomState,
        size_sigma_m: [f64; 2],
    ) -> Result<Self> {
        let spec = robot_spec();
        let idle = Executive::new(ExecutiveConfig::driving(spec.vehicle.clone()), Vec::new());
        Ok(LawDriven {
            robot: robot_on(
                Simulator::new(world, SimConfig::default(), Some(seed)),
                &spec,
                x0,
                size_sigma_m,
                idle,
            )?,
        })
    }

    /// The room filter's state now.
    pub fn estimate(&self) -> DVector<f64> {
        self.robot.perception().estimate()
    }

    /// The true pose (to score).
    pub fn truth(&self) -> Pose2 {
        self.robot.platform().truth().drive.pose
    }

    /// Puts a door into the filter's state; returns its index there.
    pub fn add_door(&mut self, wall: usize, position_m: f64, sigma_m: f64) -> usize {
        self.robot
            .perception_mut()
            .add_door(wall, position_m, sigma_m)
    }

    /// One control period at `speed_mps` with steering `steer_rad`
    /// (through the vehicle's limits); the true pose after it, or `None`
    /// when the robot touched something (an experiment's lane must be
    /// clear).
    pub fn step(&mut self, speed_mps: f64, steer_rad: f64) -> Result<Option<Pose2>> {
        let bumped = self
            .robot
            .drive(
                DriveCommand {
                    speed_mps,
                    steer_rad,
                },
                &mut [],
            )
            .map_err(anyhow::Error::from_boxed)?;
        Ok((!bumped).then(|| self.truth()))
    }
}

/// The world of `mission` (from `mission_path`'s folder), its people
/// removed when the mission closes the site to them.
pub fn load_world(mission: &Mission, mission_path: &Path) -> Result<WorldSpec> {
    let mut world = WorldSpec::load(&mission.world_path(mission_path)?)
        .map_err(|e| BadInput(format!("the world of {}: {e:#}", mission_path.display())))?;
    if !mission.people {
        world.people.clear();
    }
    Ok(world)
}

/// Writes the simulated world's state (the plaster, where the robot
/// stands) beside every checkpoint the robot writes: a killed simulation
/// leaves the world and the robot's checkpoint of one moment.
pub struct WorldKeeper {
    path: PathBuf,
}

impl WorldKeeper {
    /// Keeps the world in `dir`'s [`WORLD_FILE`].
    pub fn new(dir: &Path) -> Self {
        WorldKeeper {
            path: dir.join(WORLD_FILE),
        }
    }
}

impl<P: Simulated> Sink<P> for WorldKeeper {
    fn ticked(
        &mut self,
        robot: &Robot<P>,
        _inputs: &Inputs<'_>,
        outputs: &Outputs,
    ) -> std::result::Result<(), SinkError> {
        if outputs.checkpoint_due {
            robot.platform().world_state()?.save(&self.path)?;
        }
        Ok(())
    }
}
