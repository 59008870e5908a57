//! Synthetic range scans for tests and benches, independent of the
//! simulator: exact ray casting against segments and (moving) circles, with
//! range noise, the beam's footprint, and the sensor's own motion during the
//! sweep.
//!
//! The footprint is modelled by casting several sub-rays across the beam;
//! the echo comes from the nearest surface that catches enough of them (a
//! pulse laser reports the first strong echo), at the mean range of the
//! sub-rays it caught, so thin table legs look fatter, a flat wall is seen
//! without bias at any incidence, and a beam grazing a door frame reports
//! the frame or what lies behind it.

use nalgebra::{Point2, Vector2};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal};
use stucco_core::{LaserSpec, Pose2, Scan, Stamp, Twist2, wrap_angle};

/// A flat surface: the segment from `a` to `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// One end, m.
    pub a: Point2<f64>,
    /// The other end, m.
    pub b: Point2<f64>,
}

/// A round object: a person, a table leg, a column. It moves with constant
/// `velocity` (m/s) from `center` at the scan's stamp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circle {
    /// Centre at the scan's stamp, m.
    pub center: Point2<f64>,
    /// Radius, m.
    pub radius: f64,
    /// Velocity, m/s.
    pub velocity: Vector2<f64>,
}

/// What the laser can see.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct World {
    /// Flat surfaces.
    pub segments: Vec<Segment>,
    /// Round objects.
    pub circles: Vec<Circle>,
}

/// Distance along the ray `o + s·dir` (unit `dir`) to the first surface of
/// `world` at time `t_s`, if any.
pub fn cast_ray(world: &World, o: &Point2<f64>, dir: &Vector2<f64>, t_s: f64) -> Option<f64> {
    let mut best = f64::INFINITY;
    for seg in &world.segments {
        let e = seg.b - seg.a;
        let denom = dir.x * e.y - dir.y * e.x;
        if denom.abs() < 1e-12 {
            continue;
        }
        let w = seg.a - o;
        let s = (w.x * e.y - w.y * e.x) / denom;
        let u = (w.x * dir.y - w.y * dir.x) / denom;
        if s > 1e-9 && (0.0..=1.0).contains(&u) && s < best {
            best = s;
        }
    }
    for c in &world.circles {
        let centre = c.center + c.velocity * t_s;
        let w = centre - o;
        let proj = w.dot(dir);
        let perp2 = w.norm_squared() - proj * proj;
        let r2 = c.radius * c.radius;
        if perp2 > r2 {
            continue;
        }
        let s = proj - (r2 - perp2).sqrt();
        if s > 1e-9 && s < best {
            best = s;
        }
    }
    best.is_finite().then_some(best)
}

/// How the synthetic laser measures.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticLaser {
    /// The sensor.
    pub spec: LaserSpec,
    /// Sub-rays across the footprint (1: an ideal thin beam).
    pub sub_rays: usize,
    /// Add the sensor's range noise (off: exact ranges).
    pub noise: bool,
}

impl SyntheticLaser {
    /// The sensor with its footprint and noise.
    pub fn new(spec: LaserSpec) -> Self {
        SyntheticLaser {
            spec,
            sub_rays: 5,
            noise: true,
        }
    }

    /// One scan of `world` from a sensor at `pose` at the stamp, moving with
    /// body-frame `twist` during the sweep.
    pub fn scan(
        &self,
        world: &World,
        pose: &Pose2,
        twist: &Twist2,
        stamp: Stamp,
        rng: &mut impl Rng,
    ) -> Scan {
        let spec = &self.spec;
        let sweep = spec.sweep_duration_s();
        let noise = Normal::new(0.0, spec.range_sigma_m.max(1e-12)).ok();
        let k = self.sub_rays.max(1);
        let mut hits = Vec::with_capacity(k);
        let ranges = (0..spec.beams).map(|i| {
            let t = if spec.beams > 1 {
                sweep * i as f64 / (spec.beams - 1) as f64
            } else {
                0.0
            };
            let at = *pose * twist.displacement(t);
            let phi = at.theta + spec.beam_angle(i);
            hits.clear();
            for s in 0..k {
                let f = if k == 1 {
                    0.0
                } else {
                    s as f64 / (k - 1) as f64 - 0.5
                };
                let dir_angle = phi + f * spec.beam_width.per_m;
                let dir = Vector2::new(dir_angle.cos(), dir_angle.sin());
                let side = Vector2::new(-phi.sin(), phi.cos()) * (f * spec.beam_width.base_m);
                let o = at.position() + side;
                if let Some(r) = cast_ray(world, &o, &dir, t) {
                    hits.push(r);
                }
            }
            hits.sort_by(f64::total_cmp);
            // The first surface that catches at least a third of the footprint
            // (sub-ray ranges chained by gaps under 5 cm); its echo is their mean,
            // which for a flat surface is the range along the beam's axis.
            let need = k.div_ceil(3);
            let mut echo = None;
            let mut start = 0;
            for end in 1..=hits.len() {
                if end == hits.len() || hits[end] - hits[end - 1] >= 0.05 {
                    if end - start >= need {
                        echo = Some(hits[start..end].iter().sum::<f64>() / (end - start) as f64);
                        break;
                    }
                    start = end;
                }
            }
            match echo {
                Some(r) if self.noise => r + noise.map_or(0.0, |n| n.sample(rng)),
                Some(r) => r,
                None => f64::INFINITY,
            }
        });
        Scan::from_spec(spec, stamp, ranges.collect::<Vec<_>>())
    }
}

/// An opening in a wall of a synthetic room.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueOpening {
    /// Index of the room wall it is in.
    pub wall: usize,
    /// Centre of the opening on the wall's inner face, m.
    pub center: Point2<f64>,
    /// Width, m.
    pub width_m: f64,
    /// True when the opening is passable (an open door); false for a closed door.
    pub open: bool,
}

/// A synthetic rectangular room with what is in it, and its ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomScene {
    /// Everything the laser can see.
    pub world: World,
    /// Inner faces of the four walls as lines `n·p = d` in the world frame
    /// (normals pointing out of the room): `(d, γ)` for the walls at
    /// `x = 0`, `y = 0`, `x = width`, `y = depth` in that order.
    pub walls: [(f64, f64); 4],
    /// Room size along x and y, m.
    pub size_m: (f64, f64),
    /// Doors and other openings.
    pub openings: Vec<TrueOpening>,
}

impl RoomScene {
    /// The true wall `w` as seen from a sensor at `pose`: `(d, γ)`.
    pub fn wall_in_sensor_frame(&self, w: usize, pose: &Pose2) -> (f64, f64) {
        let (d, g) = self.walls[w];
        let n = Vector2::new(g.cos(), g.sin());
        (
            d - n.dot(&pose.position().coords),
            wrap_angle(g - pose.theta),
        )
    }

    /// Distance from `p` to the nearest wall, m (negative outside the room).
    pub fn clearance(&self, p: &Point2<f64>) -> f64 {
        let (w, h) = self.size_m;
        p.x.min(p.y).min(w - p.x).min(h - p.y)
    }
}

/// Clutter to put in a room.
#[derive(Clone, Debug, PartialEq)]
pub struct Clutter {
    /// People walking about (circles of 0.18–0.25 m at up to 1.4 m/s).
    pub people: usize,
    /// Tables: four legs of 3 cm radius at the corners of 1.6 × 0.8 m.
    pub tables: usize,
    /// Chairs: four legs of 1.5 cm radius on a 0.42 m square.
    pub chairs: usize,
    /// Radiators along the wall `y = 0`: boxes 6 cm deep, 4 cm off the wall,
    /// covering this fraction of its length, split in two.
    pub radiator_fraction: f64,
    /// People keep this far from `keep_clear`, m.
    pub clear_radius_m: f64,
    /// A point people and furniture keep clear of (the robot).
    pub keep_clear: Point2<f64>,
}

impl Default for Clutter {
    fn default() -> Self {
        Clutter {
            people: 12,
            tables: 2,
            chairs: 6,
            radiator_fraction: 0.4,
            clear_radius_m: 0.5,
            keep_clear: Point2::new(-100.0, -100.0),
        }
    }
}

/// Wall thickness of synthetic rooms, m: door frames have jambs this deep.
pub const WALL_THICKNESS_M: f64 = 0.15;

/// Builds a rectangular room `width × depth` with its corner at the origin,
/// the given openings cut into its walls (`(wall, offset of the opening's
/// start along the wall, width, open)`, walls numbered as in
/// [`RoomScene::walls`]), a space behind each opening whose far wall lies
/// `beyond_m` behind the wall (or nothing, when `None`: the beam finds no
/// echo), and `clutter` placed at random.
pub fn rectangular_room(
    width: f64,
    depth: f64,
    openings: &[(usize, f64, f64, bool)],
    beyond_m: Option<f64>,
    clutter: &Clutter,
    rng: &mut impl Rng,
) -> RoomScene {
    let corners = [
        Point2::new(0.0, depth),
        Point2::new(0.0, 0.0),
        Point2::new(width, 0.0),
        Point2::new(width, depth),
    ];
    // Wall w runs from corners[w] to corners[(w+1)%4]; outward normals.
    let normals = [
        Vector2::new(-1.0, 0.0),
        Vector2::new(0.0, -1.0),
        Vector2::new(1.0, 0.0),
        Vector2::new(0.0, 1.0),
    ];
    let mut world = World::default();
    let mut true_openings = Vec::new();
    for w in 0..4 {
        let a = corners[w];
        let b = corners[(w + 1) % 4];
        let len = (b - a).norm();
        let along = (b - a) / len;
        let n = normals[w];
        let mut cuts: Vec<(f64, f64, bool)> = openings
            .iter()
            .filter(|o| o.0 == w)
            .map(|o| (o.1.clamp(0.0, len), (o.1 + o.2).clamp(0.0, len), o.3))
            .collect();
        cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut start = 0.0;
        for &(s, e, open) in &cuts {
            world.segments.push(Segment {
                a: a + along * start,
                b: a + along * s,
            });
            let (pa, pb) = (a + along * s, a + along * e);
            // Jambs: the wall's thickness, seen through the opening.
            world.segments.push(Segment {
                a: pa,
                b: pa + n * WALL_THICKNESS_M,
            });
            world.segments.push(Segment {
                a: pb,
                b: pb + n * WALL_THICKNESS_M,
            });
            if open {
                if let Some(far) = beyond_m {
                    let back = n * (WALL_THICKNESS_M + far);
                    world.segments.push(Segment {
                        a: pa - along * 3.0 + back,
                        b: pb + along * 3.0 + back,
                    });
                }
            } else {
                // A closed door: its leaf sits 4 cm into the frame.
                world.segments.push(Segment {
                    a: pa + n * 0.04,
                    b: pb + n * 0.04,
                });
            }
            true_openings.push(TrueOpening {
                wall: w,
                center: Point2::from((pa.coords + pb.coords) / 2.0),
                width_m: e - s,
                open,
            });
            start = e;
        }
        world.segments.push(Segment {
            a: a + along * start,
            b,
        });
    }
    // Radiators along y = 0, split in two, 4 cm off the wall, 6 cm deep.
    if clutter.radiator_fraction > 0.0 {
        let each = width * clutter.radiator_fraction / 2.0;
        for x0 in [width * 0.15, width * 0.6] {
            let (y0, y1) = (0.04, 0.10);
            world.segments.push(Segment {
                a: Point2::new(x0, y1),
                b: Point2::new(x0 + each, y1),
            });
            world.segments.push(Segment {
                a: Point2::new(x0, y0),
                b: Point2::new(x0, y1),
            });
            world.segments.push(Segment {
                a: Point2::new(x0 + each, y0),
                b: Point2::new(x0 + each, y1),
            });
        }
    }
    let inside = |rng: &mut dyn FnMut() -> f64, margin: f64| {
        Point2::new(
            margin + rng() * (width - 2.0 * margin),
            margin + rng() * (depth - 2.0 * margin),
        )
    };
    let mut uniform = || rng.random::<f64>();
    let clear_of_robot =
        |p: &Point2<f64>, r: f64| (p - clutter.keep_clear).norm() > clutter.clear_radius_m + r;
    let furniture = |n: usize,
                     sx: f64,
                     sy: f64,
                     leg: f64,
                     world: &mut World,
                     uniform: &mut dyn FnMut() -> f64| {
        for _ in 0..n {
            for _ in 0..20 {
                let c = inside(uniform, 0.6);
                let heading = uniform() * std::f64::consts::PI;
                let pose = Pose2::new(c.x, c.y, heading);
                let legs: Vec<Point2<f64>> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .iter()
                    .map(|(fx, fy)| {
                        pose.transform_point(&Point2::new(
                            fx * (sx / 2.0 - 0.05),
                            fy * (sy / 2.0 - 0.05),
                        ))
                    })
                    .collect();
                if legs.iter().all(|l| {
                    clear_of_robot(l, leg)
                        && l.x > 0.1
                        && l.y > 0.15
                        && l.x < width - 0.1
                        && l.y < depth - 0.1
                }) {
                    world.circles.extend(legs.into_iter().map(|center| Circle {
                        center,
                        radius: leg,
                        velocity: Vector2::zeros(),
                    }));
                    break;
                }
            }
        }
    };
    furniture(clutter.tables, 1.6, 0.8, 0.03, &mut world, &mut uniform);
    furniture(clutter.chairs, 0.42, 0.42, 0.015, &mut world, &mut uniform);
    for _ in 0..clutter.people {
        for _ in 0..50 {
            let radius = 0.18 + 0.07 * uniform();
            let center = inside(&mut uniform, radius + 0.15);
            let heading = uniform() * std::f64::consts::TAU;
            let speed = 1.4 * uniform();
            let person = Circle {
                center,
                radius,
                velocity: Vector2::new(heading.cos(), heading.sin()) * speed,
            };
            let apart = world
                .circles
                .iter()
                .all(|c| (c.center - center).norm() > c.radius + radius + 0.05);
            if clear_of_robot(&center, radius) && apart {
                world.circles.push(person);
                break;
            }
        }
    }
    RoomScene {
        world,
        walls: [
            (0.0, std::f64::consts::PI),
            (0.0, -std::f64::consts::FRAC_PI_2),
            (width, 0.0),
            (depth, std::f64::consts::FRAC_PI_2),
        ],
        size_m: (width, depth),
        openings: true_openings,
    }
}

/// The reference room of the papers: 5.45 × 5.64 m, one open door (0.9 m,
/// in the wall `x = 5.45`), radiators 4 cm off the wall `y = 0` over 40% of
/// its length, two tables and six chairs on legs, `people` walking, all kept
/// `clear_radius_m` away from `robot`.
pub fn reference_room(robot: Point2<f64>, people: usize, rng: &mut impl Rng) -> RoomScene {
    let clutter = Clutter {
        people,
        keep_clear: robot,
        ..Clutter::default()
    };
    rectangular_room(5.45, 5.64, &[(2, 2.1, 0.9, true)], Some(3.0), &clutter, rng)
}

/// A pose drawn uniformly in the room, at least `margin_m` from every wall,
/// with any heading.
pub fn random_pose(size_m: (f64, f64), margin_m: f64, rng: &mut impl Rng) -> Pose2 {
    let (w, h) = size_m;
    Pose2::new(
        margin_m + rng.random::<f64>() * (w - 2.0 * margin_m),
        margin_m + rng.random::<f64>() * (h - 2.0 * margin_m),
        (rng.random::<f64>() * 2.0 - 1.0) * std::f64::consts::PI,
    )
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn rays_hit_segments_and_circles_at_the_right_range() {
        let world = World {
            segments: vec![Segment {
                a: Point2::new(3.0, -5.0),
                b: Point2::new(3.0, 5.0),
            }],
            circles: vec![Circle {
                center: Point2::new(0.0, 2.0),
                radius: 0.5,
                velocity: Vector2::new(1.0, 0.0),
            }],
        };
        let o = Point2::origin();
        assert_eq!(cast_ray(&world, &o, &Vector2::x(), 0.0), Some(3.0));
        assert_eq!(cast_ray(&world, &o, &Vector2::y(), 0.0), Some(1.5));
        // One second later the person has walked out of the beam.
        assert_eq!(cast_ray(&world, &o, &Vector2::y(), 1.0), None);
        assert_eq!(cast_ray(&world, &o, &-Vector2::x(), 0.0), None);
    }

    #[test]
    fn noiseless_scan_of_a_room_lands_on_its_walls() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let scene = rectangular_room(
            4.0,
            3.0,
            &[],
            None,
            &Clutter {
                people: 0,
                tables: 0,
                chairs: 0,
                radiator_fraction: 0.0,
                ..Clutter::default()
            },
            &mut rng,
        );
        let laser = SyntheticLaser {
            sub_rays: 1,
            noise: false,
            ..SyntheticLaser::new(LaserSpec::ibeo_ladar_2d())
        };
        let pose = Pose2::new(1.0, 1.0, 0.3);
        let scan = laser.scan(
            &scene.world,
            &pose,
            &Twist2::default(),
            Stamp::ZERO,
            &mut rng,
        );
        assert_eq!(scan.len(), 450);
        for b in scan.returns() {
            let p = pose.transform_point(&b.point());
            assert!(scene.clearance(&p).abs() < 1e-9, "{p:?} is not on a wall");
        }
    }
}
