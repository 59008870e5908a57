//! The scanning laser and the range camera, cast through rapier's query
//! pipeline, and the faults a configuration can inject.

use crate::plane::{PlaneCaster, ray_circle};
use crate::scene::{GLASS, Scene};
use nalgebra::{Point2, Vector2};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal};
use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};
use stucco_core::{CameraSpec, LaserSpec, Pose2, RangeProfile, Scan, Stamp, Twist2};

/// Glass returns the laser only this close to normal incidence, rad (10°).
const GLASS_MAX_INCIDENCE_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// Sub-rays across the footprint of a beam that straddles an edge.
const SUB_RAYS: usize = 5;
/// Two echoes closer than this along a beam come from one surface, m.
const SAME_SURFACE_M: f64 = 0.05;

/// Faults injected into the sensors.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FaultConfig {
    /// Chance that a whole scan is lost.
    pub scan_drop_probability: f64,
    /// Chance that a beam returns a spurious echo short of the true range.
    pub spurious_return_probability: f64,
    /// Scans reach the robot this late, s.
    pub scan_delay_s: f64,
    /// An encoder that stops counting for a while.
    pub stuck_encoder: Option<StuckEncoder>,
    /// A drive motor that gives no traction for a while: the commanded
    /// speed has no effect and the robot rolls to a stop.
    pub stalled_drive: Option<Interval>,
    /// A steering that holds its angle for a while, whatever is commanded.
    pub stuck_steering: Option<Interval>,
}

/// A stretch of simulated time, `[from_s, until_s)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interval {
    /// Start, s.
    pub from_s: f64,
    /// End, s.
    pub until_s: f64,
}

impl Interval {
    /// True when `t_s` falls in it.
    pub fn contains(&self, t_s: f64) -> bool {
        (self.from_s..self.until_s).contains(&t_s)
    }
}

/// An encoder wheel whose counter freezes from `from_s` to `until_s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StuckEncoder {
    /// 0: left, 1: right.
    pub wheel: usize,
    /// Start of the fault, s.
    pub from_s: f64,
    /// End of the fault, s.
    pub until_s: f64,
}

fn v3(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as Real, y as Real, z as Real)
}

/// The first surface along a ray that returns the light: glass only near
/// normal incidence; people where they are now. `None`: nothing within
/// `max_m`. Cast through the scene's [`SpaceCaster`](crate::SpaceCaster).
pub fn cast(scene: &Scene, origin: [f64; 3], dir: [f64; 3], max_m: f64) -> Option<f64> {
    let person = nearest_person(scene, origin, dir);
    let fixed = scene.space.cast(
        origin,
        dir,
        max_m.min(person),
        GLASS_MAX_INCIDENCE_RAD.cos(),
    );
    fixed.or(person.is_finite().then_some(person))
}

fn nearest_person(scene: &Scene, origin: [f64; 3], dir: [f64; 3]) -> f64 {
    scene
        .bodies
        .iter()
        .filter_map(|b| b.cast(origin, dir))
        .fold(f64::INFINITY, f64::min)
}

/// [`cast`] through rapier's query pipeline, as the cameras were cast
/// until the [`SpaceCaster`](crate::SpaceCaster): kept to check it against
/// and as the benches' baseline.
pub fn cast_rapier(scene: &Scene, origin: [f64; 3], dir: [f64; 3], max_m: f64) -> Option<f64> {
    let person = nearest_person(scene, origin, dir);
    let max_m = max_m.min(person);
    let mut from = 0.0;
    let mut skip: Option<ColliderHandle> = None;
    for _ in 0..4 {
        let mut filter = QueryFilter::default();
        if let Some(s) = skip {
            filter = filter.exclude_collider(s);
        }
        let q = scene.world.query_pipeline_with_filter(filter);
        let o = v3(
            origin[0] + dir[0] * from,
            origin[1] + dir[1] * from,
            origin[2] + dir[2] * from,
        );
        let ray = Ray::new(o, v3(dir[0], dir[1], dir[2]));
        let Some((handle, hit)) = q.cast_ray_and_get_normal(&ray, (max_m - from) as Real, true)
        else {
            return person.is_finite().then_some(person);
        };
        let range = from + f64::from(hit.time_of_impact);
        let glass = scene
            .world
            .colliders
            .get(handle)
            .is_some_and(|c| c.user_data == GLASS);
        if !glass {
            return Some(range);
        }
        let n = hit.normal;
        let cos_inc =
            -(f64::from(n.x) * dir[0] + f64::from(n.y) * dir[1] + f64::from(n.z) * dir[2]);
        if cos_inc.abs() >= GLASS_MAX_INCIDENCE_RAD.cos() {
            return Some(range);
        }
        from = range;
        skip = Some(handle);
    }
    person.is_finite().then_some(person)
}

/// The laser: beams cast one by one at their own time during the sweep,
/// in the plane of its scan: the static world through a [`PlaneCaster`],
/// the people's legs where they are.
#[derive(Clone, Debug)]
pub struct LaserRig {
    plane: PlaneCaster,
    legs: Vec<(Point2<f64>, f64)>,
    /// Cosine and sine of each beam's bearing in the sensor frame.
    bearings: Vec<[f64; 2]>,
    spec: LaserSpec,
    mount: Pose2,
    period_ns: i64,
    /// Start of the scan under way, ns.
    scan_start_ns: i64,
    ranges: Vec<f64>,
}

impl LaserRig {
    /// A laser of `spec` at `mount` on the robot, scanning the plane whose
    /// static solids `plane` holds.
    pub fn new(spec: LaserSpec, mount: Pose2, plane: PlaneCaster) -> Self {
        let period_ns = (1e9 / spec.rate_hz.max(1e-6)).round() as i64;
        LaserRig {
            plane,
            legs: Vec::new(),
            bearings: (0..spec.beams)
                .map(|i| {
                    let (s, c) = spec.beam_angle(i).sin_cos();
                    [c, s]
                })
                .collect(),
            ranges: Vec::with_capacity(spec.beams),
            spec,
            mount,
            period_ns,
            scan_start_ns: 0,
        }
    }

    fn beam_time_ns(&self, i: usize) -> i64 {
        let n = self.spec.beams.max(2) - 1;
        self.scan_start_ns
            + (self.spec.sweep_duration_s() * 1e9 * i as f64 / n as f64).round() as i64
    }

    /// Casts the beams due in `[t0, t1)` from a robot at `pose0` at `t0`
    /// moving with `twist`; returns the scans completed.
    #[allow(clippy::too_many_arguments)]
    pub fn sweep(
        &mut self,
        scene: &Scene,
        t0_ns: i64,
        t1_ns: i64,
        pose0: &Pose2,
        twist: &Twist2,
        faults: &FaultConfig,
        rng: &mut impl Rng,
    ) -> Vec<Scan> {
        let mut done = Vec::new();
        let noise = Normal::new(0.0, self.spec.range_sigma_m.max(1e-12)).ok();
        self.legs.clear();
        self.legs.extend(scene.legs());
        // The sensor's pose at the step's start and its velocity in the
        // world: within one physics step (10 ms) its arc is a straight line
        // to within micrometres.
        let start = *pose0 * self.mount;
        let step_s = (t1_ns - t0_ns) as f64 * 1e-9;
        let end = *pose0 * twist.displacement(step_s) * self.mount;
        let (vx, vy, w) = (
            (end.x - start.x) / step_s,
            (end.y - start.y) / step_s,
            twist.omega_radps,
        );
        let (s0, c0) = start.theta.sin_cos();
        loop {
            let i = self.ranges.len();
            let t = self.beam_time_ns(i);
            if t >= t1_ns {
                break;
            }
            let tau = (t - t0_ns) as f64 * 1e-9;
            let sensor = Pose2 {
                x: start.x + vx * tau,
                y: start.y + vy * tau,
                theta: start.theta + w * tau,
            };
            let phi = sensor.theta + self.spec.beam_angle(i);
            // The beam's direction without a sine per beam: the beam's own
            // bearing (tabled) turned by the sensor's heading at the step's
            // start and by the few milliradians it turned since (series).
            let x = w * tau;
            let (sx, cx) = (x - x * x * x / 6.0, 1.0 - x * x / 2.0);
            let [cb, sb] = self.bearings[i];
            let (cs, ss) = (cb * cx - sb * sx, sb * cx + cb * sx);
            let dir = Vector2::new(cs * c0 - ss * s0, ss * c0 + cs * s0);
            let mut r = self.ray_dir(sensor.position(), dir);
            if let Some(prev) = self.ranges.last().copied() {
                let edge = match (prev.is_finite(), r) {
                    (true, Some(x)) => (x - prev).abs() > SAME_SURFACE_M,
                    (false, None) => false,
                    _ => true,
                };
                if edge {
                    r = self.footprint_echo(&sensor, phi);
                }
            }
            let mut range = match r {
                Some(x) => x + noise.map_or(0.0, |n| n.sample(rng)),
                None => f64::INFINITY,
            };
            if faults.spurious_return_probability > 0.0
                && rng.random::<f64>() < faults.spurious_return_probability
            {
                let far = if range.is_finite() {
                    range
                } else {
                    self.spec.max_range_m
                };
                range = self.spec.min_range_m
                    + rng.random::<f64>() * (far - self.spec.min_range_m).max(0.0);
            }
            // Raw ranges are kept (finite or not) for edge tests; Scan::new
            // marks what the sensor cannot report.
            self.ranges.push(range);
            if self.ranges.len() == self.spec.beams {
                let stamp = Stamp::from_nanos(self.scan_start_ns);
                let scan = Scan::from_spec(&self.spec, stamp, self.ranges.drain(..));
                if !(faults.scan_drop_probability > 0.0
                    && rng.random::<f64>() < faults.scan_drop_probability)
                {
                    done.push(scan);
                }
                self.scan_start_ns += self.period_ns;
            }
        }
        done
    }

    /// The nearest surface along a horizontal ray from `o` in direction `a`.
    fn ray(&self, o: Point2<f64>, a: f64) -> Option<f64> {
        self.ray_dir(o, Vector2::new(a.cos(), a.sin()))
    }

    /// The nearest surface along a horizontal ray from `o` along unit `d`.
    fn ray_dir(&self, o: Point2<f64>, d: Vector2<f64>) -> Option<f64> {
        let max = self.spec.max_range_m;
        let fixed = self.plane.cast(&o, &d, max);
        self.legs
            .iter()
            .filter_map(|(c, r)| ray_circle(&o, &d, c, *r))
            .chain(fixed)
            .filter(|&s| s < max)
            .min_by(f64::total_cmp)
    }

    /// The echo of a beam whose footprint may straddle an edge: sub-rays
    /// across it, and the first surface that catches a third of them (a
    /// pulse laser reports the first strong echo), at their mean range.
    fn footprint_echo(&self, sensor: &Pose2, phi: f64) -> Option<f64> {
        let w = &self.spec.beam_width;
        let mut hits: Vec<f64> = (0..SUB_RAYS)
            .filter_map(|s| {
                let f = s as f64 / (SUB_RAYS - 1) as f64 - 0.5;
                let a = phi + f * w.per_m;
                let side = f * w.base_m;
                let o = Point2::new(sensor.x - phi.sin() * side, sensor.y + phi.cos() * side);
                self.ray(o, a)
            })
            .collect();
        hits.sort_by(f64::total_cmp);
        let need = SUB_RAYS.div_ceil(3);
        let mut start = 0;
        for end in 1..=hits.len() {
            if end == hits.len() || hits[end] - hits[end - 1] >= SAME_SURFACE_M {
                if end - start >= need {
                    return Some(hits[start..end].iter().sum::<f64>() / (end - start) as f64);
                }
                start = end;
            }
        }
        None
    }
}

/// The range camera: one profile at a time, each taken at an instant.
#[derive(Clone, Debug)]
pub struct CameraRig {
    spec: CameraSpec,
    period_ns: i64,
    next_ns: i64,
}

impl CameraRig {
    /// A camera of `spec`.
    pub fn new(spec: CameraSpec) -> Self {
        CameraRig {
            period_ns: (1e9 / spec.rate_hz.max(1e-6)).round() as i64,
            next_ns: 0,
            spec,
        }
    }

    /// Its spec.
    pub fn spec(&self) -> &CameraSpec {
        &self.spec
    }

    /// The profiles due in the physics step from `t0_ns` to `t1_ns`, each
    /// shot from where the robot is at its stamp: at `pose0` when the step
    /// began, moving at `twist`; the sensor at `origin_m` in the robot's
    /// frame.
    #[allow(clippy::too_many_arguments)]
    pub fn shoot(
        &mut self,
        scene: &Scene,
        t0_ns: i64,
        t1_ns: i64,
        pose0: &Pose2,
        twist: &Twist2,
        origin_m: [f64; 3],
        rng: &mut impl Rng,
    ) -> Vec<RangeProfile> {
        let mut out = Vec::new();
        let noise = Normal::new(0.0, self.spec.range_sigma_m.max(1e-12)).ok();
        while self.next_ns < t1_ns {
            let tau_s = (self.next_ns - t0_ns).max(0) as f64 * 1e-9;
            let pose = *pose0 * twist.displacement(tau_s);
            let at = pose.transform_point(&nalgebra::Point2::new(origin_m[0], origin_m[1]));
            let s = &self.spec;
            let az = pose.theta + s.azimuth_rad;
            let n = s.rays.max(2);
            let elevations: Vec<f64> = (0..n)
                .map(|i| {
                    s.elevation_rad[0]
                        + (s.elevation_rad[1] - s.elevation_rad[0]) * i as f64 / (n - 1) as f64
                })
                .collect();
            let ranges = elevations
                .iter()
                .map(|&el| {
                    let dir = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
                    let caster = if scene.rapier_cameras {
                        cast_rapier
                    } else {
                        cast
                    };
                    match caster(scene, [at.x, at.y, origin_m[2]], dir, s.max_range_m) {
                        Some(r) => r + noise.map_or(0.0, |n| n.sample(rng)),
                        None => f64::INFINITY,
                    }
                })
                .collect();
            out.push(RangeProfile {
                stamp: Stamp::from_nanos(self.next_ns),
                sensor: s.name.clone(),
                origin_m,
                azimuth_rad: s.azimuth_rad,
                elevations_rad: elevations,
                ranges_m: ranges,
            });
            self.next_ns += self.period_ns;
        }
        out
    }
}
