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
    /// The door's centre, m: on the wall `x = xs`.
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
                .map(|s| {
                    let before = &text[..s.start.min(text.len())];
                    (
                        before.matches('\n').count() + 1,
                        before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1,
                    )
                })
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
            bail!("{}: runs: at least one", path.display());
        }
        Ok(mission)
    }

    /// The world file, resolved against the mission file's folder.
    pub fn world_path(&self, mission_path: &Path) -> PathBuf {
        mission_path
            .parent()
            .map_or_else(|| self.world.clone(), |d| d.join(&self.world))
    }
}
