//! A robot platform over zenoh: the robot's brain on one side, its body —
//! a simulator, a real robot's driver in any language — on the other.
//!
//! Key expressions of platform `NAME`, JSON everywhere (no return of a
//! range travels as `null`):
//! - `stucco/NAME/platform/info`: a queryable answering [`PlatformInfo`]:
//!   what the robot carries, the platform's time, whether it steps in
//!   lockstep;
//! - `stucco/NAME/platform/command`: the brain's [`PlatformCommand`] once
//!   a control period: the period's number, its length, the drive's and
//!   the spray tool's commands;
//! - `stucco/NAME/platform/readings`: the platform's [`PlatformReadings`]
//!   once a period: its number, the platform's time at its end, what the
//!   sensors delivered during it;
//! - `stucco/NAME/platform/world`: a simulator's queryable answering the
//!   simulated world's state (where the robot truly stands, the plaster
//!   laid), for scoring a run; a real robot has none.
//!
//! Two ways of stepping. In lockstep the platform advances period `n` only
//! when command `n` has arrived, then publishes readings `n`: a run is the
//! same whatever the link's delays (a simulator scored against `stucco
//! run` in one process). Free-running, the platform advances with its own
//! clock, holding the last command (and stopping the drive and the spray
//! when commands stop coming); the brain reads what arrived.
//!
//! Lost messages: the brain sends a command again when its readings do
//! not come; a lockstep platform answers a command it has already carried
//! out with the same readings again, never steps twice.

use crate::{LinkError, z};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};
use stucco_core::{
    DriveCommand, Platform, PlatformError, Pose2, Readings, RobotSpec, Stamp, ToolCommand,
};
use zenoh::Session;
use zenoh::Wait;
use zenoh::bytes::ZBytes;
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::query::{Query, Queryable};
use zenoh::sample::Sample;

/// The key expressions of platform `name`.
pub mod keys {
    /// What the platform is (queryable).
    pub fn info(name: &str) -> String {
        format!("stucco/{name}/platform/info")
    }
    /// The brain's commands.
    pub fn command(name: &str) -> String {
        format!("stucco/{name}/platform/command")
    }
    /// The platform's readings.
    pub fn readings(name: &str) -> String {
        format!("stucco/{name}/platform/readings")
    }
    /// A simulator's world state (queryable).
    pub fn world(name: &str) -> String {
        format!("stucco/{name}/platform/world")
    }
}

/// What a platform tells of itself.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformInfo {
    /// Its name (the `NAME` of its keys).
    pub name: String,
    /// What the robot carries and how it drives.
    pub spec: RobotSpec,
    /// The platform's time when asked.
    pub now: Stamp,
    /// It steps only when the period's command has come.
    pub lockstep: bool,
    /// Its own control period when free-running, s.
    pub period_s: f64,
}

/// The brain's command for one control period.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformCommand {
    /// The period's number, from 1, one more each period.
    pub period: u64,
    /// How long the period lasts, s (a lockstep platform advances this
    /// much).
    pub dt_s: f64,
    /// The drive command to hold.
    pub drive: DriveCommand,
    /// The spray tool's command to hold.
    pub tool: ToolCommand,
}

/// What the platform's sensors delivered during one period.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformReadings {
    /// In lockstep, the number of the command carried out; free-running,
    /// the platform's own count of its periods.
    pub period: u64,
    /// The platform's time at the period's end.
    pub now: Stamp,
    /// What arrived from the sensors during the period.
    pub readings: Readings,
    /// A simulator's true pose at the period's end (world frame), for
    /// scoring only: the brain's perception never reads it. A real robot
    /// leaves it out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<Pose2>,
}

/// The platform's side: commands in, readings out, its info and world
/// answered.
pub struct PlatformServer {
    commands: Subscriber<FifoChannelHandler<Sample>>,
    readings: Publisher<'static>,
    info: Queryable<FifoChannelHandler<Query>>,
    world: Queryable<FifoChannelHandler<Query>>,
    /// The last readings published, sent again when their command comes
    /// again (shared bytes: keeping them copies nothing).
    last: Option<(u64, ZBytes)>,
}

impl PlatformServer {
    /// Declares platform `name` on `session`.
    pub fn new(session: &Session, name: &str) -> Result<Self, LinkError> {
        Ok(PlatformServer {
            commands: session
                .declare_subscriber(keys::command(name))
                .wait()
                .map_err(z)?,
            // Every period's readings reach the brain, in order: a
            // congested link slows the platform, never loses a scan.
            readings: session
                .declare_publisher(keys::readings(name))
                .express(true)
                .congestion_control(CongestionControl::Block)
                .wait()
                .map_err(z)?,
            info: session
                .declare_queryable(keys::info(name))
                .wait()
                .map_err(z)?,
            world: session
                .declare_queryable(keys::world(name))
                .wait()
                .map_err(z)?,
            last: None,
        })
    }

    /// Waits up to `timeout` for the brain's next command. A message that
    /// is not a command is logged and skipped.
    pub fn next_command(&mut self, timeout: Duration) -> Option<PlatformCommand> {
        let until = Instant::now() + timeout;
        loop {
            let left = until.saturating_duration_since(Instant::now());
            let sample = match self.commands.recv_timeout(left) {
                Ok(Some(s)) => s,
                _ => return None,
            };
            match crate::parse::<PlatformCommand>(&sample) {
                Ok(c) => return Some(c),
                Err(e) => tracing::warn!("platform command refused: {e}"),
            }
        }
    }

    /// The commands that came since the last call, oldest first.
    pub fn take_commands(&mut self) -> Vec<PlatformCommand> {
        let mut out = Vec::new();
        while let Some(c) = self.next_command(Duration::ZERO) {
            out.push(c);
        }
        out
    }

    /// Publishes one period's readings.
    pub fn publish(&mut self, readings: &PlatformReadings) -> Result<(), LinkError> {
        let json = ZBytes::from(serde_json::to_vec(readings).map_err(z)?);
        self.readings.put(json.clone()).wait().map_err(z)?;
        self.last = Some((readings.period, json));
        Ok(())
    }

    /// Publishes again the readings of `period` if they were the last
    /// published (their command came twice: the brain did not hear them);
    /// true if they were.
    pub fn republish(&mut self, period: u64) -> Result<bool, LinkError> {
        match &self.last {
            Some((p, json)) if *p == period => {
                self.readings.put(json.clone()).wait().map_err(z)?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// Answers the queries that came: `info` for the platform's info,
    /// `world` for its world's state as JSON, each called only when asked.
    pub fn answer(
        &mut self,
        info: impl Fn() -> PlatformInfo,
        world: impl FnOnce() -> Result<Vec<u8>, String>,
    ) -> Result<(), LinkError> {
        while let Ok(Some(q)) = self.info.try_recv() {
            let json = serde_json::to_vec(&info()).map_err(z)?;
            q.reply(q.key_expr().clone(), json).wait().map_err(z)?;
        }
        let mut world = Some(world);
        while let Ok(Some(q)) = self.world.try_recv() {
            let state = match world.take() {
                Some(f) => f(),
                None => Err("asked twice at once".to_owned()),
            };
            match state {
                Ok(json) => q.reply(q.key_expr().clone(), json).wait().map_err(z)?,
                Err(why) => q.reply_err(why).wait().map_err(z)?,
            }
        }
        Ok(())
    }
}

/// How long the brain waits for a period's readings before sending its
/// command again.
const RESEND_AFTER: Duration = Duration::from_secs(1);

/// A platform reached over zenoh: the brain's side of the keys above.
pub struct ZenohPlatform {
    name: String,
    session: Session,
    commands: Publisher<'static>,
    readings: Subscriber<FifoChannelHandler<Sample>>,
    info: PlatformInfo,
    now: Stamp,
    period: u64,
    drive: DriveCommand,
    tool: ToolCommand,
    truth: Option<Pose2>,
    /// How long the platform may stay silent before it is taken for gone.
    timeout: Duration,
}

impl ZenohPlatform {
    /// Finds platform `name` on `session` (asking until it answers, up to
    /// `timeout`), ready to step it; a period whose readings do not come
    /// within `timeout` fails the robot's loop.
    pub fn connect(session: &Session, name: &str, timeout: Duration) -> Result<Self, LinkError> {
        // Subscribed before the first command goes out: no readings lost.
        let readings = session
            .declare_subscriber(keys::readings(name))
            .wait()
            .map_err(z)?;
        let commands = session
            .declare_publisher(keys::command(name))
            .express(true)
            .congestion_control(CongestionControl::Block)
            .wait()
            .map_err(z)?;
        let info = ask::<PlatformInfo>(session, &keys::info(name), timeout)?;
        Ok(ZenohPlatform {
            name: name.to_owned(),
            session: session.clone(),
            commands,
            readings,
            now: info.now,
            info,
            period: 0,
            drive: DriveCommand::STOP,
            tool: ToolCommand::default(),
            truth: None,
            timeout,
        })
    }

    /// What the platform told of itself when found.
    pub fn info(&self) -> &PlatformInfo {
        &self.info
    }

    /// A simulator's true pose at the last period's end, for scoring
    /// (`None` from a real robot).
    pub fn truth(&self) -> Option<Pose2> {
        self.truth
    }

    /// A simulator's world state, as JSON (for scoring a run).
    pub fn world(&self) -> Result<Vec<u8>, LinkError> {
        let replies = self
            .session
            .get(keys::world(&self.name))
            .timeout(self.timeout)
            .wait()
            .map_err(z)?;
        match replies.recv_timeout(self.timeout) {
            Ok(Some(reply)) => match reply.result() {
                Ok(s) => Ok(s.payload().to_bytes().into_owned()),
                Err(e) => Err(LinkError::Zenoh(format!(
                    "{}: {}",
                    keys::world(&self.name),
                    e.payload().try_to_string().unwrap_or_default()
                ))),
            },
            _ => Err(LinkError::Zenoh(format!(
                "{}: no answer in {:?}",
                keys::world(&self.name),
                self.timeout
            ))),
        }
    }

    fn send(&self, cmd: &PlatformCommand) -> Result<(), PlatformError> {
        let json = serde_json::to_vec(cmd).map_err(|e| PlatformError(e.to_string()))?;
        self.commands
            .put(json)
            .wait()
            .map_err(|e| PlatformError(format!("{}: {e}", keys::command(&self.name))))
    }

    /// The next readings message, waiting up to `wait`; a message that
    /// is not readings fails the loop (the platform speaks another
    /// language).
    fn receive(&self, wait: Duration) -> Result<Option<PlatformReadings>, PlatformError> {
        match self.readings.recv_timeout(wait) {
            Ok(Some(sample)) => crate::parse(&sample)
                .map(Some)
                .map_err(|e| PlatformError(e.to_string())),
            Ok(None) => Ok(None),
            Err(e) => Err(PlatformError(format!(
                "{}: {e}",
                keys::readings(&self.name)
            ))),
        }
    }
}

impl Platform for ZenohPlatform {
    fn now(&self) -> Stamp {
        self.now
    }

    fn command(&mut self, drive: DriveCommand) {
        self.drive = drive;
    }

    fn tool(&mut self, cmd: ToolCommand) {
        self.tool = cmd;
    }

    /// Sends the period's command and returns the readings of the period:
    /// in lockstep, those the platform answers it with (the command sent
    /// again while they do not come); free-running, every message until
    /// the platform's clock has gone `dt_s` on.
    fn advance(&mut self, dt_s: f64) -> Result<Readings, PlatformError> {
        self.period += 1;
        let cmd = PlatformCommand {
            period: self.period,
            dt_s,
            drive: self.drive,
            tool: self.tool,
        };
        self.send(&cmd)?;
        let target = self.now.offset_secs(dt_s);
        let mut out = Readings::default();
        let started = Instant::now();
        let mut sent = Instant::now();
        loop {
            if started.elapsed() > self.timeout {
                return Err(PlatformError(format!(
                    "{}: no readings for period {} in {:?}",
                    self.name, self.period, self.timeout
                )));
            }
            let Some(r) = self.receive(RESEND_AFTER.saturating_sub(sent.elapsed()))? else {
                if self.info.lockstep && sent.elapsed() >= RESEND_AFTER {
                    tracing::warn!(platform = %self.name, period = self.period, "no readings: command sent again");
                    self.send(&cmd)?;
                    sent = Instant::now();
                }
                continue;
            };
            if self.info.lockstep && r.period != self.period {
                // Readings of a command sent twice, already taken.
                continue;
            }
            self.now = r.now;
            self.truth = r.truth.or(self.truth);
            let Readings {
                encoders,
                scans,
                profiles,
                bumper,
            } = r.readings;
            out.encoders.extend(encoders);
            out.scans.extend(scans);
            out.profiles.extend(profiles);
            out.bumper |= bumper;
            // Free-running, half a platform period early is this period's.
            let half = self.info.period_s / 2.0;
            if self.info.lockstep || self.now.offset_secs(half) >= target {
                return Ok(out);
            }
        }
    }
}

/// Asks `key` until one answer parses as `T`, for up to `timeout`.
fn ask<T: serde::de::DeserializeOwned>(
    session: &Session,
    key: &str,
    timeout: Duration,
) -> Result<T, LinkError> {
    let until = Instant::now() + timeout;
    let mut tries = 0;
    loop {
        tries += 1;
        let left = until.saturating_duration_since(Instant::now());
        let wait = left.min(Duration::from_millis(500));
        let replies = session.get(key).timeout(wait).wait().map_err(z)?;
        while let Ok(Some(reply)) = replies.recv_timeout(wait) {
            if let Ok(s) = reply.result() {
                return crate::parse(s);
            }
        }
        if Instant::now() >= until {
            return Err(LinkError::NoReply {
                robot: key.to_owned(),
                tries,
            });
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}
