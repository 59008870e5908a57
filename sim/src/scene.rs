//! The rapier3d world of a layout: static colliders for every solid,
//! kinematic bodies for the people and the robot. The z axis points up.

use crate::layout::{LEG_HALF_SPACING_M, LEG_RADIUS_M, Layout, Material, Solid};
use crate::world::PersonSpec;
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

/// A person walking a closed path.
#[derive(Clone, Debug)]
pub struct Walker {
    body: RigidBodyHandle,
    path: Vec<[f64; 2]>,
    speed_mps: f64,
    /// Where along the loop the person was at time zero, m.
    phase_m: f64,
    loop_m: f64,
}

impl Walker {
    /// Position and heading at `t_s`.
    pub fn pose_at(&self, t_s: f64) -> Pose2 {
        let mut s = (self.phase_m + self.speed_mps * t_s).rem_euclid(self.loop_m.max(1e-9));
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

/// The physics world and the handles the simulator needs.
pub struct Scene {
    /// Bodies, colliders and the query structures.
    pub world: PhysicsWorld,
    /// The robot's kinematic body.
    pub robot: RigidBodyHandle,
    /// The robot's footprint, for collision checks.
    pub robot_shape: Cuboid,
    /// Where the footprint's centre sits in the robot's frame, m.
    pub robot_shape_offset: [f64; 3],
    /// People.
    pub walkers: Vec<Walker>,
}

fn v3(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as Real, y as Real, z as Real)
}

/// The rapier pose of a planar pose lifted by `z`.
pub fn pose3(p: &Pose2, z: f64) -> Pose {
    Pose::new(v3(p.x, p.y, z), v3(0.0, 0.0, p.theta))
}

impl Scene {
    /// Builds the world of `layout` with `people`, and the robot at `start`.
    pub fn build(
        layout: &Layout,
        people: &[PersonSpec],
        vehicle: &VehicleSpec,
        start: &Pose2,
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
        let walkers = people
            .iter()
            .map(|p| {
                let loop_m: f64 = (0..p.path.len())
                    .map(|i| {
                        let (a, b) = (p.path[i], p.path[(i + 1) % p.path.len()]);
                        (b[0] - a[0]).hypot(b[1] - a[1])
                    })
                    .sum();
                let mut w = Walker {
                    body: RigidBodyHandle::invalid(),
                    path: p.path.clone(),
                    speed_mps: p.speed_mps,
                    phase_m: rng.random::<f64>() * loop_m,
                    loop_m,
                };
                let at = w.pose_at(0.0);
                let body = world.insert_body(
                    RigidBodyBuilder::kinematic_position_based().pose(pose3(&at, 0.0)),
                );
                for side in [-1.0, 1.0] {
                    world.insert_collider(
                        upright_cylinder(LEG_RADIUS_M, LEG_HEIGHT_M).translation(v3(
                            0.0,
                            side * LEG_HALF_SPACING_M,
                            LEG_HEIGHT_M / 2.0,
                        )),
                        Some(body),
                    );
                }
                world.insert_collider(
                    upright_cylinder(TORSO_RADIUS_M, PERSON_HEIGHT_M - LEG_HEIGHT_M)
                        .translation(v3(0.0, 0.0, (LEG_HEIGHT_M + PERSON_HEIGHT_M) / 2.0)),
                    Some(body),
                );
                w.body = body;
                w
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
        let robot_shape = Cuboid::new(v3(half[0], half[1], half[2]));
        let robot =
            world.insert_body(RigidBodyBuilder::kinematic_position_based().pose(pose3(start, 0.0)));
        world.insert_collider(
            ColliderBuilder::cuboid(half[0] as Real, half[1] as Real, half[2] as Real)
                .translation(v3(offset[0], offset[1], offset[2])),
            Some(robot),
        );
        // One step puts every collider into the query structures.
        world.step();
        Scene {
            world,
            robot,
            robot_shape,
            robot_shape_offset: offset,
            walkers,
        }
    }

    /// Moves the people to where they are at `t_s` and the robot to
    /// `robot`, and steps the physics so that queries see them there.
    pub fn step_to(&mut self, t_s: f64, robot: &Pose2, dt_s: f64) {
        for w in &self.walkers {
            let at = w.pose_at(t_s);
            if let Some(b) = self.world.bodies.get_mut(w.body) {
                b.set_next_kinematic_position(pose3(&at, 0.0));
            }
        }
        if let Some(b) = self.world.bodies.get_mut(self.robot) {
            b.set_next_kinematic_position(pose3(robot, 0.0));
        }
        self.world.integration_parameters.dt = dt_s as Real;
        self.world.step();
    }

    /// True when the robot's footprint, moved from `from` to `to`, meets
    /// anything on the way or at the end.
    pub fn blocked(&self, from: &Pose2, to: &Pose2) -> bool {
        let filter = QueryFilter::default().exclude_rigid_body(self.robot);
        let q = self.world.query_pipeline_with_filter(filter);
        let place = |p: &Pose2| {
            let o = p.transform_point(&nalgebra::Point2::new(
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
        {
            return true;
        }
        q.intersect_shape(b, &self.robot_shape).next().is_some()
    }

    /// People's poses at `t_s`, for ground truth.
    pub fn people_at(&self, t_s: f64) -> Vec<Pose2> {
        self.walkers.iter().map(|w| w.pose_at(t_s)).collect()
    }
}

/// A cylinder standing upright (rapier's cylinders lie along y).
fn upright_cylinder(radius: f64, height: f64) -> ColliderBuilder {
    ColliderBuilder::cylinder((height / 2.0) as Real, radius as Real)
        .rotation(v3(FRAC_PI_2, 0.0, 0.0))
}
