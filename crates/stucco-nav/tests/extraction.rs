//! Wall extraction on synthetic scans: invariance to rigid motion, clutter
//! away from the walls, motion distortion, and the reference room of
//! ACCEPTANCE.md (the full 10,000-pose study is `#[ignore]`d; run it with
//! `cargo test --release -p stucco-nav --test extraction -- --ignored`).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stucco_core::{LaserSpec, Pose2, Stamp, Twist2, wrap_angle};
use stucco_nav::synthetic::{self, Clutter, SyntheticLaser};
use stucco_nav::*;

fn empty_room(rng: &mut ChaCha8Rng) -> synthetic::RoomScene {
    let bare = Clutter {
        people: 0,
        tables: 0,
        chairs: 0,
        radiator_fraction: 0.0,
        ..Clutter::default()
    };
    synthetic::rectangular_room(5.45, 5.64, &[(2, 2.1, 0.9, true)], Some(3.0), &bare, rng)
}

/// The wall of `walls` matching `(d, γ)` within 5 cm and 2°, the nearest
/// in distance when several do (a radiator's face before its wall).
fn matching(walls: &[Wall], d: f64, g: f64) -> Option<&Wall> {
    walls
        .iter()
        .filter(|w| (w.d_m - d).abs() < 0.05 && wrap_angle(w.gamma_rad - g).abs() < 0.035)
        .min_by(|a, b| (a.d_m - d).abs().total_cmp(&(b.d_m - d).abs()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Moving every point rigidly moves every wall the same way.
    #[test]
    fn rigid_motion_moves_walls_alike(seed in 0u64..1000, dx in -0.5..0.5f64, dy in -0.5..0.5f64, dth in -3.1..3.1f64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let scene = empty_room(&mut rng);
        let pose = synthetic::random_pose(scene.size_m, 1.0, &mut rng);
        let scan = SyntheticLaser::new(LaserSpec::ibeo_ladar_2d()).scan(&scene.world, &pose, &Twist2::default(), Stamp::ZERO, &mut rng);
        let pts = ScanPoints::from_scan(&scan);
        let motion = Pose2::new(dx, dy, dth);
        let mut rwht = RwhtExtractor::new(RwhtConfig::default()).unwrap();
        let before = rwht.extract(&pts);
        let after = rwht.extract(&pts.transformed(&motion));
        let mut compared = 0;
        // Well-supported walls; marginal ones near the detection threshold may
        // come and go as the window slides over them.
        for w in before.iter().filter(|w| w.length_m() > 1.0 && w.points >= 60) {
            let moved = w.transformed(&motion);
            let m = matching(&after, moved.d_m, moved.gamma_rad);
            prop_assert!(m.is_some(), "wall {w:?} moved to {moved:?} not found in {after:?}");
            let m = m.unwrap();
            let tol_d = 3.0 * moved.sigma_d_m().max(m.sigma_d_m()) + 1e-3;
            let tol_g = 3.0 * moved.sigma_gamma_rad().max(m.sigma_gamma_rad()) + 1e-4;
            prop_assert!((m.d_m - moved.d_m).abs() < tol_d, "d {} vs {}", m.d_m, moved.d_m);
            prop_assert!(wrap_angle(m.gamma_rad - moved.gamma_rad).abs() < tol_g);
            compared += 1;
        }
        prop_assert!(compared >= 2, "only {compared} walls compared");
    }
}

/// People and furniture away from the walls change only the beams they
/// block: the walls stay put within their own uncertainty.
#[test]
fn clutter_away_from_walls_leaves_walls_unchanged() {
    let laser = SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
    let mut rwht = RwhtExtractor::new(RwhtConfig::default()).unwrap();
    let (mut total_seen, mut total_kept) = (0, 0);
    for seed in 0..20 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let scene = empty_room(&mut rng);
        let pose = synthetic::random_pose(scene.size_m, 1.0, &mut rng);
        let mut cluttered = scene.clone();
        // Table legs and people at least 1 m from every wall and 0.6 m from the robot.
        let mut placed = 0;
        while placed < 10 {
            let p = synthetic::random_pose(scene.size_m, 1.0, &mut rng).position();
            if (p - pose.position()).norm() > 0.6 {
                cluttered.world.circles.push(synthetic::Circle {
                    center: p,
                    radius: if placed % 2 == 0 { 0.2 } else { 0.03 },
                    velocity: nalgebra::Vector2::zeros(),
                });
                placed += 1;
            }
        }
        // The same noise draws for both scans: every beam returns in this closed room.
        let clean = laser.scan(
            &scene.world,
            &pose,
            &Twist2::default(),
            Stamp::ZERO,
            &mut ChaCha8Rng::seed_from_u64(seed + 100),
        );
        let busy = laser.scan(
            &cluttered.world,
            &pose,
            &Twist2::default(),
            Stamp::ZERO,
            &mut ChaCha8Rng::seed_from_u64(seed + 100),
        );
        let a = rwht.extract(&ScanPoints::from_scan(&clean));
        let b = rwht.extract(&ScanPoints::from_scan(&busy));
        let mut kept = 0;
        let mut seen = 0;
        for w in 0..4 {
            let (d, g) = scene.wall_in_sensor_frame(w, &pose);
            seen += usize::from(matching(&a, d, g).is_some());
            let (x, y) = match (matching(&a, d, g), matching(&b, d, g)) {
                (Some(x), Some(y)) => (x, y),
                // Behind the sensor, in its blind sector: seen in neither.
                // Hidden behind the clutter, or in the blind sector.
                _ => continue,
            };
            kept += 1;
            assert!(
                (x.d_m - y.d_m).abs() < 3.0 * x.sigma_d_m().max(y.sigma_d_m()) + 1e-3,
                "seed {seed} wall {w}: {x:?} vs {y:?}"
            );
            assert!(
                wrap_angle(x.gamma_rad - y.gamma_rad).abs()
                    < 3.0 * x.sigma_gamma_rad().max(y.sigma_gamma_rad()) + 1e-4
            );
        }
        total_seen += seen;
        total_kept += kept;
    }
    assert!(
        total_kept * 10 >= total_seen * 8,
        "clutter hid {} of {total_seen} walls",
        total_seen - total_kept
    );
}

/// The foot of a bed and, beside it, the legs of a desk and of the chair
/// pushed under it, a little nearer: a line fitted along the bed's foot
/// that takes the legs tilts (the apartment's bedroom seen from its door).
/// Every wall found must lie along the bed's foot.
#[test]
fn a_face_with_legs_standing_beside_it_is_not_fitted_into_one_tilted_line() {
    let laser = SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
    let mut rwht = RwhtExtractor::new(RwhtConfig {
        hough: HoughConfig {
            surface_noise_m: 0.02,
            ..HoughConfig::default()
        },
        ..RwhtConfig::default()
    })
    .unwrap();
    let leg = |x: f64, y: f64| synthetic::Circle {
        center: nalgebra::Point2::new(x, y),
        radius: 0.025,
        velocity: nalgebra::Vector2::zeros(),
    };
    // The bed's foot along y = 6.1 from x = 0.2 to 2.2; the desk's legs at
    // y = 5.95, the chair's at 6.04.
    let world = synthetic::World {
        segments: vec![synthetic::Segment {
            a: nalgebra::Point2::new(0.2, 6.1),
            b: nalgebra::Point2::new(2.2, 6.1),
        }],
        circles: vec![
            leg(2.45, 5.95),
            leg(3.55, 5.95),
            leg(2.84, 6.04),
            leg(3.16, 6.04),
        ],
    };
    let (mut found, mut tilted) = (0, Vec::new());
    for seed in 0..40u64 {
        // From the bedroom's door and inside it, 1 to 2.2 m off.
        let y = 3.9 + 0.03 * seed as f64;
        let pose = Pose2::new(3.4, y, std::f64::consts::FRAC_PI_2);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let scan = laser.scan(&world, &pose, &Twist2::default(), Stamp::ZERO, &mut rng);
        for w in rwht.extract(&ScanPoints::from_scan(&scan)) {
            found += 1;
            let off = wrap_angle(w.gamma_rad + pose.theta - std::f64::consts::FRAC_PI_2);
            if off.abs() > 3.0 * w.sigma_gamma_rad() + 0.3f64.to_radians() {
                tilted.push(format!(
                    "from y = {y:.2} m: a wall {:.2}° ({:.1} σ) off the bed's foot, {} points",
                    off.to_degrees(),
                    off.abs() / w.sigma_gamma_rad(),
                    w.points,
                ));
            }
        }
    }
    assert!(
        found >= 30,
        "the bed's foot was found {found} times in 40 scans"
    );
    assert!(tilted.is_empty(), "{tilted:#?}");
}

/// A scan taken at 0.8 m/s while turning is bent; correcting it under
/// constant velocity brings the walls back to where they are at the stamp.
#[test]
fn deskewing_undoes_motion_distortion() {
    let laser = SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
    let twist = Twist2::new(0.8, 0.0, 0.6);
    let mut rwht = RwhtExtractor::new(RwhtConfig::default()).unwrap();
    let (mut raw_err, mut fixed_err, mut compared) = (0.0, 0.0, 0);
    for seed in 0..20 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let scene = empty_room(&mut rng);
        let pose = synthetic::random_pose(scene.size_m, 1.0, &mut rng);
        let scan = laser.scan(&scene.world, &pose, &twist, Stamp::ZERO, &mut rng);
        let raw = rwht.extract(&ScanPoints::from_scan(&scan));
        let fixed = rwht.extract(&ScanPoints::from_scan_deskewed(&scan, &twist));
        for w in 0..4 {
            let (d, g) = scene.wall_in_sensor_frame(w, &pose);
            let err = |walls: &[Wall]| {
                walls
                    .iter()
                    .filter(|m| wrap_angle(m.gamma_rad - g).abs() < 0.1 && (m.d_m - d).abs() < 0.2)
                    .map(|m| (m.d_m - d).abs() + wrap_angle(m.gamma_rad - g).abs())
                    .fold(f64::INFINITY, f64::min)
            };
            let f = err(&fixed);
            if f.is_infinite() {
                continue; // in the blind sector
            }
            let m = fixed
                .iter()
                .filter(|m| wrap_angle(m.gamma_rad - g).abs() < 0.1 && (m.d_m - d).abs() < 0.2)
                .min_by(|a, b| (a.d_m - d).abs().total_cmp(&(b.d_m - d).abs()))
                .expect("a match");
            assert!(
                (m.d_m - d).abs() < 3.0 * m.sigma_d_m() + 2e-3
                    && wrap_angle(m.gamma_rad - g).abs() < 3.0 * m.sigma_gamma_rad() + 1e-4,
                "seed {seed} wall {w}: deskewed {m:?}, truth ({d}, {g})"
            );
            fixed_err += f;
            raw_err += err(&raw).min(0.3);
            compared += 1;
        }
    }
    assert!(compared >= 50, "only {compared} walls seen");
    assert!(
        fixed_err * 3.0 < raw_err,
        "deskewed {fixed_err} vs raw {raw_err}"
    );
}

/// Beams of a noise-free scan that must land on a wall for it to be in
/// view: enough to fit a line to. Walls hidden behind the people or in
/// the laser's 90° blind sector are not in view, and no single scan can
/// find them.
const IN_VIEW_BEAMS: usize = 40;

#[derive(Debug, Default)]
struct RoomStudy {
    poses: usize,
    /// Poses with all four walls found.
    all_four: usize,
    /// Poses with all four walls in view.
    all_four_in_view: usize,
    /// Poses with every wall in view found, and nothing else reported in
    /// its place.
    all_in_view_found: usize,
    /// Walls reported where the true wall was in view but elsewhere.
    wrong_walls: usize,
    /// Each pose's walls in turn: the distance and angle errors of the
    /// one found, if it was.
    per_wall: Vec<Option<(f64, f64)>>,
}

impl RoomStudy {
    /// The distance errors of the walls found, m.
    fn err_d(&self) -> Vec<f64> {
        self.per_wall.iter().flatten().map(|e| e.0).collect()
    }

    /// The angle errors of the walls found, rad.
    fn err_g(&self) -> Vec<f64> {
        self.per_wall.iter().flatten().map(|e| e.1).collect()
    }
}

/// The walls the room search finds, as one extractor.
fn room_search() -> impl FnMut(&ScanPoints) -> Vec<Wall> {
    let mut search = RoomSearch::new(RoomConfig::default()).unwrap();
    move |pts| {
        search
            .find(pts)
            .map(|r| r.walls.into_iter().flatten().collect())
            .unwrap_or_default()
    }
}

/// The walls `extractor` finds in one scan.
fn extractor(mut extractor: impl WallExtractor) -> impl FnMut(&ScanPoints) -> Vec<Wall> {
    move |pts| extractor.extract(pts)
}

fn reference_room_study(
    poses: usize,
    people: usize,
    seed: u64,
    mut find_walls: impl FnMut(&ScanPoints) -> Vec<Wall>,
) -> RoomStudy {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let laser = SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
    let exact = SyntheticLaser {
        noise: false,
        sub_rays: 1,
        ..laser.clone()
    };
    let mut study = RoomStudy {
        poses,
        ..RoomStudy::default()
    };
    for _ in 0..poses {
        let pose = synthetic::random_pose((5.45, 5.64), 0.5, &mut rng);
        let scene = synthetic::reference_room(pose.position(), people, &mut rng);
        let scan = laser.scan(
            &scene.world,
            &pose,
            &Twist2::default(),
            Stamp::ZERO,
            &mut rng,
        );
        let truth = exact.scan(
            &scene.world,
            &pose,
            &Twist2::default(),
            Stamp::ZERO,
            &mut rng,
        );
        let walls = find_walls(&ScanPoints::from_scan(&scan));
        let (mut found, mut in_view, mut found_in_view) = (0, 0, 0);
        for w in 0..4 {
            let (d, g) = scene.wall_in_sensor_frame(w, &pose);
            let n = nalgebra::Vector2::new(g.cos(), g.sin());
            let beams = truth
                .returns()
                .filter(|b| (n.dot(&b.point().coords) - d).abs() < 0.01)
                .count();
            let m = matching(&walls, d, g);
            study
                .per_wall
                .push(m.map(|m| (m.d_m - d, wrap_angle(m.gamma_rad - g))));
            found += usize::from(m.is_some());
            if beams >= IN_VIEW_BEAMS {
                in_view += 1;
                found_in_view += usize::from(m.is_some());
                let elsewhere = walls.iter().any(|x| {
                    wrap_angle(x.gamma_rad - g).abs() < 0.035 && (x.d_m - d).abs() >= 0.05
                });
                study.wrong_walls += usize::from(elsewhere);
            }
        }
        study.all_four += usize::from(found == 4);
        study.all_four_in_view += usize::from(in_view == 4);
        study.all_in_view_found += usize::from(found_in_view == in_view);
    }
    study
}

fn std_dev(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
}

/// Robust spread: 1.4826 × the median absolute deviation (σ for a
/// Gaussian), blind to the few walls matched to a radiator's face.
fn robust_spread(v: &[f64]) -> f64 {
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let m = median(&mut v.to_vec());
    1.4826 * median(&mut v.iter().map(|x| (x - m).abs()).collect())
}

fn report_room_study(s: &RoomStudy) -> (f64, f64) {
    let (sd, sg) = (std_dev(&s.err_d()), std_dev(&s.err_g()).to_degrees());
    println!(
        "{} poses: every wall in view (>= {IN_VIEW_BEAMS} beams) found in {} ({:.2}%), a wrong wall reported {} times; \
         all four walls in view in {}, all four found in {}; σ_d {:.2} mm, σ_γ {:.3}° over {} walls",
        s.poses,
        s.all_in_view_found,
        100.0 * s.all_in_view_found as f64 / s.poses as f64,
        s.wrong_walls,
        s.all_four_in_view,
        s.all_four,
        sd * 1e3,
        sg,
        s.err_d().len()
    );
    (sd, sg)
}

fn assert_room_targets(s: &RoomStudy) {
    let (sd, sg) = report_room_study(s);
    assert!(
        s.all_in_view_found as f64 >= 0.999 * s.poses as f64,
        "every wall in view found in only {}/{}",
        s.all_in_view_found,
        s.poses
    );
    assert!(sd <= 0.005 && sg <= 0.2, "σ_d {sd} m, σ_γ {sg}°");
}

/// The reference room, 1,000 poses: the default run's share of the study.
#[test]
fn reference_room_walls_in_view_found_in_1000_poses() {
    assert_room_targets(&reference_room_study(1_000, 12, 7, room_search()));
}

/// ACCEPTANCE.md, navigation core: in the cluttered reference room (IBEO,
/// a dozen people, radiators, tables), the walls in ≥ 99.9% of 10,000
/// random poses ≥ 0.5 m from the walls, σ ≤ 5 mm and ≤ 0.2°. With a
/// dozen people in 31 m² and a 90° blind sector only about half the poses
/// have all four walls in view at all: the study counts a pose as a
/// success when every wall in view is found and nothing is reported in
/// the place of one, and prints how often all four were found.
#[test]
#[ignore = "study: 10,000 scans; run with --release -- --ignored"]
fn reference_room_all_four_walls_in_999_of_10000_poses() {
    assert_room_targets(&reference_room_study(10_000, 12, 2026, room_search()));
}

/// RWHT and RANSAC on the same `poses` scans of the reference room: the
/// RWHT finds every wall in view at least as often, and on the walls both
/// find it is at least as accurate (robust spread: without the room model
/// either may match a radiator's face when its wall is missed). Accuracy
/// is compared on the same walls: each extractor's spread over its own
/// finds counts against it the hard walls only it finds.
fn rwht_against_ransac(poses: usize, seed: u64) {
    let rwht = RwhtExtractor::new(RwhtConfig::default()).unwrap();
    let ransac = RansacExtractor::new(RansacConfig::default()).unwrap();
    let a = reference_room_study(poses, 12, seed, extractor(rwht));
    let b = reference_room_study(poses, 12, seed, extractor(ransac));
    print!("RWHT:   ");
    report_room_study(&a);
    print!("RANSAC: ");
    report_room_study(&b);
    let robust = |s: &RoomStudy| (robust_spread(&s.err_d()), robust_spread(&s.err_g()));
    let ((ad, ag), (bd, bg)) = (robust(&a), robust(&b));
    println!(
        "robust σ over each one's finds: RWHT {:.2} mm {:.3}°, RANSAC {:.2} mm {:.3}°",
        ad * 1e3,
        ag.to_degrees(),
        bd * 1e3,
        bg.to_degrees()
    );
    // The same scans, so the same walls in the same order: (distance,
    // angle) errors of RWHT and RANSAC, [d_a, γ_a, d_b, γ_b].
    let both: Vec<[f64; 4]> = a
        .per_wall
        .iter()
        .zip(&b.per_wall)
        .filter_map(|(x, y)| Some(((*x)?, (*y)?)))
        .map(|((da, ga), (db, gb))| [da, ga, db, gb])
        .collect();
    let spread = |k: usize| robust_spread(&both.iter().map(|w| w[k]).collect::<Vec<_>>());
    let (ad, ag, bd, bg) = (spread(0), spread(1), spread(2), spread(3));
    println!(
        "robust σ over the {} walls both found: RWHT {:.2} mm {:.3}°, RANSAC {:.2} mm {:.3}°",
        both.len(),
        ad * 1e3,
        ag.to_degrees(),
        bd * 1e3,
        bg.to_degrees()
    );
    assert!(a.all_in_view_found >= b.all_in_view_found);
    assert!(
        ad <= bd && ag <= bg,
        "robust σ {ad} m {ag} rad vs {bd} m {bg} rad"
    );
}

/// The RWHT extractor on its own, without the room model, against the
/// RANSAC baseline: 300 poses in the default run.
#[test]
fn rwht_finds_the_walls_in_view_as_often_as_ransac() {
    rwht_against_ransac(300, 7);
}

/// The same on 10,000 poses (the accuracy comparison; the time
/// ratio is the `extract` bench's).
#[test]
#[ignore = "study: 2 × 10,000 scans; run with --release -- --ignored --nocapture"]
fn rwht_and_ransac_side_by_side_on_10000_poses() {
    rwht_against_ransac(10_000, 2026);
}
