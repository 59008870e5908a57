//! Map building on scenes built on purpose, whose every observation is
//! known: what each wall of the map truly is, so a false association is
//! caught the moment it is made.

use super::*;
use nalgebra::SymmetricEigen;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::FRAC_PI_2;

/// A surface of the scene: from `a` to `b`, facing the side its normal
/// (into the surface) comes from.
#[derive(Clone, Copy)]
struct Surface {
    a: Point2<f64>,
    b: Point2<f64>,
    normal: Vector2<f64>,
    /// Glass frames: seen only from near, weakly, and not blocking.
    glass: bool,
}

fn surface(a: (f64, f64), b: (f64, f64), normal: (f64, f64)) -> Surface {
    Surface {
        a: Point2::new(a.0, a.1),
        b: Point2::new(b.0, b.1),
        normal: Vector2::new(normal.0, normal.1),
        glass: false,
    }
}

/// The walls of a `w` × `h` room with its corner at the origin.
fn room(w: f64, h: f64) -> Vec<Surface> {
    vec![
        surface((0.0, 0.0), (w, 0.0), (0.0, -1.0)),
        surface((w, 0.0), (w, h), (1.0, 0.0)),
        surface((w, h), (0.0, h), (0.0, 1.0)),
        surface((0.0, h), (0.0, 0.0), (-1.0, 0.0)),
    ]
}

/// A box (cabinet) from `lo` to `hi`, its four faces outward.
fn cabinet(lo: (f64, f64), hi: (f64, f64)) -> Vec<Surface> {
    vec![
        surface((lo.0, lo.1), (hi.0, lo.1), (0.0, 1.0)),
        surface((hi.0, lo.1), (hi.0, hi.1), (-1.0, 0.0)),
        surface((hi.0, hi.1), (lo.0, hi.1), (0.0, -1.0)),
        surface((lo.0, hi.1), (lo.0, lo.1), (1.0, 0.0)),
    ]
}

/// The laser: range, field of view (centred forward), noise.
struct Laser {
    range_m: f64,
    fov_rad: f64,
    sigma_d_m: f64,
    sigma_gamma_rad: f64,
}

impl Default for Laser {
    fn default() -> Self {
        Laser {
            range_m: 8.0,
            fov_rad: std::f64::consts::PI,
            sigma_d_m: 0.005,
            sigma_gamma_rad: 0.3f64.to_radians(),
        }
    }
}

/// Whether the segment from `o` to `q` crosses a blocking surface other
/// than `skip`.
fn blocked(scene: &[Surface], skip: usize, o: &Point2<f64>, q: &Point2<f64>) -> bool {
    scene.iter().enumerate().any(|(k, s)| {
        if k == skip || s.glass {
            return false;
        }
        let cross = |u: Vector2<f64>, v: Vector2<f64>| u.x * v.y - u.y * v.x;
        let (r, e) = (q - o, s.b - s.a);
        let den = cross(r, e);
        if den.abs() < 1e-12 {
            return false;
        }
        let t = cross(s.a - o, e) / den;
        let u = cross(s.a - o, r) / den;
        t > 1e-6 && t < 1.0 - 1e-6 && (0.0..=1.0).contains(&u)
    })
}

/// What the laser at `pose` sees: each surface's visible runs (sampled
/// every 2 cm) at least 0.3 m long, as noisy walls, with the index of the
/// surface each one is.
fn observe(
    scene: &[Surface],
    pose: &Pose2,
    laser: &Laser,
    rng: &mut ChaCha8Rng,
) -> (Vec<Wall>, Vec<usize>) {
    let o = pose.position();
    let inv = pose.inverse();
    let mut walls = Vec::new();
    let mut truth = Vec::new();
    for (k, s) in scene.iter().enumerate() {
        let d = s.normal.dot(&(s.a - o));
        let reach = if s.glass { 3.0 } else { laser.range_m };
        if d <= 0.05 || d > reach {
            continue;
        }
        let len = (s.b - s.a).norm();
        let n = (len / 0.02).ceil() as usize;
        let visible: Vec<bool> = (0..=n)
            .map(|i| {
                let q = s.a + (s.b - s.a) * (i as f64 / n as f64);
                let local = inv.transform_point(&q);
                (q - o).norm() <= reach
                    && local.y.atan2(local.x).abs() <= laser.fov_rad / 2.0
                    && !blocked(scene, k, &o, &q)
            })
            .collect();
        let mut i = 0;
        while i <= n {
            if !visible[i] {
                i += 1;
                continue;
            }
            let start = i;
            while i <= n && visible[i] {
                i += 1;
            }
            let (p0, p1) = (
                s.a + (s.b - s.a) * (start as f64 / n as f64),
                s.a + (s.b - s.a) * ((i - 1) as f64 / n as f64),
            );
            if (p1 - p0).norm() < 0.3 {
                continue;
            }
            let (sd, sg) = if s.glass {
                (4.0 * laser.sigma_d_m, 4.0 * laser.sigma_gamma_rad)
            } else {
                (laser.sigma_d_m, laser.sigma_gamma_rad)
            };
            let alpha = s.normal.y.atan2(s.normal.x);
            let mut ends = [inv.transform_point(&p0), inv.transform_point(&p1)];
            let gamma = wrap_angle(alpha - pose.theta);
            let dir = Vector2::new(-gamma.sin(), gamma.cos());
            if dir.dot(&(ends[1] - ends[0])) < 0.0 {
                ends.swap(0, 1);
            }
            walls.push(Wall {
                d_m: d + Normal::new(0.0, sd).map_or(0.0, |g| g.sample(rng)),
                gamma_rad: wrap_angle(gamma + Normal::new(0.0, sg).map_or(0.0, |g| g.sample(rng))),
                covariance: Matrix2::new(sd * sd, 0.0, 0.0, sg * sg),
                points: if s.glass { 16 } else { i - start },
                rms_residual_m: sd,
                ends,
            });
            truth.push(k);
        }
    }
    (walls, truth)
}

/// Poses along `waypoints` every 5 cm, turning on the spot (5° a step)
/// at each.
fn path(start: Pose2, waypoints: &[(f64, f64)]) -> Vec<Pose2> {
    let mut out = vec![start];
    let mut at = start;
    for &(x, y) in waypoints {
        let target = Point2::new(x, y);
        let heading = (target.y - at.y).atan2(target.x - at.x);
        while wrap_angle(heading - at.theta).abs() > 1e-9 {
            let turn = wrap_angle(heading - at.theta).clamp(-0.087, 0.087);
            at.theta = wrap_angle(at.theta + turn);
            out.push(at);
        }
        let dist = (target - at.position()).norm();
        let steps = (dist / 0.05).ceil() as usize;
        let from = at.position();
        for i in 1..=steps {
            let p = from + (target - from) * (i as f64 / steps as f64);
            at = Pose2::new(p.x, p.y, heading);
            out.push(at);
        }
    }
    out
}

/// What a drive did.
struct Drive {
    filter: WallMapEkf,
    /// Matches of an observation to a map wall that is another surface.
    false_matches: usize,
    matches: usize,
    /// Distance of the last pose from the truth, filter and odometry, m.
    final_error_m: f64,
    odometry_error_m: f64,
}

/// The scene's surface a map wall is: same facing, nearest line, seen
/// stretches overlapping.
fn truth_of(scene: &[Surface], w: &MapWall) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (k, s) in scene.iter().enumerate() {
        let alpha = s.normal.y.atan2(s.normal.x);
        if wrap_angle(alpha - w.alpha_rad).abs() > 0.1 {
            continue;
        }
        let off = (w.rho_m - w.normal().dot(&s.a.coords)).abs();
        let (a, b) = (w.along(&s.a), w.along(&s.b));
        if w.gap_to(a, b) > 0.0 {
            continue;
        }
        if best.is_none_or(|(_, o)| off < o) {
            best = Some((k, off));
        }
    }
    best.map(|b| b.0)
}

/// Drives `poses` through `scene`, the filter started at the true first
/// pose (or at `start` when given), with odometry 2 % long and drifting
/// 1° per metre.
fn drive(
    scene: &[Surface],
    poses: &[Pose2],
    laser: &Laser,
    mut filter: WallMapEkf,
    seed: u64,
    mut each: impl FnMut(usize, &WallMapEkf, &MapUpdate),
) -> Drive {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut odo = poses[0];
    let (mut false_matches, mut matches) = (0, 0);
    let jitter = Normal::new(0.0, 1.0).ok();
    for (i, pair) in poses.windows(2).enumerate() {
        let step = pair[0].inverse() * pair[1];
        let dist = step.x.hypot(step.y);
        let mut g = || jitter.map_or(0.0, |n| n.sample(&mut rng));
        let measured = Pose2::new(
            step.x * 1.02 + 0.002 * g(),
            step.y + 0.002 * g(),
            step.theta + 1f64.to_radians() * dist + 0.002 * g(),
        );
        odo = odo * measured;
        let covariance = Matrix3::from_diagonal(&nalgebra::Vector3::new(
            (0.03 * dist + 0.003).powi(2),
            (0.01 * dist + 0.003).powi(2),
            (0.03 * dist + 0.03 * step.theta.abs() + 0.003).powi(2),
        ));
        filter.predict(&Displacement {
            since: stucco_core::Stamp::ZERO,
            until: stucco_core::Stamp::ZERO,
            pose: measured,
            covariance,
        });
        let (seen, truth) = observe(scene, &pair[1], laser, &mut rng);
        let update = filter.scan(&seen);
        for &(j, id) in &update.matched {
            matches += 1;
            let w = filter.walls().iter().find(|w| w.id == id);
            if w.and_then(|w| truth_of(scene, w)) != Some(truth[j]) {
                false_matches += 1;
            }
        }
        each(i, &filter, &update);
    }
    let last = poses[poses.len() - 1];
    let err = |p: Pose2| (p.position() - last.position()).norm();
    Drive {
        final_error_m: err(filter.pose()),
        odometry_error_m: err(odo),
        filter,
        false_matches,
        matches,
    }
}

fn exact_start(poses: &[Pose2]) -> WallMapEkf {
    WallMapEkf::new(WallMapConfig::default(), poses[0], Matrix3::zeros())
}

/// The map wall closest to the line of scene surface `s`, and its errors
/// (offset, m; angle, rad).
fn wall_for(filter: &WallMapEkf, scene: &[Surface], s: usize) -> Option<(MapWall, f64, f64)> {
    filter
        .walls()
        .iter()
        .filter(|w| truth_of(scene, w) == Some(s))
        .map(|w| {
            let alpha = scene[s].normal.y.atan2(scene[s].normal.x);
            let rho = scene[s].normal.dot(&scene[s].a.coords);
            (
                w.clone(),
                (w.rho_m - rho).abs(),
                wrap_angle(w.alpha_rad - alpha).abs(),
            )
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// Round a 6 × 4 m room, twice.
fn loop_in_room() -> Vec<Pose2> {
    let round = [(5.0, 1.0), (5.0, 3.0), (1.0, 3.0), (1.0, 1.0)];
    let twice: Vec<(f64, f64)> = round.iter().chain(&round).copied().collect();
    path(Pose2::new(1.0, 1.0, 0.0), &twice)
}

#[test]
fn maps_a_room_and_keeps_the_robot_on_it() {
    let scene = room(6.0, 4.0);
    let poses = loop_in_room();
    let mut worst_asymmetry = 0.0f64;
    let mut lowest_eigenvalue = f64::INFINITY;
    let run = drive(
        &scene,
        &poses,
        &Laser::default(),
        exact_start(&poses),
        1,
        |_, f, _| {
            let p = f.covariance();
            worst_asymmetry = worst_asymmetry.max((p - p.transpose()).amax());
            let e = SymmetricEigen::new(p.clone()).eigenvalues.min();
            lowest_eigenvalue = lowest_eigenvalue.min(e);
        },
    );
    assert_eq!(run.false_matches, 0, "of {} matches", run.matches);
    assert!(run.matches > 1000, "{} matches", run.matches);
    let map = run.filter.map();
    assert_eq!(map.building_walls().count(), 4, "{:#?}", map.walls);
    for s in 0..4 {
        let (w, off, ang) = wall_for(&run.filter, &scene, s).expect("every wall mapped");
        assert!(
            off < 0.015 && ang < 0.3f64.to_radians(),
            "wall {s}: {w:?} off {off} m, {ang} rad"
        );
    }
    assert!(
        run.final_error_m < 0.03 && run.odometry_error_m > 0.15,
        "filter {} m, odometry {} m",
        run.final_error_m,
        run.odometry_error_m
    );
    assert!(worst_asymmetry < 1e-12, "asymmetry {worst_asymmetry}");
    assert!(lowest_eigenvalue > -1e-12, "eigenvalue {lowest_eigenvalue}");
}

#[test]
fn a_step_of_ten_centimetres_makes_two_walls() {
    // The north wall steps back 10 cm half way along.
    let mut scene = room(6.0, 4.0);
    scene[2] = surface((6.0, 4.1), (3.0, 4.1), (0.0, 1.0));
    scene[1] = surface((6.0, 0.0), (6.0, 4.1), (1.0, 0.0));
    scene.push(surface((3.0, 4.1), (3.0, 4.0), (-1.0, 0.0)));
    scene.push(surface((3.0, 4.0), (0.0, 4.0), (0.0, 1.0)));
    let poses = loop_in_room();
    let run = drive(
        &scene,
        &poses,
        &Laser::default(),
        exact_start(&poses),
        2,
        |_, _, _| {},
    );
    assert_eq!(run.false_matches, 0, "of {} matches", run.matches);
    for s in [2, 5] {
        let (w, off, _) = wall_for(&run.filter, &scene, s).expect("both parts mapped");
        assert!(off < 0.015 && w.role == WallRole::Wall, "part {s}: {w:?}");
    }
    let north = run
        .filter
        .walls()
        .iter()
        .filter(|w| w.alpha_rad.sin() > 0.99)
        .count();
    assert_eq!(north, 2, "{:#?}", run.filter.walls());
}

#[test]
fn the_wall_behind_a_cabinet_unmasks_the_false_door() {
    // A cabinet 2 m wide stands 0.6 m before the north wall. The robot
    // first faces it from 1 m with a 90° laser, which sees only its front:
    // a wall at y = 3, with (as far as it knows) a door beside it.
    let mut scene = room(6.0, 4.0);
    scene.extend(cabinet((2.0, 3.0), (4.0, 3.4)));
    let front = 4; // the cabinet's face y = 3
    let laser = Laser {
        fov_rad: 90f64.to_radians(),
        ..Laser::default()
    };
    let facing = Pose2::new(3.0, 2.0, std::f64::consts::FRAC_PI_2);
    let mut poses = vec![facing; 8];
    poses.extend(path(
        facing,
        &[(3.0, 1.2), (1.0, 1.2), (1.0, 2.6), (5.0, 2.6)],
    ));
    let mut before = None;
    let run = drive(&scene, &poses, &laser, exact_start(&poses), 3, |i, f, _| {
        if i == 6 {
            before = Some(f.map());
        }
    });
    let before = before.expect("the drive is long enough");
    let seen_first: Vec<&MapWall> = before.building_walls().collect();
    assert_eq!(
        seen_first.len(),
        1,
        "only the cabinet's face at first: {seen_first:?}"
    );
    assert!((seen_first[0].rho_m - 3.0).abs() < 0.02);
    assert_eq!(run.false_matches, 0, "of {} matches", run.matches);
    let (face, _, _) = wall_for(&run.filter, &scene, front).expect("the face stays a landmark");
    assert_eq!(face.role, WallRole::InFront, "{face:?}");
    let (north, off, _) = wall_for(&run.filter, &scene, 2).expect("the wall behind is found");
    assert!(north.role == WallRole::Wall && off < 0.015, "{north:?}");
    let map = run.filter.map();
    assert!(map.building_walls().all(|w| w.id != face.id));
}

#[test]
fn glass_frames_and_the_room_behind_them_stay_apart() {
    // A corridor 2 m wide whose north side is a glass wall (its frames a
    // weak line, seen from near) with an office behind it, 3 m deep.
    let mut scene = vec![
        surface((0.0, 0.0), (10.0, 0.0), (0.0, -1.0)),
        Surface {
            glass: true,
            ..surface((10.0, 2.0), (0.0, 2.0), (0.0, 1.0))
        },
        surface((10.0, 5.0), (0.0, 5.0), (0.0, 1.0)),
        surface((10.0, 0.0), (10.0, 5.0), (1.0, 0.0)),
        surface((0.0, 5.0), (0.0, 0.0), (-1.0, 0.0)),
    ];
    scene.push(surface((4.0, 2.0), (4.0, 5.0), (1.0, 0.0)));
    let poses = path(
        Pose2::new(1.0, 1.0, 0.0),
        &[(9.0, 1.0), (9.0, 1.5), (1.0, 1.5), (1.0, 1.0), (9.0, 1.0)],
    );
    let run = drive(
        &scene,
        &poses,
        &Laser::default(),
        exact_start(&poses),
        4,
        |_, _, _| {},
    );
    assert_eq!(run.false_matches, 0, "of {} matches", run.matches);
    let (frames, off_f, _) = wall_for(&run.filter, &scene, 1).expect("the frames are mapped");
    let (office, off_o, _) = wall_for(&run.filter, &scene, 2).expect("the wall behind is mapped");
    assert!(
        frames.id != office.id && off_f < 0.03 && off_o < 0.03,
        "{frames:?} {office:?}"
    );
    // The office wall stands 3 m behind the glass: a wall of the building.
    assert_eq!(frames.role, WallRole::Wall);
    assert!(run.final_error_m < 0.05, "{} m", run.final_error_m);
}

#[test]
fn a_wall_first_seen_in_two_pieces_becomes_one() {
    // A screen in the room hides the middle of the north wall. The robot
    // looks (90° laser) left of it, then right of it: two pieces of one
    // line, 3.5 m apart. Then it walks behind the screen and sees the wall
    // whole.
    let mut scene = room(8.0, 8.0);
    scene.push(surface((3.5, 3.0), (4.5, 3.0), (0.0, 1.0)));
    scene.push(surface((4.5, 3.02), (3.5, 3.02), (0.0, -1.0)));
    let laser = Laser {
        fov_rad: 90f64.to_radians(),
        ..Laser::default()
    };
    let left = Pose2::new(4.0, 1.0, 135f64.to_radians());
    let right = Pose2::new(4.0, 1.0, 45f64.to_radians());
    let mut poses = vec![left; 6];
    poses.extend(vec![right; 6]);
    poses.extend(path(
        right,
        &[(6.0, 1.0), (6.0, 3.5), (4.0, 3.5), (4.0, 3.6)],
    ));
    let mut pieces = 0;
    let run = drive(&scene, &poses, &laser, exact_start(&poses), 5, |i, f, _| {
        if i == 10 {
            pieces = f
                .walls()
                .iter()
                .filter(|w| truth_of(&scene, w) == Some(2))
                .count();
        }
    });
    assert_eq!(pieces, 2, "the north wall starts as two pieces");
    let whole: Vec<&MapWall> = run
        .filter
        .walls()
        .iter()
        .filter(|w| truth_of(&scene, w) == Some(2))
        .collect();
    assert_eq!(whole.len(), 1, "{whole:#?}");
    assert!(whole[0].length_m() > 7.0, "{:?}", whole[0]);
    assert_eq!(run.false_matches, 0);
}

#[test]
fn a_saved_map_localises_a_robot_placed_roughly() {
    let scene = room(6.0, 4.0);
    let poses = loop_in_room();
    let built = drive(
        &scene,
        &poses,
        &Laser::default(),
        exact_start(&poses),
        6,
        |_, _, _| {},
    );
    let text = serde_json::to_string(&built.filter.map()).expect("a map serialises");
    let map: WallMap = serde_json::from_str(&text).expect("and reads back");
    assert_eq!(map, built.filter.map());
    // A cabinet now stands in the room; the robot starts 15 cm and 3° off.
    let mut furnished = scene.clone();
    furnished.extend(cabinet((2.5, 1.8), (3.5, 2.2)));
    let config = WallMapConfig {
        extend_map: false,
        ..WallMapConfig::default()
    };
    let placed = Pose2::new(poses[0].x + 0.1, poses[0].y - 0.11, 3f64.to_radians());
    let rough = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.04, 0.04, 0.003));
    let filter = WallMapEkf::in_map(config, &map, placed, rough);
    let run = drive(
        &furnished,
        &poses,
        &Laser::default(),
        filter,
        7,
        |_, _, _| {},
    );
    assert!(run.final_error_m < 0.03, "{} m", run.final_error_m);
    assert_eq!(
        run.filter.walls().len(),
        map.walls.len(),
        "the map is not extended"
    );
    assert_eq!(run.false_matches, 0);
}

#[test]
fn two_parallel_walls_ten_centimetres_apart_are_never_confused() {
    // A known map: the north wall of a 6 × 4 m room steps back 10 cm at
    // x = 3. The robot stands at y = 2.00 but believes y = 2.05 ± 0.10.
    let mut scene = room(6.0, 4.0);
    scene[2] = surface((6.0, 4.1), (3.0, 4.1), (0.0, 1.0));
    scene.push(surface((3.0, 4.0), (0.0, 4.0), (0.0, 1.0)));
    let known = |s: &Surface, id: WallId| {
        let alpha = s.normal.y.atan2(s.normal.x);
        let mut w = MapWall {
            id,
            rho_m: s.normal.dot(&s.a.coords),
            alpha_rad: alpha,
            covariance: Matrix2::new(1e-6, 0.0, 0.0, 1e-8),
            extent_m: [0.0, 0.0],
            observations: 50,
            wall_behind_scans: 0,
            role: WallRole::Wall,
        };
        let (a, b) = (w.along(&s.a), w.along(&s.b));
        w.extent_m = [a.min(b), a.max(b)];
        w
    };
    let map = WallMap {
        walls: scene.iter().zip(0..).map(|(s, id)| known(s, id)).collect(),
        pose: Pose2::IDENTITY,
    };
    let config = WallMapConfig {
        extend_map: false,
        ..WallMapConfig::default()
    };
    let believed = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-4, 0.01, 1e-6));
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let north = std::f64::consts::FRAC_PI_2;
    // Seeing only the near part, the laser cannot tell which part it is.
    let narrow = Laser {
        fov_rad: 40f64.to_radians(),
        ..Laser::default()
    };
    let truth = Pose2::new(1.2, 2.0, north);
    let mut filter =
        WallMapEkf::in_map(config.clone(), &map, Pose2::new(1.2, 2.05, north), believed);
    for _ in 0..5 {
        let (seen, which) = observe(&scene, &truth, &narrow, &mut rng);
        assert_eq!(which, [4], "only the near part is seen");
        let update = filter.scan(&seen);
        assert!(update.matched.is_empty(), "never forced: {update:?}");
        assert_eq!(update.doubtful, [0]);
    }
    assert!((filter.pose().y - 2.05).abs() < 1e-9, "nothing was applied");
    // Seeing both parts at once, their 10 cm step tells them apart.
    let wide = Laser {
        fov_rad: 90f64.to_radians(),
        ..Laser::default()
    };
    let truth = Pose2::new(2.6, 2.0, north);
    let mut filter = WallMapEkf::in_map(config, &map, Pose2::new(2.6, 2.05, north), believed);
    let (seen, which) = observe(&scene, &truth, &wide, &mut rng);
    assert_eq!(which.len(), 2);
    let update = filter.scan(&seen);
    let mut got: Vec<(usize, WallId)> = update.matched.clone();
    got.sort();
    let expected: Vec<(usize, WallId)> = which
        .iter()
        .enumerate()
        .map(|(j, &k)| (j, k as WallId))
        .collect();
    assert_eq!(got, expected, "{update:?}");
    assert!((filter.pose().y - 2.0).abs() < 0.02, "{:?}", filter.pose());
}

#[test]
fn pieces_of_one_line_in_a_scan_count_once() {
    // The north wall of a known room seen in two pieces (a door between):
    // both are that wall, and together they inform the pose no more than
    // the better one alone would.
    let scene = room(6.0, 4.0);
    let map = {
        let built = drive(
            &scene,
            &loop_in_room(),
            &Laser::default(),
            exact_start(&loop_in_room()),
            9,
            |_, _, _| {},
        );
        built.filter.map()
    };
    let config = WallMapConfig {
        extend_map: false,
        ..WallMapConfig::default()
    };
    let pose = Pose2::new(3.0, 2.0, std::f64::consts::FRAC_PI_2);
    let rough = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.01, 0.01, 1e-4));
    let piece = |x0: f64, x1: f64| Wall {
        d_m: 2.0,
        gamma_rad: 0.0,
        covariance: Matrix2::new(1e-4, 0.0, 0.0, 1e-4),
        points: 50,
        rms_residual_m: 0.005,
        ends: [Point2::new(2.0, 3.0 - x1), Point2::new(2.0, 3.0 - x0)],
    };
    let mut both = WallMapEkf::in_map(config.clone(), &map, pose, rough);
    let update = both.scan(&[piece(0.2, 2.4), piece(3.4, 5.8)]);
    let north = map
        .walls
        .iter()
        .find(|w| truth_of(&scene, w) == Some(2))
        .expect("mapped");
    assert_eq!(update.matched, [(0, north.id), (1, north.id)]);
    let mut one = WallMapEkf::in_map(config, &map, pose, rough);
    one.scan(&[piece(0.2, 5.8)]);
    let (a, b) = (
        both.pose_covariance()[(1, 1)],
        one.pose_covariance()[(1, 1)],
    );
    assert!((a - b).abs() < 0.05 * b, "two pieces {a}, one line {b}");
}

/// A filter whose map holds one wall, `y = rho` (facing the robot below
/// it) from `x = x0` to `x1`, seen `observations` times.
fn one_wall_along_x(rho: f64, [x0, x1]: [f64; 2], observations: u32) -> WallMapEkf {
    let wall = MapWall {
        id: 0,
        rho_m: rho,
        alpha_rad: FRAC_PI_2,
        covariance: Matrix2::identity() * 1e-6,
        extent_m: [-x1, -x0],
        observations,
        wall_behind_scans: 0,
        role: WallRole::Wall,
    };
    let map = WallMap {
        walls: vec![wall],
        pose: Pose2::IDENTITY,
    };
    WallMapEkf::in_map(
        WallMapConfig::default(),
        &map,
        Pose2::IDENTITY,
        Matrix3::zeros(),
    )
}

#[test]
fn a_line_askew_along_a_longer_wall_is_held_back_by_it() {
    // A known wall y = 7 from x = 0 to 18.
    let f = one_wall_along_x(7.0, [0.0, 18.0], 100);
    let p = |x: f64, y: f64| Point2::new(x, y);
    // Tilted 5° across the wall and the radiator before it: held back
    // until seen more often than the wall.
    let askew = (FRAC_PI_2 + 5f64.to_radians(), [p(6.7, 7.02), p(9.1, 6.82)]);
    assert_eq!(f.askew_rival(askew.0, &askew.1), Some(100));
    // The radiator's face itself, parallel 10 cm before the wall: a face
    // before a wall, founded.
    assert_eq!(f.askew_rival(FRAC_PI_2, &[p(7.6, 6.9), p(9.1, 6.9)]), None);
    // A wall meeting it at a right angle, and one at 20° ending at it:
    // other walls.
    assert_eq!(f.askew_rival(0.0, &[p(10.0, 3.0), p(10.0, 7.0)]), None);
    assert_eq!(
        f.askew_rival(FRAC_PI_2 + 20f64.to_radians(), &[p(6.0, 6.9), p(8.0, 6.2)]),
        None
    );
    // Askew but well away from the wall (a table's edge in the room).
    assert_eq!(f.askew_rival(askew.0, &[p(6.7, 5.02), p(9.1, 4.82)]), None);
}

#[test]
fn a_line_across_a_face_and_what_lies_past_it_is_held_back_by_the_face() {
    // A bed's foot, y = 6.1 from x = 0.2 to 2.2, seen 40 times; the map
    // does not hold the wall behind it.
    let f = one_wall_along_x(6.1, [0.2, 2.2], 40);
    let p = |x: f64, y: f64| Point2::new(x, y);
    // A line from the foot on across the legs of the desk beside it, 2.5°
    // askew and longer than the foot: held back until seen more often.
    let across = [p(0.3, 6.17), p(4.0, 6.01)];
    let tilt = (6.17f64 - 6.01).atan2(3.7);
    assert!(tilt > 2f64.to_radians() && tilt < 3f64.to_radians());
    assert_eq!(f.askew_rival(FRAC_PI_2 - tilt, &across), Some(40));
    // The foot itself seen again, and a wall 1° off it (parallel within
    // what a fit's angle strays): no rival.
    assert_eq!(f.askew_rival(FRAC_PI_2, &[p(0.2, 6.1), p(2.2, 6.1)]), None);
    assert_eq!(
        f.askew_rival(FRAC_PI_2 - 1f64.to_radians(), &[p(0.2, 6.12), p(2.2, 6.09)]),
        None
    );
}

/// An observation in the frame of a laser at the origin facing +x of the
/// line from `a` to `b` (its normal away from the laser).
fn seen(a: (f64, f64), b: (f64, f64), points: u32) -> Wall {
    let (a, b) = (Point2::new(a.0, a.1), Point2::new(b.0, b.1));
    let u = (b - a).normalize();
    let mut n = Vector2::new(-u.y, u.x);
    if n.dot(&a.coords) < 0.0 {
        n = -n;
    }
    Wall {
        d_m: n.dot(&a.coords),
        gamma_rad: n.y.atan2(n.x),
        covariance: Matrix2::new(1e-4, 0.0, 0.0, 1e-4),
        points: points as usize,
        rms_residual_m: 0.01,
        ends: [a, b],
    }
}

/// A filter that saw `askew` 4 times (founding it), then `surface` 12
/// times: the filter, and the surface's one building wall (on x = 3), once
/// the walls marked across on the way are the askew fit's alone.
fn askew_fit_then_its_surface(askew: &Wall, surface: &Wall) -> (WallMapEkf, MapWall) {
    let mut f = WallMapEkf::new(WallMapConfig::default(), Pose2::IDENTITY, Matrix3::zeros());
    for _ in 0..4 {
        f.scan(std::slice::from_ref(askew));
    }
    assert_eq!(f.map().walls.len(), 1, "the askew fit is founded first");
    let askew_id = f.map().walls[0].id;
    let mut across = Vec::new();
    for _ in 0..12 {
        across.extend(f.scan(std::slice::from_ref(surface)).across);
    }
    assert_eq!(across, [askew_id]);
    let map = f.map();
    let building: Vec<&MapWall> = map.building_walls().collect();
    assert_eq!(building.len(), 1, "{building:?}");
    let wall = building[0].clone();
    assert!((wall.rho_m - 3.0).abs() < 0.01 && wall.alpha_rad.abs() < 0.01);
    (f, wall)
}

#[test]
fn a_fit_across_a_wall_and_a_door_leaf_is_marked_once_the_wall_is_mapped() {
    // The first sightings, far off through a door: the wall (x = 3) and a
    // shut door's leaf recessed 7.5 cm in it, fitted as one line 4° askew;
    // then the wall itself, seen whole from near: founded, and the askew
    // fit along it marked, no wall of the building any more.
    let askew = seen((3.0, -0.2), (3.0 + 1.3 * 4f64.to_radians().tan(), 1.1), 24);
    let wall = seen((3.0, -4.0), (3.0, 4.0), 300);
    let (mut f, _) = askew_fit_then_its_surface(&askew, &wall);
    // The askew fit seen again, less often than the wall, founds nothing
    // beside it.
    for _ in 0..6 {
        f.scan(std::slice::from_ref(&askew));
    }
    assert_eq!(f.map().walls.len(), 2);
    assert_eq!(f.map().building_walls().count(), 1);
}

#[test]
fn a_longer_fit_across_a_face_is_marked_once_the_face_is_mapped() {
    // The first sightings, far off: a bed's foot (x = 3, 2 m long) and the
    // desk's legs past its end, fitted as one line 3.7 m long, 2.5° askew;
    // then the foot itself, seen from everywhere in the room: founded once
    // it out-sights the fit, which is marked though it is the longer.
    let tilt = 2.5f64.to_radians();
    let askew = seen((3.0, -0.9), (3.0 - 3.7 * tilt.tan(), 2.8), 40);
    let foot = seen((3.0, -1.0), (3.0, 1.0), 60);
    let (_, wall) = askew_fit_then_its_surface(&askew, &foot);
    assert!(wall.length_m() < 2.5, "{wall:?}");
}

#[test]
fn a_wall_with_a_shorter_face_recessed_in_it_stays_a_wall() {
    // A wall at x = 3, 6 m, and a shut door's leaf 7.5 cm behind it seen
    // through its frame, 0.7 m: the leaf stands behind, not the wall in
    // front of something.
    let mut f = WallMapEkf::new(WallMapConfig::default(), Pose2::IDENTITY, Matrix3::zeros());
    let wall = [
        seen((3.0, -3.0), (3.0, -0.35), 200),
        seen((3.0, 0.35), (3.0, 3.0), 200),
    ];
    let leaf = seen((3.075, -0.35), (3.075, 0.35), 30);
    for _ in 0..10 {
        f.scan(&[wall[0].clone(), wall[1].clone(), leaf.clone()]);
    }
    let roles: Vec<WallRole> = f.map().walls.iter().map(|w| w.role).collect();
    assert!(roles.iter().all(|r| *r == WallRole::Wall), "{roles:?}");
}
