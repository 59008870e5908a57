//! Recording a task mission's run as MCAP (open it in Foxglove), and
//! replaying a recording through the executive.
//!
//! Every message is JSON. Topics:
//! - `/mission`: the mission file's text and its plan file's, the seed,
//!   the checkpoint resumed from (once, first);
//! - `/executive/inputs`: what the executive read each tick (the estimate,
//!   bumper, e-stop, operator commands, which scan's echoes);
//! - `/scan/points`: the echoes of each new scan, robot frame;
//! - `/executive/outputs`: the command it gave each tick;
//! - `/truth/pose`: the simulator's true pose, room frame (to look at,
//!   never replayed);
//! - `/events`: the executive's events.
//!
//! Replaying feeds `/executive/inputs` and `/scan/points` to a fresh
//! executive built from `/mission` and compares its commands with
//! `/executive/outputs`, tick by tick.

use crate::room_frame::RoomFrame;
use crate::sim_robot::Simulated;
use anyhow::{Context, Result, anyhow};
use mcap::records::MessageHeader;
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;
use stucco_core::{DriveCommand, Pose2, Stamp, Telecommand, ToolCommand};
use stucco_mission::{Estimate, Event, Executive, Inputs, OperatorCommand, Outputs, Progress};
use stucco_runtime::{BadInput, Mission, Robot, Sink, SinkError};
use stucco_sim::Layout;

/// The `/mission` message.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordedMission {
    /// The mission file's path as given.
    pub path: String,
    /// Its text.
    pub text: String,
    /// The text of the plan file it names (a recording replays without
    /// the files it was made from).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plan_text: Option<String>,
    /// The run's seed.
    pub seed: u64,
    /// The progress the run resumed from.
    pub resumed_from: Option<Progress>,
}

/// One tick's inputs, as recorded.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordedInputs {
    stamp: Stamp,
    estimate: Estimate,
    bumper: bool,
    estop: bool,
    operator: Vec<OperatorCommand>,
    telecommands: Vec<Telecommand>,
    /// The `/scan/points` message in force.
    scan: u64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordedPoints {
    stamp: Stamp,
    scan: u64,
    points: Vec<[f64; 2]>,
    /// Echoes kept from earlier scans, out of this one's view.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    unseen: Vec<[f64; 2]>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordedOutputs {
    stamp: Stamp,
    drive: DriveCommand,
    tool: ToolCommand,
}

/// Writes a run's recording.
pub struct Recorder<W: Write + Seek> {
    writer: mcap::Writer<W>,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
    scan: u64,
}

const TOPICS: [&str; 6] = [
    "/mission",
    "/executive/inputs",
    "/scan/points",
    "/executive/outputs",
    "/truth/pose",
    "/events",
];

impl Recorder<BufWriter<std::fs::File>> {
    /// A recording at `path`, starting with the mission.
    pub fn create(path: &Path, mission: &RecordedMission) -> Result<Self> {
        let file = std::fs::File::create(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Recorder::new(BufWriter::new(file), mission)
    }
}

impl<W: Write + Seek> Recorder<W> {
    fn new(w: W, mission: &RecordedMission) -> Result<Self> {
        let mut writer = mcap::WriteOptions::new()
            .profile("stucco")
            .compression(None)
            .create(w)?;
        let mut channels = BTreeMap::new();
        for topic in TOPICS {
            channels.insert(
                topic,
                writer.add_channel(0, topic, "json", &BTreeMap::new())?,
            );
        }
        let mut r = Recorder {
            writer,
            channels,
            sequence: 0,
            scan: 0,
        };
        r.put("/mission", Stamp::ZERO, mission)?;
        Ok(r)
    }

    fn put(&mut self, topic: &'static str, stamp: Stamp, value: &impl Serialize) -> Result<()> {
        let data = serde_json::to_vec(value)?;
        let channel_id = self.channels[topic];
        let t = u64::try_from(stamp.as_nanos()).unwrap_or(0);
        self.sequence += 1;
        self.writer.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: t,
                publish_time: t,
            },
            &data,
        )?;
        Ok(())
    }

    /// Records one tick: its inputs (with the scan's echoes when a new
    /// scan came in), the command, the events and the true pose.
    pub fn tick(
        &mut self,
        inputs: &Inputs,
        new_scan: bool,
        drive: DriveCommand,
        tool: ToolCommand,
        events: &[Event],
        truth: &Pose2,
    ) -> Result<()> {
        let stamp = inputs.estimate.stamp;
        if new_scan {
            self.scan += 1;
            let points = inputs.obstacles.iter().map(|p| [p.x, p.y]).collect();
            let unseen = inputs.unseen.iter().map(|p| [p.x, p.y]).collect();
            let scan = self.scan;
            self.put(
                "/scan/points",
                stamp,
                &RecordedPoints {
                    stamp,
                    scan,
                    points,
                    unseen,
                },
            )?;
        }
        let scan = self.scan;
        self.put(
            "/executive/inputs",
            stamp,
            &RecordedInputs {
                stamp,
                estimate: inputs.estimate.clone(),
                bumper: inputs.bumper,
                estop: inputs.estop,
                operator: inputs.operator.to_vec(),
                telecommands: inputs.telecommands.to_vec(),
                scan,
            },
        )?;
        self.put(
            "/executive/outputs",
            stamp,
            &RecordedOutputs { stamp, drive, tool },
        )?;
        for e in events {
            self.put("/events", e.stamp, e)?;
        }
        self.put("/truth/pose", stamp, truth)?;
        Ok(())
    }

    /// Writes the summary and closes the file.
    pub fn finish(mut self) -> Result<()> {
        self.writer.finish()?;
        Ok(())
    }
}

/// Records a simulated run: each tick as the executive saw it, with the
/// true pose in the frame of the room the robot's frame is in.
pub struct Recording {
    recorder: Recorder<BufWriter<std::fs::File>>,
    scans: u64,
    layout: std::sync::Arc<Layout>,
    frame: RoomFrame,
}

impl Recording {
    /// Records into `recorder`, the robot starting in the room of `frame`
    /// of `layout`.
    pub fn new(
        recorder: Recorder<BufWriter<std::fs::File>>,
        layout: std::sync::Arc<Layout>,
        frame: RoomFrame,
    ) -> Self {
        Recording {
            recorder,
            scans: 0,
            layout,
            frame,
        }
    }

    /// Writes the summary and closes the file.
    pub fn finish(self) -> Result<()> {
        self.recorder.finish()
    }
}

impl<P: Simulated> Sink<P> for Recording {
    fn ticked(
        &mut self,
        robot: &Robot<P>,
        inputs: &Inputs<'_>,
        out: &Outputs,
    ) -> std::result::Result<(), SinkError> {
        let scans = robot.perception().scans();
        let new_scan = scans != self.scans;
        self.scans = scans;
        let truth = self.frame.to_room(&robot.platform().true_pose());
        self.recorder
            .tick(inputs, new_scan, out.drive, out.tool, &out.events, &truth)?;
        Ok(())
    }

    fn entered(
        &mut self,
        robot: &Robot<P>,
        _door: usize,
        _moved: &std::result::Result<(), String>,
    ) -> std::result::Result<(), SinkError> {
        self.frame
            .follow(&self.layout, robot.perception().room_name())?;
        Ok(())
    }
}

/// What replaying a recording found.
#[derive(Clone, Debug, Serialize)]
pub struct ReplayReport {
    /// The mission's name.
    pub mission: String,
    /// Ticks replayed.
    pub ticks: usize,
    /// Ticks whose command matched the recorded one exactly.
    pub identical: usize,
    /// The first tick that did not: its stamp, the recorded command and
    /// the replayed one.
    pub first_difference: Option<(Stamp, DriveCommand, DriveCommand)>,
}

/// Replays the recording at `path` through a fresh executive.
pub fn replay_run(path: &Path) -> Result<ReplayReport> {
    let bytes = std::fs::read(path)
        .map_err(|e| BadInput(format!("cannot read {}: {e}", path.display())))?;
    let bad = |what: String| anyhow!(BadInput(format!("{}: {what}", path.display())));
    let stream = mcap::MessageStream::new(&bytes).map_err(|e| bad(format!("not MCAP: {e}")))?;
    let mut exec: Option<Executive> = None;
    let mut name = String::new();
    let mut points: Vec<Point2<f64>> = Vec::new();
    let mut unseen: Vec<Point2<f64>> = Vec::new();
    let mut pending: Option<RecordedInputs> = None;
    let mut report = ReplayReport {
        mission: String::new(),
        ticks: 0,
        identical: 0,
        first_difference: None,
    };
    let mut replayed = (DriveCommand::STOP, ToolCommand::default());
    for message in stream {
        let m = message.map_err(|e| bad(format!("unreadable: {e}")))?;
        let json = |what: &str| bad(format!("a {what} message is not what stucco wrote"));
        match m.channel.topic.as_str() {
            "/mission" => {
                let r: RecordedMission =
                    serde_json::from_slice(&m.data).map_err(|_| json("/mission"))?;
                let mission =
                    Mission::parse_with_plan(&r.text, Path::new(&r.path), r.plan_text.as_deref())
                        .map_err(|e| bad(format!("/mission: {e:#}")))?;
                name = mission.name.clone();
                let mut e = mission.executive(&crate::sim_robot::robot_spec(), true);
                if let Some(p) = &r.resumed_from {
                    e.resume_from(p).map_err(|e| bad(e.to_string()))?;
                }
                exec = Some(e);
            }
            "/scan/points" => {
                let p: RecordedPoints =
                    serde_json::from_slice(&m.data).map_err(|_| json("/scan/points"))?;
                points = p.points.iter().map(|q| Point2::new(q[0], q[1])).collect();
                unseen = p.unseen.iter().map(|q| Point2::new(q[0], q[1])).collect();
            }
            "/executive/inputs" => {
                let i: RecordedInputs =
                    serde_json::from_slice(&m.data).map_err(|_| json("/executive/inputs"))?;
                let e = exec
                    .as_mut()
                    .ok_or_else(|| bad("inputs before /mission".into()))?;
                let out = e.tick(
                    i.stamp,
                    &Inputs {
                        estimate: &i.estimate,
                        obstacles: &points,
                        unseen: &unseen,
                        bumper: i.bumper,
                        estop: i.estop,
                        operator: &i.operator,
                        telecommands: &i.telecommands,
                    },
                );
                replayed = (out.drive, out.tool);
                pending = Some(i);
            }
            "/executive/outputs" => {
                let o: RecordedOutputs =
                    serde_json::from_slice(&m.data).map_err(|_| json("/executive/outputs"))?;
                let Some(i) = pending.take() else {
                    return Err(bad("an output without its inputs".into()));
                };
                report.ticks += 1;
                if (o.drive, o.tool) == replayed {
                    report.identical += 1;
                } else if report.first_difference.is_none() {
                    report.first_difference = Some((i.stamp, o.drive, replayed.0));
                }
            }
            _ => {}
        }
    }
    report.mission = name;
    Ok(report)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn a_file_that_is_not_mcap_is_bad_input() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.mcap");
        std::fs::write(&path, b"hello").unwrap();
        let err = replay_run(&path).unwrap_err();
        assert!(err.downcast_ref::<BadInput>().is_some(), "{err:#}");
    }
}
