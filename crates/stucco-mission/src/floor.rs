//! The floor plan a mission may carry: rooms on the building's drawing
//! (rectangles, or any shape given by its corners), doors between them. The robot keeps one room frame
//! at a time (its filter's); the plan says which rooms there are, how they
//! connect, and where the next room's frame lies once the robot has gone
//! through a door. Routes between named rooms run over its doors.

use crate::model::{WallGeometry, walls_of_room};
use crate::task::WallName;
use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use stucco_core::Pose2;

/// A room of the plan: a rectangle with its walls along the plan's axes,
/// given by its south-west corner and size or by its four corners, or a
/// room of any other shape given by its corners. Its frame (the one the
/// robot's filter keeps while inside) has its origin in the south-west
/// corner of its box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanRoom {
    /// Its name (tasks and telecommands name rooms by it).
    pub name: String,
    /// The south-west corner on the plan, m (from `corners` when the
    /// drawing gives them).
    #[serde(default)]
    pub origin_m: [f64; 2],
    /// Its size along x and y, m (from `corners` when the drawing gives
    /// them).
    #[serde(default)]
    pub size_m: [f64; 2],
    /// Its corners as the drawing gives them, counter-clockwise, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corners: Option<Vec<[f64; 2]>>,
}

/// A window the drawing gives: a prior of where the robot will find one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanWindow {
    /// The room whose wall it is in.
    pub room: String,
    /// Its middle on the drawing, m.
    pub at_m: [f64; 2],
    /// Its width, m.
    pub width_m: f64,
    /// Its sill above the floor, m.
    pub sill_m: f64,
    /// Its head above the floor, m.
    pub head_m: f64,
}

/// Farthest a drawn corner of a rectangle may lie from the rectangle
/// fitted to its corners (each side the mean of its two), m: a drawing off
/// by up to 3 cm in each coordinate of each corner.
const CORNER_SLACK_M: f64 = 0.05;

impl PlanRoom {
    /// Its corners in its own frame, counter-clockwise, when it is not a
    /// rectangle along the drawing's axes (empty for one: its walls are
    /// then the rectangle's four, west, south, east, north).
    pub fn outline(&self) -> Vec<[f64; 2]> {
        match &self.corners {
            Some(c) if rectangle_of(c).is_none() => c
                .iter()
                .map(|p| [p[0] - self.origin_m[0], p[1] - self.origin_m[1]])
                .collect(),
            _ => Vec::new(),
        }
    }

    /// Its wall `w` in its own frame, when it has it.
    pub fn wall(&self, w: WallName) -> Option<WallGeometry> {
        WallGeometry::of_room(&self.outline(), self.size_m, w)
    }

    /// Its walls in its own frame, by name.
    pub fn walls(&self) -> Vec<(WallName, WallGeometry)> {
        walls_of_room(&self.outline(), self.size_m)
    }
}

/// The box of a room given by `corners`, as `(origin, size)`: the
/// rectangle they draw (each side the mean of its two corners), or the
/// box round any other shape; or why they make no room.
fn box_of(corners: &[[f64; 2]]) -> Result<([f64; 2], [f64; 2]), String> {
    if let Some(fault) = stucco_plan::Outline::new(corners).fault() {
        return Err(fault);
    }
    if let Some(rectangle) = rectangle_of(corners) {
        return Ok(rectangle);
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for c in corners {
        for i in 0..2 {
            lo[i] = lo[i].min(c[i]);
            hi[i] = hi[i].max(c[i]);
        }
    }
    Ok((lo, [hi[0] - lo[0], hi[1] - lo[1]]))
}

/// The rectangle along the drawing's axes `corners` draw (each side the
/// mean of its two corners), as `(origin, size)`, if they draw one.
fn rectangle_of(corners: &[[f64; 2]]) -> Option<([f64; 2], [f64; 2])> {
    if corners.len() != 4 {
        return None;
    }
    // The corner nearest the south-west first; counter-clockwise, the
    // others are then south-east, north-east, north-west. Each side is
    // the mean of its two corners (a drawing is off corner by corner).
    let first = (0..4)
        .min_by(|&a, &b| {
            let key = |c: [f64; 2]| c[0] + c[1];
            key(corners[a]).total_cmp(&key(corners[b]))
        })
        .unwrap_or(0);
    let [sw, se, ne, nw] = std::array::from_fn(|k| corners[(first + k) % 4]);
    let (x0, x1) = ((sw[0] + nw[0]) / 2.0, (se[0] + ne[0]) / 2.0);
    let (y0, y1) = ((sw[1] + se[1]) / 2.0, (nw[1] + ne[1]) / 2.0);
    let fitted = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
    let on_box = x1 > x0
        && y1 > y0
        && [sw, se, ne, nw]
            .iter()
            .zip(&fitted)
            .all(|(c, f)| (c[0] - f[0]).hypot(c[1] - f[1]) <= CORNER_SLACK_M);
    on_box.then_some(([x0, y0], [x1 - x0, y1 - y0]))
}

/// A door of the plan between two rooms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanDoor {
    /// The rooms it joins.
    pub rooms: [String; 2],
    /// Its middle on the plan (anywhere across the wall's thickness), m.
    pub at_m: [f64; 2],
    /// Its width, m.
    pub width_m: f64,
    /// Its height, m, when the drawing gives it (the plaster stops at
    /// the top of a door the camera has not measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_m: Option<f64>,
    /// Kept shut: no way through, and no gap the laser sees; the rooms'
    /// plaster leaves its leaf out.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub shut: bool,
}

/// Where a door lies in one of its rooms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DoorSide {
    /// The room.
    pub room: usize,
    /// The wall of that room it is in.
    pub wall: WallName,
    /// Its middle along that wall, m.
    pub along_m: f64,
}

/// What is wrong in a plan: the door or room (by its index in the file)
/// and the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{table} {index}: {field}: {why}")]
pub struct PlanFault {
    /// `room` or `door`.
    pub table: &'static str,
    /// Its index among the file's tables of that name.
    pub index: usize,
    /// The field at fault.
    pub field: &'static str,
    /// Why.
    pub why: String,
}

/// A door further than this from a wall's line is not in it, m (half a
/// thick wall and the drawing's slack).
const DOOR_IN_WALL_M: f64 = 0.3;

/// A floor plan, checked: every door lies in a wall of each of its two
/// rooms, inside the wall's length.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PlanText", into = "PlanText")]
pub struct FloorPlan {
    rooms: Vec<PlanRoom>,
    doors: Vec<PlanDoor>,
    sides: Vec<[DoorSide; 2]>,
    windows: Vec<PlanWindow>,
}

/// A plan as written.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct PlanText {
    rooms: Vec<PlanRoom>,
    doors: Vec<PlanDoor>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    windows: Vec<PlanWindow>,
}

impl TryFrom<PlanText> for FloorPlan {
    type Error = PlanFault;
    fn try_from(t: PlanText) -> Result<Self, PlanFault> {
        FloorPlan::new(t.rooms, t.doors)?.with_windows(t.windows)
    }
}

impl From<FloorPlan> for PlanText {
    fn from(p: FloorPlan) -> Self {
        PlanText {
            rooms: p.rooms,
            doors: p.doors,
            windows: p.windows,
        }
    }
}

impl FloorPlan {
    /// Checks `rooms` and `doors` and places each door in its rooms' walls.
    /// A room given by its `corners` takes its origin and size from them.
    pub fn new(mut rooms: Vec<PlanRoom>, doors: Vec<PlanDoor>) -> Result<Self, PlanFault> {
        let fault = |table, index, field, why: String| PlanFault {
            table,
            index,
            field,
            why,
        };
        let mut names = BTreeSet::new();
        for (i, r) in rooms.iter_mut().enumerate() {
            if !names.insert(r.name.clone()) {
                return Err(fault("room", i, "name", format!("{:?} twice", r.name)));
            }
            if let Some(corners) = &r.corners {
                let (origin, size) =
                    box_of(corners).map_err(|why| fault("room", i, "corners", why))?;
                let given = r.size_m != [0.0, 0.0] || r.origin_m != [0.0, 0.0];
                let same = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9;
                if given && !(same(r.origin_m, origin) && same(r.size_m, size)) {
                    return Err(fault(
                        "room",
                        i,
                        "corners",
                        "give corners, or origin_m and size_m, not both".into(),
                    ));
                }
                r.origin_m = origin;
                r.size_m = size;
            }
            if !r.size_m.iter().all(|v| v.is_finite() && *v > 0.0) {
                return Err(fault("room", i, "size_m", "sides must be positive".into()));
            }
            if !r.origin_m.iter().all(|v| v.is_finite()) {
                return Err(fault("room", i, "origin_m", "must be numbers".into()));
            }
        }
        let mut sides = Vec::with_capacity(doors.len());
        for (i, d) in doors.iter().enumerate() {
            if !(d.width_m.is_finite() && d.width_m > 0.0) {
                return Err(fault("door", i, "width_m", "must be positive".into()));
            }
            if d.height_m.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
                return Err(fault("door", i, "height_m", "must be positive".into()));
            }
            if d.rooms[0] == d.rooms[1] {
                return Err(fault("door", i, "rooms", "two different rooms".into()));
            }
            let side = |name: &String| -> Result<DoorSide, PlanFault> {
                let room = rooms
                    .iter()
                    .position(|r| &r.name == name)
                    .ok_or_else(|| fault("door", i, "rooms", format!("no room {name:?}")))?;
                let r = &rooms[room];
                let at = Vector2::new(d.at_m[0] - r.origin_m[0], d.at_m[1] - r.origin_m[1]);
                r.walls()
                    .into_iter()
                    .filter(|(_, g)| g.distance(&at).abs() <= DOOR_IN_WALL_M)
                    .find(|(_, g)| {
                        let along = g.position(&at);
                        along - d.width_m / 2.0 >= 0.0 && along + d.width_m / 2.0 <= g.length_m
                    })
                    .map(|(wall, g)| DoorSide {
                        room,
                        wall,
                        along_m: g.position(&at),
                    })
                    .ok_or_else(|| {
                        fault(
                            "door",
                            i,
                            "at_m",
                            format!(
                                "not within {DOOR_IN_WALL_M} m of a wall of {name:?} with its \
                                 {} m of width inside the wall",
                                d.width_m
                            ),
                        )
                    })
            };
            sides.push([side(&d.rooms[0])?, side(&d.rooms[1])?]);
        }
        Ok(FloorPlan {
            rooms,
            doors,
            sides,
            windows: Vec::new(),
        })
    }

    /// The plan with the drawing's `windows`, each checked: in a room of
    /// the plan, within a wall's reach of one of its walls with its width
    /// inside it, its sill below its head.
    pub fn with_windows(mut self, windows: Vec<PlanWindow>) -> Result<Self, PlanFault> {
        let fault = |index, field, why: String| PlanFault {
            table: "window",
            index,
            field,
            why,
        };
        for (i, w) in windows.iter().enumerate() {
            let Some(room) = self.room(&w.room) else {
                return Err(fault(i, "room", format!("no room {:?}", w.room)));
            };
            if !(w.width_m.is_finite() && w.width_m > 0.0) {
                return Err(fault(i, "width_m", "must be positive".into()));
            }
            if !(w.sill_m.is_finite() && w.sill_m >= 0.0) {
                return Err(fault(i, "sill_m", "must not be negative".into()));
            }
            if !(w.head_m.is_finite() && w.head_m > w.sill_m) {
                return Err(fault(i, "head_m", "must lie above the sill".into()));
            }
            let r = &self.rooms[room];
            let at = Vector2::new(w.at_m[0] - r.origin_m[0], w.at_m[1] - r.origin_m[1]);
            let in_wall = r.walls().iter().any(|(_, g)| {
                let along = g.position(&at);
                g.distance(&at).abs() <= DOOR_IN_WALL_M
                    && along - w.width_m / 2.0 >= 0.0
                    && along + w.width_m / 2.0 <= g.length_m
            });
            if !in_wall {
                return Err(fault(
                    i,
                    "at_m",
                    format!(
                        "not within {DOOR_IN_WALL_M} m of a wall of {:?} with its {} m of width \
                         inside the wall",
                        w.room, w.width_m
                    ),
                ));
            }
        }
        self.windows = windows;
        Ok(self)
    }

    /// The windows the drawing gives (a prior: the robot's camera finds
    /// the windows it plasters round).
    pub fn windows(&self) -> &[PlanWindow] {
        &self.windows
    }

    /// The rooms.
    pub fn rooms(&self) -> &[PlanRoom] {
        &self.rooms
    }

    /// The doors.
    pub fn doors(&self) -> &[PlanDoor] {
        &self.doors
    }

    /// The room named `name`.
    pub fn room(&self, name: &str) -> Option<usize> {
        self.rooms.iter().position(|r| r.name == name)
    }

    /// The open doors of `room` (the ways out of it): each door's index
    /// and where it lies there.
    pub fn doors_of(&self, room: usize) -> impl Iterator<Item = (usize, DoorSide)> + '_ {
        self.sides_in(room).filter(|(i, _)| !self.doors[*i].shut)
    }

    /// The shut doors of `room`: each door's index and where it lies
    /// there.
    pub fn shut_doors_of(&self, room: usize) -> impl Iterator<Item = (usize, DoorSide)> + '_ {
        self.sides_in(room).filter(|(i, _)| self.doors[*i].shut)
    }

    fn sides_in(&self, room: usize) -> impl Iterator<Item = (usize, DoorSide)> + '_ {
        self.sides
            .iter()
            .enumerate()
            .filter_map(move |(i, s)| s.iter().find(|s| s.room == room).map(|s| (i, *s)))
    }

    /// Where `door` lies in `room`, if it is one of its doors.
    pub fn side(&self, door: usize, room: usize) -> Option<DoorSide> {
        self.sides
            .get(door)?
            .iter()
            .find(|s| s.room == room)
            .copied()
    }

    /// The room beyond `door` seen from `room`.
    pub fn beyond(&self, door: usize, room: usize) -> Option<usize> {
        let s = self.sides.get(door)?;
        match (s[0].room == room, s[1].room == room) {
            (true, _) => Some(s[1].room),
            (_, true) => Some(s[0].room),
            _ => None,
        }
    }

    /// The doors to pass, in order, to go from room `from` to room `to`
    /// on the shortest way between door middles (Dijkstra; the robot's
    /// own place in `from` is left out: rooms are small against a floor).
    /// Empty when `from == to`; `None` when no way joins them.
    pub fn route(&self, from: usize, to: usize) -> Option<Vec<usize>> {
        self.route_for(from, to, 0.0)
    }

    /// [`FloorPlan::route`] through doors at least `width_m` wide only
    /// (those a robot fits through with its protective field).
    pub fn route_for(&self, from: usize, to: usize, width_m: f64) -> Option<Vec<usize>> {
        if from == to {
            return Some(Vec::new());
        }
        // Nodes: (door, room the robot stands in after passing it).
        let n = self.doors.len();
        let mut dist = vec![f64::INFINITY; 2 * n];
        let mut prev: Vec<Option<usize>> = vec![None; 2 * n];
        let node =
            |door: usize, room: usize| 2 * door + usize::from(self.sides[door][1].room == room);
        let mut open = BTreeSet::new();
        for (d, _) in self
            .doors_of(from)
            .filter(|(d, _)| self.doors[*d].width_m >= width_m)
        {
            let Some(r) = self.beyond(d, from) else {
                continue;
            };
            let k = node(d, r);
            dist[k] = 0.0;
            open.insert((ordered(0.0), k));
        }
        while let Some((_, k)) = open.pop_first() {
            let (door, room) = (k / 2, self.sides[k / 2][k % 2].room);
            if room == to {
                let mut path = vec![door];
                let mut at = k;
                while let Some(p) = prev[at] {
                    path.push(p / 2);
                    at = p;
                }
                path.reverse();
                return Some(path);
            }
            let here = Vector2::from(self.doors[door].at_m);
            for (next, _) in self
                .doors_of(room)
                .filter(|(d, _)| self.doors[*d].width_m >= width_m)
            {
                let Some(r) = self.beyond(next, room) else {
                    continue;
                };
                let m = node(next, r);
                let d = dist[k] + (Vector2::from(self.doors[next].at_m) - here).norm();
                if d < dist[m] {
                    open.remove(&(ordered(dist[m]), m));
                    dist[m] = d;
                    prev[m] = Some(k);
                    open.insert((ordered(d), m));
                }
            }
        }
        None
    }

    /// How deep `door`'s hole through its wall is: from the line of its
    /// wall in one room to that in the other, m (the wall's thickness).
    pub fn door_depth(&self, door: usize) -> Option<f64> {
        let [s, t] = self.sides.get(door)?;
        let (a, b) = (&self.rooms[s.room], &self.rooms[t.room]);
        let near = a.wall(s.wall)?;
        // The far side's middle, in the near room's frame.
        let far = b.wall(t.wall)?.point(t.along_m, 0.0) + Vector2::from(b.origin_m)
            - Vector2::from(a.origin_m);
        Some(near.distance(&far).abs())
    }

    /// The pose in the frame of the room beyond `door` of a robot at
    /// `pose` in the frame of `room`. `here` is where the filter puts the
    /// door's middle in this room's frame; `there`, where it puts it in
    /// the frame of the room beyond when the robot has learnt that room
    /// (none: as drawn). The door anchors the two frames, so an error of
    /// the plan elsewhere in either room does not carry over.
    pub fn transfer(
        &self,
        door: usize,
        room: usize,
        pose: &Pose2,
        here: Vector2<f64>,
        there: Option<Vector2<f64>>,
    ) -> Option<(usize, Pose2)> {
        let next = self.beyond(door, room)?;
        let (near, far) = (self.side(door, room)?, self.side(door, next)?);
        let (a, b) = (&self.rooms[room], &self.rooms[next]);
        // The door's middle as the filter places it, and as the plan does.
        let plan = a.wall(near.wall)?.point(near.along_m, 0.0);
        let p = pose.position().coords + (plan - here);
        let shift = Vector2::from(a.origin_m) - Vector2::from(b.origin_m);
        let mut q = p + shift;
        if let Some(learnt) = there {
            q += learnt - b.wall(far.wall)?.point(far.along_m, 0.0);
        }
        Some((next, Pose2::new(q.x, q.y, pose.theta)))
    }

    /// The middle of `door` in the frame of `room`, a room whose walls the
    /// robot holds as `corners` (none: the rectangle `size_m`), the door
    /// `along_m` along its wall.
    pub fn door_middle(
        &self,
        door: usize,
        room: usize,
        corners: &[[f64; 2]],
        size_m: [f64; 2],
        along_m: f64,
    ) -> Option<Vector2<f64>> {
        let side = self.side(door, room)?;
        Some(WallGeometry::of_room(corners, size_m, side.wall)?.point(along_m, 0.0))
    }
}

/// An `f64` that orders (for the open set; distances are never NaN).
fn ordered(v: f64) -> u64 {
    v.max(0.0).to_bits()
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    /// A corridor 10 × 2 m with two offices north of it, the offices
    /// joined by a door of their own, a wall 0.2 m thick between all.
    fn plan() -> FloorPlan {
        let room = |name: &str, origin_m, size_m| PlanRoom {
            name: name.into(),
            origin_m,
            size_m,
            corners: None,
        };
        let door = |a: &str, b: &str, at_m| PlanDoor {
            rooms: [a.into(), b.into()],
            at_m,
            width_m: 1.0,
            height_m: None,
            shut: false,
        };
        FloorPlan::new(
            vec![
                room("corridor", [0.0, 0.0], [10.0, 2.0]),
                room("a", [0.0, 2.2], [4.9, 4.0]),
                room("b", [5.1, 2.2], [4.9, 4.0]),
            ],
            vec![
                door("corridor", "a", [2.0, 2.1]),
                door("corridor", "b", [8.0, 2.1]),
                door("a", "b", [5.0, 5.0]),
            ],
        )
        .unwrap()
    }

    #[test]
    fn doors_are_placed_in_their_walls() {
        let p = plan();
        let s = p.side(0, 0).unwrap();
        assert_eq!(s.wall, WallName::NORTH);
        assert!((s.along_m - 2.0).abs() < 1e-9, "{s:?}");
        let s = p.side(0, 1).unwrap();
        assert_eq!(s.wall, WallName::SOUTH);
        assert!((s.along_m - 2.0).abs() < 1e-9);
        assert_eq!(p.side(2, 1).unwrap().wall, WallName::EAST);
        assert_eq!(p.side(2, 2).unwrap().wall, WallName::WEST);
        assert_eq!(p.side(2, 0), None);
        // Each door's hole is as deep as the wall between its rooms.
        for door in 0..3 {
            let depth = p.door_depth(door).unwrap();
            assert!((depth - 0.2).abs() < 1e-9, "door {door}: {depth}");
        }
    }

    #[test]
    fn routes_take_the_shortest_way_over_doors() {
        let p = plan();
        assert_eq!(p.route(0, 0), Some(vec![]));
        assert_eq!(p.route(0, 1), Some(vec![0]));
        assert_eq!(p.route(1, 2), Some(vec![2]));
        assert_eq!(p.route(2, 1), Some(vec![2]));
        // From the corridor to b: its own door, not through a.
        assert_eq!(p.route(0, 2), Some(vec![1]));
        // Only through doors as wide as asked: a to b through the
        // corridor, where their own door is narrower; none at all wider.
        let mut doors = p.doors().to_vec();
        doors[2].width_m = 0.7;
        let q = FloorPlan::new(p.rooms().to_vec(), doors).unwrap();
        assert_eq!(q.route_for(1, 2, 0.7), Some(vec![2]));
        assert_eq!(q.route_for(1, 2, 0.74), Some(vec![0, 1]));
        assert_eq!(q.route_for(1, 2, 1.1), None);
        assert_eq!(q.route_for(1, 1, 1.1), Some(vec![]));
        // Without the door a–b, a to b is through the corridor.
        let mut doors = p.doors().to_vec();
        doors.pop();
        let q = FloorPlan::new(p.rooms().to_vec(), doors).unwrap();
        assert_eq!(q.route(1, 2), Some(vec![0, 1]));
        // An island is no route.
        let mut rooms = p.rooms().to_vec();
        rooms.push(PlanRoom {
            name: "island".into(),
            origin_m: [20.0, 0.0],
            size_m: [2.0, 2.0],
            corners: None,
        });
        let q = FloorPlan::new(rooms, p.doors().to_vec()).unwrap();
        assert_eq!(q.route(0, 3), None);
    }

    #[test]
    fn a_shut_door_is_no_way_but_is_kept_with_its_height() {
        let p = plan();
        let mut doors = p.doors().to_vec();
        doors[2].shut = true;
        doors[2].height_m = Some(2.05);
        let q = FloorPlan::new(p.rooms().to_vec(), doors.clone()).unwrap();
        // From a to b through the corridor, not the shut door.
        assert_eq!(q.route(1, 2), Some(vec![0, 1]));
        assert_eq!(q.doors_of(1).map(|(d, _)| d).collect::<Vec<_>>(), [0]);
        let shut: Vec<_> = q.shut_doors_of(2).collect();
        assert_eq!(shut.len(), 1);
        assert_eq!((shut[0].0, shut[0].1.wall), (2, WallName::WEST));
        assert_eq!(q.doors()[2].height_m, Some(2.05));
        // Read from a drawing and written back the same.
        let text = toml::to_string(&PlanText::from(q.clone())).unwrap();
        assert!(text.contains("shut = true"), "{text}");
        let back: FloorPlan = toml::from_str(&text).unwrap();
        assert_eq!(back, q);
        doors[2].height_m = Some(0.0);
        let e = FloorPlan::new(p.rooms().to_vec(), doors).unwrap_err();
        assert_eq!((e.table, e.index, e.field), ("door", 2, "height_m"));
    }

    #[test]
    fn a_pose_moves_to_the_next_room_anchored_on_the_door() {
        let p = plan();
        // Just beyond the corridor's door into a, heading north; the
        // filter puts the door 3 cm east of the plan and the corridor
        // 2 cm wider.
        let pose = Pose2::new(2.0, 2.4, 1.5);
        let here = p.door_middle(0, 0, &[], [10.0, 2.02], 2.03).unwrap();
        let (room, q) = p.transfer(0, 0, &pose, here, None).unwrap();
        assert_eq!(room, 1);
        // The door's middle: (2.03, 2.02) in the filter's corridor, so
        // the robot is 3 cm west of it and 0.38 m beyond the wall line,
        // i.e. 0.18 m into a (the wall is 0.2 m thick).
        assert!((q.x - 1.97).abs() < 1e-9, "{q:?}");
        assert!((q.y - 0.18).abs() < 1e-9, "{q:?}");
        assert_eq!(q.theta, 1.5);
        assert_eq!(p.transfer(0, 2, &pose, Vector2::zeros(), None), None);
        // Room a as the robot learnt it: its south wall's door 2 cm west of
        // the drawing's, the room as drawn; the pose follows the door.
        let (_, r) = p
            .transfer(
                0,
                0,
                &pose,
                here,
                p.door_middle(0, 1, &[], [4.9, 4.0], 1.98),
            )
            .unwrap();
        assert!(
            (r.x - 1.95).abs() < 1e-9 && (r.y - 0.18).abs() < 1e-9,
            "{r:?}"
        );
    }

    #[test]
    fn a_door_off_its_walls_is_refused_with_its_field() {
        let p = plan();
        let mut doors = p.doors().to_vec();
        doors[1].at_m = [8.0, 1.0];
        let e = FloorPlan::new(p.rooms().to_vec(), doors).unwrap_err();
        assert_eq!((e.table, e.index, e.field), ("door", 1, "at_m"));
        let mut doors = p.doors().to_vec();
        doors[0].rooms[1] = "kitchen".into();
        let e = FloorPlan::new(p.rooms().to_vec(), doors).unwrap_err();
        assert_eq!((e.field, e.why.as_str()), ("rooms", "no room \"kitchen\""));
        // A door too wide for its wall's length.
        let mut doors = p.doors().to_vec();
        doors[0].at_m = [0.3, 2.1];
        let e = FloorPlan::new(p.rooms().to_vec(), doors).unwrap_err();
        assert_eq!(e.field, "at_m");
    }
}
