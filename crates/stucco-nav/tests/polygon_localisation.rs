//! Localising in a room that is not a rectangle, its drawing as the prior
//! map: which filter to put on the runtime path (issue 33, part 1).
//!
//! - The room filter on the drawing's box: its four outer lines, each of
//!   which holds a stretch of wall in an L, a T, a room with a chimney
//!   breast or with a corner cut at an angle; the notch's walls must be
//!   gated out.
//! - The room filter in the drawing's polygon ([`RoomShape::polygon`]).
//! - The wall-map filter in the drawing's walls, all of them.
//!
//! A robot stands at random places in each room, started 5 cm and 2° off,
//! and takes 40 scans, then tours the room or not. The drawing is exact,
//! or each corner off by up to 3 cm as a site drawing is: the walls
//! themselves then stand off the drawing's frame, so the errors that count
//! are frame-free, the robot's distances to the walls as built. Run with
//! `cargo test --release -p stucco-nav --test polygon_localisation -- --ignored --nocapture`
//! (the default run takes one tour in an L and one in the angled room).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use nalgebra::{DVector, Matrix2, Matrix3, Point2, Vector2};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stucco_core::{EncoderSample, LaserSpec, Pose2, Stamp, Twist2, wrap_angle};
use stucco_nav::synthetic::{Segment, SyntheticLaser, World};
use stucco_nav::*;

/// The rooms, corners counter-clockwise from the box's corner.
fn rooms() -> Vec<(&'static str, Vec<[f64; 2]>)> {
    vec![
        (
            "L",
            vec![
                [0.0, 0.0],
                [6.0, 0.0],
                [6.0, 2.5],
                [3.5, 2.5],
                [3.5, 5.0],
                [0.0, 5.0],
            ],
        ),
        (
            "T",
            vec![
                [2.0, 0.0],
                [4.0, 0.0],
                [4.0, 2.5],
                [6.5, 2.5],
                [6.5, 5.0],
                [0.0, 5.0],
                [0.0, 2.5],
                [2.0, 2.5],
            ],
        ),
        (
            "chimney breast",
            vec![
                [0.0, 0.0],
                [4.5, 0.0],
                [4.5, 4.0],
                [2.8, 4.0],
                [2.8, 3.55],
                [1.6, 3.55],
                [1.6, 4.0],
                [0.0, 4.0],
            ],
        ),
        (
            "angled",
            vec![[0.0, 0.0], [5.0, 0.0], [5.0, 2.5], [3.0, 4.5], [0.0, 4.5]],
        ),
    ]
}

fn world(corners: &[[f64; 2]]) -> World {
    let n = corners.len();
    World {
        segments: (0..n)
            .map(|k| Segment {
                a: Point2::from(corners[k]),
                b: Point2::from(corners[(k + 1) % n]),
            })
            .collect(),
        circles: Vec::new(),
    }
}

/// Distance from `p` to the nearest wall, negative outside.
fn clearance(corners: &[[f64; 2]], p: &Point2<f64>) -> f64 {
    stucco_plan::Outline::new(corners).clearance_m(p)
}

/// The drawing's walls as a map: each edge's line, the free side inside.
fn drawn_map(corners: &[[f64; 2]], sigma_m: f64) -> WallMap {
    let n = corners.len();
    let walls = (0..n)
        .map(|k| {
            let (a, b) = (Point2::from(corners[k]), Point2::from(corners[(k + 1) % n]));
            let d = (b - a).normalize();
            // Outward: the room lies on the edge's left.
            let normal = Vector2::new(d.y, -d.x);
            let alpha = normal.y.atan2(normal.x);
            let dir = Vector2::new(-alpha.sin(), alpha.cos());
            let (u0, u1) = (dir.dot(&a.coords), dir.dot(&b.coords));
            MapWall {
                id: k as u32,
                rho_m: normal.dot(&a.coords),
                alpha_rad: alpha,
                covariance: Matrix2::new(
                    sigma_m * sigma_m,
                    0.0,
                    0.0,
                    (sigma_m / (b - a).norm()).powi(2),
                ),
                extent_m: [u0.min(u1), u0.max(u1)],
                observations: 10,
                wall_behind_scans: 0,
                role: WallRole::Wall,
            }
        })
        .collect();
    WallMap {
        walls,
        pose: Pose2::new(0.0, 0.0, 0.0),
    }
}

#[derive(Default)]
struct Errors {
    runs: usize,
    lost: usize,
    pos: Vec<f64>,
    head: Vec<f64>,
    /// Worst error of the robot's distance to a wall on the box's lines,
    /// against the walls as built (frame-free: what plastering needs).
    walls: Vec<f64>,
}

impl Errors {
    fn add(&mut self, est: &Pose2, truth: &Pose2) {
        self.runs += 1;
        let e = (est.position() - truth.position()).norm();
        let h = wrap_angle(est.theta - truth.theta).abs();
        if e > 0.2 {
            self.lost += 1;
        }
        self.pos.push(e);
        self.head.push(h);
    }

    fn line(&mut self) -> String {
        self.pos.sort_by(f64::total_cmp);
        self.head.sort_by(f64::total_cmp);
        self.walls.sort_by(f64::total_cmp);
        let q = |v: &[f64], f: f64| v[((v.len() - 1) as f64 * f) as usize];
        format!(
            "median {:.1} mm, 95 % {:.1} mm, heading median {:.2}°, lost {} of {}; \
             to the walls as built: median {:.1} mm, 95 % {:.1} mm",
            q(&self.pos, 0.5) * 1e3,
            q(&self.pos, 0.95) * 1e3,
            q(&self.head, 0.5).to_degrees(),
            self.lost,
            self.runs,
            q(&self.walls, 0.5) * 1e3,
            q(&self.walls, 0.95) * 1e3,
        )
    }
}

/// Where the robot stands while it scans: `None` standing still at its
/// start, or a tour through `stops` places of the room.
#[derive(Clone, Copy)]
enum Run {
    Still,
    Tour { stops: usize },
}

/// A random place in the room as built, clear of its walls by 0.7 m (the
/// laser too).
fn a_place(rng: &mut ChaCha8Rng, truth: &[[f64; 2]], size: [f64; 2], mount: &Pose2) -> Pose2 {
    loop {
        let p = Pose2::new(
            rng.random_range(0.0..size[0]),
            rng.random_range(0.0..size[1]),
            rng.random_range(-3.1..3.1),
        );
        if clearance(truth, &p.position()) > 0.7 && clearance(truth, &(p * *mount).position()) > 0.7
        {
            return p;
        }
    }
}

/// The three filters the study sets side by side.
struct Filters {
    boxed: RoomEkf,
    polygon: RoomEkf,
    mapped: WallMapEkf,
    drawing: WallMap,
}

impl Filters {
    fn new(drawn: &[[f64; 2]], size: [f64; 2], start: Pose2, sigma: f64, mount: Pose2) -> Self {
        let pose_cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(
            0.05f64.powi(2),
            0.05f64.powi(2),
            2f64.to_radians().powi(2),
        ));
        let config = RoomEkfConfig::new(OdometryConfig::default(), mount);
        let boxed = RoomEkf::new(
            config.clone(),
            RoomState::new(start.x, start.y, start.theta, size[0], size[1]),
            RoomCovariance::from_diagonal(&nalgebra::SVector::<f64, 5>::new(
                0.05f64.powi(2),
                0.05f64.powi(2),
                2f64.to_radians().powi(2),
                sigma * sigma,
                sigma * sigma,
            )),
            Stamp::ZERO,
        );
        let polygon = RoomEkf::in_polygon(
            config,
            RoomShape::polygon(drawn, sigma).unwrap(),
            start,
            pose_cov,
            Stamp::ZERO,
        );
        let drawing = drawn_map(drawn, sigma);
        let mapped = WallMapEkf::in_map(
            WallMapConfig {
                laser_mount: mount,
                ..WallMapConfig::default()
            },
            &drawing,
            start,
            pose_cov,
        );
        Filters {
            boxed,
            polygon,
            mapped,
            drawing,
        }
    }

    fn odometry(&mut self, sample: EncoderSample) {
        self.boxed.odometry(sample);
        self.polygon.odometry(sample);
    }

    fn scan(&mut self, stamp: Stamp, walls: &[Wall]) {
        self.boxed.scan(stamp, walls, &[]);
        self.polygon.scan(stamp, walls, &[]);
        self.mapped.scan(walls);
    }
}

/// Drives the robot from `from` to `to` (a pivot, a straight run, a pivot
/// to `to`'s heading) in steps of 5 cm and 0.1 rad, the wheels slipping
/// by up to 1 %: feeds the filters the encoders and a scan at each step.
fn drive(
    filters: &mut Filters,
    from: Pose2,
    to: Pose2,
    ticks: &mut [i64; 2],
    t: &mut f64,
    scan: &mut dyn FnMut(&Pose2, &mut ChaCha8Rng) -> Vec<Wall>,
    rng: &mut ChaCha8Rng,
) {
    let odo = OdometryConfig::default();
    let per_m = f64::from(odo.ticks_per_rev) / (std::f64::consts::TAU * odo.wheel_radius_m[0]);
    let run = to.position() - from.position();
    let bearing = run.y.atan2(run.x);
    let legs = [
        (0.0, wrap_angle(bearing - from.theta)),
        (run.norm(), 0.0),
        (0.0, wrap_angle(to.theta - bearing)),
    ];
    let mut pose = from;
    // Wheels' travel not yet counted in whole ticks, m.
    let mut carried = [0.0f64; 2];
    for (dist, turn) in legs {
        let steps = ((dist / 0.05).max(turn.abs() / 0.1)).ceil().max(1.0) as usize;
        for _ in 0..steps {
            let (ds, da) = (dist / steps as f64, turn / steps as f64);
            pose = Pose2::new(
                pose.x + ds * pose.theta.cos(),
                pose.y + ds * pose.theta.sin(),
                wrap_angle(pose.theta + da),
            );
            let half = 0.5 * odo.track_m * da;
            let mut counted = [0.0; 2];
            for (w, travel) in [ds - half, ds + half].into_iter().enumerate() {
                let slipped = travel * (1.0 + 0.01 * rng.random_range(-1.0..=1.0));
                carried[w] += slipped * per_m;
                let whole = carried[w].trunc();
                ticks[w] += whole as i64;
                carried[w] -= whole;
                counted[w] = whole / per_m;
            }
            let since = Stamp::from_secs_f64(*t);
            *t += 0.025;
            let stamp = Stamp::from_secs_f64(*t);
            filters.odometry(EncoderSample {
                stamp,
                left_ticks: ticks[0],
                right_ticks: ticks[1],
            });
            // The wall-map filter takes the same ticks as a displacement.
            let mut d = Displacement::zero(since);
            d.extend(counted, stamp, &odo);
            filters.mapped.predict(&d);
            let walls = scan(&pose, rng);
            filters.scan(stamp, &walls);
        }
    }
}

/// What one run of the three filters came to.
struct Outcome {
    truth: Pose2,
    /// The box filter's, the polygon filter's and the wall-map filter's
    /// pose.
    estimates: [Pose2; 3],
    /// Their worst error of the robot's distance to a wall on the box's
    /// lines against the walls as built.
    to_walls: [f64; 3],
    /// The polygon filter's worst error of where a wall's middle is from
    /// the robot.
    every_wall_middle: f64,
}

/// One run: the room as built drawn off by up to `drawing_off_m`, the
/// robot at a random place, scanning there and then on `run`.
fn one_run(
    drawn: &[[f64; 2]],
    drawing_off_m: f64,
    run: Run,
    rng: &mut ChaCha8Rng,
    rwht: &mut RwhtExtractor,
) -> Outcome {
    let mount = Pose2::new(0.35, 0.0, 0.0);
    let laser = SyntheticLaser::new(LaserSpec::ibeo_ladar_2d());
    // The room as built: the drawing's corners, each off a little.
    let truth: Vec<[f64; 2]> = drawn
        .iter()
        .map(|c| {
            [
                c[0] + rng.random_range(-1.0..=1.0) * drawing_off_m,
                c[1] + rng.random_range(-1.0..=1.0) * drawing_off_m,
            ]
        })
        .collect();
    let scene = world(&truth);
    let size = drawn
        .iter()
        .fold([0.0f64; 2], |m, c| [m[0].max(c[0]), m[1].max(c[1])]);
    let first = a_place(rng, &truth, size, &mount);
    let start = Pose2::new(
        first.x + 0.05 * rng.random_range(-1.0..=1.0),
        first.y + 0.05 * rng.random_range(-1.0..=1.0),
        first.theta + 2f64.to_radians() * rng.random_range(-1.0..=1.0),
    );
    let sigma = drawing_off_m.max(0.005);
    let mut filters = Filters::new(drawn, size, start, sigma, mount);
    let mut scan = |at: &Pose2, rng: &mut ChaCha8Rng| {
        let s = laser.scan(&scene, &(*at * mount), &Twist2::default(), Stamp::ZERO, rng);
        rwht.extract(&ScanPoints::from_scan(&s))
    };
    let mut t = 0.0;
    for _ in 0..40 {
        t += 0.025;
        let walls = scan(&first, rng);
        filters.scan(Stamp::from_secs_f64(t), &walls);
    }
    let mut pose = first;
    if let Run::Tour { stops } = run {
        let mut ticks = [0i64; 2];
        filters.odometry(EncoderSample {
            stamp: Stamp::from_secs_f64(t),
            left_ticks: 0,
            right_ticks: 0,
        });
        let mut visited = 0;
        while visited < stops {
            let next = a_place(rng, &truth, size, &mount);
            // Only a straight run clear of the walls.
            let clear = (1..20).all(|i| {
                let f = f64::from(i) / 20.0;
                let p = pose.position() + (next.position() - pose.position()) * f;
                clearance(&truth, &p) > 0.5
            });
            if !clear {
                continue;
            }
            drive(&mut filters, pose, next, &mut ticks, &mut t, &mut scan, rng);
            pose = next;
            visited += 1;
        }
    }
    let (x, _): (DVector<f64>, _) = filters.boxed.now();
    let (xp, _): (DVector<f64>, _) = filters.polygon.now();
    let estimates = [
        Pose2::new(x[0], x[1], x[2]),
        Pose2::new(xp[0], xp[1], xp[2]),
        filters.mapped.pose(),
    ];
    // The robot's distance to each wall on the box's lines: as
    // built, and as each filter has it; and, for the polygon
    // filter, to every wall.
    let (mut worst_box, mut worst_poly, mut worst_map, mut worst_every) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let n = drawn.len();
    let poly_corners = filters.polygon.shape().corners(&xp);
    for k in 0..n {
        let (ta, tb) = (Point2::from(truth[k]), Point2::from(truth[(k + 1) % n]));
        let d = (tb - ta).normalize();
        let inward = Vector2::new(-d.y, d.x);
        let built = inward.dot(&(pose.position() - ta));
        let (normal, rho) = filters.polygon.shape().line(&xp, k);
        let poly_d = rho - normal.dot(&xp.fixed_rows::<2>(0).into_owned());
        // Where the wall's middle is from the robot, as built and
        // as the polygon filter has it.
        let seen_from = Pose2::new(xp[0], xp[1], xp[2]).inverse();
        let mid = |c: &[[f64; 2]]| {
            Point2::new(
                0.5 * (c[k][0] + c[(k + 1) % n][0]),
                0.5 * (c[k][1] + c[(k + 1) % n][1]),
            )
        };
        let est_mid = seen_from.transform_point(&mid(&poly_corners));
        let true_mid = pose.inverse().transform_point(&mid(&truth));
        worst_every = worst_every.max((est_mid - true_mid).norm());
        let (a, b) = (drawn[k], drawn[(k + 1) % n]);
        let side = if a[0] == 0.0 && b[0] == 0.0 {
            Some(0)
        } else if a[1] == 0.0 && b[1] == 0.0 {
            Some(1)
        } else if a[0] == size[0] && b[0] == size[0] {
            Some(2)
        } else if a[1] == size[1] && b[1] == size[1] {
            Some(3)
        } else {
            None
        };
        let Some(side) = side else { continue };
        let boxed_d = [x[0], x[1], x[3] - x[0], x[4] - x[1]][side];
        // The map wall along the drawn one (walls in one line,
        // either side of a chimney breast, are merged into one).
        let drawn_w = &filters.drawing.walls[k];
        let w = filters
            .mapped
            .walls()
            .iter()
            .filter(|w| wrap_angle(w.alpha_rad - drawn_w.alpha_rad).abs() < 0.1)
            .min_by(|p, q| {
                (p.rho_m - drawn_w.rho_m)
                    .abs()
                    .total_cmp(&(q.rho_m - drawn_w.rho_m).abs())
            })
            .unwrap();
        let mapped_d = w.rho_m - w.normal().dot(&filters.mapped.pose().position().coords);
        worst_box = worst_box.max((boxed_d - built).abs());
        worst_poly = worst_poly.max((poly_d - built).abs());
        worst_map = worst_map.max((mapped_d - built).abs());
    }
    Outcome {
        truth: pose,
        estimates,
        to_walls: [worst_box, worst_poly, worst_map],
        every_wall_middle: worst_every,
    }
}

fn study(drawing_off_m: f64, run: Run) {
    let mut rwht = RwhtExtractor::new(RwhtConfig::default()).unwrap();
    for (name, drawn) in rooms() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut boxed, mut polygon, mut mapped) =
            (Errors::default(), Errors::default(), Errors::default());
        let mut polygon_every = Vec::new();
        for _ in 0..40 {
            let o = one_run(&drawn, drawing_off_m, run, &mut rng, &mut rwht);
            for (errors, (est, to_walls)) in [&mut boxed, &mut polygon, &mut mapped]
                .into_iter()
                .zip(o.estimates.iter().zip(o.to_walls))
            {
                errors.add(est, &o.truth);
                errors.walls.push(to_walls);
            }
            polygon_every.push(o.every_wall_middle);
        }
        polygon_every.sort_by(f64::total_cmp);
        let q = |v: &[f64], f: f64| v[((v.len() - 1) as f64 * f) as usize] * 1e3;
        let how = match run {
            Run::Still => "standing still".to_string(),
            Run::Tour { stops } => format!("a tour of {stops} places"),
        };
        eprintln!(
            "{name:>15}, drawing off by up to {:.0} cm, {how}\n  room filter on its box: {}\n  \
             room filter in its polygon: {}\n    (every wall's middle: median {:.1} mm, 95 % {:.1} mm)\n  \
             wall-map filter in its walls: {}",
            drawing_off_m * 100.0,
            boxed.line(),
            polygon.line(),
            q(&polygon_every, 0.5),
            q(&polygon_every, 0.95),
            mapped.line()
        );
    }
}

#[test]
#[ignore = "a study: run it with --ignored --nocapture"]
fn which_filter_localises_in_a_room_of_any_shape() {
    for run in [Run::Still, Run::Tour { stops: 4 }] {
        study(0.0, run);
        study(0.03, run);
    }
}

#[test]
fn a_robot_touring_a_room_drawn_3_cm_off_is_held_to_its_walls_as_built() {
    // One L and one room with a wall at an angle, fresh seeds: after a
    // tour the polygon filter's distances to the walls are within 5 mm of
    // the walls as built, where the drawing was up to 3 cm off, and beat
    // the box filter's.
    let mut rwht = RwhtExtractor::new(RwhtConfig::default()).unwrap();
    for (seed, (name, drawn)) in [(101, &rooms()[0]), (202, &rooms()[3])] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let o = one_run(drawn, 0.03, Run::Tour { stops: 3 }, &mut rng, &mut rwht);
        let [boxed, polygon, _] = o.to_walls;
        assert!(polygon < 0.005, "{name}: {:.1} mm", polygon * 1e3);
        assert!(
            polygon < boxed,
            "{name}: {polygon} against the box's {boxed}"
        );
    }
}
