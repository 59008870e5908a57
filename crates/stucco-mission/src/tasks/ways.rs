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
    if !space.pose_clear(from) {
        // Standing nearer something than the body's margins allow (seen
        // only on the way here, or a station's end squeezed against a
        // wall): run out, and go on from there.
        return run_outs(&space, *from).find_map(|(d, out)| {
            let (cost, moves) = space.manoeuvre(&out, goal)?;
            let mut way = vec![run_out(config, from, d, speed_mps)];
            way.extend(manoeuvre::behaviours(&config.gains, &moves, speed_mps));
            Some((cost + 0.5 + d.abs() / speed_mps, way))
        });
    }
    None
}

/// The runs along the robot's own line from `from` that end where the
/// body and its margins keep clear in `space`, least first, backing
/// before forward (the way it came): each as the distance run (negative
/// backing), m, and the pose it ends at.
pub(crate) fn run_outs<'a>(
    space: &'a Space<'_>,
    from: Pose2,
) -> impl Iterator<Item = (f64, Pose2)> + 'a {
    RUN_OUT_M
        .iter()
        .flat_map(|&d| [-d, d])
        .map(move |d| (d, from * Pose2::new(d, 0.0, 0.0)))
        .filter(|(_, out)| space.pose_clear(out))
}

/// The behaviour that runs `d` along the robot's own line from `from`,
/// m (negative backing).
pub(crate) fn run_out(config: &ExecutiveConfig, from: &Pose2, d: f64, speed_mps: f64) -> Behaviour {
    let out = *from * Pose2::new(d, 0.0, 0.0);
    if d < 0.0 {
        Behaviour::reverse_to(&config.gains, out, speed_mps)
    } else {
        Behaviour::regulate(&config.gains, out, speed_mps)
    }
}

/// How far a robot standing too near something may run out along its
/// line, backing or forward, before its way is planned, m (tried in turn).
const RUN_OUT_M: [f64; 4] = [0.1, 0.2, 0.3, 0.4];

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
