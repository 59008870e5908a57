//! The operator's commands: telecommands taken between ticks (retries
//! recognised, stale or conflicting ones refused, a stop always obeyed),
//! the operator's tasks queued next, and the replies.

use super::{Executive, MissionMode, OperatorCommand, TaskStatus};
use crate::ledger::{Intake, MAX_ID_BYTES, MAX_OPERATOR_BYTES};
use crate::model::Estimate;
use crate::task::TaskSpec;
use crate::tasks::{out_of_reach, route};
use stucco_core::telemetry::EventKind;
use stucco_core::{Ack, Command, DriveCommand, Reply, Stamp, Telecommand};

impl Executive {
    /// Takes telecommands between ticks (as soon as they arrive) and
    /// returns the replies: acceptance never waits for the next control
    /// period. The effects (a stop, a queued task, a jog) show in the next
    /// tick's command.
    pub fn telecommands(&mut self, now: Stamp, cmds: &[Telecommand], est: &Estimate) -> Vec<Ack> {
        for t in cmds {
            self.telecommand(now, t, est);
        }
        std::mem::take(&mut self.acks)
    }

    /// Follows an operator command: whether the progress changed, or why
    /// it cannot be followed.
    pub(super) fn operator(&mut self, now: Stamp, cmd: OperatorCommand) -> Result<bool, String> {
        let result = self.follow(now, cmd);
        if let Err(reason) = &result {
            self.emit(
                now,
                EventKind::CommandRefused {
                    command: cmd,
                    reason: reason.clone(),
                },
            );
        }
        result
    }

    pub(super) fn follow(&mut self, now: Stamp, cmd: OperatorCommand) -> Result<bool, String> {
        // A mission stopped by a task's failure goes on when resumed: the
        // failed task is tried again (the operator has cleared its way).
        if cmd == OperatorCommand::Resume
            && let Some(k) = self.failed_task
            && matches!(
                self.closed.as_ref().unwrap_or(&self.mode),
                MissionMode::Failed { .. }
            )
        {
            self.failed_task = None;
            self.failure = None;
            self.closed = None;
            self.status[k] = TaskStatus::Pending;
            self.mode = MissionMode::Running;
            self.emit(now, EventKind::Resumed);
            return Ok(true);
        }
        if self.mode.is_final() {
            return Err("the mission is over".to_owned());
        }
        match cmd {
            OperatorCommand::Pause => {
                if self.mode != MissionMode::Running {
                    return Err("not running".to_owned());
                }
                self.pause(now, "operator".to_owned());
                Ok(false)
            }
            OperatorCommand::Resume => match self.mode {
                MissionMode::Paused { .. } | MissionMode::EStopped => {
                    self.mode = MissionMode::Running;
                    self.emit(now, EventKind::Resumed);
                    Ok(false)
                }
                _ => Err("not paused".to_owned()),
            },
            OperatorCommand::Abort => {
                if let Some(a) = self.active.take() {
                    self.status[a.index] = TaskStatus::Pending;
                    self.answer(
                        now,
                        a.index,
                        Reply::failed("aborted", "the mission was aborted"),
                    );
                }
                self.mode = MissionMode::Aborted;
                self.emit(now, EventKind::Aborted);
                Ok(true)
            }
            OperatorCommand::Skip => {
                let Some(a) = self.active.take() else {
                    return Err("no task under way".to_owned());
                };
                self.status[a.index] = TaskStatus::Skipped;
                self.emit(now, EventKind::TaskSkipped { task: a.index });
                self.answer(now, a.index, Reply::failed("skipped", "skipped"));
                Ok(true)
            }
            OperatorCommand::Continue => {
                let waiting = self.active.as_ref().is_some_and(|a| {
                    matches!(self.tasks[a.index], TaskSpec::WaitForOperator { .. })
                });
                if !waiting {
                    return Err("no task is waiting for the operator".to_owned());
                }
                self.continue_asked = true;
                Ok(false)
            }
        }
    }

    /// Stops the robot for operator `who`: a jog ends, a running mission
    /// pauses.
    pub(super) fn stop(&mut self, now: Stamp, who: &str) {
        if let Some((_, _, id)) = self.jog.take() {
            self.reply(
                now,
                &id,
                Reply::failed("stopped", "stopped by the operator"),
            );
        }
        if self.mode == MissionMode::Running {
            self.pause(
                now,
                format!("stop from {}", clipped(who, MAX_OPERATOR_BYTES)),
            );
        }
    }

    /// Sends `reply` to telecommand `id` (and keeps it for retries).
    pub(super) fn reply(&mut self, now: Stamp, id: &str, reply: Reply) {
        self.ledger.replied(id, &reply);
        self.acks.push(Ack {
            id: id.to_owned(),
            stamp: now,
            reply,
        });
    }

    /// Answers the telecommand behind operator task `index`, if any.
    pub(super) fn answer(&mut self, now: Stamp, index: usize, reply: Reply) {
        if let Some(id) = self.waiting.remove(&index) {
            self.reply(now, &id, reply);
        }
    }

    /// Takes a telecommand: a retry gets the last reply again and is not
    /// carried out twice; a stale one, one reusing an id for another
    /// command, or one beyond the ledger's bounds is refused. `stop` acts
    /// at once and always: stale, repeated or malformed in a field, it
    /// still stops the robot.
    pub(super) fn telecommand(&mut self, now: Stamp, t: &Telecommand, est: &Estimate) {
        let stop = t.command == Command::Stop;
        if stop {
            self.stop(now, &t.operator);
        }
        let digest = match self.ledger.intake(now, t) {
            Intake::New(digest) => digest,
            Intake::Retry(reply) => {
                self.acks.push(Ack {
                    id: t.id.clone(),
                    stamp: now,
                    reply,
                });
                return;
            }
            Intake::Refused(reason) => {
                let reply = if stop {
                    Reply::Done
                } else {
                    Reply::Rejected { reason }
                };
                self.acks.push(Ack {
                    id: clipped(&t.id, MAX_ID_BYTES).to_owned(),
                    stamp: now,
                    reply,
                });
                return;
            }
        };
        self.ledger.take(t, digest);
        let follow = |s: &mut Self, cmd: OperatorCommand| match s.operator(now, cmd) {
            Ok(_) => Reply::Done,
            Err(reason) => Reply::Rejected { reason },
        };
        let reply = match &t.command {
            Command::Stop => Reply::Done,
            Command::Status => Reply::Done,
            Command::Pause => follow(self, OperatorCommand::Pause),
            Command::Resume => follow(self, OperatorCommand::Resume),
            Command::Abort => follow(self, OperatorCommand::Abort),
            Command::Skip => follow(self, OperatorCommand::Skip),
            Command::Continue => follow(self, OperatorCommand::Continue),
            Command::Jog {
                speed_mps,
                steer_rad,
                ttl_s,
            } => {
                let v = &self.config.vehicle;
                if self.mode == MissionMode::EStopped {
                    Reply::Rejected {
                        reason: "e-stopped: release the e-stop and resume first".to_owned(),
                    }
                } else if !(ttl_s.is_finite() && *ttl_s > 0.0 && *ttl_s <= 2.0) {
                    Reply::Rejected {
                        reason: "ttl_s: more than 0 and at most 2 s".to_owned(),
                    }
                } else if !(speed_mps.abs() <= v.max_speed_mps
                    && steer_rad.abs() <= v.max_steer_rad)
                {
                    Reply::Rejected {
                        reason: "speed or steering beyond the robot's limits".to_owned(),
                    }
                } else {
                    // A newer jog takes over an older one.
                    if let Some((_, _, old)) = self.jog.take() {
                        self.reply(now, &old, Reply::Done);
                    }
                    let drive = DriveCommand {
                        speed_mps: *speed_mps,
                        steer_rad: *steer_rad,
                    };
                    self.jog = Some((drive, now.offset_secs(*ttl_s), t.id.clone()));
                    Reply::Accepted
                }
            }
            task => match TaskSpec::from_command(task) {
                None => Reply::Rejected {
                    reason: "not a task".to_owned(),
                },
                Some(spec) => self.accept_task(t, spec, est),
            },
        };
        self.reply(now, &t.id, reply);
    }

    /// Queues an operator's task to run next, or says why it cannot run.
    pub(super) fn accept_task(&mut self, t: &Telecommand, spec: TaskSpec, est: &Estimate) -> Reply {
        if let Some((key, why)) = spec.invalid() {
            return Reply::Rejected {
                reason: format!("{key}: {why}"),
            };
        }
        if matches!(spec, TaskSpec::Plaster { .. }) && self.config.spray.is_none() {
            return Reply::Rejected {
                reason: "this robot carries no spray tool (the mission has no [spray])".to_owned(),
            };
        }
        if let Some(why) = out_of_reach(&spec, est, &self.config) {
            return Reply::Rejected { reason: why };
        }
        if let TaskSpec::PassDoor { door, .. } = spec
            && door >= est.doors.len()
        {
            return Reply::Rejected {
                reason: format!("door {door} is not known ({} found)", est.doors.len()),
            };
        }
        if let TaskSpec::GoToRoom { room, .. } = &spec
            && let Err(why) = route(&self.config, room, est)
        {
            return Reply::Rejected {
                reason: why.to_string(),
            };
        }
        // Next after the task under way; a task waiting for the operator
        // has its answer.
        let at = match &self.active {
            Some(a) => {
                if matches!(self.tasks[a.index], TaskSpec::WaitForOperator { .. }) {
                    self.continue_asked = true;
                }
                a.index + 1
            }
            None => self
                .status
                .iter()
                .position(|s| *s == TaskStatus::Pending)
                .unwrap_or(self.tasks.len()),
        };
        self.tasks.insert(at, spec);
        self.status.insert(at, TaskStatus::Pending);
        self.scripted.insert(at, false);
        self.rooms.insert(at, None);
        self.waiting = std::mem::take(&mut self.waiting)
            .into_iter()
            .map(|(i, id)| (if i >= at { i + 1 } else { i }, id))
            .collect();
        self.waiting.insert(at, t.id.clone());
        // Work done so far does not end the robot's day: a new task
        // reopens the mission. A failed or aborted mission's own tasks
        // stay held while the operator's run; it returns to that state
        // when they are over.
        if matches!(self.mode, MissionMode::Failed { .. } | MissionMode::Aborted) {
            self.closed = Some(self.mode.clone());
        }
        if self.mode.is_final() {
            self.mode = MissionMode::Running;
        }
        Reply::Accepted
    }
}

/// At most `bytes` of `text`, cut at a character's boundary.
fn clipped(text: &str, bytes: usize) -> &str {
    let mut end = text.len().min(bytes);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    &text[..end]
}
