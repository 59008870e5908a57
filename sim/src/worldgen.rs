//! Buildings nobody has seen: a seeded generator of worlds, their
//! drawings and a job on them. A building is one to five rooms off a
//! corridor 1.2–1.8 m wide; each room rectangular, L-shaped, T-shaped,
//! with a chimney breast, or with one wall at 30–60°; 2.4–8 m across and
//! 2.4–3.0 m high; a door 0.7–1.0 m wide to the corridor (some shut);
//! 0–3 windows in its outer walls, 0.4–3 m wide, sills 0–1.2 m (glazing
//! to the floor among them); 0–6 pieces of furniture (tables on legs,
//! chairs, sofas, beds, wardrobes against walls, columns); 0–3 people
//! walking. The drawing gives the rooms' corners, exact or off by up to
//! 3 cm, the doors and, for half the buildings, the windows.

use crate::world::{
    BoxSpec, ColumnSpec, DoorSpec, PersonSpec, RobotStart, RoomSpec, TableSpec, WindowSpec,
    WorldSpec,
};
use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write;

/// Thickness of every wall, m.
const WALL_M: f64 = 0.15;
/// The corridor's name in the world and on the drawing.
pub const CORRIDOR: &str = "corridor";

/// Time a generated job is given a square metre of its rooms' walls and
/// ceilings, s: about three times what the apartment's job takes (52 s a
/// square metre of plasterable surface, mapping and driving included), so
/// a job is cut short only when far slower than that.
const JOB_SECONDS_PER_M2: f64 = 150.0;
/// Least time a generated job is given, s (a mission's default).
const MIN_JOB_S: f64 = 1800.0;

/// A generated building: its world (the truth), its drawing, and a job.
#[derive(Clone, Debug, PartialEq)]
pub struct Building {
    /// The world, as the simulator takes it.
    pub world: WorldSpec,
    /// The drawing, as a site engineer would be given it.
    pub drawing: Drawing,
    /// The seed it came from.
    pub seed: u64,
    /// Each room's shape: `rectangle`, `L`, `T`, `chimney breast`,
    /// `angled`.
    pub shapes: Vec<(String, &'static str)>,
}

/// A building's drawing: rooms as corner lists, doors, windows.
#[derive(Clone, Debug, PartialEq)]
pub struct Drawing {
    /// Each room: name and corners (counter-clockwise), m.
    pub rooms: Vec<(String, Vec<[f64; 2]>)>,
    /// Each door: the rooms it joins, its middle, width, height, shut.
    pub doors: Vec<DrawnDoor>,
    /// Each window, when the drawing gives them.
    pub windows: Vec<DrawnWindow>,
}

/// A door on the drawing.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawnDoor {
    /// The two rooms it joins.
    pub rooms: [String; 2],
    /// Its middle, m.
    pub at_m: [f64; 2],
    /// Width and height, m.
    pub width_m: f64,
    /// Height, m.
    pub height_m: f64,
    /// Kept shut.
    pub shut: bool,
}

/// A window on the drawing.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawnWindow {
    /// Its room.
    pub room: String,
    /// Its middle, m.
    pub at_m: [f64; 2],
    /// Width, m.
    pub width_m: f64,
    /// Sill and head above the floor, m.
    pub sill_m: f64,
    /// Head above the floor, m.
    pub head_m: f64,
}

/// Rounds to the millimetre: what a drawing and a world file write.
fn mm(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

fn mm2(p: Point2<f64>) -> [f64; 2] {
    [mm(p.x), mm(p.y)]
}

/// A room's shape before it is placed: corners in its own frame, x along
/// the corridor, y away from it; its corridor wall runs along y = 0 from
/// x = `door_span[0]` to `door_span[1]`.
struct Shape {
    kind: &'static str,
    corners: Vec<Point2<f64>>,
    door_span: [f64; 2],
}

fn shape(rng: &mut ChaCha8Rng, w: f64, d: f64) -> Shape {
    let p = Point2::new;
    let rect = || vec![p(0.0, 0.0), p(w, 0.0), p(w, d), p(0.0, d)];
    // Arms and stems at least this wide, m.
    let arm = 1.4;
    match rng.random_range(0..5) {
        1 if w > 2.0 * arm && d > 2.0 * arm => {
            // L: a far corner cut away.
            let (a, b) = (
                rng.random_range(arm..w - arm),
                rng.random_range(arm..d - arm),
            );
            let corners = if rng.random_bool(0.5) {
                vec![p(0.0, 0.0), p(w, 0.0), p(w, b), p(a, b), p(a, d), p(0.0, d)]
            } else {
                vec![
                    p(0.0, 0.0),
                    p(w, 0.0),
                    p(w, d),
                    p(w - a, d),
                    p(w - a, b),
                    p(0.0, b),
                ]
            };
            Shape {
                kind: "L",
                corners,
                door_span: [0.0, w],
            }
        }
        2 if w > 3.0 * arm && d > 2.0 * arm => {
            // T: a bar along the far side, a stem to the corridor.
            let stem = rng.random_range(arm..(w - 2.0 * 0.5).min(0.6 * w).max(arm + 0.01));
            let x0 = rng.random_range(0.5..(w - stem - 0.5).max(0.51));
            let b = rng.random_range(arm..d - arm);
            Shape {
                kind: "T",
                corners: vec![
                    p(x0, 0.0),
                    p(x0 + stem, 0.0),
                    p(x0 + stem, b),
                    p(w, b),
                    p(w, d),
                    p(0.0, d),
                    p(0.0, b),
                    p(x0, b),
                ],
                door_span: [x0, x0 + stem],
            }
        }
        3 if w >= 2.4 && d >= 2.4 => {
            // A chimney breast standing out of the far wall.
            let bw = rng.random_range(0.6..1.2);
            let bd = rng.random_range(0.3..0.6);
            let x0 = rng.random_range(0.4..(w - bw - 0.4));
            Shape {
                kind: "chimney breast",
                corners: vec![
                    p(0.0, 0.0),
                    p(w, 0.0),
                    p(w, d),
                    p(x0 + bw, d),
                    p(x0 + bw, d - bd),
                    p(x0, d - bd),
                    p(x0, d),
                    p(0.0, d),
                ],
                door_span: [0.0, w],
            }
        }
        4 if w >= 3.0 && d >= 3.0 => {
            // A far corner cut by a wall at 30–60° to the corridor.
            let angle = rng.random_range(30f64..60.0).to_radians();
            let a = rng.random_range(1.0..(0.5 * w).min(0.5 * d / angle.tan()).max(1.01));
            let b = a * angle.tan();
            let corners = if rng.random_bool(0.5) {
                vec![p(0.0, 0.0), p(w, 0.0), p(w, d - b), p(w - a, d), p(0.0, d)]
            } else {
                vec![p(0.0, 0.0), p(w, 0.0), p(w, d), p(a, d), p(0.0, d - b)]
            };
            Shape {
                kind: "angled",
                corners,
                door_span: [0.0, w],
            }
        }
        _ => Shape {
            kind: "rectangle",
            corners: rect(),
            door_span: [0.0, w],
        },
    }
}

/// A placed room: world corners (counter-clockwise), height, which wall
/// faces the corridor, and the others that may hold windows.
struct Placed {
    name: String,
    corners: Vec<Point2<f64>>,
    height_m: f64,
    corridor_wall: usize,
    /// Span of the corridor wall along x, world.
    door_span: [f64; 2],
    north: bool,
    outer_walls: Vec<usize>,
}

/// Generates the building of `seed`.
pub fn generate(seed: u64) -> Building {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let corridor_w = mm(rng.random_range(1.2..=1.8));
    let n = rng.random_range(1..=5usize);
    let mut placed: Vec<Placed> = Vec::new();
    let mut shapes = Vec::new();
    let mut ends = [0.5f64, 0.5f64]; // next free x, south and north
    for k in 0..n {
        let north = rng.random_bool(0.5);
        let w = mm(rng.random_range(2.4..=8.0));
        let d = mm(rng.random_range(2.4..=8.0));
        let height_m = mm(rng.random_range(2.4..=3.0));
        let s = shape(&mut rng, w, d);
        let x0 = ends[north as usize];
        ends[north as usize] = x0 + w + WALL_M;
        let y0 = corridor_w + WALL_M;
        // North: y = y0 + ly; south: mirrored, y = −WALL_M − ly, its corner
        // order reversed to stay counter-clockwise.
        let to_world = |q: &Point2<f64>| {
            if north {
                Point2::new(mm(x0 + q.x), mm(y0 + q.y))
            } else {
                Point2::new(mm(x0 + q.x), mm(-WALL_M - q.y))
            }
        };
        let mut corners: Vec<Point2<f64>> = s.corners.iter().map(to_world).collect();
        if !north {
            corners.reverse();
        }
        let m = corners.len();
        let y_corr = if north { y0 } else { -WALL_M };
        let y_far = corners
            .iter()
            .map(|c| (c.y - y_corr).abs())
            .fold(0.0, f64::max);
        let on = |y: f64, target: f64| (y - target).abs() < 1e-6;
        let corridor_wall = (0..m)
            .find(|&i| on(corners[i].y, y_corr) && on(corners[(i + 1) % m].y, y_corr))
            .unwrap_or(0);
        // Windows go in the far walls and the slanted ones, and in a side
        // wall with no room beside it (the first or last on its side).
        let outer_walls = (0..m)
            .filter(|&i| {
                let (a, b) = (corners[i], corners[(i + 1) % m]);
                let far = on((a.y - y_corr).abs(), y_far) && on((b.y - y_corr).abs(), y_far);
                let slanted = (a.x - b.x).abs() > 1e-6 && (a.y - b.y).abs() > 1e-6;
                let west_side = on(a.x, x0) && on(b.x, x0) && k == 0;
                far || slanted || west_side
            })
            .collect();
        let name = format!("room{}", k + 1);
        let door_span = [x0 + s.door_span[0], x0 + s.door_span[1]];
        shapes.push((name.clone(), s.kind));
        placed.push(Placed {
            name,
            corners,
            height_m,
            corridor_wall,
            door_span,
            north,
            outer_walls,
        });
    }
    let length = mm(ends[0].max(ends[1]) + 0.5);
    let corridor = RoomSpec {
        name: CORRIDOR.to_owned(),
        corners: vec![
            [0.0, 0.0],
            [length, 0.0],
            [length, corridor_w],
            [0.0, corridor_w],
        ],
        height_m: placed.iter().map(|r| r.height_m).fold(2.4, f64::max),
        wall_thickness_m: WALL_M,
        shared_walls: Vec::new(),
    };
    let mut world = WorldSpec {
        name: format!("generated building {seed}"),
        seed,
        robot: RobotStart {
            at: [0.6, mm(corridor_w / 2.0)],
            heading_deg: 0.0,
        },
        rooms: vec![corridor],
        doors: Vec::new(),
        windows: Vec::new(),
        tables: Vec::new(),
        chairs: Vec::new(),
        boxes: Vec::new(),
        radiators: Vec::new(),
        columns: Vec::new(),
        people: Vec::new(),
        tour: Vec::new(),
        tours: Default::default(),
    };
    let mut drawing = Drawing {
        rooms: Vec::new(),
        doors: Vec::new(),
        windows: Vec::new(),
    };
    let mut doors_at: Vec<(String, Point2<f64>)> = Vec::new();
    for r in &placed {
        world.rooms.push(RoomSpec {
            name: r.name.clone(),
            corners: r.corners.iter().map(|c| [c.x, c.y]).collect(),
            height_m: r.height_m,
            wall_thickness_m: WALL_M,
            // The corridor builds the wall between them, door and all.
            shared_walls: vec![r.corridor_wall],
        });
        // The door, in the corridor's wall facing the room.
        let width = mm(rng.random_range(0.7..=1.0));
        let height = mm(rng.random_range(2.0..=2.1f64).min(r.height_m - 0.2));
        let lo = r.door_span[0] + 0.2;
        let hi = (r.door_span[1] - 0.2 - width).max(lo + 1e-3);
        let x = mm(rng.random_range(lo..hi));
        let open = rng.random_bool(0.85);
        let (wall, offset) = if r.north {
            (2, mm(length - x - width))
        } else {
            (0, x)
        };
        world.doors.push(DoorSpec {
            room: CORRIDOR.to_owned(),
            wall,
            offset_m: offset,
            width_m: width,
            height_m: height,
            open,
        });
        let y = if r.north {
            corridor_w + WALL_M / 2.0
        } else {
            -WALL_M / 2.0
        };
        let mid = Point2::new(x + width / 2.0, y);
        doors_at.push((r.name.clone(), mid));
        drawing.doors.push(DrawnDoor {
            rooms: [CORRIDOR.to_owned(), r.name.clone()],
            at_m: mm2(mid),
            width_m: width,
            height_m: height,
            shut: !open,
        });
        // Windows.
        let m = r.corners.len();
        for _ in 0..rng.random_range(0..=3usize) {
            if r.outer_walls.is_empty() {
                break;
            }
            let wall = r.outer_walls[rng.random_range(0..r.outer_walls.len())];
            let (a, b) = (r.corners[wall], r.corners[(wall + 1) % m]);
            let len = (b - a).norm();
            if len < 1.2 {
                continue;
            }
            let width = mm(rng.random_range(0.4..=3.0f64.min(len - 0.6)));
            let offset = mm(rng.random_range(0.3..=(len - 0.3 - width)));
            let taken = world.windows.iter().any(|w| {
                w.room == r.name
                    && w.wall == wall
                    && w.offset_m < offset + width + 0.3
                    && offset < w.offset_m + w.width_m + 0.3
            });
            if taken {
                continue;
            }
            let sill = if rng.random_bool(0.2) {
                0.0
            } else {
                mm(rng.random_range(0.3..=1.2))
            };
            let head = mm(rng.random_range((sill + 0.5).max(1.6)..=(r.height_m - 0.2)));
            world.windows.push(WindowSpec {
                room: r.name.clone(),
                wall,
                offset_m: offset,
                width_m: width,
                sill_m: sill,
                head_m: head,
                glazed: rng.random_bool(0.8),
            });
            let u = (b - a) / len;
            drawing.windows.push(DrawnWindow {
                room: r.name.clone(),
                at_m: mm2(a + u * (offset + width / 2.0)),
                width_m: width,
                sill_m: sill,
                head_m: head,
            });
        }
        // Furniture.
        furnish(&mut rng, &mut world, r, doors_at.last().map(|d| d.1));
    }
    // People: walking the corridor, or between two free places in a room.
    for _ in 0..rng.random_range(0..=3usize) {
        let path = if rng.random_bool(0.5) || placed.is_empty() {
            let y = mm(rng.random_range(0.4..=(corridor_w - 0.4).max(0.41)));
            vec![[mm(length * 0.3), y], [mm(length - 0.5), y]]
        } else {
            let r = &placed[rng.random_range(0..placed.len())];
            let (a, b) = (
                free_point(&mut rng, &world, r),
                free_point(&mut rng, &world, r),
            );
            match (a, b) {
                (Some(a), Some(b)) if clear_walk(&world, a, b) => vec![mm2(a), mm2(b)],
                _ => continue,
            }
        };
        world.people.push(PersonSpec {
            path,
            speed_mps: mm(rng.random_range(0.8..=1.4)),
        });
    }
    // The drawing: every room's corners, exact or each off by up to 3 cm.
    let off = if rng.random_bool(0.5) { 0.03 } else { 0.0 };
    for r in &world.rooms {
        let corners = r
            .corners
            .iter()
            .map(|c| {
                let e = [
                    rng.random_range(-1.0..=1.0) * off,
                    rng.random_range(-1.0..=1.0) * off,
                ];
                [mm(c[0] + e[0]), mm(c[1] + e[1])]
            })
            .collect();
        drawing.rooms.push((r.name.clone(), corners));
    }
    if rng.random_bool(0.5) {
        drawing.windows.clear();
    }
    Building {
        world,
        drawing,
        seed,
        shapes,
    }
}

/// Places 0–6 pieces of furniture in room `r`, clear of each other, of
/// its walls and of the way in from its door at `door`.
fn furnish(rng: &mut ChaCha8Rng, world: &mut WorldSpec, r: &Placed, door: Option<Point2<f64>>) {
    let count = rng.random_range(0..=6usize);
    let mut taken: Vec<(Point2<f64>, f64)> = Vec::new();
    let m = r.corners.len();
    for _ in 0..count {
        for _attempt in 0..30 {
            let kind = rng.random_range(0..6);
            // Length, width, height of the footprint.
            let (size, height) = match kind {
                0 => (
                    [rng.random_range(0.8..1.8), rng.random_range(0.6..1.0)],
                    0.75,
                ),
                1 => ([0.45, 0.45], 0.45),
                2 => (
                    [rng.random_range(1.6..2.2), rng.random_range(0.8..0.95)],
                    0.8,
                ),
                3 => (
                    [rng.random_range(1.9..2.1), rng.random_range(1.4..2.0)],
                    0.5,
                ),
                4 => (
                    [rng.random_range(0.8..1.6), rng.random_range(0.55..0.65)],
                    rng.random_range(1.9..2.2),
                ),
                _ => ([0.3, 0.3], r.height_m),
            };
            let (at, heading) = if kind == 4 {
                // A wardrobe's back against a wall other than the
                // corridor's.
                let wall = rng.random_range(0..m);
                if wall == r.corridor_wall {
                    continue;
                }
                let (a, b) = (r.corners[wall], r.corners[(wall + 1) % m]);
                let len = (b - a).norm();
                if len < size[0] + 0.2 {
                    continue;
                }
                let u = (b - a) / len;
                let inward = Vector2::new(-u.y, u.x);
                let s = rng.random_range(0.1 + size[0] / 2.0..len - 0.1 - size[0] / 2.0);
                let at = a + u * s + inward * (size[1] / 2.0 + 0.01);
                (at, u.y.atan2(u.x))
            } else {
                let Some(at) = free_point(rng, world, r) else {
                    continue;
                };
                let heading = if rng.random_bool(0.7) {
                    // Along a wall of the room.
                    let (a, b) = (r.corners[0], r.corners[1]);
                    (b.y - a.y).atan2(b.x - a.x)
                        + f64::from(rng.random_range(0..2u8)) * std::f64::consts::FRAC_PI_2
                } else {
                    rng.random_range(0.0..std::f64::consts::PI)
                };
                (at, heading)
            };
            let radius = 0.5 * size[0].hypot(size[1]);
            let (c, s) = (heading.cos(), heading.sin());
            let feet: Vec<Point2<f64>> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|(fx, fy)| {
                    let (x, y) = (fx * size[0] / 2.0, fy * size[1] / 2.0);
                    at + Vector2::new(c * x - s * y, s * x + c * y)
                })
                .collect();
            // Inside the room: every corner of the footprint in it, and no
            // wall through it (an L's inner corner can stand in a turned
            // bed whose corners are all in the room).
            let inside_room = feet.iter().all(|f| {
                crate::truth::inside(&r.corners, f)
                    && crate::truth::edge_distance(&r.corners, f) >= 0.005
            }) && !r.corners.iter().any(|c| crate::truth::inside(&feet, c))
                && !(0..4).any(|i| {
                    let (a, b) = (feet[i], feet[(i + 1) % 4]);
                    (0..m).any(|j| crosses(a, b, r.corners[j], r.corners[(j + 1) % m]))
                });
            let clear_of_others = taken
                .iter()
                .all(|(p, q)| (p - at).norm() >= q + radius + 0.15);
            let clear_of_door = door.is_none_or(|d| (d - at).norm() >= radius + 1.3);
            if !(inside_room && clear_of_others && clear_of_door) {
                continue;
            }
            taken.push((at, radius));
            let (at_m, size_m, heading_deg) = (
                mm2(at),
                [mm(size[0]), mm(size[1])],
                mm(heading.to_degrees()),
            );
            match kind {
                0 | 1 => {
                    let t = TableSpec {
                        at: at_m,
                        size_m,
                        heading_deg,
                        height_m: height,
                        leg_radius_m: if kind == 0 { 0.025 } else { 0.015 },
                    };
                    if kind == 0 {
                        world.tables.push(t);
                    } else {
                        world.chairs.push(t);
                    }
                }
                5 => world.columns.push(ColumnSpec {
                    at: at_m,
                    radius_m: 0.15,
                    height_m: r.height_m,
                }),
                _ => world.boxes.push(BoxSpec {
                    at: at_m,
                    size_m,
                    heading_deg,
                    height_m: mm(height),
                }),
            }
            break;
        }
    }
}

/// True when the segments `a`–`b` and `c`–`d` cross.
fn crosses(a: Point2<f64>, b: Point2<f64>, c: Point2<f64>, d: Point2<f64>) -> bool {
    let side = |p: Point2<f64>, q: Point2<f64>, r: Point2<f64>| {
        (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x)
    };
    let (d1, d2) = (side(c, d, a), side(c, d, b));
    let (d3, d4) = (side(a, b, c), side(a, b, d));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// A point of room `r` 0.5 m or more from its walls and clear of what
/// stands in the world, if one is found.
fn free_point(rng: &mut ChaCha8Rng, world: &WorldSpec, r: &Placed) -> Option<Point2<f64>> {
    let (mut lo, mut hi) = (r.corners[0], r.corners[0]);
    for c in &r.corners {
        lo = lo.inf(c);
        hi = hi.sup(c);
    }
    (0..50).find_map(|_| {
        let p = Point2::new(rng.random_range(lo.x..hi.x), rng.random_range(lo.y..hi.y));
        (crate::truth::inside(&r.corners, &p)
            && crate::truth::edge_distance(&r.corners, &p) >= 0.5
            && clear_of_things(world, p, 0.3))
        .then_some(p)
    })
}

/// True when nothing standing in `world` comes within `radius` of `p`
/// (each piece taken as the circle round its footprint).
fn clear_of_things(world: &WorldSpec, p: Point2<f64>, radius: f64) -> bool {
    let round =
        |at: [f64; 2], size: [f64; 2]| (Point2::new(at[0], at[1]), 0.5 * size[0].hypot(size[1]));
    world
        .tables
        .iter()
        .chain(&world.chairs)
        .map(|t| round(t.at, t.size_m))
        .chain(world.boxes.iter().map(|b| round(b.at, b.size_m)))
        .chain(
            world
                .columns
                .iter()
                .map(|c| (Point2::new(c.at[0], c.at[1]), c.radius_m)),
        )
        .all(|(c, r)| (c - p).norm() >= r + radius)
}

/// True when a person walking from `a` to `b` passes clear of what
/// stands in the world.
fn clear_walk(world: &WorldSpec, a: Point2<f64>, b: Point2<f64>) -> bool {
    (0..=20).all(|k| clear_of_things(world, a + (b - a) * (k as f64 / 20.0), 0.35))
}

impl Building {
    /// The world file.
    pub fn world_toml(&self) -> String {
        let head = format!(
            "# Generated by `stucco worldgen --seed {}`: the truth the simulator runs.\n",
            self.seed
        );
        head + &toml::to_string(&self.world).unwrap_or_default()
    }

    /// The drawing: `[[room]]` with corners, `[[door]]`, `[[window]]`.
    pub fn plan_toml(&self) -> String {
        let mut s = format!(
            "# Generated by `stucco worldgen --seed {}`: the building's drawing.\n",
            self.seed
        );
        let pair = |p: [f64; 2]| format!("[{:?}, {:?}]", p[0], p[1]);
        for (name, corners) in &self.drawing.rooms {
            let list: Vec<String> = corners.iter().map(|c| pair(*c)).collect();
            let _ = write!(
                s,
                "\n[[room]]\nname = {name:?}\ncorners = [{}]\n",
                list.join(", ")
            );
        }
        for d in &self.drawing.doors {
            let _ = write!(
                s,
                "\n[[door]]\nrooms = [{:?}, {:?}]\nat_m = {}\nwidth_m = {:?}\nheight_m = {:?}\n",
                d.rooms[0],
                d.rooms[1],
                pair(d.at_m),
                d.width_m,
                d.height_m
            );
            if d.shut {
                s.push_str("shut = true\n");
            }
        }
        for w in &self.drawing.windows {
            let _ = write!(
                s,
                "\n[[window]]\nroom = {:?}\nat_m = {}\nwidth_m = {:?}\nsill_m = {:?}\nhead_m = {:?}\n",
                w.room,
                pair(w.at_m),
                w.width_m,
                w.sill_m,
                w.head_m
            );
        }
        s
    }

    /// The job: plaster every room, from the drawing alone.
    pub fn mission_toml(&self) -> String {
        format!(
            "# Generated by `stucco worldgen --seed {seed}`: plaster every room of the drawing.\n\
             name = \"plaster generated building {seed}\"\n\
             world = \"world.toml\"\n\
             plan = \"plan.toml\"\n\
             seed = {seed}\n\
             # The job's time, {per_m2} s a square metre of its {area:.0} m² of walls and ceilings.\n\
             time_limit_s = {limit:.0}\n\
             \n\
             [start]\n\
             room = \"{CORRIDOR}\"\n\
             \n\
             [spray]\n\
             \n\
             [[task]]\n\
             task = \"plaster\"\n\
             rooms = \"all\"\n",
            seed = self.seed,
            per_m2 = JOB_SECONDS_PER_M2,
            area = self.surface_m2(),
            limit = (JOB_SECONDS_PER_M2 * self.surface_m2()).max(MIN_JOB_S),
        )
    }

    /// The area of its rooms' walls and ceilings, openings included, m².
    pub fn surface_m2(&self) -> f64 {
        self.world
            .rooms
            .iter()
            .map(|r| {
                let n = r.corners.len();
                let perimeter: f64 = (0..n)
                    .map(|k| {
                        let (a, b) = (r.corners[k], r.corners[(k + 1) % n]);
                        (b[0] - a[0]).hypot(b[1] - a[1])
                    })
                    .sum();
                // (The helper's area is twice the polygon's.)
                perimeter * r.height_m + 0.5 * crate::world::signed_area(&r.corners)
            })
            .sum()
    }
}
