//! Manoeuvres where the robot cannot turn on the spot.
//!
//! The tricycle turns about the middle of its rear axle and its front
//! corners sweep a circle of 0.81 m radius: in a 1.2 m hall, or in a
//! doorway with a chair beyond it, a turn on the spot would put the front
//! into a wall. A driver turns a car in a narrow street in several moves;
//! the robot does the same with partial turns on the spot and short
//! straight runs, forward or backing, between them. [`Space::manoeuvre`]
//! finds such moves by an A* search over the pose; its estimate of the
//! way still to go is the crow's flight at first, and past a few thousand
//! poses the shortest way over the floor for a disc as wide as the body
//! (round furniture, through a door), which also tells a goal no way
//! reaches.
//!
//! Every pose along every move keeps the body inside the room (or a
//! doorway of it) and off what stands on the floor, with the supervisor's
//! protective field around it: its sides grown by the lateral margin, and
//! the body carried on past the end of each move by the field's length,
//! so that the supervisor never stops a manoeuvre planned here (the field
//! does not know where a move ends).

use crate::behaviour::{Behaviour, BehaviourKind};
use crate::model::{DoorEstimate, WallGeometry};
use crate::route::rect_clear;
use crate::supervisor::SafetyConfig;
use nalgebra::{Rotation2, Vector2};
use std::collections::{BTreeMap, BTreeSet};
use stucco_control::GainSchedule;
use stucco_core::{Pose2, VehicleSpec, wrap_angle};
use stucco_plan::{Obstacle, Outline};

/// Room kept between the field and the walls for the motion's own
/// error (estimate and tracking), m.
const PLAN_MARGIN_M: f64 = 0.02;
/// Room kept between the field and what stands on the floor, whose place
/// the map knows less well than the walls', m.
const OBSTACLE_MARGIN_M: f64 = 0.02;
/// How far a doorway's free space reaches beyond its wall, m.
const DOORWAY_DEPTH_M: f64 = 1.5;
/// The grid the search tells poses apart on: position, m, and heading.
const CELL_M: f64 = 0.03;
const CELL_RAD: f64 = 5.0 * std::f64::consts::PI / 180.0;
/// The largest turn whose way round is sure, rad.
const MAX_TURN_RAD: f64 = 170.0 * std::f64::consts::PI / 180.0;
/// Poses along a turn are checked this often, rad, and along a run, m.
const TURN_STEP_RAD: f64 = 2.0 * std::f64::consts::PI / 180.0;
const RUN_STEP_M: f64 = 0.02;
/// Turns and runs the search tries, deg and m (each either way).
const TURNS_DEG: [f64; 6] = [5.0, 10.0, 20.0, 30.0, 45.0, 90.0];
const RUNS_M: [f64; 7] = [0.05, 0.1, 0.2, 0.4, 0.8, 1.6, 3.2];
/// What a run's stop and start are reckoned to add to it, s.
const RUN_OVERHEAD_S: f64 = 0.5;
/// Rate a turn on the spot is reckoned at, rad/s.
pub(crate) const TURN_RADPS: f64 = 0.5;
/// Poses the search may expand before it gives up.
const BUDGET: usize = 100_000;
/// How much the search's estimate of the time still to go is inflated.
const GREED: f64 = 1.5;
/// Poses the search expands on its estimate as the crow flies before it
/// works out the way over the floor (most ways are found before).
const CROW_EXPANSIONS: usize = 2_000;
/// Cells of the floor the way over it is worked out on, m.
const REACH_CELL_M: f64 = 0.1;
/// Points on the rim of the body's middle disc checked free.
const RIM_POINTS: usize = 24;
/// A run's start this far off the line through its goal, m, or turned
/// this much from it, rad, is taken onto the line by the line law with a
/// swing of the body no straight run sweeps.
const RUN_OFF_LINE_M: f64 = 0.05;
const RUN_OFF_LINE_RAD: f64 = 0.1;
/// A goal this near needs no run, m, and this near in heading no turn, rad.
const AT_GOAL_M: f64 = 0.01;
const AT_GOAL_RAD: f64 = 0.01;

/// One move of a manoeuvre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Move {
    /// A turn on the spot to this heading, rad.
    Turn(f64),
    /// A straight run to this pose (the heading the run's), forward or
    /// backing.
    Run { to: Pose2, forward: bool },
}

/// A door's free space beyond its wall: along the wall between two
/// positions, from the wall's line out to [`DOORWAY_DEPTH_M`].
#[derive(Clone, Copy, Debug)]
struct Doorway {
    wall: WallGeometry,
    from_m: f64,
    to_m: f64,
}

impl Doorway {
    fn contains(&self, p: &Vector2<f64>) -> bool {
        let (at, d) = (self.wall.position(p), self.wall.distance(p));
        (self.from_m..=self.to_m).contains(&at) && (-DOORWAY_DEPTH_M..=0.05).contains(&d)
    }
}

/// Where a manoeuvre may go: the room, its doorways, what stands on the
/// floor, and the body with its protective field.
#[derive(Clone, Debug)]
pub(crate) struct Space<'a> {
    room_m: [f64; 2],
    /// The floor's outline of a room that is not a rectangle.
    outline: Option<Outline<'a>>,
    obstacles: &'a [Obstacle],
    doorways: Vec<Doorway>,
    /// The body's rectangle in its own frame, field and margins included:
    /// behind the rear axle, ahead of it, and half its width, m.
    rear_m: f64,
    front_m: f64,
    half_width_m: f64,
    /// How far the field reaches past the end of a run, m, and of a turn,
    /// rad.
    run_field_m: f64,
    turn_field_rad: f64,
    /// Time costs of the search: the speed of a run, m/s, the rate of a
    /// turn, rad/s, and the time a turn's wheel takes to swing across and
    /// back, s.
    speed_mps: f64,
    turn_radps: f64,
    turn_overhead_s: f64,
}

/// How far the middle of the body is from its place at the goal over the
/// floor, cell by cell: the shortest way for a disc as wide as the body
/// (what any pose of the body clears), 8-neighbours, infinite where no
/// such way reaches.
#[derive(Clone, Debug)]
pub(crate) struct Reach {
    first: Vector2<f64>,
    cells: [usize; 2],
    metres: Vec<f64>,
}

impl Reach {
    /// The index of the cell `p` lies in, if the grid holds it.
    fn cell(&self, p: &Vector2<f64>) -> Option<usize> {
        let c = (p - self.first) / REACH_CELL_M;
        let (i, j) = (c.x.floor(), c.y.floor());
        (i >= 0.0 && j >= 0.0 && i < self.cells[0] as f64 && j < self.cells[1] as f64)
            .then(|| j as usize * self.cells[0] + i as usize)
    }

    fn at(&self, p: &Vector2<f64>) -> f64 {
        self.cell(p).map_or(f64::INFINITY, |k| self.metres[k])
    }

    /// The middle of every `every`-th cell across and along that the way
    /// reaches, with how far it is over the floor, m.
    pub(crate) fn reached(&self, every: usize) -> impl Iterator<Item = (Vector2<f64>, f64)> + '_ {
        let every = every.max(1);
        let [ni, nj] = self.cells;
        (0..nj).step_by(every).flat_map(move |j| {
            (0..ni).step_by(every).filter_map(move |i| {
                let m = self.metres[j * ni + i];
                m.is_finite().then(|| {
                    let c = Vector2::new(i as f64 + 0.5, j as f64 + 0.5) * REACH_CELL_M;
                    (self.first + c, m)
                })
            })
        })
    }
}

impl<'a> Space<'a> {
    /// The room `room_m` (or, when they are given, of the `corners`
    /// within that box) with its `doors` and `obstacles`, for `vehicle`
    /// under the supervisor's `safety` field, driven at `speed_mps`.
    pub fn new(
        room_m: [f64; 2],
        corners: &'a [[f64; 2]],
        doors: &[DoorEstimate],
        obstacles: &'a [Obstacle],
        vehicle: &VehicleSpec,
        safety: &SafetyConfig,
        speed_mps: f64,
    ) -> Self {
        let doorways = doors
            .iter()
            .filter_map(|d| {
                let half = 0.5 * d.width_m.unwrap_or(vehicle.width_m + 0.1);
                Some(Doorway {
                    wall: WallGeometry::of_room(corners, room_m, d.wall)?,
                    from_m: d.position_m - half,
                    to_m: d.position_m + half,
                })
            })
            .collect();
        // The field's length past a move's end: its margin, and what the
        // speed a move ends at adds to it, taken as 0.05 rad/s about the
        // rear axle (0.03 m/s at the wheel). A pivot braking evenly onto
        // its heading ends at about 0.09 rad/s and a run at about 0.04 m/s:
        // the field then reaches 3–4 mm further, which the plan margin
        // takes.
        let creep = 0.05 * vehicle.wheelbase_m;
        let field =
            safety.obstacle_margin_m + creep * creep / (2.0 * safety.stop_decel_mps2) + 0.1 * creep;
        Space {
            room_m,
            outline: (!corners.is_empty()).then(|| Outline::new(corners)),
            obstacles,
            doorways,
            rear_m: vehicle.rear_overhang_m + PLAN_MARGIN_M,
            front_m: vehicle.front_m() + PLAN_MARGIN_M,
            half_width_m: 0.5 * vehicle.width_m + safety.lateral_margin_m + PLAN_MARGIN_M,
            run_field_m: field + PLAN_MARGIN_M,
            turn_field_rad: (field + PLAN_MARGIN_M) / vehicle.wheelbase_m,
            speed_mps: speed_mps.max(0.05),
            turn_radps: TURN_RADPS,
            turn_overhead_s: 2.0 * (vehicle.max_steer_rad / vehicle.max_steer_rate_radps + 0.1),
        }
    }

    fn free_point(&self, p: &Vector2<f64>) -> bool {
        let [xs, ys] = self.room_m;
        let in_room = match &self.outline {
            Some(o) => o.contains(&(*p).into()),
            None => (0.0..=xs).contains(&p.x) && (0.0..=ys).contains(&p.y),
        };
        in_room || self.doorways.iter().any(|d| d.contains(p))
    }

    /// How far ahead of the rear axle the body's middle is, m (its field
    /// and margins included).
    pub(crate) fn middle_ahead_m(&self) -> f64 {
        0.5 * (self.front_m - self.rear_m)
    }

    /// The middle of the body (field and margins included) of a robot
    /// at `pose`.
    fn middle(&self, pose: &Pose2) -> Vector2<f64> {
        let f = Vector2::new(pose.theta.cos(), pose.theta.sin());
        pose.position().coords + f * self.middle_ahead_m()
    }

    /// The way over the floor to the body's middle at `goal`: a cell is
    /// free when the disc the body holds about its middle (its half-width,
    /// less the cell's half-diagonal and a centimetre for the rim's
    /// points) is in the room or a doorway and off every obstacle, so the
    /// middle of every clear pose lies in a free cell and every clear way
    /// keeps to free cells joined one to the next. The way is the same
    /// both ways: from a robot standing at `goal`, where its middle can go
    /// and how far.
    pub(crate) fn reach(&self, goal: &Pose2) -> Reach {
        let [xs, ys] = self.room_m;
        let pad = if self.doorways.is_empty() {
            0.0
        } else {
            DOORWAY_DEPTH_M
        };
        let first = Vector2::new(-pad, -pad);
        let cells = [xs, ys].map(|s| ((s + 2.0 * pad) / REACH_CELL_M).ceil().max(1.0) as usize);
        let half = 0.5 * (self.front_m + self.rear_m);
        let r = self.half_width_m.min(half) - std::f64::consts::FRAC_1_SQRT_2 * REACH_CELL_M - 0.01;
        let free_cell = |k: usize| {
            let c = first
                + Vector2::new(
                    ((k % cells[0]) as f64 + 0.5) * REACH_CELL_M,
                    ((k / cells[0]) as f64 + 0.5) * REACH_CELL_M,
                );
            let rim = (0..RIM_POINTS).all(|n| {
                let a = std::f64::consts::TAU * n as f64 / RIM_POINTS as f64;
                self.free_point(&(c + Vector2::new(a.cos(), a.sin()) * r.max(0.0)))
            });
            rim && self.free_point(&c)
                && self.obstacles.iter().all(|o| {
                    let dx = (o.min_m[0] - c.x).max(c.x - o.max_m[0]).max(0.0);
                    let dy = (o.min_m[1] - c.y).max(c.y - o.max_m[1]).max(0.0);
                    dx.hypot(dy) >= r
                })
        };
        let n = cells[0] * cells[1];
        let free: Vec<bool> = (0..n).map(free_cell).collect();
        let mut reach = Reach {
            first,
            cells,
            metres: vec![f64::INFINITY; n],
        };
        let Some(k0) = reach.cell(&self.middle(goal)) else {
            return reach;
        };
        let metres = &mut reach.metres;
        metres[k0] = 0.0;
        let mut open = BTreeSet::new();
        open.insert((0.0f64.to_bits(), k0));
        while let Some((d, k)) = open.pop_first() {
            let d = f64::from_bits(d);
            if d > metres[k] {
                continue;
            }
            let (i, j) = ((k % cells[0]) as i64, (k / cells[0]) as i64);
            for (di, dj) in [
                (1, 0),
                (-1, 0),
                (0, 1),
                (0, -1),
                (1, 1),
                (1, -1),
                (-1, 1),
                (-1, -1),
            ] {
                let (a, b) = (i + di, j + dj);
                if a < 0 || b < 0 || a >= cells[0] as i64 || b >= cells[1] as i64 {
                    continue;
                }
                let m = b as usize * cells[0] + a as usize;
                let step = if di != 0 && dj != 0 {
                    std::f64::consts::SQRT_2
                } else {
                    1.0
                };
                let e = d + step * REACH_CELL_M;
                if free[m] && e < metres[m] {
                    metres[m] = e;
                    open.insert((e.to_bits(), m));
                }
            }
        }
        reach
    }

    /// True when the floor the way over it reaches from the path's start
    /// holds the body's middle all along `points` (rear axle places, each
    /// stretch driven heading along it): a disc as wide as the body
    /// keeps off the walls and what stands on the floor there. What
    /// sweeps past that at a corner turned on the move is not checked.
    pub(crate) fn path_open(&self, points: &[[f64; 2]]) -> bool {
        let heading = |a: [f64; 2], b: [f64; 2]| (b[1] - a[1]).atan2(b[0] - a[0]);
        let (Some(&a), Some(&b)) = (points.first(), points.get(1)) else {
            return false;
        };
        let reach = self.reach(&Pose2::new(a[0], a[1], heading(a, b)));
        points.windows(2).all(|w| {
            let (a, b) = (Vector2::from(w[0]), Vector2::from(w[1]));
            let h = heading(w[0], w[1]);
            let n = ((b - a).norm() / REACH_CELL_M).ceil().max(1.0) as usize;
            (0..=n).all(|k| {
                let p = a + (b - a) * (k as f64 / n as f64);
                reach.at(&self.middle(&Pose2::new(p.x, p.y, h))).is_finite()
            })
        })
    }

    /// True when the body (with its field's sides) at `p` heading `theta`
    /// is inside the room or its doorways and off every obstacle.
    fn body_clear(&self, p: &Vector2<f64>, theta: f64) -> bool {
        let r = Rotation2::new(theta);
        let (back, ahead, half) = (-self.rear_m, self.front_m, self.half_width_m);
        let corners = [
            Vector2::new(back, -half),
            Vector2::new(ahead, -half),
            Vector2::new(ahead, half),
            Vector2::new(back, half),
        ]
        .map(|c| p + r * c);
        let [xs, ys] = self.room_m;
        let inside = match &self.outline {
            Some(o) => o.holds(&corners.map(Into::into), 0.0),
            None => corners
                .iter()
                .all(|c| (0.0..=xs).contains(&c.x) && (0.0..=ys).contains(&c.y)),
        };
        // Inside the room, the corners tell (a room of another shape: and
        // no wall reaching into the body); reaching into a doorway, the
        // outline is walked.
        let walls_clear = inside
            || (!self.doorways.is_empty()
                && (0..4).all(|i| {
                    let (a, b) = (corners[i], corners[(i + 1) % 4]);
                    let n = ((b - a).norm() / RUN_STEP_M).ceil().max(1.0) as usize;
                    (0..n).all(|k| self.free_point(&(a + (b - a) * (k as f64 / n as f64))))
                }));
        walls_clear && {
            // The heading's unit vector: the rotation's first column.
            let f = r.matrix().column(0).into_owned();
            let c = p + f * (0.5 * (ahead + back));
            rect_clear(
                self.obstacles,
                &c,
                &f,
                [0.5 * (ahead - back), half],
                OBSTACLE_MARGIN_M,
            )
        }
    }

    /// True when a turn on the spot at `p` from `from` to `to` (the short
    /// way round) and the field past its end keep the body clear. A turn
    /// of nearly half round must be clear both ways round: which way the
    /// robot takes it hangs on a hair of its heading then.
    fn turn_clear(&self, p: &Vector2<f64>, from: f64, to: f64) -> bool {
        let delta = wrap_angle(to - from);
        let sweep = |delta: f64| {
            let reach = delta.abs() + self.turn_field_rad;
            let n = (reach / TURN_STEP_RAD).ceil().max(1.0) as usize;
            (0..=n).all(|k| self.body_clear(p, from + delta.signum() * reach * k as f64 / n as f64))
        };
        sweep(delta)
            && (delta.abs() <= MAX_TURN_RAD || sweep(delta - std::f64::consts::TAU.copysign(delta)))
    }

    /// True when a straight run heading `theta` from `a` to `b` (forward
    /// when `b` lies ahead) and the field past its end keep the body
    /// clear.
    fn run_clear(&self, a: &Vector2<f64>, b: &Vector2<f64>, theta: f64) -> bool {
        let d = b - a;
        let Some(dir) = d.try_normalize(1e-9) else {
            return self.body_clear(a, theta);
        };
        let end = b + dir * self.run_field_m;
        let n = ((end - a).norm() / RUN_STEP_M).ceil().max(1.0) as usize;
        (0..=n).all(|k| self.body_clear(&(a + (end - a) * (k as f64 / n as f64)), theta))
    }

    /// True when the body (with its field's sides) standing at `pose` is
    /// clear.
    pub fn pose_clear(&self, pose: &Pose2) -> bool {
        self.body_clear(&pose.position().coords, pose.theta)
    }

    /// True when every move from `from` keeps the body clear.
    pub fn moves_clear(&self, from: &Pose2, moves: &[Move]) -> bool {
        let (mut p, mut theta) = (from.position().coords, from.theta);
        for m in moves {
            match *m {
                Move::Turn(h) => {
                    if !self.turn_clear(&p, theta, h) {
                        return false;
                    }
                    theta = h;
                }
                Move::Run { to, .. } => {
                    let q = to.position().coords;
                    if !self.run_clear(&p, &q, theta) {
                        return false;
                    }
                    p = q;
                }
            }
        }
        true
    }

    /// The moves of a turn toward (or away from, `forward` false) the
    /// goal, a run to it, and a turn to its heading.
    fn direct(from: &Pose2, goal: &Pose2, forward: bool) -> Vec<Move> {
        let d = goal.position() - from.position();
        let mut out = Vec::new();
        let mut theta = from.theta;
        if d.norm() > AT_GOAL_M {
            let face = d.y.atan2(d.x) + if forward { 0.0 } else { std::f64::consts::PI };
            let face = wrap_angle(face);
            if wrap_angle(face - theta).abs() > AT_GOAL_RAD {
                out.push(Move::Turn(face));
            }
            theta = face;
            out.push(Move::Run {
                to: Pose2::new(goal.x, goal.y, face),
                forward,
            });
        }
        if wrap_angle(goal.theta - theta).abs() > AT_GOAL_RAD {
            out.push(Move::Turn(goal.theta));
        }
        out
    }

    /// The time the behaviours `way` (turns on the spot, runs forward or
    /// backing) take from `from` when every move keeps the body clear, s;
    /// `None` when one does not, or `way` holds another behaviour.
    pub fn way_cost(&self, from: &Pose2, way: &[Behaviour]) -> Option<f64> {
        let moves: Option<Vec<Move>> = way
            .iter()
            .map(|b| match *b.kind() {
                BehaviourKind::Pivot { heading_rad, .. } => Some(Move::Turn(heading_rad)),
                BehaviourKind::Regulate { goal } => Some(Move::Run {
                    to: goal,
                    forward: true,
                }),
                BehaviourKind::Reverse { goal } => Some(Move::Run {
                    to: goal,
                    forward: false,
                }),
                _ => None,
            })
            .collect();
        let moves = moves?;
        // A run is driven along the line through its goal (the line law):
        // started off that line, or turned from it, the robot swings its
        // body across to the line, which a straight run does not sweep
        // (a station 30 cm beside the last at the end of a corridor: its
        // front swung onto the far wall). Such a way is no straight run.
        let (mut p, mut theta) = (from.position(), from.theta);
        for m in &moves {
            match *m {
                Move::Turn(h) => theta = h,
                Move::Run { to, .. } => {
                    let normal = Vector2::new(-to.theta.sin(), to.theta.cos());
                    if wrap_angle(theta - to.theta).abs() > RUN_OFF_LINE_RAD
                        || normal.dot(&(p - to.position())).abs() > RUN_OFF_LINE_M
                    {
                        return None;
                    }
                    (p, theta) = (to.position(), to.theta);
                }
            }
        }
        self.moves_clear(from, &moves)
            .then(|| self.cost(from, &moves))
    }

    /// The time the plain way — turn to face the goal, drive to it, turn
    /// to its heading — takes when it keeps the body clear, s.
    #[cfg(test)]
    fn direct_cost(&self, from: &Pose2, goal: &Pose2) -> Option<f64> {
        let moves = Self::direct(from, goal, true);
        self.moves_clear(from, &moves)
            .then(|| self.cost(from, &moves))
    }

    fn cost(&self, from: &Pose2, moves: &[Move]) -> f64 {
        let mut theta = from.theta;
        let mut p = from.position().coords;
        moves
            .iter()
            .map(|m| match *m {
                Move::Turn(h) => {
                    let c = self.turn_overhead_s + wrap_angle(h - theta).abs() / self.turn_radps;
                    theta = h;
                    c
                }
                Move::Run { to, .. } => {
                    let q = to.position().coords;
                    let c = RUN_OVERHEAD_S + (q - p).norm() / self.speed_mps;
                    p = q;
                    c
                }
            })
            .sum()
    }

    /// The quickest way found from `from` to `goal` in partial turns and
    /// straight runs, every pose along it clear, and the time it takes,
    /// s; `None` when the search finds none within its budget (or `from`
    /// itself is not clear).
    pub fn manoeuvre(&self, from: &Pose2, goal: &Pose2) -> Option<(f64, Vec<Move>)> {
        if !self.body_clear(&from.position().coords, from.theta)
            || !self.body_clear(&goal.position().coords, goal.theta)
        {
            return None;
        }
        self.search(from, goal)
            .or_else(|| self.turn_run_turn(from, goal))
    }

    /// A way in three parts, for where the search finds none within its
    /// budget (a long corridor too narrow to turn in, with a turn needed
    /// at either end: the search, drawn on by the goal, spends itself
    /// along the run): turned where it stands to face along the run (or
    /// away from it, to back down it), the straight run, and turned at
    /// the goal onto its heading; each turn a search of its own about its
    /// place. The quicker of forward and backing.
    fn turn_run_turn(&self, from: &Pose2, goal: &Pose2) -> Option<(f64, Vec<Move>)> {
        let d = goal.position() - from.position();
        if d.norm() <= AT_GOAL_M {
            return None;
        }
        let turned = |a: &Pose2, b: &Pose2| {
            if wrap_angle(b.theta - a.theta).abs() <= AT_GOAL_RAD {
                Some(Vec::new())
            } else {
                self.search(a, b).map(|(_, m)| m)
            }
        };
        [true, false]
            .into_iter()
            .filter_map(|forward| {
                let back = if forward { 0.0 } else { std::f64::consts::PI };
                let face = wrap_angle(d.y.atan2(d.x) + back);
                let (a, b) = (
                    Pose2::new(from.x, from.y, face),
                    Pose2::new(goal.x, goal.y, face),
                );
                if !self.body_clear(&a.position().coords, face)
                    || !self.run_clear(&a.position().coords, &b.position().coords, face)
                {
                    return None;
                }
                let mut moves = turned(from, &a)?;
                moves.push(Move::Run { to: b, forward });
                moves.extend(turned(&b, goal)?);
                let moves = merged(from.theta, moves);
                Some((self.cost(from, &moves), moves))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0))
    }

    /// The A* search of [`Space::manoeuvre`], its ends known clear.
    fn search(&self, from: &Pose2, goal: &Pose2) -> Option<(f64, Vec<Move>)> {
        // The time of the run and the turn still needed, inflated: the
        // search is greedier and its way at most that much dearer than
        // the best.
        // Past the first expansions, the way over the floor stands in for
        // the crow's flight where it is longer (round furniture, through
        // a door), and a goal it does not reach is given up at once. The
        // body's middle moves at most as fast as a run drives it, and
        // half as fast as a turn on the spot swings it.
        let mut reach: Option<Reach> = None;
        let heuristic = |p: &Pose2, reach: &Option<Reach>| {
            let turn = wrap_angle(goal.theta - p.theta).abs();
            let overhead = if turn > AT_GOAL_RAD {
                self.turn_overhead_s
            } else {
                0.0
            };
            let crow = (goal.position() - p.position()).norm();
            let floor = reach.as_ref().map_or(0.0, |r| r.at(&self.middle(p)));
            GREED * (crow.max(floor) / self.speed_mps + turn / self.turn_radps + overhead)
        };
        let key = |p: &Pose2, turned: bool| {
            (
                (p.x / CELL_M).round() as i64,
                (p.y / CELL_M).round() as i64,
                (wrap_angle(p.theta) / CELL_RAD).round() as i64,
                turned,
            )
        };
        // Nodes: pose, cost so far, the node before and the move from it,
        // whether the move was a turn (a turn follows a run; a run either).
        struct Node {
            pose: Pose2,
            cost: f64,
            parent: Option<(usize, Move)>,
            turned: Option<bool>,
        }
        let mut nodes = vec![Node {
            pose: *from,
            cost: 0.0,
            parent: None,
            turned: None,
        }];
        let mut best: BTreeMap<(i64, i64, i64, bool), f64> = BTreeMap::new();
        let mut open = BTreeSet::new();
        open.insert((heuristic(from, &reach).to_bits(), 0usize));
        let mut found: Option<(f64, usize, Vec<Move>)> = None;
        let mut expanded = 0;
        while let Some((f, k)) = open.pop_first() {
            if found
                .as_ref()
                .is_some_and(|(c, ..)| f64::from_bits(f) >= *c)
            {
                break;
            }
            expanded += 1;
            if expanded > BUDGET {
                break;
            }
            if expanded == CROW_EXPANSIONS && found.is_none() {
                let r = self.reach(goal);
                if !r.at(&self.middle(from)).is_finite() {
                    return None;
                }
                reach = Some(r);
                open.insert((f, k));
                open = std::mem::take(&mut open)
                    .into_iter()
                    .map(|(_, k)| {
                        let n = &nodes[k];
                        ((n.cost + heuristic(&n.pose, &reach)).to_bits(), k)
                    })
                    .collect();
                continue;
            }
            let (pose, cost, turned) = (nodes[k].pose, nodes[k].cost, nodes[k].turned);
            // The last moves straight onto the goal, forward or backing.
            for forward in [true, false] {
                let shot = Self::direct(&pose, goal, forward);
                let total = cost + self.cost(&pose, &shot);
                if found.as_ref().is_none_or(|(c, ..)| total < *c) && self.moves_clear(&pose, &shot)
                {
                    found = Some((total, k, shot));
                }
            }
            let p = pose.position().coords;
            let mut next = Vec::new();
            if turned != Some(true) {
                for deg in TURNS_DEG {
                    for sign in [1.0, -1.0] {
                        let h = wrap_angle(pose.theta + sign * deg.to_radians());
                        if self.turn_clear(&p, pose.theta, h) {
                            next.push((Move::Turn(h), Pose2::new(p.x, p.y, h), true));
                        }
                    }
                }
            }
            // Runs after a turn; after a run, the longest (a corridor
            // longer than it is driven straight down in one run, not
            // zigzagged in turns of 5°).
            let runs = if turned == Some(false) {
                &RUNS_M[RUNS_M.len() - 1..]
            } else {
                &RUNS_M[..]
            };
            let f = Vector2::new(pose.theta.cos(), pose.theta.sin());
            for forward in [true, false] {
                let sign = if forward { 1.0 } else { -1.0 };
                for run in runs {
                    let q = p + f * (sign * run);
                    if !self.run_clear(&p, &q, pose.theta) {
                        break;
                    }
                    let to = Pose2::new(q.x, q.y, pose.theta);
                    next.push((Move::Run { to, forward }, to, false));
                }
            }
            for (m, to, is_turn) in next {
                let mut c = cost + self.cost(&pose, &[m]);
                if let (
                    Some((
                        _,
                        Move::Run {
                            forward: before, ..
                        },
                    )),
                    Move::Run { forward, .. },
                ) = (nodes[k].parent, m)
                    && before == forward
                {
                    // Not a stop and a start: the run before goes on.
                    c -= RUN_OVERHEAD_S;
                }
                let kk = key(&to, is_turn);
                if best.get(&kk).is_some_and(|b| *b <= c) {
                    continue;
                }
                best.insert(kk, c);
                nodes.push(Node {
                    pose: to,
                    cost: c,
                    parent: Some((k, m)),
                    turned: Some(is_turn),
                });
                open.insert(((c + heuristic(&to, &reach)).to_bits(), nodes.len() - 1));
            }
        }
        let (cost, mut k, shot) = found?;
        let mut moves = Vec::new();
        while let Some((parent, m)) = nodes[k].parent {
            moves.push(m);
            k = parent;
        }
        moves.reverse();
        moves.extend(shot);
        Some((cost, merged(from.theta, moves)))
    }
}

/// The behaviours that drive `moves` at `speed_mps`.
pub(crate) fn behaviours(gains: &GainSchedule, moves: &[Move], speed_mps: f64) -> Vec<Behaviour> {
    moves
        .iter()
        .map(|m| match *m {
            Move::Turn(h) => Behaviour::pivot(h),
            Move::Run { to, forward: true } => Behaviour::regulate(gains, to, speed_mps),
            Move::Run { to, forward: false } => Behaviour::reverse_to(gains, to, speed_mps),
        })
        .collect()
}

/// Moves one after the other of a kind made one: two runs the same way,
/// two turns the same way round (within the largest turn), for a robot
/// heading `theta` before them.
fn merged(mut theta: f64, moves: Vec<Move>) -> Vec<Move> {
    let mut out: Vec<Move> = Vec::with_capacity(moves.len());
    // The heading before the last move kept.
    let mut before = theta;
    for m in moves {
        match (out.last_mut(), m) {
            (Some(Move::Run { to, forward }), Move::Run { to: t, forward: f })
                if *forward == f && wrap_angle(to.theta - t.theta).abs() < 1e-9 =>
            {
                *to = t;
                continue;
            }
            (Some(Move::Turn(h)), Move::Turn(next)) => {
                // Each turn is driven the short way round: the two may be
                // made one only if the short way round of the whole is the
                // way both went (their sum, not its wrap, within the
                // largest sure turn).
                let (first, second) = (wrap_angle(*h - before), wrap_angle(next - *h));
                if first * second >= 0.0 && (first + second).abs() <= MAX_TURN_RAD {
                    *h = next;
                    theta = next;
                    continue;
                }
            }
            _ => {}
        }
        before = theta;
        if let Move::Turn(h) = m {
            theta = h;
        }
        out.push(m);
    }
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::task::WallName;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn demo_safety() -> SafetyConfig {
        SafetyConfig {
            obstacle_margin_m: 0.05,
            lateral_margin_m: 0.05,
            ..SafetyConfig::default()
        }
    }

    /// Every pose of the way, sampled finely, with the body inside the
    /// room or a doorway: what a test checks a manoeuvre by.
    fn assert_way_clear(space: &Space, from: &Pose2, moves: &[Move], goal: &Pose2) {
        assert!(space.moves_clear(from, moves), "{moves:?}");
        let (mut p, mut theta) = (from.position().coords, from.theta);
        for m in moves {
            match *m {
                Move::Turn(h) => theta = h,
                Move::Run { to, forward } => {
                    let ahead =
                        Vector2::new(theta.cos(), theta.sin()).dot(&(to.position().coords - p));
                    assert_eq!(ahead > 0.0, forward, "a run's direction");
                    // (A turn smaller than the goal's tolerance is not
                    // made.)
                    assert!(
                        wrap_angle(to.theta - theta).abs() <= AT_GOAL_RAD,
                        "a run keeps its heading"
                    );
                    p = to.position().coords;
                }
            }
        }
        assert!((p - goal.position().coords).norm() <= AT_GOAL_M);
        assert!(wrap_angle(theta - goal.theta).abs() <= AT_GOAL_RAD);
    }

    #[test]
    fn a_long_corridor_is_driven_with_a_turn_at_either_end() {
        // A generated building's corridor, 20.8 × 1.625 m: the robot cannot
        // turn on the spot in it (its front corners sweep 1.66 m across
        // with the field's margins). Turned round where it stands, driven
        // to the far end and turned there, or stood across the corridor
        // and taken to the far end to stand across it again (the search
        // alone, drawn on by the goal, spent its budget along the run).
        let v = VehicleSpec::default();
        let space = Space::new(
            [20.8, 1.625],
            &[],
            &[],
            &[],
            &v,
            &SafetyConfig::default(),
            0.3,
        );
        for (from, goal) in [
            (Pose2::new(19.0, 0.8, 0.0), Pose2::new(19.0, 0.8, PI)),
            (Pose2::new(19.0, 0.8, 0.0), Pose2::new(2.0, 0.8, PI)),
            (Pose2::new(19.0, 0.8, 0.0), Pose2::new(2.0, 0.8, 0.0)),
            (
                Pose2::new(20.06, 0.76, 1.77),
                Pose2::new(1.2, 0.85, -FRAC_PI_2),
            ),
        ] {
            let t = std::time::Instant::now();
            let found = space.manoeuvre(&from, &goal);
            eprintln!(
                "{from:?} -> {goal:?}: {:?} in {:?}",
                found.as_ref().map(|f| (f.0, f.1.len())),
                t.elapsed()
            );
            let (_, moves) = found.expect("a way");
            assert_way_clear(&space, &from, &moves, &goal);
        }
    }

    #[test]
    fn a_corridor_longer_than_the_longest_run_is_driven_straight_down() {
        // Generated building 12's corridor, 15.46 × 1.2 m: the robot has
        // plastered its east end and faces it. The way on is through a
        // door in the north wall near the west end, from just inside it
        // facing out. Nowhere in the corridor can the robot turn round: it
        // backs straight down it and turns into the door there. Runs
        // could not follow runs, and the search zigzagged down the
        // corridor in 3.2 m runs and turns of 5°, its body swung within
        // centimetres of the walls at every turn.
        let v = VehicleSpec::default();
        let door = |wall, position_m, width_m| DoorEstimate {
            wall,
            position_m,
            width_m: Some(width_m),
            sigma_m: 0.002,
            plan_door: None,
        };
        let doors = [
            door(WallName::NORTH, 2.457, 0.974),
            door(WallName::SOUTH, 10.815, 0.738),
            door(WallName::NORTH, 7.491, 0.797),
        ];
        let space = Space::new(
            [15.46, 1.203],
            &[],
            &doors,
            &[],
            &v,
            &SafetyConfig::default(),
            0.3,
        );
        let from = Pose2::new(13.54, 0.508, 0.0);
        let goal = Pose2::new(2.457, 0.353, FRAC_PI_2);
        let (_, moves) = space.manoeuvre(&from, &goal).expect("a way to the door");
        assert_way_clear(&space, &from, &moves, &goal);
        // Every run of more than a metre is along the corridor.
        let mut at = from;
        for m in &moves {
            if let Move::Run { to, .. } = *m {
                if (to.position() - at.position()).norm() > 1.0 {
                    assert!(to.theta.sin().abs() < 1e-6, "{moves:?}");
                }
                at = to;
            }
        }
    }

    #[test]
    fn a_hall_too_narrow_to_turn_in_is_turned_in_several_moves() {
        // The apartment's hall: 8 × 1.2 m, doors in its south wall at 3.55
        // and 6.6 m, in its north wall at 3.4 m. The robot has come in
        // through the south door heading north, its axle 0.25 m in.
        let v = VehicleSpec::default();
        let doors = [
            DoorEstimate {
                wall: WallName::SOUTH,
                position_m: 3.55,
                width_m: Some(0.9),
                sigma_m: 0.01,
                plan_door: None,
            },
            DoorEstimate {
                wall: WallName::SOUTH,
                position_m: 6.6,
                width_m: Some(0.8),
                sigma_m: 0.01,
                plan_door: None,
            },
        ];
        let space = Space::new([8.0, 1.2], &[], &doors, &[], &v, &demo_safety(), 0.3);
        let from = Pose2::new(3.55, 0.25, std::f64::consts::FRAC_PI_2);
        // A turn on the spot there would put the front through the north
        // wall.
        let east = Pose2::new(5.0, 0.6, 0.0);
        assert!(space.direct_cost(&from, &east).is_none());
        // Before the other south door, facing it, axle 0.9 m from it.
        let goal = Pose2::new(6.6, 0.9, -std::f64::consts::FRAC_PI_2);
        let moves = space
            .manoeuvre(&from, &goal)
            .expect("a way through the hall")
            .1;
        assert_way_clear(&space, &from, &moves, &goal);
        let turns = moves.iter().filter(|m| matches!(m, Move::Turn(_))).count();
        assert!(turns >= 3, "{moves:?}");
        println!("{} moves: {moves:?}", moves.len());
    }

    #[test]
    fn turns_are_made_one_only_when_the_short_way_round_is_theirs() {
        let deg = f64::to_radians;
        // 45° then 150° anticlockwise: 195° in all, which the pivot would
        // take 165° clockwise. Kept apart.
        let apart = merged(0.0, vec![Move::Turn(deg(45.0)), Move::Turn(deg(195.0))]);
        assert_eq!(apart.len(), 2, "{apart:?}");
        // 30° then 60° anticlockwise: one turn of 90°.
        let one = merged(0.0, vec![Move::Turn(deg(30.0)), Move::Turn(deg(90.0))]);
        assert_eq!(one, vec![Move::Turn(deg(90.0))]);
        // Back and forth: kept apart.
        let back = merged(0.0, vec![Move::Turn(deg(30.0)), Move::Turn(deg(10.0))]);
        assert_eq!(back.len(), 2, "{back:?}");
    }

    #[test]
    fn a_room_wide_enough_gets_the_plain_way() {
        let v = VehicleSpec::default();
        let space = Space::new([5.0, 4.0], &[], &[], &[], &v, &demo_safety(), 0.3);
        let from = Pose2::new(2.0, 2.0, 0.0);
        let goal = Pose2::new(3.0, 2.0, 1.0);
        assert!(space.direct_cost(&from, &goal).is_some());
        let moves = space.manoeuvre(&from, &goal).unwrap().1;
        assert_eq!(moves, Space::direct(&from, &goal, true));
    }

    #[test]
    fn no_way_out_of_a_box_the_body_does_not_fit() {
        let v = VehicleSpec::default();
        // 1.0 m wide: the body with its field's sides fits heading along
        // it, but no heading across it fits.
        let space = Space::new([6.0, 1.0], &[], &[], &[], &v, &demo_safety(), 0.3);
        let from = Pose2::new(2.0, 0.5, 0.0);
        let back = Pose2::new(4.0, 0.5, std::f64::consts::PI);
        assert!(space.manoeuvre(&from, &back).is_none());
        // Along it, it goes.
        let on = Pose2::new(4.0, 0.5, 0.0);
        assert!(space.manoeuvre(&from, &on).is_some());
    }

    #[test]
    fn a_chair_beyond_a_doorway_is_kept_off() {
        // The bedroom: the robot has come in heading north through the
        // door at 3.4 m, a chair 0.8 m ahead and to its left.
        let v = VehicleSpec::default();
        let doors = [DoorEstimate {
            wall: WallName::SOUTH,
            position_m: 3.4,
            width_m: Some(0.8),
            sigma_m: 0.01,
            plan_door: None,
        }];
        let chair = [Obstacle {
            min_m: [2.29, 1.04],
            max_m: [2.71, 1.46],
            height_m: 0.45,
        }];
        let space = Space::new([4.0, 3.65], &[], &doors, &chair, &v, &demo_safety(), 0.3);
        let from = Pose2::new(3.4, 0.2, std::f64::consts::FRAC_PI_2);
        // Back out through the door: facing it from 0.8 m in.
        let goal = Pose2::new(3.4, 0.8, -std::f64::consts::FRAC_PI_2);
        let moves = space.manoeuvre(&from, &goal).expect("a way round").1;
        assert_way_clear(&space, &from, &moves, &goal);
    }

    /// The way over the floor for the body's middle: round a box, longer
    /// than the crow's flight; through a wall of boxes from side to side,
    /// none, and the search gives up on the goal beyond it.
    #[test]
    fn the_way_over_the_floor_goes_round_what_stands_and_none_crosses_a_barrier() {
        let v = VehicleSpec::default();
        let (from, goal) = (Pose2::new(1.0, 2.0, 0.0), Pose2::new(5.0, 2.0, 0.0));
        let box_ = [Obstacle {
            min_m: [2.8, 1.0],
            max_m: [3.4, 3.0],
            height_m: 1.0,
        }];
        let space = Space::new([8.0, 4.0], &[], &[], &box_, &v, &demo_safety(), 0.3);
        let reach = space.reach(&goal);
        let (at, crow) = (
            reach.at(&space.middle(&from)),
            (space.middle(&goal) - space.middle(&from)).norm(),
        );
        assert!(
            at.is_finite() && at > crow + 0.5,
            "{at} m, {crow} m as the crow flies"
        );
        let moves = space.manoeuvre(&from, &goal).expect("a way round").1;
        assert_way_clear(&space, &from, &moves, &goal);
        // The box from wall to wall: no way for the body's middle, and
        // none for the body.
        let barrier = [Obstacle {
            min_m: [2.8, 0.0],
            max_m: [3.4, 4.0],
            height_m: 1.0,
        }];
        let space = Space::new([8.0, 4.0], &[], &[], &barrier, &v, &demo_safety(), 0.3);
        assert!(!space.reach(&goal).at(&space.middle(&from)).is_finite());
        assert_eq!(space.manoeuvre(&from, &goal), None);
    }
}
