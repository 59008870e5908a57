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
    /// What it tried, e.g. `Query (ingress)`.
    pub action: String,
    /// On which key expression.
    pub key: String,
}

impl std::fmt::Display for Denial {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let who = if self.subject.is_empty() {
            &self.zid
        } else {
            &self.subject
        };
        write!(f, "refused {} on {} from {who}", self.action, self.key)
    }
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

/// The tracing layer that turns zenoh's access-control log into
/// [`Denial`]s; add it to the process's subscriber (it enables zenoh's
/// `trace` level for that one module only).
pub fn layer<S: Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>>() -> impl Layer<S>
{
    AclLayer.with_filter(Targets::new().with_target(ACL_TARGET, Level::TRACE))
}

struct AclLayer;

impl<S: Subscriber> Layer<S> for AclLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let mut message = Message(String::new());
        event.record(&mut message);
        if let Some(d) = decision(&message.0) {
            record(&d);
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
