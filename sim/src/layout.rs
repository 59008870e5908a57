//! A world file turned into solids (what the physics and the sensors see)
//! and ground truth (the true walls, openings and rooms, for scoring).

use crate::world::{TableSpec, WorldSpec};
use nalgebra::{Point2, Vector2};
use serde::Serialize;

/// Thickness of a closed door's leaf, m.
const LEAF_M: f64 = 0.04;
/// Thickness of a window's glass, m.
const GLASS_M: f64 = 0.01;
/// Legs of a person: radius, m, and half their spacing, m.
pub const LEG_RADIUS_M: f64 = 0.06;
/// Half the spacing of a person's legs, m.
pub const LEG_HALF_SPACING_M: f64 = 0.1;

/// What a solid is made of, for the sensors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Material {
    /// Returns the laser at any incidence.
    Opaque,
    /// Returns the laser only near normal incidence; otherwise it passes.
    Glass,
}

/// A solid of the world, static.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Solid {
    /// A box: centre, half extents (along its own x, y, z) and heading.
    Box {
        /// Centre, m.
        center: [f64; 3],
        /// Half extents, m.
        half: [f64; 3],
        /// Heading of its x axis, rad.
        yaw_rad: f64,
        /// What it is made of.
        material: Material,
    },
    /// An upright cylinder from `z0` to `z1`.
    Cylinder {
        /// Centre of its footprint, m.
        at: [f64; 2],
        /// Radius, m.
        radius: f64,
        /// Bottom and top, m.
        z: [f64; 2],
    },
}

/// A true wall: its inner face, from `a` to `b`, as seen from its room.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrueWall {
    /// The room it bounds.
    pub room: String,
    /// Its index in the room's corners.
    pub index: usize,
    /// Start of the inner face, m.
    pub a: Point2<f64>,
    /// End of the inner face, m.
    pub b: Point2<f64>,
    /// Unit normal pointing out of the room (into the wall).
    pub normal: Vector2<f64>,
    /// Height, m.
    pub height_m: f64,
}

impl TrueWall {
    /// The wall as a line `n·p = d` seen from a sensor at `pose`: `(d, γ)`,
    /// the papers' wall parameters.
    pub fn in_sensor_frame(&self, pose: &stucco_core::Pose2) -> (f64, f64) {
        let d = self.normal.dot(&self.a.coords) - self.normal.dot(&pose.position().coords);
        let g = self.normal.y.atan2(self.normal.x) - pose.theta;
        (d, stucco_core::wrap_angle(g))
    }
}

/// A true opening in a wall.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrueOpening {
    /// Door (passable when open) or window.
    pub kind: OpeningKind,
    /// The room whose wall it is in.
    pub room: String,
    /// The wall's index in that room.
    pub wall: usize,
    /// Its two edges on the wall's inner face, m.
    pub edges: [Point2<f64>; 2],
    /// Bottom and top above the floor, m.
    pub z: [f64; 2],
}

/// What an opening is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum OpeningKind {
    /// An open door.
    OpenDoor,
    /// A closed door.
    ClosedDoor,
    /// A window without glass.
    Window,
    /// A glazed window.
    GlazedWindow,
}

/// A true room: its floor polygon and height.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrueRoom {
    /// Name.
    pub name: String,
    /// Corners, counter-clockwise, m.
    pub corners: Vec<Point2<f64>>,
    /// Height, m.
    pub height_m: f64,
}

/// The solids and the truth of a world.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Layout {
    /// Everything static.
    pub solids: Vec<Solid>,
    /// True walls, room by room.
    pub walls: Vec<TrueWall>,
    /// True openings.
    pub openings: Vec<TrueOpening>,
    /// True rooms.
    pub rooms: Vec<TrueRoom>,
    /// What stands in the rooms (furniture, columns, radiators), each with
    /// its solids.
    pub pieces: Vec<Piece>,
}

/// Something standing in a room that is not the building: a table, a
/// chair, a box (a sofa, a bed, a wardrobe), a radiator, a column.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Piece {
    /// What it is, as the world file's table names it (`table`, `chair`,
    /// `box`, `radiator`, `column`).
    pub what: &'static str,
    /// The middle of its footprint, m.
    pub at: [f64; 2],
    /// Its solids, in [`Layout::solids`].
    pub solids: std::ops::Range<usize>,
}

impl Layout {
    /// The solids and truth of `world` (checked by its parser).
    pub fn of(world: &WorldSpec) -> Layout {
        let mut out = Layout::default();
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for room in &world.rooms {
            let n = room.corners.len();
            let corners: Vec<Point2<f64>> = room
                .corners
                .iter()
                .map(|c| Point2::new(c[0], c[1]))
                .collect();
            for c in &corners {
                lo = [lo[0].min(c.x), lo[1].min(c.y)];
                hi = [hi[0].max(c.x), hi[1].max(c.y)];
            }
            for i in 0..n {
                let (a, b) = (corners[i], corners[(i + 1) % n]);
                let u = (b - a).normalize();
                let normal = Vector2::new(u.y, -u.x);
                out.walls.push(TrueWall {
                    room: room.name.clone(),
                    index: i,
                    a,
                    b,
                    normal,
                    height_m: room.height_m,
                });
                let cuts = openings_of(world, &room.name, i);
                // A wall another room builds has that room's openings in it
                // too: a door the plan gives on the corridor's side is a
                // hole on the office's side as well.
                let seen_through = if room.shared_walls.contains(&i) {
                    shared_cuts(world, &room.name, a, b)
                } else {
                    Vec::new()
                };
                for c in cuts.iter().chain(&seen_through) {
                    out.openings.push(TrueOpening {
                        kind: c.kind,
                        room: room.name.clone(),
                        wall: i,
                        edges: [a + u * c.s0, a + u * c.s1],
                        z: c.z,
                    });
                }
                if room.shared_walls.contains(&i) {
                    continue;
                }
                // A wall reaches past a corner where the room turns left
                // (convex: the outer corner needs closing); at a corner
                // where it turns right the two walls' boxes already meet,
                // and reaching past would stand inside the room.
                let turns_left = |p: Point2<f64>, q: Point2<f64>, r: Point2<f64>| {
                    let (e, f) = (q - p, r - q);
                    e.x * f.y - e.y * f.x > 0.0
                };
                let ends = [
                    turns_left(corners[(i + n - 1) % n], a, b),
                    turns_left(a, b, corners[(i + 2) % n]),
                ];
                wall_solids(
                    &mut out.solids,
                    [a, b],
                    ends,
                    room.wall_thickness_m,
                    room.height_m,
                    &cuts,
                );
            }
            out.rooms.push(TrueRoom {
                name: room.name.clone(),
                corners,
                height_m: room.height_m,
            });
            // Ceiling over the room's bounding box.
            let (x0, x1) = bounds(room.corners.iter().map(|c| c[0]));
            let (y0, y1) = bounds(room.corners.iter().map(|c| c[1]));
            out.solids.push(Solid::Box {
                center: [(x0 + x1) / 2.0, (y0 + y1) / 2.0, room.height_m + 0.05],
                half: [(x1 - x0) / 2.0 + 0.3, (y1 - y0) / 2.0 + 0.3, 0.05],
                yaw_rad: 0.0,
                material: Material::Opaque,
            });
        }
        // The floor under everything.
        out.solids.push(Solid::Box {
            center: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, -0.05],
            half: [
                (hi[0] - lo[0]) / 2.0 + 1.0,
                (hi[1] - lo[1]) / 2.0 + 1.0,
                0.05,
            ],
            yaw_rad: 0.0,
            material: Material::Opaque,
        });
        let piece = |out: &mut Layout, what: &'static str, at: [f64; 2], from: usize| {
            out.pieces.push(Piece {
                what,
                at,
                solids: from..out.solids.len(),
            });
        };
        for (what, t) in world
            .tables
            .iter()
            .map(|t| ("table", t))
            .chain(world.chairs.iter().map(|c| ("chair", c)))
        {
            let from = out.solids.len();
            legged(&mut out.solids, t);
            piece(&mut out, what, t.at, from);
        }
        for b in &world.boxes {
            let from = out.solids.len();
            out.solids.push(Solid::Box {
                center: [b.at[0], b.at[1], b.height_m / 2.0],
                half: [b.size_m[0] / 2.0, b.size_m[1] / 2.0, b.height_m / 2.0],
                yaw_rad: b.heading_deg.to_radians(),
                material: Material::Opaque,
            });
            piece(&mut out, "box", b.at, from);
        }
        for r in &world.radiators {
            let Some(w) = out
                .walls
                .iter()
                .find(|w| w.room == r.room && w.index == r.wall)
            else {
                continue;
            };
            let u = (w.b - w.a).normalize();
            let mid =
                w.a + u * (r.offset_m + r.length_m / 2.0) - w.normal * (r.gap_m + r.depth_m / 2.0);
            let from = out.solids.len();
            out.solids.push(Solid::Box {
                center: [mid.x, mid.y, (r.span_m[0] + r.span_m[1]) / 2.0],
                half: [
                    r.length_m / 2.0,
                    r.depth_m / 2.0,
                    (r.span_m[1] - r.span_m[0]) / 2.0,
                ],
                yaw_rad: u.y.atan2(u.x),
                material: Material::Opaque,
            });
            piece(&mut out, "radiator", [mid.x, mid.y], from);
        }
        for c in &world.columns {
            let from = out.solids.len();
            out.solids.push(Solid::Cylinder {
                at: c.at,
                radius: c.radius_m,
                z: [0.0, c.height_m],
            });
            piece(&mut out, "column", c.at, from);
        }
        out
    }

    /// The true walls of room `name`.
    pub fn walls_of<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a TrueWall> + 'a {
        self.walls.iter().filter(move |w| w.room == name)
    }
}

fn bounds(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    })
}

/// An opening cut into a wall, along it from `s0` to `s1`, from `z[0]` to
/// `z[1]` above the floor.
#[derive(Clone, Copy, Debug)]
struct Cut {
    s0: f64,
    s1: f64,
    z: [f64; 2],
    kind: OpeningKind,
}

fn openings_of(world: &WorldSpec, room: &str, wall: usize) -> Vec<Cut> {
    let mut cuts: Vec<Cut> = world
        .doors
        .iter()
        .filter(|d| d.room == room && d.wall == wall)
        .map(|d| Cut {
            s0: d.offset_m,
            s1: d.offset_m + d.width_m,
            z: [0.0, d.height_m],
            kind: if d.open {
                OpeningKind::OpenDoor
            } else {
                OpeningKind::ClosedDoor
            },
        })
        .chain(
            world
                .windows
                .iter()
                .filter(|w| w.room == room && w.wall == wall)
                .map(|w| Cut {
                    s0: w.offset_m,
                    s1: w.offset_m + w.width_m,
                    z: [w.sill_m, w.head_m],
                    kind: if w.glazed {
                        OpeningKind::GlazedWindow
                    } else {
                        OpeningKind::Window
                    },
                }),
        )
        .collect();
    cuts.sort_by(|a, b| a.s0.total_cmp(&b.s0));
    cuts
}

/// The boxes of one wall from `a` to `b` (inner face), `t` thick outward,
/// `h` high, with its openings cut out. An end at a convex corner
/// (`reach_past`) reaches `t` past it so neighbouring walls close their
/// outer corner.
fn wall_solids(
    out: &mut Vec<Solid>,
    [a, b]: [Point2<f64>; 2],
    reach_past: [bool; 2],
    t: f64,
    h: f64,
    cuts: &[Cut],
) {
    let len = (b - a).norm();
    let u = (b - a) / len;
    let out_n = Vector2::new(u.y, -u.x);
    let yaw = u.y.atan2(u.x);
    let mut piece = |s0: f64, s1: f64, z0: f64, z1: f64, depth: (f64, f64), material| {
        if s1 - s0 <= 1e-6 || z1 - z0 <= 1e-6 {
            return;
        }
        let mid = a + u * ((s0 + s1) / 2.0) + out_n * ((depth.0 + depth.1) / 2.0);
        out.push(Solid::Box {
            center: [mid.x, mid.y, (z0 + z1) / 2.0],
            half: [(s1 - s0) / 2.0, (depth.1 - depth.0) / 2.0, (z1 - z0) / 2.0],
            yaw_rad: yaw,
            material,
        });
    };
    let full = (0.0, t);
    let past = |yes: bool| if yes { t } else { 0.0 };
    let mut start = -past(reach_past[0]);
    for c in cuts {
        piece(start, c.s0, 0.0, h, full, Material::Opaque);
        piece(c.s0, c.s1, 0.0, c.z[0], full, Material::Opaque);
        piece(c.s0, c.s1, c.z[1], h, full, Material::Opaque);
        match c.kind {
            OpeningKind::ClosedDoor => piece(
                c.s0,
                c.s1,
                c.z[0],
                c.z[1],
                (LEAF_M, 2.0 * LEAF_M),
                Material::Opaque,
            ),
            OpeningKind::GlazedWindow => piece(
                c.s0,
                c.s1,
                c.z[0],
                c.z[1],
                (t / 2.0 - GLASS_M / 2.0, t / 2.0 + GLASS_M / 2.0),
                Material::Glass,
            ),
            OpeningKind::OpenDoor | OpeningKind::Window => {}
        }
        start = c.s1;
    }
    piece(
        start,
        len + past(reach_past[1]),
        0.0,
        h,
        full,
        Material::Opaque,
    );
}

/// A top on four legs, the legs inset 5 cm from the top's corners.
fn legged(out: &mut Vec<Solid>, t: &TableSpec) {
    let yaw = t.heading_deg.to_radians();
    let (s, c) = yaw.sin_cos();
    let top = 0.03f64.min(t.height_m / 4.0);
    out.push(Solid::Box {
        center: [t.at[0], t.at[1], t.height_m - top / 2.0],
        half: [t.size_m[0] / 2.0, t.size_m[1] / 2.0, top / 2.0],
        yaw_rad: yaw,
        material: Material::Opaque,
    });
    let (hx, hy) = (t.size_m[0] / 2.0 - 0.05, t.size_m[1] / 2.0 - 0.05);
    for (fx, fy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let (lx, ly) = (fx * hx, fy * hy);
        out.push(Solid::Cylinder {
            at: [t.at[0] + c * lx - s * ly, t.at[1] + s * lx + c * ly],
            radius: t.leg_radius_m,
            z: [0.0, t.height_m - top],
        });
    }
}

/// The openings of the walls of other rooms that build the wall `a`–`b`
/// (inner face) of `room`: facing it, at most a thick wall's depth behind
/// it. Their spans measured along `a`–`b`; those off its length dropped.
fn shared_cuts(world: &WorldSpec, room: &str, a: Point2<f64>, b: Point2<f64>) -> Vec<Cut> {
    /// Deepest a wall between two rooms is taken to be, m.
    const DEPTH_M: f64 = 0.5;
    let len = (b - a).norm();
    let u = (b - a) / len;
    let out_n = Vector2::new(u.y, -u.x);
    let mut cuts = Vec::new();
    for other in world.rooms.iter().filter(|r| r.name != room) {
        let n = other.corners.len();
        for j in 0..n {
            let (c0, c1) = (other.corners[j], other.corners[(j + 1) % n]);
            let (p, q) = (Point2::new(c0[0], c0[1]), Point2::new(c1[0], c1[1]));
            let v = (q - p).normalize();
            let behind = (p - a).dot(&out_n);
            if v.dot(&u) > -0.999 || !(0.0..=DEPTH_M).contains(&behind) {
                continue;
            }
            for c in openings_of(world, &other.name, j) {
                let s = |t: f64| (p + v * t - a).dot(&u);
                let (s0, s1) = (s(c.s0).min(s(c.s1)), s(c.s0).max(s(c.s1)));
                if s1 > 0.0 && s0 < len {
                    cuts.push(Cut {
                        s0: s0.max(0.0),
                        s1: s1.min(len),
                        ..c
                    });
                }
            }
        }
    }
    cuts
}
