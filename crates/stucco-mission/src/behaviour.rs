//! Behaviours: the motions tasks are built of, each a control law of
//! `stucco-control` with a start and an end. A task is a queue of them.

use crate::model::{Estimate, WallGeometry};
use crate::task::{Side, WallName};
use stucco_control::{GainSchedule, PathFollower, PoseRegulator, WallFollower, WallSide};
pub use stucco_core::{BehaviourKind, PivotPhase};
use stucco_core::{DriveCommand, Pose2, Stamp, VehicleSpec, wrap_angle};

/// Heading error a pivot stops at, rad.
const PIVOT_TOLERANCE_RAD: f64 = 0.01;
/// Share of the top speed the front wheel runs at, across, in a pivot.
const PIVOT_WHEEL_SHARE: f64 = 0.75;
/// Share of the drive's acceleration a pivot brakes with, so the wheel,
/// which can brake harder, is sure to stop it on its heading.
const PIVOT_BRAKE_SHARE: f64 = 0.6;
/// Slowest turn of a pivot, rad/s: the last hundredths of a radian.
const PIVOT_CREEP_RADPS: f64 = 0.05;

/// The turning rate of a pivot `left_rad` short of its heading, rad/s:
/// as fast as the front wheel, across, may run, and no faster than
/// braking at [`PIVOT_BRAKE_SHARE`] of the drive's deceleration stops it
/// on the heading (ω = v / wheelbase with the wheel across).
fn pivot_rate(left_rad: f64, vehicle: &VehicleSpec) -> f64 {
    let top = PIVOT_WHEEL_SHARE * vehicle.max_speed_mps / vehicle.wheelbase_m;
    let brake = PIVOT_BRAKE_SHARE * vehicle.max_accel_mps2 / vehicle.wheelbase_m;
    let to_stop = (left_rad - 0.5 * PIVOT_TOLERANCE_RAD).max(0.0);
    (2.0 * brake * to_stop)
        .sqrt()
        .min(top)
        .max(PIVOT_CREEP_RADPS)
}

/// A goal nearer than this needs no drive, only a turn, m.
const NEAR_M: f64 = 0.05;
/// A turn smaller than this is left to the line law, rad.
const SMALL_TURN_RAD: f64 = 0.035;

/// One step of a behaviour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step {
    /// Still at it, with this command.
    Drive(DriveCommand),
    /// Finished.
    Done,
}

/// A behaviour with its law and progress.
#[derive(Clone, Debug)]
pub struct Behaviour {
    kind: BehaviourKind,
    law: Law,
    started: Option<Stamp>,
}

#[derive(Clone, Debug)]
enum Law {
    Hold,
    /// A turn on the spot, at most this fast if given, rad/s.
    Pivot(Option<f64>),
    Regulate(PoseRegulator),
    Reverse(PoseRegulator),
    Wall {
        law: WallFollower,
        speed_mps: f64,
        forward: bool,
    },
    Path(PathFollower, usize),
}

impl Behaviour {
    /// Standing still until the task decides otherwise.
    pub fn hold() -> Self {
        Behaviour {
            kind: BehaviourKind::Hold,
            law: Law::Hold,
            started: None,
        }
    }

    /// A turn on the spot to `heading_rad`.
    pub fn pivot(heading_rad: f64) -> Self {
        Behaviour {
            kind: BehaviourKind::Pivot {
                heading_rad: wrap_angle(heading_rad),
                phase: PivotPhase::Steer,
            },
            law: Law::Pivot(None),
            started: None,
        }
    }

    /// A turn on the spot to `heading_rad` no faster than `rate_radps`: a
    /// look, sweeping a camera's fan slowly across what it is to measure.
    pub fn pivot_slowly(heading_rad: f64, rate_radps: f64) -> Self {
        Behaviour {
            law: Law::Pivot(Some(rate_radps.max(PIVOT_CREEP_RADPS))),
            ..Self::pivot(heading_rad)
        }
    }

    /// Driving along the line through `goal` (along its heading) to it.
    pub fn regulate(gains: &GainSchedule, goal: Pose2, speed_mps: f64) -> Self {
        let mut law = PoseRegulator::new(gains.clone(), speed_mps);
        law.tolerance_m = 0.005;
        Behaviour {
            kind: BehaviourKind::Regulate { goal },
            law: Law::Regulate(law),
            started: None,
        }
    }

    /// Backing along the line through `goal` to it, the robot facing the
    /// goal's heading. The rear axle's kinematics are the same backward
    /// with the heading turned half round and the steering negated, so the
    /// forward law drives a mirrored robot and its command is mirrored back.
    pub fn reverse_to(gains: &GainSchedule, goal: Pose2, speed_mps: f64) -> Self {
        let mut law = PoseRegulator::new(gains.clone(), speed_mps);
        law.tolerance_m = 0.005;
        Behaviour {
            kind: BehaviourKind::Reverse { goal },
            law: Law::Reverse(law),
            started: None,
        }
    }

    /// Following `wall` at `standoff_m` to `to_m` along it, the wall on
    /// `side`.
    pub fn follow_wall(
        gains: &GainSchedule,
        wall: WallName,
        side: Side,
        standoff_m: f64,
        to_m: f64,
        forward: bool,
        speed_mps: f64,
    ) -> Self {
        let side = match side {
            Side::Left => WallSide::Left,
            Side::Right => WallSide::Right,
        };
        Behaviour {
            kind: BehaviourKind::FollowWall {
                wall,
                standoff_m,
                to_m,
            },
            law: Law::Wall {
                law: WallFollower::new(gains.clone(), side, standoff_m),
                speed_mps,
                forward,
            },
            started: None,
        }
    }

    /// Following the path through `points`.
    pub fn path(gains: &GainSchedule, points: Vec<[f64; 2]>, speed_mps: f64) -> Self {
        let segments = points.len().saturating_sub(1);
        Behaviour {
            kind: BehaviourKind::Path {
                segment: 0,
                segments,
            },
            law: Law::Path(
                PathFollower::new(gains.clone(), points, speed_mps),
                segments,
            ),
            started: None,
        }
    }

    /// What it is doing.
    pub fn kind(&self) -> &BehaviourKind {
        &self.kind
    }

    /// Its name, for events.
    pub fn name(&self) -> &'static str {
        match self.kind {
            BehaviourKind::Hold => "hold",
            BehaviourKind::Pivot { .. } => "pivot",
            BehaviourKind::Regulate { .. } => "regulate",
            BehaviourKind::Reverse { .. } => "reverse",
            BehaviourKind::FollowWall { .. } => "follow_wall",
            BehaviourKind::Path { .. } => "path",
        }
    }

    /// True for a turn on the spot.
    pub fn is_pivot(&self) -> bool {
        matches!(self.kind, BehaviourKind::Pivot { .. })
    }

    /// One control step at `now` on the estimate `est`.
    pub fn step(&mut self, now: Stamp, est: &Estimate, vehicle: &VehicleSpec) -> Step {
        let started = *self.started.get_or_insert(now);
        let pose = est.pose;
        match (&mut self.law, &mut self.kind) {
            (Law::Hold, _) => Step::Drive(DriveCommand::STOP),
            (Law::Pivot(top), BehaviourKind::Pivot { heading_rad, phase }) => {
                // The wheel needs this long to swing through 90°.
                let settle = vehicle.max_steer_rad / vehicle.max_steer_rate_radps + 0.1;
                let err = wrap_angle(*heading_rad - pose.theta);
                let steer = vehicle.max_steer_rad.copysign(err);
                match phase {
                    PivotPhase::Steer => {
                        if now.seconds_since(started) >= settle {
                            *phase = PivotPhase::Turn;
                        }
                        Step::Drive(DriveCommand {
                            speed_mps: 0.0,
                            steer_rad: steer,
                        })
                    }
                    PivotPhase::Turn => {
                        if err.abs() <= PIVOT_TOLERANCE_RAD {
                            *phase = PivotPhase::Straighten;
                            self.started = Some(now);
                            return Step::Drive(DriveCommand::STOP);
                        }
                        let omega = pivot_rate(err.abs(), vehicle).min(top.unwrap_or(f64::MAX));
                        Step::Drive(DriveCommand {
                            speed_mps: omega * vehicle.wheelbase_m,
                            steer_rad: steer,
                        })
                    }
                    PivotPhase::Straighten => {
                        if now.seconds_since(started) >= settle {
                            Step::Done
                        } else {
                            Step::Drive(DriveCommand::STOP)
                        }
                    }
                }
            }
            (Law::Pivot(_), _) => Step::Done,
            (Law::Regulate(law), BehaviourKind::Regulate { goal }) => {
                let rel = goal.inverse() * pose;
                if -rel.x <= law.tolerance_m {
                    return Step::Done;
                }
                Step::Drive(law.command(&pose, goal))
            }
            (Law::Regulate(_), _) => Step::Done,
            (Law::Reverse(law), BehaviourKind::Reverse { goal }) => {
                let mirror = |p: &Pose2| Pose2::new(p.x, p.y, p.theta + std::f64::consts::PI);
                let (m, g) = (mirror(&pose), mirror(goal));
                let rel = g.inverse() * m;
                if -rel.x <= law.tolerance_m {
                    return Step::Done;
                }
                let cmd = law.command(&m, &g);
                Step::Drive(DriveCommand {
                    speed_mps: -cmd.speed_mps,
                    steer_rad: -cmd.steer_rad,
                })
            }
            (Law::Reverse(_), _) => Step::Done,
            (
                Law::Wall {
                    law,
                    speed_mps,
                    forward,
                },
                BehaviourKind::FollowWall { wall, to_m, .. },
            ) => {
                let Some(g) = WallGeometry::in_room(est, *wall) else {
                    return Step::Done;
                };
                let at = g.position(&pose.position().coords);
                let remaining = if *forward { *to_m - at } else { at - *to_m };
                if remaining <= 0.005 {
                    return Step::Done;
                }
                let speed = *speed_mps * (remaining / 0.5).clamp(0.1, 1.0);
                let (d, gamma) = g.seen_from(&pose);
                Step::Drive(DriveCommand {
                    speed_mps: speed,
                    steer_rad: law.steer(d, gamma, speed),
                })
            }
            (Law::Wall { .. }, _) => Step::Done,
            (Law::Path(law, segments), BehaviourKind::Path { segment, .. }) => {
                let cmd = law.command(&pose);
                *segment = law.segment();
                if law.segment() >= *segments {
                    Step::Done
                } else {
                    Step::Drive(cmd)
                }
            }
            (Law::Path(..), _) => Step::Done,
        }
    }
}

/// The behaviours that take a robot at `from` to `goal` on a tricycle that
/// turns on the spot: turn toward the goal, drive the line to it, turn to
/// its heading. Turns too small to matter are left to the line law.
pub fn go_to(gains: &GainSchedule, from: &Pose2, goal: &Pose2, speed_mps: f64) -> Vec<Behaviour> {
    let mut out = Vec::new();
    let delta = goal.position() - from.position();
    if delta.norm() > NEAR_M {
        let heading = delta.y.atan2(delta.x);
        if wrap_angle(heading - from.theta).abs() > SMALL_TURN_RAD {
            out.push(Behaviour::pivot(heading));
        }
        out.push(Behaviour::regulate(
            gains,
            Pose2::new(goal.x, goal.y, heading),
            speed_mps,
        ));
        if wrap_angle(goal.theta - heading).abs() > SMALL_TURN_RAD {
            out.push(Behaviour::pivot(goal.theta));
        }
    } else if wrap_angle(goal.theta - from.theta).abs() > PIVOT_TOLERANCE_RAD {
        out.push(Behaviour::pivot(goal.theta));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pivot of `turn_rad` on the kinematic tricycle, its wheel's speed
    /// changing at most as fast as the drive allows: the seconds it turns
    /// and where it stops from the heading.
    fn pivot(turn_rad: f64) -> (f64, f64) {
        let v = VehicleSpec::default();
        let dt = 0.02;
        let (mut left, mut omega, mut t) = (turn_rad, 0.0_f64, 0.0);
        while left.abs() > PIVOT_TOLERANCE_RAD && t < 30.0 {
            let goal = pivot_rate(left.abs(), &v).copysign(left);
            let most = v.max_accel_mps2 / v.wheelbase_m * dt;
            omega += (goal - omega).clamp(-most, most);
            left -= omega * dt;
            t += dt;
        }
        // Stopped there, the wheel still turns the robot on while it
        // brakes as hard as it can.
        let coast = omega * omega.abs() / (2.0 * v.max_accel_mps2 / v.wheelbase_m);
        (t, (left - coast).abs())
    }

    #[test]
    fn a_pivot_turns_fast_and_stops_on_its_heading() {
        for turn in [0.05, 0.5, std::f64::consts::FRAC_PI_2, 3.0] {
            let (t, off) = pivot(turn);
            assert!(off <= PIVOT_TOLERANCE_RAD, "{turn} rad: {off} rad off");
            // A quarter turn in 2.4 s, where slowing in proportion to the
            // angle left took 4.3 s.
            if turn == std::f64::consts::FRAC_PI_2 {
                assert!(t < 2.6, "{t} s");
            }
        }
    }
}
