//! `stucco bench stop` and `stucco bench commands`: the operator link's
//! figures, measured on a robot served in this process on a Unix socket
//! (loopback), driven by operators in this process and, for a client that
//! froze, in a process of its own.

use crate::op::Operator;
use crate::robot::{PlatformKind, RobotJob, run_robot};
use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use stucco_core::{Command, Reply, RobotState, Stamp};
use stucco_link::LinkConfig;
use stucco_runtime::DT_S;

/// The robot's name on the bench's network.
const ROBOT: &str = "b1";

/// A robot standing by on `mission`, in this process, on a Unix socket in
/// a folder of its own; stopped when dropped.
struct LoopbackRobot {
    dir: PathBuf,
    endpoint: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<crate::RobotRun>>>,
}

impl LoopbackRobot {
    fn start(mission: &Path) -> Result<Self> {
        let dir = std::env::temp_dir().join(format!("stucco-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).with_context(|| dir.display().to_string())?;
        let endpoint = format!("unixsock-stream/{}", dir.join("z.sock").display());
        let job = RobotJob {
            mission: mission.to_owned(),
            name: ROBOT.to_owned(),
            link: LinkConfig {
                listen: vec![endpoint.clone()],
                ..LinkConfig::default()
            },
            speed: 1.0,
            stop_after_s: None,
            exit_when_done: false,
            out: None,
            resume: false,
            record: false,
            platform: PlatformKind::Sim,
            platform_timeout: Duration::from_secs(10),
        };
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            std::thread::spawn(move || run_robot(&job, &stop))
        };
        let robot = LoopbackRobot {
            dir,
            endpoint,
            stop,
            thread: Some(thread),
        };
        // Up once it publishes its state.
        let op = Operator::connect(&robot.peer(), "bench-probe")?;
        op.robot_time(ROBOT, Duration::from_secs(10))
            .context("the bench's robot did not start")?;
        Ok(robot)
    }

    /// How a peer reaches it.
    fn peer(&self) -> LinkConfig {
        LinkConfig {
            connect: vec![self.endpoint.clone()],
            ..LinkConfig::default()
        }
    }

    /// Stops it; fails if it had failed.
    fn finish(mut self) -> Result<()> {
        self.halt()
    }

    fn halt(&mut self) -> Result<()> {
        self.stop.store(true, Ordering::Relaxed);
        let ran = match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| anyhow!("the bench's robot panicked"))?
                .map(|_| ()),
            None => Ok(()),
        };
        let _ = std::fs::remove_dir_all(&self.dir);
        ran
    }
}

impl Drop for LoopbackRobot {
    fn drop(&mut self) {
        let _ = self.halt();
    }
}

/// A `stucco` process subscribed to everything the robot publishes that
/// never reads it; killed when dropped.
struct FrozenClient(std::process::Child);

impl FrozenClient {
    fn start(stucco: &Path, robot: &LoopbackRobot) -> Result<Self> {
        let child = std::process::Command::new(stucco)
            .args(["op", ROBOT, "stall", "--as", "frozen", "--connect"])
            .arg(&robot.endpoint)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .with_context(|| format!("starting {}", stucco.display()))?;
        let mut client = FrozenClient(child);
        // Joined, subscribed and stuck on the first message by then.
        std::thread::sleep(Duration::from_secs(2));
        if let Some(status) = client.0.try_wait()? {
            bail!("the frozen client ended at once ({status})");
        }
        Ok(client)
    }
}

impl Drop for FrozenClient {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Status commands posted to the robot at a steady rate, none waited for,
/// from an operator of their own; stopped when [`Flood::finish`]ed.
struct Flood {
    done: Arc<AtomicBool>,
    thread: JoinHandle<Result<(u64, Duration)>>,
}

impl Flood {
    fn start(peer: &LinkConfig, per_second: f64) -> Result<Self> {
        let done = Arc::new(AtomicBool::new(false));
        let mut op = Operator::connect(peer, "flood")?;
        let states = op.states(ROBOT)?;
        let mut now = op.robot_time(ROBOT, Duration::from_secs(3))?;
        let thread = {
            let done = done.clone();
            std::thread::spawn(move || {
                let every = Duration::from_secs_f64(1.0 / per_second);
                let t0 = Instant::now();
                let mut sent = 0u64;
                while !done.load(Ordering::Relaxed) {
                    if let Some(s) = states.drain().last() {
                        now = s.stamp;
                    }
                    let due = t0 + every.mul_f64(sent as f64);
                    if let Some(wait) = due.checked_duration_since(Instant::now()) {
                        std::thread::sleep(wait);
                    }
                    op.post(ROBOT, now, Command::Status, 5.0)?;
                    sent += 1;
                }
                Ok((sent, t0.elapsed()))
            })
        };
        Ok(Flood { done, thread })
    }

    /// Commands sent, and the rate they went at, per second.
    fn finish(self) -> Result<(u64, f64)> {
        self.done.store(true, Ordering::Relaxed);
        let (sent, took) = self
            .thread
            .join()
            .map_err(|_| anyhow!("the flood panicked"))??;
        Ok((sent, sent as f64 / took.as_secs_f64()))
    }
}

/// The robot's states as an operator receives them, the latest kept.
struct States {
    feed: crate::Feed<RobotState>,
    latest: Option<RobotState>,
}

impl States {
    /// The first state from now on that `pred` holds for, within `within`.
    fn until(
        &mut self,
        within: Duration,
        pred: impl Fn(&RobotState) -> bool,
    ) -> Result<RobotState> {
        let until = Instant::now() + within;
        while Instant::now() < until {
            for s in self.feed.drain() {
                let found = pred(&s);
                self.latest = Some(s.clone());
                if found {
                    return Ok(s);
                }
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        bail!("no such state within {within:?}")
    }

    /// The robot's clock at its latest state.
    fn now(&mut self) -> Result<Stamp> {
        if let Some(s) = self.feed.drain().pop() {
            self.latest = Some(s);
        }
        match &self.latest {
            Some(s) => Ok(s.stamp),
            None => Ok(self.until(Duration::from_secs(3), |_| true)?.stamp),
        }
    }
}

/// What `stucco bench stop` measures.
#[derive(Clone, Debug)]
pub struct StopBenchJob {
    /// The robot's mission (`missions/robot.toml`: standing by).
    pub mission: PathBuf,
    /// Stops to time.
    pub stops: usize,
    /// Other commands a second meanwhile, from another operator.
    pub flood_per_s: f64,
    /// The `stucco` binary, to run a client that froze in a process of its
    /// own (none: no such client).
    pub frozen_client: Option<PathBuf>,
}

/// Stop → zero velocity, over many stops.
#[derive(Clone, Debug, Serialize)]
pub struct StopBenchReport {
    /// Stops timed.
    pub stops: usize,
    /// From the stop sent to the first state showing the drive command
    /// zero, received (the robot's whole way: the command over the link,
    /// the next control period, its state back): median, ms.
    pub stop_to_zero_ms_p50: f64,
    /// The same, 99th percentile, ms.
    pub stop_to_zero_ms_p99: f64,
    /// The same, the longest, ms.
    pub stop_to_zero_ms_max: f64,
    /// Control periods from the one during which the stop was taken to the
    /// first whose drive command was zero, at most (1: the next one).
    pub periods_to_zero_max: u64,
    /// Other commands sent meanwhile.
    pub other_commands: u64,
    /// Their rate, per second.
    pub other_commands_per_s: f64,
    /// A client that froze was subscribed to everything the robot
    /// publishes.
    pub frozen_client: bool,
}

/// Times `job.stops` stops of a jogging robot, with other traffic and a
/// client that froze.
pub fn bench_stop(job: &StopBenchJob) -> Result<StopBenchReport> {
    if job.stops == 0 || !(job.flood_per_s.is_finite() && job.flood_per_s > 0.0) {
        return Err(stucco_runtime::BadInput(
            "--stops and --other-per-s: positive numbers".to_owned(),
        )
        .into());
    }
    let robot = LoopbackRobot::start(&job.mission)?;
    let peer = robot.peer();
    let frozen = job
        .frozen_client
        .as_deref()
        .map(|exe| FrozenClient::start(exe, &robot))
        .transpose()?;
    let flood = Flood::start(&peer, job.flood_per_s)?;
    let mut op = Operator::connect(&peer, "ann")?;
    let mut states = States {
        feed: op.states(ROBOT)?,
        latest: None,
    };
    let mut ms = Vec::with_capacity(job.stops);
    let mut periods_max = 0;
    for i in 0..job.stops {
        // Back and forth, so the robot stays where it stood.
        let speed_mps = if i % 2 == 0 { 0.15 } else { -0.15 };
        let now = states.now()?;
        let jog = Command::Jog {
            speed_mps,
            steer_rad: 0.0,
            ttl_s: 2.0,
        };
        let ack = op.send_at(ROBOT, now, jog, 5.0)?;
        if ack.reply != Reply::Accepted {
            bail!("jog {i} refused: {:?}", ack.reply);
        }
        states
            .until(Duration::from_secs(3), |s| s.drive.speed_mps != 0.0)
            .with_context(|| format!("jog {i} did not drive"))?;
        // Somewhere in a control period.
        std::thread::sleep(Duration::from_micros((i as u64 * 7_919) % 20_000));
        let now = states.now()?;
        let t0 = Instant::now();
        let ack = op.send_at(ROBOT, now, Command::Stop, 5.0)?;
        let zero = states
            .until(Duration::from_secs(3), |s| {
                s.stamp >= ack.stamp && s.drive.speed_mps == 0.0
            })
            .with_context(|| format!("stop {i} did not stop the robot"))?;
        ms.push(t0.elapsed().as_secs_f64() * 1e3);
        let periods = (zero.stamp.seconds_since(ack.stamp) / DT_S).round() as u64 + 1;
        periods_max = periods_max.max(periods);
    }
    let (other_commands, other_commands_per_s) = flood.finish()?;
    drop(frozen);
    robot.finish()?;
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| ms[((ms.len() as f64 - 1.0) * q).round() as usize];
    Ok(StopBenchReport {
        stops: job.stops,
        stop_to_zero_ms_p50: at(0.5),
        stop_to_zero_ms_p99: at(0.99),
        stop_to_zero_ms_max: at(1.0),
        periods_to_zero_max: periods_max,
        other_commands,
        other_commands_per_s,
        frozen_client: job.frozen_client.is_some(),
    })
}

/// What `stucco bench commands` measures.
#[derive(Clone, Debug)]
pub struct CommandsBenchJob {
    /// The robot's mission (`missions/robot.toml`: standing by).
    pub mission: PathBuf,
    /// Commands to send.
    pub count: u64,
    /// Their rate, per second.
    pub per_s: f64,
}

/// The process's memory while a robot takes many commands.
#[derive(Clone, Debug, Serialize)]
pub struct CommandsBenchReport {
    /// Commands sent.
    pub commands: u64,
    /// Their rate, per second.
    pub per_s: f64,
    /// Resident memory when a tenth of them had been sent, MB.
    pub rss_at_tenth_mb: f64,
    /// Resident memory when all had, MB.
    pub rss_at_end_mb: f64,
    /// The largest of the readings taken every tenth, MB.
    pub rss_max_mb: f64,
}

/// This process's resident memory, MB (Linux).
fn rss_mb() -> Result<f64> {
    let status = std::fs::read_to_string("/proc/self/status").context("/proc/self/status")?;
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .ok_or_else(|| anyhow!("/proc/self/status: no VmRSS"))?;
    Ok(kb / 1024.0)
}

/// Sends `job.count` status commands, each with a fresh id, and reads the
/// process's memory (the robot's, the operator's) at every tenth.
pub fn bench_commands(job: &CommandsBenchJob) -> Result<CommandsBenchReport> {
    if job.count < 10 || !(job.per_s.is_finite() && job.per_s > 0.0) {
        return Err(stucco_runtime::BadInput(
            "--count: at least 10; --per-s: a positive number".to_owned(),
        )
        .into());
    }
    let robot = LoopbackRobot::start(&job.mission)?;
    let mut op = Operator::connect(&robot.peer(), "ann")?;
    let mut states = States {
        feed: op.states(ROBOT)?,
        latest: None,
    };
    let every = Duration::from_secs_f64(1.0 / job.per_s);
    let t0 = Instant::now();
    let mut readings = Vec::with_capacity(10);
    for sent in 0..job.count {
        if sent % 1000 == 0 {
            states.now()?;
        }
        let now = states.latest.as_ref().map_or(Stamp::ZERO, |s| s.stamp);
        let due = t0 + every.mul_f64(sent as f64);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        op.post(ROBOT, now, Command::Status, 5.0)?;
        if (sent + 1) % (job.count / 10) == 0 {
            readings.push(rss_mb()?);
        }
    }
    let per_s = job.count as f64 / t0.elapsed().as_secs_f64();
    // The last of them answered.
    let now = states.now()?;
    op.send_at(ROBOT, now, Command::Status, 5.0)?;
    let end = rss_mb()?;
    robot.finish()?;
    Ok(CommandsBenchReport {
        commands: job.count,
        per_s,
        rss_at_tenth_mb: readings[0],
        rss_at_end_mb: end,
        rss_max_mb: readings.iter().copied().fold(end, f64::max),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Settings no bench can run with are refused as bad input (exit code
    /// 2), before any robot starts.
    #[test]
    fn a_bench_with_nothing_to_measure_is_refused_as_bad_input() {
        let stop = bench_stop(&StopBenchJob {
            mission: PathBuf::from("missions/robot.toml"),
            stops: 0,
            flood_per_s: 1000.0,
            frozen_client: None,
        });
        let commands = bench_commands(&CommandsBenchJob {
            mission: PathBuf::from("missions/robot.toml"),
            count: 1_000_000,
            per_s: f64::NAN,
        });
        for (e, field) in [(stop.err(), "--stops"), (commands.err(), "--per-s")] {
            let e = e.map(|e| e.downcast::<stucco_runtime::BadInput>());
            assert!(matches!(&e, Some(Ok(b)) if b.0.contains(field)), "{e:?}");
        }
    }
}
