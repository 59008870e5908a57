//! World files (`sim/worlds/*.toml`): rooms as polygons of walls, their
//! doors and windows, furniture, people and the robot's start.
//!
//! Every table is `deny_unknown_fields`, so a misspelt key is an error
//! that names the file, the line and the key, never a silent default.

use crate::SimError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// A whole world: what a world file holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// Name, for reports.
    pub name: String,
    /// Seed of everything random in the world (noise, people's timing).
    pub seed: u64,
    /// Where the robot starts.
    pub robot: RobotStart,
    /// Rooms: polygons of walls.
    #[serde(default, rename = "room")]
    pub rooms: Vec<RoomSpec>,
    /// Doors, each in a wall of a room.
    #[serde(default, rename = "door", skip_serializing_if = "Vec::is_empty")]
    pub doors: Vec<DoorSpec>,
    /// Windows, each in a wall of a room.
    #[serde(default, rename = "window", skip_serializing_if = "Vec::is_empty")]
    pub windows: Vec<WindowSpec>,
    /// Tables: a top on four legs.
    #[serde(default, rename = "table", skip_serializing_if = "Vec::is_empty")]
    pub tables: Vec<TableSpec>,
    /// Chairs: a seat on four legs.
    #[serde(default, rename = "chair", skip_serializing_if = "Vec::is_empty")]
    pub chairs: Vec<TableSpec>,
    /// Boxes standing on the floor.
    #[serde(default, rename = "box", skip_serializing_if = "Vec::is_empty")]
    pub boxes: Vec<BoxSpec>,
    /// Radiators on walls.
    #[serde(default, rename = "radiator", skip_serializing_if = "Vec::is_empty")]
    pub radiators: Vec<RadiatorSpec>,
    /// Round columns.
    #[serde(default, rename = "column", skip_serializing_if = "Vec::is_empty")]
    pub columns: Vec<ColumnSpec>,
    /// People walking along paths.
    #[serde(default, rename = "person", skip_serializing_if = "Vec::is_empty")]
    pub people: Vec<PersonSpec>,
    /// A collision-free loop of waypoints for benches and demos, m.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tour: Vec<[f64; 2]>,
    /// Further drives by name (`[tours.NAME]`), for a world whose rooms
    /// a loop driven forwards cannot reach.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub tours: BTreeMap<String, TourSpec>,
}

/// A closed loop of waypoints, some legs of it driven backwards: the way
/// out of a room too narrow to turn in is the way in, reversed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TourSpec {
    /// Waypoints of the rear axle's middle, m; the last leads to the first.
    pub points: Vec<[f64; 2]>,
    /// Legs driven backwards: leg `i` runs from point `i` to point `i + 1`.
    #[serde(default)]
    pub reverse: Vec<usize>,
}

impl TourSpec {
    /// A loop driven forwards all the way.
    pub fn forwards(points: Vec<[f64; 2]>) -> Self {
        TourSpec {
            points,
            reverse: Vec::new(),
        }
    }
}

/// The robot's start pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotStart {
    /// Position of the rear axle's middle, m.
    pub at: [f64; 2],
    /// Heading, degrees.
    pub heading_deg: f64,
}

/// A room: a polygon of walls, listed counter-clockwise as seen from above;
/// wall `i` runs from corner `i` to corner `i + 1`. Each wall's inner face
/// lies on the polygon; its thickness is outside.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomSpec {
    /// Name, used by doors, windows and radiators to find the room.
    pub name: String,
    /// Corners, m.
    pub corners: Vec<[f64; 2]>,
    /// Height of walls and ceiling, m.
    #[serde(default = "default_height")]
    pub height_m: f64,
    /// Thickness of the walls, m.
    #[serde(default = "default_thickness")]
    pub wall_thickness_m: f64,
    /// Walls (by index) that another room already builds (the shared wall
    /// between two rooms is built once); they still bound this room.
    #[serde(default)]
    pub shared_walls: Vec<usize>,
}

fn default_height() -> f64 {
    2.6
}
fn default_thickness() -> f64 {
    0.15
}

/// A door in a wall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DoorSpec {
    /// The room whose wall it is in.
    pub room: String,
    /// The wall, by index in the room's corners.
    pub wall: usize,
    /// Distance from the wall's first corner to the opening, m.
    pub offset_m: f64,
    /// Width of the opening, m.
    pub width_m: f64,
    /// Height of the opening, m.
    #[serde(default = "default_door_height")]
    pub height_m: f64,
    /// Open (passable) or closed (its leaf fills the opening).
    #[serde(default = "default_true")]
    pub open: bool,
}

fn default_door_height() -> f64 {
    2.0
}
fn default_true() -> bool {
    true
}

/// A window in a wall: a hole from `sill_m` to `head_m` above the floor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowSpec {
    /// The room whose wall it is in.
    pub room: String,
    /// The wall, by index in the room's corners.
    pub wall: usize,
    /// Distance from the wall's first corner to the opening, m.
    pub offset_m: f64,
    /// Width of the opening, m.
    pub width_m: f64,
    /// Height of the sill above the floor, m.
    pub sill_m: f64,
    /// Height of the head above the floor, m.
    pub head_m: f64,
    /// Glazed: glass returns the laser only near normal incidence.
    #[serde(default)]
    pub glazed: bool,
}

/// A table or a chair: a top on four legs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// Centre, m.
    pub at: [f64; 2],
    /// Length and width of the top, m.
    pub size_m: [f64; 2],
    /// Heading of the length, degrees.
    #[serde(default)]
    pub heading_deg: f64,
    /// Height of the top, m.
    #[serde(default = "default_table_height")]
    pub height_m: f64,
    /// Radius of the legs, m.
    #[serde(default = "default_leg")]
    pub leg_radius_m: f64,
}

fn default_table_height() -> f64 {
    0.75
}
fn default_leg() -> f64 {
    0.025
}

/// A box on the floor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Centre, m.
    pub at: [f64; 2],
    /// Length and width, m.
    pub size_m: [f64; 2],
    /// Heading of the length, degrees.
    #[serde(default)]
    pub heading_deg: f64,
    /// Height, m.
    pub height_m: f64,
}

/// A radiator on a wall: a box standing `gap_m` off the wall's face.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiatorSpec {
    /// The room whose wall it is on.
    pub room: String,
    /// The wall, by index in the room's corners.
    pub wall: usize,
    /// Distance from the wall's first corner to the radiator, m.
    pub offset_m: f64,
    /// Length along the wall, m.
    pub length_m: f64,
    /// Gap between the wall and the radiator, m.
    #[serde(default = "default_gap")]
    pub gap_m: f64,
    /// Depth, m.
    #[serde(default = "default_depth")]
    pub depth_m: f64,
    /// Bottom and top above the floor, m.
    #[serde(default = "default_radiator_span")]
    pub span_m: [f64; 2],
}

fn default_gap() -> f64 {
    0.04
}
fn default_depth() -> f64 {
    0.06
}
fn default_radiator_span() -> [f64; 2] {
    [0.1, 0.7]
}

/// A round column from floor to ceiling.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnSpec {
    /// Centre, m.
    pub at: [f64; 2],
    /// Radius, m.
    pub radius_m: f64,
    /// Height, m.
    #[serde(default = "default_height")]
    pub height_m: f64,
}

/// A person walking a closed path of waypoints, forever.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersonSpec {
    /// Waypoints, m; the last leads back to the first.
    pub path: Vec<[f64; 2]>,
    /// Walking speed, m/s.
    #[serde(default = "default_walk")]
    pub speed_mps: f64,
}

fn default_walk() -> f64 {
    1.2
}

impl WorldSpec {
    /// Reads and checks the world file at `path`.
    pub fn load(path: &Path) -> Result<WorldSpec, SimError> {
        let text = std::fs::read_to_string(path).map_err(|source| SimError::Read {
            path: path.display().to_string(),
            source,
        })?;
        WorldSpec::parse(&text, &path.display().to_string())
    }

    /// Parses and checks a world from `text`; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<WorldSpec, SimError> {
        let world: WorldSpec = toml::from_str(text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|s| stucco_core::line_column(text, s.start))
                .unwrap_or((0, 0));
            SimError::Syntax {
                origin: origin.to_owned(),
                line,
                column,
                message: e.message().to_owned(),
            }
        })?;
        // TOML reads `nan` and `inf`: no length, place or speed is one.
        if let Some(bad) = stucco_core::first_non_finite(text) {
            return Err(SimError::Invalid {
                origin: origin.to_owned(),
                line: bad.line,
                field: bad.field,
                reason: "numbers must be finite".to_owned(),
            });
        }
        world.check().map_err(|(field, reason)| SimError::Invalid {
            origin: origin.to_owned(),
            line: find_line(text, &field),
            field,
            reason,
        })?;
        Ok(world)
    }

    /// Checks what the types alone cannot: geometry that makes sense and
    /// names that resolve. On failure, the offending field and why.
    fn check(&self) -> Result<(), (String, String)> {
        let bad = |field: String, reason: &str| Err((field, reason.to_owned()));
        if self.rooms.is_empty() {
            return bad("room".into(), "a world needs at least one room");
        }
        for (i, r) in self.rooms.iter().enumerate() {
            if r.corners.len() < 3 {
                return bad(
                    format!("room[{i}].corners"),
                    "a room needs 3 corners or more",
                );
            }
            if signed_area(&r.corners) <= 0.0 {
                return bad(
                    format!("room[{i}].corners"),
                    "corners must run counter-clockwise and enclose an area",
                );
            }
            if !(r.height_m > 0.0 && r.wall_thickness_m > 0.0) {
                return bad(
                    format!("room[{i}].height_m"),
                    "height and wall thickness must be positive",
                );
            }
            if r.shared_walls.iter().any(|&w| w >= r.corners.len()) {
                return bad(format!("room[{i}].shared_walls"), "no such wall");
            }
        }
        let wall_len = |room: &str, wall: usize| -> Option<f64> {
            let r = self.rooms.iter().find(|r| r.name == room)?;
            let a = r.corners.get(wall)?;
            let b = r.corners[(wall + 1) % r.corners.len()];
            Some((b[0] - a[0]).hypot(b[1] - a[1]))
        };
        let on_wall =
            |kind: &str, i: usize, room: &str, wall: usize, offset: f64, len: f64| match wall_len(
                room, wall,
            ) {
                None => bad(format!("{kind}[{i}].wall"), "no such room or wall"),
                Some(l) if offset < 0.0 || len <= 0.0 || offset + len > l + 1e-9 => bad(
                    format!("{kind}[{i}].offset_m"),
                    "the opening must lie within its wall",
                ),
                Some(_) => Ok(()),
            };
        for (i, d) in self.doors.iter().enumerate() {
            on_wall("door", i, &d.room, d.wall, d.offset_m, d.width_m)?;
        }
        for (i, w) in self.windows.iter().enumerate() {
            on_wall("window", i, &w.room, w.wall, w.offset_m, w.width_m)?;
            if !(0.0 <= w.sill_m && w.sill_m < w.head_m) {
                return bad(
                    format!("window[{i}].sill_m"),
                    "the sill must lie below the head",
                );
            }
        }
        for (i, r) in self.radiators.iter().enumerate() {
            on_wall("radiator", i, &r.room, r.wall, r.offset_m, r.length_m)?;
        }
        for (i, p) in self.people.iter().enumerate() {
            if p.path.len() < 2 || p.speed_mps <= 0.0 {
                return bad(
                    format!("person[{i}].path"),
                    "a person walks a path of 2 points or more at a positive speed",
                );
            }
        }
        for (name, t) in &self.tours {
            if t.points.len() < 2 {
                return bad(
                    format!("tours.{name}.points"),
                    "a tour needs 2 points or more",
                );
            }
            if t.reverse.iter().any(|&l| l >= t.points.len()) {
                return bad(
                    format!("tours.{name}.reverse"),
                    "no such leg: leg i runs from point i to point i + 1",
                );
            }
        }
        Ok(())
    }

    /// The tour called `name`; `tour` is the world's own loop.
    pub fn tour_named(&self, name: &str) -> Option<TourSpec> {
        if name == "tour" {
            return Some(TourSpec::forwards(self.tour.clone()));
        }
        self.tours.get(name).cloned()
    }
}

/// Twice the signed area of a polygon (positive when counter-clockwise).
pub(crate) fn signed_area(c: &[[f64; 2]]) -> f64 {
    (0..c.len())
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// The line of the table `field` names (`door[2].wall` → the third
/// `[[door]]`, `tours.hall.reverse` → `[tours.hall]`, `tour` → its key's
/// line in the top table), 0 when it cannot be told.
fn find_line(text: &str, field: &str) -> usize {
    if !field.contains(['.', '['])
        && let Some(i) = text
            .lines()
            .take_while(|l| !l.trim_start().starts_with('['))
            .position(|l| l.split_once('=').is_some_and(|(k, _)| k.trim() == field))
    {
        return i + 1;
    }
    if !field.contains('[')
        && let Some((table, _)) = field.rsplit_once('.')
    {
        let header = format!("[{table}]");
        return text
            .lines()
            .position(|l| l.trim() == header)
            .map_or(0, |i| i + 1);
    }
    let (table, index) = match field.split_once('[') {
        Some((t, rest)) => (t, rest.split(']').next().and_then(|n| n.parse().ok())),
        None => (field, Some(0)),
    };
    let header = format!("[[{table}]]");
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == header)
        .nth(index.unwrap_or(0))
        .map_or(0, |(i, _)| i + 1)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;

    const ROOM: &str = r#"
name = "box"
seed = 1
tour = [[1.0, 1.0], [3.0, 1.0]]

[robot]
at = [1.0, 1.0]
heading_deg = 0.0

[[room]]
name = "a"
corners = [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]]

[[door]]
room = "a"
wall = 1
offset_m = 1.0
width_m = 0.9
"#;

    #[test]
    fn a_room_with_a_door_parses() {
        let w = WorldSpec::parse(ROOM, "box.toml").unwrap();
        assert_eq!(w.rooms[0].corners.len(), 4);
        assert!(w.doors[0].open);
        assert_eq!(w.rooms[0].wall_thickness_m, 0.15);
    }

    #[test]
    fn a_misspelt_key_names_file_line_and_key() {
        let text = ROOM.replace("width_m = 0.9", "widht_m = 0.9");
        let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
        assert!(err.contains("box.toml:18"), "{err}");
        assert!(err.contains("widht_m"), "{err}");
    }

    #[test]
    fn a_door_outside_its_wall_is_refused_with_its_table() {
        let text = ROOM.replace("offset_m = 1.0", "offset_m = 2.5");
        let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
        assert!(
            err.contains("box.toml:14") && err.contains("door[0].offset_m"),
            "{err}"
        );
    }

    #[test]
    fn clockwise_corners_are_refused() {
        let text = ROOM.replace(
            "[[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]]",
            "[[0.0, 0.0], [0.0, 3.0], [4.0, 3.0], [4.0, 0.0]]",
        );
        let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
        assert!(err.contains("room[0].corners"), "{err}");
    }

    #[test]
    fn a_named_tour_with_a_leg_it_lacks_is_refused_at_its_table() {
        let text =
            format!("{ROOM}\n[tours.back]\npoints = [[1.0, 1.0], [3.0, 1.0]]\nreverse = [1]\n");
        let w = WorldSpec::parse(&text, "box.toml").unwrap();
        assert_eq!(w.tour_named("back").unwrap().reverse, [1]);
        assert_eq!(w.tour_named("tour").unwrap().points, w.tour);
        assert!(w.tour_named("front").is_none());
        let text = text.replace("reverse = [1]", "reverse = [2]");
        let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
        assert!(
            err.contains("box.toml:20") && err.contains("tours.back.reverse"),
            "{err}"
        );
    }

    #[test]
    fn a_number_that_is_no_number_is_refused_at_its_line() {
        let text = ROOM.replace(
            "tour = [[1.0, 1.0], [3.0, 1.0]]",
            "tour = [[1.0, 1.0], [nan, 1.0]]",
        );
        let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
        let line = ROOM.lines().position(|l| l.starts_with("tour =")).unwrap() + 1;
        assert!(
            err.contains(&format!("box.toml:{line}")) && err.contains("finite"),
            "{err}"
        );
        let text = format!("{ROOM}\n[tours.back]\npoints = [[1.0, 1.0], [3.0, inf]]\n");
        let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
        let line = text
            .lines()
            .position(|l| l.starts_with("points ="))
            .unwrap()
            + 1;
        assert!(
            err.contains(&format!("box.toml:{line}")) && err.contains("tours.back.points"),
            "{err}"
        );
        // Not only tours: a room's corner, a door's place, each at its
        // number's own line.
        for (from, to, field) in [
            (
                "[4.0, 3.0], [0.0, 3.0]]",
                "[4.0, nan], [0.0, 3.0]]",
                "room[0].corners",
            ),
            ("offset_m = 1.0", "offset_m = nan", "door[0].offset_m"),
        ] {
            let text = ROOM.replace(from, to);
            let line = text.lines().position(|l| l.contains("nan")).unwrap() + 1;
            let err = WorldSpec::parse(&text, "box.toml").unwrap_err().to_string();
            assert!(
                err.contains(&format!("box.toml:{line}")) && err.contains(field),
                "{err}"
            );
        }
    }
}
