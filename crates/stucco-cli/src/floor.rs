//! A floor mapped while driving (issue 5's acceptance): the robot's own
//! laser (IBEO) and odometry, the tour driven on the truth, the wall-map
//! EKF from nothing and the room graph on top of it; the map's walls, the
//! walls that lie along nothing, and the graph scored against the world's
//! truth.

use anyhow::Result;
use nalgebra::{Point2, Vector2};
use serde::Serialize;
use stucco_core::{LaserSpec, Pose2, wrap_angle};
use stucco_nav::{
    Defeature, DefeaturedLaser, MapWall, OdometryConfig, RoomGraph, RoomGraphConfig, Rpe,
    WallMapEkf,
};
use stucco_sim::{DynamicsConfig, Layout, OpeningKind, SimConfig, Solid, TourSpec, WorldSpec};

use crate::study::{Drive, MATCH_ANGLE_RAD, MATCH_DIST_M, MATCH_OVERHANG_M, map_run_with, record};
use crate::walls::ExtractorKind;

/// One floor mapped.
#[derive(Clone, Debug, Serialize)]
pub struct FloorRun {
    /// Seed of the run.
    pub seed: u64,
    /// Speed along the tour, m/s.
    pub speed_mps: f64,
    /// Building walls of the final map along a true wall.
    pub walls: usize,
    /// Their RMS distance from it, m.
    pub wall_dist_rms_m: f64,
    /// Their RMS angle to it, rad.
    pub wall_angle_rms_rad: f64,
    /// Building walls of the final map that lie along no surface of the
    /// world (wall, radiator, furniture): what a false association leaves.
    pub stray_walls: usize,
    /// Relative pose error of the filter, pairs 1 m apart.
    pub rpe: Rpe,
    /// The room graph built.
    pub graph: RoomGraph,
    /// Whether the graph is the truth's: one room for each room driven
    /// through, one door for each door passed, each between the right
    /// rooms; and the rooms named after the true ones.
    pub graph_correct: bool,
    /// What was wrong with the graph, if anything.
    pub graph_fault: Option<String>,
}

/// The vertical faces at height `z` of every box of `layout` (walls,
/// radiators, furniture, legs) as `(a, b, normal)`.
fn faces(layout: &Layout, z: f64) -> Vec<Face> {
    let mut out = Vec::new();
    for s in &layout.solids {
        let Solid::Box {
            center,
            half,
            yaw_rad,
            ..
        } = s
        else {
            continue;
        };
        if (center[2] - z).abs() > half[2] {
            continue;
        }
        let (sn, cs) = yaw_rad.sin_cos();
        let ux = Vector2::new(cs, sn);
        let uy = Vector2::new(-sn, cs);
        let c = Point2::new(center[0], center[1]);
        for (n, h_n, u, h_u) in [
            (ux, half[0], uy, half[1]),
            (-ux, half[0], uy, half[1]),
            (uy, half[1], ux, half[0]),
            (-uy, half[1], ux, half[0]),
        ] {
            let mid = c + n * h_n;
            // The normal points out of the solid, toward who sees it: a
            // map wall's normal points into it.
            out.push((mid - u * h_u, mid + u * h_u, -n));
        }
    }
    out
}

/// A face of the world: its ends and its normal, as a map wall's (from
/// the free side into the solid).
type Face = (Point2<f64>, Point2<f64>, Vector2<f64>);

/// The motion (a turn about the origin, then a shift) that puts the
/// map's building walls best on the faces they lie nearest: a map drifts
/// as a whole (its frame turned by the first turn's odometry), which is no
/// false association. Weighted least squares over walls within 3° and
/// 20 cm of a face.
fn frame_fit(walls: &[MapWall], faces: &[Face]) -> Pose2 {
    let pairs: Vec<(&MapWall, f64, Vector2<f64>, f64)> = walls
        .iter()
        .filter_map(|w| {
            faces
                .iter()
                .filter_map(|(a, b, n)| {
                    let alpha = n.y.atan2(n.x);
                    let mid = nalgebra::center(a, b);
                    let off = w.in_front(&mid).abs();
                    (wrap_angle(w.alpha_rad - alpha).abs() < 3f64.to_radians() && off < 0.2)
                        .then_some((off, alpha, *n, n.dot(&a.coords)))
                })
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .map(|(_, alpha, n, rho)| (w, alpha, n, rho))
        })
        .collect();
    let total: f64 = pairs.iter().map(|(w, ..)| w.length_m()).sum();
    if total <= 0.0 {
        return Pose2::IDENTITY;
    }
    let turn = pairs
        .iter()
        .map(|(w, alpha, ..)| w.length_m() * wrap_angle(alpha - w.alpha_rad))
        .sum::<f64>()
        / total;
    // ρ of a turned wall is unchanged; the shift t moves it by n·t.
    let (mut a, mut b) = (nalgebra::Matrix2::zeros(), Vector2::zeros());
    for (w, _, n, rho) in &pairs {
        a += n * n.transpose() * w.length_m();
        b += n * ((rho - w.rho_m) * w.length_m());
    }
    let shift = a.try_inverse().map_or(Vector2::zeros(), |inv| inv * b);
    Pose2::new(shift.x, shift.y, turn)
}

/// Building walls of `ekf`'s map along no surface of `faces`, the map put
/// on the world's frame ([`frame_fit`]): less than half of the wall's seen
/// stretch covered by faces that lie on its line (a door's gap in a wall
/// is not a fault).
fn stray(ekf: &WallMapEkf, faces: &[Face]) -> usize {
    let walls: Vec<MapWall> = ekf.map().building_walls().cloned().collect();
    let onto_world = frame_fit(&walls, faces);
    walls
        .iter()
        .map(|w| w.transformed(&onto_world))
        .filter(|w| {
            let mut covered: Vec<(f64, f64)> = faces
                .iter()
                .filter(|(fa, fb, n)| {
                    let mid = nalgebra::center(fa, fb);
                    wrap_angle(w.alpha_rad - n.y.atan2(n.x)).abs() < MATCH_ANGLE_RAD
                        && (w.in_front(&mid)).abs() < MATCH_DIST_M
                })
                .map(|(fa, fb, _)| {
                    let (a, b) = (w.along(fa), w.along(fb));
                    (
                        a.min(b).max(w.extent_m[0]) - MATCH_OVERHANG_M,
                        a.max(b).min(w.extent_m[1]) + MATCH_OVERHANG_M,
                    )
                })
                .filter(|(a, b)| b > a)
                .collect();
            covered.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut total = 0.0;
            let mut reach = f64::NEG_INFINITY;
            for (a, b) in covered {
                let a = a.max(reach).max(w.extent_m[0]);
                let b = b.min(w.extent_m[1]);
                if b > a {
                    total += b - a;
                }
                reach = reach.max(b);
            }
            total < 0.5 * w.length_m()
        })
        .count()
}

/// The true room holding `p`.
fn true_room(layout: &Layout, p: &Point2<f64>) -> Option<String> {
    layout
        .rooms
        .iter()
        .find(|r| {
            let xs = r.corners.iter().map(|c| c.x);
            let ys = r.corners.iter().map(|c| c.y);
            let (x0, x1) = (
                xs.clone().fold(f64::MAX, f64::min),
                xs.fold(f64::MIN, f64::max),
            );
            let (y0, y1) = (
                ys.clone().fold(f64::MAX, f64::min),
                ys.fold(f64::MIN, f64::max),
            );
            p.x > x0 && p.x < x1 && p.y > y0 && p.y < y1
        })
        .map(|r| r.name.clone())
}

/// Checks `graph` against the truth: each room of the graph a different
/// true room (named after it on the way), each door between the true rooms
/// on either side of a true open door it lies in; the rooms and doors the
/// true path went through, all there.
fn check_graph(graph: &mut RoomGraph, layout: &Layout, path: &[Point2<f64>]) -> Result<(), String> {
    let mut names = Vec::new();
    for room in graph.rooms() {
        let centre = graph.centre(room.id).ok_or("a room without a centre")?;
        let name = true_room(layout, &centre)
            .ok_or_else(|| format!("{}'s centre {centre:?} is in no room", room.name))?;
        if names.contains(&name) {
            return Err(format!("two rooms of the graph are {name}"));
        }
        names.push(name);
    }
    for (id, name) in names.iter().enumerate() {
        graph.name(id, name.clone());
    }
    // The true rooms and doors the path went through.
    let mut visited: Vec<String> = Vec::new();
    let mut passed: Vec<[String; 2]> = Vec::new();
    let mut last: Option<String> = None;
    for p in path {
        let Some(here) = true_room(layout, p) else {
            continue;
        };
        if !visited.contains(&here) {
            visited.push(here.clone());
        }
        if let Some(prev) = last.replace(here.clone())
            && prev != here
        {
            let mut pair = [prev, here];
            pair.sort();
            if !passed.contains(&pair) {
                passed.push(pair);
            }
        }
    }
    let mut built: Vec<&String> = names.iter().collect();
    built.sort();
    let mut truth: Vec<&String> = visited.iter().collect();
    truth.sort();
    if built != truth {
        return Err(format!("rooms {built:?}, driven through {truth:?}"));
    }
    let open_doors: Vec<Point2<f64>> = layout
        .openings
        .iter()
        .filter(|o| o.kind == OpeningKind::OpenDoor)
        .map(|o| nalgebra::center(&o.edges[0], &o.edges[1]))
        .collect();
    let mut doors: Vec<[String; 2]> = Vec::new();
    for d in graph.doors() {
        let mut pair = d.rooms.map(|r| names[r].clone());
        pair.sort();
        if doors.contains(&pair) {
            return Err(format!("two doors between {pair:?}"));
        }
        let near = open_doors
            .iter()
            .map(|c| (c - d.at).norm())
            .fold(f64::INFINITY, f64::min);
        if near > 0.6 {
            return Err(format!(
                "door {pair:?} at {:?} is {near:.2} m from any open door",
                d.at
            ));
        }
        doors.push(pair);
    }
    doors.sort();
    passed.sort();
    if doors != passed {
        return Err(format!("doors {doors:?}, passed {passed:?}"));
    }
    Ok(())
}

/// Maps `world` from a drive of `seconds` along `tour` at `speed_mps`
/// with `seed`.
pub fn map_floor(
    world: &WorldSpec,
    tour: &TourSpec,
    seed: u64,
    speed_mps: f64,
    seconds: f64,
) -> Result<FloorRun> {
    let laser = LaserSpec::ibeo_ladar_2d();
    let drive = Drive {
        seconds,
        speed_mps,
        dynamics: DynamicsConfig::default(),
        odometry: OdometryConfig::default(),
        rpe_pair_m: 1.0,
        extractor: ExtractorKind::Rwht,
    };
    let mut world = world.clone();
    world.people.clear();
    let rec = record(&drive, &world, tour, &laser, seed)?;
    let layout = Layout::of(&world);
    let full = DefeaturedLaser::new(&laser, &Defeature::default())?;
    // The robot is in the room its body's middle is in, ahead of its rear
    // axle.
    let vehicle = SimConfig::default().vehicle;
    let ahead = 0.5 * vehicle.length_m - vehicle.rear_overhang_m;
    let mut graph = RoomGraph::new(RoomGraphConfig {
        body_middle_ahead_m: ahead,
        ..RoomGraphConfig::default()
    });
    let (score, ekf) = map_run_with(&drive, &rec, &full, &layout, seed, |ekf| {
        graph.update(&ekf.pose(), ekf.walls());
    })?;
    // Checked along the true path of the same point of the body.
    let path: Vec<Point2<f64>> = rec.truth_path(&Pose2::new(ahead, 0.0, 0.0));
    let check = check_graph(&mut graph, &layout, &path);
    let z = SimConfig::default().vehicle.laser_height_m;
    let m = &score.map;
    let n = m.walls.max(1) as f64;
    Ok(FloorRun {
        seed,
        speed_mps,
        walls: m.walls,
        wall_dist_rms_m: (m.dist_sq_sum / n).sqrt(),
        wall_angle_rms_rad: (m.angle_sq_sum / n).sqrt(),
        stray_walls: stray(&ekf, &faces(&layout, z)),
        rpe: score.rpe,
        graph,
        graph_correct: check.is_ok(),
        graph_fault: check.err(),
    })
}
