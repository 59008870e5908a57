//! The telecommands a robot has taken, for as long as a retry of one may
//! still come: a retry (the same id, the same command) gets the reply
//! given before and is never carried out twice; the same id with another
//! command is refused. Memory stays bounded whatever the operators send:
//! an id is kept until its command's deadline passes (a later retry is
//! stale and refused anyway), deadlines may lie at most
//! [`MAX_DEADLINE_AHEAD_S`] ahead, at most [`MAX_KEPT`] ids are kept, and
//! ids and operator names are capped in size.

use std::collections::{HashMap, VecDeque};
use std::hash::Hasher;
use stucco_core::{Reply, Stamp, Telecommand};

/// The longest id taken, bytes.
pub const MAX_ID_BYTES: usize = 64;
/// The longest operator name taken, bytes.
pub const MAX_OPERATOR_BYTES: usize = 64;
/// How far past the robot's clock a deadline may lie, s: a command is
/// remembered until its deadline, so a deadline on another clock (Unix
/// time, say) is refused rather than kept for ever.
pub const MAX_DEADLINE_AHEAD_S: f64 = 60.0;
/// The most ids remembered at once (at 1,000 commands a second with
/// deadlines a minute ahead, 60,000 are).
pub const MAX_KEPT: usize = 100_000;

/// What to do with a telecommand.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Intake {
    /// Not seen before: carry it out (its content's digest, to record).
    New(u64),
    /// A retry: answer it with the reply given before, do nothing.
    Retry(Reply),
    /// Refused, and why (stale, an id already used for another command,
    /// too long a field, too far a deadline, too many in flight).
    Refused(String),
}

#[derive(Clone, Debug)]
struct Entry {
    digest: u64,
    deadline: Stamp,
    reply: Option<Reply>,
}

/// The ids taken and their replies, until their deadlines pass.
#[derive(Clone, Debug, Default)]
pub(crate) struct Ledger {
    entries: HashMap<String, Entry>,
    /// Ids in the order they were taken, with their deadlines: the ones to
    /// forget first are near the front (deadlines are at most a minute
    /// ahead, so the order is nearly the deadlines').
    taken: VecDeque<(Stamp, String)>,
}

impl Ledger {
    /// What to do with `t` at `now`.
    pub fn intake(&mut self, now: Stamp, t: &Telecommand) -> Intake {
        self.forget(now);
        if t.id.len() > MAX_ID_BYTES {
            return Intake::Refused(format!("id: {} bytes, at most {MAX_ID_BYTES}", t.id.len()));
        }
        if t.operator.len() > MAX_OPERATOR_BYTES {
            return Intake::Refused(format!(
                "operator: {} bytes, at most {MAX_OPERATOR_BYTES}",
                t.operator.len()
            ));
        }
        let digest = digest(t);
        if let Some(e) = self.entries.get(&t.id) {
            return match (&e.reply, e.digest == digest) {
                (Some(reply), true) => Intake::Retry(reply.clone()),
                (None, true) => Intake::Refused("a retry of a command still being taken".into()),
                (_, false) => Intake::Refused(format!(
                    "id {:?} was used for another command: a new command needs a new id",
                    t.id
                )),
            };
        }
        if now > t.deadline {
            let late = now.seconds_since(t.deadline);
            return Intake::Refused(format!("stale: {late:.3} s past its deadline"));
        }
        let ahead = t.deadline.seconds_since(now);
        if ahead > MAX_DEADLINE_AHEAD_S {
            return Intake::Refused(format!(
                "deadline: {ahead:.0} s ahead of the robot's clock (now {:.3} s); deadlines are \
                 on the robot's clock (the stamp of its state) and at most \
                 {MAX_DEADLINE_AHEAD_S} s ahead",
                now.as_secs_f64()
            ));
        }
        if self.entries.len() >= MAX_KEPT {
            return Intake::Refused(format!(
                "busy: {MAX_KEPT} commands whose deadlines have not passed; try again later"
            ));
        }
        Intake::New(digest)
    }

    /// Remembers a command taken (`digest` from [`Ledger::intake`]).
    pub fn take(&mut self, t: &Telecommand, digest: u64) {
        self.entries.insert(
            t.id.clone(),
            Entry {
                digest,
                deadline: t.deadline,
                reply: None,
            },
        );
        self.taken.push_back((t.deadline, t.id.clone()));
    }

    /// The latest reply to `id`, for its retries (nothing kept for an id
    /// not remembered: refused before it was taken, or forgotten).
    pub fn replied(&mut self, id: &str, reply: &Reply) {
        if let Some(e) = self.entries.get_mut(id) {
            e.reply = Some(reply.clone());
        }
    }

    /// Ids remembered.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Forgets the ids whose deadlines have passed.
    fn forget(&mut self, now: Stamp) {
        while let Some((deadline, _)) = self.taken.front() {
            if *deadline >= now {
                // Later ones were taken later; a few with earlier
                // deadlines behind this one wait for it (at most a minute).
                break;
            }
            if let Some((_, id)) = self.taken.pop_front()
                && self.entries.get(&id).is_some_and(|e| e.deadline < now)
            {
                self.entries.remove(&id);
            }
        }
    }
}

/// A digest of everything a telecommand says.
fn digest(t: &Telecommand) -> u64 {
    let mut h = fnv::FnvHasher::default();
    h.write(serde_json::to_string(t).unwrap_or_default().as_bytes());
    h.finish()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use stucco_core::Command;

    fn t(id: &str, at: f64, command: Command) -> Telecommand {
        Telecommand {
            id: id.to_owned(),
            operator: "ann".to_owned(),
            issued: Stamp::from_secs_f64(at),
            deadline: Stamp::from_secs_f64(at + 5.0),
            command,
        }
    }

    #[test]
    fn an_id_is_a_retry_only_with_the_same_command() {
        let mut l = Ledger::default();
        let now = Stamp::from_secs_f64(1.0);
        let status = t("c1", 1.0, Command::Status);
        let Intake::New(d) = l.intake(now, &status) else {
            panic!()
        };
        l.take(&status, d);
        l.replied("c1", &Reply::Done);
        assert_eq!(l.intake(now, &status), Intake::Retry(Reply::Done));
        // The same id, another command (a stop, say): refused, named.
        let stop = t("c1", 1.0, Command::Stop);
        assert!(
            matches!(l.intake(now, &stop), Intake::Refused(r) if r.contains("another command"))
        );
    }

    #[test]
    fn ids_are_forgotten_when_their_deadlines_pass_and_memory_stays_bounded() {
        let mut l = Ledger::default();
        for k in 0..1_000_000_u64 {
            let at = k as f64 * 1e-3;
            let c = t(&format!("c{k}"), at, Command::Status);
            match l.intake(Stamp::from_secs_f64(at), &c) {
                Intake::New(d) => l.take(&c, d),
                other => panic!("{other:?}"),
            }
            l.replied(&c.id, &Reply::Done);
        }
        // Deadlines 5 s ahead at 1,000 a second: about 5,000 kept.
        assert!((5_000..=5_002).contains(&l.len()), "{}", l.len());
        assert!(l.taken.len() <= 5_002);
    }

    #[test]
    fn oversized_fields_and_far_deadlines_are_refused() {
        let mut l = Ledger::default();
        let now = Stamp::from_secs_f64(10.0);
        let mut c = t(&"x".repeat(65), 10.0, Command::Status);
        assert!(matches!(l.intake(now, &c), Intake::Refused(r) if r.starts_with("id:")));
        c.id = "ok".into();
        c.operator = "o".repeat(1_000_000);
        assert!(matches!(l.intake(now, &c), Intake::Refused(r) if r.starts_with("operator:")));
        c.operator = "ann".into();
        // A deadline in Unix-epoch nanoseconds, on a robot whose clock
        // started at its boot.
        c.deadline = Stamp::from_nanos(1_764_930_000_000_000_000);
        assert!(
            matches!(l.intake(now, &c), Intake::Refused(r) if r.contains("robot's clock")),
            "{:?}",
            l.intake(now, &c)
        );
        assert_eq!(l.len(), 0);
    }
}
