//! The checkpoint file: what a robot switched off in the middle of a job
//! needs to go on where it stopped — the mission's progress, what it knew
//! of the room, the plan it was carrying out — written atomically, checked
//! against the mission it was made for when read back.

use crate::file::{BadInput, Mission};
use crate::{DoorEstimate, Progress, WallName};
use serde::{Deserialize, Serialize};
use std::hash::Hasher;
use std::io::Write;
use std::path::Path;
use stucco_core::Pose2;

/// The checkpoint's file in a run's folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.json";
/// The plan a plastering run carries out, beside its checkpoint.
pub const PLAN_FILE: &str = "plan.json";

/// What a checkpoint file holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    /// The mission's name.
    pub mission: String,
    /// Digest of the mission file's text and its plan file's: a checkpoint
    /// of another version of either is refused.
    pub digest: String,
    /// The seed of the run.
    pub seed: u64,
    /// The tasks' states.
    pub progress: Progress,
    /// What the robot knew of the room.
    pub map: RoomMap,
    /// Seconds each task started has taken, over every part of the run
    /// (one under way: so far), by task index: a resumed run reports the
    /// whole job's plastering time.
    #[serde(default)]
    pub task_seconds: std::collections::BTreeMap<usize, f64>,
    /// The windows found in each room the robot had left, by the plan's
    /// name of the room: a resumed run reports them with its own.
    #[serde(default)]
    pub rooms_left: Vec<(String, Vec<(WallName, stucco_nav::Window)>)>,
}

/// The room as the robot knew it at a checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomMap {
    /// Its size, m.
    pub room_m: [f64; 2],
    /// Its σ, m.
    pub room_sigma_m: [f64; 2],
    /// Its doors.
    pub doors: Vec<DoorEstimate>,
    /// The robot's estimated pose in it.
    pub pose: Pose2,
    /// The floor plan's room it is, when the mission has a plan.
    #[serde(default)]
    pub room: Option<String>,
    /// The windows the camera had found in it, wall by wall.
    #[serde(default)]
    pub windows: Vec<(WallName, stucco_nav::Window)>,
}

/// FNV-1a digest of what a checkpoint of `mission` must have been made
/// with: the mission file's text and, when it names one, its plan file's
/// (door numbers in a checkpoint are the plan's), each as the mission was
/// parsed from it, a newline between.
pub fn digest(mission: &Mission) -> String {
    let mut h = fnv::FnvHasher::default();
    h.write(mission.text().as_bytes());
    if let Some(plan) = mission.plan_text() {
        h.write(b"\n");
        h.write(plan.as_bytes());
    }
    format!("fnv1a64:{:016x}", h.finish())
}

/// Writes `bytes` to `path` atomically: a temporary file beside it,
/// flushed to disk, renamed over it, the folder flushed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp"));
    {
        let mut f = std::fs::File::create(&tmp).map_err(|e| named(&tmp, "cannot write", e))?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path).map_err(|e| named(path, "cannot replace", e))?;
    if let Ok(d) = std::fs::File::open(dir) {
        // Persists the rename; not every platform can sync a folder.
        let _ = d.sync_all();
    }
    Ok(())
}

/// Reads the checkpoint at `path` for `mission`, or says why it cannot be
/// used — leaving the file as it is.
pub fn read_checkpoint(path: &Path, mission: &Mission) -> Result<Checkpoint, BadInput> {
    let raw = std::fs::read_to_string(path).map_err(|e| {
        BadInput(format!(
            "{}: cannot read the checkpoint: {e}",
            path.display()
        ))
    })?;
    let cp: Checkpoint = serde_json::from_str(&raw).map_err(|e| {
        BadInput(format!(
            "{}:{}:{}: the checkpoint is corrupt ({e}); it is left as it is",
            path.display(),
            e.line(),
            e.column()
        ))
    })?;
    let digest = digest(mission);
    if cp.mission != mission.name || cp.digest != digest {
        return Err(BadInput(format!(
            "{}: the checkpoint was written for mission {:?} ({}), not this file ({:?}, {}); it is left as it is",
            path.display(),
            cp.mission,
            cp.digest,
            mission.name,
            digest
        )));
    }
    Ok(cp)
}

/// An I/O error that names the file.
fn named(path: &Path, what: &str, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("{what} {}: {e}", path.display()))
}
