//! `stucco op`: the operator's console — send a telecommand and wait for
//! its reply (and its end), watch a robot, list the robots, measure the
//! command → acknowledgement latency.

use anyhow::{Result, anyhow};
use serde::Serialize;
use std::time::{Duration, Instant};
use stucco_core::telemetry::{Estimate, Event, PlasterCoverage};
use stucco_core::{Ack, Command, Reply, RobotState, Stamp, Telecommand};
use stucco_link::{LinkConfig, OperatorClient, ScanFrame, keys, parse};

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
        stucco_link::operator_chunk(identity)
            .map_err(|why| stucco_runtime::BadInput(format!("--as: {why}")))?;
        Ok(Operator {
            client: OperatorClient::new(stucco_link::open(link)?),
            identity: identity.to_owned(),
            counter: 0,
        })
    }

    /// The robot's next published state.
    pub fn state(&self, robot: &str, within: Duration) -> Result<RobotState> {
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
        Ok(self.state(robot, within)?.stamp)
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
        let ack = self.send_telecommand(robot, &t, deadline_s)?;
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

    /// Sends `command` to `robot`, issued at `now` on the robot's clock
    /// (from a state the caller has at hand) and valid `deadline_s` from
    /// then; returns its first reply.
    pub fn send_at(
        &mut self,
        robot: &str,
        now: Stamp,
        command: Command,
        deadline_s: f64,
    ) -> Result<Ack> {
        let t = self.telecommand(now, deadline_s, command);
        self.send_telecommand(robot, &t, deadline_s)
    }

    fn send_telecommand(&self, robot: &str, t: &Telecommand, deadline_s: f64) -> Result<Ack> {
        let give_up = Instant::now() + Duration::from_secs_f64(deadline_s.clamp(1.0, 60.0));
        Ok(self.client.send(robot, t, RETRY, give_up)?)
    }

    /// Sends `command` to `robot` once, issued at `now` on the robot's
    /// clock, and does not wait for its reply: traffic for benches.
    pub fn post(
        &mut self,
        robot: &str,
        now: Stamp,
        command: Command,
        deadline_s: f64,
    ) -> Result<()> {
        let t = self.telecommand(now, deadline_s, command);
        Ok(self.client.post(robot, &t)?)
    }

    /// Subscribes to everything `robot` publishes and never reads it (a
    /// client that froze), until the process ends: for benches and tests,
    /// in a process of its own.
    pub fn stall(&self, robot: &str) -> Result<()> {
        let _frozen = self.client.stall(robot)?;
        loop {
            std::thread::park();
        }
    }

    /// Sends `count` status queries one after another and measures each
    /// one's round trip to its acknowledgement.
    pub fn bench(&mut self, robot: &str, count: usize) -> Result<BenchReport> {
        let states = self.client.watch(keys::state(robot))?;
        let mut now = self.robot_time(robot, Duration::from_secs(3))?;
        let mut ms = Vec::with_capacity(count);
        for _ in 0..count {
            // The robot's clock runs on while we measure: the latest state
            // gives it, and the deadline is as long as the robot takes.
            while let Ok(Some(s)) = states.try_recv() {
                if let Ok(state) = parse::<RobotState>(&s) {
                    now = state.stamp;
                }
            }
            let t = self.telecommand(now, stucco_mission::MAX_DEADLINE_AHEAD_S, Command::Status);
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
    pub fn events(&self, robot: &str) -> Result<Feed<Event>> {
        Ok(Feed::new(self.client.watch(keys::events(robot))?))
    }

    /// `robot`'s states from now on.
    pub fn states(&self, robot: &str) -> Result<Feed<RobotState>> {
        Ok(Feed::new(self.client.watch(keys::state(robot))?))
    }

    /// One heartbeat to `robot`: the link is up while they come.
    pub fn heartbeat(&self, robot: &str) -> Result<()> {
        Ok(self.client.heartbeat(robot, &self.identity)?)
    }

    /// The robots on the network.
    pub fn list(&self) -> Result<Vec<String>> {
        Ok(self.client.list(Duration::from_secs(1))?)
    }

    /// Follows `robot` for `seconds` (forever without), handing `print`
    /// one line for each thing worth telling: its state once a second (with
    /// the nearest echo of its latest scan), every event and reply as it
    /// comes, its map when what it has perceived changes, its plastering
    /// coverage when it moves on. With `json`, the lines are the messages
    /// themselves, each `{"topic": ..., "message": ...}`. Keeps the link up
    /// with the operator's heartbeat meanwhile.
    pub fn watch(
        &self,
        robot: &str,
        seconds: Option<f64>,
        json: bool,
        mut print: impl FnMut(String),
    ) -> Result<()> {
        let sub = |key: String| self.client.watch(key);
        let state = sub(keys::state(robot))?;
        let events = sub(keys::events(robot))?;
        let acks = self.client.acks(robot)?;
        let map = sub(keys::map(robot))?;
        let coverage = sub(keys::coverage(robot))?;
        let scans = sub(keys::scan(robot))?;
        let until = seconds.map(|s| Instant::now() + Duration::from_secs_f64(s));
        let mut shown = Instant::now() - Duration::from_secs(2);
        let mut beat = Instant::now() - Duration::from_secs(1);
        let mut view = WatchView::default();
        while until.is_none_or(|u| Instant::now() < u) {
            // A person watching is the link: their heartbeat, 20 a second
            // (a robot run faster than the wall clock has its link's
            // timeout shortened as much).
            if beat.elapsed() >= Duration::from_millis(50) {
                self.client.heartbeat(robot, &self.identity)?;
                beat = Instant::now();
            }
            let mut idle = true;
            let mut emit = |topic: &str, v: serde_json::Value, line: Option<String>| {
                idle = false;
                if json {
                    print(serde_json::json!({ "topic": topic, "message": v }).to_string());
                } else if let Some(line) = line {
                    print(line);
                }
            };
            while let Ok(Some(s)) = scans.try_recv() {
                if let Ok(frame) = ScanFrame::decode(&s.payload().to_bytes()) {
                    view.nearest_m = frame
                        .points
                        .iter()
                        .map(|p| f64::from(p[0]).hypot(f64::from(p[1])))
                        .min_by(f64::total_cmp);
                    if json {
                        let v = serde_json::json!({
                            "stamp": frame.stamp,
                            "points": frame.points,
                        });
                        emit("scan", v, None);
                    }
                }
            }
            while let Ok(Some(s)) = events.try_recv() {
                match parse::<Event>(&s) {
                    Ok(e) => emit("event", json_of(&e), Some(event_line(&e))),
                    Err(e) => emit("event", serde_json::Value::Null, Some(unread("event", &e))),
                }
            }
            while let Ok(Some(s)) = acks.try_recv() {
                match parse::<Ack>(&s) {
                    Ok(a) => emit("reply", json_of(&a), Some(reply_line(&a))),
                    Err(e) => emit("reply", serde_json::Value::Null, Some(unread("reply", &e))),
                }
            }
            while let Ok(Some(s)) = map.try_recv() {
                if let Ok(m) = parse::<Estimate>(&s) {
                    let line = view.map_line(&m);
                    emit("map", json_of(&m), line);
                }
            }
            while let Ok(Some(s)) = coverage.try_recv() {
                if let Ok(c) = parse::<PlasterCoverage>(&s) {
                    let line = view.coverage_line(&c);
                    emit("coverage", json_of(&c), line);
                }
            }
            let mut latest = None;
            while let Ok(Some(s)) = state.try_recv() {
                latest = Some(s);
            }
            if let Some(s) = latest
                && (json || shown.elapsed() >= Duration::from_secs(1))
                && let Ok(state) = parse::<RobotState>(&s)
            {
                let line = view.state_line(&state);
                emit("state", json_of(&state), Some(line));
                shown = Instant::now();
            }
            if idle {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        Ok(())
    }
}

/// What `stucco op NAME watch` remembers between lines.
#[derive(Default)]
struct WatchView {
    /// The nearest echo of the latest scan, m.
    nearest_m: Option<f64>,
    /// The last map and coverage lines shown (shown again only changed).
    map: String,
    coverage: String,
}

/// Text a robot sent, made safe for a terminal: control characters
/// escaped (none can forge a line or move the cursor), at most
/// [`PRINTED_CHARS`] characters.
fn printable(text: &str) -> String {
    let mut out: String = text
        .chars()
        .take(PRINTED_CHARS)
        .flat_map(|c| {
            let escaped: Vec<char> = if c.is_control() {
                c.escape_default().collect()
            } else {
                vec![c]
            };
            escaped
        })
        .collect();
    if text.chars().nth(PRINTED_CHARS).is_some() {
        out.push('…');
    }
    out
}

/// The most characters of one field a line shows.
const PRINTED_CHARS: usize = 120;

/// A message as JSON, for `watch --json`.
fn json_of(message: &impl Serialize) -> serde_json::Value {
    serde_json::to_value(message).unwrap_or(serde_json::Value::Null)
}

/// A message's fields but its stamp and tag, compact and safe to print.
fn fields(message: &impl Serialize, tag: &str) -> String {
    let mut v = json_of(message);
    match v.as_object_mut() {
        Some(m) => {
            m.remove("stamp");
            m.remove(tag);
            if m.is_empty() {
                return String::new();
            }
        }
        None => return String::new(),
    }
    printable(&v.to_string())
}

/// An event: when, its kind, and its other fields.
fn event_line(e: &Event) -> String {
    format!(
        "{:>9.1} s  event  {} {}",
        e.stamp.as_secs_f64(),
        e.kind.name(),
        fields(e, "event")
    )
    .trim_end()
    .to_owned()
}

/// A reply: when, to which command, what, and why.
fn reply_line(a: &Ack) -> String {
    let (what, why) = match &a.reply {
        Reply::Accepted => ("accepted", String::new()),
        Reply::Done => ("done", String::new()),
        Reply::Rejected { reason } => ("rejected", printable(reason)),
        Reply::Failed { reason, code } => (
            "failed",
            match code {
                Some(code) => format!("[{}] {}", printable(code), printable(reason)),
                None => printable(reason),
            },
        ),
    };
    format!(
        "{:>9.1} s  reply  {what} {} {why}",
        a.stamp.as_secs_f64(),
        printable(&a.id)
    )
    .trim_end()
    .to_owned()
}

/// A message this `op` could not read (a newer robot's, or a broken one).
fn unread(topic: &str, e: &impl std::fmt::Display) -> String {
    format!(
        "{:>11}  {topic:<6} not read: {}",
        "",
        printable(&e.to_string())
    )
}

impl WatchView {
    fn state_line(&self, v: &RobotState) -> String {
        let mut mode = v.mission.name().to_owned();
        if let Some(why) = v.mission.reason() {
            mode = format!("{mode} ({})", printable(why));
        }
        let task = match &v.task {
            Some((k, name)) => format!("task {k} {}", printable(name)),
            None => "no task".to_owned(),
        };
        // The pose's frame is the room's, when the robot follows a plan.
        let room = v
            .room
            .as_deref()
            .map_or_else(String::new, |r| format!(" in {}", printable(r)));
        let mut line = format!(
            "{:>9.1} s  state  {mode} · {task} · {}  pose{room} {:.2} {:.2} m {:.1}°  σ {:.1} cm  drive {:.2} m/s",
            v.stamp.as_secs_f64(),
            v.behaviour.as_ref().map_or("-", |b| b.name()),
            v.pose.x,
            v.pose.y,
            v.pose.theta.to_degrees(),
            100.0 * v.position_sigma_m,
            v.drive.speed_mps,
        );
        if let Some(d) = self.nearest_m {
            line += &format!("  nearest {d:.2} m");
        }
        if let Some(h) = v.hazard {
            line += &format!("  HOLD: {}", h.name());
        }
        line
    }

    /// The map in one line, when it differs from the last one shown.
    fn map_line(&mut self, map: &Estimate) -> Option<String> {
        let line = format!(
            "map    room {:.2} × {:.2} m, {:.2} m high · doors {} · windows {} · on the floor {}",
            map.room_m[0],
            map.room_m[1],
            map.height_m,
            map.doors.len(),
            map.windows.len(),
            map.obstacles.len(),
        );
        // Sizes to the centimetre: a map line when something changed.
        (line != self.map).then(|| {
            self.map = line.clone();
            format!("{:>9.1} s  {line}", map.stamp.as_secs_f64())
        })
    }

    /// The coverage in one line, when it differs from the last one shown.
    fn coverage_line(&mut self, c: &PlasterCoverage) -> Option<String> {
        let surfaces: Vec<String> = c
            .surfaces
            .iter()
            .map(|s| {
                let name = s.surface.name();
                let mut part = if s.planned_spray_s > 0.0 {
                    format!("{name}: {:.0}%", s.done_pct())
                } else {
                    format!("{name}: nothing planned")
                };
                if s.unreachable_m2 > 0.0 {
                    part += &format!(" ({:.2} m² out of reach)", s.unreachable_m2);
                }
                part
            })
            .collect();
        let line = format!(
            "coverage  station {}/{} · {}",
            c.stations_done,
            c.stations,
            surfaces.join(" · ")
        );
        (line != self.coverage).then(|| {
            self.coverage = line.clone();
            line
        })
    }
}

/// A robot's messages of one kind (its events, its states) as they come.
pub struct Feed<T> {
    subscription: stucco_link::Subscription,
    kind: std::marker::PhantomData<fn() -> T>,
}

impl<T: serde::de::DeserializeOwned> Feed<T> {
    fn new(subscription: stucco_link::Subscription) -> Self {
        Feed {
            subscription,
            kind: std::marker::PhantomData,
        }
    }

    /// The messages that came since the last call (any that do not read
    /// as a `T` are left out).
    pub fn drain(&self) -> Vec<T> {
        let mut out = Vec::new();
        while let Ok(Some(s)) = self.subscription.try_recv() {
            if let Ok(v) = parse::<T>(&s) {
                out.push(v);
            }
        }
        out
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use stucco_core::telemetry::{EventKind, SurfaceCoverage, TaskFailure};
    use stucco_core::{SurfaceId, WallName};

    #[test]
    fn text_from_a_robot_cannot_forge_a_line() {
        assert_eq!(printable("link lost"), "link lost");
        let forged = printable("ok\n     12.0 s  state  done\u{1b}[2K");
        assert!(!forged.chars().any(char::is_control), "{forged}");
        assert!(forged.contains("\\n"), "{forged}");
        let long = printable(&"x".repeat(1_000_000));
        assert_eq!(long.chars().count(), PRINTED_CHARS + 1);
    }

    #[test]
    fn coverage_reads_as_a_line_shown_when_it_moves_on() {
        let mut c = PlasterCoverage {
            task: 2,
            stations_done: 3,
            stations: 14,
            surfaces: vec![
                SurfaceCoverage {
                    surface: SurfaceId::Wall(WallName::SOUTH),
                    planned_spray_s: 200.0,
                    done_spray_s: 50.0,
                    unreachable_m2: 0.0,
                },
                SurfaceCoverage {
                    surface: SurfaceId::Ceiling,
                    planned_spray_s: 0.0,
                    done_spray_s: 0.0,
                    unreachable_m2: 0.4,
                },
            ],
        };
        let mut view = WatchView::default();
        assert_eq!(
            view.coverage_line(&c).as_deref(),
            Some(
                "coverage  station 3/14 · wall 1: 25% · ceiling: nothing planned (0.40 m² out of reach)"
            )
        );
        assert_eq!(view.coverage_line(&c), None);
        c.surfaces[0].done_spray_s = 60.0;
        assert!(view.coverage_line(&c).unwrap().contains("wall 1: 30%"));
    }

    #[test]
    fn a_refusal_reads_with_its_reason() {
        let ack = stucco_core::Ack {
            id: "c1".to_owned(),
            stamp: Stamp::from_secs_f64(12.5),
            reply: Reply::Rejected {
                reason: "door 7 is not known (1 found)".to_owned(),
            },
        };
        let line = reply_line(&ack);
        assert_eq!(
            line,
            "     12.5 s  reply  rejected c1 door 7 is not known (1 found)"
        );
    }

    #[test]
    fn an_event_reads_with_its_kind_and_fields() {
        let e = Event {
            stamp: Stamp::from_secs_f64(3.0),
            kind: EventKind::TaskFailed {
                task: 2,
                reason: "map_room: no clear way\nreaches".to_owned(),
                failure: TaskFailure::NoWayToCorners,
            },
        };
        let line = event_line(&e);
        assert!(
            line.starts_with("      3.0 s  event  task_failed {"),
            "{line}"
        );
        assert!(line.contains("\"code\":\"no_way_to_corners\""), "{line}");
        assert!(!line.chars().any(char::is_control), "{line}");
    }
}
