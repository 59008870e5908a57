//! The robot's link over Eclipse Zenoh — the only crate of stucco that
//! knows zenoh.
//!
//! Key expressions, one robot named `NAME`:
//! - `stucco/NAME/cmd/OPERATOR`: a queryable (on `stucco/NAME/cmd/*`);
//!   a query's payload is a [`Telecommand`] as JSON, its reply the first
//!   [`Ack`] (JSON). The key's last chunk is the operator sending it: with
//!   zenoh's access control each authenticated user may query only their
//!   own key, so the robot knows who sent a command, and refuses one whose
//!   `operator` field names someone else;
//! - `stucco/NAME/acks`: every reply, published (the later `done` or
//!   `failed` of an accepted command too);
//! - `stucco/NAME/state`, `stucco/NAME/events`: the robot's state and its
//!   executive's events, JSON;
//! - `stucco/NAME/map`: what the robot has perceived, by the ids
//!   telecommands name (walls, doors, windows, what stands on the floor,
//!   the room's size), JSON, once a second;
//! - `stucco/NAME/scan`: the latest laser scan's echoes in the robot's
//!   frame, 10 a second, in the compact binary encoding of [`scan`];
//! - `stucco/NAME/coverage`: the plastering task's progress over its plan,
//!   surface by surface, JSON, once a second while it runs;
//! - `stucco/NAME/heartbeat`: once a second;
//! - `stucco/NAME/info`: a queryable answering the robot's name (for
//!   `stucco op list`);
//! - `stucco/NAME/operator`: the operators' heartbeats, which define the
//!   link (its loss triggers the mission's link-loss policy).
//!
//! JSON for everything but scans, so any zenoh client (Python, C, the
//! zenoh CLI tools) can command and watch a robot.
//!
//! A robot's body reached over zenoh (`stucco/NAME/platform/...`): see
//! [`platform`].
//!
//! What zenoh's access control refuses reaches the robot through
//! [`audit`]: [`RobotLink::denials`].

pub mod audit;
mod outbox;
pub mod platform;
pub mod scan;

pub use audit::Denial;
use outbox::{Outbox, Publishers, Topic};
pub use platform::{PlatformServer, ZenohPlatform};
pub use scan::{ScanDecodeError, ScanFrame};
use serde::Serialize;
use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};
use stucco_core::{Ack, Reply, Stamp, Telecommand};
use zenoh::Wait;
use zenoh::handlers::{FifoChannelHandler, RingChannel, RingChannelHandler};
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::query::{Query, Queryable};
use zenoh::sample::Sample;

pub use zenoh::Session;

/// A subscription's queue of samples.
pub type Subscription = Subscriber<RingChannelHandler<Sample>>;

/// Messages a watcher's subscription holds before it drops the oldest: a
/// reader that falls behind loses old states, never holds up the robot (a
/// FIFO that fills blocks the session's delivery, and with it the
/// robot's publishing: measured, a state feed left unread for a minute
/// slowed the robot's loop to a sixtieth of its pace).
pub const WATCH_CAPACITY: usize = 1024;

/// Why `name` cannot be an operator's name in a key (`stucco/NAME/cmd/
/// OPERATOR`), if it cannot: a single key chunk of letters, digits, `-`,
/// `_`, `.` and `@`, at most 64 bytes.
pub fn operator_chunk(name: &str) -> Result<(), String> {
    let ok = !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '@'));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "operator {name:?}: 1 to 64 letters, digits, '-', '_', '.' or '@' (it is a key \
             chunk, and the user name zenoh authenticates)"
        ))
    }
}

/// Waits until `querier` has a queryable to answer it, or `until`: a
/// session just opened may not have heard of the robot's yet.
fn answerable(querier: &zenoh::query::Querier<'_>, until: Instant) -> Result<(), LinkError> {
    while !querier.matching_status().wait().map_err(z)?.matching() && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(())
}

/// The largest telecommand taken, bytes (a query's payload): larger ones
/// are refused unread.
pub const MAX_COMMAND_BYTES: usize = 4096;

/// Runs a router: a session in router mode that the robots and operators
/// of a site connect to; it routes until dropped.
pub fn router(cfg: &LinkConfig) -> Result<Session, LinkError> {
    open(&LinkConfig {
        mode: Mode::Router,
        ..cfg.clone()
    })
}

/// What can go wrong on the link.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// Zenoh refused or failed.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The zenoh configuration file cannot be used as it is.
    #[error("{path}:{line}:{column}: {why}")]
    Config {
        /// The file.
        path: String,
        /// Line of the fault (1-based; 0 when the file could not be read).
        line: usize,
        /// Its column (1-based).
        column: usize,
        /// What is wrong there.
        why: String,
    },
    /// A message was not what stucco writes.
    #[error("a message on {key} is not valid: {why}")]
    Malformed {
        /// Where it came from.
        key: String,
        /// Why.
        why: String,
    },
    /// No reply came before the deadline.
    #[error("no reply from {robot} before the deadline ({tries} tries)")]
    NoReply {
        /// The robot.
        robot: String,
        /// Tries made.
        tries: usize,
    },
}

fn z(e: impl std::fmt::Display) -> LinkError {
    LinkError::Zenoh(e.to_string())
}

/// The key expressions of robot `name`.
pub mod keys {
    /// Commands from every operator (the robot's queryable).
    pub fn cmd(name: &str) -> String {
        format!("stucco/{name}/cmd/*")
    }
    /// Commands from `operator` (a key chunk: see [`super::operator_chunk`]).
    pub fn command(name: &str, operator: &str) -> String {
        format!("stucco/{name}/cmd/{operator}")
    }
    /// Every reply.
    pub fn acks(name: &str) -> String {
        format!("stucco/{name}/acks")
    }
    /// The robot's state.
    pub fn state(name: &str) -> String {
        format!("stucco/{name}/state")
    }
    /// The executive's events.
    pub fn events(name: &str) -> String {
        format!("stucco/{name}/events")
    }
    /// What the robot has perceived.
    pub fn map(name: &str) -> String {
        format!("stucco/{name}/map")
    }
    /// The latest scan (binary, see [`crate::scan`]).
    pub fn scan(name: &str) -> String {
        format!("stucco/{name}/scan")
    }
    /// The plastering task's progress.
    pub fn coverage(name: &str) -> String {
        format!("stucco/{name}/coverage")
    }
    /// Once a second.
    pub fn heartbeat(name: &str) -> String {
        format!("stucco/{name}/heartbeat")
    }
    /// Who is there (queryable).
    pub fn info(name: &str) -> String {
        format!("stucco/{name}/info")
    }
    /// The operators' heartbeats: the link is up while they come.
    pub fn operator(name: &str) -> String {
        format!("stucco/{name}/operator")
    }
}

/// A session's role on the network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// Talks directly to the peers it connects to or that connect to it
    /// (the default: one robot, one operator, nothing else needed).
    #[default]
    Peer,
    /// Talks through the router it connects to (a site's network).
    Client,
    /// Routes for the others (`stucco router`).
    Router,
}

/// How to join the zenoh network.
#[derive(Clone, Debug, Default)]
pub struct LinkConfig {
    /// The session's role.
    pub mode: Mode,
    /// Endpoints to listen on (`tcp/127.0.0.1:7447`,
    /// `unixsock-stream/PATH`); none: connect only.
    pub listen: Vec<String>,
    /// Endpoints (peers or a router) to connect to.
    pub connect: Vec<String>,
    /// A zenoh configuration file (JSON5), read first; the endpoints
    /// above are added to it.
    pub config_file: Option<std::path::PathBuf>,
}

/// Opens a zenoh session, multicast scouting off: the endpoints say whom
/// to talk to.
pub fn open(cfg: &LinkConfig) -> Result<Session, LinkError> {
    let mode = match cfg.mode {
        Mode::Peer => "\"peer\"",
        Mode::Client => "\"client\"",
        Mode::Router => "\"router\"",
    };
    let mut c = match &cfg.config_file {
        Some(path) => read_config(path)?,
        None => zenoh::Config::default(),
    };
    if cfg.config_file.is_none() || cfg.mode != Mode::Peer {
        c.insert_json5("mode", mode).map_err(z)?;
    }
    c.insert_json5("scouting/multicast/enabled", "false")
        .map_err(z)?;
    // Opening does not wait for the peers gossip tells of: a watcher
    // connected to a robot (a peer with no endpoint of its own) cannot be
    // reached, and each session opened after it waited the whole scouting
    // delay (500 ms) for it before its first command could go out. (What
    // a session asks first waits instead for a robot to answer it: see
    // `OperatorClient::send` and `list`.)
    c.insert_json5("open/return_conditions/connect_scouted", "false")
        .map_err(z)?;
    let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".to_owned());
    if !cfg.listen.is_empty() || cfg.config_file.is_none() {
        c.insert_json5("listen/endpoints", &list(&cfg.listen))
            .map_err(z)?;
    }
    if !cfg.connect.is_empty() {
        c.insert_json5("connect/endpoints", &list(&cfg.connect))
            .map_err(z)?;
    }
    zenoh::open(c).wait().map_err(z)
}

/// The zenoh configuration in the JSON5 file at `path`; a fault is named
/// with the file, line and column: a syntax error as JSON5 reports it, a
/// key or value zenoh does not take as zenoh reports it, its own source
/// location left out.
fn read_config(path: &std::path::Path) -> Result<zenoh::Config, LinkError> {
    let at = |line: usize, column: usize, why: String| LinkError::Config {
        path: path.display().to_string(),
        line,
        column,
        why,
    };
    let text = std::fs::read_to_string(path).map_err(|e| at(0, 0, format!("cannot read: {e}")))?;
    // Zenoh also reads YAML (by the file's extension); JSON5 is checked
    // here, YAML left to zenoh.
    let yaml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"));
    if !yaml
        && let Err(json5::Error::Message { msg, location }) =
            json5::from_str::<serde_json::Value>(&text)
    {
        let (line, column) = location.map_or((0, 0), |l| (l.line, l.column));
        // A syntax error's message draws the line; its last line says what
        // was expected.
        let why = msg
            .lines()
            .rev()
            .map(|l| l.trim().trim_start_matches("= ").trim())
            .find(|l| !l.is_empty())
            .unwrap_or("not JSON5")
            .to_owned();
        return Err(at(line, column, why));
    }
    // Read from the file, zenoh's errors carry the fault's location.
    zenoh::Config::from_file(path).map_err(|e| {
        let (line, column, why) = zenoh_fault(&e.to_string());
        at(line, column, why)
    })
}

/// The line, column and message of a fault zenoh found in a configuration
/// (`… Message { msg: "…", location: Some(Location { line: L, column: C })
/// } at SRC`); the whole text, at line 0, when it is not in that form.
fn zenoh_fault(text: &str) -> (usize, usize, String) {
    let number_after = |key: &str| -> Option<usize> {
        let rest = &text[text.find(key)? + key.len()..];
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        digits.parse().ok()
    };
    let msg = text.find("msg: \"").and_then(|i| {
        let rest = &text[i + 6..];
        rest.find("\", location")
            .map(|j| rest[..j].replace("\\\"", "\""))
    });
    match (msg, number_after("line: "), number_after("column: ")) {
        (Some(msg), Some(line), Some(column)) => (line, column, msg),
        _ => (0, 0, text.to_owned()),
    }
}

/// The robot's side: commands in, replies, state and events out.
///
/// Nothing here waits on the network: replies, and apart from them
/// everything published, go through bounded queues to sending threads of
/// their own (see [`RobotLink::dropped`]), so a congested link or a client
/// that stopped reading never holds up the robot's loop.
pub struct RobotLink {
    name: String,
    cmd: Queryable<FifoChannelHandler<Query>>,
    /// Answers `stucco op list` from zenoh's own thread.
    _info: Queryable<()>,
    /// Queries waiting for the first reply to their command.
    pending: Vec<(String, Query)>,
    /// Replies to queries (a querier's congestion control may hold them).
    replies: Outbox,
    /// What is published (dropped, never held, when a link congests).
    telemetry: Outbox,
    operators: Subscriber<FifoChannelHandler<Sample>>,
    denials: Receiver<Denial>,
    /// Commands refused for naming another operator than their key's.
    impostors: Vec<Denial>,
}

impl RobotLink {
    /// Declares robot `name` on `session`.
    pub fn new(session: &Session, name: &str) -> Result<Self, LinkError> {
        let publisher = |k: String| -> Result<Publisher<'static>, LinkError> {
            session.declare_publisher(k).express(true).wait().map_err(z)
        };
        // Replies and events go first (their priority is above the
        // telemetry's) but, like everything the robot publishes, are
        // dropped rather than queued when a link is congested: a
        // subscriber that stops reading must never hold up the sending
        // thread longer than it must. The record of what the robot did is
        // the job's events.jsonl on its disk.
        let record = |k: String| -> Result<Publisher<'static>, LinkError> {
            session
                .declare_publisher(k)
                .express(true)
                .priority(zenoh::qos::Priority::InteractiveHigh)
                .congestion_control(zenoh::qos::CongestionControl::Drop)
                .wait()
                .map_err(z)
        };
        let publishers = Publishers {
            acks: record(keys::acks(name))?,
            state: publisher(keys::state(name))?,
            events: record(keys::events(name))?,
            map: publisher(keys::map(name))?,
            // Scans are many and soon stale: dropped rather than queued
            // when the network is congested.
            scan: session
                .declare_publisher(keys::scan(name))
                .congestion_control(zenoh::qos::CongestionControl::Drop)
                .wait()
                .map_err(z)?,
            coverage: publisher(keys::coverage(name))?,
            heartbeat: publisher(keys::heartbeat(name))?,
        };
        let publishers = std::sync::Arc::new(publishers);
        let replies = Outbox::start(name, "link-replies", publishers.clone()).map_err(z)?;
        let telemetry = Outbox::start(name, "link-telemetry", publishers).map_err(z)?;
        let info = {
            let (sender, answer) = (replies.sender(), name.as_bytes().to_vec());
            session
                .declare_queryable(keys::info(name))
                .callback(move |q| sender.reply(q, answer.clone()))
                .wait()
                .map_err(z)?
        };
        Ok(RobotLink {
            name: name.to_owned(),
            cmd: session
                .declare_queryable(keys::cmd(name))
                .wait()
                .map_err(z)?,
            _info: info,
            pending: Vec::new(),
            replies,
            telemetry,
            operators: session
                .declare_subscriber(keys::operator(name))
                .wait()
                .map_err(z)?,
            denials: audit::listen(format!("stucco/{name}/")),
            impostors: Vec::new(),
        })
    }

    /// Replies and messages dropped so far because a sending thread had
    /// fallen a whole queue behind (a link congested for several periods).
    pub fn dropped(&self) -> u64 {
        self.replies.dropped() + self.telemetry.dropped()
    }

    /// What zenoh's access control refused on this robot's keys since the
    /// last call (seen only where [`audit::layer`] is part of the process's
    /// tracing subscriber).
    pub fn denials(&mut self) -> Vec<Denial> {
        let mut out = std::mem::take(&mut self.impostors);
        out.extend(self.denials.try_iter());
        out
    }

    /// True when an operator's heartbeat came since the last call.
    pub fn operator_heartbeat(&mut self) -> bool {
        let mut any = false;
        while let Ok(Some(_)) = self.operators.try_recv() {
            any = true;
        }
        any
    }

    /// The telecommands that came in since the last call. A query whose
    /// payload is not a telecommand is answered at once with a rejection.
    pub fn take_commands(&mut self, now: Stamp) -> Vec<Telecommand> {
        let mut out = Vec::new();
        while let Ok(Some(q)) = self.cmd.try_recv() {
            self.accept_query(q, now, &mut out);
        }
        out
    }

    /// Waits up to `timeout` for telecommands; returns those that came.
    pub fn wait_commands(&mut self, now: Stamp, timeout: Duration) -> Vec<Telecommand> {
        let mut out = Vec::new();
        if let Ok(Some(q)) = self.cmd.recv_timeout(timeout) {
            self.accept_query(q, now, &mut out);
        }
        out.extend(self.take_commands(now));
        out
    }

    fn accept_query(&mut self, q: Query, now: Stamp, out: &mut Vec<Telecommand>) {
        let parsed = q
            .payload()
            .ok_or_else(|| "no payload".to_owned())
            .and_then(|p| {
                if p.len() > MAX_COMMAND_BYTES {
                    return Err(format!(
                        "payload: {} bytes, at most {MAX_COMMAND_BYTES}",
                        p.len()
                    ));
                }
                serde_json::from_slice::<Telecommand>(&p.to_bytes()).map_err(|e| e.to_string())
            });
        // The key's last chunk: who sent it (the identity zenoh's access
        // control lets query that key).
        let sender = q
            .key_expr()
            .as_str()
            .rsplit('/')
            .next()
            .unwrap_or_default()
            .to_owned();
        let parsed = parsed.and_then(|t| {
            if t.operator == sender {
                Ok(t)
            } else {
                let claimed: String = t.operator.chars().take(64).collect();
                let denial = Denial {
                    zid: String::new(),
                    subject: sender.clone(),
                    action: format!("Command claiming operator {claimed:?}"),
                    key: q.key_expr().as_str().to_owned(),
                };
                tracing::warn!(robot = %self.name, "{denial}");
                self.impostors.push(denial);
                Err(format!(
                    "operator: the command names {claimed:?} but was sent as {sender:?} (its key \
                     {})",
                    q.key_expr()
                ))
            }
        });
        match parsed {
            Ok(t) => {
                self.pending.push((t.id.clone(), q));
                out.push(t);
            }
            Err(why) => {
                let ack = Ack {
                    id: String::new(),
                    stamp: now,
                    reply: Reply::Rejected {
                        reason: format!("not a telecommand: {why}"),
                    },
                };
                if let Ok(json) = serde_json::to_vec(&ack) {
                    self.replies.reply(q, json);
                }
            }
        }
    }

    /// Sends the executive's replies: each answers the queries waiting for
    /// its command, and all are published on `acks`.
    pub fn send_acks(&mut self, acks: &[Ack]) -> Result<(), LinkError> {
        for a in acks {
            let json = serde_json::to_vec(a).map_err(z)?;
            let (answered, rest): (Vec<_>, Vec<_>) = std::mem::take(&mut self.pending)
                .into_iter()
                .partition(|(id, _)| *id == a.id);
            self.pending = rest;
            for (_, q) in answered {
                self.replies.reply(q, json.clone());
            }
            self.telemetry.put(Topic::Acks, json);
        }
        Ok(())
    }

    /// Publishes the robot's state.
    pub fn publish_state(&self, state: &impl Serialize) -> Result<(), LinkError> {
        self.put_json(Topic::State, state)
    }

    /// Publishes what the robot has perceived.
    pub fn publish_map(&self, map: &impl Serialize) -> Result<(), LinkError> {
        self.put_json(Topic::Map, map)
    }

    /// Publishes a scan.
    pub fn publish_scan(&self, scan: &ScanFrame) -> Result<(), LinkError> {
        self.telemetry.put(Topic::Scan, scan.encode());
        Ok(())
    }

    /// Publishes the plastering progress.
    pub fn publish_coverage(&self, coverage: &impl Serialize) -> Result<(), LinkError> {
        self.put_json(Topic::Coverage, coverage)
    }

    /// Publishes events.
    pub fn publish_events<E: Serialize>(&self, events: &[E]) -> Result<(), LinkError> {
        events
            .iter()
            .try_for_each(|e| self.put_json(Topic::Events, e))
    }

    /// Publishes the heartbeat.
    pub fn heartbeat(&self, now: Stamp) -> Result<(), LinkError> {
        self.put_json(Topic::Heartbeat, &now)
    }

    fn put_json(&self, topic: Topic, message: &impl Serialize) -> Result<(), LinkError> {
        self.telemetry
            .put(topic, serde_json::to_vec(message).map_err(z)?);
        Ok(())
    }
}

/// The operator's side.
pub struct OperatorClient {
    session: Session,
}

impl OperatorClient {
    /// A client on `session`.
    pub fn new(session: Session) -> Self {
        OperatorClient { session }
    }

    /// Sends `t` to `robot` and returns its first reply, sending it again
    /// every `retry` until one comes or `give_up` passes. Earlier tries
    /// stay open meanwhile: on a slow link the first try's reply may come
    /// after the second was sent.
    pub fn send(
        &self,
        robot: &str,
        t: &Telecommand,
        retry: Duration,
        give_up: Instant,
    ) -> Result<Ack, LinkError> {
        let json = serde_json::to_vec(t).map_err(z)?;
        operator_chunk(&t.operator).map_err(|why| LinkError::Malformed {
            key: keys::cmd(robot),
            why,
        })?;
        let key = keys::command(robot, &t.operator);
        // The first try goes out once the robot's queryable is known (a
        // session just opened may not have heard of it yet), or after a
        // retry's period without.
        let querier = self
            .session
            .declare_querier(&key)
            .timeout(give_up.saturating_duration_since(Instant::now()))
            .wait()
            .map_err(z)?;
        answerable(&querier, (Instant::now() + retry).min(give_up))?;
        let mut tries = Vec::new();
        let mut next_try = Instant::now();
        while Instant::now() < give_up {
            if Instant::now() >= next_try {
                tries.push(querier.get().payload(json.clone()).wait().map_err(z)?);
                next_try = Instant::now() + retry;
            }
            for replies in &tries {
                while let Ok(Some(reply)) = replies.try_recv() {
                    if let Ok(sample) = reply.result() {
                        let ack = parse::<Ack>(sample)?;
                        if ack.id == t.id {
                            return Ok(ack);
                        }
                    }
                }
            }
            // Wait on the newest try: until the next retry while it is the
            // only one, a moment when older ones may still answer.
            let wait = if tries.len() == 1 {
                next_try.saturating_duration_since(Instant::now())
            } else {
                Duration::from_millis(2)
            };
            if let Some(last) = tries.last()
                && let Ok(Some(reply)) = last.recv_timeout(wait)
                && let Ok(sample) = reply.result()
            {
                let ack = parse::<Ack>(sample)?;
                if ack.id == t.id {
                    return Ok(ack);
                }
            }
        }
        Err(LinkError::NoReply {
            robot: robot.to_owned(),
            tries: tries.len(),
        })
    }

    /// Sends `t` to `robot` once and does not wait for its reply (which
    /// is dropped when it comes): traffic for benches and tests.
    pub fn post(&self, robot: &str, t: &Telecommand) -> Result<(), LinkError> {
        let json = serde_json::to_vec(t).map_err(z)?;
        self.session
            .get(keys::command(robot, &t.operator))
            .payload(json)
            .callback(|_| {})
            .wait()
            .map_err(z)
    }

    /// A client that stopped reading, for tests and benches: a subscriber
    /// to everything `robot` publishes whose callback never returns. It
    /// holds up this process's zenoh delivery for good (run it in a process
    /// of its own), and the robot's link to it congests.
    pub fn stall(&self, robot: &str) -> Result<Subscriber<()>, LinkError> {
        self.session
            .declare_subscriber(format!("stucco/{robot}/**"))
            .callback(|_| {
                loop {
                    std::thread::park();
                }
            })
            .wait()
            .map_err(z)
    }

    /// Publishes one heartbeat of operator `identity` to `robot`.
    pub fn heartbeat(&self, robot: &str, identity: &str) -> Result<(), LinkError> {
        self.session
            .put(keys::operator(robot), identity.to_owned())
            .wait()
            .map_err(z)
    }

    /// Every reply `robot` publishes from now on.
    pub fn acks(&self, robot: &str) -> Result<Subscription, LinkError> {
        self.watch(keys::acks(robot))
    }

    /// A subscriber to one of `robot`'s topics (`state`, `events`,
    /// `heartbeat`).
    pub fn watch(&self, key: String) -> Result<Subscription, LinkError> {
        self.session
            .declare_subscriber(key)
            .with(RingChannel::new(WATCH_CAPACITY))
            .wait()
            .map_err(z)
    }

    /// The robots that answer within `timeout`.
    pub fn list(&self, timeout: Duration) -> Result<Vec<String>, LinkError> {
        // Every robot's queryable, every reply: asked once one is known (a
        // session just opened may not have heard of any yet), or after half
        // the time given.
        let until = Instant::now() + timeout;
        let querier = self
            .session
            .declare_querier("stucco/*/info")
            .target(zenoh::query::QueryTarget::All)
            .consolidation(zenoh::query::ConsolidationMode::None)
            .timeout(timeout)
            .wait()
            .map_err(z)?;
        answerable(&querier, Instant::now() + timeout / 2)?;
        let replies = querier.get().wait().map_err(z)?;
        let timeout = until.saturating_duration_since(Instant::now());
        let mut names = Vec::new();
        while let Ok(Some(reply)) = replies.recv_timeout(timeout) {
            if let Ok(s) = reply.result()
                && let Ok(name) = s.payload().try_to_string()
            {
                names.push(name.into_owned());
            }
        }
        names.sort();
        names.dedup();
        Ok(names)
    }
}

/// The JSON payload of `sample`.
pub fn parse<T: serde::de::DeserializeOwned>(sample: &Sample) -> Result<T, LinkError> {
    serde_json::from_slice(&sample.payload().to_bytes()).map_err(|e| LinkError::Malformed {
        key: sample.key_expr().to_string(),
        why: e.to_string(),
    })
}

/// What a [`FaultyRelay`] does to the messages it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Faults {
    /// Each way, a message waits up to this long (uniformly), s.
    pub max_delay_s: f64,
    /// Share of messages lost, each way.
    pub loss: f64,
    /// Share of commands sent on twice.
    pub duplication: f64,
}

/// A bad link for tests: it carries `stucco/FROM/cmd/OPERATOR` queries to
/// `stucco/TO/cmd/OPERATOR` and their replies back, delaying, losing, duplicating
/// (and so reordering) them, and relays `TO`'s state as `FROM`'s. It stops
/// when dropped.
pub struct FaultyRelay {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl FaultyRelay {
    /// Starts the relay on its own session joined by `cfg`; `seed` fixes
    /// its faults' draws.
    pub fn start(
        cfg: &LinkConfig,
        from: &str,
        to: &str,
        faults: Faults,
        seed: u64,
    ) -> Result<Self, LinkError> {
        use std::sync::Arc;
        use std::sync::atomic::{AtomicBool, Ordering};
        let session = Arc::new(open(cfg)?);
        let cmd = session
            .declare_queryable(keys::cmd(from))
            .wait()
            .map_err(z)?;
        let state = session
            .declare_subscriber(keys::state(to))
            .wait()
            .map_err(z)?;
        let (from, to) = (from.to_owned(), to.to_owned());
        let stop = Arc::new(AtomicBool::new(false));
        let halt = stop.clone();
        // A small deterministic generator (SplitMix64): the faults of a
        // run are the seed's.
        let mut x = seed;
        let mut draw = move || {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as f64 / u64::MAX as f64
        };
        let thread = std::thread::spawn(move || {
            while !halt.load(Ordering::Relaxed) {
                while let Ok(Some(s)) = state.try_recv() {
                    let _ = session.put(keys::state(&from), s.payload().clone()).wait();
                }
                let Ok(Some(q)) = cmd.recv_timeout(Duration::from_millis(10)) else {
                    continue;
                };
                let copies = if draw() < faults.duplication { 2 } else { 1 };
                for _ in 0..copies {
                    let lose_request = draw() < faults.loss;
                    let lose_reply = draw() < faults.loss;
                    let d1 = draw() * faults.max_delay_s;
                    let d2 = draw() * faults.max_delay_s;
                    let (session, q, to) = (session.clone(), q.clone(), to.clone());
                    std::thread::spawn(move || {
                        std::thread::sleep(Duration::from_secs_f64(d1));
                        if lose_request {
                            return;
                        }
                        let payload = q
                            .payload()
                            .map(|p| p.to_bytes().into_owned())
                            .unwrap_or_default();
                        let operator = q.key_expr().as_str().rsplit('/').next().unwrap_or("");
                        let Ok(replies) = session
                            .get(keys::command(&to, operator))
                            .payload(payload)
                            .timeout(Duration::from_secs(3))
                            .wait()
                        else {
                            return;
                        };
                        let Ok(Some(reply)) = replies.recv_timeout(Duration::from_secs(3)) else {
                            return;
                        };
                        std::thread::sleep(Duration::from_secs_f64(d2));
                        if lose_reply {
                            return;
                        }
                        if let Ok(s) = reply.result() {
                            let _ = q.reply(q.key_expr().clone(), s.payload().clone()).wait();
                        }
                    });
                }
            }
        });
        Ok(FaultyRelay {
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for FaultyRelay {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod config_tests {
    use super::*;

    fn fault(text: &str) -> String {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("robot.json5");
        std::fs::write(&path, text).unwrap();
        let e = read_config(&path).map(|_| ()).unwrap_err();
        assert!(matches!(e, LinkError::Config { .. }), "{e:?}");
        e.to_string()
            .replace(&path.display().to_string(), "robot.json5")
    }

    #[test]
    fn a_bad_zenoh_config_names_its_file_line_and_column() {
        // A brace left open: where JSON5 stops, and what it expected.
        let e = fault("{\n  mode: \"peer\",\n  listen: { endpoints: [] \n  scouting: {},\n}\n");
        assert!(e.starts_with("robot.json5:3:"), "{e}");
        assert!(e.contains("expected"), "{e}");
        assert!(!e.contains(".rs:"), "zenoh's own source is no help: {e}");
        // A key zenoh does not know: its line and the keys it takes.
        let e = fault("{\n  mode: \"peer\",\n  lisen: { endpoints: [] },\n}\n");
        assert!(
            e.starts_with("robot.json5:3:3: unknown field `lisen`"),
            "{e}"
        );
        assert!(e.contains("`listen`") && !e.contains(".rs:"), "{e}");
        // A file that is not there.
        let e = read_config(std::path::Path::new("/nonexistent/z.json5"))
            .map(|_| ())
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("/nonexistent/z.json5:0:0: cannot read"),
            "{e}"
        );
    }

    #[test]
    fn the_shipped_zenoh_configs_load() {
        let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/config"));
        let mut n = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "json5") {
                read_config(&path).unwrap_or_else(|e| panic!("{e}"));
                n += 1;
            }
        }
        assert!(n >= 4, "{n}");
    }
}
