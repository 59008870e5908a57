//! The tricycle's motion: actuator limits, drive slip, lateral skid when
//! the floor cannot hold the turn, and the rear-wheel encoders.

use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use stucco_core::{DriveCommand, EncoderSample, Pose2, Stamp, Twist2, VehicleSpec};

/// Standard gravity, m/s².
const G_MPS2: f64 = 9.81;

/// How the wheels meet the floor and how the encoders err.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DynamicsConfig {
    /// Friction coefficient of the tyres on the floor: the robot skids
    /// sideways when the turn asks for more lateral acceleration than
    /// `friction * g`.
    pub friction: f64,
    /// Steady slip of the driven front wheel: the ground speed is this much
    /// short of the wheel's (0.02 = 2%).
    pub drive_slip: f64,
    /// Random sideways creep of the rear axle, m/s per m/s of speed (σ).
    pub creep_sigma: f64,
    /// Relative error of the left and right encoder wheels' radii: the true
    /// radius is the nominal one times `1 + error`.
    pub wheel_radius_error: [f64; 2],
    /// Encoder slip bursts (a wheel sliding on dust) per second, on average.
    pub slip_burst_rate_hz: f64,
    /// Length of a slip burst, s.
    pub slip_burst_s: f64,
    /// Share of the wheel's travel lost during a burst.
    pub slip_burst_loss: f64,
}

impl Default for DynamicsConfig {
    fn default() -> Self {
        DynamicsConfig {
            friction: 0.6,
            drive_slip: 0.01,
            creep_sigma: 0.002,
            wheel_radius_error: [0.002, -0.0015],
            slip_burst_rate_hz: 0.0,
            slip_burst_s: 0.3,
            slip_burst_loss: 0.2,
        }
    }
}

/// Actuators failing during one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ActuatorFaults {
    /// The drive motor gives no traction.
    pub stalled: bool,
    /// The steering holds its angle.
    pub steering_stuck: bool,
}

/// The true state of the drive.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DriveState {
    /// Pose of the rear axle's middle, world frame.
    pub pose: Pose2,
    /// Body-frame velocity of the rear axle's middle.
    pub twist: Twist2,
    /// Front wheel's speed, m/s.
    pub wheel_speed_mps: f64,
    /// Steering angle, rad.
    pub steer_rad: f64,
}

/// The drive's dynamics and its encoders.
#[derive(Clone, Debug)]
pub struct Drive {
    spec: VehicleSpec,
    cfg: DynamicsConfig,
    state: DriveState,
    /// Rotation of each rear wheel since start, turns.
    turns: [f64; 2],
    /// Seconds left of the slip burst of each wheel.
    burst_left_s: [f64; 2],
}

impl Drive {
    /// A drive at rest at `pose`.
    pub fn new(spec: VehicleSpec, cfg: DynamicsConfig, pose: Pose2) -> Self {
        Drive {
            spec,
            cfg,
            state: DriveState {
                pose,
                ..DriveState::default()
            },
            turns: [0.0; 2],
            burst_left_s: [0.0; 2],
        }
    }

    /// The true state.
    pub fn state(&self) -> &DriveState {
        &self.state
    }

    /// The pose the drive reaches after `dt_s` of following `cmd` within
    /// its limits, with its actuators failing as `faults` says, and the
    /// twist it moves with; nothing is committed.
    pub fn propose(
        &self,
        cmd: &DriveCommand,
        dt_s: f64,
        faults: ActuatorFaults,
        rng: &mut impl Rng,
    ) -> DriveState {
        let s = &self.spec;
        let cmd = DriveCommand {
            speed_mps: if faults.stalled { 0.0 } else { cmd.speed_mps },
            steer_rad: if faults.steering_stuck {
                self.state.steer_rad
            } else {
                cmd.steer_rad
            },
        };
        let steer_goal = cmd.steer_rad.clamp(-s.max_steer_rad, s.max_steer_rad);
        let max_turn = s.max_steer_rate_radps * dt_s;
        let steer =
            self.state.steer_rad + (steer_goal - self.state.steer_rad).clamp(-max_turn, max_turn);
        let speed_goal = cmd.speed_mps.clamp(-s.max_speed_mps, s.max_speed_mps);
        let max_dv = s.max_accel_mps2 * dt_s;
        let wheel = self.state.wheel_speed_mps
            + (speed_goal - self.state.wheel_speed_mps).clamp(-max_dv, max_dv);
        let ground = wheel * (1.0 - self.cfg.drive_slip);
        // The front wheel rolls along its heading; the rear axle follows.
        let v = ground * steer.cos();
        let mut omega = ground * steer.sin() / s.wheelbase_m;
        // The floor holds at most friction·g sideways: past it the robot
        // turns less and its rear slides out of the turn.
        let grip = self.cfg.friction * G_MPS2;
        let mut vy = 0.0;
        let lateral = v * omega;
        if lateral.abs() > grip && v.abs() > 1e-9 {
            let held = grip * lateral.signum();
            omega = held / v;
            vy = -(lateral - held) * SKID_RESPONSE_S;
        }
        if self.cfg.creep_sigma > 0.0 && v != 0.0 {
            let creep = Normal::new(0.0, self.cfg.creep_sigma * v.abs()).ok();
            vy += creep.map_or(0.0, |n| n.sample(rng));
        }
        let twist = Twist2::new(v, vy, omega);
        DriveState {
            pose: self.state.pose * twist.displacement(dt_s),
            twist,
            wheel_speed_mps: wheel,
            steer_rad: steer,
        }
    }

    /// Takes `next` as the new state and turns the encoder wheels by the
    /// rear wheels' true travel over `dt_s` (the sideways skid turns none).
    pub fn commit(&mut self, next: DriveState, dt_s: f64, rng: &mut impl Rng) {
        let half = self.spec.track_m / 2.0;
        let travel = [
            (next.twist.vx_mps - next.twist.omega_radps * half) * dt_s,
            (next.twist.vx_mps + next.twist.omega_radps * half) * dt_s,
        ];
        for (w, t) in travel.iter().enumerate() {
            if self.burst_left_s[w] <= 0.0
                && self.cfg.slip_burst_rate_hz > 0.0
                && rng.random::<f64>() < self.cfg.slip_burst_rate_hz * dt_s
            {
                self.burst_left_s[w] = self.cfg.slip_burst_s;
            }
            let loss = if self.burst_left_s[w] > 0.0 {
                self.burst_left_s[w] -= dt_s;
                self.cfg.slip_burst_loss
            } else {
                0.0
            };
            let radius = self.spec.rear_wheel_radius_m * (1.0 + self.cfg.wheel_radius_error[w]);
            self.turns[w] += t * (1.0 - loss) / (std::f64::consts::TAU * radius);
        }
        self.state = next;
    }

    /// Stops the drive where it is (a collision): wheel speed and twist to
    /// zero.
    pub fn halt(&mut self) {
        self.state.wheel_speed_mps = 0.0;
        self.state.twist = Twist2::default();
    }

    /// The encoder counters now, read at `stamp`.
    pub fn encoders(&self, stamp: Stamp) -> EncoderSample {
        let ticks = |w: usize| (self.turns[w] * f64::from(self.spec.ticks_per_rev)).floor() as i64;
        EncoderSample {
            stamp,
            left_ticks: ticks(0),
            right_ticks: ticks(1),
        }
    }
}

/// How fast a skid builds sideways velocity from the excess lateral
/// acceleration, s.
const SKID_RESPONSE_S: f64 = 0.1;

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn exact() -> DynamicsConfig {
        DynamicsConfig {
            drive_slip: 0.0,
            creep_sigma: 0.0,
            wheel_radius_error: [0.0, 0.0],
            ..DynamicsConfig::default()
        }
    }

    fn run(drive: &mut Drive, cmd: DriveCommand, seconds: f64) {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..(seconds * 100.0).round() as usize {
            let next = drive.propose(&cmd, 0.01, ActuatorFaults::default(), &mut rng);
            drive.commit(next, 0.01, &mut rng);
        }
    }

    #[test]
    fn speed_and_steering_obey_their_limits() {
        let mut d = Drive::new(VehicleSpec::default(), exact(), Pose2::IDENTITY);
        let cmd = DriveCommand {
            speed_mps: 5.0,
            steer_rad: 3.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let next = d.propose(&cmd, 0.1, ActuatorFaults::default(), &mut rng);
        assert!((next.wheel_speed_mps - 0.08).abs() < 1e-12); // 0.8 m/s² · 0.1 s
        assert!((next.steer_rad - 0.2).abs() < 1e-12); // 2 rad/s · 0.1 s
        run(&mut d, cmd, 5.0);
        assert!((d.state().wheel_speed_mps - 0.8).abs() < 1e-12);
        assert!((d.state().steer_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn a_slow_turn_follows_tricycle_kinematics_and_the_encoders_see_it() {
        let spec = VehicleSpec::default();
        let mut d = Drive::new(spec.clone(), exact(), Pose2::IDENTITY);
        let steer = 0.3f64;
        // Settle the steering, then drive a full second at 0.2 m/s.
        run(
            &mut d,
            DriveCommand {
                speed_mps: 0.0,
                steer_rad: steer,
            },
            1.0,
        );
        run(
            &mut d,
            DriveCommand {
                speed_mps: 0.2,
                steer_rad: steer,
            },
            2.0,
        );
        let t = d.state().twist;
        assert!((t.vx_mps - 0.2 * steer.cos()).abs() < 1e-9);
        assert!((t.omega_radps - 0.2 * steer.sin() / spec.wheelbase_m).abs() < 1e-9);
        assert_eq!(t.vy_mps, 0.0);
        let e = d.encoders(Stamp::ZERO);
        assert!(e.right_ticks > e.left_ticks && e.left_ticks > 0);
    }

    #[test]
    fn too_sharp_a_turn_at_speed_skids() {
        let cfg = DynamicsConfig {
            friction: 0.02,
            ..exact()
        };
        let mut d = Drive::new(VehicleSpec::default(), cfg, Pose2::IDENTITY);
        run(
            &mut d,
            DriveCommand {
                speed_mps: 0.8,
                steer_rad: 1.0,
            },
            3.0,
        );
        let t = d.state().twist;
        assert!((t.vx_mps * t.omega_radps).abs() <= 0.02 * G_MPS2 + 1e-9);
        assert!(t.vy_mps < 0.0, "the rear slides out of a left turn: {t:?}");
    }
}
