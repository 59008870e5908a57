//! The operator's side of the robot: the walls of a room by name, the
//! telecommands of the semiautonomous vocabulary (each naming things the
//! robot perceives, never bare coordinates to hit blindly), and the
//! robot's replies.

use crate::Stamp;
use serde::{Deserialize, Serialize};

/// A wall of a room, by its index in the room.
///
/// A room drawn by its corners (counter-clockwise) has its walls numbered
/// from 0, wall `k` running from corner `k` to corner `k + 1`. A
/// rectangular room, whose frame has its origin in the south-west corner,
/// x east and y north, as the room filter keeps it, has walls 0 (`x = 0`,
/// west), 1 (`y = 0`, south), 2 (`x = xs`, east) and 3 (`y = ys`,
/// north).
///
/// Files and telecommands give a wall by its index (`1`) or, in a
/// rectangular room, by its compass name (`"south"`); reports give the
/// index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct WallName(u16);

impl WallName {
    /// `x = 0` of a rectangular room.
    pub const WEST: WallName = WallName(0);
    /// `y = 0` of a rectangular room.
    pub const SOUTH: WallName = WallName(1);
    /// `x = xs` of a rectangular room.
    pub const EAST: WallName = WallName(2);
    /// `y = ys` of a rectangular room.
    pub const NORTH: WallName = WallName(3);

    /// The four walls of a rectangular room, in the room filter's order.
    pub const ALL: [WallName; 4] = [
        WallName::WEST,
        WallName::SOUTH,
        WallName::EAST,
        WallName::NORTH,
    ];

    /// The compass names of a rectangular room's walls, by index.
    pub const COMPASS: [&'static str; 4] = ["west", "south", "east", "north"];

    /// Wall `index` of its room.
    ///
    /// # Panics
    /// When `index` does not fit in 16 bits: no room has that many walls.
    pub fn new(index: usize) -> WallName {
        WallName(u16::try_from(index).unwrap_or_else(|_| panic!("wall index {index} too large")))
    }

    /// Its index in the room.
    pub fn index(self) -> usize {
        usize::from(self.0)
    }

    /// Wall `i` of its room, when `i` fits in 16 bits.
    pub fn from_index(i: usize) -> Option<WallName> {
        u16::try_from(i).ok().map(WallName)
    }

    /// The wall a rectangular room's compass name names.
    pub fn compass(name: &str) -> Option<WallName> {
        WallName::COMPASS
            .iter()
            .position(|&c| c == name)
            .map(WallName::new)
    }

    /// Its compass name, were it a rectangular room's.
    pub fn compass_name(self) -> Option<&'static str> {
        WallName::COMPASS.get(self.index()).copied()
    }
}

impl std::fmt::Display for WallName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "wall {}", self.0)
    }
}

/// `"1"` or, in a rectangular room, `"south"`.
impl std::str::FromStr for WallName {
    type Err = String;

    fn from_str(s: &str) -> Result<WallName, String> {
        match s.parse::<u16>() {
            Ok(i) => Ok(WallName(i)),
            Err(_) => WallName::compass(s).ok_or_else(|| {
                format!(
                    "{s}: a wall's index (0, 1, ...) or, in a rectangular room, west, south, \
                     east or north"
                )
            }),
        }
    }
}

impl Serialize for WallName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u16(self.0)
    }
}

impl<'de> Deserialize<'de> for WallName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<WallName, D::Error> {
        struct Visit;
        impl serde::de::Visitor<'_> for Visit {
            type Value = WallName;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a wall's index in its room (0, 1, ...) or, in a rectangular room, `west`, `south`, `east` or `north`")
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<WallName, E> {
                u16::try_from(v)
                    .map(WallName)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Unsigned(v), &self))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<WallName, E> {
                u16::try_from(v)
                    .map(WallName)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<WallName, E> {
                WallName::compass(v).ok_or_else(|| E::unknown_variant(v, &WallName::COMPASS))
            }
        }
        d.deserialize_any(Visit)
    }
}

/// Which side of the robot a wall is on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// On the robot's left.
    #[default]
    Left,
    /// On its right.
    Right,
}

/// A command from the operator, with who sent it, when, and until when it
/// may still be carried out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Telecommand {
    /// Its id: a command retried with the same id is carried out once.
    pub id: String,
    /// The operator's identity.
    pub operator: String,
    /// When it was issued (the operator's clock, synchronised).
    pub issued: Stamp,
    /// Past this it is stale and refused.
    pub deadline: Stamp,
    /// What to do.
    pub command: Command,
}

/// The telecommand vocabulary (`../shared/DESIGN.md`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    /// Map the room the robot is in.
    MapRoom,
    /// Drive through a door the robot knows (by its index).
    PassDoor {
        /// The door.
        door: usize,
    },
    /// Go to a room of the floor plan (by its name), through the doors
    /// the plan's shortest way takes.
    GoToRoom {
        /// The room.
        room: String,
    },
    /// Follow a wall at a standoff between two positions along it.
    FollowWall {
        /// The wall.
        wall: WallName,
        /// Distance from the wall, m.
        standoff_m: f64,
        /// Where the pass starts along the wall, m.
        from_m: f64,
        /// Where it ends, m.
        to_m: f64,
    },
    /// Move by `(dx, dy, dθ)` in the robot's frame, or to `(dx, dy, dθ)`
    /// in a landmark's frame (see [`Landmark`]).
    MoveRelative {
        /// Forward, m.
        dx_m: f64,
        /// To the left, m.
        dy_m: f64,
        /// Turn, degrees.
        dtheta_deg: f64,
        /// The thing the move is relative to (the robot, without it).
        #[serde(default)]
        landmark: Option<Landmark>,
    },
    /// Stop parallel to a wall at a standoff.
    AlignToWall {
        /// The wall.
        wall: WallName,
        /// Distance from it, m.
        standoff_m: f64,
        /// Position along it, m.
        at_m: f64,
        /// The side it ends up on.
        side: Side,
    },
    /// Stop where you are and wait.
    Pause,
    /// Go on.
    Resume,
    /// Give the mission up.
    Abort,
    /// Give the current task up.
    Skip,
    /// The answer a waiting task waits for.
    Continue,
    /// Stop now: the e-stop lane, never queued behind anything.
    Stop,
    /// Drive directly for `ttl_s`, then stop (a dead-man timeout).
    Jog {
        /// Front-wheel speed, m/s.
        speed_mps: f64,
        /// Steering angle, rad.
        steer_rad: f64,
        /// How long the command holds, s.
        ttl_s: f64,
    },
    /// Plaster one surface of the room the robot is in, whole: the robot
    /// surveys the room, plans on what it finds and sprays (the mission's
    /// spray tool and settings).
    PlasterSurface {
        /// The surface, as `map` and `coverage` name it.
        surface: SurfaceId,
        /// Only this part of it (a wall's), when given.
        #[serde(default)]
        region: Option<Region>,
    },
    /// A harmless query: replied to at once.
    Status,
}

/// Something the robot perceives that a move may be relative to
/// (`{"wall": "south"}`, `{"door": 0}`). Its frame faces it from inside
/// the room: the origin at its middle (a door's middle, the middle of a
/// wall) on the wall's line, x toward it (out of the room), y to the left.
/// `dx = -1.0` with a door stands the robot a metre before it, facing it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Landmark {
    /// A wall of the room.
    Wall(WallName),
    /// A door the robot knows, by its index.
    Door(usize),
}

/// A part of a wall: the rectangle between two positions along it and
/// two heights above the floor (`{"along_m": [1.0, 2.5], "height_m": [0.0,
/// 1.2]}`). Plastered, it is coated inside and left bare outside, less the
/// tool's margin at its edges as at a window's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    /// From and to along the wall's axis, m.
    pub along_m: [f64; 2],
    /// From and to above the floor, m.
    pub height_m: [f64; 2],
}

/// A surface of a room: a wall or the ceiling (`{"wall": 1}`, in a
/// rectangular room also `{"wall": "south"}`; `"ceiling"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceId {
    /// A wall.
    Wall(WallName),
    /// The ceiling.
    Ceiling,
}

impl SurfaceId {
    /// The five surfaces of a rectangular room.
    pub const ALL: [SurfaceId; 5] = [
        SurfaceId::Wall(WallName::WEST),
        SurfaceId::Wall(WallName::SOUTH),
        SurfaceId::Wall(WallName::EAST),
        SurfaceId::Wall(WallName::NORTH),
        SurfaceId::Ceiling,
    ];

    /// A short name for reports and file names (`wall 1`, `ceiling`).
    pub fn name(self) -> String {
        match self {
            SurfaceId::Wall(w) => w.to_string(),
            SurfaceId::Ceiling => "ceiling".to_owned(),
        }
    }
}

/// What the operator (or a script standing in for one) asks of the
/// executive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OperatorCommand {
    /// Stop where you are and wait.
    Pause,
    /// Go on after a pause or a released e-stop.
    Resume,
    /// Give the mission up.
    Abort,
    /// Give the current task up and go on with the next.
    Skip,
    /// The answer a `wait_for_operator` task waits for.
    Continue,
}

/// The robot's reply to a telecommand.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "reply", rename_all = "snake_case", deny_unknown_fields)]
pub enum Reply {
    /// Taken: it will be carried out.
    Accepted,
    /// Refused, and why.
    Rejected {
        /// Why.
        reason: String,
    },
    /// Carried out.
    Done,
    /// Tried and failed, and why.
    Failed {
        /// Why, in a sentence.
        reason: String,
        /// The kind of failure, for programs (a task's failure code, such
        /// as `way_blocked`); absent from older robots.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        code: Option<String>,
    },
}

impl Reply {
    /// Failed for `reason`, of the kind `code`.
    pub fn failed(code: &str, reason: impl Into<String>) -> Reply {
        Reply::Failed {
            reason: reason.into(),
            code: Some(code.to_owned()),
        }
    }
}

/// A reply to the telecommand `id`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ack {
    /// The command's id.
    pub id: String,
    /// When the robot replied.
    pub stamp: Stamp,
    /// The reply.
    pub reply: Reply,
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// `plaster_surface` names a wall or the ceiling; anything else is
    /// refused naming the value and what was expected (inside the tagged
    /// `command` serde keeps no line and column).
    #[test]
    fn a_surface_is_a_wall_or_the_ceiling() {
        let read = |surface: &str| {
            serde_json::from_str::<Command>(&format!(
                "{{\"type\": \"plaster_surface\",\n \"surface\": {surface}}}"
            ))
        };
        assert_eq!(
            read(r#"{"wall": "south"}"#).unwrap(),
            Command::PlasterSurface {
                surface: SurfaceId::Wall(WallName::SOUTH),
                region: None,
            }
        );
        assert_eq!(
            read(r#""ceiling""#).unwrap(),
            Command::PlasterSurface {
                surface: SurfaceId::Ceiling,
                region: None,
            }
        );
        for (bad, named, expected) in [
            (r#""floor""#, "`floor`", "`ceiling`"),
            (r#"{"wall": "up"}"#, "`up`", "`south`"),
        ] {
            let e = read(bad).unwrap_err().to_string();
            assert!(e.contains(named) && e.contains(expected), "{e}");
        }
    }

    /// A wall is its index in its room, or in a rectangular room its
    /// compass name; it is written as its index. Anything else is refused
    /// naming the value.
    #[test]
    fn a_wall_is_named_by_its_index_or_its_compass_name() {
        let read = |v: &str| serde_json::from_str::<SurfaceId>(&format!("{{\"wall\": {v}}}"));
        assert_eq!(read("1").unwrap(), SurfaceId::Wall(WallName::SOUTH));
        assert_eq!(read("\"south\"").unwrap(), SurfaceId::Wall(WallName::SOUTH));
        assert_eq!(read("6").unwrap(), SurfaceId::Wall(WallName::new(6)));
        assert_eq!(
            serde_json::to_string(&SurfaceId::Wall(WallName::NORTH)).unwrap(),
            r#"{"wall":3}"#
        );
        for (bad, named) in [("-1", "-1"), ("70000", "70000"), ("\"up\"", "`up`")] {
            let e = read(bad).unwrap_err().to_string();
            assert!(e.contains(named), "{e}");
        }
        let toml: std::collections::BTreeMap<String, WallName> =
            toml::from_str("a = 2\nb = \"west\"").unwrap();
        assert_eq!(toml["a"], WallName::EAST);
        assert_eq!(toml["b"], WallName::WEST);
        assert_eq!(WallName::new(4).to_string(), "wall 4");
        assert_eq!(WallName::new(4).compass_name(), None);
    }

    /// A region and a landmark are read with their fields; a field they
    /// do not have, or a landmark that is not one, is refused naming it.
    #[test]
    fn a_region_and_a_landmark_name_what_is_wrong() {
        let plaster = |region: &str| {
            serde_json::from_str::<Command>(&format!(
                r#"{{"type": "plaster_surface", "surface": {{"wall": "south"}}, "region": {region}}}"#
            ))
        };
        assert_eq!(
            plaster(r#"{"along_m": [1.0, 2.5], "height_m": [0.0, 1.2]}"#).unwrap(),
            Command::PlasterSurface {
                surface: SurfaceId::Wall(WallName::SOUTH),
                region: Some(Region {
                    along_m: [1.0, 2.5],
                    height_m: [0.0, 1.2],
                }),
            }
        );
        let e = plaster(r#"{"along_m": [1.0, 2.5], "height": [0.0, 1.2]}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("`height`") && e.contains("`height_m`"), "{e}");
        let e = plaster(r#"{"along_m": [1.0, 2.5]}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("`height_m`"), "{e}");
        let moving = |landmark: &str| {
            serde_json::from_str::<Command>(&format!(
                r#"{{"type": "move_relative", "dx_m": -1.0, "dy_m": 0.0, "dtheta_deg": 0.0, "landmark": {landmark}}}"#
            ))
        };
        assert!(matches!(
            moving(r#"{"door": 2}"#).unwrap(),
            Command::MoveRelative {
                landmark: Some(Landmark::Door(2)),
                ..
            }
        ));
        let e = moving(r#"{"window": 1}"#).unwrap_err().to_string();
        assert!(e.contains("`window`") && e.contains("`door`"), "{e}");
    }

    #[test]
    fn telecommands_read_as_json_any_client_can_write() {
        let t: Telecommand = serde_json::from_str(
            r#"{"id":"c7","operator":"ann","issued":0,"deadline":5000000000,
                "command":{"type":"follow_wall","wall":"south","standoff_m":0.6,"from_m":2.0,"to_m":4.0}}"#,
        )
        .unwrap();
        assert_eq!(t.deadline, Stamp::from_secs_f64(5.0));
        assert!(matches!(
            t.command,
            Command::FollowWall {
                wall: WallName::SOUTH,
                ..
            }
        ));
        let back: Telecommand = serde_json::from_str(&serde_json::to_string(&t).unwrap()).unwrap();
        assert_eq!(back, t);
        let bad = serde_json::from_str::<Telecommand>(
            r#"{"id":"c8","operator":"ann","issued":0,"deadline":1,"command":{"type":"fly"}}"#,
        );
        assert!(bad.is_err());
        let ack = Ack {
            id: "c7".into(),
            stamp: Stamp::ZERO,
            reply: Reply::Rejected {
                reason: "stale".into(),
            },
        };
        assert_eq!(
            serde_json::to_string(&ack).unwrap(),
            r#"{"id":"c7","stamp":0,"reply":{"reply":"rejected","reason":"stale"}}"#
        );
    }
}
