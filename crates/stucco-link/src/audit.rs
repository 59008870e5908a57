//! What zenoh's access control refuses, made visible to the robot.
//!
//! Zenoh drops a message its access control denies before any queryable or
//! subscriber sees it, and says so only in its own `trace` log. The
//! [`layer`] reads those log events and hands each refusal that concerns a
//! robot to that robot's [`RobotLink`](crate::RobotLink), which logs it and
//! keeps it for its report: a viewer's command is refused *and* the robot
//! knows who tried.
//!
//! Zenoh names the remote side in its log only on the first decision for a
//! key (later ones are answered from its cache with the zenoh id alone), so
//! the layer remembers each zenoh id's subject from the decisions that name
//! it.
//!
//! A session refused at joining (a wrong password, an unknown user, a
//! certificate no authority of the site signed, none at all) is read from
//! zenoh's log too and handed to every robot of the process, with what
//! zenoh tells of it: the reason, and the address the attempt came from
//! when zenoh names it (a user/password handshake's link, when it was the
//! only one joining at the time; a TLS handshake fails before zenoh names
//! its link, and zenoh 1.10 never logs the user name a wrong password was
//! tried for).

use serde::Serialize;
use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender, channel};
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::Layer;
use tracing_subscriber::filter::Targets;
use tracing_subscriber::layer::Context;

/// The module of zenoh whose log carries the access-control decisions.
pub const ACL_TARGET: &str = "zenoh::net::routing::interceptor::access_control";
/// The module of zenoh that logs each link it begins to accept.
const MANAGER_TARGET: &str = "zenoh_transport::unicast::manager";
/// The module of zenoh that logs why a joining session was refused.
const ACCEPT_TARGET: &str = "zenoh_transport::unicast::establishment::accept";
/// The module of zenoh that logs a TLS handshake that failed.
const TLS_TARGET: &str = "zenoh_link_tls::unicast";
/// Links being accepted that are remembered.
const JOINING_KEPT: usize = 64;

/// A message zenoh's access control refused.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Denial {
    /// The remote session's zenoh id.
    pub zid: String,
    /// Who it authenticated as, in zenoh's words: the interface, the
    /// certificate's common name, the user name, the link protocol and the
    /// zenoh id that matched a configured subject, joined by `+`; empty if
    /// zenoh has not named it yet.
    pub subject: String,
    /// What it tried, e.g. `Query (ingress)`, or `Join (wrong password)`
    /// for a session refused at joining.
    pub action: String,
    /// On which key expression (empty for a session refused at joining).
    pub key: String,
}

impl std::fmt::Display for Denial {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let who = if self.subject.is_empty() {
            &self.zid
        } else {
            &self.subject
        };
        match (self.key.is_empty(), who.is_empty()) {
            (false, _) => write!(f, "refused {} on {} from {who}", self.action, self.key),
            (true, false) => write!(f, "refused {} from {who}", self.action),
            (true, true) => write!(
                f,
                "refused {} (from an address zenoh does not name)",
                self.action
            ),
        }
    }
}

/// Why zenoh refused a session at joining, read from its log.
fn join_refusal(target: &str, message: &str) -> Option<String> {
    if target == ACCEPT_TARGET && message.contains("UsrPwd") {
        if message.contains("Invalid user") {
            return Some("Join (unknown user)".to_owned());
        }
        if message.contains("Invalid password") {
            return Some("Join (wrong password)".to_owned());
        }
    }
    if target == TLS_TARGET {
        let why = message.strip_suffix(". Hint: increase the system open file limit.")?;
        return Some(format!("Join (TLS: {why})"));
    }
    None
}

/// One access-control decision as zenoh logs it.
#[derive(Debug, PartialEq, Eq)]
struct Decision<'a> {
    zid: &'a str,
    subject: Option<&'a str>,
    allowed: bool,
    action: &'a str,
    key: &'a str,
}

/// Reads `"{zid} on {subject} is unauthorized to {action} on {key}"` and its
/// variants (authorized; `Using cached result: ` without the subject; the
/// key as `Some(key)` for undeclarations).
fn decision(message: &str) -> Option<Decision<'_>> {
    let message = message
        .strip_prefix("Using cached result: ")
        .unwrap_or(message);
    let (who, allowed, what) = if let Some((w, r)) = message.split_once(" is unauthorized to ") {
        (w, false, r)
    } else {
        let (w, r) = message.split_once(" is authorized to ")?;
        (w, true, r)
    };
    let (zid, subject) = match who.split_once(" on ") {
        Some((z, s)) => (z, Some(s)),
        None => (who, None),
    };
    let (action, key) = what.rsplit_once(" on ")?;
    let key = key
        .strip_prefix("Some(")
        .and_then(|k| k.strip_suffix(')'))
        .unwrap_or(key);
    Some(Decision {
        zid,
        subject,
        allowed,
        action,
        key,
    })
}

/// The robots listening for refusals and what is known of each zenoh id.
struct Registry {
    /// Key prefix (`stucco/NAME/`) and where its refusals go.
    sinks: Vec<(String, Sender<Denial>)>,
    /// The subject zenoh named for each zenoh id, the latest named last;
    /// at most [`SUBJECTS_KEPT`], so a robot that sees many short operator
    /// sessions keeps a bounded memory.
    subjects: VecDeque<(String, String)>,
    /// The links zenoh has begun to accept and not yet accepted (`SRC =>
    /// DST`), oldest first; at most [`JOINING_KEPT`].
    joining: VecDeque<String>,
}

/// Zenoh ids whose subject is remembered.
const SUBJECTS_KEPT: usize = 256;

impl Registry {
    fn remember(&mut self, zid: &str, subject: &str) {
        if let Some(i) = self.subjects.iter().position(|(z, _)| z == zid) {
            self.subjects.remove(i);
        }
        self.subjects
            .push_back((zid.to_owned(), subject.to_owned()));
        while self.subjects.len() > SUBJECTS_KEPT {
            self.subjects.pop_front();
        }
    }

    /// Reads zenoh's log of the links it accepts.
    fn link_news(&mut self, target: &str, message: &str) {
        if target == MANAGER_TARGET {
            if let Some(link) = message.strip_prefix("Accepting link... ") {
                self.joining.push_back(link.to_owned());
                while self.joining.len() > JOINING_KEPT {
                    self.joining.pop_front();
                }
            } else if message.starts_with("Failed to accept link before deadline") {
                self.joining.pop_front();
            }
        } else if target == ACCEPT_TARGET && message.starts_with("New transport link accepted") {
            self.joining.retain(|link| !message.contains(link.as_str()));
        }
    }

    /// The remote end of the link a refused session came on, when one link
    /// only was being accepted (forgotten then).
    fn refused_link(&mut self) -> String {
        if self.joining.len() == 1 {
            let link = self.joining.pop_front().unwrap_or_default();
            link.rsplit(" => ").next().unwrap_or_default().to_owned()
        } else {
            String::new()
        }
    }

    fn subject_of(&self, zid: &str) -> Option<&str> {
        self.subjects
            .iter()
            .find(|(z, _)| z == zid)
            .map(|(_, s)| s.as_str())
    }
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    sinks: Vec::new(),
    subjects: VecDeque::new(),
    joining: VecDeque::new(),
});

/// Refusals on key expressions under `prefix` from now on.
pub(crate) fn listen(prefix: String) -> Receiver<Denial> {
    let (tx, rx) = channel();
    if let Ok(mut r) = REGISTRY.lock() {
        r.sinks.push((prefix, tx));
    }
    rx
}

fn record(d: &Decision<'_>) {
    let Ok(mut r) = REGISTRY.lock() else {
        return;
    };
    if let Some(s) = d.subject {
        r.remember(d.zid, s);
    }
    if d.allowed {
        return;
    }
    let denial = Denial {
        zid: d.zid.to_owned(),
        subject: r.subject_of(d.zid).unwrap_or_default().to_owned(),
        action: d.action.to_owned(),
        key: d.key.to_owned(),
    };
    // A robot gone (its receiver dropped) is forgotten.
    r.sinks.retain(|(prefix, tx)| {
        !d.key.starts_with(prefix.as_str()) || tx.send(denial.clone()).is_ok()
    });
}

/// Hands a session refused at joining to every robot.
fn record_refusal(action: String) {
    let Ok(mut r) = REGISTRY.lock() else {
        return;
    };
    let denial = Denial {
        zid: String::new(),
        subject: r.refused_link(),
        action,
        key: String::new(),
    };
    r.sinks.retain(|(_, tx)| tx.send(denial.clone()).is_ok());
}

/// The tracing layer that turns zenoh's access-control log, and its log
/// of sessions refused at joining, into [`Denial`]s; add it to the
/// process's subscriber (it enables zenoh's `trace` level for the modules
/// it reads only).
pub fn layer<S: Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>>() -> impl Layer<S>
{
    AclLayer.with_filter(
        Targets::new()
            .with_target(ACL_TARGET, Level::TRACE)
            .with_target(MANAGER_TARGET, Level::TRACE)
            .with_target(ACCEPT_TARGET, Level::DEBUG)
            .with_target(TLS_TARGET, Level::WARN),
    )
}

struct AclLayer;

impl<S: Subscriber> Layer<S> for AclLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let mut message = Message(String::new());
        event.record(&mut message);
        let target = event.metadata().target();
        if target == ACL_TARGET {
            if let Some(d) = decision(&message.0) {
                record(&d);
            }
            return;
        }
        if let Some(action) = join_refusal(target, &message.0) {
            record_refusal(action);
        } else if let Ok(mut r) = REGISTRY.lock() {
            r.link_news(target, &message.0);
        }
    }
}

struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_subjects_remembered_are_bounded_and_the_latest_kept() {
        let mut r = Registry {
            sinks: Vec::new(),
            subjects: VecDeque::new(),
            joining: VecDeque::new(),
        };
        for i in 0..SUBJECTS_KEPT + 10 {
            r.remember(&format!("z{i}"), &format!("user{i}"));
        }
        assert_eq!(r.subjects.len(), SUBJECTS_KEPT);
        assert_eq!(r.subject_of("z0"), None);
        let last = SUBJECTS_KEPT + 9;
        assert_eq!(
            r.subject_of(&format!("z{last}")),
            Some(format!("user{last}").as_str())
        );
        // Named again, an id moves to the back and its new subject holds.
        r.remember("z20", "ann");
        r.remember("z-new", "vic");
        assert_eq!(r.subject_of("z20"), Some("ann"));
        assert_eq!(r.subjects.len(), SUBJECTS_KEPT);
    }

    #[test]
    fn reads_sessions_refused_at_joining_and_where_they_came_from() {
        assert_eq!(
            join_refusal(
                ACCEPT_TARGET,
                "UsrPwd extension - Recv OpenSyn. Invalid password."
            ),
            Some("Join (wrong password)".to_owned())
        );
        assert_eq!(
            join_refusal(
                ACCEPT_TARGET,
                "UsrPwd extension - Recv OpenSyn. Invalid user."
            ),
            Some("Join (unknown user)".to_owned())
        );
        assert_eq!(
            join_refusal(
                TLS_TARGET,
                "invalid peer certificate: UnknownIssuer. Hint: increase the system open file limit."
            ),
            Some("Join (TLS: invalid peer certificate: UnknownIssuer)".to_owned())
        );
        assert_eq!(join_refusal(ACCEPT_TARGET, "Some other trouble"), None);
        let mut r = Registry {
            sinks: Vec::new(),
            subjects: VecDeque::new(),
            joining: VecDeque::new(),
        };
        // Two links joining, one accepted: the other is where a refusal came
        // from.
        r.link_news(
            MANAGER_TARGET,
            "Accepting link... tcp/10.0.0.2:7447 => tcp/10.0.0.9:51000",
        );
        r.link_news(
            MANAGER_TARGET,
            "Accepting link... tcp/10.0.0.2:7447 => tcp/10.0.0.7:40000",
        );
        assert_eq!(r.refused_link(), "", "two joining: which one is not known");
        r.link_news(
            ACCEPT_TARGET,
            "New transport link accepted from 4f to 9a: tcp/10.0.0.2:7447 => tcp/10.0.0.9:51000 x",
        );
        assert_eq!(r.refused_link(), "tcp/10.0.0.7:40000");
        assert!(r.joining.is_empty());
        // Bounded, whatever comes.
        for i in 0..JOINING_KEPT + 5 {
            r.link_news(MANAGER_TARGET, &format!("Accepting link... a => b{i}"));
        }
        assert_eq!(r.joining.len(), JOINING_KEPT);
    }

    #[test]
    fn reads_zenoh_decisions() {
        let d = decision(
            "4f2a on lo+vic+UnixsockStream+4f2a is unauthorized to Query (ingress) on stucco/r1/cmd",
        );
        assert_eq!(
            d,
            Some(Decision {
                zid: "4f2a",
                subject: Some("lo+vic+UnixsockStream+4f2a"),
                allowed: false,
                action: "Query (ingress)",
                key: "stucco/r1/cmd",
            })
        );
        let d =
            decision("Using cached result: 4f2a is authorized to Put (egress) on stucco/r1/state");
        assert_eq!(
            d,
            Some(Decision {
                zid: "4f2a",
                subject: None,
                allowed: true,
                action: "Put (egress)",
                key: "stucco/r1/state",
            })
        );
        let d = decision(
            "Using cached result: 4f2a is unauthorized to Undeclare Queryable (ingress) on Some(stucco/r1/cmd)",
        );
        assert_eq!(d.map(|d| d.key), Some("stucco/r1/cmd"));
        assert_eq!(decision("Access control is enabled"), None);
    }
}
