//! The room filter of paper A §3: an extended Kalman filter of the robot's
//! pose in a rectangular room and of the room's size, fed by dead
//! reckoning and by the walls the laser sees, with the delayed-measurement
//! scheme of eq. 8.
//!
//! The room frame has its origin in a corner and its walls on the lines
//! `x = 0`, `y = 0`, `x = xs`, `y = ys`. The state is
//! `(x, y, θ, xs, ys, s₁, s₂, …)`: the rear axle's pose, the room's size,
//! and the position of each door along its wall (added with
//! [`RoomEkf::add_door`]).
//!
//! The same filter holds a robot in a room of any shape, its drawing the
//! prior ([`RoomEkf::in_polygon`]): the state's room rows are then each
//! wall's angle and offset but wall 0's, which fixes the frame (see
//! [`RoomShape`]).
//!
//! A scan is applied at its own stamp: the filter holds its estimate at the
//! last scan's stamp and the encoder samples that came since; a new scan's
//! stamp splits them into the part before it (predicted through, then the
//! update) and the part after (re-predicted to "now" when asked). How long
//! the extraction took — how late the scan is handed in — never changes
//! the estimate.
//!
//! The gains take each scan's walls for looks independent of the last
//! scan's, which pulls the estimate onto the walls scan after scan; but
//! what clutter along a wall makes of its line is the same in every scan,
//! and the covariance of those gains shrinks far below the estimate's
//! error (in the living room, to a tenth of a millimetre against 1–2 mm).
//! Beside it the filter carries the covariance of its error with that
//! shared error taken in (a consider analysis of its own gains, as in a
//! Schmidt–Kalman filter), and reports that one
//! ([`RoomEkf::estimate_now`]).

use crate::door::DoorOpening;
use crate::odometry::{Displacement, OdometryConfig, turned_covariance};
use crate::room_shape::RoomShape;
use crate::wall::Wall;
use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, SMatrix, SVector, Vector2};
use serde::Serialize;
use stucco_core::{EncoderSample, Pose2, Stamp, wrap_angle};

/// The filter's state without doors: `(x, y, θ, xs, ys)`.
pub type RoomState = SVector<f64, 5>;
/// Its covariance.
pub type RoomCovariance = SMatrix<f64, 5, 5>;

/// A door of the room: the wall it is in (a rectangle's 0: x = 0, 1:
/// y = 0, 2: x = xs, 3: y = ys) and the index of its position in the
/// state (along the wall's axis: a rectangle's y for walls 0 and 2, x for
/// 1 and 3; see [`RoomShape::door_centre`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct RoomDoor {
    /// The wall.
    pub wall: usize,
    /// Index in the state.
    pub index: usize,
}

/// Settings of the room filter.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomEkfConfig {
    /// The odometry.
    pub odometry: OdometryConfig,
    /// Where the laser sits on the robot.
    pub laser_mount: Pose2,
    /// Innovation gate: a wall whose squared Mahalanobis distance to its
    /// prediction exceeds this is rejected (χ², 2 degrees of freedom;
    /// 13.8 ≈ 99.9%).
    pub gate_chi2: f64,
    /// Floor on a wall observation's variance: `(d, γ)`, m², rad².
    pub min_wall_variance: [f64; 2],
    /// Standard deviation of the error a wall observation shares with the
    /// scans of that wall before it, `(d, γ)`, m and rad: what a jamb, a
    /// radiator or a shelf along a wall makes of its line is the same scan
    /// after scan, and no number of scans averages it away. The filter's
    /// gains leave it out (they are tuned to pull the estimate onto the
    /// walls); the covariance it reports takes it in (see
    /// [`RoomEkf::estimate_now`]).
    pub wall_bias_sigma: [f64; 2],
    /// Travel over which that shared error is forgotten, m: it falls by
    /// `exp(−travel / this − turn / wall_bias_turn_rad)`.
    pub wall_bias_travel_m: f64,
    /// Turn over which it is forgotten, rad.
    pub wall_bias_turn_rad: f64,
}

impl RoomEkfConfig {
    /// The filter for a robot with `odometry` and its laser at `mount`.
    pub fn new(odometry: OdometryConfig, laser_mount: Pose2) -> Self {
        RoomEkfConfig {
            odometry,
            laser_mount,
            gate_chi2: 13.8,
            min_wall_variance: [1e-6, 1e-7],
            // Measured in the simulator's rooms: a robot standing before
            // the living room's walls, its radiator and its window, is off
            // by 1-2 mm across the room however many scans it takes.
            wall_bias_sigma: [0.002, 0.001],
            wall_bias_travel_m: 2.0,
            wall_bias_turn_rad: 1.0,
        }
    }
}

/// What one scan did to the filter.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ScanUpdate {
    /// Walls used, by room wall (0: x = 0, 1: y = 0, 2: x = xs, 3: y = ys).
    pub used: Vec<usize>,
    /// Walls rejected by the innovation gate.
    pub rejected: usize,
    /// Doors used, by their index in the state.
    pub doors_used: Vec<usize>,
    /// The scan was stamped before the filter's last measurement and was
    /// left out: the filter takes measurements in time order.
    pub late: bool,
}

/// An innovation: squared Mahalanobis distance, innovation, inverse of
/// its covariance.
struct Innovation {
    m2: f64,
    nu: Vector2<f64>,
    s_inv: Matrix2<f64>,
}

/// The innovation of `z` against its prediction `z_hat` (the second
/// component an angle when `angular`).
fn innovation(
    p: &DMatrix<f64>,
    z: &Vector2<f64>,
    z_hat: &Vector2<f64>,
    h: &DMatrix<f64>,
    r: &Matrix2<f64>,
    angular: bool,
) -> Option<Innovation> {
    let hp = h * p * h.transpose();
    let s = Matrix2::new(hp[(0, 0)], hp[(0, 1)], hp[(1, 0)], hp[(1, 1)]) + r;
    let s_inv = s.try_inverse()?;
    let dy = z.y - z_hat.y;
    let nu = Vector2::new(z.x - z_hat.x, if angular { wrap_angle(dy) } else { dy });
    let m2 = (nu.transpose() * s_inv * nu)[(0, 0)];
    Some(Innovation { m2, nu, s_inv })
}

/// The Kalman update of `x`, `p` with innovation `m` (Joseph form, which
/// keeps `p` symmetric and positive); returns the gain.
fn update(
    x: &mut DVector<f64>,
    p: &mut DMatrix<f64>,
    h: &DMatrix<f64>,
    m: &Innovation,
    r: &Matrix2<f64>,
) -> DMatrix<f64> {
    let s_inv = DMatrix::from_column_slice(2, 2, m.s_inv.as_slice());
    let k = &*p * h.transpose() * s_inv;
    let nu = DVector::from_column_slice(m.nu.as_slice());
    *x += &k * nu;
    x[2] = wrap_angle(x[2]);
    *p = joseph(p, &(DMatrix::identity(x.len(), x.len()) - &k * h), &k, r);
    k
}

/// `A P Aᵀ + K R Kᵀ`, symmetric: the covariance after an update of gain
/// `K` (`A = I − KH`) by an observation of error `R`, whatever the gain.
fn joseph(p: &DMatrix<f64>, a: &DMatrix<f64>, k: &DMatrix<f64>, r: &Matrix2<f64>) -> DMatrix<f64> {
    let r = DMatrix::from_column_slice(2, 2, r.as_slice());
    let q = a * p * a.transpose() + k * r * k.transpose();
    0.5 * (&q + q.transpose())
}

/// `p` with one more row and column, the new one of variance `variance`
/// and uncorrelated.
fn padded(p: &DMatrix<f64>, variance: f64) -> DMatrix<f64> {
    let n = p.nrows();
    let mut out = DMatrix::zeros(n + 1, n + 1);
    out.view_mut((0, 0), (n, n)).copy_from(p);
    out[(n, n)] = variance;
    out
}

/// The covariance of the filter's error when its observations of walls
/// share errors from scan to scan (a consider analysis, as of a
/// Schmidt–Kalman filter: the shared errors are in the covariance, never
/// estimated). The filter's own gains are left as they are: the estimate
/// does not change, only what it says of itself.
#[derive(Clone, Debug)]
struct ErrorCovariance {
    /// Covariance of the state's error.
    p: DMatrix<f64>,
    /// Its covariance with the walls' shared errors, `(d, γ)` of wall 0,
    /// then 1, 2, …: `n × 2·walls`.
    cross: DMatrix<f64>,
}

impl ErrorCovariance {
    /// Takes in the update of gain `k` by an observation `h` of wall `q`
    /// with the fit's own error `r` and the shared error `shared`: the
    /// error becomes `(I − KH)e − K(v + b)`, `v` the scan's own error and
    /// `b` the shared one.
    fn wall_update(
        &mut self,
        h: &DMatrix<f64>,
        k: &DMatrix<f64>,
        r: &Matrix2<f64>,
        q: usize,
        shared: &Matrix2<f64>,
    ) {
        let n = self.p.nrows();
        let a = DMatrix::identity(n, n) - k * h;
        let c = self.cross.columns(2 * q, 2).into_owned();
        // The shared error counts as the scan's own in the Joseph form,
        // less its covariance with the state's error before the update.
        let akc = &a * &c * k.transpose();
        self.p = joseph(&self.p, &a, k, &(r + shared)) - (&akc + akc.transpose());
        self.cross = &a * &self.cross;
        let mut own = self.cross.columns_mut(2 * q, 2);
        own -= k * DMatrix::from_column_slice(2, 2, shared.as_slice());
    }

    /// Takes in an update of gain `k` by an observation `h` with error `r`
    /// shared with nothing (a door).
    fn own_update(&mut self, h: &DMatrix<f64>, k: &DMatrix<f64>, r: &Matrix2<f64>) {
        let n = self.p.nrows();
        let a = DMatrix::identity(n, n) - k * h;
        self.p = joseph(&self.p, &a, k, r);
        self.cross = &a * &self.cross;
    }
}

/// The room filter with its delayed-measurement bookkeeping.
#[derive(Clone, Debug)]
pub struct RoomEkf {
    config: RoomEkfConfig,
    shape: RoomShape,
    /// The estimate at `at` (the last scan's stamp, or the start).
    x: DVector<f64>,
    /// The covariance the gains are made of.
    p: DMatrix<f64>,
    /// The covariance of the estimate's error as it is, with the walls'
    /// shared errors in, at `at`.
    error: ErrorCovariance,
    doors: Vec<RoomDoor>,
    at: Stamp,
    /// The encoder sample the estimate's pose corresponds to.
    anchor: Option<EncoderSample>,
    /// Encoder samples since `anchor`, oldest first.
    pending: Vec<EncoderSample>,
}

impl RoomEkf {
    /// A filter in a rectangular room starting from `x0` with covariance
    /// `p0` at `at`.
    pub fn new(config: RoomEkfConfig, x0: RoomState, p0: RoomCovariance, at: Stamp) -> Self {
        Self::in_shape(
            config,
            RoomShape::rectangle(),
            DVector::from_column_slice(x0.as_slice()),
            DMatrix::from_column_slice(5, 5, p0.as_slice()),
            at,
        )
    }

    /// A filter in a room of the shape `shape` (its drawing's walls the
    /// prior, uncorrelated), the robot at `pose` with covariance
    /// `pose_covariance`, at `at`.
    pub fn in_polygon(
        config: RoomEkfConfig,
        shape: RoomShape,
        pose: Pose2,
        pose_covariance: Matrix3<f64>,
        at: Stamp,
    ) -> Self {
        let n = 3 + shape.drawn().len();
        let mut x = DVector::zeros(n);
        let mut p = DMatrix::zeros(n, n);
        x.rows_mut(0, 3)
            .copy_from_slice(&[pose.x, pose.y, pose.theta]);
        p.view_mut((0, 0), (3, 3)).copy_from(&pose_covariance);
        for (i, (v, sigma)) in shape.drawn().iter().enumerate() {
            x[3 + i] = *v;
            p[(3 + i, 3 + i)] = sigma * sigma;
        }
        Self::in_shape(config, shape, x, p, at)
    }

    fn in_shape(
        config: RoomEkfConfig,
        shape: RoomShape,
        x: DVector<f64>,
        p: DMatrix<f64>,
        at: Stamp,
    ) -> Self {
        let n = x.len();
        let walls = shape.len();
        RoomEkf {
            config,
            shape,
            error: ErrorCovariance {
                p: p.clone(),
                cross: DMatrix::zeros(n, 2 * walls),
            },
            x,
            p,
            doors: Vec::new(),
            at,
            anchor: None,
            pending: Vec::new(),
        }
    }

    /// The walls of the room.
    pub fn shape(&self) -> &RoomShape {
        &self.shape
    }

    /// The filter of this room with the robot placed anew at `pose`,
    /// `pose_covariance` uncertain, at `at`: what it learnt of the room's
    /// walls kept (their rows and covariance), their correlation with the
    /// old pose and the doors dropped (put them in again with
    /// [`RoomEkf::add_door`]).
    pub fn placed_anew(&self, pose: Pose2, pose_covariance: Matrix3<f64>, at: Stamp) -> Self {
        let rows = self.shape.rows();
        let n = 3 + rows;
        let mut x = DVector::zeros(n);
        let mut p = DMatrix::zeros(n, n);
        x.rows_mut(0, 3)
            .copy_from_slice(&[pose.x, pose.y, pose.theta]);
        x.rows_mut(3, rows).copy_from(&self.x.rows(3, rows));
        p.view_mut((0, 0), (3, 3)).copy_from(&pose_covariance);
        let (_, now) = self.now();
        p.view_mut((3, 3), (rows, rows))
            .copy_from(&now.view((3, 3), (rows, rows)));
        Self::in_shape(self.config.clone(), self.shape.clone(), x, p, at)
    }

    /// The estimate at the last scan, and when that was.
    pub fn at_last_scan(&self) -> (&DVector<f64>, &DMatrix<f64>, Stamp) {
        (&self.x, &self.p, self.at)
    }

    /// Adds a door in room wall `wall` at `position_m` along it (a
    /// rectangle's y for walls 0 and 2, x for 1 and 3), `sigma_m`
    /// uncertain; returns it.
    pub fn add_door(&mut self, wall: usize, position_m: f64, sigma_m: f64) -> RoomDoor {
        let n = self.x.len();
        self.x = self.x.clone().insert_row(n, position_m);
        self.p = padded(&self.p, sigma_m * sigma_m);
        self.error.p = padded(&self.error.p, sigma_m * sigma_m);
        self.error.cross = self.error.cross.clone().insert_row(n, 0.0);
        let door = RoomDoor { wall, index: n };
        self.doors.push(door);
        door
    }

    /// The doors in the state.
    pub fn doors(&self) -> &[RoomDoor] {
        &self.doors
    }

    /// Takes an encoder sample (dead reckoning runs at the encoders' rate).
    pub fn odometry(&mut self, sample: EncoderSample) {
        if self.anchor.is_none() {
            self.anchor = Some(sample);
            return;
        }
        self.pending.push(sample);
    }

    /// The estimate now: the last scan's estimate re-predicted with the
    /// displacement accumulated since (eq. 8).
    pub fn now(&self) -> (DVector<f64>, DMatrix<f64>) {
        let d = self.displacement(self.pending.len(), None);
        predict(&self.x, &self.p, &d)
    }

    /// The estimate now with the covariance of its error, the walls'
    /// shared errors taken in: what the robot acts on. (The covariance
    /// [`RoomEkf::now`] returns is the one the gains are made of, and takes
    /// scan after scan of one wall for independent looks.)
    pub fn estimate_now(&self) -> (DVector<f64>, DMatrix<f64>) {
        let d = self.displacement(self.pending.len(), None);
        predict(&self.x, &self.error.p, &d)
    }

    /// How much of the walls' shared errors outlasts the motion `d`.
    fn bias_memory(&self, d: &Displacement) -> f64 {
        let c = &self.config;
        let travel = d.pose.position().coords.norm() / c.wall_bias_travel_m;
        let turn = d.pose.theta.abs() / c.wall_bias_turn_rad;
        (-(travel + turn)).exp()
    }

    /// The displacement from the anchor through the first `n` pending
    /// samples, and on to `until` by constant velocity over the next one.
    fn displacement(&self, n: usize, until: Option<Stamp>) -> Displacement {
        let cfg = &self.config.odometry;
        let Some(mut prev) = self.anchor else {
            return Displacement::zero(self.at);
        };
        let mut d = Displacement::zero(prev.stamp);
        let per_tick =
            |w: usize| std::f64::consts::TAU * cfg.wheel_radius_m[w] / f64::from(cfg.ticks_per_rev);
        let wheels = |a: &EncoderSample, b: &EncoderSample| {
            [
                (b.left_ticks - a.left_ticks) as f64 * per_tick(0),
                (b.right_ticks - a.right_ticks) as f64 * per_tick(1),
            ]
        };
        for s in &self.pending[..n] {
            d.extend(wheels(&prev, s), s.stamp, cfg);
            prev = *s;
        }
        if let (Some(t), Some(next)) = (until, self.pending.get(n)) {
            let span = next.stamp.seconds_since(prev.stamp);
            if span > 0.0 {
                let f = (t.seconds_since(prev.stamp) / span).clamp(0.0, 1.0);
                let w = wheels(&prev, next);
                d.extend([w[0] * f, w[1] * f], t, cfg);
            }
        }
        d
    }

    /// Applies the walls and door openings seen in a scan stamped `stamp`
    /// (its first beam), given in the laser's frame: predicts the last
    /// estimate through the odometry up to `stamp`, associates each wall
    /// with the room wall it predicts nearest and each opening with the
    /// door it predicts nearest (within the gate), and updates. The samples
    /// after `stamp` stay pending for [`RoomEkf::now`]. A scan stamped
    /// before the last one taken is left out (and reported `late`).
    pub fn scan(&mut self, stamp: Stamp, walls: &[Wall], doors: &[DoorOpening]) -> ScanUpdate {
        if stamp < self.at {
            // Its walls were seen from where the robot stood then, and the
            // estimate is already past that: fused now, they would pull it
            // back by the motion since (a degree in 20 ms of a 1 rad/s
            // pivot).
            return ScanUpdate {
                rejected: walls.len(),
                late: true,
                ..ScanUpdate::default()
            };
        }
        let n = self.pending.iter().take_while(|s| s.stamp <= stamp).count();
        let d = self.displacement(n, Some(stamp));
        let (mut x, mut p) = predict(&self.x, &self.p, &d);
        let mut error = ErrorCovariance {
            p: predict(&self.x, &self.error.p, &d).1,
            cross: transition(&self.x, &d) * &self.error.cross * self.bias_memory(&d),
        };
        let mut report = ScanUpdate::default();
        let floor = Matrix2::from_diagonal(&Vector2::from(self.config.min_wall_variance));
        let [bd, bg] = self.config.wall_bias_sigma;
        let shared = Matrix2::new(bd * bd, 0.0, 0.0, bg * bg);
        // The best-supported walls first: a short piece seen at the edge
        // of the field of view must not shrink the filter onto itself
        // before the long wall ahead is gated.
        let mut order: Vec<&Wall> = walls.iter().collect();
        order.sort_by_key(|w| std::cmp::Reverse(w.points));
        for wall in order {
            let z = Vector2::new(wall.d_m, wall.gamma_rad);
            let r = wall.covariance + floor;
            let (l, dl) = laser_pose(&x, &self.config.laser_mount);
            let ends = wall.ends.map(|e| l.transform_point(&e));
            // A polygon's corners as the state has them now (a rectangle
            // needs none).
            let corners = if self.shape.is_polygon() {
                self.shape.corners(&x)
            } else {
                Vec::new()
            };
            let best = (0..self.shape.len())
                .filter(|&q| self.shape.may_see(&x, &corners, q, &l, ends))
                .filter_map(|q| {
                    let (z_hat, h) = self.shape.observe_from(&x, q, &l, dl);
                    innovation(&p, &z, &z_hat, &h, &r, true).map(|m| (q, m, h))
                })
                .min_by(|a, b| a.1.m2.total_cmp(&b.1.m2));
            let Some((q, m, h)) = best else { continue };
            if m.m2 > self.config.gate_chi2 {
                report.rejected += 1;
                continue;
            }
            let k = update(&mut x, &mut p, &h, &m, &r);
            error.wall_update(&h, &k, &r, q, &shared);
            report.used.push(q);
        }
        for opening in doors {
            let z = Vector2::new(opening.center.x, opening.center.y);
            let r = opening.covariance + Matrix2::identity() * 1e-6;
            let best = self
                .doors
                .iter()
                .filter_map(|door| {
                    let (z_hat, h) = door_seen(&self.shape, &x, door, &self.config.laser_mount);
                    innovation(&p, &z, &z_hat, &h, &r, false).map(|m| (door.index, m, h))
                })
                .min_by(|a, b| a.1.m2.total_cmp(&b.1.m2));
            let Some((index, m, h)) = best else { continue };
            if m.m2 > self.config.gate_chi2 {
                report.rejected += 1;
                continue;
            }
            let k = update(&mut x, &mut p, &h, &m, &r);
            error.own_update(&h, &k, &r);
            report.doors_used.push(index);
        }
        // The scan's stamp is the new reference: the odometry from the
        // anchor to it is spent.
        self.x = x;
        self.p = p;
        self.error = error;
        self.at = stamp;
        let rest = self.pending.split_off(n);
        let anchor_at_stamp = self.pending.last().copied().or(self.anchor);
        // A sample at the stamp itself anchors exactly; otherwise the next
        // sample's travel is split at the stamp.
        if let Some(next) = rest.first().copied() {
            if let Some(a) = anchor_at_stamp {
                let span = next.stamp.seconds_since(a.stamp);
                let f = if span > 0.0 {
                    (stamp.seconds_since(a.stamp) / span).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                // The anchor's counters are placed where the wheels were at
                // the stamp (fractional ticks are rounded; the remainder is
                // below one tick).
                self.anchor = Some(EncoderSample {
                    stamp,
                    left_ticks: a.left_ticks
                        + ((next.left_ticks - a.left_ticks) as f64 * f).round() as i64,
                    right_ticks: a.right_ticks
                        + ((next.right_ticks - a.right_ticks) as f64 * f).round() as i64,
                });
            }
        } else {
            self.anchor = anchor_at_stamp;
        }
        self.pending = rest;
        report
    }
}

/// The state moved by a displacement (eq. 5) and its covariance (eq. 6–7):
/// the pose composed, the room and its doors unchanged.
pub fn predict(
    x: &DVector<f64>,
    p: &DMatrix<f64>,
    d: &Displacement,
) -> (DVector<f64>, DMatrix<f64>) {
    let th = x[2];
    let (s, c) = th.sin_cos();
    let dp = d.pose;
    let mut out = x.clone();
    out[0] += c * dp.x - s * dp.y;
    out[1] += s * dp.x + c * dp.y;
    out[2] = wrap_angle(th + dp.theta);
    let f = transition(x, d);
    let q = turned_covariance(&d.covariance, th);
    let mut out_p = &f * p * f.transpose();
    for i in 0..3 {
        for j in 0..3 {
            out_p[(i, j)] += q[(i, j)];
        }
    }
    let sym = 0.5 * (&out_p + out_p.transpose());
    (out, sym)
}

/// The Jacobian of [`predict`]'s state with respect to `x`.
fn transition(x: &DVector<f64>, d: &Displacement) -> DMatrix<f64> {
    let (s, c) = x[2].sin_cos();
    let dp = d.pose;
    let mut f = DMatrix::identity(x.len(), x.len());
    f[(0, 2)] = -s * dp.x - c * dp.y;
    f[(1, 2)] = c * dp.x - s * dp.y;
    f
}

/// The laser's pose in the room for state `x`, and the derivative of its
/// position with respect to the heading.
fn laser_pose(x: &DVector<f64>, mount: &Pose2) -> (Pose2, [f64; 2]) {
    let (s, c) = x[2].sin_cos();
    (
        Pose2 {
            x: x[0] + c * mount.x - s * mount.y,
            y: x[1] + s * mount.x + c * mount.y,
            theta: x[2] + mount.theta,
        },
        [-s * mount.x - c * mount.y, c * mount.x - s * mount.y],
    )
}

/// The predicted observation `(d, γ)` of rectangular room wall `q` from
/// the laser at `mount` on a robot in state `x`, and its Jacobian.
pub fn observe(x: &DVector<f64>, q: usize, mount: &Pose2) -> (Vector2<f64>, DMatrix<f64>) {
    let (l, dl) = laser_pose(x, mount);
    RoomShape::rectangle().observe_from(x, q, &l, dl)
}

/// The predicted centre of `door` of a rectangular room, in the laser's
/// frame, and its Jacobian.
pub fn observe_door(
    x: &DVector<f64>,
    door: &RoomDoor,
    mount: &Pose2,
) -> (Vector2<f64>, DMatrix<f64>) {
    door_seen(&RoomShape::rectangle(), x, door, mount)
}

/// The predicted centre of `door` in a room of `shape`, in the laser's
/// frame, and its Jacobian.
fn door_seen(
    shape: &RoomShape,
    x: &DVector<f64>,
    door: &RoomDoor,
    mount: &Pose2,
) -> (Vector2<f64>, DMatrix<f64>) {
    let (l, [dlx, dly]) = laser_pose(x, mount);
    let (centre, along, by_rows) = shape.door_centre(x, door.wall, x[door.index]);
    let (sn, c) = l.theta.sin_cos();
    // p = R(−θ_L)·(centre − L).
    let r_inv = Matrix2::new(c, sn, -sn, c);
    let v = centre - Vector2::new(l.x, l.y);
    let z = r_inv * v;
    let dr_inv = Matrix2::new(-sn, c, -c, -sn);
    let d_theta = dr_inv * v - r_inv * Vector2::new(dlx, dly);
    let mut h = DMatrix::zeros(2, x.len());
    let a = r_inv * along;
    for row in 0..2 {
        h[(row, 0)] = -r_inv[(row, 0)];
        h[(row, 1)] = -r_inv[(row, 1)];
        h[(row, 2)] = d_theta[row];
        h[(row, door.index)] = a[row];
    }
    for (i, dir) in by_rows {
        let b = r_inv * dir;
        for row in 0..2 {
            h[(row, i)] += b[row];
        }
    }
    (z, h)
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    fn wall(d: f64, g: f64) -> Wall {
        Wall {
            d_m: d,
            gamma_rad: g,
            covariance: Matrix2::new(1e-5, 0.0, 0.0, 1e-6),
            points: 50,
            rms_residual_m: 0.01,
            ends: [Point2::origin(), Point2::origin()],
        }
    }

    proptest::proptest! {
        /// Predictions and updates with any motion and any walls keep the
        /// covariance symmetric positive semi-definite.
        #[test]
        fn covariance_stays_symmetric_positive(
            moves in proptest::collection::vec((-0.05..0.05f64, -0.05..0.05f64), 1..40),
            seen in proptest::collection::vec((0usize..4, -0.3..0.3f64, -0.1..0.1f64), 1..12),
        ) {
            let mount = Pose2::new(0.35, 0.0, 0.0);
            let cfg = RoomEkfConfig::new(OdometryConfig::default(), mount);
            let x0 = RoomState::new(2.0, 2.0, 0.2, 5.0, 4.0);
            let p0 = RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(1e-3, 1e-3, 1e-3, 0.05, 0.05));
            let mut ekf = RoomEkf::new(cfg, x0, p0, Stamp::ZERO);
            let (mut l, mut r) = (0i64, 0i64);
            for (k, (dl, dr)) in moves.iter().enumerate() {
                l += (dl * 3000.0) as i64;
                r += (dr * 3000.0) as i64;
                ekf.odometry(EncoderSample { stamp: Stamp::from_secs_f64(k as f64 * 0.02), left_ticks: l, right_ticks: r });
            }
            let t = Stamp::from_secs_f64(moves.len() as f64 * 0.01);
            let walls: Vec<Wall> = seen
                .iter()
                .map(|&(q, dd, dg)| {
                    let (z, _) = observe(&DVector::from_column_slice(x0.as_slice()), q, &mount);
                    wall(z.x + dd, z.y + dg)
                })
                .collect();
            ekf.scan(t, &walls, &[]);
            let (_, p, _) = ekf.at_last_scan();
            proptest::prop_assert!((p - p.transpose()).norm() < 1e-12);
            proptest::prop_assert!(p.symmetric_eigenvalues().iter().all(|&e| e >= -1e-12));
            let (_, now) = ekf.now();
            proptest::prop_assert!(now.symmetric_eigenvalues().iter().all(|&e| e >= -1e-12));
        }
    }

    #[test]
    fn observation_jacobian_matches_finite_differences() {
        let x = DVector::from_vec(vec![1.2, 2.3, 0.4, 5.45, 5.64]);
        let mount = Pose2::new(0.35, 0.05, 0.02);
        for q in 0..4 {
            let (z, h) = observe(&x, q, &mount);
            for i in 0..5 {
                let mut dx = x.clone();
                dx[i] += 1e-7;
                let (z2, _) = observe(&dx, q, &mount);
                let num = (z2 - z) / 1e-7;
                assert!((num.x - h[(0, i)]).abs() < 1e-5, "q{q} i{i}");
                assert!((wrap_angle(num.y * 1e-7) / 1e-7 - h[(1, i)]).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn door_jacobian_matches_finite_differences() {
        let x = DVector::from_vec(vec![1.2, 2.3, 0.4, 5.45, 5.64, 2.55, 3.1]);
        let mount = Pose2::new(0.35, 0.05, 0.02);
        for (wall, index) in [(2, 5), (3, 6), (0, 5), (1, 6)] {
            let door = RoomDoor { wall, index };
            let (z, h) = observe_door(&x, &door, &mount);
            for i in 0..7 {
                let mut dx = x.clone();
                dx[i] += 1e-7;
                let (z2, _) = observe_door(&dx, &door, &mount);
                let num = (z2 - z) / 1e-7;
                for row in 0..2 {
                    assert!(
                        (num[row] - h[(row, i)]).abs() < 1e-5,
                        "wall {wall} i {i} row {row}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_seen_door_places_itself_in_the_state() {
        let truth = DVector::from_vec(vec![2.0, 2.5, 0.1, 5.45, 5.64, 2.55]);
        let mount = Pose2::new(0.35, 0.0, 0.0);
        let cfg = RoomEkfConfig::new(OdometryConfig::default(), mount);
        let x0 = RoomState::new(2.0, 2.5, 0.1, 5.45, 5.64);
        let p0 =
            RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(1e-4, 1e-4, 1e-5, 1e-4, 1e-4));
        let mut ekf = RoomEkf::new(cfg, x0, p0, Stamp::ZERO);
        let door = ekf.add_door(2, 2.35, 0.3);
        let (z, _) = observe_door(&truth, &door, &mount);
        let opening = DoorOpening {
            wall: 0,
            center: Point2::new(z.x, z.y),
            covariance: Matrix2::identity() * 1e-4,
            width_m: 0.9,
            width_sigma_m: 0.01,
            frames: [Point2::origin(), Point2::origin()],
        };
        for k in 0..10 {
            let r = ekf.scan(
                Stamp::from_secs_f64(k as f64 * 0.125),
                &[],
                std::slice::from_ref(&opening),
            );
            assert_eq!(r.doors_used, vec![door.index]);
        }
        let (x, _, _) = ekf.at_last_scan();
        assert!((x[door.index] - 2.55).abs() < 0.01, "{}", x[door.index]);
    }

    #[test]
    fn walls_seen_from_the_true_pose_pull_a_wrong_estimate_to_it() {
        let truth = RoomState::new(2.0, 1.5, 0.3, 5.45, 5.64);
        let mount = Pose2::new(0.35, 0.0, 0.0);
        let cfg = RoomEkfConfig::new(OdometryConfig::default(), mount);
        let x0 = RoomState::new(2.05, 1.45, 0.32, 5.3, 5.8);
        let p0 =
            RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(0.01, 0.01, 0.004, 0.1, 0.1));
        let mut ekf = RoomEkf::new(cfg, x0, p0, Stamp::ZERO);
        let walls: Vec<Wall> = (0..4)
            .map(|q| {
                let (z, _) = observe(&DVector::from_column_slice(truth.as_slice()), q, &mount);
                wall(z.x, z.y)
            })
            .collect();
        for k in 0..5 {
            let r = ekf.scan(Stamp::from_secs_f64(k as f64 * 0.125), &walls, &[]);
            assert_eq!(r.used.len(), 4, "{r:?}");
        }
        let (x, p, _) = ekf.at_last_scan();
        assert!(
            (x - DVector::from_column_slice(truth.as_slice())).norm() < 1e-3,
            "{x}"
        );
        assert!((p - p.transpose()).norm() < 1e-15);
        assert!(p.symmetric_eigenvalues().iter().all(|&e| e > 0.0));
        // A person 1 m in front of the far wall is gated out.
        let person = wall(walls[2].d_m - 1.0, walls[2].gamma_rad);
        let r = ekf.scan(Stamp::from_secs_f64(1.0), &[person], &[]);
        assert_eq!((r.used.len(), r.rejected), (0, 1));
    }

    /// Mean NEES of the pose `(x, y, θ)` over runs of a robot standing
    /// still before the four walls of a room for 4 s of scans at 40 Hz,
    /// each wall's observations erring by an error of its own drawn once
    /// per run (`N(0, bias)`, as the filter's config has it) and by one
    /// drawn anew every scan (the fit's covariance): against the error
    /// covariance, and against the covariance the gains are made of.
    fn standing_still_nees(runs: u64) -> (f64, f64) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let truth = RoomState::new(2.0, 1.5, 0.3, 5.45, 3.64);
        let t = DVector::from_column_slice(truth.as_slice());
        let mount = Pose2::new(0.35, 0.0, 0.0);
        let cfg = RoomEkfConfig::new(OdometryConfig::default(), mount);
        let [bd, bg] = cfg.wall_bias_sigma;
        let (fit_d, fit_g) = (0.002, 3e-4);
        let p0 =
            RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(1e-4, 1e-4, 1e-4, 1e-4, 1e-4));
        let nees = |e: &DVector<f64>, p: &DMatrix<f64>| {
            let e = e.rows(0, 3).into_owned();
            let p = p.view((0, 0), (3, 3)).into_owned();
            let inv = p.try_inverse().expect("a covariance of full rank");
            (e.transpose() * inv * e)[(0, 0)]
        };
        let (mut error_nees, mut gain_nees) = (0.0, 0.0);
        for run in 0..runs {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(run);
            let normal = |s: f64| Normal::new(0.0, s).expect("a spread");
            let start = DVector::from_fn(5, |i, _| t[i] + normal(1e-2).sample(&mut rng));
            let x0 = RoomState::from_column_slice(start.as_slice());
            let mut ekf = RoomEkf::new(cfg.clone(), x0, p0, Stamp::ZERO);
            let bias: Vec<[f64; 2]> = (0..4)
                .map(|_| [normal(bd).sample(&mut rng), normal(bg).sample(&mut rng)])
                .collect();
            for k in 0..160 {
                let walls: Vec<Wall> = (0..4)
                    .map(|q| {
                        let (z, _) = observe(&t, q, &mount);
                        let mut w = wall(
                            z.x + bias[q][0] + normal(fit_d).sample(&mut rng),
                            z.y + bias[q][1] + normal(fit_g).sample(&mut rng),
                        );
                        w.covariance = Matrix2::new(fit_d * fit_d, 0.0, 0.0, fit_g * fit_g);
                        w
                    })
                    .collect();
                ekf.scan(Stamp::from_secs_f64(k as f64 * 0.025), &walls, &[]);
            }
            let (x, p) = ekf.now();
            let mut e = x - &t;
            e[2] = wrap_angle(e[2]);
            error_nees += nees(&e, &ekf.estimate_now().1);
            gain_nees += nees(&e, &p);
        }
        (error_nees / runs as f64, gain_nees / runs as f64)
    }

    #[test]
    fn a_robot_standing_still_knows_its_walls_share_their_errors_from_scan_to_scan() {
        // Honest: the mean NEES of three degrees of freedom is 3 (over 100
        // runs its standard error is 0.25). The gains' covariance, which
        // takes 160 scans of a wall for 160 independent looks, is sure of
        // the pose to a small fraction of its error.
        let (error, gains) = standing_still_nees(100);
        assert!((2.2..=3.8).contains(&error), "{error}");
        assert!(gains > 30.0, "{gains}");
    }

    #[test]
    fn a_scan_stamped_before_the_last_measurement_is_left_out() {
        // The robot pivots at 1 rad/s; the camera's wall, stamped now, is
        // taken before a laser scan stamped 100 ms earlier comes in.
        let mount = Pose2::new(0.35, 0.0, 0.0);
        let odometry = OdometryConfig::default();
        let cfg = RoomEkfConfig::new(odometry.clone(), mount);
        let x0 = RoomState::new(2.0, 1.5, 0.0, 5.45, 5.64);
        let p0 =
            RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(1e-6, 1e-6, 1e-4, 1e-6, 1e-6));
        let mut ekf = RoomEkf::new(cfg, x0, p0, Stamp::ZERO);
        // Rear wheels turning the robot on the spot at 1 rad/s.
        let per_m = f64::from(odometry.ticks_per_rev)
            / (std::f64::consts::TAU * odometry.wheel_radius_m[0]);
        let at = |t: f64| {
            let wheel = 0.5 * odometry.track_m * t;
            EncoderSample {
                stamp: Stamp::from_secs_f64(t),
                left_ticks: (-wheel * per_m).round() as i64,
                right_ticks: (wheel * per_m).round() as i64,
            }
        };
        for k in 0..=10 {
            ekf.odometry(at(0.02 * k as f64));
        }
        let truth = |t: f64| DVector::from_vec(vec![2.0, 1.5, t, 5.45, 5.64]);
        // Walls whose direction is loosely known (a short piece): one
        // taken at the wrong time would be let through and pull.
        let seen = |t: f64| {
            let (z, _) = observe(&truth(t), 0, &mount);
            Wall {
                covariance: Matrix2::new(1e-5, 0.0, 0.0, 1e-2),
                ..wall(z.x, z.y)
            }
        };
        let now = ekf.scan(Stamp::from_secs_f64(0.2), &[seen(0.2)], &[]);
        assert_eq!((now.used.len(), now.late), (1, false), "{now:?}");
        let before = ekf.at_last_scan().0.clone();
        let late = ekf.scan(Stamp::from_secs_f64(0.1), &[seen(0.1)], &[]);
        assert!(late.late && late.used.is_empty(), "{late:?}");
        assert_eq!(ekf.at_last_scan().0, &before);
        assert!((ekf.now().0[2] - 0.2).abs() < 1e-3, "{}", ekf.now().0);
    }
}
