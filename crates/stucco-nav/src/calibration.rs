//! Online calibration of the laser's mounting and the odometry (the idea of
//! paper C: the encoders' relative motion is the reference the sensor is
//! calibrated against, during normal driving).
//!
//! The state is `c = (m_x, m_y, m_θ, k_r, k_b)`: the laser's pose on the
//! robot, the factor on the encoder wheels' nominal radius (odometry
//! scale) and the factor on their nominal track (effective wheelbase).
//! Between two scans, each wall seen in both constrains `c`: the wall of
//! the first scan, moved by the laser's motion — the robot's motion from
//! the encoders under `k_r`, `k_b`, seen through the mount, `M⁻¹·T·M` —
//! must be the wall of the second. Driving straight fixes `m_θ` (the
//! direction walls move) and `k_r` (how far against the laser's absolute
//! ranges); turning on the spot fixes `m_x, m_y` (the laser swings round
//! the axle) and `k_b` (how far the walls turn against the wheels'
//! difference).
//!
//! The walls come from the extractor as they are for navigation; no map is
//! needed. A wall of one scan serves in two pairs, a correlation the filter
//! ignores (it is slightly overconfident; the tests check its errors
//! against its σ).

use crate::odometry::{Displacement, OdometryConfig};
use crate::wall::Wall;
use nalgebra::{DMatrix, DVector, Matrix2, SMatrix, SVector, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{Pose2, Stamp, wrap_angle};

/// The calibrated quantities.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The laser's pose on the robot.
    pub laser_mount: Pose2,
    /// True wheel radius over nominal.
    pub wheel_scale: f64,
    /// True (effective) track over nominal.
    pub track_scale: f64,
}

impl Calibration {
    /// The nominal: `mount` as designed, the wheels as specified.
    pub fn nominal(mount: Pose2) -> Self {
        Calibration {
            laser_mount: mount,
            wheel_scale: 1.0,
            track_scale: 1.0,
        }
    }

    /// How far this is from `truth`: mount x, y (m) and θ (rad), the
    /// wheel and track scales as fractions of the true ones.
    pub fn error_to(&self, truth: &Calibration) -> [f64; 5] {
        [
            self.laser_mount.x - truth.laser_mount.x,
            self.laser_mount.y - truth.laser_mount.y,
            wrap_angle(self.laser_mount.theta - truth.laser_mount.theta),
            self.wheel_scale / truth.wheel_scale - 1.0,
            self.track_scale / truth.track_scale - 1.0,
        ]
    }

    fn state(&self) -> SVector<f64, 5> {
        SVector::<f64, 5>::from([
            self.laser_mount.x,
            self.laser_mount.y,
            self.laser_mount.theta,
            self.wheel_scale,
            self.track_scale,
        ])
    }

    fn of(c: &SVector<f64, 5>) -> Self {
        Calibration {
            laser_mount: Pose2::new(c[0], c[1], c[2]),
            wheel_scale: c[3],
            track_scale: c[4],
        }
    }
}

/// How the calibrator starts and what it trusts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CalibratorConfig {
    /// The odometry as specified (its radii and track are the nominal the
    /// scales multiply; its noise is the encoders' noise).
    pub odometry: OdometryConfig,
    /// σ of the first guess: mount x, y (m), θ (rad), wheel and track
    /// scale (fractions).
    pub initial_sigma: [f64; 5],
    /// Floor of a wall's σ of distance, m, and of direction, rad.
    pub min_sigma_d_m: f64,
    /// Floor of a wall's σ of direction, rad.
    pub min_sigma_gamma_rad: f64,
    /// χ² (2 degrees of freedom) within which a wall of the second scan is
    /// the wall of the first.
    pub gate_chi2: f64,
    /// Fewest measurements a wall must rest on to be used.
    pub min_points: usize,
    /// σ added to a wall's predicted distance (m) and direction (rad) when
    /// pairing it with the next scan's walls, beyond the walls' noise and
    /// the calibration's own uncertainty (which the gate carries): the
    /// robot's true motion strays from the encoders' by more than their
    /// noise model says (creep, slip).
    pub association_slack: [f64; 2],
}

impl Default for CalibratorConfig {
    fn default() -> Self {
        CalibratorConfig {
            odometry: OdometryConfig::default(),
            initial_sigma: [0.05, 0.05, 2f64.to_radians(), 0.05, 0.05],
            min_sigma_d_m: 0.002,
            min_sigma_gamma_rad: 0.05f64.to_radians(),
            gate_chi2: 9.21,
            min_points: 20,
            association_slack: [0.005, 0.2f64.to_radians()],
        }
    }
}

/// The calibrating filter.
#[derive(Clone, Debug)]
pub struct OnlineCalibrator {
    config: CalibratorConfig,
    x: SVector<f64, 5>,
    p: SMatrix<f64, 5, 5>,
    /// The last scan's walls.
    last: Vec<Wall>,
    /// The wheels' nominal travel since it, step by step, m.
    steps: Vec<[f64; 2]>,
    /// Wall pairs used so far.
    used: usize,
}

/// One wall seen in two scans.
struct Pair<'a> {
    before: &'a Wall,
    after: &'a Wall,
}

impl OnlineCalibrator {
    /// Starts from `guess`.
    pub fn new(config: CalibratorConfig, guess: Calibration) -> Self {
        let s = SVector::<f64, 5>::from(config.initial_sigma);
        OnlineCalibrator {
            p: SMatrix::from_diagonal(&s.component_mul(&s)),
            x: guess.state(),
            config,
            last: Vec::new(),
            steps: Vec::new(),
            used: 0,
        }
    }

    /// The estimate.
    pub fn estimate(&self) -> Calibration {
        Calibration::of(&self.x)
    }

    /// σ of each calibrated quantity: mount x, y (m), θ (rad), wheel and
    /// track scale.
    pub fn sigma(&self) -> [f64; 5] {
        std::array::from_fn(|i| self.p[(i, i)].max(0.0).sqrt())
    }

    /// σ of the estimate's error against `truth` as
    /// [`Calibration::error_to`] measures it.
    pub fn error_sigma(&self, truth: &Calibration) -> [f64; 5] {
        let s = self.sigma();
        [
            s[0],
            s[1],
            s[2],
            s[3] / truth.wheel_scale,
            s[4] / truth.track_scale,
        ]
    }

    /// Wall pairs used so far.
    pub fn pairs_used(&self) -> usize {
        self.used
    }

    /// The wheels rolled `wheels_m` (left, right; at their nominal radius)
    /// since the last call.
    pub fn wheels(&mut self, wheels_m: [f64; 2]) {
        self.steps.push(wheels_m);
    }

    /// A scan's walls (in the laser's frame): each one also seen in the
    /// previous scan corrects the calibration. Returns how many did.
    pub fn scan(&mut self, walls: &[Wall]) -> usize {
        let now: Vec<Wall> = walls
            .iter()
            .filter(|w| w.points >= self.config.min_points)
            .cloned()
            .collect();
        let before = std::mem::take(&mut self.last);
        let steps = std::mem::take(&mut self.steps);
        // The motion under the calibration as it stands, for both.
        let (t, q) = self.motion(&self.x, &steps);
        let pairs = self.associate(&before, &now, &steps, &t, &q);
        let n = pairs.len();
        self.correct(&pairs, &steps, &t, &q);
        self.used += n;
        self.last = now;
        n
    }

    /// The robot's motion over `steps` under calibration `c`, and its
    /// covariance from the encoders' noise.
    fn motion(&self, c: &SVector<f64, 5>, steps: &[[f64; 2]]) -> (Pose2, SMatrix<f64, 3, 3>) {
        let cfg = OdometryConfig {
            track_m: self.config.odometry.track_m * c[4],
            ..self.config.odometry.clone()
        };
        let mut d = Displacement::zero(Stamp::ZERO);
        for s in steps {
            d.extend([s[0] * c[3], s[1] * c[3]], Stamp::ZERO, &cfg);
        }
        (d.pose, d.covariance)
    }

    /// Where wall `z` of the first scan lies in the laser's frame after
    /// the robot moved by `t`, under mount `m`.
    fn moved(z: &Wall, m: &Pose2, t: &Pose2) -> Vector2<f64> {
        let l = m.inverse() * *t * *m;
        let (s, c) = z.gamma_rad.sin_cos();
        Vector2::new(z.d_m - c * l.x - s * l.y, wrap_angle(z.gamma_rad - l.theta))
    }

    fn noise(&self, z: &Wall) -> Matrix2<f64> {
        let mut r = z.covariance;
        r[(0, 0)] = r[(0, 0)].max(self.config.min_sigma_d_m.powi(2));
        r[(1, 1)] = r[(1, 1)].max(self.config.min_sigma_gamma_rad.powi(2));
        r
    }

    /// Each wall of the first scan with the one wall of the second within
    /// the gate, and that wall with no other of the first scan (none when
    /// two are: a radiator's face 4 cm before a wall is not that wall).
    /// The gate is the walls' noise, the calibration's own uncertainty
    /// carried into the prediction (wide while the guess is poor, narrow
    /// once it is known) and a floor for what neither knows.
    fn associate<'a>(
        &self,
        before: &'a [Wall],
        after: &'a [Wall],
        steps: &[[f64; 2]],
        t: &Pose2,
        q: &SMatrix<f64, 3, 3>,
    ) -> Vec<Pair<'a>> {
        let m = Pose2::new(self.x[0], self.x[1], self.x[2]);
        let l = m.inverse() * *t * m;
        let [slack_d, slack_g] = self.config.association_slack;
        let slack = Matrix2::from_diagonal(&Vector2::new(slack_d.powi(2), slack_g.powi(2)));
        // The motion and mount under each state nudged both ways, for the
        // predictions' Jacobians.
        let step = [1e-4, 1e-4, 1e-5, 1e-5, 1e-5];
        let nudged: Vec<[(Pose2, Pose2); 2]> = step
            .iter()
            .enumerate()
            .map(|(j, e)| {
                [1.0, -1.0].map(|sign| {
                    let mut c = self.x;
                    c[j] += sign * e;
                    (Pose2::new(c[0], c[1], c[2]), self.motion(&c, steps).0)
                })
            })
            .collect();
        let mut gated: Vec<Vec<usize>> = Vec::with_capacity(before.len());
        for b in before {
            let predicted = Self::moved(b, &m, t);
            let mut jac = SMatrix::<f64, 2, 5>::zeros();
            for (j, [(mu, tu), (md, td)]) in nudged.iter().enumerate() {
                let d = Self::moved(b, mu, tu) - Self::moved(b, md, td);
                jac[(0, j)] = d[0] / (2.0 * step[j]);
                jac[(1, j)] = wrap_angle(d[1]) / (2.0 * step[j]);
            }
            // The encoders' noise through the motion, as the update takes
            // it.
            let mut j_t = SMatrix::<f64, 2, 3>::zeros();
            for (j, e) in [1e-5, 1e-5, 1e-6].iter().enumerate() {
                let shift = |sign: f64| {
                    let mut v = [t.x, t.y, t.theta];
                    v[j] += sign * e;
                    Pose2::new(v[0], v[1], v[2])
                };
                let d = Self::moved(b, &m, &shift(1.0)) - Self::moved(b, &m, &shift(-1.0));
                j_t[(0, j)] = d[0] / (2.0 * e);
                j_t[(1, j)] = wrap_angle(d[1]) / (2.0 * e);
            }
            let (sg, cg) = b.gamma_rad.sin_cos();
            let g = Matrix2::new(1.0, sg * l.x - cg * l.y, 0.0, 1.0);
            let own = jac * self.p * jac.transpose() + j_t * q * j_t.transpose();
            let r = g * self.noise(b) * g.transpose() + own + slack;
            let inside: Vec<usize> = after
                .iter()
                .enumerate()
                .filter(|(_, a)| {
                    let nu =
                        Vector2::new(a.d_m - predicted[0], wrap_angle(a.gamma_rad - predicted[1]));
                    let s = r + self.noise(a);
                    s.try_inverse()
                        .is_some_and(|si| (nu.transpose() * si * nu)[0] < self.config.gate_chi2)
                })
                .map(|(k, _)| k)
                .collect();
            gated.push(inside);
        }
        // A wall of the second scan in the gate of two of the first pairs
        // with neither, whether or not their gates hold others too.
        let claimed = |k: usize| gated.iter().filter(|g| g.contains(&k)).count();
        gated
            .iter()
            .enumerate()
            .filter_map(|(i, inside)| match inside[..] {
                [k] if claimed(k) == 1 => Some(Pair {
                    before: &before[i],
                    after: &after[k],
                }),
                _ => None,
            })
            .collect()
    }

    /// One stacked EKF update with every pair.
    /// `t`, `q`: the motion over `steps` under the calibration as it
    /// stands, and its covariance.
    fn correct(
        &mut self,
        pairs: &[Pair<'_>],
        steps: &[[f64; 2]],
        t: &Pose2,
        q: &SMatrix<f64, 3, 3>,
    ) {
        if pairs.is_empty() {
            return;
        }
        let m = 2 * pairs.len();
        let x = self.x;
        let h_of = |c: &SVector<f64, 5>| -> DVector<f64> {
            let (t, _) = self.motion(c, steps);
            let mount = Pose2::new(c[0], c[1], c[2]);
            DVector::from_iterator(
                m,
                pairs.iter().flat_map(|p| {
                    Self::moved(p.before, &mount, &t)
                        .iter()
                        .copied()
                        .collect::<Vec<_>>()
                }),
            )
        };
        let mount = Pose2::new(x[0], x[1], x[2]);
        let h0: Vec<Vector2<f64>> = pairs
            .iter()
            .map(|p| Self::moved(p.before, &mount, t))
            .collect();
        // ∂h/∂c by central differences (the motion is a chain of arcs).
        let step = [1e-4, 1e-4, 1e-5, 1e-5, 1e-5];
        let mut h = DMatrix::zeros(m, 5);
        for (j, e) in step.iter().enumerate() {
            let mut up = x;
            let mut down = x;
            up[j] += e;
            down[j] -= e;
            let mut col = h_of(&up) - h_of(&down);
            for k in 0..pairs.len() {
                col[2 * k + 1] = wrap_angle(col[2 * k + 1]);
            }
            h.set_column(j, &(col / (2.0 * e)));
        }
        // Noise: both walls' and the encoders' (through the motion, shared
        // by every pair).
        let mut j_t = DMatrix::zeros(m, 3);
        for (j, e) in [1e-5, 1e-5, 1e-6].iter().enumerate() {
            let shift = |sign: f64| {
                let mut v = [t.x, t.y, t.theta];
                v[j] += sign * e;
                Pose2::new(v[0], v[1], v[2])
            };
            let (up, down) = (shift(1.0), shift(-1.0));
            for (k, p) in pairs.iter().enumerate() {
                let d = Self::moved(p.before, &mount, &up) - Self::moved(p.before, &mount, &down);
                j_t[(2 * k, j)] = d[0] / (2.0 * e);
                j_t[(2 * k + 1, j)] = wrap_angle(d[1]) / (2.0 * e);
            }
        }
        let q = DMatrix::from_iterator(3, 3, q.iter().copied());
        let mut s = &h * DMatrix::from_iterator(5, 5, self.p.iter().copied()) * h.transpose()
            + &j_t * q * j_t.transpose();
        let l = mount.inverse() * *t * mount;
        for (k, p) in pairs.iter().enumerate() {
            let (sg, cg) = p.before.gamma_rad.sin_cos();
            let g = Matrix2::new(1.0, sg * l.x - cg * l.y, 0.0, 1.0);
            let r = self.noise(p.after) + g * self.noise(p.before) * g.transpose();
            let mut block = s.view_mut((2 * k, 2 * k), (2, 2));
            block += r;
        }
        let nu = DVector::from_iterator(
            m,
            pairs.iter().enumerate().flat_map(|(k, p)| {
                [
                    p.after.d_m - h0[k][0],
                    wrap_angle(p.after.gamma_rad - h0[k][1]),
                ]
            }),
        );
        let Some(chol) = s.cholesky() else {
            return;
        };
        let p_full = DMatrix::from_iterator(5, 5, self.p.iter().copied());
        let pht = &p_full * h.transpose();
        let k_t = chol.solve(&pht.transpose());
        let dx = k_t.transpose() * nu;
        let p_new = &p_full - &pht * &k_t;
        for i in 0..5 {
            self.x[i] += dx[i];
            for j in 0..5 {
                self.p[(i, j)] = 0.5 * (p_new[(i, j)] + p_new[(j, i)]);
            }
        }
        self.x[2] = wrap_angle(self.x[2]);
    }
}

/// The `(d, γ)` of the world line with normal direction `normal_rad` at
/// distance `rho_m` from the origin, seen from `laser` (the tests'
/// simulation).
#[cfg(test)]
fn line_seen(normal_rad: f64, rho_m: f64, laser: &Pose2) -> (f64, f64) {
    let (s, c) = normal_rad.sin_cos();
    (
        rho_m - c * laser.x - s * laser.y,
        wrap_angle(normal_rad - laser.theta),
    )
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// The walls of a 6 × 4 m room (normal from inside, distance) as an
    /// extractor with the study's accuracy (σ 4 mm, 0.08°) reports them
    /// from `laser`: those whose foot lies in a 270° view, 0.3–10 m away.
    fn walls_seen(laser: &Pose2, rng: &mut ChaCha8Rng) -> Vec<Wall> {
        let (sd, sg) = (0.004, 0.08f64.to_radians());
        let nd = Normal::new(0.0, sd).unwrap();
        let ng = Normal::new(0.0, sg).unwrap();
        let room = [
            (std::f64::consts::PI, 0.0),
            (-std::f64::consts::FRAC_PI_2, 0.0),
            (0.0, 6.0),
            (std::f64::consts::FRAC_PI_2, 4.0),
        ];
        room.iter()
            .filter_map(|&(a, rho)| {
                let (d, g) = line_seen(a, rho, laser);
                (d > 0.3 && d < 10.0 && g.abs() < 125f64.to_radians()).then(|| Wall {
                    d_m: d + nd.sample(rng),
                    gamma_rad: wrap_angle(g + ng.sample(rng)),
                    covariance: Matrix2::new(sd * sd, 0.0, 0.0, sg * sg),
                    points: 200,
                    rms_residual_m: sd,
                    ends: [Point2::origin(); 2],
                })
            })
            .collect()
    }

    /// Runs loops round the room (straight 3 m and 1.6 m legs at 0.5 m/s,
    /// 90° turns on the spot at 0.8 rad/s), the true robot with wheels
    /// 1.5% larger and a track 2% shorter than specified and the laser
    /// mounted at (0.25, 0.02) m, 0.5°; the wheels slip; scans at 10 Hz,
    /// encoders at 50 Hz quantised to their ticks. Returns the calibrator
    /// and the truth.
    fn drive(guess: Calibration, loops: usize, seed: u64) -> (OnlineCalibrator, Calibration) {
        let truth = Calibration {
            laser_mount: Pose2::new(0.25, 0.02, 0.5f64.to_radians()),
            wheel_scale: 1.015,
            track_scale: 0.98,
        };
        let cfg = CalibratorConfig::default();
        let odo = cfg.odometry.clone();
        let mut cal = OnlineCalibrator::new(cfg, guess);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let r_nom = odo.wheel_radius_m[0];
        let metres_per_tick = 2.0 * std::f64::consts::PI * r_nom / f64::from(odo.ticks_per_rev);
        let true_track = odo.track_m * truth.track_scale;
        let mut pose = Pose2::new(1.5, 1.2, 0.0);
        // True wheel travel, accumulated; what the encoders count is
        // that over the true radius's tick length.
        let mut travel = [0.0f64; 2];
        let mut counted = [0i64; 2];
        let dt = 0.02;
        let legs: Vec<(f64, f64, f64)> = (0..loops)
            .flat_map(|_| {
                [3.0, 1.6, 3.0, 1.6].into_iter().flat_map(|len| {
                    [
                        (0.5, 0.0, len / 0.5),
                        (0.0, 0.8, std::f64::consts::FRAC_PI_2 / 0.8),
                    ]
                })
            })
            .collect();
        let mut k = 0u64;
        cal.scan(&walls_seen(&(pose * truth.laser_mount), &mut rng));
        for (v, w, dur) in legs {
            let n = (dur / dt).round() as usize;
            for _ in 0..n {
                // What the wheels turn through; the ground slips under them
                // by half the variance the odometry's noise model allows.
                let (rl, rr) = (
                    (v - w * true_track / 2.0) * dt,
                    (v + w * true_track / 2.0) * dt,
                );
                travel[0] += rl;
                travel[1] += rr;
                let mut slip = |r: f64| {
                    r + Normal::new(0.0, (0.5 * odo.travel_variance_per_m * r.abs()).sqrt())
                        .unwrap()
                        .sample(&mut rng)
                };
                let (dl, dr) = (slip(rl), slip(rr));
                // The encoders count ticks of the true wheel.
                let ticks =
                    travel.map(|t| (t / (metres_per_tick * truth.wheel_scale)).floor() as i64);
                cal.wheels([
                    (ticks[0] - counted[0]) as f64 * metres_per_tick,
                    (ticks[1] - counted[1]) as f64 * metres_per_tick,
                ]);
                counted = ticks;
                let d = 0.5 * (dl + dr);
                let dth = (dr - dl) / true_track;
                pose = pose * Pose2::new(d * (0.5 * dth).cos(), d * (0.5 * dth).sin(), dth);
                k += 1;
                if k.is_multiple_of(5) {
                    cal.scan(&walls_seen(&(pose * truth.laser_mount), &mut rng));
                }
            }
        }
        (cal, truth)
    }

    #[test]
    fn converges_from_a_wrong_guess() {
        let guess = Calibration {
            laser_mount: Pose2::new(0.28, -0.01, 1.5f64.to_radians()),
            wheel_scale: 1.0,
            track_scale: 1.0,
        };
        let (cal, truth) = drive(guess, 3, 7);
        let e = cal.estimate();
        let sigma = cal.error_sigma(&truth);
        let err = e.error_to(&truth);
        let report = format!("{e:?} σ {sigma:?} err {err:?} pairs {}", cal.pairs_used());
        eprintln!("calibration after three loops: {report}");
        // The targets: 5 mm, 0.2°, 0.5%.
        assert!(err[0].abs() <= 0.005 && err[1].abs() <= 0.005, "{report}");
        assert!(err[2].abs() <= 0.2f64.to_radians(), "{report}");
        assert!(err[3].abs() <= 0.005 && err[4].abs() <= 0.005, "{report}");
        // The filter knows how well it knows: every error within 3σ.
        for (e, s) in err.iter().zip(sigma) {
            assert!(e.abs() <= 3.0 * s + 1e-4, "{report}");
        }
    }
}
