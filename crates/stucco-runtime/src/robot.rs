//! The robot: a [`Platform`], the robot's [`Perception`] of it, the
//! executive and its supervisor, stepped once per control period; what
//! the loop produces leaves it through [`Sink`]s.

use crate::perception::{DT_S, Perception};
use nalgebra::{Matrix3, Point2};
use stucco_control::Limiter;
use stucco_core::{Ack, DriveCommand, Platform, Stamp, Telecommand};
use stucco_mission::{Estimate, Executive, Inputs, Outputs};

/// What a sink or the platform may fail with (a file that cannot be
/// written, a link that is gone): the loop stops and hands it up.
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

/// Where what the robot's loop produces goes: events, checkpoints,
/// recordings, telemetry, scores. Each hook sees the whole robot, read
/// only; a sink that scores a simulated run reads the simulator's truth
/// through [`Robot::platform`], and nothing a sink does reaches the
/// executive.
pub trait Sink<P: Platform> {
    /// The executive has ticked: what it read and what it answered, before
    /// the robot acts on it.
    fn ticked(
        &mut self,
        robot: &Robot<P>,
        inputs: &Inputs<'_>,
        outputs: &Outputs,
    ) -> Result<(), SinkError> {
        let _ = (robot, inputs, outputs);
        Ok(())
    }

    /// The robot's frame was asked to move into the room beyond `door` of
    /// the floor plan: `moved` says whether it did, or why not.
    fn entered(
        &mut self,
        robot: &Robot<P>,
        door: usize,
        moved: &Result<(), String>,
    ) -> Result<(), SinkError> {
        let _ = (robot, door, moved);
        Ok(())
    }

    /// The platform has advanced one control period and perception has
    /// taken in its readings.
    fn stepped(&mut self, robot: &Robot<P>) -> Result<(), SinkError> {
        let _ = robot;
        Ok(())
    }
}

/// A robot on any platform: perception, executive and supervisor stepped
/// once per control period ([`DT_S`]).
///
/// A period is two halves: [`Robot::tick`] (the executive reads the
/// estimate and decides) and [`Robot::act`] (the drive command goes to the
/// platform through the vehicle's limits, the platform advances, its
/// readings are perceived). A caller may stop between them (a time limit,
/// a switch-off); [`Robot::step`] does both.
pub struct Robot<P: Platform> {
    platform: P,
    perception: Perception,
    executive: Executive,
    limiter: Limiter,
    /// The estimate the executive reads next, and the covariance of its
    /// pose's error, from one prediction per period.
    estimate: Estimate,
    pose_covariance: Matrix3<f64>,
    /// Perception was set up from outside since the estimate was made:
    /// it is made again before the next tick reads it.
    stale: bool,
    /// A bumper touched something during the last period.
    bumper: bool,
    /// The drive command of the last tick, for the next act.
    drive: DriveCommand,
    /// Control periods acted.
    periods: u64,
}

impl<P: Platform> Robot<P> {
    /// The robot on `platform`, perceiving with `perception`, carrying out
    /// `executive`'s mission; `limiter` holds the vehicle's limits.
    pub fn new(
        platform: P,
        perception: Perception,
        executive: Executive,
        limiter: Limiter,
    ) -> Self {
        let (estimate, pose_covariance) = perception.mission_estimate_with_covariance();
        Robot {
            platform,
            perception,
            executive,
            limiter,
            estimate,
            pose_covariance,
            stale: false,
            bumper: false,
            drive: DriveCommand::STOP,
            periods: 0,
        }
    }

    /// The platform's time.
    pub fn now(&self) -> Stamp {
        self.platform.now()
    }

    /// The platform (the simulator's truth is read through it, to score).
    pub fn platform(&self) -> &P {
        &self.platform
    }

    /// The platform, to set up (a resumed simulation's plaster).
    pub fn platform_mut(&mut self) -> &mut P {
        &mut self.platform
    }

    /// What the robot perceives.
    pub fn perception(&self) -> &Perception {
        &self.perception
    }

    /// What the robot perceives, to set up (doors and windows known
    /// before, the building's plan): the next tick reads an estimate made
    /// after it.
    pub fn perception_mut(&mut self) -> &mut Perception {
        self.stale = true;
        &mut self.perception
    }

    /// The executive.
    pub fn executive(&self) -> &Executive {
        &self.executive
    }

    /// The executive, to set up (a checkpoint's progress) or tell of the
    /// link.
    pub fn executive_mut(&mut self) -> &mut Executive {
        &mut self.executive
    }

    /// The estimate made again if perception was set up since it was.
    fn refresh(&mut self) {
        if std::mem::take(&mut self.stale) {
            (self.estimate, self.pose_covariance) =
                self.perception.mission_estimate_with_covariance();
        }
    }

    /// The estimate the executive reads at the next tick (made at the
    /// last period's end; one set up since is made again by the tick).
    pub fn estimate(&self) -> &Estimate {
        &self.estimate
    }

    /// The covariance of the estimated pose's error `(x, y, θ)`, room
    /// frame, from the same prediction as [`Robot::estimate`].
    pub fn pose_covariance(&self) -> &Matrix3<f64> {
        &self.pose_covariance
    }

    /// The last scan's echoes in the robot's frame.
    pub fn obstacles(&self) -> &[Point2<f64>] {
        self.perception.obstacles()
    }

    /// Control periods acted so far.
    pub fn periods(&self) -> u64 {
        self.periods
    }

    /// The first half of a control period: the executive reads the
    /// estimate, the bumper and the `telecommands` that arrived, and
    /// decides; the sinks hear it; the frame moves into the next room when
    /// the executive says the robot went through a door; the tool gets its
    /// command. The drive command waits for [`Robot::act`].
    pub fn tick(
        &mut self,
        telecommands: &[Telecommand],
        estop: bool,
        sinks: &mut [&mut dyn Sink<P>],
    ) -> Result<Outputs, SinkError> {
        let now = self.platform.now();
        self.refresh();
        let inputs = Inputs {
            estimate: &self.estimate,
            obstacles: self.perception.obstacles(),
            unseen: self.perception.unseen_echoes(),
            bumper: self.bumper,
            estop,
            operator: &[],
            telecommands,
        };
        let out = self.executive.tick(now, &inputs);
        for s in sinks.iter_mut() {
            s.ticked(self, &inputs, &out)?;
        }
        if let Some(door) = out.enter_room {
            // The executive checks on its next tick that the frame moved.
            let moved = self.perception.enter_through(door);
            if let Err(why) = &moved {
                tracing::warn!(door, "the robot's frame stays: {why}");
            }
            for s in sinks.iter_mut() {
                s.entered(self, door, &moved)?;
            }
        }
        self.platform.tool(out.tool);
        self.perception.tool_look(out.tool_look);
        self.drive = out.drive;
        Ok(out)
    }

    /// The second half of a control period: the last tick's drive command
    /// goes to the platform through the vehicle's limits, the platform
    /// advances, perception takes in its readings and the next estimate is
    /// predicted; the sinks hear it. Fails when the platform or a sink
    /// does.
    pub fn act(&mut self, sinks: &mut [&mut dyn Sink<P>]) -> Result<(), SinkError> {
        let cmd = self.limiter.limit(self.drive, DT_S);
        self.platform.command(cmd);
        let readings = self.platform.advance(DT_S)?;
        self.perception.take(&readings, self.platform.now());
        self.bumper = readings.bumper;
        if readings.bumper && cmd.speed_mps != 0.0 {
            self.perception.touched(&cmd);
        }
        (self.estimate, self.pose_covariance) = self.perception.mission_estimate_with_covariance();
        self.periods += 1;
        for s in sinks.iter_mut() {
            s.stepped(self)?;
        }
        Ok(())
    }

    /// One whole control period: [`Robot::tick`], then [`Robot::act`]
    /// unless the mission has come to its end (then the robot stands).
    pub fn step(
        &mut self,
        telecommands: &[Telecommand],
        sinks: &mut [&mut dyn Sink<P>],
    ) -> Result<Outputs, SinkError> {
        let out = self.tick(telecommands, false, sinks)?;
        if !self.executive.mode().is_final() {
            self.act(sinks)?;
        }
        Ok(out)
    }

    /// A control period driven by `cmd` from outside the executive (an
    /// experiment's control law): the executive does not tick, the rest
    /// of the period is [`Robot::act`]'s. True when a bumper touched
    /// something.
    pub fn drive(
        &mut self,
        cmd: DriveCommand,
        sinks: &mut [&mut dyn Sink<P>],
    ) -> Result<bool, SinkError> {
        self.drive = cmd;
        self.act(sinks)?;
        Ok(self.bumper)
    }

    /// Telecommands that arrived between control periods, answered at
    /// once on the estimate at hand.
    pub fn telecommands(&mut self, cmds: &[Telecommand]) -> Vec<Ack> {
        self.refresh();
        let now = self.platform.now();
        self.executive.telecommands(now, cmds, &self.estimate)
    }
}
