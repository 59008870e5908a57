//! The executive's events as JSON lines, one event a line: the job's log.

use crate::robot::{Robot, Sink, SinkError};
use std::io::Write;
use stucco_core::Platform;
use stucco_mission::{EventKind, Inputs, Outputs};

/// Writes every event of the executive to `W` as a line of JSON, and
/// counts them and the safety stops among them.
pub struct EventLog<W: Write> {
    out: W,
    events: usize,
    safety_stops: usize,
}

impl<W: Write> EventLog<W> {
    /// A log writing into `out`.
    pub fn new(out: W) -> Self {
        EventLog {
            out,
            events: 0,
            safety_stops: 0,
        }
    }

    /// Events written.
    pub fn events(&self) -> usize {
        self.events
    }

    /// Times the supervisor stopped the robot.
    pub fn safety_stops(&self) -> usize {
        self.safety_stops
    }

    /// Flushes what is written and hands the writer back.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

impl<W: Write, P: Platform> Sink<P> for EventLog<W> {
    fn ticked(
        &mut self,
        _robot: &Robot<P>,
        _inputs: &Inputs<'_>,
        outputs: &Outputs,
    ) -> Result<(), SinkError> {
        for e in &outputs.events {
            serde_json::to_writer(&mut self.out, e)?;
            self.out.write_all(b"\n")?;
            self.events += 1;
            if matches!(e.kind, EventKind::SafetyStop { .. }) {
                self.safety_stops += 1;
            }
        }
        Ok(())
    }
}
