//! The plaster scored on the truth: every true plasterable surface of the
//! rooms a job names, whatever the robot planned or believed. Each cell of
//! a wall or ceiling is plasterable (openings and the bands the job leaves
//! to be finished by hand excepted), and then one of: covered (within the
//! coat's tolerance), blocked (bare, and the tool cannot physically reach
//! it for the true furniture and the room's shape), or unreached (the rest:
//! bare, thin or thick where the tool could have sprayed).
//!
//! Reach is the robot's, from the truth: a wall's cell is reached when the
//! robot can stand beside the wall, its body clear of every solid by the
//! clearance, in a pose it can drive to from where it started (forward,
//! back and turning on the spot, its body clear by its protective field's
//! margin), with the cell within
//! the rail's travel, its height within the lift's, and the line from the
//! body's side to the wall at that height free (the arm and the spray). A
//! ceiling's cell is reached when, at one of eight headings, the robot can
//! get to a pose in the room from where the cell lies within the rail's and the arm's travel, the
//! nozzle's height under the ceiling is within the lift's and nothing
//! stands between the nozzle and the cell.

use crate::deposition::{Coat, SurfaceKind};
use crate::grid::CellGrid;
use crate::layout::{Layout, OpeningKind, Solid};
use crate::space::SpaceCaster;
use nalgebra::{Point2, Vector2};
use serde::Serialize;
use stucco_core::Pose2;

/// What the robot can reach: its body and its spray tool's travel, in the
/// robot's frame (x forward of the rear axle, y left, z up).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Reach {
    /// The body's footprint from and to along x, m.
    pub body_x_m: [f64; 2],
    /// Half the body's width, m.
    pub body_half_width_m: f64,
    /// Top of the robot with its tool parked, m: what stands lower is in
    /// the body's way, what hangs higher (a door's head) is not.
    pub body_top_m: f64,
    /// Clearance the body keeps from every solid where it stands to
    /// spray, m.
    pub clearance_m: f64,
    /// Least clearance it keeps while it drives and turns (its protective
    /// field), m.
    pub drive_margin_m: f64,
    /// The nozzle's travel along x (the rail), m.
    pub rail_m: [f64; 2],
    /// Its travel along y (the arm), m.
    pub arm_m: [f64; 2],
    /// Its height's travel (the lift), m.
    pub lift_m: [f64; 2],
    /// The nozzle's distance from a wall it sprays, m.
    pub wall_standoff_m: f64,
    /// Its distance from the ceiling it sprays, m.
    pub ceiling_standoff_m: f64,
}

/// What the job asks: the coat, and the bands it leaves to be finished
/// by hand (not plasterable, not counted).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finish {
    /// The coat, m.
    pub coat_m: f64,
    /// Accepted deviation from the coat, as a share of it.
    pub tolerance: f64,
    /// A wall's plaster starts this high above the floor, m.
    pub skirting_m: f64,
    /// Band along a surface's edges (corners, the ceiling line), m.
    pub edge_margin_m: f64,
    /// Band around an opening, m.
    pub opening_margin_m: f64,
}

/// Plasterable area, and how much of it is covered, blocked, unreached.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Tally {
    /// Every true plasterable area, m².
    pub plasterable_m2: f64,
    /// Within the coat's tolerance, m².
    pub covered_m2: f64,
    /// Not covered, and out of the tool's reach, m².
    pub blocked_m2: f64,
    /// Not covered, within reach: left bare, thin or thick, m².
    pub unreached_m2: f64,
}

impl Tally {
    /// Covered share of the area not blocked, %: what the robot could
    /// reach and did; none when it could reach nothing.
    pub fn coverage_pct(&self) -> Option<f64> {
        let open = self.plasterable_m2 - self.blocked_m2;
        (open > 1e-9).then(|| (100.0 * self.covered_m2 / open).min(100.0))
    }

    fn add(&mut self, o: &Tally) {
        self.plasterable_m2 += o.plasterable_m2;
        self.covered_m2 += o.covered_m2;
        self.blocked_m2 += o.blocked_m2;
        self.unreached_m2 += o.unreached_m2;
    }
}

/// One true surface's tally.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceTruth {
    /// Its room.
    pub room: String,
    /// Wall (by index in its room) or ceiling.
    pub surface: SurfaceKind,
    /// Its areas.
    pub tally: Tally,
}

/// Surface the tool cannot reach, and what stands in the way.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Blocker {
    /// The room.
    pub room: String,
    /// The surface.
    pub surface: SurfaceKind,
    /// What blocks it (`table`, `box`, …, or [`SHUT_DOOR`] for a room the
    /// robot cannot get into), or none: the room's own shape or height (a
    /// corner too tight for the body, a wall above the lift).
    pub what: Option<&'static str>,
    /// Where it stands (the middle of its footprint), m.
    pub at: Option<[f64; 2]>,
    /// The surface it keeps from the tool, m².
    pub area_m2: f64,
}

/// Every named room's true surfaces, tallied.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TrueScore {
    /// All walls together.
    pub walls: Tally,
    /// All ceilings together.
    pub ceilings: Tally,
    /// Each surface.
    pub surfaces: Vec<SurfaceTruth>,
    /// What blocks what, largest first.
    pub blockers: Vec<Blocker>,
}

/// Cells of the floor the robot's reach is searched on, m.
const FLOOR_CELL_M: f64 = 0.05;
/// Steps of the body's distance from a wall tried, m.
const STANDOFF_STEP_M: f64 = 0.05;
/// Deepest a doorway through a wall is taken to be, m.
const DOORWAY_M: f64 = 0.5;
/// Headings of the lattice of poses the robot can get to.
const HEADINGS: usize = 32;

/// Scores the plaster of `coats` on the true surfaces of `rooms` of
/// `layout`, the robot having started at `start` (true pose).
pub fn score_truth(
    layout: &Layout,
    coats: &[Coat],
    rooms: &[String],
    start: &Pose2,
    reach: &Reach,
    finish: &Finish,
) -> TrueScore {
    let world = World::new(layout, reach, start);
    let mut out = TrueScore::default();
    let mut blocked: Vec<Blocker> = Vec::new();
    // Each room's shut door when the robot cannot get into it, worked out
    // once a room.
    let mut shut: Vec<(String, Option<Option<[f64; 2]>>)> = Vec::new();
    for coat in coats.iter().filter(|c| rooms.contains(&c.room)) {
        let Some(room) = layout.rooms.iter().find(|r| r.name == coat.room) else {
            continue;
        };
        let cells = match coat.kind {
            SurfaceKind::Wall { .. } => world.wall_cells(coat, finish),
            SurfaceKind::Ceiling => world.ceiling_cells(coat, &room.corners, room.height_m, finish),
        };
        // A room the robot cannot get into at all (a shut door, a way too
        // narrow): every blocked cell is put to its shut door, if it has
        // one.
        let shut_door = match shut.iter().find(|(r, _)| r == &coat.room) {
            Some((_, d)) => *d,
            None => {
                let d = (!world.enterable(&room.corners)).then(|| {
                    layout
                        .openings
                        .iter()
                        .find(|o| o.room == coat.room && o.kind == OpeningKind::ClosedDoor)
                        .map(|o| {
                            let m = nalgebra::center(&o.edges[0], &o.edges[1]);
                            [m.x, m.y]
                        })
                });
                shut.push((coat.room.clone(), d));
                d
            }
        };
        let area = coat.grid.cell_area_m2();
        let mut tally = Tally::default();
        for cell in &cells {
            tally.plasterable_m2 += area;
            match cell {
                Cell::Covered => tally.covered_m2 += area,
                Cell::Unreached => tally.unreached_m2 += area,
                Cell::Blocked(by) => {
                    tally.blocked_m2 += area;
                    let (what, at) = match (shut_door, by) {
                        (Some(door), _) => (door.map(|_| SHUT_DOOR), door),
                        (None, Some(k)) => {
                            (Some(layout.pieces[*k].what), Some(layout.pieces[*k].at))
                        }
                        (None, None) => (None, None),
                    };
                    match blocked
                        .iter_mut()
                        .find(|b| b.room == coat.room && b.surface == coat.kind && b.at == at)
                    {
                        Some(b) => b.area_m2 += area,
                        None => blocked.push(Blocker {
                            room: coat.room.clone(),
                            surface: coat.kind.clone(),
                            what,
                            at,
                            area_m2: area,
                        }),
                    }
                }
            }
        }
        match coat.kind {
            SurfaceKind::Wall { .. } => out.walls.add(&tally),
            SurfaceKind::Ceiling => out.ceilings.add(&tally),
        }
        out.surfaces.push(SurfaceTruth {
            room: coat.room.clone(),
            surface: coat.kind.clone(),
            tally,
        });
    }
    blocked.sort_by(|a, b| b.area_m2.total_cmp(&a.area_m2));
    out.blockers = blocked;
    out
}

/// What a blocker is when it is the shut door of a room the robot cannot
/// get into.
pub const SHUT_DOOR: &str = "shut door";

/// A plasterable cell's lot.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Cell {
    Covered,
    /// Blocked, by the piece of furniture of this index or by the room.
    Blocked(Option<usize>),
    Unreached,
}

/// A solid's footprint, for the body.
#[derive(Clone, Copy, Debug)]
enum Footprint {
    /// Centre, half extents, and the cosine and sine of its heading.
    Rect {
        c: Point2<f64>,
        half: [f64; 2],
        cs: (f64, f64),
    },
    Disc {
        c: Point2<f64>,
        r: f64,
    },
}

impl Footprint {
    fn of(solid: &Solid) -> (Footprint, [f64; 2]) {
        match *solid {
            Solid::Box {
                center,
                half,
                yaw_rad,
                ..
            } => (
                Footprint::Rect {
                    c: Point2::new(center[0], center[1]),
                    half: [half[0], half[1]],
                    cs: (yaw_rad.cos(), yaw_rad.sin()),
                },
                [center[2] - half[2], center[2] + half[2]],
            ),
            Solid::Cylinder { at, radius, z } => (
                Footprint::Disc {
                    c: Point2::new(at[0], at[1]),
                    r: radius,
                },
                z,
            ),
        }
    }

    /// Its bounding box.
    fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        match *self {
            Footprint::Rect { c, half, cs } => {
                let e = Vector2::new(
                    (cs.0 * half[0]).abs() + (cs.1 * half[1]).abs(),
                    (cs.1 * half[0]).abs() + (cs.0 * half[1]).abs(),
                );
                (c - e, c + e)
            }
            Footprint::Disc { c, r } => (c - Vector2::new(r, r), c + Vector2::new(r, r)),
        }
    }

    /// Distance from `p` to it (0 inside).
    fn distance(&self, p: &Point2<f64>) -> f64 {
        match *self {
            Footprint::Rect { c, half, cs } => {
                let d = p - c;
                let (x, y) = (cs.0 * d.x + cs.1 * d.y, -cs.1 * d.x + cs.0 * d.y);
                let (ex, ey) = ((x.abs() - half[0]).max(0.0), (y.abs() - half[1]).max(0.0));
                ex.hypot(ey)
            }
            Footprint::Disc { c, r } => ((p - c).norm() - r).max(0.0),
        }
    }

    /// True when it comes within `grow` of the rectangle centred at `c`
    /// with half extents `half`, turned to `cs`.
    fn meets_rect(&self, c: &Point2<f64>, half: [f64; 2], cs: (f64, f64), grow: f64) -> bool {
        match *self {
            Footprint::Disc { c: p, r } => {
                Footprint::Rect { c: *c, half, cs }.distance(&p) < r + grow
            }
            Footprint::Rect {
                c: c2,
                half: h2,
                cs: cs2,
            } => {
                // Separating axes of two rectangles, the body's grown.
                let h1 = [half[0] + grow, half[1] + grow];
                let axes = [
                    Vector2::new(cs.0, cs.1),
                    Vector2::new(-cs.1, cs.0),
                    Vector2::new(cs2.0, cs2.1),
                    Vector2::new(-cs2.1, cs2.0),
                ];
                let d = c2 - c;
                axes.iter().all(|n| {
                    let r1 = h1[0] * n.dot(&axes[0]).abs() + h1[1] * n.dot(&axes[1]).abs();
                    let r2 = h2[0] * n.dot(&axes[2]).abs() + h2[1] * n.dot(&axes[3]).abs();
                    d.dot(n).abs() < r1 + r2
                })
            }
        }
    }
}

/// The world as the reach needs it: the footprints in the body's way, the
/// floor the robot can get to, the solids for the arm's and spray's lines.
struct World<'a> {
    layout: &'a Layout,
    reach: &'a Reach,
    /// Footprints of the solids in the body's way, with the piece each
    /// belongs to.
    feet: Vec<(Footprint, Option<usize>)>,
    grid: CellGrid,
    caster: SpaceCaster,
    /// The poses the robot can get to.
    lattice: Lattice,
}

/// The poses the robot can get to from where it started: a lattice of
/// positions (its rear axle) and headings, joined by driving a step
/// forward or back and by turning on the spot (the front wheel steered
/// across), each pose's body clear of every solid.
struct Lattice {
    origin: Point2<f64>,
    cells: [usize; 2],
    reached: Vec<bool>,
}

impl Lattice {
    fn heading(h: usize) -> f64 {
        h as f64 * std::f64::consts::TAU / HEADINGS as f64
    }

    fn centre(&self, i: usize, j: usize) -> Point2<f64> {
        self.origin
            + Vector2::new(
                (i as f64 + 0.5) * FLOOR_CELL_M,
                (j as f64 + 0.5) * FLOOR_CELL_M,
            )
    }

    fn cell(&self, p: &Point2<f64>) -> Option<(usize, usize)> {
        let i = ((p.x - self.origin.x) / FLOOR_CELL_M).floor();
        let j = ((p.y - self.origin.y) / FLOOR_CELL_M).floor();
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.cells[0] && (j as usize) < self.cells[1])
            .then_some((i as usize, j as usize))
    }

    fn index(&self, i: usize, j: usize, h: usize) -> usize {
        (j * self.cells[0] + i) * HEADINGS + h
    }

    /// True when a lattice pose next to `pose` (its cell, one of the two
    /// headings either side of its own) was reached.
    fn reaches(&self, pose: &Pose2) -> bool {
        let Some((i, j)) = self.cell(&pose.position()) else {
            return false;
        };
        let x = pose.theta.rem_euclid(std::f64::consts::TAU) / Self::heading(1);
        let below = x.floor() as usize % HEADINGS;
        [below, (below + 1) % HEADINGS]
            .iter()
            .any(|&h| self.reached[self.index(i, j, h)])
    }
}

impl<'a> World<'a> {
    fn new(layout: &'a Layout, reach: &'a Reach, start: &Pose2) -> World<'a> {
        let piece_of = |k: usize| layout.pieces.iter().position(|p| p.solids.contains(&k));
        let feet: Vec<(Footprint, Option<usize>)> = layout
            .solids
            .iter()
            .enumerate()
            .filter_map(|(k, s)| {
                let (f, z) = Footprint::of(s);
                (z[1] > 0.005 && z[0] < reach.body_top_m).then(|| (f, piece_of(k)))
            })
            .collect();
        let bounds: Vec<_> = feet.iter().map(|(f, _)| f.bounds()).collect();
        let grid = CellGrid::new(&bounds);
        let mut world = World {
            layout,
            reach,
            feet,
            grid,
            caster: SpaceCaster::new(layout),
            lattice: Lattice {
                origin: Point2::origin(),
                cells: [0, 0],
                reached: Vec::new(),
            },
        };
        world.lattice = world.drive(start);
        world
    }

    /// The first footprint within `grow` of the body at `pose`, if any:
    /// its piece (none for the building).
    fn body_meets(&self, pose: &Pose2, grow: f64) -> Option<Option<usize>> {
        let r = self.reach;
        let cs = (pose.theta.cos(), pose.theta.sin());
        let mid = (r.body_x_m[0] + r.body_x_m[1]) / 2.0;
        let c = Point2::new(pose.x + cs.0 * mid, pose.y + cs.1 * mid);
        let half = [(r.body_x_m[1] - r.body_x_m[0]) / 2.0, r.body_half_width_m];
        let e = half[0].hypot(half[1]) + grow;
        let (lo, hi) = (c - Vector2::new(e, e), c + Vector2::new(e, e));
        self.grid
            .overlapping(&lo, &hi)
            .find(|&k| self.feet[k].0.meets_rect(&c, half, cs, grow))
            .map(|k| self.feet[k].1)
    }

    /// The poses joined to `start` by driving and turning on the spot,
    /// the body clear of every solid and over the rooms (or a doorway
    /// through their walls).
    fn drive(&self, start: &Pose2) -> Lattice {
        let (mut lo, mut hi) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for r in &self.layout.rooms {
            for c in &r.corners {
                lo = lo.inf(c);
                hi = hi.sup(c);
            }
        }
        let mut lattice = Lattice {
            origin: lo,
            cells: [0, 0],
            reached: Vec::new(),
        };
        if !lo.x.is_finite() {
            return lattice;
        }
        lattice.cells = [
            ((hi.x - lo.x) / FLOOR_CELL_M).ceil() as usize + 1,
            ((hi.y - lo.y) / FLOOR_CELL_M).ceil() as usize + 1,
        ];
        let n = lattice.cells[0] * lattice.cells[1];
        // Each cell over a room (or a doorway), each pose's body clear:
        // worked out when first asked.
        let over: Vec<bool> = (0..n)
            .map(|k| {
                let p = lattice.centre(k % lattice.cells[0], k / lattice.cells[0]);
                self.layout
                    .rooms
                    .iter()
                    .any(|r| inside(&r.corners, &p) || edge_distance(&r.corners, &p) <= DOORWAY_M)
            })
            .collect();
        let mut clear: Vec<Option<bool>> = vec![None; n * HEADINGS];
        let mut is_clear = |i: usize, j: usize, h: f64, k: Option<usize>| -> bool {
            let margin = self.reach.drive_margin_m;
            let body = |p: Point2<f64>| self.body_meets(&Pose2::new(p.x, p.y, h), margin).is_none();
            let p = lattice.centre(i, j);
            if !over[j * lattice.cells[0] + i] {
                return false;
            }
            match k {
                Some(k) => *clear[k].get_or_insert_with(|| body(p)),
                None => body(p),
            }
        };
        // From the clear pose nearest the start.
        let Some((i0, j0)) = lattice.cell(&start.position()) else {
            return lattice;
        };
        let h0 = (start.theta.rem_euclid(std::f64::consts::TAU) / Lattice::heading(1)).round()
            as usize
            % HEADINGS;
        let mut seed = None;
        'search: for ring in 0..20usize {
            let r = ring as i64;
            for dj in -r..=r {
                for di in -r..=r {
                    if di.abs().max(dj.abs()) != r {
                        continue;
                    }
                    let (i, j) = (i0 as i64 + di, j0 as i64 + dj);
                    if i < 0
                        || j < 0
                        || i as usize >= lattice.cells[0]
                        || j as usize >= lattice.cells[1]
                    {
                        continue;
                    }
                    let (i, j) = (i as usize, j as usize);
                    for dh in 0..HEADINGS {
                        let h = (h0 + dh) % HEADINGS;
                        let k = lattice.index(i, j, h);
                        if is_clear(i, j, Lattice::heading(h), Some(k)) {
                            seed = Some((i, j, h));
                            break 'search;
                        }
                    }
                }
            }
        }
        let mut reached = vec![false; n * HEADINGS];
        let mut stack: Vec<(usize, usize, usize)> = seed.into_iter().collect();
        if let Some((i, j, h)) = seed {
            reached[lattice.index(i, j, h)] = true;
        }
        let [nx, ny] = lattice.cells.map(|c| c as i64);
        while let Some((i, j, h)) = stack.pop() {
            let theta = Lattice::heading(h);
            let mut next: Vec<(usize, usize, usize, Option<f64>)> = Vec::with_capacity(4);
            // A step forward or back: the neighbouring cell nearest the
            // heading, two cells out.
            for sign in [1.0, -1.0] {
                let (di, dj) = (
                    (sign * 2.0 * theta.cos()).round() as i64,
                    (sign * 2.0 * theta.sin()).round() as i64,
                );
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a >= 0 && b >= 0 && a < nx && b < ny {
                    next.push((a as usize, b as usize, h, None));
                }
            }
            // A turn on the spot, the body clear half way through it too.
            for dh in [1, HEADINGS - 1] {
                let to = (h + dh) % HEADINGS;
                let half = theta + if dh == 1 { 0.5 } else { -0.5 } * Lattice::heading(1);
                next.push((i, j, to, Some(half)));
            }
            for (a, b, to, half) in next {
                let k = lattice.index(a, b, to);
                if reached[k] {
                    continue;
                }
                let swept = half.is_none_or(|t| is_clear(a, b, t, None));
                if swept && is_clear(a, b, Lattice::heading(to), Some(k)) {
                    reached[k] = true;
                    stack.push((a, b, to));
                }
            }
        }
        lattice.reached = reached;
        lattice
    }

    /// True when the robot can get into the room of `corners`: a pose it
    /// gets to stands in it.
    fn enterable(&self, corners: &[Point2<f64>]) -> bool {
        let l = &self.lattice;
        l.reached.iter().enumerate().any(|(k, &r)| {
            r && {
                let cell = k / HEADINGS;
                inside(corners, &l.centre(cell % l.cells[0], cell / l.cells[0]))
            }
        })
    }

    /// True when the robot can stand at `pose`: on floor it can get to,
    /// its body clear by the clearance.
    fn stands(&self, pose: &Pose2) -> bool {
        self.lattice.reaches(pose) && self.body_meets(pose, self.reach.clearance_m).is_none()
    }

    /// The piece of furniture nearest `p` within `within_m`, if any.
    fn piece_near(&self, p: &Point2<f64>, within_m: f64) -> Option<usize> {
        self.layout
            .pieces
            .iter()
            .enumerate()
            .filter_map(|(k, piece)| {
                let d = self.layout.solids[piece.solids.clone()]
                    .iter()
                    .map(|s| Footprint::of(s).0.distance(p))
                    .fold(f64::INFINITY, f64::min);
                (d <= within_m).then_some((k, d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k)
    }

    /// The lot of each plasterable cell of a wall's coat.
    fn wall_cells(&self, coat: &Coat, finish: &Finish) -> Vec<Cell> {
        let r = self.reach;
        let g = &coat.grid;
        let [length, height] = coat.frame.size_m;
        let a = Point2::new(coat.frame.origin.x, coat.frame.origin.y);
        let u = Vector2::new(coat.frame.u.x, coat.frame.u.y);
        let inward = Vector2::new(-u.y, u.x);
        // The wall on its left: the robot faces from the wall's end to its
        // start, and the rail's x runs against the wall's u.
        let heading = (-u.y).atan2(-u.x);
        let [nu, nv] = g.cells;
        let plasterable = |uv: [f64; 2]| {
            let m = finish.edge_margin_m;
            uv[0] >= m
                && uv[0] <= length - m
                && uv[1] >= finish.skirting_m
                && uv[1] <= height - m
                && !coat.openings.iter().any(|o| {
                    let om = finish.opening_margin_m;
                    uv[0] > o[0] - om && uv[0] < o[1] + om && uv[1] > o[2] - om && uv[1] < o[3] + om
                })
        };
        // Nearest the body stands to the wall, column by column.
        let mut nearest = vec![f64::INFINITY; nu];
        let d_lo = r.arm_m[0].max(r.body_half_width_m) + r.wall_standoff_m;
        let d_hi = r.arm_m[1] + r.wall_standoff_m;
        let steps = ((d_hi - d_lo) / STANDOFF_STEP_M).floor().max(0.0) as usize;
        let t_step = g.cell_m;
        let reach_past = r.rail_m[1].abs().max(r.rail_m[0].abs());
        let t_n = ((length + 2.0 * reach_past) / t_step).ceil() as usize;
        for s in 0..=steps {
            let d = d_lo + s as f64 * STANDOFF_STEP_M;
            for k in 0..=t_n {
                let t = -reach_past + k as f64 * t_step;
                let p = a + u * t + inward * d;
                if !self.stands(&Pose2::new(p.x, p.y, heading)) {
                    continue;
                }
                // The nozzle at rail x lies at t − x along the wall.
                let (s0, s1) = (t - r.rail_m[1], t - r.rail_m[0]);
                let i0 = (s0 / g.cell_m - 0.5).ceil().max(0.0) as usize;
                let i1 = ((s1 / g.cell_m - 0.5).floor()).min(nu as f64 - 1.0);
                if i1 < 0.0 {
                    continue;
                }
                for best in nearest.iter_mut().take(i1 as usize + 1).skip(i0) {
                    *best = best.min(d);
                }
            }
        }
        let mut out = Vec::new();
        for j in 0..nv {
            for (i, &stand) in nearest.iter().enumerate() {
                let uv = g.center(i, j);
                if !plasterable(uv) {
                    continue;
                }
                let t = g.at(i, j);
                if (t / finish.coat_m - 1.0).abs() <= finish.tolerance {
                    out.push(Cell::Covered);
                    continue;
                }
                let foot = a + u * uv[0];
                let z = uv[1];
                let arm = stand - r.body_half_width_m;
                let lifted = z >= r.lift_m[0] && z <= r.lift_m[1];
                if !lifted {
                    out.push(Cell::Blocked(None));
                    continue;
                }
                if stand.is_infinite() {
                    // Nowhere to stand: what is in the body's way where it
                    // would stand nearest.
                    let mid = (r.rail_m[0] + r.rail_m[1]) / 2.0;
                    let p = foot + u * mid + inward * d_lo;
                    let by = self
                        .body_meets(&Pose2::new(p.x, p.y, heading), r.clearance_m)
                        .flatten()
                        .or_else(|| self.piece_near(&(foot + inward * d_lo), d_lo));
                    out.push(Cell::Blocked(by));
                    continue;
                }
                let o = [foot.x + inward.x * 1e-3, foot.y + inward.y * 1e-3, z];
                match self.caster.cast(o, [inward.x, inward.y, 0.0], arm, 0.0) {
                    None => out.push(Cell::Unreached),
                    Some(s) => {
                        let hit = foot + inward * (s + 1e-3);
                        out.push(Cell::Blocked(self.piece_near(&hit, 0.05)));
                    }
                }
            }
        }
        out
    }

    /// The lot of each plasterable cell of a ceiling's coat (over its
    /// room's bounding box; the cells inside the room's polygon).
    fn ceiling_cells(
        &self,
        coat: &Coat,
        corners: &[Point2<f64>],
        height_m: f64,
        finish: &Finish,
    ) -> Vec<Cell> {
        let r = self.reach;
        let g = &coat.grid;
        let [nu, nv] = g.cells;
        let o = Point2::new(coat.frame.origin.x, coat.frame.origin.y);
        let at = |uv: [f64; 2]| o + Vector2::new(uv[0], uv[1]);
        let nozzle_z = height_m - r.ceiling_standoff_m;
        let lifted = nozzle_z >= r.lift_m[0] && nozzle_z <= r.lift_m[1];
        // Cells the nozzle gets under, from every pose the robot gets to
        // (every other cell of the lattice, eight headings).
        let mut under = vec![false; nu * nv];
        let (lo, hi) = (
            o - Vector2::new(1.5, 1.5),
            o + Vector2::new(
                g.cells[0] as f64 * g.cell_m + 1.5,
                g.cells[1] as f64 * g.cell_m + 1.5,
            ),
        );
        let l = &self.lattice;
        for j in (0..l.cells[1]).step_by(2) {
            for i in (0..l.cells[0]).step_by(2) {
                let p = l.centre(i, j);
                if p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
                    continue;
                }
                for h in (0..HEADINGS).step_by(HEADINGS / 8) {
                    if !l.reached[l.index(i, j, h)] {
                        continue;
                    }
                    let theta = Lattice::heading(h);
                    let pose = Pose2::new(p.x, p.y, theta);
                    // The body in the room: the arm does not reach
                    // through a wall.
                    let mid = (r.body_x_m[0] + r.body_x_m[1]) / 2.0;
                    let centre = Point2::new(p.x + theta.cos() * mid, p.y + theta.sin() * mid);
                    if !inside(corners, &centre) || self.body_meets(&pose, r.clearance_m).is_some()
                    {
                        continue;
                    }
                    mark_reach(&mut under, g, &o, &pose, r);
                }
            }
        }
        let mut out = Vec::new();
        for j in 0..nv {
            for i in 0..nu {
                let uv = g.center(i, j);
                let p = at(uv);
                if !inside(corners, &p) || edge_distance(corners, &p) < finish.edge_margin_m {
                    continue;
                }
                let t = g.at(i, j);
                if (t / finish.coat_m - 1.0).abs() <= finish.tolerance {
                    out.push(Cell::Covered);
                    continue;
                }
                if !lifted {
                    out.push(Cell::Blocked(None));
                    continue;
                }
                let from = [p.x, p.y, height_m - 1e-3];
                let below = self
                    .caster
                    .cast(from, [0.0, 0.0, -1.0], r.ceiling_standoff_m, 0.0);
                if below.is_some() || !under[j * nu + i] {
                    out.push(Cell::Blocked(self.piece_near(&p, 1.5)));
                } else {
                    out.push(Cell::Unreached);
                }
            }
        }
        out
    }
}

/// Marks the cells of the ceiling grid `g` (origin `o`, axes x and y) the
/// nozzle gets under from `pose`.
fn mark_reach(
    under: &mut [bool],
    g: &stucco_core::ThicknessGrid,
    o: &Point2<f64>,
    pose: &Pose2,
    r: &Reach,
) {
    let (c, s) = (pose.theta.cos(), pose.theta.sin());
    let corners = [
        [r.rail_m[0], r.arm_m[0]],
        [r.rail_m[1], r.arm_m[0]],
        [r.rail_m[1], r.arm_m[1]],
        [r.rail_m[0], r.arm_m[1]],
    ]
    .map(|[x, y]| Point2::new(pose.x + c * x - s * y - o.x, pose.y + s * x + c * y - o.y));
    let (mut lo, mut hi) = (corners[0], corners[0]);
    for q in &corners[1..] {
        lo = lo.inf(q);
        hi = hi.sup(q);
    }
    let [nu, nv] = g.cells;
    let cell = g.cell_m;
    let i0 = ((lo.x / cell - 0.5).ceil().max(0.0)) as usize;
    let j0 = ((lo.y / cell - 0.5).ceil().max(0.0)) as usize;
    let i1 = (hi.x / cell - 0.5).floor();
    let j1 = (hi.y / cell - 0.5).floor();
    if i1 < 0.0 || j1 < 0.0 {
        return;
    }
    let (i1, j1) = ((i1 as usize).min(nu - 1), (j1 as usize).min(nv - 1));
    for j in j0..=j1 {
        for i in i0..=i1 {
            let q = g.center(i, j);
            let (dx, dy) = (q[0] + o.x - pose.x, q[1] + o.y - pose.y);
            let (x, y) = (c * dx + s * dy, -s * dx + c * dy);
            if x >= r.rail_m[0] && x <= r.rail_m[1] && y >= r.arm_m[0] && y <= r.arm_m[1] {
                under[j * nu + i] = true;
            }
        }
    }
}

/// True when `p` lies inside the polygon `corners` (even–odd rule).
pub fn inside(corners: &[Point2<f64>], p: &Point2<f64>) -> bool {
    let n = corners.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (corners[i], corners[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance from `p` to the nearest side of the polygon `corners`.
pub fn edge_distance(corners: &[Point2<f64>], p: &Point2<f64>) -> f64 {
    let n = corners.len();
    (0..n)
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            let ab = b - a;
            let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-18)).clamp(0.0, 1.0);
            (p - (a + ab * t)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}
