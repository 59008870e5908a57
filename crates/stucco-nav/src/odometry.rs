//! Dead reckoning of the tricycle from its rear-wheel encoders (paper A
//! §3.2): the motion between two samples is an arc; the displacement is
//! kept in the frame {k} of the robot at the last scan, with its
//! covariance propagated through each arc (eq. 5–7) and a process noise
//! per step that grows with the distance each wheel rolled and with the
//! turn.

use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector3};
use serde::{Deserialize, Serialize};
use stucco_core::{EncoderSample, Pose2, Stamp, Twist2, VehicleSpec};

/// The encoders and how much to trust them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OdometryConfig {
    /// Effective radius of the left and right encoder wheels, m.
    pub wheel_radius_m: [f64; 2],
    /// Effective distance between the encoder wheels, m.
    pub track_m: f64,
    /// Encoder ticks per wheel turn.
    pub ticks_per_rev: u32,
    /// Variance of a wheel's travel per metre it rolled, m²/m.
    pub travel_variance_per_m: f64,
    /// Variance of the heading per radian turned, rad²/rad (slip in turns).
    pub turn_variance_per_rad: f64,
    /// Variance of the sideways creep per metre travelled, m²/m.
    pub lateral_variance_per_m: f64,
}

impl OdometryConfig {
    /// The nominal odometry of `vehicle`, with the noise of a robot on a
    /// hard floor: 1 cm per √m along each wheel, 1° per √rad of turn,
    /// 5 mm per √m sideways.
    pub fn for_vehicle(vehicle: &VehicleSpec) -> Self {
        OdometryConfig {
            wheel_radius_m: [vehicle.rear_wheel_radius_m; 2],
            track_m: vehicle.track_m,
            ticks_per_rev: vehicle.ticks_per_rev,
            travel_variance_per_m: 1e-4,
            turn_variance_per_rad: 1f64.to_radians().powi(2),
            lateral_variance_per_m: 2.5e-5,
        }
    }
}

impl Default for OdometryConfig {
    fn default() -> Self {
        OdometryConfig::for_vehicle(&VehicleSpec::default())
    }
}

/// The robot's displacement since a reference time, in the frame of its
/// pose then, and the covariance of that displacement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Displacement {
    /// Since when.
    pub since: Stamp,
    /// Until when.
    pub until: Stamp,
    /// The displacement `ᵏP`: the pose now in the frame {k} of then.
    pub pose: Pose2,
    /// Its covariance `Q`, over `(x, y, θ)`.
    pub covariance: Matrix3<f64>,
}

/// A covariance over `(x, y, θ)` expressed in a frame turned by `angle`:
/// its position block rotated, its heading untouched.
pub(crate) fn turned_covariance(covariance: &Matrix3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let rot = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    rot * covariance * rot.transpose()
}

impl Displacement {
    /// No motion at `at`.
    pub fn zero(at: Stamp) -> Self {
        Displacement {
            since: at,
            until: at,
            pose: Pose2::IDENTITY,
            covariance: Matrix3::zeros(),
        }
    }

    /// Continues this displacement by the arc of a step that rolled the
    /// wheels `(left, right)` metres, with the process noise of `cfg`.
    pub fn extend(&mut self, wheels_m: [f64; 2], until: Stamp, cfg: &OdometryConfig) {
        let [dl, dr] = wheels_m;
        let d = 0.5 * (dl + dr);
        let dth = (dr - dl) / cfg.track_m;
        // The arc in the frame of the step's start: exact for any turn.
        let (a, b) = if dth.abs() < 1e-9 {
            (1.0 - dth * dth / 6.0, dth / 2.0)
        } else {
            (dth.sin() / dth, (1.0 - dth.cos()) / dth)
        };
        let step = Pose2::new(a * d, b * d, dth);
        // Linearised about the chord at half the turn (eq. 7):
        // position += d·(cos φ, sin φ), θ += dθ, φ = θ + dθ/2.
        let th = self.pose.theta;
        let phi = th + 0.5 * dth;
        let (s, c) = phi.sin_cos();
        let f = Matrix3::new(
            1.0,
            0.0,
            -(step.x * th.sin() + step.y * th.cos()),
            0.0,
            1.0,
            step.x * th.cos() - step.y * th.sin(),
            0.0,
            0.0,
            1.0,
        );
        // ∂(x, y, θ)/∂(d, dθ), then (d, dθ) from the wheels.
        let g = Matrix3x2::new(c, -0.5 * d * s, s, 0.5 * d * c, 0.0, 1.0);
        let w = Matrix2::new(0.5, 0.5, -1.0 / cfg.track_m, 1.0 / cfg.track_m);
        let j = g * w;
        let u = Matrix2::new(
            cfg.travel_variance_per_m * dl.abs(),
            0.0,
            0.0,
            cfg.travel_variance_per_m * dr.abs(),
        );
        // Turning slips the heading; travelling creeps sideways.
        let side = Vector3::new(-s, c, 0.0);
        let extra = Matrix3::from_diagonal(&Vector3::new(
            0.0,
            0.0,
            cfg.turn_variance_per_rad * dth.abs(),
        )) + side * side.transpose() * (cfg.lateral_variance_per_m * d.abs());
        let q = f * self.covariance * f.transpose() + j * u * j.transpose() + extra;
        self.covariance = 0.5 * (q + q.transpose());
        self.pose = self.pose * step;
        self.until = until;
    }
}

/// The robot's velocity over the pair of encoder samples that spans `t`
/// (or the nearest pair), for undoing a scan's motion distortion.
pub fn twist_at(samples: &[EncoderSample], t: Stamp, cfg: &OdometryConfig) -> Twist2 {
    if samples.len() < 2 {
        return Twist2::default();
    }
    let i = samples
        .partition_point(|s| s.stamp <= t)
        .clamp(1, samples.len() - 1);
    let (a, b) = (samples[i - 1], samples[i]);
    let dt = b.stamp.seconds_since(a.stamp).max(1e-9);
    let per_tick =
        |w: usize| std::f64::consts::TAU * cfg.wheel_radius_m[w] / f64::from(cfg.ticks_per_rev);
    let dl = (b.left_ticks - a.left_ticks) as f64 * per_tick(0);
    let dr = (b.right_ticks - a.right_ticks) as f64 * per_tick(1);
    Twist2::new((dl + dr) / 2.0 / dt, 0.0, (dr - dl) / cfg.track_m / dt)
}

/// The wheels' travel (left, right) from the first of `samples` to `t`,
/// m, at the nominal radii of `cfg`, interpolated within the sample period
/// that spans `t` (the speed taken as constant within it).
pub fn wheel_travel_at(samples: &[EncoderSample], t: Stamp, cfg: &OdometryConfig) -> [f64; 2] {
    let Some(first) = samples.first() else {
        return [0.0; 2];
    };
    let per_tick =
        |w: usize| std::f64::consts::TAU * cfg.wheel_radius_m[w] / f64::from(cfg.ticks_per_rev);
    let travel = |s: &EncoderSample| {
        [
            (s.left_ticks - first.left_ticks) as f64 * per_tick(0),
            (s.right_ticks - first.right_ticks) as f64 * per_tick(1),
        ]
    };
    let k = samples.partition_point(|s| s.stamp <= t);
    match (k.checked_sub(1).map(|i| &samples[i]), samples.get(k)) {
        (Some(a), Some(b)) => {
            let f = t.seconds_since(a.stamp) / b.stamp.seconds_since(a.stamp).max(1e-12);
            let (wa, wb) = (travel(a), travel(b));
            [wa[0] + f * (wb[0] - wa[0]), wa[1] + f * (wb[1] - wa[1])]
        }
        (Some(a), None) => travel(a),
        _ => [0.0; 2],
    }
}

/// The wheels' travel over each encoder period from `since` to `until`,
/// the first and last periods cut at those instants, with the instant each
/// ends: the arcs the motion between two scans' stamps is made of.
pub fn wheel_steps(
    samples: &[EncoderSample],
    since: Stamp,
    until: Stamp,
    cfg: &OdometryConfig,
) -> Vec<([f64; 2], Stamp)> {
    let from = samples.partition_point(|s| s.stamp <= since);
    let to = samples.partition_point(|s| s.stamp < until);
    let mut out = Vec::with_capacity(to.saturating_sub(from) + 1);
    let (mut at, mut w0) = (since, wheel_travel_at(samples, since, cfg));
    for t in samples[from..to.max(from)]
        .iter()
        .map(|s| s.stamp)
        .chain([until])
    {
        if t <= at {
            continue;
        }
        let w1 = wheel_travel_at(samples, t, cfg);
        out.push(([w1[0] - w0[0], w1[1] - w0[1]], t));
        (w0, at) = (w1, t);
    }
    out
}

/// The velocity, in its own frame, of a sensor mounted at `mount` on a
/// robot moving with `robot`.
pub fn sensor_twist(robot: &Twist2, mount: &Pose2) -> Twist2 {
    let w = robot.omega_radps;
    let (vx, vy) = (robot.vx_mps - w * mount.y, robot.vy_mps + w * mount.x);
    let (s, c) = mount.theta.sin_cos();
    Twist2::new(c * vx + s * vy, -s * vx + c * vy, w)
}

/// Dead reckoning from encoder samples.
#[derive(Clone, Debug)]
pub struct DeadReckoning {
    config: OdometryConfig,
    last: Option<EncoderSample>,
    since_scan: Displacement,
    total: Displacement,
}

impl DeadReckoning {
    /// Dead reckoning with `config`, starting at the first sample given.
    pub fn new(config: OdometryConfig) -> Self {
        DeadReckoning {
            config,
            last: None,
            since_scan: Displacement::zero(Stamp::ZERO),
            total: Displacement::zero(Stamp::ZERO),
        }
    }

    /// Its settings.
    pub fn config(&self) -> &OdometryConfig {
        &self.config
    }

    /// Takes one encoder sample: the wheels' travel since the previous one
    /// extends both displacements. The first sample only sets the counters'
    /// origin.
    pub fn update(&mut self, sample: &EncoderSample) {
        let Some(prev) = self.last.replace(*sample) else {
            self.since_scan = Displacement::zero(sample.stamp);
            self.total = Displacement::zero(sample.stamp);
            return;
        };
        let per_tick = |w: usize| {
            std::f64::consts::TAU * self.config.wheel_radius_m[w]
                / f64::from(self.config.ticks_per_rev)
        };
        let wheels = [
            (sample.left_ticks - prev.left_ticks) as f64 * per_tick(0),
            (sample.right_ticks - prev.right_ticks) as f64 * per_tick(1),
        ];
        self.since_scan.extend(wheels, sample.stamp, &self.config);
        self.total.extend(wheels, sample.stamp, &self.config);
    }

    /// The displacement since the last [`DeadReckoning::restart`] (the
    /// last scan): `ᵏP(t)` and `Q(t)`.
    pub fn since_scan(&self) -> &Displacement {
        &self.since_scan
    }

    /// The displacement since the first sample.
    pub fn total(&self) -> &Displacement {
        &self.total
    }

    /// Hands over the displacement since the last restart and starts a new
    /// frame {k} at the latest sample.
    pub fn restart(&mut self) -> Displacement {
        let at = self.since_scan.until;
        std::mem::replace(&mut self.since_scan, Displacement::zero(at))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wheel_travel_is_interpolated_and_cut_at_the_instants_asked() {
        let cfg = OdometryConfig {
            wheel_radius_m: [
                1000.0 / std::f64::consts::TAU,
                2000.0 / std::f64::consts::TAU,
            ],
            ticks_per_rev: 1_000_000,
            ..OdometryConfig::default()
        }; // 1 mm and 2 mm a tick
        let s = |t: f64, l: i64, r: i64| EncoderSample {
            stamp: Stamp::from_secs_f64(t),
            left_ticks: l,
            right_ticks: r,
        };
        let samples = [s(1.0, 100, 100), s(1.02, 120, 140), s(1.04, 140, 180)];
        let w = wheel_travel_at(&samples, Stamp::from_secs_f64(1.015), &cfg);
        assert!(
            (w[0] - 0.015).abs() < 1e-9 && (w[1] - 0.06).abs() < 1e-9,
            "{w:?}"
        );
        let end = wheel_travel_at(&samples, Stamp::from_secs_f64(3.0), &cfg);
        assert!(
            (end[0] - 0.04).abs() < 1e-9 && (end[1] - 0.16).abs() < 1e-9,
            "{end:?}"
        );
        // From 1.01 to 1.03: half of each period, cut at 1.02.
        let steps = wheel_steps(
            &samples,
            Stamp::from_secs_f64(1.01),
            Stamp::from_secs_f64(1.03),
            &cfg,
        );
        assert_eq!(steps.len(), 2);
        assert!((steps[0].0[0] - 0.01).abs() < 1e-9 && (steps[1].0[1] - 0.04).abs() < 1e-9);
        assert_eq!(steps[0].1, Stamp::from_secs_f64(1.02));
        assert_eq!(steps[1].1, Stamp::from_secs_f64(1.03));
    }

    fn sample(t_s: f64, l: i64, r: i64) -> EncoderSample {
        EncoderSample {
            stamp: Stamp::from_secs_f64(t_s),
            left_ticks: l,
            right_ticks: r,
        }
    }

    #[test]
    fn equal_ticks_go_straight_and_unequal_ones_turn_about_the_axle() {
        let cfg = OdometryConfig::default();
        let per_m = f64::from(cfg.ticks_per_rev) / (std::f64::consts::TAU * cfg.wheel_radius_m[0]);
        let mut dr = DeadReckoning::new(cfg.clone());
        dr.update(&sample(0.0, 0, 0));
        dr.update(&sample(1.0, per_m as i64, per_m as i64));
        let p = dr.total().pose;
        assert!((p.x - 1.0).abs() < 1e-3 && p.y.abs() < 1e-9 && p.theta.abs() < 1e-9);
        // A quarter turn on the spot: each wheel rolls a quarter of the
        // track's half-circle, in opposite directions.
        let q = (std::f64::consts::FRAC_PI_4 * cfg.track_m * per_m).round() as i64;
        let start = per_m as i64;
        dr.update(&sample(2.0, start - q, start + q));
        let p = dr.total().pose;
        assert!(
            (p.theta - std::f64::consts::FRAC_PI_2).abs() < 2e-3,
            "{p:?}"
        );
        assert!((p.x - 1.0).abs() < 1e-3 && p.y.abs() < 1e-3, "{p:?}");
    }

    #[test]
    fn covariance_grows_with_travel_and_stays_symmetric_positive() {
        let mut dr = DeadReckoning::new(OdometryConfig::default());
        dr.update(&sample(0.0, 0, 0));
        let mut last = 0.0;
        for k in 1..200 {
            dr.update(&sample(k as f64 * 0.02, k * 30, k * 33));
            let q = dr.total().covariance;
            assert!((q - q.transpose()).norm() < 1e-15);
            let eig = q.symmetric_eigenvalues();
            assert!(eig.iter().all(|&e| e >= -1e-15), "{eig}");
            let tr = q.trace();
            assert!(tr > last);
            last = tr;
        }
    }

    #[test]
    fn a_sensor_ahead_of_the_axle_moves_sideways_when_the_robot_turns() {
        let robot = Twist2::new(0.5, 0.0, 1.0);
        let t = sensor_twist(&robot, &Pose2::new(0.4, 0.0, 0.0));
        assert!((t.vx_mps - 0.5).abs() < 1e-12 && (t.vy_mps - 0.4).abs() < 1e-12);
        // Mounted looking left, the forward motion is to its right.
        let t = sensor_twist(&robot, &Pose2::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
        assert!(t.vx_mps.abs() < 1e-12 && (t.vy_mps + 0.5).abs() < 1e-12);
        let cfg = OdometryConfig::default();
        let samples = [sample(0.0, 0, 0), sample(0.02, 100, 120)];
        let tw = twist_at(&samples, Stamp::from_secs_f64(0.01), &cfg);
        assert!(tw.vx_mps > 0.0 && tw.omega_radps > 0.0);
    }

    #[test]
    fn restarting_composes_back_to_the_total() {
        let mut dr = DeadReckoning::new(OdometryConfig::default());
        dr.update(&sample(0.0, 0, 0));
        for k in 1..50 {
            dr.update(&sample(k as f64 * 0.02, k * 40, k * 37));
        }
        let first = dr.restart();
        for k in 50..120 {
            dr.update(&sample(k as f64 * 0.02, k * 40, k * 45));
        }
        let second = dr.since_scan().pose;
        let composed = first.pose * second;
        let total = dr.total().pose;
        assert!((composed.x - total.x).abs() < 1e-9 && (composed.y - total.y).abs() < 1e-9);
        assert!((composed.theta - total.theta).abs() < 1e-9);
        assert!(second.theta != 0.0);
    }
}
