//! Control laws of stucco: what the front wheel of the papers' tricycle
//! should do to follow a line, pass a door, keep to the middle of a
//! corridor, follow a wall at a standoff, reach a pose or follow a path of
//! segments. Each law maps the estimated pose relative to its reference to
//! a [`DriveCommand`]; [`Limiter`] holds the command to the vehicle's
//! steering angle and rate.
//!
//! The papers' law (paper A §3.4) steers the front wheel so that it points
//! at the line ahead:
//!
//! ```text
//! α = −atan(k1·(y − y_d) + k2·sin θ) − θ
//! ```
//!
//! with `y − y_d` the rear axle's offset from the line and `θ` the heading
//! relative to it; `k1` sets how far ahead the wheel aims (1/m), `k2` how
//! much the heading counts. The gains are scheduled by speed.
//!
//! ```
//! use stucco_control::{LineFollower, GainSchedule};
//! let law = LineFollower::new(GainSchedule::default());
//! // 10 cm left of the line, parallel to it: steer right.
//! assert!(law.steer(0.10, 0.0, 0.5) < 0.0);
//! ```
#![warn(missing_docs)]

mod laws;
mod limiter;

pub use laws::{
    CorridorCentring, GainSchedule, LineFollower, PathFollower, PoseRegulator, WallFollower,
    WallSide,
};
pub use limiter::Limiter;
