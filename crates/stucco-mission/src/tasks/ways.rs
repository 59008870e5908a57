//! Ways about a room as the robot knows it, shared by the tasks that
//! drive.

use crate::behaviour::{Behaviour, go_to};
use crate::executive::ExecutiveConfig;
use crate::manoeuvre::{self, Space};
use crate::model::Estimate;
use stucco_core::Pose2;

/// The room as `est` knows it, for checking ways at `speed_mps`: its
/// doors and what stands on its floor.
pub(crate) fn estimate_space<'a>(
    config: &'a ExecutiveConfig,
    est: &'a Estimate,
    speed_mps: f64,
) -> Space<'a> {
    Space::new(
        est.room_m,
        &est.corners,
        &est.doors,
        &est.obstacles,
        &config.vehicle,
        &config.safety,
        speed_mps,
    )
}

/// The way from `from` to `goal` in the room `est` knows: the plain one
/// (turn toward the goal, drive, turn to its heading) when the body and
/// the supervisor's field keep clear of the walls, the doorways and what
/// stands on the floor all along it; else the manoeuvre in partial turns
/// and short runs that does; `None` when neither does. With it, the time
/// it is reckoned to take, s.
pub(crate) fn planned_way(
    config: &ExecutiveConfig,
    est: &Estimate,
    from: &Pose2,
    goal: &Pose2,
    speed_mps: f64,
) -> Option<(f64, Vec<Behaviour>)> {
    let space = estimate_space(config, est, speed_mps);
    // The plain way is checked as it will be driven.
    let plain = go_to(&config.gains, from, goal, speed_mps);
    if let Some(cost) = space.way_cost(from, &plain) {
        return Some((cost, plain));
    }
    if let Some((cost, moves)) = space.manoeuvre(from, goal) {
        return Some((
            cost,
            manoeuvre::behaviours(&config.gains, &moves, speed_mps),
        ));
    }
    if space.pose_clear(from) {
        return None;
    }
    // Standing nearer something than the body's margins allow (it was
    // seen only on the way here): back out along the way the robot came,
    // as little as frees it, and go on from there.
    BACK_OUT_M.iter().find_map(|&d| {
        let back = *from * Pose2::new(-d, 0.0, 0.0);
        if !space.pose_clear(&back) {
            return None;
        }
        let (cost, moves) = space.manoeuvre(&back, goal)?;
        let mut way = vec![Behaviour::reverse_to(&config.gains, back, speed_mps)];
        way.extend(manoeuvre::behaviours(&config.gains, &moves, speed_mps));
        Some((cost + 0.5 + d / speed_mps, way))
    })
}

/// How far a robot standing too near something may back out before its
/// way is planned, m (tried in turn).
const BACK_OUT_M: [f64; 4] = [0.1, 0.2, 0.3, 0.4];

/// [`planned_way`], or failing that the plain way, the supervisor
/// stopping the robot before it touches anything.
pub(crate) fn way(
    config: &ExecutiveConfig,
    est: &Estimate,
    from: &Pose2,
    goal: &Pose2,
    speed_mps: f64,
) -> Vec<Behaviour> {
    planned_way(config, est, from, goal, speed_mps)
        .map_or_else(|| go_to(&config.gains, from, goal, speed_mps), |(_, w)| w)
}
