//! Building a map of walls while moving (paper B): an EKF over the robot's
//! pose and every wall of the map, fed by the odometry and by the walls
//! found in each scan.
//!
//! - Prediction moves only the pose; its cost is linear in the map's size
//!   (the pose's rows of the covariance are turned, nothing else).
//! - Each scan's walls are classified against the map by the
//!   decision-directed classifier ([`crate::association`]); the matches
//!   update the filter in one stacked step, at a cost quadratic in the
//!   map's size (see `benches/map.rs`).
//! - A wall no map wall is near becomes a candidate; seen again in
//!   `confirm_scans` scans, long enough and well measured, it joins the
//!   state with its correlation to the pose.
//! - Two walls of the map that turn out to be one (the same line, their
//!   seen stretches meeting) are merged.
//! - A face with a parallel wall close behind it, seen across its own
//!   stretch from its free side, is marked [`WallRole::InFront`]: a
//!   table's legs in a row, a cabinet, a glass wall's frames (the "large
//!   false door" of paper A, corrected once the wall behind is seen).
//! - A line that lies along a wall of the map, close to it but a few
//!   degrees askew, is a fit across two surfaces (a wall and a shut
//!   door's leaf recessed in it, seen far off through a door; a bed's foot
//!   and the desk's legs past its end): it founds nothing until seen more
//!   often than the wall, and the wall it out-sights is marked
//!   [`WallRole::Across`]; one founded before a longer wall it lies along
//!   was mapped is marked once that wall is.

use nalgebra::{DMatrix, DVector, Matrix2, Matrix2x3, Matrix3, Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{Pose2, wrap_angle};

use crate::association::{Classifier, Decision, Pairing, stacked_covariance};
use crate::odometry::{Displacement, turned_covariance};
use crate::wall::Wall;
use crate::wall_map::{MapWall, WallId, WallMap, WallRole};

/// Widest angle at which a line close along a map wall is taken for a
/// fit across that wall and what stands before it, rad (beyond, it may be
/// another wall meeting it).
const ASKEW_MAX_RAD: f64 = 0.2;
/// Narrowest angle at which such a line is askew, rad: a face before a
/// wall is parallel to it, and a fitted line's angle strays by a few
/// tenths of a degree (1.5° is three times the least σ of a sighting's).
/// Lines fitted across a wall and the radiator before it, or a bed's foot
/// and the legs beside it, lie 2–3° askew.
const ASKEW_MIN_RAD: f64 = 0.026;
/// How far beyond the shallowest face before a wall such a line's ends
/// may lie from the wall, m.
const ASKEW_BAND_M: f64 = 0.15;

/// Settings of the map-building filter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WallMapConfig {
    /// Where the laser sits on the robot.
    pub laser_mount: Pose2,
    /// Least standard deviation of an observed wall's distance, m: the
    /// walls of a building are not perfectly straight, which a fit's own
    /// covariance does not know.
    pub min_sigma_d_m: f64,
    /// Least standard deviation of an observed wall's angle, rad.
    pub min_sigma_gamma_rad: f64,
    /// Squared Mahalanobis distance beyond which a pairing is not
    /// considered (13.8: 99.9 % for two degrees of freedom).
    pub gate_chi2: f64,
    /// Probability a pairing must reach to be accepted.
    pub accept_probability: f64,
    /// Density of "a new wall or clutter" in the space of `(d, γ)`, per
    /// m·rad.
    pub clutter_density: f64,
    /// Most joint assignments scored per scan.
    pub max_hypotheses: usize,
    /// Widest gap along a wall between its seen stretch and an observation
    /// of it, m (a door is narrower).
    pub max_gap_m: f64,
    /// Shortest observed stretch that may found a new wall, m.
    pub new_wall_min_length_m: f64,
    /// Fewest points of an observation that may found a new wall.
    pub new_wall_min_points: usize,
    /// Largest RMS residual of the fit of an observation that may found a
    /// new wall, m: one flat surface scatters by the laser's noise, a line
    /// fitted across two surfaces (a wall and a radiator before it, seen
    /// at a grazing angle) by more. Set from the laser (1.25 σ: a true
    /// wall of 15 echoes is refused in under 4% of its sightings, and only
    /// waits for the next); unbounded by default.
    pub new_wall_max_rms_m: f64,
    /// Scans a candidate must be seen in before it joins the map.
    pub confirm_scans: u32,
    /// Scans a candidate may go unseen before it is forgotten.
    pub candidate_lifetime_scans: u64,
    /// Walls closer than this in angle are parallel, rad.
    pub parallel_rad: f64,
    /// Squared Mahalanobis distance under which two map walls whose
    /// stretches meet are one.
    pub merge_chi2: f64,
    /// Scans that must see a wall behind a face before it is marked
    /// [`WallRole::InFront`].
    pub in_front_scans: u32,
    /// Shallowest a face may stand before a wall to be taken for something
    /// in front of it, m.
    pub in_front_min_depth_m: f64,
    /// Deepest a face may stand before a wall to be taken for something in
    /// front of it, m (the wall of the next room, seen through a door,
    /// stands further behind).
    pub in_front_depth_m: f64,
    /// How much of a face the wall behind it must be seen across, m.
    pub in_front_overlap_m: f64,
    /// Whether unknown walls join the map (false: localisation in a known
    /// map only).
    pub extend_map: bool,
}

impl Default for WallMapConfig {
    fn default() -> Self {
        WallMapConfig {
            laser_mount: Pose2::IDENTITY,
            min_sigma_d_m: 0.01,
            min_sigma_gamma_rad: 0.5f64.to_radians(),
            gate_chi2: 13.8,
            accept_probability: 0.95,
            clutter_density: 0.02,
            max_hypotheses: 1024,
            max_gap_m: 1.2,
            new_wall_min_length_m: 0.8,
            new_wall_min_points: 15,
            new_wall_max_rms_m: f64::INFINITY,
            confirm_scans: 3,
            candidate_lifetime_scans: 20,
            parallel_rad: 3f64.to_radians(),
            merge_chi2: 9.21,
            in_front_scans: 3,
            in_front_min_depth_m: 0.05,
            in_front_depth_m: 1.0,
            in_front_overlap_m: 0.3,
            extend_map: true,
        }
    }
}

/// What one scan did to the map.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MapUpdate {
    /// Observations matched, as (index among the scan's walls, map wall).
    pub matched: Vec<(usize, WallId)>,
    /// Observations discarded as doubtful.
    pub doubtful: Vec<usize>,
    /// Walls that joined the map.
    pub added: Vec<WallId>,
    /// Walls merged, as (kept, dropped).
    pub merged: Vec<(WallId, WallId)>,
    /// Walls found to stand in front of a wall by this scan.
    pub in_front: Vec<WallId>,
    /// Walls found to be fits across two surfaces by this scan: each lies
    /// askew along a longer wall, or a wall founded by this scan lies
    /// askew along it and has been seen more often.
    pub across: Vec<WallId>,
}

/// A wall seen but not yet in the map.
#[derive(Clone, Debug)]
struct Candidate {
    rho_m: f64,
    alpha_rad: f64,
    /// Covariance of `(ρ, α)` at the last sighting, from the pose's then
    /// and the observation's.
    covariance: Matrix2<f64>,
    extent_m: [f64; 2],
    sightings: u32,
    last_scan: u64,
}

/// The map-building EKF: state `(x, y, θ, ρ₁, α₁, …, ρₙ, αₙ)`.
#[derive(Clone, Debug)]
pub struct WallMapEkf {
    config: WallMapConfig,
    x: DVector<f64>,
    p: DMatrix<f64>,
    walls: Vec<MapWall>,
    candidates: Vec<Candidate>,
    next_id: WallId,
    scans: u64,
}

/// Row of wall `i`'s `(ρ, α)` in the state.
fn row(i: usize) -> usize {
    3 + 2 * i
}

impl WallMapEkf {
    /// An empty map, the robot at `pose` with covariance `pose_covariance`.
    pub fn new(config: WallMapConfig, pose: Pose2, pose_covariance: Matrix3<f64>) -> Self {
        let mut p = DMatrix::zeros(3, 3);
        p.fixed_view_mut::<3, 3>(0, 0).copy_from(&pose_covariance);
        WallMapEkf {
            config,
            x: DVector::from_column_slice(&[pose.x, pose.y, pose.theta]),
            p,
            walls: Vec::new(),
            candidates: Vec::new(),
            next_id: 0,
            scans: 0,
        }
    }

    /// A filter in a known `map` (each wall with its own covariance, their
    /// correlations forgotten), the robot at `pose`.
    pub fn in_map(
        config: WallMapConfig,
        map: &WallMap,
        pose: Pose2,
        pose_covariance: Matrix3<f64>,
    ) -> Self {
        let n = 3 + 2 * map.walls.len();
        let mut x = DVector::zeros(n);
        let mut p = DMatrix::zeros(n, n);
        x.fixed_rows_mut::<3>(0)
            .copy_from_slice(&[pose.x, pose.y, pose.theta]);
        p.fixed_view_mut::<3, 3>(0, 0).copy_from(&pose_covariance);
        for (i, w) in map.walls.iter().enumerate() {
            x[row(i)] = w.rho_m;
            x[row(i) + 1] = w.alpha_rad;
            p.fixed_view_mut::<2, 2>(row(i), row(i))
                .copy_from(&w.covariance);
        }
        WallMapEkf {
            config,
            x,
            p,
            walls: map.walls.clone(),
            candidates: Vec::new(),
            next_id: map.walls.iter().map(|w| w.id + 1).max().unwrap_or(0),
            scans: 0,
        }
    }

    /// The settings.
    pub fn config(&self) -> &WallMapConfig {
        &self.config
    }

    /// The robot's pose.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x[0], self.x[1], self.x[2])
    }

    /// The covariance of the robot's pose.
    pub fn pose_covariance(&self) -> Matrix3<f64> {
        self.p.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// The walls of the map.
    pub fn walls(&self) -> &[MapWall] {
        &self.walls
    }

    /// The full covariance of the state.
    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.p
    }

    /// The map as it stands, to be saved.
    pub fn map(&self) -> WallMap {
        WallMap {
            walls: self.walls.clone(),
            pose: self.pose(),
        }
    }

    /// Moves the robot by `d` (eq. 5–7 of paper A): the pose composed, its
    /// rows of the covariance turned, the walls untouched.
    pub fn predict(&mut self, d: &Displacement) {
        let th = self.x[2];
        let (s, c) = th.sin_cos();
        let dp = d.pose;
        self.x[0] += c * dp.x - s * dp.y;
        self.x[1] += s * dp.x + c * dp.y;
        self.x[2] = wrap_angle(th + dp.theta);
        let mut f = Matrix3::identity();
        f[(0, 2)] = -s * dp.x - c * dp.y;
        f[(1, 2)] = c * dp.x - s * dp.y;
        let n = self.x.len();
        let pose_pose = self.p.fixed_view::<3, 3>(0, 0).into_owned();
        let new_pose_pose = f * pose_pose * f.transpose() + turned_covariance(&d.covariance, th);
        self.p
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(0.5 * (new_pose_pose + new_pose_pose.transpose())));
        if n > 3 {
            let pose_map = f * self.p.view((0, 3), (3, n - 3));
            self.p.view_mut((0, 3), (3, n - 3)).copy_from(&pose_map);
            self.p
                .view_mut((3, 0), (n - 3, 3))
                .copy_from(&pose_map.transpose());
        }
    }

    /// The laser's pose, and the derivative of its position by the heading.
    fn laser(&self) -> (Pose2, Vector2<f64>) {
        let m = &self.config.laser_mount;
        let (s, c) = self.x[2].sin_cos();
        (
            Pose2::new(
                self.x[0] + c * m.x - s * m.y,
                self.x[1] + s * m.x + c * m.y,
                self.x[2] + m.theta,
            ),
            Vector2::new(-s * m.x - c * m.y, c * m.x - s * m.y),
        )
    }

    /// The pairing of observation `z` with map wall `i`, if the wall faces
    /// the laser and the observation lies along its seen stretch.
    fn pairing(&self, i: usize, z: &Wall, laser: &Pose2, dl: &Vector2<f64>) -> Option<Pairing> {
        let w = &self.walls[i];
        let (rho, alpha) = (self.x[row(i)], self.x[row(i) + 1]);
        let (s, c) = alpha.sin_cos();
        let d = rho - c * laser.x - s * laser.y;
        if d <= 0.0 {
            return None;
        }
        let [a, b] = z.ends.map(|e| w.along(&laser.transform_point(&e)));
        if w.gap_to(a, b) > self.config.max_gap_m {
            return None;
        }
        let gamma = wrap_angle(alpha - laser.theta);
        Some(Pairing {
            state_row: row(i),
            innovation: Vector2::new(z.d_m - d, wrap_angle(z.gamma_rad - gamma)),
            h_pose: Matrix2x3::new(-c, -s, -(c * dl.x + s * dl.y), 0.0, 0.0, -1.0),
            h_wall: Matrix2::new(1.0, s * laser.x - c * laser.y, 0.0, 1.0),
        })
    }

    /// The covariance of observation `z`, floored.
    fn noise(&self, z: &Wall) -> Matrix2<f64> {
        let mut r = z.covariance;
        r[(0, 0)] = r[(0, 0)].max(self.config.min_sigma_d_m.powi(2));
        r[(1, 1)] = r[(1, 1)].max(self.config.min_sigma_gamma_rad.powi(2));
        r
    }

    /// Applies the walls `seen` in one scan (in the laser's frame, taken at
    /// the pose the filter now holds).
    pub fn scan(&mut self, walls: &[Wall]) -> MapUpdate {
        self.scans += 1;
        let mut update = MapUpdate::default();
        let (laser, dl) = self.laser();
        // Pieces of one line (a wall broken by a door, by clutter before
        // it) are one observation: their errors are one error.
        let (seen, pieces) = self.join_pieces(walls);
        let seen = &seen[..];
        let mut candidates = self.candidates_of(seen, &laser, &dl);
        // An observation that bridges two map walls of one line (a wall
        // first seen in two pieces) joins them before it is classified.
        while let Some((keep, drop)) = self.bridged(&candidates) {
            update
                .merged
                .push((self.walls[keep].id, self.walls[drop].id));
            self.merge(keep, drop);
            candidates = self.candidates_of(seen, &laser, &dl);
        }
        let noise: Vec<Matrix2<f64>> = seen.iter().map(|z| self.noise(z)).collect();
        let classifier = Classifier {
            gate_chi2: self.config.gate_chi2,
            accept_probability: self.config.accept_probability,
            clutter_density: self.config.clutter_density,
            max_hypotheses: self.config.max_hypotheses,
        };
        let pairings: Vec<Vec<Pairing>> = candidates
            .iter()
            .map(|c| c.iter().map(|(_, p)| p.clone()).collect())
            .collect();
        let decisions = classifier.classify(&pairings, &noise, &self.p);
        let mut matched: Vec<(usize, usize)> = Vec::new();
        let mut unknown = Vec::new();
        for (j, d) in decisions.iter().enumerate() {
            match d {
                Decision::Match(k) => matched.push((j, candidates[j][*k].0)),
                Decision::Unknown => unknown.push(j),
                Decision::Doubtful => update.doubtful.extend(&pieces[j]),
            }
        }
        let set: Vec<(usize, &Pairing)> = matched
            .iter()
            .map(|&(j, i)| {
                let k = candidates[j].iter().position(|(w, _)| *w == i).unwrap_or(0);
                (j, &candidates[j][k].1)
            })
            .collect();
        self.correct(&set, &noise);
        let (laser, _) = self.laser();
        for &(j, i) in &matched {
            let w = &mut self.walls[i];
            let [a, b] = seen[j].ends.map(|e| w.along(&laser.transform_point(&e)));
            w.extent_m = [w.extent_m[0].min(a.min(b)), w.extent_m[1].max(a.max(b))];
            w.observations += 1;
            update.matched.extend(pieces[j].iter().map(|&k| (k, w.id)));
        }
        update.matched.sort_unstable();
        update.doubtful.sort_unstable();
        update.in_front = self.mark_in_front(&matched, &laser);
        if self.config.extend_map {
            for j in unknown {
                if let Some((id, outsighted)) = self.consider(&seen[j], &noise[j]) {
                    update.added.push(id);
                    update.across.extend(outsighted);
                }
            }
            self.candidates
                .retain(|c| self.scans - c.last_scan <= self.config.candidate_lifetime_scans);
        }
        let touched: Vec<WallId> = update
            .matched
            .iter()
            .map(|m| m.1)
            .chain(update.added.iter().copied())
            .collect();
        let merged = self.merge_around(&touched);
        update.merged.extend(merged);
        let across = self.mark_askew(&touched);
        update.across.extend(across);
        update
    }

    /// Marks [`WallRole::Across`] the building walls that lie askew along a
    /// longer wall of `touched`: lines fitted across that wall and what is
    /// recessed in it or stands before it, founded before the wall itself
    /// was mapped. They stay landmarks (the filter keeps them as they are);
    /// they bound no room.
    fn mark_askew(&mut self, touched: &[WallId]) -> Vec<WallId> {
        let mut marked = Vec::new();
        for &id in touched {
            let Some(a) = self.walls.iter().position(|w| w.id == id) else {
                continue;
            };
            if self.walls[a].role != WallRole::Wall {
                continue;
            }
            for b in 0..self.walls.len() {
                let (wall, v) = (&self.walls[a], &self.walls[b]);
                if b != a
                    && v.role == WallRole::Wall
                    && v.length_m() < wall.length_m()
                    && askew_along(&self.config, v.alpha_rad, &v.ends(), wall)
                {
                    self.walls[b].role = WallRole::Across;
                    marked.push(self.walls[b].id);
                }
            }
        }
        marked
    }

    /// The walls of one scan with the pieces of each line joined: each
    /// joined wall and the indices of its pieces. Pieces are joined when
    /// their lines agree within their noise; the joined line is their
    /// points-weighted mean, with the covariance of the best-measured piece
    /// (not less: their errors share the pose and the wall's own waviness).
    fn join_pieces(&self, walls: &[Wall]) -> (Vec<Wall>, Vec<Vec<usize>>) {
        let mut joined: Vec<Wall> = Vec::with_capacity(walls.len());
        let mut pieces: Vec<Vec<usize>> = Vec::with_capacity(walls.len());
        for (j, z) in walls.iter().enumerate() {
            let r = self.noise(z);
            let same = joined.iter().position(|w| {
                let delta = Vector2::new(w.d_m - z.d_m, wrap_angle(w.gamma_rad - z.gamma_rad));
                (self.noise(w) + r)
                    .try_inverse()
                    .is_some_and(|inv| delta.dot(&(inv * delta)) < self.config.merge_chi2)
            });
            match same {
                None => {
                    joined.push(z.clone());
                    pieces.push(vec![j]);
                }
                Some(k) => {
                    let w = &joined[k];
                    let (nw, nz) = (w.points as f64, z.points as f64);
                    let f = nz / (nw + nz);
                    let gamma = wrap_angle(w.gamma_rad + f * wrap_angle(z.gamma_rad - w.gamma_rad));
                    let dir = Vector2::new(-gamma.sin(), gamma.cos());
                    let ts: Vec<f64> = w
                        .ends
                        .iter()
                        .chain(&z.ends)
                        .map(|e| dir.dot(&e.coords))
                        .collect();
                    let lo = ts.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = ts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    let d = w.d_m + f * (z.d_m - w.d_m);
                    let foot = Vector2::new(gamma.cos(), gamma.sin()) * d;
                    let best = if z.points > w.points {
                        z.covariance
                    } else {
                        w.covariance
                    };
                    joined[k] = Wall {
                        d_m: d,
                        gamma_rad: gamma,
                        covariance: best,
                        points: w.points + z.points,
                        rms_residual_m: w.rms_residual_m.max(z.rms_residual_m),
                        ends: [Point2::from(foot + dir * lo), Point2::from(foot + dir * hi)],
                    };
                    pieces[k].push(j);
                }
            }
        }
        (joined, pieces)
    }

    /// The pairings of each of `seen` with the map's walls.
    fn candidates_of(
        &self,
        seen: &[Wall],
        laser: &Pose2,
        dl: &Vector2<f64>,
    ) -> Vec<Vec<(usize, Pairing)>> {
        seen.iter()
            .map(|z| {
                (0..self.walls.len())
                    .filter_map(|i| self.pairing(i, z, laser, dl).map(|p| (i, p)))
                    .collect()
            })
            .collect()
    }

    /// Two map walls that one observation could be, which are one line:
    /// (the better observed, the other).
    fn bridged(&self, candidates: &[Vec<(usize, Pairing)>]) -> Option<(usize, usize)> {
        for pairs in candidates {
            for (k, &(a, _)) in pairs.iter().enumerate() {
                for &(b, _) in &pairs[k + 1..] {
                    if wrap_angle(self.walls[a].alpha_rad - self.walls[b].alpha_rad).abs() < 0.2
                        && self.same_line_chi2(a, b) < self.config.merge_chi2
                    {
                        return Some(
                            if self.walls[a].observations >= self.walls[b].observations {
                                (a, b)
                            } else {
                                (b, a)
                            },
                        );
                    }
                }
            }
        }
        None
    }

    /// The EKF update with the stacked pairings of `set`.
    fn correct(&mut self, set: &[(usize, &Pairing)], noise: &[Matrix2<f64>]) {
        if set.is_empty() {
            return;
        }
        let n = self.x.len();
        let m = 2 * set.len();
        let s = stacked_covariance(set, noise, &self.p);
        let Some(chol) = s.cholesky() else {
            return;
        };
        // P Hᵀ, from the pose's and each matched wall's columns.
        let mut pht = DMatrix::zeros(n, m);
        for (k, (_, pr)) in set.iter().enumerate() {
            let cols = self.p.columns(0, 3) * pr.h_pose.transpose()
                + self.p.columns(pr.state_row, 2) * pr.h_wall.transpose();
            pht.columns_mut(2 * k, 2).copy_from(&cols);
        }
        let nu = DVector::from_iterator(
            m,
            set.iter().flat_map(|(_, p)| p.innovation.iter().copied()),
        );
        let gain_t = chol.solve(&pht.transpose()); // S⁻¹ H P = Kᵀ
        self.x += gain_t.transpose() * nu;
        self.p.gemm(-1.0, &pht, &gain_t, 1.0);
        symmetrize(&mut self.p);
        self.x[2] = wrap_angle(self.x[2]);
        for i in 0..self.walls.len() {
            self.x[row(i) + 1] = wrap_angle(self.x[row(i) + 1]);
            self.sync_wall(i);
        }
    }

    /// Copies wall `i`'s estimate from the state into its record.
    fn sync_wall(&mut self, i: usize) {
        let w = &mut self.walls[i];
        let (rho, alpha) = (self.x[row(i)], self.x[row(i) + 1]);
        // Keep the seen stretch where it was when the line turns or moves.
        let ends = w.ends();
        w.rho_m = rho;
        w.alpha_rad = alpha;
        let [a, b] = ends.map(|e| w.along(&e));
        w.extent_m = [a.min(b), a.max(b)];
        w.covariance = self.p.fixed_view::<2, 2>(row(i), row(i)).into_owned();
    }

    /// Marks the map walls that stand in front of a wall matched in this
    /// scan: parallel, facing the same way, less than `in_front_depth_m`
    /// before it, the laser on their free side, and the wall behind seen
    /// across their own seen stretch (past a table's legs, through a glass
    /// wall's frames, on both sides of a cabinet) and longer. A step in a
    /// wall, whose two parts only meet, is not marked; nor is a wall with
    /// something shorter recessed in it (a shut door's leaf).
    fn mark_in_front(&mut self, matched: &[(usize, usize)], laser: &Pose2) -> Vec<WallId> {
        let from = laser.position();
        let cfg = &self.config;
        let mut marked = Vec::new();
        for f in 0..self.walls.len() {
            let front = &self.walls[f];
            if front.role == WallRole::InFront || front.in_front(&from) <= 0.05 {
                continue;
            }
            let behind_it = matched.iter().any(|&(_, b)| {
                let behind = &self.walls[b];
                let depth = behind.rho_m - front.rho_m;
                b != f
                    && behind.length_m() > front.length_m()
                    && wrap_angle(behind.alpha_rad - front.alpha_rad).abs() < cfg.parallel_rad
                    && depth > cfg.in_front_min_depth_m
                    && depth < cfg.in_front_depth_m
                    && -front.gap_to(behind.extent_m[0], behind.extent_m[1])
                        > cfg.in_front_overlap_m
            });
            if behind_it {
                let w = &mut self.walls[f];
                w.wall_behind_scans += 1;
                if w.wall_behind_scans >= cfg.in_front_scans {
                    w.role = WallRole::InFront;
                    marked.push(w.id);
                }
            }
        }
        marked
    }

    /// The line of observation `z` in the map, and its Jacobians by the
    /// pose `(x, y, θ)` and by the observation `(d, γ)`.
    fn line_jacobians(&self, z: &Wall) -> (Matrix2x3<f64>, Matrix2<f64>, f64, f64) {
        let (laser, dl) = self.laser();
        let alpha = wrap_angle(z.gamma_rad + laser.theta);
        let (s, c) = alpha.sin_cos();
        let rho = z.d_m + c * laser.x + s * laser.y;
        let drho_dalpha = -s * laser.x + c * laser.y;
        let g_pose = Matrix2x3::new(c, s, c * dl.x + s * dl.y + drho_dalpha, 0.0, 0.0, 1.0);
        let g_obs = Matrix2::new(1.0, drho_dalpha, 0.0, 1.0);
        (g_pose, g_obs, rho, alpha)
    }

    /// The line of observation `z` (noise `r`) in the map: `(ρ, α)` and
    /// its covariance, from the pose's and the observation's.
    fn line_in_map(&self, z: &Wall, r: &Matrix2<f64>) -> (f64, f64, Matrix2<f64>) {
        let (g_pose, g_obs, rho, alpha) = self.line_jacobians(z);
        let covariance = g_pose * self.p.fixed_view::<3, 3>(0, 0) * g_pose.transpose()
            + g_obs * r * g_obs.transpose();
        (rho, alpha, covariance)
    }

    /// Tracks an observation no map wall is near; returns the new wall's id
    /// when it has been seen often enough to join the map, with the walls
    /// it lies askew along and has out-sighted, now marked
    /// [`WallRole::Across`] (see [`WallMapEkf::askew_rival`]).
    fn consider(&mut self, z: &Wall, r: &Matrix2<f64>) -> Option<(WallId, Vec<WallId>)> {
        if z.length_m() < self.config.new_wall_min_length_m
            || z.points < self.config.new_wall_min_points
            || z.rms_residual_m.is_nan()
            || z.rms_residual_m > self.config.new_wall_max_rms_m
        {
            return None;
        }
        let (rho, alpha, covariance) = self.line_in_map(z, r);
        let (s, c) = alpha.sin_cos();
        let (laser, _) = self.laser();
        let along = |p: &Point2<f64>| -s * p.x + c * p.y;
        let ends = z.ends.map(|e| laser.transform_point(&e));
        let [a, b] = ends.map(|e| along(&e));
        let (lo, hi) = (a.min(b), a.max(b));
        let rival = self.askew_rival(alpha, &ends);
        let cfg = &self.config;
        let scans = self.scans;
        // Sightings agree when their difference fits both uncertainties
        // (the pose's at each sighting and the observations').
        let agrees = |k: &Candidate| {
            let delta = Vector2::new(k.rho_m - rho, wrap_angle(k.alpha_rad - alpha));
            (k.covariance + covariance)
                .try_inverse()
                .is_some_and(|inv| delta.dot(&(inv * delta)) < cfg.gate_chi2)
        };
        let found = self.candidates.iter().position(|k| {
            agrees(k)
                && lo < k.extent_m[1] + cfg.max_gap_m
                && hi > k.extent_m[0] - cfg.max_gap_m
                && k.last_scan < scans
        });
        let k = match found {
            Some(k) => k,
            None => {
                self.candidates.push(Candidate {
                    rho_m: rho,
                    alpha_rad: alpha,
                    covariance,
                    extent_m: [lo, hi],
                    sightings: 1,
                    last_scan: scans,
                });
                return None;
            }
        };
        let c = &mut self.candidates[k];
        c.rho_m = rho;
        c.alpha_rad = alpha;
        c.covariance = covariance;
        c.extent_m = [c.extent_m[0].min(lo), c.extent_m[1].max(hi)];
        c.sightings += 1;
        c.last_scan = scans;
        if c.sightings < self.config.confirm_scans || rival.is_some_and(|o| c.sightings <= o) {
            return None;
        }
        let c = self.candidates.swap_remove(k);
        let mut outsighted = Vec::new();
        if rival.is_some() {
            let cfg = &self.config;
            for w in &mut self.walls {
                if w.role == WallRole::Wall && askew_along(cfg, alpha, &ends, w) {
                    w.role = WallRole::Across;
                    outsighted.push(w.id);
                }
            }
        }
        Some((self.augment(z, r, c.extent_m, c.sightings), outsighted))
    }

    /// Whether a stretch seen from `ends[0]` to `ends[1]` (map frame), at
    /// angle `alpha`, lies along a map wall's stretch, close to it, but at
    /// an angle no face before a wall stands at: walls that meet do so at
    /// their ends, and what stands before a wall (a radiator, a cabinet) is
    /// parallel to it. One of the two is a fit across two surfaces, and
    /// the one seen more often is taken for the surface. Such a line
    /// founds nothing until it is seen more often than the map's walls it
    /// lies askew along: returns the most observations of such a wall.
    /// Shorter, it is a fit across a wall and the radiator before it, seen
    /// far off through a door. Longer, it is either the wall the map holds
    /// a fit across (a shut door's leaf and its wall fitted as one from
    /// afar, founded before the wall was seen near, and seldom seen again:
    /// the wall soon outnumbers it and the fit is marked,
    /// [`WallMapEkf::mark_askew`]), or a fit across a face the map holds
    /// and what lies beyond it (a radiator and the wall past its end, a
    /// bed's foot and the legs of the desk beside it), which the face,
    /// seen from everywhere in the room, outnumbers. A line that does
    /// outnumber them is founded, and they are marked
    /// [`WallRole::Across`]: each was the fit across.
    fn askew_rival(&self, alpha: f64, ends: &[Point2<f64>; 2]) -> Option<u32> {
        self.walls
            .iter()
            .filter(|w| askew_along(&self.config, alpha, ends, w))
            .map(|w| w.observations)
            .max()
    }

    /// Adds the wall observed as `z` (noise `r`) to the state, correlated
    /// with the pose it was seen from, after `sightings` sightings.
    fn augment(
        &mut self,
        z: &Wall,
        r: &Matrix2<f64>,
        extent_m: [f64; 2],
        sightings: u32,
    ) -> WallId {
        let (rho, alpha, own) = self.line_in_map(z, r);
        let g_pose = self.line_jacobians(z).0;
        let n = self.x.len();
        let mut x = self.x.clone().resize_vertically(n + 2, 0.0);
        x[n] = rho;
        x[n + 1] = alpha;
        let mut p = self.p.clone().resize(n + 2, n + 2, 0.0);
        let cross = g_pose * self.p.rows(0, 3); // 2 × n
        p.view_mut((n, 0), (2, n)).copy_from(&cross);
        p.view_mut((0, n), (n, 2)).copy_from(&cross.transpose());
        p.fixed_view_mut::<2, 2>(n, n).copy_from(&own);
        self.x = x;
        self.p = p;
        let id = self.next_id;
        self.next_id += 1;
        self.walls.push(MapWall {
            id,
            rho_m: rho,
            alpha_rad: alpha,
            covariance: own,
            extent_m,
            observations: sightings,
            wall_behind_scans: 0,
            role: WallRole::Wall,
        });
        id
    }

    /// Merges each wall of `touched` with any map wall that is the same
    /// line and whose seen stretch meets it.
    fn merge_around(&mut self, touched: &[WallId]) -> Vec<(WallId, WallId)> {
        let mut merged = Vec::new();
        for &id in touched {
            let Some(a) = self.walls.iter().position(|w| w.id == id) else {
                continue;
            };
            let partner = (0..self.walls.len()).find(|&b| {
                let (wa, wb) = (&self.walls[a], &self.walls[b]);
                if b == a
                    || wrap_angle(wa.alpha_rad - wb.alpha_rad).abs() > 0.2
                    || wb.gap_to(wa.extent_m[0], wa.extent_m[1]) > self.config.max_gap_m
                {
                    return false;
                }
                self.same_line_chi2(a, b) < self.config.merge_chi2
            });
            if let Some(b) = partner {
                let (keep, drop) = if self.walls[a].observations >= self.walls[b].observations {
                    (a, b)
                } else {
                    (b, a)
                };
                merged.push((self.walls[keep].id, self.walls[drop].id));
                self.merge(keep, drop);
            }
        }
        merged
    }

    /// Squared Mahalanobis distance of the difference of walls `a` and `b`.
    fn same_line_chi2(&self, a: usize, b: usize) -> f64 {
        let (ra, rb) = (row(a), row(b));
        let delta = Vector2::new(
            self.x[ra] - self.x[rb],
            wrap_angle(self.x[ra + 1] - self.x[rb + 1]),
        );
        let c = self.p.fixed_view::<2, 2>(ra, ra) + self.p.fixed_view::<2, 2>(rb, rb)
            - self.p.fixed_view::<2, 2>(ra, rb)
            - self.p.fixed_view::<2, 2>(rb, ra);
        c.try_inverse()
            .map_or(f64::INFINITY, |inv| delta.dot(&(inv * delta)))
    }

    /// Makes wall `drop` equal to `keep` (a constraint observed exactly),
    /// then removes it from the state.
    fn merge(&mut self, keep: usize, drop: usize) {
        let (rk, rd) = (row(keep), row(drop));
        let nu = Vector2::new(
            self.x[rd] - self.x[rk],
            wrap_angle(self.x[rd + 1] - self.x[rk + 1]),
        );
        // h = x_drop − x_keep, observed as 0 with a tiny noise.
        let pht = self.p.columns(rd, 2) - self.p.columns(rk, 2); // n × 2
        let s = pht.rows(rd, 2) - pht.rows(rk, 2) + Matrix2::identity() * 1e-12;
        if let Some(inv) = s.try_inverse() {
            let gain = &pht * inv;
            self.x -= &gain * nu;
            self.p.gemm(-1.0, &gain, &pht.transpose(), 1.0);
            symmetrize(&mut self.p);
        }
        let ends = self.walls[drop].ends();
        let keep_id = self.walls[keep].id;
        let kept = self.walls[drop].observations;
        let through = self.walls[drop].wall_behind_scans;
        self.remove(drop);
        let keep = self.walls.iter().position(|w| w.id == keep_id).unwrap_or(0);
        let w = &mut self.walls[keep];
        let [a, b] = ends.map(|e| w.along(&e));
        w.extent_m = [w.extent_m[0].min(a.min(b)), w.extent_m[1].max(a.max(b))];
        w.observations += kept;
        w.wall_behind_scans = w.wall_behind_scans.max(through);
    }

    /// Removes wall `i` from the state (marginalises it out: its rows and
    /// columns go).
    fn remove(&mut self, i: usize) {
        let r = row(i);
        let n = self.x.len();
        let order: Vec<usize> = (0..n).filter(|&k| k != r && k != r + 1).collect();
        self.x = DVector::from_iterator(order.len(), order.iter().map(|&k| self.x[k]));
        self.p = self.p.select_rows(&order).select_columns(&order);
        self.walls.remove(i);
        for k in 0..self.walls.len() {
            self.sync_wall(k);
        }
    }
}

/// Whether a stretch seen from `ends[0]` to `ends[1]` (map frame), at
/// angle `alpha`, lies along `wall`'s stretch, close to it, but at an angle
/// no face before a wall stands at (see [`WallMapEkf::askew_rival`]).
fn askew_along(cfg: &WallMapConfig, alpha: f64, ends: &[Point2<f64>; 2], wall: &MapWall) -> bool {
    let angle = wrap_angle(alpha - wall.alpha_rad).abs();
    if !(ASKEW_MIN_RAD..=ASKEW_MAX_RAD).contains(&angle) {
        return false;
    }
    let near = ends
        .iter()
        .all(|e| wall.in_front(e).abs() < cfg.in_front_min_depth_m + ASKEW_BAND_M);
    let [ta, tb] = ends.map(|e| wall.along(&e));
    let overlap = ta.max(tb).min(wall.extent_m[1]) - ta.min(tb).max(wall.extent_m[0]);
    near && overlap > cfg.in_front_overlap_m
}

/// Makes `p` exactly symmetric, in place (rounding leaves the update's two
/// halves apart in the last bits).
fn symmetrize(p: &mut DMatrix<f64>) {
    let n = p.nrows();
    for j in 0..n {
        for i in j + 1..n {
            let m = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = m;
            p[(j, i)] = m;
        }
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests;
