//! The safety supervisor: it sees every command before the platform does
//! and may stop it — an obstacle where the robot is about to be, a bumper,
//! the e-stop, an estimate too uncertain to drive or spray on. The
//! protective field is the stopping distance of the speed driven: a
//! command whose field reaches something that a slower speed's does not
//! is slowed (no faster than the robot brakes), and only stopped when
//! even that field holds something.

use crate::model::Estimate;
use nalgebra::Point2;
use serde::{Deserialize, Serialize};
pub use stucco_core::Hazard;
use stucco_core::{DriveCommand, Pose2, Twist2, VehicleSpec};

/// What to do when the pose estimate is lost (its σ past the limits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LostPolicy {
    /// Stand still until the estimate is back, failing after
    /// `lost_timeout_s`.
    #[default]
    Hold,
    /// Keep driving (never spraying) and hope the walls come back.
    Continue,
    /// Fail the mission at once.
    Fail,
}

/// What to do when the operator's link is lost (their heartbeat stops).
/// A jog stops at once whatever the policy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinkLossPolicy {
    /// Pause the mission until the operator resumes it.
    #[default]
    Pause,
    /// Go on with the autonomous task (never spraying until the link is
    /// back).
    Continue,
}

/// What a scripted task's failure does to the mission (an operator's task
/// fails alone whatever the policy: the robot stands ready for the next
/// command). Touching something or the e-stop with nobody there, and the
/// estimate lost, stop it whatever the policy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailurePolicy {
    /// A task of one room of a job over rooms (`plaster` with `rooms`:
    /// going there, mapping it, plastering it) gives that room up — its
    /// tasks still to come are skipped — and the job goes on with the
    /// next room, and ends failed; any other task's failure stops the
    /// mission, as `stop`. A site engineer's robot held in one room
    /// plasters the others and names the room it left.
    #[default]
    NextRoom,
    /// The mission stops, failed; the operator's commands are still taken,
    /// and `resume` tries the failed task again.
    Stop,
    /// The mission goes on with its next task, and ends failed.
    Continue,
}

/// The supervisor's settings (a mission file's `[failsafe]` table).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SafetyConfig {
    /// Extra length of the protective field ahead of the body, beyond the
    /// stopping distance, m.
    pub obstacle_margin_m: f64,
    /// Extra width of the field either side of the body, m.
    pub lateral_margin_m: f64,
    /// Deceleration the stopping distance is reckoned with, m/s².
    pub stop_decel_mps2: f64,
    /// The field must stay clear this long before driving on, s.
    pub clear_s: f64,
    /// The estimate is lost when its position σ exceeds this, m.
    pub max_position_sigma_m: f64,
    /// Or its heading σ this, rad.
    pub max_heading_sigma_rad: f64,
    /// What to do then.
    pub on_lost: LostPolicy,
    /// How long `hold` waits for the estimate, and a plastering station
    /// for it to come within `spray_max_sigma_m`, s.
    pub lost_timeout_s: f64,
    /// Spraying only with the position known to this, m (σ).
    pub spray_max_sigma_m: f64,
    /// How long an obstacle may block the way before the task fails, s.
    pub blocked_timeout_s: f64,
    /// What to do when the operator's link is lost.
    pub on_link_loss: LinkLossPolicy,
    /// The link is lost when no operator heartbeat came for this long, s.
    pub link_timeout_s: f64,
    /// What a scripted task's failure does to the mission.
    pub on_task_failure: FailurePolicy,
    /// With nobody there, a touch (the bumper) holds the robot, the spray
    /// off, until the bumper has been free for `clear_s`; the task fails
    /// when the touches go on this long, s (each within this long of the
    /// last: a robot pushing every half second into someone it cannot see
    /// is touching them still).
    pub touch_timeout_s: f64,
}

impl Default for SafetyConfig {
    fn default() -> Self {
        SafetyConfig {
            obstacle_margin_m: 0.15,
            lateral_margin_m: 0.05,
            stop_decel_mps2: 0.8,
            clear_s: 0.5,
            max_position_sigma_m: 0.05,
            max_heading_sigma_rad: 0.035,
            on_lost: LostPolicy::Hold,
            lost_timeout_s: 10.0,
            spray_max_sigma_m: 0.01,
            blocked_timeout_s: 30.0,
            on_link_loss: LinkLossPolicy::Pause,
            link_timeout_s: 1.0,
            on_task_failure: FailurePolicy::NextRoom,
            touch_timeout_s: 60.0,
        }
    }
}

impl SafetyConfig {
    /// The narrowest door a robot `vehicle` drives through with this
    /// field, m: its body, the field's sides, and a centimetre either
    /// side for the line law's tracking. Through a narrower one the field
    /// holds the robot on the jambs.
    pub fn door_width_m(&self, vehicle: &VehicleSpec) -> f64 {
        vehicle.width_m + 2.0 * (self.lateral_margin_m + DOOR_TRACK_M)
    }

    /// The first value out of its range: the key and why.
    pub fn invalid(&self) -> Option<(&'static str, &'static str)> {
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let checks = [
            ("obstacle_margin_m", non_negative(self.obstacle_margin_m)),
            ("lateral_margin_m", non_negative(self.lateral_margin_m)),
            ("stop_decel_mps2", positive(self.stop_decel_mps2)),
            ("clear_s", non_negative(self.clear_s)),
            ("max_position_sigma_m", positive(self.max_position_sigma_m)),
            (
                "max_heading_sigma_rad",
                positive(self.max_heading_sigma_rad),
            ),
            ("lost_timeout_s", positive(self.lost_timeout_s)),
            ("spray_max_sigma_m", positive(self.spray_max_sigma_m)),
            ("blocked_timeout_s", positive(self.blocked_timeout_s)),
            ("link_timeout_s", positive(self.link_timeout_s)),
            ("touch_timeout_s", positive(self.touch_timeout_s)),
        ];
        checks
            .into_iter()
            .find(|(_, ok)| !ok)
            .map(|(k, _)| (k, "must be a number in range (margins ≥ 0, the rest > 0)"))
    }
}

/// The supervisor's verdict on one command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// The command to send.
    pub drive: DriveCommand,
    /// What stopped it, if anything did.
    pub hazard: Option<Hazard>,
}

/// The safety supervisor.
#[derive(Clone, Debug)]
pub struct Supervisor {
    config: SafetyConfig,
    vehicle: VehicleSpec,
    /// Seconds the field has been clear since it last held something.
    clear_for_s: f64,
    lost: bool,
    /// The last obstacle point that held a command, and whether it was
    /// backing.
    last_block: Option<(Point2<f64>, bool)>,
    /// The speed the last check let through, m/s (negative backing).
    granted_mps: f64,
}

/// How far the line law lets the body stray off a door's line on the run
/// through it, m.
const DOOR_TRACK_M: f64 = 0.01;
/// The slowest speed the supervisor slows a command to before it stops
/// it, m/s (3 cm/s at the wheel, as a manoeuvre ends its moves).
const CREEP_MPS: f64 = 0.05;
/// How much nearer a drive must take a point already in the field's side
/// band for it to hold the robot, m: a millimetre, what the arithmetic of
/// the body's poses along the arc may add by itself.
const NEARER_M: f64 = 1e-3;

impl Supervisor {
    /// The supervisor of `vehicle` with `config`.
    pub fn new(config: SafetyConfig, vehicle: VehicleSpec) -> Self {
        Supervisor {
            config,
            vehicle,
            clear_for_s: f64::INFINITY,
            lost: false,
            last_block: None,
            granted_mps: 0.0,
        }
    }

    /// Its settings.
    pub fn config(&self) -> &SafetyConfig {
        &self.config
    }

    /// True when the estimate is good enough to spray on.
    pub fn spray_allowed(&self, est: &Estimate) -> bool {
        !self.lost && est.position_sigma_m <= self.config.spray_max_sigma_m
    }

    /// True while the estimate counts as lost (with hysteresis: it comes
    /// back at 80% of the limits).
    pub fn lost(&self) -> bool {
        self.lost
    }

    /// Updates the lost flag from `est`; returns it.
    pub fn watch_estimate(&mut self, est: &Estimate) -> bool {
        let c = &self.config;
        let k = if self.lost { 0.8 } else { 1.0 };
        self.lost = !(est.position_sigma_m <= k * c.max_position_sigma_m
            && est.heading_sigma_rad <= k * c.max_heading_sigma_rad);
        self.lost
    }

    /// True when an obstacle point (robot frame, rear axle at the origin)
    /// lies in the body's footprint anywhere along the arc `cmd` drives
    /// within its stopping distance (and the margin): forward, backward,
    /// on a curve or turning on the spot alike.
    pub fn blocked(&self, cmd: &DriveCommand, obstacles: &[Point2<f64>]) -> bool {
        self.blocking(cmd, obstacles).is_some()
    }

    /// The obstacle point that blocks `cmd` (as [`Supervisor::blocked`]
    /// tells), the first the body would meet along the arc; robot frame.
    pub fn blocking(&self, cmd: &DriveCommand, obstacles: &[Point2<f64>]) -> Option<Point2<f64>> {
        let v = &self.vehicle;
        let c = &self.config;
        if cmd.speed_mps == 0.0 || obstacles.is_empty() {
            return None;
        }
        let s = cmd.speed_mps.abs();
        // Front-wheel travel before a stop, and the margin.
        let travel = s * s / (2.0 * c.stop_decel_mps2) + c.obstacle_margin_m + 0.1 * s;
        let sign = cmd.speed_mps.signum();
        // Per metre of front-wheel travel: the rear axle's advance and the
        // turn.
        let (forward, turn) = (
            sign * cmd.steer_rad.cos(),
            sign * cmd.steer_rad.sin() / v.wheelbase_m,
        );
        let (back, front) = (-v.rear_overhang_m, v.front_m());
        let bare = 0.5 * v.width_m;
        let half = bare + c.lateral_margin_m;
        // How deep a point lies in the field's side band, m, where it does.
        let depth = |q: &Point2<f64>| {
            (q.x >= back && q.x <= front && q.y.abs() <= half).then(|| half - q.y.abs())
        };
        // Beside the body already, within the side margin (a wall the
        // robot stands nearer than the margin, as after a station): held
        // only by a drive that takes it nearer. Held by any drive, a robot
        // that came within the margin of a wall (the laser's echoes of it
        // scatter by 2 cm) stood there until its way failed, when it
        // could have driven or backed along it.
        let beside: Vec<Option<f64>> = obstacles
            .iter()
            .map(|p| depth(p).filter(|_| p.y.abs() > bare))
            .collect();
        // Poses every 5 cm of travel (and every 3° of turn).
        let steps = ((travel / 0.05).max(travel * turn.abs() / 0.05).ceil() as usize).max(1);
        let ds = travel / steps as f64;
        let twist = Twist2::new(forward, 0.0, turn);
        (1..=steps).find_map(|k| {
            let pose = Pose2::default().advanced(&twist, ds * k as f64);
            let inv = pose.inverse();
            obstacles
                .iter()
                .zip(&beside)
                .find(|(p, beside)| {
                    let q = inv.transform_point(p);
                    depth(&q).is_some_and(|d| beside.is_none_or(|d0| d > d0 + NEARER_M))
                })
                .map(|(p, _)| *p)
        })
    }

    /// What blocked the last command held for an obstacle (robot frame,
    /// at the time), and whether that command was backing.
    pub fn last_block(&self) -> Option<(Point2<f64>, bool)> {
        self.last_block
    }

    /// Checks `cmd` against the obstacles seen and the estimate; `dt_s`
    /// since the last check. `unseen` are echoes seen before where the
    /// laser does not look now (behind the robot): a command that reverses
    /// is checked against them too.
    pub fn check(
        &mut self,
        cmd: DriveCommand,
        obstacles: &[Point2<f64>],
        unseen: &[Point2<f64>],
        est: &Estimate,
        dt_s: f64,
    ) -> Verdict {
        let lost = self.watch_estimate(est);
        if lost && self.config.on_lost != LostPolicy::Continue {
            self.granted_mps = 0.0;
            return Verdict {
                drive: DriveCommand::STOP,
                hazard: Some(Hazard::Lost),
            };
        }
        // The field is the stopping distance of the speed driven: the
        // fastest speed up to the command's whose field is clear is
        // driven (a robot nearing a wall beside its way slows, as a car
        // does, rather than stopping for good with its field on the
        // wall), but never slower than the robot can have braked to
        // since the last check. Only when even that field holds
        // something is it stopped.
        let at = |speed_mps: f64| DriveCommand {
            speed_mps: speed_mps.copysign(cmd.speed_mps),
            steer_rad: cmd.steer_rad,
        };
        let block_at = |s: f64| {
            let c = at(s);
            self.blocking(&c, obstacles).or_else(|| {
                (c.speed_mps < 0.0)
                    .then(|| self.blocking(&c, unseen))
                    .flatten()
            })
        };
        let want = cmd.speed_mps.abs();
        let same_way = self.granted_mps * cmd.speed_mps > 0.0;
        let braked = if same_way {
            (self.granted_mps.abs() - self.config.stop_decel_mps2 * dt_s).max(0.0)
        } else {
            0.0
        };
        let lowest = braked.max(CREEP_MPS.min(want));
        let mut speed = want;
        let block = loop {
            match block_at(speed) {
                None => break None,
                Some(p) if speed <= lowest => break Some(p),
                Some(_) => speed = (0.5 * speed).max(lowest),
            }
        };
        if let Some(p) = block {
            self.clear_for_s = 0.0;
            self.last_block = Some((p, cmd.speed_mps < 0.0));
        } else {
            self.clear_for_s += dt_s;
        }
        if self.clear_for_s < self.config.clear_s {
            self.granted_mps = 0.0;
            return Verdict {
                drive: DriveCommand {
                    speed_mps: 0.0,
                    steer_rad: cmd.steer_rad,
                },
                hazard: Some(Hazard::Obstacle),
            };
        }
        let drive = if speed < want { at(speed) } else { cmd };
        self.granted_mps = drive.speed_mps;
        Verdict {
            drive,
            hazard: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stucco_core::Pose2;

    fn estimate(sigma: f64) -> Estimate {
        Estimate {
            position_sigma_m: sigma,
            room_sigma_m: [0.01; 2],
            walls_seen: vec![0; 4],
            ..crate::model::known_room([5.0, 3.0], &[], Pose2::new(1.0, 1.0, 0.0))
        }
    }

    const FORWARD: DriveCommand = DriveCommand {
        speed_mps: 0.5,
        steer_rad: 0.0,
    };

    #[test]
    fn something_ahead_stops_the_robot_and_it_waits_for_a_clear_field() {
        let mut s = Supervisor::new(SafetyConfig::default(), VehicleSpec::default());
        let est = estimate(0.005);
        // Front at 0.75 m; even creeping the field reaches 0.75 + 0.15 and
        // a little.
        let person = [Point2::new(0.85, 0.1)];
        let v = s.check(FORWARD, &person, &[], &est, 0.02);
        assert_eq!(v.hazard, Some(Hazard::Obstacle));
        assert_eq!(v.drive.speed_mps, 0.0);
        // Gone: still stopped until the field has been clear for 0.5 s.
        let mut t = 0.0f64;
        while s.check(FORWARD, &[], &[], &est, 0.02).hazard.is_some() {
            t += 0.02;
            assert!(t < 1.0);
        }
        assert!((t - 0.48).abs() < 0.03, "{t}");
        // Beside the path, or beyond the field: no stop.
        assert!(!s.blocked(&FORWARD, &[Point2::new(1.0, 0.5)]));
        assert!(!s.blocked(&FORWARD, &[Point2::new(1.5, 0.0)]));
        // Standing still: nothing blocks.
        assert!(!s.blocked(&DriveCommand::STOP, &person));
    }

    /// Something ahead of a robot standing still, within the field of the
    /// speed asked for but beyond a slower one's: it drives at that
    /// slower speed. Something that comes as near while it drives fast
    /// stops it: it cannot brake to the slower speed at once.
    #[test]
    fn a_field_the_speed_asked_for_reaches_slows_the_robot_unless_it_is_too_late() {
        let mut s = Supervisor::new(SafetyConfig::default(), VehicleSpec::default());
        let est = estimate(0.005);
        // At 0.5 m/s the field reaches 0.75 + 0.156 + 0.15 + 0.05 = 1.106.
        let person = [Point2::new(1.0, 0.1)];
        assert!(s.blocked(&FORWARD, &person));
        let v = s.check(FORWARD, &person, &[], &est, 0.02);
        assert_eq!(v.hazard, None);
        assert!(v.drive.speed_mps > 0.0 && v.drive.speed_mps < 0.5, "{v:?}");
        assert!(!s.blocked(&v.drive, &person));
        assert_eq!(v.drive.steer_rad, FORWARD.steer_rad);
        // Driving at 0.5 m/s with the field clear; the person steps in.
        let mut fast = Supervisor::new(SafetyConfig::default(), VehicleSpec::default());
        assert_eq!(fast.check(FORWARD, &[], &[], &est, 0.02).drive, FORWARD);
        let v = fast.check(FORWARD, &person, &[], &est, 0.02);
        assert_eq!(v.hazard, Some(Hazard::Obstacle));
        assert_eq!(v.drive.speed_mps, 0.0);
    }

    #[test]
    fn a_pivot_is_blocked_by_what_its_front_corners_sweep_into() {
        let s = Supervisor::new(SafetyConfig::default(), VehicleSpec::default());
        let left = DriveCommand {
            speed_mps: 0.2,
            steer_rad: std::f64::consts::FRAC_PI_2,
        };
        // Turning left, the front-left corner (0.75, 0.31) swings toward
        // +y: a post just ahead of it on its circle is hit...
        let r = 0.75f64.hypot(0.31);
        let a = 0.31f64.atan2(0.75) + 0.15;
        assert!(s.blocked(&left, &[Point2::new(r * a.cos(), r * a.sin())]));
        // ... one just behind it (where the corner comes from) is not, nor
        // one beyond the circle.
        let b = -0.31f64.atan2(0.75) - 0.15;
        assert!(!s.blocked(&left, &[Point2::new(r * b.cos(), r * b.sin())]));
        assert!(!s.blocked(&left, &[Point2::new(0.0, 0.9)]));
        // Backing up, what is behind counts.
        let back = DriveCommand {
            speed_mps: -0.2,
            steer_rad: 0.0,
        };
        assert!(s.blocked(&back, &[Point2::new(-0.3, 0.0)]));
        assert!(!s.blocked(&back, &[Point2::new(1.0, 0.0)]));
    }

    /// Echoes of a wall 2 cm nearer the body's right side than the field's
    /// margin, beside the body (a station's standoff, the laser's
    /// scatter): the robot may drive or back straight along them, not turn
    /// into them, nor turn off them (its rear corner swings nearer); where
    /// the wall goes on ahead of the body, its echoes there hold a drive
    /// along it as the margin asks.
    #[test]
    fn echoes_beside_within_the_side_margin_hold_only_a_drive_nearer_to_them() {
        let s = Supervisor::new(SafetyConfig::default(), VehicleSpec::default());
        let y = -(0.31 + SafetyConfig::default().lateral_margin_m - 0.02);
        let wall = |from: f64, to: f64| -> Vec<Point2<f64>> {
            let n = ((to - from) / 0.05).round() as usize;
            (0..=n)
                .map(|k| Point2::new(from + 0.05 * k as f64, y))
                .collect()
        };
        let drive = |speed_mps: f64, steer_rad: f64| DriveCommand {
            speed_mps,
            steer_rad,
        };
        let beside = wall(-0.15, 0.75);
        assert!(!s.blocked(&drive(0.3, 0.0), &beside), "along it");
        assert!(!s.blocked(&drive(-0.3, 0.0), &beside), "backing along it");
        assert!(s.blocked(&drive(0.3, -0.3), &beside), "turning into it");
        assert!(s.blocked(&drive(0.3, 0.3), &beside), "turning off it");
        assert!(s.blocked(&drive(0.3, 0.0), &wall(-0.15, 2.0)), "on ahead");
    }

    #[test]
    fn a_lost_estimate_stops_and_comes_back_with_hysteresis() {
        let mut s = Supervisor::new(SafetyConfig::default(), VehicleSpec::default());
        assert_eq!(
            s.check(FORWARD, &[], &[], &estimate(0.06), 0.02).hazard,
            Some(Hazard::Lost)
        );
        assert!(!s.spray_allowed(&estimate(0.06)));
        // Under the limit but above 80% of it: still lost.
        assert_eq!(
            s.check(FORWARD, &[], &[], &estimate(0.045), 0.02).hazard,
            Some(Hazard::Lost)
        );
        assert_eq!(
            s.check(FORWARD, &[], &[], &estimate(0.03), 0.02).hazard,
            None
        );
        assert!(!s.spray_allowed(&estimate(0.03)));
        assert!(s.spray_allowed(&estimate(0.008)));
        let mut go_on = Supervisor::new(
            SafetyConfig {
                on_lost: LostPolicy::Continue,
                ..SafetyConfig::default()
            },
            VehicleSpec::default(),
        );
        let v = go_on.check(FORWARD, &[], &[], &estimate(0.2), 0.02);
        assert_eq!(v.drive, FORWARD);
        assert!(!go_on.spray_allowed(&estimate(0.2)));
    }
}
