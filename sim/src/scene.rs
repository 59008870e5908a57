//! The rapier3d world of a layout: static colliders for every solid, in
//! one bounding-volume tree that is built once and never stepped; the
//! robot's footprint is shape-cast against it. People walk outside it, as
//! upright cylinders (two legs and a torso) that the sensors and the
//! collision check meet where they are at the moment: moving them inside
//! rapier would refit its tree at every step, a third of the simulator's
//! time for a handful of people. The z axis points up.

use crate::layout::{LEG_HALF_SPACING_M, LEG_RADIUS_M, Layout, Material, Solid};
use crate::world::PersonSpec;
use nalgebra::Point2;
use rand::{Rng, RngExt};
use rapier3d::parry::query::ShapeCastOptions;
use rapier3d::parry::shape::Cuboid;
use rapier3d::prelude::*;
use std::f64::consts::FRAC_PI_2;
use stucco_core::{Pose2, VehicleSpec};

/// `user_data` of glass colliders.
pub const GLASS: u128 = 1;

/// Height of a person's legs, m; their torso is above.
const LEG_HEIGHT_M: f64 = 0.85;
/// Radius of a person's torso, m.
const TORSO_RADIUS_M: f64 = 0.18;
/// Top of a person, m.
const PERSON_HEIGHT_M: f64 = 1.7;
/// The robot's body clears the floor by this much, m.
const GROUND_CLEARANCE_M: f64 = 0.05;

/// An upright cylinder: centre of its footprint, radius, bottom and top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Upright {
    /// Centre, m.
    pub at: Point2<f64>,
    /// Radius, m.
    pub radius: f64,
    /// Bottom and top, m.
    pub z: [f64; 2],
}

impl Upright {
    /// Distance along the unit ray `o + s·d` to this cylinder, if hit.
    pub fn cast(&self, o: [f64; 3], d: [f64; 3]) -> Option<f64> {
        let (wx, wy) = (self.at.x - o[0], self.at.y - o[1]);
        let r2 = self.radius * self.radius;
        // The ray's horizontal part, squared.
        let h2 = d[0] * d[0] + d[1] * d[1];
        let mut best = f64::INFINITY;
        if h2 > 1e-24 {
            // In plan the ray's line passes wide of the circle: it meets
            // neither the side nor the caps.
            let cross = wx * d[1] - wy * d[0];
            if cross * cross > r2 * h2 {
                return None;
            }
            // The side: |o + s·d − at|² = r² in plan, the nearer root.
            let proj = wx * d[0] + wy * d[1];
            let disc = proj * proj - h2 * (wx * wx + wy * wy - r2);
            if disc >= 0.0 {
                let s = (proj - disc.sqrt()) / h2;
                let z = o[2] + d[2] * s;
                if s > 1e-9 && (self.z[0]..=self.z[1]).contains(&z) {
                    best = s;
                }
            }
        }
        // The caps.
        if d[2].abs() > 1e-12 {
            for zc in self.z {
                let s = (zc - o[2]) / d[2];
                if s > 1e-9 && s < best {
                    let (x, y) = (o[0] + d[0] * s - self.at.x, o[1] + d[1] * s - self.at.y);
                    if x * x + y * y <= r2 {
                        best = s;
                    }
                }
            }
        }
        best.is_finite().then_some(best)
    }
}

/// A person walking a closed path, who waits rather than walk into the
/// robot.
#[derive(Clone, Debug)]
pub struct Walker {
    path: Vec<[f64; 2]>,
    speed_mps: f64,
    /// Where along the loop the person was at time zero, m.
    phase_m: f64,
    loop_m: f64,
    /// How far the person has walked, m (back along the path counts
    /// against).
    walked_m: f64,
    /// The time of the last step, s.
    t_s: f64,
    /// Walking along the path (1) or back along it (-1).
    way: f64,
    /// How long they have been waiting for the robot, s.
    waited_s: f64,
    /// How far they stand off their path, stepped out of the robot's way,
    /// m (room frame).
    aside: nalgebra::Vector2<f64>,
    /// How long they have stood aside with the robot still near, s.
    aside_s: f64,
}

/// A person walking toward the robot stops this far from its body (the
/// middle of their stride from the body's outline), m.
const YIELD_M: f64 = 0.45;
/// After waiting this long for the robot, a person turns back, s.
const TURN_BACK_S: f64 = 4.0;
/// A robot whose body comes nearer a person than this has come at them
/// (they never walk so near it): they step out of its way, m.
const MAKE_WAY_M: f64 = 0.3;
/// Stepped out of the robot's way, a person goes back to their path once
/// the robot's body is this far off, m.
const BACK_TO_PATH_M: f64 = 1.0;
/// The bearings a person may step out of the robot's way on.
const MAKE_WAY_BEARINGS: usize = 16;
/// Stood aside this long with the robot still near, a person walks on
/// beside their path, the way along it that leads off the robot, s.
const WALK_ON_S: f64 = 4.0;

impl Walker {
    /// The person's legs and torso where they are now.
    pub fn body(&self) -> [Upright; 3] {
        let p = self.pose();
        let leg = |side: f64| Upright {
            at: p.transform_point(&Point2::new(0.0, side * LEG_HALF_SPACING_M)),
            radius: LEG_RADIUS_M,
            z: [0.0, LEG_HEIGHT_M],
        };
        [
            leg(-1.0),
            leg(1.0),
            Upright {
                at: p.position(),
                radius: TORSO_RADIUS_M,
                z: [LEG_HEIGHT_M, PERSON_HEIGHT_M],
            },
        ]
    }

    /// Position and heading now.
    pub fn pose(&self) -> Pose2 {
        let p = self.pose_along(self.walked_m);
        let p = Pose2::new(p.x + self.aside.x, p.y + self.aside.y, p.theta);
        if self.way < 0.0 {
            Pose2::new(p.x, p.y, p.theta + std::f64::consts::PI)
        } else {
            p
        }
    }

    /// Walks on to `t_s`, unless that would bring them within `YIELD_M`
    /// of the robot's body (`robot`: its outline's centre, half extents
    /// and heading), nearer than they are: then they wait. A robot that
    /// comes at them nearer than [`MAKE_WAY_M`] (backing, it does not see
    /// them) they step away from, where `free` (a place a person may stand
    /// on) lets them, and they go back to their path once it is
    /// [`BACK_TO_PATH_M`] off. Stood aside [`WALK_ON_S`] with the robot
    /// still near (it waits for them: they stand in its field), they walk
    /// on beside their path, whichever way along it takes them off the
    /// robot, as people do: standing by it, someone who stepped aside in a
    /// hall held a robot there until its task failed.
    fn walk_to(
        &mut self,
        t_s: f64,
        robot: Option<(Point2<f64>, [f64; 2], f64)>,
        free: impl Fn(&Point2<f64>) -> bool,
    ) {
        let dt = (t_s - self.t_s).max(0.0);
        let next = self.walked_m + self.way * self.speed_mps * dt;
        self.t_s = t_s;
        if let Some((centre, half, heading)) = robot {
            let frame = Pose2::new(centre.x, centre.y, heading).inverse();
            let gap_at = |p: &Point2<f64>| {
                let q = frame.transform_point(p);
                let (dx, dy) = (
                    (q.x.abs() - half[0]).max(0.0),
                    (q.y.abs() - half[1]).max(0.0),
                );
                dx.hypot(dy)
            };
            let gap = |p: &Pose2| gap_at(&p.position());
            let here = self.pose().position();
            let step = self.speed_mps * dt;
            if gap_at(&here) < MAKE_WAY_M {
                // The step that takes them furthest from the body.
                let away = (0..MAKE_WAY_BEARINGS)
                    .map(|k| {
                        let a = std::f64::consts::TAU * k as f64 / MAKE_WAY_BEARINGS as f64;
                        nalgebra::Vector2::new(a.cos(), a.sin()) * step
                    })
                    .filter(|d| free(&(here + d)))
                    .map(|d| (gap_at(&(here + d)), d))
                    .max_by(|a, b| a.0.total_cmp(&b.0));
                if let Some((further, d)) = away
                    && further > gap_at(&here)
                {
                    self.aside += d;
                }
                return;
            }
            if self.aside.norm() > 0.0 {
                // Back to the path once the robot is off, straight.
                let back = self.aside.norm().min(step);
                let to = here - self.aside.normalize() * back;
                if gap_at(&here) >= BACK_TO_PATH_M {
                    self.aside_s = 0.0;
                    if gap_at(&to) >= YIELD_M && free(&to) {
                        self.step_back(back);
                    }
                    return;
                }
                self.aside_s += dt;
                if self.aside_s > WALK_ON_S {
                    // On beside the path, off the robot: the way they were
                    // going, else back.
                    let beside = |walked: f64| {
                        let p = self.pose_along(walked).position();
                        Point2::new(p.x + self.aside.x, p.y + self.aside.y)
                    };
                    let gap_here = gap_at(&here);
                    let on = [self.way, -self.way].into_iter().find(|&way| {
                        let to = beside(self.walked_m + way * step);
                        free(&to) && gap_at(&to) > gap_here
                    });
                    if let Some(way) = on {
                        self.way = way;
                        self.walked_m += way * step;
                    } else if gap_at(&to) >= MAKE_WAY_M && free(&to) {
                        // Walled in beside it (stepped into a doorway):
                        // back to the path, still clear of the body, and
                        // off along it from there.
                        self.step_back(back);
                    }
                }
                return;
            }
            let (now, then) = (gap(&self.pose()), gap(&self.pose_along(next)));
            if then < YIELD_M && then < now {
                self.waited_s += dt;
                if self.waited_s > TURN_BACK_S {
                    self.way = -self.way;
                    self.waited_s = 0.0;
                }
                return;
            }
        }
        self.waited_s = 0.0;
        self.walked_m = next;
    }

    /// A step of `back` m toward their path from where they stood aside.
    fn step_back(&mut self, back: f64) {
        self.aside -= self.aside.normalize() * back;
        if self.aside.norm() < 1e-9 {
            self.aside = nalgebra::Vector2::zeros();
        }
    }

    /// Position and heading `walked_m` along the path from where they
    /// started.
    fn pose_along(&self, walked_m: f64) -> Pose2 {
        let mut s = (self.phase_m + walked_m).rem_euclid(self.loop_m.max(1e-9));
        let n = self.path.len();
        for i in 0..n {
            let (a, b) = (self.path[i], self.path[(i + 1) % n]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            if s <= len || i == n - 1 {
                let f = if len > 0.0 { (s / len).min(1.0) } else { 0.0 };
                return Pose2::new(
                    a[0] + f * (b[0] - a[0]),
                    a[1] + f * (b[1] - a[1]),
                    (b[1] - a[1]).atan2(b[0] - a[0]),
                );
            }
            s -= len;
        }
        Pose2::IDENTITY
    }
}

/// The static world in rapier, the people, and the robot's footprint.
pub struct Scene {
    /// The static colliders and their query structures.
    pub world: PhysicsWorld,
    /// The same static solids for the cameras' rays.
    pub space: crate::space::SpaceCaster,
    /// The cameras cast through rapier, as before the [`SpaceCaster`]
    /// (`crate::SpaceCaster`): a benchmark's baseline.
    pub rapier_cameras: bool,
    /// The robot's footprint, for collision checks.
    pub robot_shape: Cuboid,
    /// Where the footprint's centre sits in the robot's frame, m.
    pub robot_shape_offset: [f64; 3],
    /// People.
    pub walkers: Vec<Walker>,
    /// The people's legs and torsos now.
    pub bodies: Vec<Upright>,
}

fn v3(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as Real, y as Real, z as Real)
}

/// The rapier pose of a planar pose lifted by `z`.
pub fn pose3(p: &Pose2, z: f64) -> Pose {
    Pose::new(v3(p.x, p.y, z), v3(0.0, 0.0, p.theta))
}

impl Scene {
    /// Builds the static world of `layout`, the people of `people` (each
    /// starting somewhere along its path), and the robot's footprint.
    pub fn build(
        layout: &Layout,
        people: &[PersonSpec],
        vehicle: &VehicleSpec,
        rng: &mut impl Rng,
    ) -> Scene {
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::ZERO;
        for solid in &layout.solids {
            let collider = match *solid {
                Solid::Box {
                    center,
                    half,
                    yaw_rad,
                    material,
                } => ColliderBuilder::cuboid(half[0] as Real, half[1] as Real, half[2] as Real)
                    .translation(v3(center[0], center[1], center[2]))
                    .rotation(v3(0.0, 0.0, yaw_rad))
                    .user_data(if material == Material::Glass {
                        GLASS
                    } else {
                        0
                    }),
                Solid::Cylinder { at, radius, z } => upright_cylinder(radius, z[1] - z[0])
                    .translation(v3(at[0], at[1], (z[0] + z[1]) / 2.0)),
            };
            world.insert_collider(collider, None);
        }
        let walkers: Vec<Walker> = people
            .iter()
            .map(|p| {
                let loop_m: f64 = (0..p.path.len())
                    .map(|i| {
                        let (a, b) = (p.path[i], p.path[(i + 1) % p.path.len()]);
                        (b[0] - a[0]).hypot(b[1] - a[1])
                    })
                    .sum();
                Walker {
                    path: p.path.clone(),
                    speed_mps: p.speed_mps,
                    phase_m: rng.random::<f64>() * loop_m,
                    loop_m,
                    walked_m: 0.0,
                    t_s: 0.0,
                    way: 1.0,
                    waited_s: 0.0,
                    aside: nalgebra::Vector2::zeros(),
                    aside_s: 0.0,
                }
            })
            .collect();
        let half = [
            vehicle.length_m / 2.0,
            vehicle.width_m / 2.0,
            (vehicle.height_m - GROUND_CLEARANCE_M) / 2.0,
        ];
        let offset = [
            vehicle.length_m / 2.0 - vehicle.rear_overhang_m,
            0.0,
            GROUND_CLEARANCE_M + half[2],
        ];
        // One step builds the query structures; nothing moves in them later.
        world.step();
        let mut scene = Scene {
            world,
            space: crate::space::SpaceCaster::new(layout),
            rapier_cameras: false,
            robot_shape: Cuboid::new(v3(half[0], half[1], half[2])),
            robot_shape_offset: offset,
            walkers,
            bodies: Vec::new(),
        };
        scene.step_to(0.0, None);
        scene
    }

    /// Moves the people on to `t_s`, each waiting rather than walk into
    /// the robot standing at `robot` (true pose).
    pub fn step_to(&mut self, t_s: f64, robot: Option<&Pose2>) {
        let outline = robot.map(|r| {
            let c = r.transform_point(&Point2::new(
                self.robot_shape_offset[0],
                self.robot_shape_offset[1],
            ));
            (
                c,
                [
                    f64::from(self.robot_shape.half_extents.x),
                    f64::from(self.robot_shape.half_extents.y),
                ],
                r.theta,
            )
        });
        self.bodies.clear();
        let q = self.world.query_pipeline();
        let person = Cuboid::new(v3(TORSO_RADIUS_M, TORSO_RADIUS_M, 0.5 * PERSON_HEIGHT_M));
        // Where a person may stand: clear of the walls and what stands.
        let free = |p: &Point2<f64>| {
            q.intersect_shape(
                pose3(&Pose2::new(p.x, p.y, 0.0), 0.5 * PERSON_HEIGHT_M + 0.01),
                &person,
            )
            .next()
            .is_none()
        };
        for w in &mut self.walkers {
            w.walk_to(t_s, outline, free);
            self.bodies.extend(w.body());
        }
    }

    /// The people's legs now: centres and radius.
    pub fn legs(&self) -> impl Iterator<Item = (Point2<f64>, f64)> + '_ {
        self.bodies
            .iter()
            .filter(|b| b.z[0] <= 0.0)
            .map(|b| (b.at, b.radius))
    }

    /// True when the robot's footprint, moved from `from` to `to`, meets
    /// anything on the way or at the end.
    pub fn blocked(&self, from: &Pose2, to: &Pose2) -> bool {
        let q = self.world.query_pipeline();
        let place = |p: &Pose2| {
            let o = p.transform_point(&Point2::new(
                self.robot_shape_offset[0],
                self.robot_shape_offset[1],
            ));
            pose3(&Pose2::new(o.x, o.y, p.theta), self.robot_shape_offset[2])
        };
        let (a, b) = (place(from), place(to));
        let motion = b.translation - a.translation;
        let options = ShapeCastOptions {
            max_time_of_impact: 1.0,
            stop_at_penetration: true,
            ..ShapeCastOptions::default()
        };
        if q.cast_shape(&a, motion, &self.robot_shape, options)
            .is_some()
            || q.intersect_shape(b, &self.robot_shape).next().is_some()
        {
            return true;
        }
        // People: their legs against the footprint at its end.
        let (hx, hy) = (
            f64::from(self.robot_shape.half_extents.x),
            f64::from(self.robot_shape.half_extents.y),
        );
        let centre = to.transform_point(&Point2::new(
            self.robot_shape_offset[0],
            self.robot_shape_offset[1],
        ));
        let frame = Pose2::new(centre.x, centre.y, to.theta).inverse();
        self.bodies.iter().any(|b| {
            let p = frame.transform_point(&b.at);
            let (dx, dy) = ((p.x.abs() - hx).max(0.0), (p.y.abs() - hy).max(0.0));
            b.z[0] < self.robot_shape_offset[2] * 2.0 && dx * dx + dy * dy <= b.radius * b.radius
        })
    }

    /// People's poses now, for ground truth.
    pub fn people(&self) -> Vec<Pose2> {
        self.walkers.iter().map(Walker::pose).collect()
    }
}

/// A cylinder standing upright (rapier's cylinders lie along y).
fn upright_cylinder(radius: f64, height: f64) -> ColliderBuilder {
    ColliderBuilder::cylinder((height / 2.0) as Real, radius as Real)
        .rotation(v3(FRAC_PI_2, 0.0, 0.0))
}
