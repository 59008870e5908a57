//! `align_to_wall` and `follow_wall`: onto a wall's standoff, and along it.

use super::ways::way;
use super::{
    Behaviours, RUN_IN_M, Task, TaskCx, TaskFailure, TaskStep, Thaw, drive_through, pivot_clearance,
};
use crate::behaviour::{Behaviour, BehaviourKind};
use crate::executive::ExecutiveConfig;
use crate::model::{Estimate, wall_in};
use crate::task::{Side, WallName};
use stucco_core::Pose2;

/// The shortest run-in accepted near a corner, m (a 0.3 m offset settles
/// to about a centimetre).
pub(crate) const MIN_RUN_IN_M: f64 = 1.5;

/// Stops parallel to a wall at a standoff, at a place along it.
#[derive(Clone, Debug)]
pub(crate) struct AlignToWall {
    wall: WallName,
    standoff_m: f64,
    at_m: f64,
    side: Side,
    speed_mps: f64,
    ways: Behaviours,
}

impl AlignToWall {
    pub fn new(wall: WallName, standoff_m: f64, at_m: f64, side: Side, speed_mps: f64) -> Self {
        AlignToWall {
            wall,
            standoff_m,
            at_m,
            side,
            speed_mps,
            ways: Behaviours::default(),
        }
    }
}

impl Task for AlignToWall {
    fn start(&mut self, cx: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        let (config, est, pose) = (cx.config, cx.est, cx.est.pose);
        let gains = &config.gains;
        let clearance = pivot_clearance(config);
        let g = wall_in(est, self.wall, "align_to_wall")?;
        let goal = g.pose_at(self.at_m, self.standoff_m, self.side);
        let queue = &mut self.ways.queue;
        queue.extend(
            approach(
                config,
                &pose,
                &goal,
                self.wall,
                est,
                clearance,
                self.speed_mps,
            )?
            .0,
        );
        let forward = g
            .along
            .dot(&nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin()))
            > 0.0;
        queue.push_back(Behaviour::follow_wall(
            gains,
            self.wall,
            self.side,
            self.standoff_m,
            self.at_m,
            forward,
            self.speed_mps,
        ));
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        drive_through(&mut self.ways, cx)
    }

    fn behaviour(&self) -> Option<&BehaviourKind> {
        self.ways.kind()
    }

    fn clone_box(&self) -> Box<dyn Task> {
        Box::new(self.clone())
    }
}

/// Follows a wall at a standoff from one place along it to another.
#[derive(Clone, Debug)]
pub(crate) struct FollowWall {
    wall: WallName,
    standoff_m: f64,
    from_m: f64,
    to_m: f64,
    speed_mps: f64,
    ways: Behaviours,
}

impl FollowWall {
    pub fn new(wall: WallName, standoff_m: f64, [from_m, to_m]: [f64; 2], speed_mps: f64) -> Self {
        FollowWall {
            wall,
            standoff_m,
            from_m,
            to_m,
            speed_mps,
            ways: Behaviours::default(),
        }
    }
}

impl Task for FollowWall {
    fn start(&mut self, cx: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        let (config, est, pose) = (cx.config, cx.est, cx.est.pose);
        let gains = &config.gains;
        let clearance = pivot_clearance(config);
        let (wall, standoff_m, from_m, to_m, speed_mps) = (
            self.wall,
            self.standoff_m,
            self.from_m,
            self.to_m,
            self.speed_mps,
        );
        let queue = &mut self.ways.queue;
        let g = wall_in(est, wall, "follow_wall")?;
        let forward = to_m > from_m;
        let front = config.vehicle.front_m();
        let room_left = if forward { g.length_m - to_m } else { to_m };
        if room_left < front + 0.1 {
            return Err(TaskFailure::PassEndsAtCorner {
                room_left_m: room_left,
                front_m: front,
            });
        }
        let side = g.side_for(forward);
        let start = g.pose_at(from_m, standoff_m, side);
        let (way, turn_at) = approach(config, &pose, &start, wall, est, clearance, speed_mps)?;
        queue.extend(way);
        queue.push_back(Behaviour::follow_wall(
            gains, wall, side, standoff_m, to_m, forward, speed_mps,
        ));
        // A pass ends too near the wall to turn on the spot: back out
        // along the standoff to where the robot turned in, then drive
        // forward out to a lane as far from the wall as that turn
        // point (the front leads away from the wall; backing out of
        // the line would swing it into the wall).
        let dir = if forward { 1.0 } else { -1.0 };
        let turned_at = g.position(&turn_at.position().coords);
        let back = g.point(turned_at, standoff_m);
        queue.push_back(Behaviour::reverse_to(
            gains,
            Pose2::new(back.x, back.y, start.theta),
            speed_mps,
        ));
        let lane = g.distance(&turn_at.position().coords);
        let out = g.point(turned_at + dir * RUN_IN_M, lane);
        queue.push_back(Behaviour::regulate(
            gains,
            Pose2::new(out.x, out.y, start.theta),
            speed_mps,
        ));
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        drive_through(&mut self.ways, cx)
    }

    fn behaviour(&self) -> Option<&BehaviourKind> {
        self.ways.kind()
    }

    fn clone_box(&self) -> Box<dyn Task> {
        Box::new(self.clone())
    }
}

/// The way onto a pose beside `wall`: to a point `RUN_IN_M` before it,
/// far enough from every wall to turn on the spot, turned to the
/// goal's heading there; the wall law takes it from there.
pub(crate) fn approach(
    config: &ExecutiveConfig,
    from: &Pose2,
    goal: &Pose2,
    wall: WallName,
    est: &Estimate,
    clearance: f64,
    speed_mps: f64,
) -> Result<(Vec<Behaviour>, Pose2), TaskFailure> {
    let g = wall_in(est, wall, "approach")?;
    let gp = goal.position().coords;
    let dir = nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin());
    let forward = g.along.dot(&dir) > 0.0;
    let at = g.position(&gp);
    let standoff = g.distance(&gp);
    let lo = clearance;
    let hi = g.length_m - clearance;
    let want = if forward {
        at - RUN_IN_M
    } else {
        at + RUN_IN_M
    };
    if lo > hi {
        return Err(TaskFailure::RoomTooSmallToTurn);
    }
    let p_at = want.clamp(lo, hi);
    let run_in = (at - p_at).abs();
    if run_in < MIN_RUN_IN_M || (forward && p_at > at) || (!forward && p_at < at) {
        return Err(TaskFailure::PassStartsAtCorner {
            at_m: at,
            clearance_m: clearance,
            run_in_m: MIN_RUN_IN_M,
        });
    }
    let p = g.point(p_at, standoff.max(clearance));
    let turn_at = Pose2::new(p.x, p.y, goal.theta);
    // The plain way when it is clear, else a manoeuvre: a robot
    // stopped on the standoff mid-pass (a run resumed there) is too
    // near the wall to turn back on the spot.
    Ok((way(config, est, from, &turn_at, speed_mps), turn_at))
}
