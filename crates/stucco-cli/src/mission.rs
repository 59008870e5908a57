//! Experiment missions (`missions/*.toml`): a world, seeds and one of the
//! navigation experiments of paper A, run by `stucco run`. Every table is
//! `deny_unknown_fields`; errors name the file, line and column.

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A mission file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mission {
    /// Name, for reports.
    pub name: String,
    /// The world file, relative to the mission file.
    pub world: PathBuf,
    /// Seed of the first run; run `k` uses `seed + k`.
    pub seed: u64,
    /// Runs when `--runs` is not given.
    #[serde(default = "one")]
    pub runs: u64,
    /// Door passage (Table III).
    pub door_passage: Option<DoorPassage>,
    /// Corridor centring.
    pub corridor: Option<Corridor>,
    /// The room's size learnt while touring it.
    pub room_size: Option<RoomSize>,
}

fn one() -> u64 {
    1
}

/// Passing the door in the room's wall `x = xs` (the room frame has its
/// origin in a corner), heading +x.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DoorPassage {
    /// The room's size as a map gives it, m (the filter refines it).
    pub room_m: [f64; 2],
    /// The door's centre as the map gives it, m: on the wall `x = xs`.
    /// The passage is scored against the world's open door nearest it
    /// (there must be one within 0.3 m).
    pub door_m: [f64; 2],
    /// How far off the map's door is, m (the filter places it).
    #[serde(default)]
    pub door_map_error_m: f64,
    /// Speeds, m/s: each start is run at each.
    pub speeds_mps: Vec<f64>,
    /// Starts.
    pub start: Vec<Start>,
}

/// A named start pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Start {
    /// Name (`easy`, `difficult`).
    pub name: String,
    /// Position of the rear axle, m.
    pub at: [f64; 2],
    /// Heading, degrees.
    pub heading_deg: f64,
}

/// Driving a straight corridor (the room `x ∈ [0, xs]`, `y ∈ [0, ys]`)
/// along +x on its middle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Corridor {
    /// The corridor's size as a map gives it, m.
    pub room_m: [f64; 2],
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Start.
    pub start: Start,
    /// The stretch scored, m along x.
    pub score_x_m: [f64; 2],
}

/// Touring a rectangular room on the filter's estimate while it learns
/// the room's size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomSize {
    /// The size the filter starts from, m.
    pub room_m: [f64; 2],
    /// Its uncertainty, m (σ).
    pub room_sigma_m: f64,
    /// Simulated seconds of touring.
    pub seconds: f64,
    /// Speed, m/s.
    pub speed_mps: f64,
}

impl Mission {
    /// Reads and checks the mission file at `path`.
    pub fn load(path: &Path) -> Result<Mission> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let mission: Mission = toml::from_str(&text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|s| stucco_core::line_column(&text, s.start))
                .unwrap_or((0, 0));
            anyhow::anyhow!("{}:{line}:{column}: {}", path.display(), e.message())
        })?;
        let kinds = usize::from(mission.door_passage.is_some())
            + usize::from(mission.corridor.is_some())
            + usize::from(mission.room_size.is_some());
        if kinds != 1 {
            bail!(
                "{}: a mission holds exactly one of [door_passage], [corridor], [room_size]",
                path.display()
            );
        }
        if mission.runs == 0 {
            bail!(
                "{}:{}: runs: at least one",
                path.display(),
                line_of(&text, "", "runs")
            );
        }
        if let Some((table, key, why)) = mission.invalid() {
            bail!(
                "{}:{}: [{table}] {key}: {why}",
                path.display(),
                line_of(&text, table, key)
            );
        }
        Ok(mission)
    }

    /// The first value out of its range: its table, its key and why.
    fn invalid(&self) -> Option<(&'static str, &'static str, &'static str)> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let size = |r: &[f64; 2]| r.iter().all(|&v| positive(v));
        if let Some(d) = &self.door_passage {
            let t = "door_passage";
            if !size(&d.room_m) {
                return Some((t, "room_m", "sides must be positive"));
            }
            if d.speeds_mps.is_empty() || !d.speeds_mps.iter().all(|&v| positive(v)) {
                return Some((t, "speeds_mps", "at least one speed, each positive"));
            }
            if d.start.is_empty() {
                return Some((t, "start", "at least one [[door_passage.start]]"));
            }
            if !d.door_map_error_m.is_finite() {
                return Some((t, "door_map_error_m", "must be a number"));
            }
        }
        if let Some(c) = &self.corridor {
            let t = "corridor";
            if !size(&c.room_m) {
                return Some((t, "room_m", "sides must be positive"));
            }
            if !positive(c.speed_mps) {
                return Some((t, "speed_mps", "must be positive"));
            }
            if c.score_x_m[0].partial_cmp(&c.score_x_m[1]) != Some(std::cmp::Ordering::Less) {
                return Some((t, "score_x_m", "the stretch must run forward"));
            }
        }
        if let Some(r) = &self.room_size {
            let t = "room_size";
            if !size(&r.room_m) {
                return Some((t, "room_m", "sides must be positive"));
            }
            if !(r.room_sigma_m.is_finite() && r.room_sigma_m >= 0.0) {
                return Some((t, "room_sigma_m", "must not be negative"));
            }
            if !positive(r.seconds) {
                return Some((t, "seconds", "must be positive"));
            }
            if !positive(r.speed_mps) {
                return Some((t, "speed_mps", "must be positive"));
            }
        }
        None
    }

    /// The world file, resolved against the mission file's folder.
    pub fn world_path(&self, mission_path: &Path) -> PathBuf {
        mission_path
            .parent()
            .map_or_else(|| self.world.clone(), |d| d.join(&self.world))
    }
}

/// The line of `key` in `table` (`""`: the top level; its sub-tables count
/// as inside it), or of the table's header when the key is not written
/// there; 0 when neither is.
fn line_of(text: &str, table: &str, key: &str) -> usize {
    let mut current = String::new();
    let mut header = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with('[') {
            current = line
                .trim_matches(|c| c == '[' || c == ']')
                .trim()
                .to_owned();
            if current == table {
                header = i + 1;
            }
            continue;
        }
        let inside = current == table || current.starts_with(&format!("{table}."));
        let written = line.split_once('=').is_some_and(|(k, _)| k.trim() == key);
        if inside && written {
            return i + 1;
        }
    }
    header
}
