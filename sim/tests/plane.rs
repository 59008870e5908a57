//! The laser's plane caster holds the same geometry as the rapier world:
//! horizontal rays at the laser's height from free space along each world's
//! tour meet the same surface at the same range in both (within a
//! millimetre: rapier casts in f32, and its cylinders by GJK).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stucco_core::VehicleSpec;
use stucco_sim::{Layout, PlaneCaster, Scene, WorldSpec, cast, cast_rapier};

/// Each of `names`' worlds with its layout and scene, and 20 points along
/// each leg of its tour.
fn along_tours(
    names: &[&str],
    rng: &mut ChaCha8Rng,
    mut visit: impl FnMut(&str, &Layout, &Scene, Point2<f64>, &mut ChaCha8Rng),
) {
    let vehicle = VehicleSpec::default();
    for name in names {
        let path = format!("{}/worlds/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let world = WorldSpec::load(std::path::Path::new(&path)).unwrap();
        let layout = Layout::of(&world);
        let scene = Scene::build(&layout, &world.people, &vehicle, &mut *rng);
        let n = world.tour.len();
        for i in 0..n {
            let (a, b) = (world.tour[i], world.tour[(i + 1) % n]);
            for k in 0..20 {
                let f = k as f64 / 20.0;
                let o = Point2::new(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
                visit(name, &layout, &scene, o, &mut *rng);
            }
        }
    }
}

#[test]
fn plane_caster_and_rapier_agree() {
    let h = VehicleSpec::default().laser_height_m;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut compared = 0;
    // Each world's plane caster, made when its first point comes.
    let mut plane: Option<(String, PlaneCaster)> = None;
    along_tours(
        &["reference-room", "corridor", "apartment"],
        &mut rng,
        |name, layout, scene, o, rng| {
            if plane.as_ref().is_none_or(|(n, _)| n != name) {
                plane = Some((name.to_owned(), PlaneCaster::new(layout, h)));
            }
            let plane = &plane.as_ref().unwrap().1;
            let legs: Vec<_> = scene.legs().collect();
            for _ in 0..10 {
                let phi = rng.random::<f64>() * std::f64::consts::TAU;
                let d = Vector2::new(phi.cos(), phi.sin());
                let fast = legs
                    .iter()
                    .filter_map(|(c, r)| stucco_sim::ray_circle(&o, &d, c, *r))
                    .chain(plane.cast(&o, &d, 30.0))
                    .min_by(f64::total_cmp);
                let full = cast_rapier(scene, [o.x, o.y, h], [d.x, d.y, 0.0], 30.0);
                match (fast, full) {
                    (Some(x), Some(y)) => assert!(
                        (x - y).abs() < 1e-3,
                        "{name}: from {o:?} at {phi}: plane {x}, rapier {y}"
                    ),
                    (None, None) => {}
                    other => panic!("{name}: from {o:?} at {phi}: {other:?}"),
                }
                compared += 1;
            }
        },
    );
    assert!(compared >= 2000, "{compared}");
}

/// The cameras' caster holds the same geometry as the rapier world: rays
/// in every direction (up to the ceiling, down to the floor, through the
/// windows' glass at a slant and face-on) from heights a camera looks
/// from, along each world's tour, meet the same surface at the same range
/// in both (within a millimetre: rapier casts in f32, and its cylinders
/// by GJK).
#[test]
fn space_caster_and_rapier_agree() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut compared = 0;
    let mut hits = 0;
    along_tours(
        &["reference-room", "corridor", "apartment", "floor"],
        &mut rng,
        |name, _, scene, o, rng| {
            for _ in 0..10 {
                let z = 0.1 + rng.random::<f64>() * 1.8;
                let phi = rng.random::<f64>() * std::f64::consts::TAU;
                let el = (rng.random::<f64>() - 0.5) * std::f64::consts::PI;
                let d = [el.cos() * phi.cos(), el.cos() * phi.sin(), el.sin()];
                let fast = cast(scene, [o.x, o.y, z], d, 30.0);
                let full = cast_rapier(scene, [o.x, o.y, z], d, 30.0);
                match (fast, full) {
                    (Some(x), Some(y)) => {
                        assert!(
                            (x - y).abs() < 1e-3,
                            "{name}: from {o:?} at {z} along {d:?}: space {x}, rapier {y}"
                        );
                        hits += 1;
                    }
                    (None, None) => {}
                    other => panic!("{name}: from {o:?} at {z} along {d:?}: {other:?}"),
                }
                compared += 1;
            }
        },
    );
    assert!(
        compared >= 2000 && hits * 10 >= compared * 9,
        "{hits}/{compared}"
    );
}
