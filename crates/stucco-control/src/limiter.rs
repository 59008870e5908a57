//! The vehicle's limits on a command: speed, steering angle, steering rate.

use stucco_core::{DriveCommand, VehicleSpec};

/// Holds commands within a vehicle's limits, step by step.
#[derive(Clone, Debug)]
pub struct Limiter {
    max_speed_mps: f64,
    max_steer_rad: f64,
    max_steer_rate_radps: f64,
    last_steer_rad: f64,
}

impl Limiter {
    /// Limits of `vehicle`, the steering straight.
    pub fn new(vehicle: &VehicleSpec) -> Self {
        Limiter {
            max_speed_mps: vehicle.max_speed_mps,
            max_steer_rad: vehicle.max_steer_rad,
            max_steer_rate_radps: vehicle.max_steer_rate_radps,
            last_steer_rad: 0.0,
        }
    }

    /// `cmd` within the limits, `dt_s` after the previous command.
    pub fn limit(&mut self, cmd: DriveCommand, dt_s: f64) -> DriveCommand {
        let goal = cmd.steer_rad.clamp(-self.max_steer_rad, self.max_steer_rad);
        let step = self.max_steer_rate_radps * dt_s.max(0.0);
        let steer = self.last_steer_rad + (goal - self.last_steer_rad).clamp(-step, step);
        self.last_steer_rad = steer;
        DriveCommand {
            speed_mps: cmd.speed_mps.clamp(-self.max_speed_mps, self.max_speed_mps),
            steer_rad: steer,
        }
    }
}
