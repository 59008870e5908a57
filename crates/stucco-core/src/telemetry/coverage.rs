//! How far a plastering task has got, as the robot publishes it on
//! `stucco/NAME/coverage`: the plan's spraying time carried out, surface by
//! surface.

use crate::SurfaceId;
use serde::{Deserialize, Serialize};

/// How far the `plaster` task under way has got over its plan, as the
/// robot knows it: the plan's spraying time carried out, surface by
/// surface (the coat itself is measured only in the simulator).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlasterCoverage {
    /// The task's index among the mission's.
    pub task: usize,
    /// Stations done.
    pub stations_done: usize,
    /// Stations planned.
    pub stations: usize,
    /// Each planned surface's share done.
    pub surfaces: Vec<SurfaceCoverage>,
}

/// One surface's share of a plan carried out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceCoverage {
    /// The surface.
    pub surface: SurfaceId,
    /// Spraying time planned on it, s.
    pub planned_spray_s: f64,
    /// Spraying time carried out, s.
    pub done_spray_s: f64,
    /// Plasterable area no station reaches, m² (reported, not sprayed).
    pub unreachable_m2: f64,
}

impl SurfaceCoverage {
    /// Share of the planned spraying done, % (100 when none is planned).
    pub fn done_pct(&self) -> f64 {
        if self.planned_spray_s > 0.0 {
            100.0 * self.done_spray_s / self.planned_spray_s
        } else {
            100.0
        }
    }
}
