//! The room-and-door map (paper 002, the room graph): rooms as nodes, the
//! doors between them as edges, built as the robot drives through a floor
//! on the map of walls ([`crate::WallMap`]).
//!
//! A room is the rectangle of building walls around the robot, measured in
//! the floor's own frame (the walls' dominant direction): on each side the
//! nearest wall that faces the robot and reaches past it (across a door's
//! width). The robot has left its room when it stands beyond one of the
//! room's sides; the room change is verified by the pose relative to the
//! room it comes into — a rectangle of its own, holding the robot, unlike
//! the one it left — and that room is one already known when its sides
//! agree with a known room's in the metric map (a loop, or two look-alike
//! rooms told apart by where they are), or a new node. The crossing is the
//! door: which side of the room, left, middle or right along it, and the
//! heading it was passed in.
//!
//! A hall too narrow to stand `enter_m` inside it on both sides (crossed
//! from one door to the door facing it) is measured within 40 % of its
//! width. No side is taken beyond the back of a wall the robot stands
//! behind: just through a door, before the near face of the next room's
//! wall is mapped, the rooms on both sides of the wall would make one
//! rectangle.

use nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{Pose2, wrap_angle};

use crate::error::NavError;
use crate::wall_map::{MapWall, WallRole, building};

/// Share of a narrow room's width the robot must stand inside it for the
/// room to be measured.
const NARROW_ENTER: f64 = 0.4;

/// Settings of the room graph.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoomGraphConfig {
    /// Shortest wall that bounds a room, m (furniture faces are shorter);
    /// the pieces on either side of a door count together.
    pub min_wall_m: f64,
    /// Widest door, m: a room's side may be two pieces of one line this
    /// far apart, the robot between them, less what the faces standing
    /// before the line cover of the gap (a sofa hides the wall behind it).
    pub max_door_m: f64,
    /// Pieces of wall whose lines pass this close to each other where the
    /// robot stands are one line, m.
    pub same_line_m: f64,
    /// A wall faces a side of the room within this angle, rad.
    pub parallel_rad: f64,
    /// A wall reaches past the robot when its seen stretch, widened by
    /// this on each end, covers the robot's projection (a door's width and
    /// its jambs), m.
    pub door_slack_m: f64,
    /// How far beyond a side of its room the robot must stand to have left
    /// it, m.
    pub leave_m: f64,
    /// How far inside the room it comes into the robot must stand for
    /// that room to be measured, m; in a room narrower than `enter_m / 0.4`
    /// (a hall crossed from door to door), 40 % of its width.
    pub enter_m: f64,
    /// Two rooms whose sides agree within this are one, m: less than a
    /// wall's thickness, so the rooms on either side of a wall differ.
    pub same_room_m: f64,
    /// A passage within this of a known door between the same rooms is
    /// that door, m.
    pub same_door_m: f64,
    /// Measurements of a room's sides kept for their median.
    pub keep: usize,
    /// The robot is in the room that holds the point this far ahead of
    /// its pose, m: the middle of its body when the pose is its rear
    /// axle's, a long way back when it noses into a room.
    pub body_middle_ahead_m: f64,
}

impl Default for RoomGraphConfig {
    fn default() -> Self {
        RoomGraphConfig {
            min_wall_m: 1.1,
            max_door_m: 1.4,
            same_line_m: 0.05,
            parallel_rad: 5f64.to_radians(),
            door_slack_m: 0.2,
            leave_m: 0.3,
            enter_m: 0.6,
            same_room_m: 0.1,
            same_door_m: 1.0,
            keep: 64,
            body_middle_ahead_m: 0.0,
        }
    }
}

/// A side of a room in the floor's frame; also the heading class of a
/// passage (the side it goes out through).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoomSide {
    /// −y.
    South,
    /// +x.
    East,
    /// +y.
    North,
    /// −x.
    West,
}

impl RoomSide {
    /// All four, in the order of [`Room::bounds`] (`[x0, x1, y0, y1]`:
    /// west, east, south, north).
    pub const ALL: [RoomSide; 4] = [
        RoomSide::West,
        RoomSide::East,
        RoomSide::South,
        RoomSide::North,
    ];

    /// Its index in `[x0, x1, y0, y1]`.
    fn index(self) -> usize {
        match self {
            RoomSide::West => 0,
            RoomSide::East => 1,
            RoomSide::South => 2,
            RoomSide::North => 3,
        }
    }

    /// Unit vector out of the room through this side, in the floor's frame.
    fn out(self) -> Vector2<f64> {
        match self {
            RoomSide::West => Vector2::new(-1.0, 0.0),
            RoomSide::East => Vector2::new(1.0, 0.0),
            RoomSide::South => Vector2::new(0.0, -1.0),
            RoomSide::North => Vector2::new(0.0, 1.0),
        }
    }
}

/// Where along a wall a door is, looking at the wall from inside the room.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DoorPlace {
    /// The left third.
    Left,
    /// The middle third.
    Middle,
    /// The right third.
    Right,
}

/// A room of the graph.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Room {
    /// Its index in the graph.
    pub id: usize,
    /// Its name (`room-N` until named).
    pub name: String,
    /// `[x0, x1, y0, y1]` in the floor's frame, m: the medians of its
    /// sides as measured.
    pub bounds: [f64; 4],
    /// Times the robot has come into it.
    pub visits: u32,
    #[serde(skip)]
    sides: [Vec<f64>; 4],
}

impl Room {
    /// Width (x) and depth (y), m.
    pub fn size_m(&self) -> [f64; 2] {
        [
            self.bounds[1] - self.bounds[0],
            self.bounds[3] - self.bounds[2],
        ]
    }

    /// Whether `q` (floor frame) lies inside, `margin` in from its sides.
    fn holds(&self, q: &Point2<f64>, margin: f64) -> bool {
        q.x > self.bounds[0] + margin
            && q.x < self.bounds[1] - margin
            && q.y > self.bounds[2] + margin
            && q.y < self.bounds[3] - margin
    }

    fn measure(&mut self, rect: [f64; 4], keep: usize) {
        for (k, v) in rect.into_iter().enumerate() {
            let s = &mut self.sides[k];
            if s.len() >= keep.max(1) {
                s.remove(0);
            }
            s.push(v);
            let mut sorted = s.clone();
            sorted.sort_by(f64::total_cmp);
            self.bounds[k] = sorted[sorted.len() / 2];
        }
    }
}

/// A door of the graph: an edge between two rooms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Door {
    /// Its index in the graph.
    pub id: usize,
    /// The rooms it joins; the first is the one it was first passed from.
    pub rooms: [usize; 2],
    /// Where it was crossed, in the map's frame, m (mean of passages).
    pub at: Point2<f64>,
    /// The side of `rooms[0]` it is in.
    pub wall: RoomSide,
    /// Where along that side, seen from inside `rooms[0]`.
    pub place: DoorPlace,
    /// The heading class of its first passage (the side of `rooms[0]` it
    /// was passed out through).
    pub heading: RoomSide,
    /// Times passed.
    pub passages: u32,
}

/// What an update did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum RoomEvent {
    /// The first room, where the robot started.
    Started {
        /// The room.
        room: usize,
    },
    /// The robot went through `door` into `room`.
    Entered {
        /// The room.
        room: usize,
        /// The door.
        door: usize,
        /// Whether the room is new to the graph.
        new_room: bool,
        /// Whether the door is new to the graph.
        new_door: bool,
    },
}

/// A way between two rooms through doors.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Route {
    /// The rooms, from the first to the last.
    pub rooms: Vec<usize>,
    /// The doors passed, in order.
    pub doors: Vec<usize>,
    /// Length from the first room's centre through each door's point to
    /// the last room's centre, m.
    pub length_m: f64,
}

/// The room graph of a floor.
#[derive(Clone, Debug, Serialize)]
pub struct RoomGraph {
    config: RoomGraphConfig,
    /// Orientation of the floor's frame in the map's, rad.
    frame_rad: Option<f64>,
    rooms: Vec<Room>,
    doors: Vec<Door>,
    current: Option<usize>,
    /// Where the robot left its room and through which side, while the
    /// room it went into is not yet measured.
    leaving: Option<(usize, Point2<f64>, RoomSide)>,
}

impl RoomGraph {
    /// An empty graph.
    pub fn new(config: RoomGraphConfig) -> Self {
        RoomGraph {
            config,
            frame_rad: None,
            rooms: Vec::new(),
            doors: Vec::new(),
            current: None,
            leaving: None,
        }
    }

    /// The rooms.
    pub fn rooms(&self) -> &[Room] {
        &self.rooms
    }

    /// The doors.
    pub fn doors(&self) -> &[Door] {
        &self.doors
    }

    /// The room the robot is in, when it is known.
    pub fn current(&self) -> Option<usize> {
        self.current
    }

    /// Names room `id`.
    pub fn name(&mut self, id: usize, name: impl Into<String>) {
        if let Some(r) = self.rooms.get_mut(id) {
            r.name = name.into();
        }
    }

    /// The room called `name`.
    pub fn room_named(&self, name: &str) -> Option<&Room> {
        self.rooms.iter().find(|r| r.name == name)
    }

    /// `p` (map frame) in the floor's frame.
    fn to_floor(&self, p: &Point2<f64>) -> Point2<f64> {
        let (s, c) = self.frame_rad.unwrap_or(0.0).sin_cos();
        Point2::new(c * p.x + s * p.y, -s * p.x + c * p.y)
    }

    /// `q` (floor frame) in the map's frame.
    pub fn to_map(&self, q: &Point2<f64>) -> Point2<f64> {
        let (s, c) = self.frame_rad.unwrap_or(0.0).sin_cos();
        Point2::new(c * q.x - s * q.y, s * q.x + c * q.y)
    }

    /// The centre of room `id`, map frame.
    pub fn centre(&self, id: usize) -> Option<Point2<f64>> {
        let b = self.rooms.get(id)?.bounds;
        Some(self.to_map(&Point2::new(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]))))
    }

    /// The rectangle of building walls around `p` (map frame), `[x0, x1,
    /// y0, y1]` in the floor's frame; `None` while a side has no wall.
    fn rectangle(&self, walls: &[MapWall], p: &Point2<f64>) -> Option<[f64; 4]> {
        let phi = self.frame_rad?;
        let q = self.to_floor(p);
        let cfg = &self.config;
        let mut rect = [0.0; 4];
        for side in RoomSide::ALL {
            let out = side.out();
            let dir_map = Vector2::new(
                phi.cos() * out.x - phi.sin() * out.y,
                phi.sin() * out.x + phi.cos() * out.y,
            );
            // Pieces of wall on this side that face the robot, and those
            // whose back it stands behind (it came through a door in them).
            let facing = |w: &&MapWall, toward: f64| {
                toward * w.normal().dot(&dir_map) > cfg.parallel_rad.cos()
                    && toward * w.in_front(p) > 0.0
            };
            let pieces: Vec<&MapWall> = building(walls).filter(|w| facing(w, 1.0)).collect();
            let backs: Vec<&MapWall> = building(walls).filter(|w| facing(w, -1.0)).collect();
            // Faces standing before the walls (furniture marked in front
            // of one), which hide what is behind them.
            let screens: Vec<&MapWall> = walls
                .iter()
                .filter(|w| w.role != WallRole::Wall && facing(w, 1.0))
                .collect();
            let d = Self::nearest_reaching(cfg, &pieces, &screens, p)?;
            // A side beyond the back of a wall is the next room's: from
            // within a door's depth, or before the near face of the wall
            // it came through is mapped, the rooms on both sides would
            // make one rectangle.
            if Self::nearest_reaching(cfg, &backs, &[], p).is_some_and(|b| -b < d) {
                return None;
            }
            let k = side.index();
            rect[k] = match side {
                RoomSide::West => q.x - d,
                RoomSide::East => q.x + d,
                RoomSide::South => q.y - d,
                RoomSide::North => q.y + d,
            };
        }
        Some(rect)
    }

    /// Distance from `p` (along their normal, signed as
    /// [`MapWall::in_front`]) to the nearest of `pieces` (parallel walls on
    /// one side of `p`) that reaches past it: long enough with the pieces
    /// of its line, and covering `p`'s projection or a door facing it.
    /// `screens` stand before the pieces and hide the gaps they cover.
    fn nearest_reaching(
        cfg: &RoomGraphConfig,
        pieces: &[&MapWall],
        screens: &[&MapWall],
        p: &Point2<f64>,
    ) -> Option<f64> {
        let same_line = |a: &MapWall, b: &MapWall| {
            a.id != b.id && (a.in_front(p) - b.in_front(p)).abs() < cfg.same_line_m
        };
        // The gap along the line between two pieces' stretches, m.
        let gap = |a: &MapWall, b: &MapWall| {
            (a.extent_m[0] - b.extent_m[1]).max(b.extent_m[0] - a.extent_m[1])
        };
        // The longest stretch of that gap that no screen nearer `p` than
        // the line covers, m.
        let open_gap = |a: &MapWall, b: &MapWall| {
            let (lo, hi) = if a.extent_m[1] <= b.extent_m[0] {
                (a.extent_m[1], b.extent_m[0])
            } else {
                (b.extent_m[1], a.extent_m[0])
            };
            if hi <= lo || screens.is_empty() {
                return gap(a, b);
            }
            let mut cover: Vec<(f64, f64)> = screens
                .iter()
                .filter(|s| s.in_front(p) < a.in_front(p))
                .map(|s| {
                    let [u, v] = s.ends().map(|e| a.along(&e));
                    (u.min(v), u.max(v))
                })
                .filter(|&(u, v)| v > lo && u < hi)
                .collect();
            cover.sort_by(|x, y| x.0.total_cmp(&y.0));
            let (mut longest, mut from) = (0.0f64, lo);
            for (u, v) in cover {
                longest = longest.max(u - from);
                from = from.max(v);
            }
            longest.max(hi - from)
        };
        let reaches = |w: &MapWall| {
            let t = w.along(p);
            // The pieces of its line this piece is one wall with, across
            // doors.
            let partners: Vec<&&MapWall> = pieces
                .iter()
                .filter(|o| same_line(w, o) && open_gap(w, o) <= cfg.max_door_m)
                .collect();
            let long =
                w.length_m() + partners.iter().map(|o| o.length_m()).sum::<f64>() >= cfg.min_wall_m;
            let covers =
                t > w.extent_m[0] - cfg.door_slack_m && t < w.extent_m[1] + cfg.door_slack_m;
            // Or the robot faces a door in it: a piece of the line on the
            // other side of the gap.
            let door = partners.iter().any(|o| {
                let (left, right) = if w.extent_m[1] < t {
                    (w.extent_m[1], o.extent_m[0])
                } else {
                    (o.extent_m[1], w.extent_m[0])
                };
                left < t && right > t
            });
            long && (covers || door)
        };
        pieces
            .iter()
            .filter(|w| reaches(w))
            .map(|w| w.in_front(p))
            .min_by(|a, b| a.abs().total_cmp(&b.abs()))
    }

    /// The floor's orientation: the walls' dominant direction (modulo a
    /// quarter turn), weighted by their length.
    fn orientation(walls: &[MapWall]) -> Option<f64> {
        let (mut s, mut c, mut total) = (0.0, 0.0, 0.0);
        for w in building(walls) {
            let l = w.length_m();
            s += l * (4.0 * w.alpha_rad).sin();
            c += l * (4.0 * w.alpha_rad).cos();
            total += l;
        }
        (total > 0.0).then(|| wrap_angle(s.atan2(c) / 4.0))
    }

    /// Takes the robot's pose and the map's walls as they are after a scan
    /// ([`crate::WallMapEkf::walls`]: read in place, not copied).
    pub fn update(&mut self, pose: &Pose2, walls: &[MapWall]) -> Option<RoomEvent> {
        let pose = &(*pose * Pose2::new(self.config.body_middle_ahead_m, 0.0, 0.0));
        if self.current.is_none() {
            // The frame is fixed once the first room is found: rooms are
            // compared in it.
            self.frame_rad = Self::orientation(walls);
        }
        let p = pose.position();
        let q = self.to_floor(&p);
        let rect = self.rectangle(walls, &p);
        let keep = self.config.keep;
        let Some(cur) = self.current else {
            let rect = rect?;
            let id = self.add_room(rect);
            self.current = Some(id);
            return Some(RoomEvent::Started { room: id });
        };
        if let Some((from, at, side)) = self.leaving {
            let old = &self.rooms[from];
            if old.holds(&q, 0.0) {
                // Back in the room it left (it stood in the doorway).
                self.leaving = None;
                return None;
            }
            // In the doorway the walls of both rooms are in view across
            // it: measure only once clear of the side it left through.
            let b = old.bounds;
            let past = [b[0] - q.x, q.x - b[1], b[2] - q.y, q.y - b[3]][side.index()];
            if past <= self.config.leave_m {
                return None;
            }
            // Through a door: which room is this?
            let rect = rect?;
            let narrow = (rect[1] - rect[0]).min(rect[3] - rect[2]);
            let m = self.config.enter_m.min(NARROW_ENTER * narrow);
            let inside =
                q.x > rect[0] + m && q.x < rect[1] - m && q.y > rect[2] + m && q.y < rect[3] - m;
            if !inside {
                return None;
            }
            if self.agrees(old, &rect) {
                return None;
            }
            let known = (0..self.rooms.len())
                .filter(|&i| i != from && self.agrees(&self.rooms[i], &rect))
                .max_by_key(|&i| self.sides_agreeing(&self.rooms[i], &rect));
            let (room, new_room) = match known {
                Some(i) => {
                    self.rooms[i].visits += 1;
                    self.rooms[i].measure(rect, keep);
                    (i, false)
                }
                None => (self.add_room(rect), true),
            };
            let (door, new_door) = self.pass(from, room, at, side);
            self.current = Some(room);
            self.leaving = None;
            return Some(RoomEvent::Entered {
                room,
                door,
                new_room,
                new_door,
            });
        }
        let b = self.rooms[cur].bounds;
        let beyond = [b[0] - q.x, q.x - b[1], b[2] - q.y, q.y - b[3]];
        let out = RoomSide::ALL
            .into_iter()
            .filter(|s| beyond[s.index()] > self.config.leave_m)
            .max_by(|a, b| beyond[a.index()].total_cmp(&beyond[b.index()]));
        if let Some(side) = out {
            // The door is where the robot's path crosses the side's line.
            let k = side.index();
            let edge = b[k];
            let mut crossing = q;
            match side {
                RoomSide::West | RoomSide::East => crossing.x = edge,
                RoomSide::South | RoomSide::North => crossing.y = edge,
            }
            self.leaving = Some((cur, self.to_map(&crossing), side));
            return None;
        }
        // A side seen wrong once (a wall not yet in the map, a farther one
        // taken) is outvoted by the measurements that agree.
        if let Some(rect) = rect
            && self.agrees(&self.rooms[cur], &rect)
        {
            self.rooms[cur].measure(rect, keep);
        }
        None
    }

    fn add_room(&mut self, rect: [f64; 4]) -> usize {
        let id = self.rooms.len();
        let mut room = Room {
            id,
            name: format!("room-{id}"),
            bounds: rect,
            visits: 1,
            sides: Default::default(),
        };
        room.measure(rect, self.config.keep);
        self.rooms.push(room);
        id
    }

    /// Sides of `rect` that agree with `room`'s.
    fn sides_agreeing(&self, room: &Room, rect: &[f64; 4]) -> usize {
        room.bounds
            .iter()
            .zip(rect)
            .filter(|(a, b)| (*a - *b).abs() < self.config.same_room_m)
            .count()
    }

    /// Whether `rect` is `room`: three sides of four agree (the fourth may
    /// be the end of a wall of the room next door, seen short of its
    /// corner). Two distinct rooms share at most two sides: side by side,
    /// the shared wall's two faces stand a wall's thickness apart.
    fn agrees(&self, room: &Room, rect: &[f64; 4]) -> bool {
        self.sides_agreeing(room, rect) >= 3
    }

    /// Records a passage from `from` into `to` at `at` through `side` of
    /// `from`.
    fn pass(&mut self, from: usize, to: usize, at: Point2<f64>, side: RoomSide) -> (usize, bool) {
        let near = self.doors.iter().position(|d| {
            (d.rooms == [from, to] || d.rooms == [to, from])
                && (d.at - at).norm() < self.config.same_door_m
        });
        if let Some(i) = near {
            let d = &mut self.doors[i];
            let n = f64::from(d.passages);
            d.at = Point2::from((d.at.coords * n + at.coords) / (n + 1.0));
            d.passages += 1;
            return (i, false);
        }
        let b = self.rooms[from].bounds;
        let q = self.to_floor(&at);
        // Along the side, seen from inside: left to right.
        // Facing a wall from inside, its left end is where a quarter turn
        // left from the wall's direction points.
        let (t, len) = match side {
            RoomSide::North => (q.x - b[0], b[1] - b[0]),
            RoomSide::South => (b[1] - q.x, b[1] - b[0]),
            RoomSide::East => (b[3] - q.y, b[3] - b[2]),
            RoomSide::West => (q.y - b[2], b[3] - b[2]),
        };
        let f = t / len.max(1e-9);
        let place = if f < 1.0 / 3.0 {
            DoorPlace::Left
        } else if f > 2.0 / 3.0 {
            DoorPlace::Right
        } else {
            DoorPlace::Middle
        };
        let id = self.doors.len();
        self.doors.push(Door {
            id,
            rooms: [from, to],
            at,
            wall: side,
            place,
            heading: side,
            passages: 1,
        });
        (id, true)
    }

    /// The shortest way from room `from` to room `to` through known doors
    /// (Dijkstra over doors; each leg a straight line).
    pub fn route(&self, from: usize, to: usize) -> Option<Route> {
        let n = self.rooms.len();
        if from >= n || to >= n {
            return None;
        }
        let start = self.centre(from)?;
        let goal = self.centre(to)?;
        if from == to {
            return Some(Route {
                rooms: vec![from],
                doors: Vec::new(),
                length_m: 0.0,
            });
        }
        // Nodes are (door, the room it leads into): node 2i + k stands at
        // door i, going into its room k.
        let m = 2 * self.doors.len();
        let into = |n: usize| self.doors[n / 2].rooms[n % 2];
        let from_of = |n: usize| self.doors[n / 2].rooms[1 - n % 2];
        let at = |n: usize| self.doors[n / 2].at;
        let mut dist = vec![f64::INFINITY; m];
        let mut prev: Vec<Option<usize>> = vec![None; m];
        let mut done = vec![false; m];
        for (n, d) in dist.iter_mut().enumerate() {
            if from_of(n) == from {
                *d = (at(n) - start).norm();
            }
        }
        let mut best: Option<(f64, usize)> = None;
        while let Some(n) = (0..m)
            .filter(|&n| !done[n] && dist[n].is_finite())
            .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
        {
            done[n] = true;
            let here = into(n);
            if here == to {
                let total = dist[n] + (goal - at(n)).norm();
                if best.is_none_or(|(l, _)| total < l) {
                    best = Some((total, n));
                }
                continue;
            }
            for next in 0..m {
                if done[next] || next / 2 == n / 2 || from_of(next) != here {
                    continue;
                }
                let via = dist[n] + (at(next) - at(n)).norm();
                if via < dist[next] {
                    dist[next] = via;
                    prev[next] = Some(n);
                }
            }
        }
        let (length_m, last) = best?;
        let mut nodes = vec![last];
        while let Some(p) = prev[*nodes.last()?] {
            nodes.push(p);
        }
        nodes.reverse();
        let mut rooms = vec![from];
        rooms.extend(nodes.iter().map(|&n| into(n)));
        Some(Route {
            rooms,
            doors: nodes.iter().map(|&n| n / 2).collect(),
            length_m,
        })
    }

    /// [`RoomGraph::route`] between rooms by name; refused naming the
    /// room that is not in the graph, or when no known door leads there.
    pub fn route_by_name(&self, from: &str, to: &str) -> Result<Route, NavError> {
        let id = |name: &str| {
            self.room_named(name).map(|r| r.id).ok_or_else(|| {
                let names: Vec<&str> = self.rooms.iter().map(|r| r.name.as_str()).collect();
                NavError::InvalidConfig {
                    field: "room",
                    reason: format!("no room `{name}` (rooms: {})", names.join(", ")),
                }
            })
        };
        let (a, b) = (id(from)?, id(to)?);
        self.route(a, b).ok_or_else(|| NavError::InvalidConfig {
            field: "room",
            reason: format!("no known way from `{from}` to `{to}`"),
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::wall_map::WallMap;
    use crate::wall_map::WallRole;
    use nalgebra::Matrix2;

    /// Whether two rooms' bounds `[x0, x1, y0, y1]` agree.
    fn same_bounds(a: [f64; 4], b: [f64; 4]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9)
    }

    /// The inner face of a room's wall from `a` to `b` (counter-clockwise
    /// round the room), as the map holds it.
    fn face(id: u32, a: (f64, f64), b: (f64, f64)) -> MapWall {
        let (a, b) = (Point2::new(a.0, a.1), Point2::new(b.0, b.1));
        let u = (b - a).normalize();
        let n = Vector2::new(u.y, -u.x);
        MapWall {
            id,
            rho_m: n.dot(&a.coords),
            alpha_rad: n.y.atan2(n.x),
            covariance: Matrix2::identity() * 1e-6,
            extent_m: [u.dot(&a.coords), u.dot(&b.coords)],
            observations: 50,
            wall_behind_scans: 0,
            role: WallRole::Wall,
        }
    }

    /// Two rooms of the same size, A [0, 4] × [0, 3] and B [4.15, 8.15] ×
    /// [0, 3], a door between them (y 1–2); a corridor C [0, 8.15] × [3.15,
    /// 5.15] to the north, a door from it into each (x 1.5–2.5 and 6–7),
    /// some walls seen as the two pieces either side of their door; a
    /// cabinet's face in A, too short to bound a room.
    fn floor() -> WallMap {
        let walls = vec![
            // A: south, east (two pieces round the door to B), north (in
            // one, as merged across its door), west.
            face(0, (0.0, 0.0), (4.0, 0.0)),
            face(1, (4.0, 0.0), (4.0, 1.0)),
            face(2, (4.0, 2.0), (4.0, 3.0)),
            face(3, (4.0, 3.0), (0.0, 3.0)),
            face(4, (0.0, 3.0), (0.0, 0.0)),
            // B.
            face(5, (4.15, 0.0), (8.15, 0.0)),
            face(6, (8.15, 0.0), (8.15, 3.0)),
            face(7, (8.15, 3.0), (7.0, 3.0)),
            face(8, (6.0, 3.0), (4.15, 3.0)),
            face(9, (4.15, 3.0), (4.15, 2.0)),
            face(10, (4.15, 1.0), (4.15, 0.0)),
            // C.
            face(11, (0.0, 3.15), (8.15, 3.15)),
            face(12, (8.15, 3.15), (8.15, 5.15)),
            face(13, (8.15, 5.15), (0.0, 5.15)),
            face(14, (0.0, 5.15), (0.0, 3.15)),
            // A cabinet's face in A, 0.8 m long.
            face(15, (3.0, 2.5), (2.2, 2.5)),
        ];
        WallMap {
            walls,
            pose: Pose2::IDENTITY,
        }
    }

    /// Drives `graph` along `points` in steps of 5 cm; the events.
    fn drive(graph: &mut RoomGraph, map: &WallMap, points: &[(f64, f64)]) -> Vec<RoomEvent> {
        let mut events = Vec::new();
        for pair in points.windows(2) {
            let (a, b) = (
                Point2::new(pair[0].0, pair[0].1),
                Point2::new(pair[1].0, pair[1].1),
            );
            let d = b - a;
            let steps = (d.norm() / 0.05).ceil().max(1.0) as usize;
            for k in 0..=steps {
                let p = a + d * (k as f64 / steps as f64);
                let pose = Pose2::new(p.x, p.y, d.y.atan2(d.x));
                events.extend(graph.update(&pose, &map.walls));
            }
        }
        events
    }

    const LOOP: [(f64, f64); 6] = [
        (1.0, 4.15),
        (2.0, 4.15),
        (2.0, 1.5),
        (6.5, 1.5),
        (6.5, 4.15),
        (1.0, 4.15),
    ];

    #[test]
    fn a_loop_through_two_look_alike_rooms_gives_three_rooms_and_three_doors() {
        let map = floor();
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        let events = drive(&mut graph, &map, &LOOP);
        assert_eq!(events[0], RoomEvent::Started { room: 0 });
        let rooms = graph.rooms();
        assert_eq!(rooms.len(), 3, "{rooms:?}");
        assert!(
            same_bounds(rooms[0].bounds, [0.0, 8.15, 3.15, 5.15]),
            "{:?}",
            rooms[0]
        );
        assert!(
            same_bounds(rooms[1].bounds, [0.0, 4.0, 0.0, 3.0]),
            "{:?}",
            rooms[1]
        );
        assert!(
            same_bounds(rooms[2].bounds, [4.15, 8.15, 0.0, 3.0]),
            "{:?}",
            rooms[2]
        );
        // A and B are the same size, two rooms: told apart by where they
        // are.
        let (a, b) = (rooms[1].size_m(), rooms[2].size_m());
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        let doors = graph.doors();
        assert_eq!(doors.len(), 3, "{doors:?}");
        assert_eq!(doors[0].rooms, [0, 1]);
        assert_eq!(
            (doors[0].wall, doors[0].heading),
            (RoomSide::South, RoomSide::South)
        );
        // Facing C's south wall from inside, x = 2 is in its right third.
        assert_eq!(doors[0].place, DoorPlace::Right);
        assert!((doors[0].at - Point2::new(2.0, 3.15)).norm() < 1e-9);
        assert_eq!(doors[1].rooms, [1, 2]);
        assert_eq!(
            (doors[1].wall, doors[1].place),
            (RoomSide::East, DoorPlace::Middle)
        );
        assert_eq!(doors[2].rooms, [2, 0]);
        assert_eq!(doors[2].wall, RoomSide::North);
        // Back in C, the room it started in: a loop closed, no new room.
        assert_eq!(
            events.last(),
            Some(&RoomEvent::Entered {
                room: 0,
                door: 2,
                new_room: false,
                new_door: true
            })
        );
        // Round again: the same rooms and doors, each passed twice.
        let visits = |g: &RoomGraph| g.rooms().iter().map(|r| r.visits).collect::<Vec<_>>();
        // C started in and come back to; A and B entered once.
        assert_eq!(visits(&graph), [2, 1, 1]);
        let again = drive(&mut graph, &map, &LOOP[1..]);
        assert_eq!(again.len(), 3);
        assert_eq!(graph.rooms().len(), 3);
        assert_eq!(visits(&graph), [3, 2, 2]);
        assert!(
            graph.doors().iter().all(|d| d.passages == 2),
            "{:?}",
            graph.doors()
        );
    }

    /// The apartment's rooms round its hall: a living room L [0, 5] × [0,
    /// 2.85], a hall H [0, 8] × [3, 4.2] (1.2 m wide) and a bedroom B [0,
    /// 4] × [4.35, 8], the walls 0.15 m thick; a door from L into H (x 3.1
    /// to 4) and one from H into B (x 3 to 3.8), nearly facing each other.
    /// With `bedroom_near_face`, B's south face is mapped.
    fn apartment(bedroom_near_face: bool) -> WallMap {
        let mut walls = vec![
            face(0, (0.0, 0.0), (5.0, 0.0)),
            face(1, (5.0, 0.0), (5.0, 2.85)),
            face(2, (5.0, 2.85), (4.0, 2.85)),
            face(3, (3.1, 2.85), (0.0, 2.85)),
            face(4, (0.0, 2.85), (0.0, 0.0)),
            face(5, (0.0, 3.0), (8.0, 3.0)),
            face(6, (8.0, 3.0), (8.0, 4.2)),
            face(7, (8.0, 4.2), (3.8, 4.2)),
            face(8, (3.0, 4.2), (0.0, 4.2)),
            face(9, (0.0, 4.2), (0.0, 3.0)),
            face(10, (4.0, 4.35), (4.0, 8.0)),
            face(11, (4.0, 8.0), (0.0, 8.0)),
            face(12, (0.0, 8.0), (0.0, 4.35)),
        ];
        if bedroom_near_face {
            walls.push(face(13, (0.0, 4.35), (3.0, 4.35)));
            walls.push(face(14, (3.8, 4.35), (4.0, 4.35)));
        }
        WallMap {
            walls,
            pose: Pose2::IDENTITY,
        }
    }

    #[test]
    fn a_hall_crossed_from_door_to_door_is_a_room_between_two_doors() {
        let map = apartment(true);
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        // Straight across the hall into the bedroom and back out, twice.
        let there_and_back = [(3.6, 1.5), (3.3, 5.3), (3.6, 1.5)];
        drive(&mut graph, &map, &there_and_back);
        drive(&mut graph, &map, &there_and_back);
        let rooms = graph.rooms();
        assert_eq!(rooms.len(), 3, "{rooms:?}");
        assert!(
            same_bounds(rooms[1].bounds, [0.0, 8.0, 3.0, 4.2]),
            "{:?}",
            rooms[1]
        );
        assert!(
            same_bounds(rooms[2].bounds, [0.0, 4.0, 4.35, 8.0]),
            "{:?}",
            rooms[2]
        );
        let pairs: Vec<[usize; 2]> = graph.doors().iter().map(|d| d.rooms).collect();
        assert_eq!(pairs, [[0, 1], [1, 2]]);
        assert!(graph.doors().iter().all(|d| d.passages == 4));
    }

    #[test]
    fn a_room_is_not_measured_across_the_wall_it_was_entered_through() {
        // Just through the bedroom's door, before its own south face is
        // mapped: the hall's far face lies behind the robot's back, so the
        // hall's south face beyond it is no side of the bedroom.
        let map = apartment(false);
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        graph.update(&Pose2::new(2.0, 1.5, 0.0), &map.walls);
        let past_the_door = Point2::new(3.4, 4.6);
        assert_eq!(graph.rectangle(&map.walls, &past_the_door), None);
        // Its south face mapped, the bedroom is measured.
        let map = apartment(true);
        let rect = graph.rectangle(&map.walls, &past_the_door).unwrap();
        assert!(same_bounds(rect, [0.0, 4.0, 4.35, 8.0]), "{rect:?}");
    }

    #[test]
    fn a_wall_hidden_behind_a_sofa_still_bounds_its_room() {
        // The living room [0, 5] × [0, 2.85]: of its west wall only the
        // ends are mapped, 1.6 m apart; the sofa's face stands 0.9 m
        // before it across that gap.
        let mut walls = vec![
            face(0, (0.0, 0.0), (5.0, 0.0)),
            face(1, (5.0, 0.0), (5.0, 2.85)),
            face(2, (5.0, 2.85), (0.0, 2.85)),
            face(3, (0.0, 2.85), (0.0, 2.1)),
            face(4, (0.0, 0.5), (0.0, 0.0)),
        ];
        let mut sofa = face(5, (0.9, 2.2), (0.9, 0.4));
        sofa.role = WallRole::InFront;
        walls.push(sofa);
        let at = Point2::new(2.5, 1.4);
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        graph.update(&Pose2::new(at.x, at.y, 0.0), &walls);
        let rect = graph.rectangle(&walls, &at).unwrap();
        assert!(same_bounds(rect, [0.0, 5.0, 0.0, 2.85]), "{rect:?}");
        // Without the sofa the gap is wider than a door: the two short
        // pieces are no side.
        walls.pop();
        assert_eq!(graph.rectangle(&walls, &at), None);
        // Nor does a face behind the wall's line hide its gap.
        let mut beyond = face(5, (-0.9, 2.2), (-0.9, 0.4));
        beyond.role = WallRole::InFront;
        walls.push(beyond);
        assert_eq!(graph.rectangle(&walls, &at), None);
    }

    #[test]
    fn standing_in_a_doorway_and_turning_back_changes_no_room() {
        let map = floor();
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        // Into the doorway of A (past C's side by 0.4 m) and back.
        let events = drive(&mut graph, &map, &[(2.0, 4.15), (2.0, 2.75), (2.0, 4.5)]);
        assert_eq!(events, [RoomEvent::Started { room: 0 }]);
        assert_eq!(graph.current(), Some(0));
        assert!(graph.doors().is_empty());
    }

    #[test]
    fn routes_go_the_short_way_through_known_doors() {
        let map = floor();
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        drive(&mut graph, &map, &LOOP);
        graph.name(0, "corridor");
        graph.name(1, "office-a");
        graph.name(2, "office-b");
        // A to B: through their own door, not round by the corridor.
        let r = graph.route_by_name("office-a", "office-b").unwrap();
        assert_eq!((r.rooms.clone(), r.doors.clone()), (vec![1, 2], vec![1]));
        let direct: f64 = (Point2::new(4.075, 1.5) - Point2::new(2.0, 1.5)).norm()
            + (Point2::new(6.15, 1.5) - Point2::new(4.075, 1.5)).norm();
        assert!((r.length_m - direct).abs() < 0.05, "{}", r.length_m);
        let r = graph.route_by_name("corridor", "office-b").unwrap();
        assert_eq!(r.rooms, [0, 2]);
        assert_eq!(graph.route(1, 1).unwrap().doors, Vec::<usize>::new());
        let e = graph
            .route_by_name("office-a", "kitchen")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no room `kitchen`") && e.contains("office-b"),
            "{e}"
        );
    }

    #[test]
    fn a_room_never_entered_has_no_route() {
        let map = floor();
        let mut graph = RoomGraph::new(RoomGraphConfig::default());
        drive(&mut graph, &map, &[(1.0, 4.15), (2.0, 4.15), (2.0, 1.5)]);
        assert_eq!(graph.rooms().len(), 2);
        // B is not in the graph: no route there, nor by name; the way from
        // A to the corridor is the one door passed.
        assert!(graph.route(1, 0).is_some_and(|r| r.doors == [0]));
        assert!(graph.route(1, 2).is_none());
        assert_eq!(graph.rooms()[1].visits, 1);
    }
}
