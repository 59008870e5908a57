//! The surfaces of a room to plaster: each wall and the ceiling as a
//! rectangle in its own `(u, v)` plane, its doors and windows as holes.
//!
//! The room frame is the room filter's: origin in the south-west corner,
//! x east, y north. A wall's `u` runs along it the way the room filter's
//! positions do (x for the south and north walls, y for the west and east
//! walls), `v` up from the floor. The ceiling's `u, v` are the room's
//! `x, y`.

use crate::SprayTool;
use crate::outline::Outline;
use nalgebra::{Point2, Point3, Vector2, Vector3};
use serde::{Deserialize, Serialize};
pub use stucco_core::{Obstacle, SurfaceId};
use stucco_core::{SurfaceFrame, WallName};

/// An axis-aligned rectangle of a surface's plane, m.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rect {
    /// From and to along `u`.
    pub u_m: [f64; 2],
    /// From and to along `v`.
    pub v_m: [f64; 2],
}

impl Rect {
    /// True when `p` lies inside or on the border.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        p[0] >= self.u_m[0] && p[0] <= self.u_m[1] && p[1] >= self.v_m[0] && p[1] <= self.v_m[1]
    }

    /// True when `p` lies strictly inside.
    pub fn contains_strictly(&self, p: [f64; 2]) -> bool {
        p[0] > self.u_m[0] && p[0] < self.u_m[1] && p[1] > self.v_m[0] && p[1] < self.v_m[1]
    }

    /// The rectangle grown by `d_m` on every side.
    pub fn grown(&self, d_m: f64) -> Rect {
        Rect {
            u_m: [self.u_m[0] - d_m, self.u_m[1] + d_m],
            v_m: [self.v_m[0] - d_m, self.v_m[1] + d_m],
        }
    }

    /// The smallest rectangle holding both.
    pub fn union(&self, other: &Rect) -> Rect {
        Rect {
            u_m: [self.u_m[0].min(other.u_m[0]), self.u_m[1].max(other.u_m[1])],
            v_m: [self.v_m[0].min(other.v_m[0]), self.v_m[1].max(other.v_m[1])],
        }
    }

    /// True when the two share more than a border.
    pub fn overlaps(&self, other: &Rect) -> bool {
        self.u_m[0] < other.u_m[1]
            && other.u_m[0] < self.u_m[1]
            && self.v_m[0] < other.v_m[1]
            && other.v_m[0] < self.v_m[1]
    }

    /// The part `[t0, t1]` of the segment from `a` to `b` (as fractions
    /// of it) that lies inside, if any (Liang–Barsky).
    pub fn clip(&self, a: [f64; 2], b: [f64; 2]) -> Option<[f64; 2]> {
        let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
        for k in 0..2 {
            let (lo, hi) = if k == 0 {
                (self.u_m[0], self.u_m[1])
            } else {
                (self.v_m[0], self.v_m[1])
            };
            let d = b[k] - a[k];
            if d.abs() < 1e-12 {
                if a[k] < lo || a[k] > hi {
                    return None;
                }
                continue;
            }
            let (mut e0, mut e1) = ((lo - a[k]) / d, (hi - a[k]) / d);
            if e0 > e1 {
                std::mem::swap(&mut e0, &mut e1);
            }
            t0 = t0.max(e0);
            t1 = t1.min(e1);
        }
        (t0 < t1).then_some([t0, t1])
    }

    /// Area, m².
    pub fn area_m2(&self) -> f64 {
        (self.u_m[1] - self.u_m[0]).max(0.0) * (self.v_m[1] - self.v_m[0]).max(0.0)
    }
}

/// What an opening is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpeningKind {
    /// A door: from the floor up.
    Door,
    /// A door the building's drawing gives that is kept shut: not
    /// plastered, and no way through.
    ShutDoor,
    /// A window: from its sill to its head.
    Window,
}

/// A hole in a surface.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Opening {
    /// Door or window.
    pub kind: OpeningKind,
    /// The hole, in the surface's frame.
    pub rect: Rect,
}

/// An opening in a wall of the room, as the map knows it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallOpening {
    /// The wall.
    pub wall: WallName,
    /// Door or window.
    pub kind: OpeningKind,
    /// Its edges along the wall, m.
    pub along_m: [f64; 2],
    /// Its bottom and top above the floor, m (a door's bottom is 0).
    pub sill_head_m: [f64; 2],
}

/// A room as the map knows it: what the planner plans on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomModel {
    /// Size along x and y, m: the room's box, from the origin.
    pub size_m: [f64; 2],
    /// The floor's corners, counter-clockwise in the room frame and within
    /// its box, when the room is not the rectangle `size_m`: wall `k` runs
    /// from corner `k` to corner `k + 1`. Empty for a rectangle, whose
    /// walls are the room filter's four (see [`WallName`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub corners: Vec<[f64; 2]>,
    /// Height of the ceiling, m.
    pub height_m: f64,
    /// Doors and windows.
    pub openings: Vec<WallOpening>,
    /// Furniture and anything else on the floor.
    pub obstacles: Vec<Obstacle>,
}

/// A wall of a room in the plane: where its axis starts, which way it
/// runs and its normal into the room.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallLine {
    /// The point at position 0 along the wall.
    pub origin: Vector2<f64>,
    /// Unit vector along it.
    pub along: Vector2<f64>,
    /// Unit normal into the room.
    pub inward: Vector2<f64>,
    /// Its length, m.
    pub length_m: f64,
}

impl WallLine {
    /// Wall `w` of a rectangular room `size_m` in size, which has four.
    pub fn of(w: WallName, size_m: [f64; 2]) -> Option<WallLine> {
        let [xs, ys] = size_m;
        let (o, a, n, l) = match w {
            WallName::WEST => ([0.0, 0.0], [0.0, 1.0], [1.0, 0.0], ys),
            WallName::SOUTH => ([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], xs),
            WallName::EAST => ([xs, 0.0], [0.0, 1.0], [-1.0, 0.0], ys),
            WallName::NORTH => ([0.0, ys], [1.0, 0.0], [0.0, -1.0], xs),
            _ => return None,
        };
        Some(WallLine {
            origin: Vector2::new(o[0], o[1]),
            along: Vector2::new(a[0], a[1]),
            inward: Vector2::new(n[0], n[1]),
            length_m: l,
        })
    }

    /// The walls of a room given by its `corners` (counter-clockwise, wall
    /// `k` from corner `k`), or when there are none the rectangle
    /// `size_m`'s four.
    pub fn of_room(corners: &[[f64; 2]], size_m: [f64; 2]) -> Vec<WallLine> {
        if corners.is_empty() {
            WallName::ALL
                .iter()
                .filter_map(|&w| WallLine::of(w, size_m))
                .collect()
        } else {
            let n = corners.len();
            (0..n)
                .map(|k| WallLine::between(corners[k], corners[(k + 1) % n]))
                .collect()
        }
    }

    /// The wall from corner `a` to corner `b` of a room whose corners run
    /// counter-clockwise (the room on its left).
    pub fn between(a: [f64; 2], b: [f64; 2]) -> WallLine {
        let d = Vector2::new(b[0] - a[0], b[1] - a[1]);
        let length_m = d.norm();
        let along = if length_m > 0.0 {
            d / length_m
        } else {
            Vector2::x()
        };
        WallLine {
            origin: Vector2::new(a[0], a[1]),
            along,
            inward: Vector2::new(-along.y, along.x),
            length_m,
        }
    }

    /// The point `off_m` into the room at `at_m` along the wall.
    pub fn point(&self, at_m: f64, off_m: f64) -> Vector2<f64> {
        self.origin + self.along * at_m + self.inward * off_m
    }

    /// The heading that keeps the wall on the robot's left.
    pub fn heading_wall_left(&self) -> f64 {
        // Left of heading h is h turned +90°, and must be −inward.
        (self.inward.x).atan2(-self.inward.y)
    }
}

/// A surface to plaster, with its holes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Surface {
    /// Which surface.
    pub id: SurfaceId,
    /// Its plane and extent in the room frame.
    pub frame: SurfaceFrame,
    /// Doors and windows in it.
    pub openings: Vec<Opening>,
    /// Its edge, counter-clockwise in `(u, v)`, when it is not the
    /// rectangle of its size (the ceiling of a room that is not a
    /// rectangle); empty otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outline: Vec<[f64; 2]>,
}

impl Surface {
    /// True for the ceiling.
    pub fn is_ceiling(&self) -> bool {
        self.id == SurfaceId::Ceiling
    }

    /// Extent along `u` and `v`, m.
    pub fn size_m(&self) -> [f64; 2] {
        self.frame.size_m
    }

    /// The part of the surface the tool is to coat, before reach: the
    /// surface less its edge bands (and the skirting on a wall).
    pub fn field(&self, tool: &SprayTool) -> Rect {
        let [su, sv] = self.size_m();
        let e = tool.edge_margin_m;
        let bottom = if self.is_ceiling() {
            e
        } else {
            tool.skirting_m
        };
        Rect {
            u_m: [e, su - e],
            v_m: [bottom, sv - e],
        }
    }

    /// True when `p` is to be coated: inside the field and clear of every
    /// opening's margin.
    pub fn plasterable(&self, p: [f64; 2], tool: &SprayTool) -> bool {
        self.field(tool).contains(p)
            && (self.outline.is_empty()
                || Outline::new(&self.outline).clearance_m(&Point2::new(p[0], p[1]))
                    >= tool.edge_margin_m)
            && !self
                .openings
                .iter()
                .any(|o| o.rect.grown(tool.opening_margin_m).contains_strictly(p))
    }

    /// True when `p` is in one of the holes.
    pub fn in_opening(&self, p: [f64; 2]) -> bool {
        self.openings.iter().any(|o| o.rect.contains_strictly(p))
    }

    /// The point `standoff_m` off the surface in front of `uv`, where the
    /// nozzle sits to spray it.
    pub fn nozzle_point(&self, uv: [f64; 2], standoff_m: f64, room: &RoomModel) -> Point3<f64> {
        let p = self.frame.point(uv);
        p + self.into_room(room) * standoff_m
    }

    /// Unit normal from the surface into the room.
    pub fn into_room(&self, room: &RoomModel) -> Vector3<f64> {
        match self.id {
            SurfaceId::Ceiling => Vector3::new(0.0, 0.0, -1.0),
            SurfaceId::Wall(w) => {
                let n = room.wall(w).map_or_else(Vector2::zeros, |l| l.inward);
                Vector3::new(n.x, n.y, 0.0)
            }
        }
    }
}

impl RoomModel {
    /// The room's walls, by index: a rectangle's four (west, south, east,
    /// north), or its polygon's edges.
    pub fn walls(&self) -> Vec<WallLine> {
        WallLine::of_room(&self.corners, self.size_m)
    }

    /// Wall `w`, when the room has it.
    pub fn wall(&self, w: WallName) -> Option<WallLine> {
        self.walls().get(w.index()).copied()
    }

    /// The floor's outline, counter-clockwise.
    pub fn outline(&self) -> Outline<'_> {
        if self.corners.is_empty() {
            let [xs, ys] = self.size_m;
            Outline::owned(vec![[0.0, 0.0], [xs, 0.0], [xs, ys], [0.0, ys]])
        } else {
            Outline::new(&self.corners)
        }
    }

    /// The room's walls and its ceiling, with their openings.
    pub fn surfaces(&self) -> Vec<Surface> {
        let mut out: Vec<Surface> = self
            .walls()
            .iter()
            .enumerate()
            .map(|(k, line)| {
                let w = WallName::new(k);
                Surface {
                    id: SurfaceId::Wall(w),
                    frame: SurfaceFrame {
                        origin: Point3::new(line.origin.x, line.origin.y, 0.0),
                        u: Vector3::new(line.along.x, line.along.y, 0.0),
                        v: Vector3::new(0.0, 0.0, 1.0),
                        size_m: [line.length_m, self.height_m],
                    },
                    openings: self
                        .openings
                        .iter()
                        .filter(|o| o.wall == w)
                        .map(|o| Opening {
                            kind: o.kind,
                            rect: Rect {
                                u_m: o.along_m,
                                v_m: o.sill_head_m,
                            },
                        })
                        .collect(),
                    outline: Vec::new(),
                }
            })
            .collect();
        out.push(Surface {
            id: SurfaceId::Ceiling,
            frame: SurfaceFrame {
                origin: Point3::new(0.0, 0.0, self.height_m),
                u: Vector3::new(1.0, 0.0, 0.0),
                v: Vector3::new(0.0, 1.0, 0.0),
                size_m: self.size_m,
            },
            openings: Vec::new(),
            outline: self.corners.clone(),
        });
        out
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    fn room() -> RoomModel {
        RoomModel {
            size_m: [5.0, 3.0],
            height_m: 2.6,
            openings: vec![WallOpening {
                wall: WallName::SOUTH,
                kind: OpeningKind::Window,
                along_m: [1.0, 2.2],
                sill_head_m: [0.9, 2.1],
            }],
            obstacles: Vec::new(),
            corners: Vec::new(),
        }
    }

    #[test]
    fn walls_face_into_the_room_and_run_like_the_filter() {
        let r = room();
        let s = r.surfaces();
        let south = &s[1];
        assert_eq!(south.id, SurfaceId::Wall(WallName::SOUTH));
        // u along x, at y = 0; the nozzle stands north of it.
        let p = south.nozzle_point([2.0, 1.0], 0.3, &r);
        assert!((p - Point3::new(2.0, 0.3, 1.0)).norm() < 1e-12);
        let east = &s[2];
        let p = east.nozzle_point([1.0, 1.0], 0.3, &r);
        assert!((p - Point3::new(4.7, 1.0, 1.0)).norm() < 1e-12);
        let ceiling = &s[4];
        let p = ceiling.nozzle_point([1.0, 2.0], 0.3, &r);
        assert!((p - Point3::new(1.0, 2.0, 2.3)).norm() < 1e-12);
        for w in WallName::ALL {
            let line = r.wall(w).expect("a rectangle's wall");
            let h = line.heading_wall_left();
            let left = Vector2::new(-h.sin(), h.cos());
            assert!((left + line.inward).norm() < 1e-12, "{w:?}");
        }
    }

    #[test]
    fn openings_and_edges_are_not_plastered() {
        let r = room();
        let tool = SprayTool::default();
        let south = &r.surfaces()[1];
        assert!(south.plasterable([0.5, 1.0], &tool));
        assert!(!south.plasterable([1.5, 1.5], &tool)); // in the window
        assert!(!south.plasterable([0.95, 1.5], &tool)); // its margin
        assert!(south.plasterable([0.85, 1.5], &tool));
        assert!(!south.plasterable([0.05, 1.0], &tool)); // the corner
        assert!(!south.plasterable([3.0, 0.05], &tool)); // skirting
        assert!(south.in_opening([1.5, 1.5]));
    }
}
