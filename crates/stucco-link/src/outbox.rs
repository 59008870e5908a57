//! What the robot sends, sent off its control loop.
//!
//! The loop hands every reply and every message it publishes to a bounded
//! queue and goes on; a thread of the link's sends them. There are two:
//! one for replies, one for what is published. Nothing the network does
//! reaches back into the loop. A reply travels at its querier's congestion
//! control, which may be zenoh's `Block`: a querier that stopped reading
//! holds up the replies' thread (until zenoh closes its link), never the
//! loop, a stop or the vehicle's braking, nor the telemetry, which is
//! published with `Drop` and never waits. While a thread is held up its
//! queue fills, and what does not fit is dropped and counted: a querier
//! whose reply is dropped asks again, a watcher's state is superseded 50
//! times a second, and the record of what the robot did is the job's
//! events on its disk.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;
use zenoh::Wait;
use zenoh::pubsub::Publisher;
use zenoh::query::Query;

/// Messages the queue holds: at 50 periods a second, some five periods
/// of a robot answering a thousand commands a second.
pub const CAPACITY: usize = 1024;

/// A topic the robot publishes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Topic {
    Acks,
    State,
    Events,
    Map,
    Scan,
    Coverage,
    Heartbeat,
}

/// The publishers of a robot's topics, owned by the sending thread.
pub(crate) struct Publishers {
    pub acks: Publisher<'static>,
    pub state: Publisher<'static>,
    pub events: Publisher<'static>,
    pub map: Publisher<'static>,
    pub scan: Publisher<'static>,
    pub coverage: Publisher<'static>,
    pub heartbeat: Publisher<'static>,
}

impl Publishers {
    fn of(&self, topic: Topic) -> &Publisher<'static> {
        match topic {
            Topic::Acks => &self.acks,
            Topic::State => &self.state,
            Topic::Events => &self.events,
            Topic::Map => &self.map,
            Topic::Scan => &self.scan,
            Topic::Coverage => &self.coverage,
            Topic::Heartbeat => &self.heartbeat,
        }
    }
}

enum Message {
    Reply(Query, Vec<u8>),
    Put(Topic, Vec<u8>),
    Close,
}

/// The queue's sending end: [`Outbox::reply`] and [`Outbox::put`] never
/// wait.
#[derive(Clone)]
pub(crate) struct Sender {
    tx: SyncSender<Message>,
    dropped: Arc<AtomicU64>,
}

impl Sender {
    fn offer(&self, m: Message) {
        match self.tx.try_send(m) {
            Ok(()) => {}
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Answers `query` with `payload` (its query is closed once sent).
    pub fn reply(&self, query: Query, payload: Vec<u8>) {
        self.offer(Message::Reply(query, payload));
    }

    /// Publishes `payload` on `topic`.
    pub fn put(&self, topic: Topic, payload: Vec<u8>) {
        self.offer(Message::Put(topic, payload));
    }
}

/// A queue and its sending thread.
pub(crate) struct Outbox {
    sender: Sender,
    thread: Option<JoinHandle<()>>,
}

impl Outbox {
    /// Starts the thread `name` that sends replies and through
    /// `publishers`; `robot` names it in the log.
    pub fn start(robot: &str, name: &str, publishers: Arc<Publishers>) -> std::io::Result<Self> {
        let (tx, rx) = sync_channel(CAPACITY);
        let robot = robot.to_owned();
        let thread = std::thread::Builder::new()
            .name(name.to_owned())
            .spawn(move || send_all(&robot, &publishers, &rx))?;
        Ok(Outbox {
            sender: Sender {
                tx,
                dropped: Arc::new(AtomicU64::new(0)),
            },
            thread: Some(thread),
        })
    }

    /// A sending end (for a zenoh callback).
    pub fn sender(&self) -> Sender {
        self.sender.clone()
    }

    /// Answers `query` with `payload`.
    pub fn reply(&self, query: Query, payload: Vec<u8>) {
        self.sender.reply(query, payload);
    }

    /// Publishes `payload` on `topic`.
    pub fn put(&self, topic: Topic, payload: Vec<u8>) {
        self.sender.put(topic, payload);
    }

    /// Messages dropped so far because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.sender.dropped.load(Ordering::Relaxed)
    }
}

impl Drop for Outbox {
    /// Sends what is queued, then stops the thread.
    fn drop(&mut self) {
        let _ = self.sender.tx.send(Message::Close);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn send_all(robot: &str, publishers: &Publishers, rx: &Receiver<Message>) {
    let mut failed = 0u64;
    while let Ok(m) = rx.recv() {
        let sent = match m {
            Message::Reply(q, payload) => q.reply(q.key_expr().clone(), payload).wait(),
            Message::Put(topic, payload) => publishers.of(topic).put(payload).wait(),
            Message::Close => break,
        };
        if let Err(e) = sent {
            failed += 1;
            // The first of a run, then one in a thousand.
            if failed % 1000 == 1 {
                tracing::warn!(robot, failed, "a message could not be sent: {e}");
            }
        }
    }
}
