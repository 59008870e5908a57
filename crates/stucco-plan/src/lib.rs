//! Plastering plans of stucco: the surfaces of a room with their doors and
//! windows as holes, the spray tool, where the robot stands and what the
//! nozzle does there, and the scores of a coat.
//!
//! - [`RoomModel`] → [`RoomModel::surfaces`]: each wall and the ceiling as
//!   a [`Surface`], a rectangle in its own `(u, v)` plane with its
//!   [`Opening`]s.
//! - [`SprayTool`]: the gantry (rail, arm, lift), the footprint, the flow
//!   and the coat, as a mission file's `[spray]` table gives them.
//! - [`plan()`]: [`Station`]s (where the rear axle stands) with their
//!   [`Pass`]es of [`Move`]s (where the nozzle aims, at what speed,
//!   spraying or not), and the [`Unreachable`] area, reported, never
//!   dropped.
//! - [`predict`], [`score`], [`RoomScore`]: thickness grids and the scores
//!   acceptance asks for (coverage within tolerance, overspray, CV).
//!
//! ```
//! use stucco_core::{Pose2, VehicleSpec};
//! use stucco_plan::{RoomModel, SprayTool, plan, predicted_score};
//!
//! let room = RoomModel {
//!     size_m: [3.2, 2.6],
//!     corners: Vec::new(),
//!     height_m: 2.5,
//!     openings: Vec::new(),
//!     obstacles: Vec::new(),
//! };
//! let tool = SprayTool::default();
//! let p = plan(&room, &tool, &VehicleSpec::default(), &Pose2::new(1.6, 1.3, 0.0))?;
//! let s = predicted_score(&p);
//! assert!(s.wall_coverage_pct > 99.9 && s.ceiling_coverage_pct > 99.9);
//! # Ok::<(), stucco_plan::PlanError>(())
//! ```
#![warn(missing_docs)]

mod coverage;
mod outline;
mod planner;
mod surface;
mod tool;

pub use coverage::{RoomScore, SurfaceScore, minimum_spray_m2, predict, predicted_score, score};
pub use outline::{Outline, segments_meet};
pub use planner::{Lane, Move, PLAN_CELL_M, Pass, Plan, ReachMask, Station, Unreachable, plan};
pub use surface::{
    Obstacle, Opening, OpeningKind, Rect, RoomModel, Surface, SurfaceId, WallLine, WallOpening,
};
pub use tool::SprayTool;

/// Why no plan could be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The tool cannot lay the coat it is asked for.
    #[error("spray tool: {field} {why}")]
    Tool {
        /// The setting at fault.
        field: &'static str,
        /// Why.
        why: String,
    },
    /// The room cannot be plastered with this tool.
    #[error("room: {0}")]
    Room(String),
}
