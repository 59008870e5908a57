//! `stucco op`: the operator's console — send a telecommand and wait for
//! its reply (and its end), watch a robot, list the robots, measure the
//! command → acknowledgement latency.

use anyhow::{Result, anyhow};
use serde::Serialize;
use std::time::{Duration, Instant};
use stucco_core::{Ack, Command, Reply, Stamp, Telecommand};
use stucco_link::{LinkConfig, OperatorClient, keys, parse};

/// Retry period of an unanswered command.
const RETRY: Duration = Duration::from_millis(500);

/// An operator connected to the network.
pub struct Operator {
    client: OperatorClient,
    /// Who is commanding.
    pub identity: String,
    counter: u64,
}

/// The result of one command: its first reply, and its last when waited
/// for.
#[derive(Clone, Debug, Serialize)]
pub struct CommandResult {
    /// The first reply (accepted, rejected, or done for immediate ones).
    pub ack: Ack,
    /// The final reply (done or failed), when waited for.
    pub last: Option<Ack>,
}

/// Command → acknowledgement latency over many commands.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// Commands sent.
    pub count: usize,
    /// Median, ms.
    pub p50_ms: f64,
    /// 99th percentile, ms.
    pub p99_ms: f64,
    /// Largest, ms.
    pub max_ms: f64,
}

impl Operator {
    /// Joins the network as `identity`.
    pub fn connect(link: &LinkConfig, identity: &str) -> Result<Self> {
        Ok(Operator {
            client: OperatorClient::new(stucco_link::open(link)?),
            identity: identity.to_owned(),
            counter: 0,
        })
    }

    /// The robot's next published state (JSON).
    pub fn state(&self, robot: &str, within: Duration) -> Result<serde_json::Value> {
        let sub = self.client.watch(keys::state(robot))?;
        let until = Instant::now() + within;
        while let Some(left) = until.checked_duration_since(Instant::now()) {
            if let Ok(Some(s)) = sub.recv_timeout(left) {
                return Ok(parse(&s)?);
            }
        }
        Err(anyhow!("{robot} publishes no state: is it running?"))
    }

    /// The robot's clock: the stamp of its latest state.
    pub fn robot_time(&self, robot: &str, within: Duration) -> Result<Stamp> {
        let v = self.state(robot, within)?;
        v["stamp"]
            .as_i64()
            .map(Stamp::from_nanos)
            .ok_or_else(|| anyhow!("{robot}'s state has no stamp"))
    }

    fn telecommand(&mut self, now: Stamp, deadline_s: f64, command: Command) -> Telecommand {
        self.counter += 1;
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        Telecommand {
            id: format!(
                "{}-{}-{nanos}-{}",
                self.identity,
                std::process::id(),
                self.counter
            ),
            operator: self.identity.clone(),
            issued: now,
            deadline: now.offset_secs(deadline_s),
            command,
        }
    }

    /// Sends `command` to `robot` (valid for `deadline_s` of the robot's
    /// time), returns its first reply, and with `wait` its final one.
    pub fn send(
        &mut self,
        robot: &str,
        command: Command,
        deadline_s: f64,
        wait: Option<Duration>,
    ) -> Result<CommandResult> {
        let now = self.robot_time(robot, Duration::from_secs(3))?;
        let t = self.telecommand(now, deadline_s, command);
        // Listen before sending: the end may come right after the reply.
        let acks = self.client.acks(robot)?;
        let give_up = Instant::now() + Duration::from_secs_f64(deadline_s.clamp(1.0, 60.0));
        let ack = self.client.send(robot, &t, RETRY, give_up)?;
        let mut last = None;
        if let Some(limit) = wait
            && ack.reply == Reply::Accepted
        {
            let until = Instant::now() + limit;
            while let Some(left) = until.checked_duration_since(Instant::now()) {
                let Ok(Some(s)) = acks.recv_timeout(left) else {
                    break;
                };
                let a: Ack = parse(&s)?;
                if a.id == t.id && matches!(a.reply, Reply::Done | Reply::Failed { .. }) {
                    last = Some(a);
                    break;
                }
            }
            if last.is_none() {
                return Err(anyhow!(
                    "{robot} took the command but did not finish it in time"
                ));
            }
        }
        Ok(CommandResult { ack, last })
    }

    /// Sends `count` status queries one after another and measures each
    /// one's round trip to its acknowledgement.
    pub fn bench(&mut self, robot: &str, count: usize) -> Result<BenchReport> {
        let now = self.robot_time(robot, Duration::from_secs(3))?;
        let mut ms = Vec::with_capacity(count);
        for _ in 0..count {
            // The robot's clock runs on while we measure: a long deadline.
            let t = self.telecommand(now, 1e6, Command::Status);
            let t0 = Instant::now();
            let ack =
                self.client
                    .send(robot, &t, RETRY, Instant::now() + Duration::from_secs(5))?;
            if ack.reply != Reply::Done {
                return Err(anyhow!("status refused: {:?}", ack.reply));
            }
            ms.push(t0.elapsed().as_secs_f64() * 1e3);
        }
        ms.sort_by(f64::total_cmp);
        let at = |q: f64| ms[((ms.len() as f64 - 1.0) * q).round() as usize];
        Ok(BenchReport {
            count,
            p50_ms: at(0.5),
            p99_ms: at(0.99),
            max_ms: at(1.0),
        })
    }

    /// `robot`'s events from now on; `drain` gives those that came.
    pub fn events(&self, robot: &str) -> Result<EventFeed> {
        Ok(EventFeed(self.client.watch(keys::events(robot))?))
    }

    /// `robot`'s states from now on.
    pub fn states(&self, robot: &str) -> Result<EventFeed> {
        Ok(EventFeed(self.client.watch(keys::state(robot))?))
    }

    /// One heartbeat to `robot`: the link is up while they come.
    pub fn heartbeat(&self, robot: &str) -> Result<()> {
        Ok(self.client.heartbeat(robot, &self.identity)?)
    }

    /// The robots on the network.
    pub fn list(&self) -> Result<Vec<String>> {
        Ok(self.client.list(Duration::from_secs(1))?)
    }

    /// Prints `robot`'s state (once a second), events and replies as they
    /// come, for `seconds` (forever without), and keeps the link up with
    /// the operator's heartbeat meanwhile.
    pub fn watch(
        &self,
        robot: &str,
        seconds: Option<f64>,
        mut print: impl FnMut(String),
    ) -> Result<()> {
        let state = self.client.watch(keys::state(robot))?;
        let events = self.client.watch(keys::events(robot))?;
        let acks = self.client.acks(robot)?;
        let until = seconds.map(|s| Instant::now() + Duration::from_secs_f64(s));
        let mut shown = Instant::now() - Duration::from_secs(2);
        let mut beat = Instant::now() - Duration::from_secs(1);
        while until.is_none_or(|u| Instant::now() < u) {
            // A person watching is the link: their heartbeat, 5 a second.
            if beat.elapsed() >= Duration::from_millis(200) {
                self.client.heartbeat(robot, &self.identity)?;
                beat = Instant::now();
            }
            let mut idle = true;
            while let Ok(Some(s)) = events.try_recv() {
                print(format!(
                    "event  {}",
                    s.payload().try_to_string().unwrap_or_default()
                ));
                idle = false;
            }
            while let Ok(Some(s)) = acks.try_recv() {
                print(format!(
                    "reply  {}",
                    s.payload().try_to_string().unwrap_or_default()
                ));
                idle = false;
            }
            let mut latest = None;
            while let Ok(Some(s)) = state.try_recv() {
                latest = Some(s);
            }
            if let Some(s) = latest
                && shown.elapsed() >= Duration::from_secs(1)
            {
                print(format!(
                    "state  {}",
                    s.payload().try_to_string().unwrap_or_default()
                ));
                shown = Instant::now();
                idle = false;
            }
            if idle {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        Ok(())
    }
}

/// A robot's events (or states) as they come.
pub struct EventFeed(stucco_link::Subscription);

impl EventFeed {
    /// The messages that came since the last call, as JSON.
    pub fn drain(&self) -> Vec<serde_json::Value> {
        let mut out = Vec::new();
        while let Ok(Some(s)) = self.0.try_recv() {
            if let Ok(v) = parse::<serde_json::Value>(&s) {
                out.push(v);
            }
        }
        out
    }
}
