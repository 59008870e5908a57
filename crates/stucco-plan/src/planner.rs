//! Coverage planning: where the robot stands (stations) and what the nozzle
//! does there (passes of strokes), so every plasterable part of every
//! surface gets one even coat, and what cannot be reached is said so.
//!
//! Walls are coated with vertical strokes: the robot stands parallel to
//! the wall at its standoff, the wall on its left, and the gantry moves the
//! nozzle up and down the wall, stepping along the rail between strokes.
//! Strokes are spaced evenly along the whole wall (≤ 1.5 σ apart), with a
//! stroke where the band it coats ends `spray_off_m` short of each opening,
//! so the coat is even across stations and full up to every opening's
//! margin; a stroke crossing an opening stops spraying `spray_off_m` before
//! it and starts again past it, and strokes cut so are taken below the
//! opening first, then above it, so the nozzle crosses it once; a wall
//! pass is turned to end at the top of the wall, where the ceiling pass
//! that follows begins, when that is nearer. The ceiling is coated with
//! strokes along the room's x axis from the same stations (the nozzle
//! turned up, the arm reaching across) and from lanes down the middle
//! where the walls' stations do not reach; where one station's share of a
//! stroke ends the next one's begins, so their edges add up to the full
//! coat.
//!
//! Reach is honest: a part of a surface no station can reach (behind a
//! sofa, under a radiator, too high for the lift) is not planned and is
//! reported with its area.

use crate::outline::{Outline, cut_spans};
use crate::surface::{Opening, OpeningKind, RoomModel, Surface, SurfaceId, WallOpening};
use crate::{PlanError, Rect, SprayTool};
use serde::{Deserialize, Serialize};
use stucco_core::{Aim, Pose2, VehicleSpec, WallName};

/// Least length of a missed ceiling row a lane must take on to be worth
/// its drive, m.
const MIN_LANE_GAIN_M: f64 = 0.25;
/// Most lanes down the middle of a room a plan tries.
const MAX_MIDDLE_LANES: usize = 12;

/// Side of the cells of reach masks and predicted thickness, m.
pub const PLAN_CELL_M: f64 = 0.02;

/// Where a station stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Lane {
    /// Along a wall at the robot's standoff, the wall on the left.
    Wall(WallName),
    /// Down the middle of the room, heading east, `n`-th from the south.
    Middle(usize),
}

/// One move of the nozzle's aim point over a surface, at constant speed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Move {
    /// Start, in the surface's frame, m.
    pub from_m: [f64; 2],
    /// End, m.
    pub to_m: [f64; 2],
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Plaster flowing.
    pub spray: bool,
}

impl Move {
    /// Length, m.
    pub fn length_m(&self) -> f64 {
        (self.to_m[0] - self.from_m[0]).hypot(self.to_m[1] - self.from_m[1])
    }

    /// Duration, s.
    pub fn duration_s(&self) -> f64 {
        self.length_m() / self.speed_mps
    }

    /// The aim point `t_s` seconds into the move.
    pub fn at(&self, t_s: f64) -> [f64; 2] {
        let d = self.duration_s();
        let f = if d > 0.0 {
            (t_s / d).clamp(0.0, 1.0)
        } else {
            1.0
        };
        [
            self.from_m[0] + f * (self.to_m[0] - self.from_m[0]),
            self.from_m[1] + f * (self.to_m[1] - self.from_m[1]),
        ]
    }
}

/// The nozzle's work on one surface from one station.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pass {
    /// The surface.
    pub surface: SurfaceId,
    /// Where the nozzle points.
    pub aim: Aim,
    /// Its moves, one after the other.
    pub moves: Vec<Move>,
}

impl Pass {
    /// Turns the spray off wherever a move aims inside `rect`: each move
    /// crossing it is split at its border, the speed kept, so the pass
    /// takes as long as before and lays nothing there.
    pub fn spray_off_inside(&mut self, rect: &Rect) {
        let mut out = Vec::with_capacity(self.moves.len());
        for m in self.moves.drain(..) {
            let Some([t0, t1]) = m.spray.then(|| rect.clip(m.from_m, m.to_m)).flatten() else {
                out.push(m);
                continue;
            };
            let at = |t: f64| {
                [
                    m.from_m[0] + t * (m.to_m[0] - m.from_m[0]),
                    m.from_m[1] + t * (m.to_m[1] - m.from_m[1]),
                ]
            };
            for (a, b, spray) in [(0.0, t0, true), (t0, t1, false), (t1, 1.0, true)] {
                if (b - a) * m.length_m() > 1e-9 {
                    out.push(Move {
                        from_m: at(a),
                        to_m: at(b),
                        spray,
                        ..m
                    });
                }
            }
        }
        self.moves = out;
    }

    /// Takes a wall pass's strokes again in the planner's order, from
    /// what it sprays: once [`Pass::spray_off_inside`] has cut strokes
    /// across a window, they are taken below it and then above it, as the
    /// planner takes strokes across a window it knows, instead of crossing
    /// it spray off at the strokes' speed. Nothing changes on a pass whose
    /// sprayed moves are not vertical strokes.
    pub fn restroke(&mut self, axis_speed_mps: f64) {
        self.restroke_from(axis_speed_mps, self.starts_up());
    }

    /// True when the pass's first stroke runs up (or it has none).
    fn starts_up(&self) -> bool {
        self.moves
            .iter()
            .find(|m| m.spray)
            .is_none_or(|m| m.to_m[1] >= m.from_m[1])
    }

    /// [`Pass::restroke`], the first stroke up the wall when `up`, else
    /// down it.
    fn restroke_from(&mut self, axis_speed_mps: f64, up: bool) {
        let mut lines: Vec<(f64, Line)> = Vec::new();
        for m in self.moves.iter().filter(|m| m.spray) {
            if m.from_m[0] != m.to_m[0] {
                return;
            }
            let piece = if m.from_m[1] <= m.to_m[1] {
                (m.from_m, m.to_m)
            } else {
                (m.to_m, m.from_m)
            };
            match lines.iter_mut().find(|(u, _)| *u == m.from_m[0]) {
                Some((_, line)) => line.pieces.push(piece),
                None => lines.push((
                    m.from_m[0],
                    Line {
                        pieces: vec![piece],
                        speed_mps: m.speed_mps,
                    },
                )),
            }
        }
        let lines: Vec<Line> = lines
            .into_iter()
            .map(|(_, mut line)| {
                line.pieces.sort_by(|a, b| a.0[1].total_cmp(&b.0[1]));
                line
            })
            .collect();
        self.moves = boustrophedon(&lines, axis_speed_mps, up);
    }

    /// Duration, s.
    pub fn duration_s(&self) -> f64 {
        self.moves.iter().map(Move::duration_s).sum()
    }

    /// Time spent spraying, s.
    pub fn spray_s(&self) -> f64 {
        self.moves
            .iter()
            .filter(|m| m.spray)
            .map(Move::duration_s)
            .sum()
    }
}

/// Where the robot stands and what it sprays from there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Station {
    /// What it stands along.
    pub lane: Lane,
    /// The rear axle's pose, room frame.
    pub base: Pose2,
    /// The passes, in order.
    pub passes: Vec<Pass>,
}

/// Which cells of a surface the plan reaches (the plasterable ones among
/// them are to be coated).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReachMask {
    /// The surface.
    pub surface: SurfaceId,
    /// Side of a cell, m.
    pub cell_m: f64,
    /// Cells along `u` and `v`.
    pub cells: [usize; 2],
    /// Reached, row by row (`v` major).
    pub reached: Vec<bool>,
}

impl ReachMask {
    /// The mask less a band `d_m` wide along every border of what it
    /// reaches: where the plan's frame may sit `d_m` off the truth.
    pub fn eroded(&self, d_m: f64) -> ReachMask {
        let [nu, nv] = self.cells;
        let r = (d_m / self.cell_m).round() as i64;
        let at = |i: i64, j: i64| {
            i < 0
                || j < 0
                || i >= nu as i64
                || j >= nv as i64
                || self.reached[j as usize * nu + i as usize]
        };
        let mut reached = self.reached.clone();
        for j in 0..nv as i64 {
            for i in 0..nu as i64 {
                if !at(i, j) {
                    continue;
                }
                let near_gap = (-r..=r)
                    .flat_map(|dj| (-r..=r).map(move |di| (di, dj)))
                    .filter(|(di, dj)| di * di + dj * dj <= r * r)
                    .any(|(di, dj)| !at(i + di, j + dj));
                if near_gap {
                    reached[j as usize * nu + i as usize] = false;
                }
            }
        }
        ReachMask {
            reached,
            ..self.clone()
        }
    }

    /// True when the point `uv` lies in a reached cell; outside the mask,
    /// false.
    pub fn reaches(&self, uv: [f64; 2]) -> bool {
        let i = (uv[0] / self.cell_m).floor();
        let j = (uv[1] / self.cell_m).floor();
        if i < 0.0 || j < 0.0 {
            return false;
        }
        let (i, j) = (i as usize, j as usize);
        i < self.cells[0] && j < self.cells[1] && self.reached[j * self.cells[0] + i]
    }
}

/// Plasterable area no station reaches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Unreachable {
    /// The surface.
    pub surface: SurfaceId,
    /// Its area, m².
    pub area_m2: f64,
    /// A rectangle around it, in the surface's frame.
    pub bounds: Rect,
}

/// A plastering plan for one room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// The tool it was made for.
    pub tool: SprayTool,
    /// The room it was made on.
    pub room: RoomModel,
    /// The room's surfaces.
    pub surfaces: Vec<Surface>,
    /// Stations in the order the robot visits them.
    pub stations: Vec<Station>,
    /// What each surface's stations reach, in [`Plan::surfaces`] order.
    pub reach: Vec<ReachMask>,
    /// Plasterable parts no station reaches.
    pub unreachable: Vec<Unreachable>,
}

impl Plan {
    /// The surface `id`.
    pub fn surface(&self, id: SurfaceId) -> Option<&Surface> {
        self.surfaces.iter().find(|s| s.id == id)
    }

    /// The reach of surface `id`.
    pub fn reach_of(&self, id: SurfaceId) -> Option<&ReachMask> {
        self.reach.iter().find(|r| r.surface == id)
    }

    /// Time the nozzle spends spraying, s.
    pub fn spray_s(&self) -> f64 {
        self.passes().map(|(_, p)| p.spray_s()).sum()
    }

    /// Keeps a window found once the plan was made (the camera on the
    /// tool saw it at a station) out of the coat: it becomes an opening of
    /// its wall (or grows the one it overlaps to hold both), and every
    /// pass on that wall from station `from` on lays nothing within the
    /// tool's spray-off distance of it. False, and nothing changed, when
    /// the wall's openings hold it already.
    pub fn add_window(
        &mut self,
        wall: WallName,
        along_m: [f64; 2],
        sill_head_m: [f64; 2],
        from: usize,
    ) -> bool {
        let id = SurfaceId::Wall(wall);
        let rect = Rect {
            u_m: along_m,
            v_m: sill_head_m,
        };
        let Some(surface) = self.surfaces.iter_mut().find(|s| s.id == id) else {
            return false;
        };
        let rect =
            match surface.openings.iter_mut().find(|o| o.rect.overlaps(&rect)) {
                Some(o) => {
                    let both = o.rect.union(&rect);
                    if both == o.rect {
                        return false;
                    }
                    let old = o.rect;
                    o.rect = both;
                    if let Some(r) = self.room.openings.iter_mut().find(|r| {
                        r.wall == wall && r.along_m == old.u_m && r.sill_head_m == old.v_m
                    }) {
                        r.along_m = both.u_m;
                        r.sill_head_m = both.v_m;
                    }
                    both
                }
                None => {
                    surface.openings.push(Opening {
                        kind: OpeningKind::Window,
                        rect,
                    });
                    self.room.openings.push(WallOpening {
                        wall,
                        kind: OpeningKind::Window,
                        along_m,
                        sill_head_m,
                    });
                    rect
                }
            };
        let keep_out = rect.grown(self.tool.spray_off_m);
        for station in self.stations.iter_mut().skip(from) {
            for pass in station.passes.iter_mut().filter(|p| p.surface == id) {
                pass.spray_off_inside(&keep_out);
                pass.restroke(self.tool.axis_speed_mps);
            }
        }
        true
    }

    /// Turns a station's wall pass upside down where it then ends nearer
    /// the station's next pass: strokes taken alternately up and down end
    /// at the foot of the wall when there are as many up as down, while
    /// the ceiling pass that follows begins under the ceiling, the lift's
    /// whole travel away.
    fn end_wall_passes_near_the_next(&mut self) {
        let axis = self.tool.axis_speed_mps;
        // How far the nozzle's slowest axis has to go from the end of
        // `pass` to `to`, m.
        let gap = |plan: &Plan, pass: &Pass, to: nalgebra::Point3<f64>| {
            pass.moves
                .last()
                .and_then(|m| plan.nozzle_point(pass.surface, m.to_m))
                .map_or(f64::INFINITY, |p| (p - to).amax())
        };
        for k in 0..self.stations.len() {
            for i in 1..self.stations[k].passes.len() {
                let (pass, next) = (&self.stations[k].passes[i - 1], &self.stations[k].passes[i]);
                if matches!(pass.surface, SurfaceId::Ceiling) {
                    continue;
                }
                let Some(to) = next
                    .moves
                    .first()
                    .and_then(|m| self.nozzle_point(next.surface, m.from_m))
                else {
                    continue;
                };
                let mut turned = pass.clone();
                turned.restroke_from(axis, !pass.starts_up());
                if gap(self, &turned, to) < gap(self, pass, to) - 1e-9 {
                    self.stations[k].passes[i - 1] = turned;
                }
            }
        }
    }

    /// Gives up station `k`, which the robot found no way to (a hall too
    /// narrow to turn across): it leaves the plan, and what only it
    /// reached of the surfaces it sprays is reported unreachable (the
    /// rest of the plan's reach stays as it was). The plasterable area
    /// lost with it, m²; `None` when there is no station `k`.
    pub fn give_up_station(&mut self, k: usize) -> Option<f64> {
        if k >= self.stations.len() {
            return None;
        }
        let station = self.stations.remove(k);
        let mut lost = 0.0;
        for (i, surface) in self.surfaces.iter().enumerate() {
            if !station.passes.iter().any(|p| p.surface == surface.id) {
                continue;
            }
            let (mut reach, unreachable) =
                reach_of(std::slice::from_ref(surface), &self.stations, &self.tool);
            let before = self.unreachable.iter().filter(|u| u.surface == surface.id);
            lost -= before.map(|u| u.area_m2).sum::<f64>();
            lost += unreachable.iter().map(|u| u.area_m2).sum::<f64>();
            self.unreachable.retain(|u| u.surface != surface.id);
            self.unreachable.extend(unreachable);
            if let (Some(r), Some(new)) = (self.reach.get_mut(i), reach.pop()) {
                *r = new;
            }
        }
        Some(lost)
    }

    /// Plasterable area no station reaches, m².
    pub fn unreachable_m2(&self) -> f64 {
        // Folded from 0 (a float sum of nothing is -0, which the events
        // then read as "-0.0").
        self.unreachable.iter().fold(0.0, |a, u| a + u.area_m2)
    }

    /// Every pass with the index of its station.
    pub fn passes(&self) -> impl Iterator<Item = (usize, &Pass)> {
        self.stations
            .iter()
            .enumerate()
            .flat_map(|(i, s)| s.passes.iter().map(move |p| (i, p)))
    }

    /// Where the nozzle sits for aim point `uv` on `surface`, in the room
    /// frame.
    pub fn nozzle_point(&self, surface: SurfaceId, uv: [f64; 2]) -> Option<nalgebra::Point3<f64>> {
        let s = self.surface(surface)?;
        let standoff = if s.is_ceiling() {
            self.tool.ceiling_standoff_m
        } else {
            self.tool.wall_standoff_m
        };
        Some(s.nozzle_point(uv, standoff, &self.room))
    }
}

/// Plans the coating of every wall and the ceiling of `room` with `tool`
/// on a robot of `vehicle`, starting from `start` (the rear axle's pose in
/// the room frame).
pub fn plan(
    room: &RoomModel,
    tool: &SprayTool,
    vehicle: &VehicleSpec,
    start: &Pose2,
) -> Result<Plan, PlanError> {
    tool.validate(vehicle.width_m)?;
    let outline = room.outline();
    if let Some(fault) = outline.fault() {
        return Err(PlanError::Room(format!("the room's corners: {fault}")));
    }
    if !(room.size_m[0] > 0.0
        && room.size_m[1] > 0.0
        && room.height_m > 0.0
        && outline.signed_area_m2() > 0.0)
    {
        return Err(PlanError::Room(format!(
            "a room {:?} m and {} m high has no surfaces",
            room.size_m, room.height_m
        )));
    }
    let ceiling_z = room.height_m - tool.ceiling_standoff_m;
    if ceiling_z > tool.lift_m[1] || ceiling_z < tool.lift_m[0] {
        return Err(PlanError::Room(format!(
            "the ceiling at {:.2} m needs the nozzle at {ceiling_z:.2} m; the lift reaches \
             {:.2}..{:.2} m",
            room.height_m, tool.lift_m[0], tool.lift_m[1]
        )));
    }
    let body = Body::of(vehicle);
    let planner = Planner {
        room,
        tool,
        body,
        floor: Floor::reached(room, &outline, body.half_width_m + tool.clearance_m, start),
        outline,
    };
    let surfaces = room.surfaces();
    let mut lanes: Vec<(Lane, Vec<Station>)> = Vec::new();
    for surface in surfaces.iter().filter(|s| !s.is_ceiling()) {
        let SurfaceId::Wall(w) = surface.id else {
            continue;
        };
        let stations = planner.wall(w, surface);
        lanes.push((Lane::Wall(w), stations));
    }
    // The ceiling from the walls' stations, then lanes where they fall
    // short.
    let strokes = planner.ceiling_lines();
    let mut reach_rects: Vec<Rect> = lanes
        .iter()
        .flat_map(|(_, st)| st.iter().map(|s| planner.ceiling_reach(&s.base)))
        .collect();
    // Lanes down the middle, each placed for the lowest row of the
    // ceiling still missed somewhere a lane can reach; a row no lane
    // reaches more of is given up (and reported unreachable).
    let [a0, a1] = tool.planned_arm_m();
    let mut given_up: Vec<f64> = Vec::new();
    let mut middle = 0;
    while middle < MAX_MIDDLE_LANES {
        let Some(row) = planner
            .open_rows(&strokes.0, &reach_rects)
            .into_iter()
            .find(|r| !given_up.iter().any(|g| (g - r).abs() < 1e-9))
        else {
            break;
        };
        let missed = |rects: &[Rect]| planner.missed_m(row, rects);
        let before = missed(&reach_rects);
        let mut placed = false;
        // The lane as low as covers the row at its arm's near end, then
        // higher up, while it still covers the row.
        let mut y = row - a0;
        while y + a1 >= row - 1e-9 {
            let stations = planner.middle_lane(y, middle, &strokes.0, &reach_rects);
            let mut with: Vec<Rect> = reach_rects.clone();
            with.extend(stations.iter().map(|s| planner.ceiling_reach(&s.base)));
            if !stations.is_empty() && missed(&with) < before - MIN_LANE_GAIN_M {
                reach_rects = with;
                lanes.push((Lane::Middle(middle), stations));
                middle += 1;
                placed = true;
                break;
            }
            y -= BASE_STEP_M * 5.0;
        }
        if !placed {
            given_up.push(row);
        }
    }
    let ordered = order_lanes(lanes, start);
    let mut stations = ordered;
    planner.ceiling_passes(&mut stations, &strokes);

    let (reach, unreachable) = reach_of(&surfaces, &stations, tool);
    let mut plan = Plan {
        tool: tool.clone(),
        room: room.clone(),
        surfaces,
        stations,
        reach,
        unreachable,
    };
    plan.end_wall_passes_near_the_next();
    Ok(plan)
}

/// What `stations` reach of each of `surfaces`, and the plasterable parts
/// they leave.
fn reach_of(
    surfaces: &[Surface],
    stations: &[Station],
    tool: &SprayTool,
) -> (Vec<ReachMask>, Vec<Unreachable>) {
    let mut reach = Vec::new();
    let mut unreachable = Vec::new();
    for surface in surfaces {
        let bands: Vec<Rect> = stations
            .iter()
            .flat_map(|s| s.passes.iter())
            .filter(|p| p.surface == surface.id)
            .flat_map(|p| p.moves.iter().filter(|m| m.spray))
            .map(|m| band(m, tool))
            .collect();
        let mask = reach_mask(surface, &bands, tool);
        if let Some(u) = lost_area(surface, &mask, tool) {
            unreachable.push(u);
        }
        reach.push(mask);
    }
    (reach, unreachable)
}

/// The robot's footprint, in its own frame.
#[derive(Clone, Copy, Debug)]
struct Body {
    /// From and to along x, m.
    x_m: [f64; 2],
    /// Half its width, m.
    half_width_m: f64,
}

impl Body {
    fn of(v: &VehicleSpec) -> Body {
        Body {
            x_m: [-v.rear_overhang_m, v.front_m()],
            half_width_m: v.width_m / 2.0,
        }
    }
}

/// The largest box of room-frame points about the middle of the
/// robot-frame box `x × y` at `pose` that lies inside it: that box itself
/// at a heading that is a multiple of 90°, a square within it at any
/// other (a station along a wall at an angle).
fn inscribed_box(pose: &Pose2, x: [f64; 2], y: [f64; 2]) -> [[f64; 2]; 2] {
    let (s, c) = pose.theta.sin_cos();
    let (s, c) = (s.abs(), c.abs());
    if s.min(c) < 1e-9 {
        return room_box(pose, x, y);
    }
    let mid = pose.transform_point(&nalgebra::Point2::new(
        (x[0] + x[1]) / 2.0,
        (y[0] + y[1]) / 2.0,
    ));
    // A square of half side h has its corners inside the box when h·(|cos|
    // + |sin|) is within both half sides.
    let h = ((x[1] - x[0]) / 2.0).min((y[1] - y[0]) / 2.0) / (s + c);
    [[mid.x - h, mid.y - h], [mid.x + h, mid.y + h]]
}

/// The box of room-frame points covered by the robot-frame box
/// `x × y` at `pose`.
fn room_box(pose: &Pose2, x: [f64; 2], y: [f64; 2]) -> [[f64; 2]; 2] {
    let mut lo = [f64::MAX; 2];
    let mut hi = [f64::MIN; 2];
    for px in x {
        for py in y {
            let p = pose.transform_point(&nalgebra::Point2::new(px, py));
            lo = [lo[0].min(p.x), lo[1].min(p.y)];
            hi = [hi[0].max(p.x), hi[1].max(p.y)];
        }
    }
    [lo, hi]
}

struct Planner<'a> {
    room: &'a RoomModel,
    /// The room's floor.
    outline: Outline<'a>,
    tool: &'a SprayTool,
    body: Body,
    floor: Floor,
}

/// Cells of the floor the robot can get to, m.
const REACH_CELL_M: f64 = 0.05;

/// The floor the robot can get to from where it starts: the cells whose
/// middle is `radius` or more from every wall and obstacle (the robot
/// passes there, its rear axle on the cell), joined to the start's cell.
/// A station on floor that furniture cuts off from the robot (the far side
/// of a bed and a desk that span a bedroom) cannot be reached whatever the
/// way; its plaster is reported unreachable.
struct Floor {
    cells: [usize; 2],
    /// Cells within the passage's radius of a reached one.
    near: Vec<bool>,
}

impl Floor {
    fn reached(room: &RoomModel, outline: &Outline, radius: f64, start: &Pose2) -> Floor {
        let [xs, ys] = room.size_m;
        let cells = [
            ((xs / REACH_CELL_M).ceil() as usize).max(1),
            ((ys / REACH_CELL_M).ceil() as usize).max(1),
        ];
        let centre = |i: usize, j: usize| {
            [
                (i as f64 + 0.5) * REACH_CELL_M,
                (j as f64 + 0.5) * REACH_CELL_M,
            ]
        };
        let open = |i: usize, j: usize| {
            let [x, y] = centre(i, j);
            outline.clearance_m(&nalgebra::Point2::new(x, y)) >= radius
                && room.obstacles.iter().all(|o| {
                    let dx = (o.min_m[0] - x).max(x - o.max_m[0]).max(0.0);
                    let dy = (o.min_m[1] - y).max(y - o.max_m[1]).max(0.0);
                    dx.hypot(dy) >= radius
                })
        };
        let n = cells[0] * cells[1];
        let is_open: Vec<bool> = (0..n).map(|k| open(k % cells[0], k / cells[0])).collect();
        // From the open cell nearest the start (the robot may stand nearer
        // something than `radius`).
        let p = start.position();
        let seed = (0..n).filter(|&k| is_open[k]).min_by(|&a, &b| {
            let d = |k: usize| {
                let [x, y] = centre(k % cells[0], k / cells[0]);
                (x - p.x).hypot(y - p.y)
            };
            d(a).total_cmp(&d(b))
        });
        let mut reached = vec![false; n];
        let mut stack: Vec<usize> = seed.into_iter().collect();
        while let Some(k) = stack.pop() {
            if reached[k] || !is_open[k] {
                continue;
            }
            reached[k] = true;
            let (i, j) = (k % cells[0], k / cells[0]);
            if i > 0 {
                stack.push(k - 1);
            }
            if i + 1 < cells[0] {
                stack.push(k + 1);
            }
            if j > 0 {
                stack.push(k - cells[0]);
            }
            if j + 1 < cells[1] {
                stack.push(k + cells[0]);
            }
        }
        // Once here, not at each of the thousands of stations' bases
        // tried: the cells within `radius` of a reached one.
        let k = (radius / REACH_CELL_M).ceil() as i64;
        let [ni, nj] = cells.map(|c| c as i64);
        let mut near = vec![false; n];
        for (idx, _) in reached.iter().enumerate().filter(|(_, r)| **r) {
            let (i, j) = ((idx % cells[0]) as i64, (idx / cells[0]) as i64);
            for b in (j - k).max(0)..=(j + k).min(nj - 1) {
                for a in (i - k).max(0)..=(i + k).min(ni - 1) {
                    let d = (((a - i) * (a - i) + (b - j) * (b - j)) as f64).sqrt() * REACH_CELL_M;
                    if d <= radius {
                        near[(b * ni + a) as usize] = true;
                    }
                }
            }
        }
        Floor { cells, near }
    }

    /// True when the robot can get to `p` (its rear axle there): a reached
    /// cell lies within the passage's radius of its cell (a station stands
    /// nearer a wall, or a corner, than the way it came by is wide).
    fn reaches(&self, p: [f64; 2]) -> bool {
        let (i, j) = (
            (p[0] / REACH_CELL_M).floor() as i64,
            (p[1] / REACH_CELL_M).floor() as i64,
        );
        let [ni, nj] = self.cells.map(|c| c as i64);
        (0..ni).contains(&i) && (0..nj).contains(&j) && self.near[(j * ni + i) as usize]
    }
}

/// Step of the search for stations' bases, m.
const BASE_STEP_M: f64 = 0.01;
/// Step out from a wall of the standoffs its stations' bases are searched
/// at, beyond the tool's, m.
const STANDOFF_STEP_M: f64 = 0.05;

impl Planner<'_> {
    /// True when the robot can stand at `pose`: its body, grown by the
    /// clearance, inside the room and clear of every obstacle.
    fn free(&self, pose: &Pose2) -> bool {
        let c = self.tool.clearance_m;
        let b = self.body;
        let [lo, hi] = room_box(pose, b.x_m, [-b.half_width_m, b.half_width_m]);
        let body = [
            [b.x_m[0], -b.half_width_m],
            [b.x_m[1], -b.half_width_m],
            [b.x_m[1], b.half_width_m],
            [b.x_m[0], b.half_width_m],
        ]
        .map(|[x, y]| pose.transform_point(&nalgebra::Point2::new(x, y)));
        if !self.outline.holds(&body, c) {
            return false;
        }
        !self.room.obstacles.iter().any(|o| {
            lo[0] < o.max_m[0] + c
                && hi[0] > o.min_m[0] - c
                && lo[1] < o.max_m[1] + c
                && hi[1] > o.min_m[1] - c
        }) && self.floor.reaches([pose.x, pose.y])
    }

    /// The stations along wall `w`, far end first: on its lane at the
    /// tool's standoff, and where no base there reaches a stretch of the
    /// wall (furniture against it, or a corner, leaves no room for the
    /// body), from farther out, as far as the arm reaches the wall from,
    /// the nearest first. What stands before the wall limits the tool only
    /// where it stands: between a corner and a wardrobe, a stretch shorter
    /// than the body and its clearance was never planned.
    fn wall(&self, w: WallName, surface: &Surface) -> Vec<Station> {
        let tool = self.tool;
        let Some(line) = self.room.wall(w) else {
            return Vec::new();
        };
        let [length, _] = surface.size_m();
        let gap = tool.surface_gap_m;
        let mut left = vec![[gap, length - gap]];
        let mut stations = Vec::new();
        let farthest = tool.wall_standoff_m + tool.planned_arm_m()[1];
        let mut standoff = tool.robot_standoff_m;
        let half = 0.5 * tool.stroke_spacing_m();
        while !left.is_empty() && standoff <= farthest + 1e-9 {
            let (mine, reached) = self.wall_at(w, surface, standoff, &left);
            stations.extend(mine);
            // The next strokes a whole spacing on from these, as within
            // one station's (half a spacing on, the bands overlapped and
            // laid the coat double there).
            for r in reached {
                cut_spans(&mut left, [r[0] - half, r[1] + half]);
            }
            // Stretches too short for a stroke are done.
            left.retain(|l| l[1] - l[0] > half);
            standoff += STANDOFF_STEP_M;
        }
        // Far end first, as each lane's stations are driven.
        let heading = line.heading_wall_left();
        let sgn = line
            .along
            .dot(&nalgebra::Vector2::new(heading.cos(), heading.sin()));
        let at = |s: &Station| sgn * line.along.dot(&(s.base.position().coords - line.origin));
        stations.sort_by(|a, b| at(b).total_cmp(&at(a)));
        stations
    }

    /// The stations along wall `w` with their bases `standoff` m from it,
    /// spraying the stretches of it in `within` (along it, m), far end
    /// first; and the stretches their strokes cover. Farther out than the
    /// tool's standoff, nothing between the body and the wall is sprayed
    /// over (the laser sees what stands there, not how high).
    fn wall_at(
        &self,
        w: WallName,
        surface: &Surface,
        standoff: f64,
        within: &[[f64; 2]],
    ) -> (Vec<Station>, Vec<[f64; 2]>) {
        let tool = self.tool;
        let Some(line) = self.room.wall(w) else {
            return (Vec::new(), Vec::new());
        };
        let heading = line.heading_wall_left();
        let sgn = line
            .along
            .dot(&nalgebra::Vector2::new(heading.cos(), heading.sin()));
        let [length, height] = surface.size_m();
        let pose_at = |u: f64| {
            let p = line.point(u, standoff);
            Pose2::new(p.x, p.y, heading)
        };
        // Positions t = sgn·u of the feasible bases.
        let n = ((length + 2.0) / BASE_STEP_M).ceil() as i64;
        let feasible: Vec<f64> = (0..=n)
            .map(|k| -1.0 + k as f64 * BASE_STEP_M)
            .filter(|&u| self.free(&pose_at(u)))
            .map(|u| sgn * u)
            .collect();
        let gap = tool.surface_gap_m;
        let clip = |t: [f64; 2]| -> Option<[f64; 2]> {
            // t-interval → u-interval clipped to the wall.
            let (a, b) = (sgn * t[0], sgn * t[1]);
            let (a, b) = (a.min(b).max(gap), a.max(b).min(length - gap));
            (b > a).then_some([a, b])
        };
        let x = tool.planned_rail_m();
        let reach_of = |t: f64| clip([t + x[0], t + x[1]]);
        let lift = [
            tool.lift_m[0].max(tool.skirting_m - tool.ramp_m()),
            tool.lift_m[1].min(height - gap),
        ];
        // Nozzle along the wall: union of the reaches, as intervals,
        // within the stretches asked for.
        let mut spans: Vec<[f64; 2]> = feasible
            .iter()
            .filter_map(|&t| reach_of(t))
            .flat_map(|r| {
                within.iter().filter_map(move |l| {
                    let (a, b) = (r[0].max(l[0]), r[1].min(l[1]));
                    (b > a).then_some([a, b])
                })
            })
            .collect();
        spans.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let mut merged: Vec<[f64; 2]> = Vec::new();
        for s in spans {
            match merged.last_mut() {
                Some(m) if s[0] <= m[1] + 1e-9 => m[1] = m[1].max(s[1]),
                _ => merged.push(s),
            }
        }
        // Obstacles between the wall and the body: the nozzle cannot go
        // below their tops there (farther out than the tool's standoff,
        // nowhere there).
        let corridor = standoff - self.body.half_width_m;
        let nearest = standoff <= tool.robot_standoff_m + 1e-9;
        let low_blocks: Vec<([f64; 2], f64)> = self
            .room
            .obstacles
            .iter()
            .filter_map(|o| {
                let corners = [
                    o.min_m,
                    o.max_m,
                    [o.min_m[0], o.max_m[1]],
                    [o.max_m[0], o.min_m[1]],
                ];
                let d = corners
                    .iter()
                    .map(|c| {
                        line.inward
                            .dot(&(nalgebra::Vector2::new(c[0], c[1]) - line.origin))
                    })
                    .fold(f64::MAX, f64::min);
                let u: Vec<f64> = corners
                    .iter()
                    .map(|c| {
                        line.along
                            .dot(&(nalgebra::Vector2::new(c[0], c[1]) - line.origin))
                    })
                    .collect();
                let (u0, u1) = u
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
                let top = if nearest {
                    o.height_m + tool.clearance_m
                } else {
                    f64::MAX
                };
                (d < corridor).then_some(([u0, u1], top))
            })
            .collect();
        let strokes = self.wall_strokes(&merged, surface, lift, &low_blocks);
        let half = 0.5 * tool.stroke_spacing_m();
        let reached: Vec<[f64; 2]> = strokes
            .iter()
            .map(|(u, _, _)| [u - half, u + half])
            .collect();
        // Stations, far end first: each covers the farthest strokes left.
        let mut left: Vec<(f64, Vec<[f64; 2]>, f64)> = strokes;
        left.sort_by(|a, b| (sgn * b.0).total_cmp(&(sgn * a.0)));
        let mut stations = Vec::new();
        // Each station's reach runs on to where the last one's began, so
        // together they reach the ceiling along the wall without a gap.
        let mut reached_from: Option<f64> = None;
        while let Some(first) = left.first() {
            let t1 = sgn * first.0;
            let covering = |reach_to: f64| {
                feasible
                    .iter()
                    .copied()
                    .filter(move |&t| t + x[1] >= reach_to - 1e-9 && t + x[0] <= t1 + 1e-9)
                    .min_by(|a, b| a.total_cmp(b))
            };
            let Some(tb) = reached_from.and_then(covering).or_else(|| covering(t1)) else {
                // Cannot happen: every stroke lies in some base's reach.
                left.remove(0);
                continue;
            };
            let lo = tb + x[0] - 1e-9;
            reached_from = Some(tb + x[0]);
            let k = left.iter().take_while(|s| sgn * s.0 >= lo).count();
            let mine: Vec<_> = left.drain(..k).collect();
            let base = pose_at(sgn * tb);
            stations.push(Station {
                lane: Lane::Wall(w),
                base,
                passes: vec![self.wall_pass(surface.id, &mine)],
            });
        }
        (stations, reached)
    }

    /// The strokes of a wall: `(u, pieces of v sprayed, speed)`.
    fn wall_strokes(
        &self,
        spans: &[[f64; 2]],
        surface: &Surface,
        lift: [f64; 2],
        low_blocks: &[([f64; 2], f64)],
    ) -> Vec<(f64, Vec<[f64; 2]>, f64)> {
        let tool = self.tool;
        let so = tool.spray_off_m;
        // A stroke beside an opening coats a band half a spacing wide
        // toward it: that band, not the stroke, stops `spray_off_m` short.
        let beside = so + tool.stroke_spacing_m() / 2.0;
        let mut out = Vec::new();
        for span in spans {
            let mut keys = vec![span[0], span[1]];
            for o in &surface.openings {
                for k in [o.rect.u_m[0] - beside, o.rect.u_m[1] + beside] {
                    if k > span[0] && k < span[1] {
                        keys.push(k);
                    }
                }
            }
            keys.sort_by(f64::total_cmp);
            keys.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
            let mut us = vec![keys[0]];
            for pair in keys.windows(2) {
                let n = ((pair[1] - pair[0]) / tool.stroke_spacing_m())
                    .ceil()
                    .max(1.0);
                for i in 1..=n as usize {
                    us.push(pair[0] + (pair[1] - pair[0]) * i as f64 / n);
                }
            }
            for (i, &u) in us.iter().enumerate() {
                let width = match (i.checked_sub(1).map(|j| us[j]), us.get(i + 1)) {
                    (Some(a), Some(&b)) => (b - a) / 2.0,
                    (Some(a), None) => u - a,
                    (None, Some(&b)) => b - u,
                    (None, None) => tool.stroke_spacing_m(),
                };
                let mut pieces = vec![lift];
                for o in &surface.openings {
                    if u > o.rect.u_m[0] - beside + 1e-9 && u < o.rect.u_m[1] + beside - 1e-9 {
                        cut_spans(&mut pieces, [o.rect.v_m[0] - so, o.rect.v_m[1] + so]);
                    }
                }
                for (bu, top) in low_blocks {
                    if u >= bu[0] && u <= bu[1] {
                        cut_spans(&mut pieces, [f64::MIN, *top]);
                    }
                }
                if !pieces.is_empty() {
                    out.push((u, pieces, tool.stroke_speed_mps(width)));
                }
            }
        }
        out
    }

    /// A station's pass over its wall strokes, in the order given,
    /// alternately up and down.
    fn wall_pass(&self, surface: SurfaceId, strokes: &[(f64, Vec<[f64; 2]>, f64)]) -> Pass {
        let lines: Vec<Line> = strokes
            .iter()
            .map(|(u, pieces, speed)| Line {
                pieces: pieces.iter().map(|p| ([*u, p[0]], [*u, p[1]])).collect(),
                speed_mps: *speed,
            })
            .collect();
        Pass {
            surface,
            aim: Aim::Left,
            moves: boustrophedon(&lines, self.tool.axis_speed_mps, true),
        }
    }

    /// The ceiling's strokes: lines along x at these y, m, with their
    /// speed.
    fn ceiling_lines(&self) -> (Vec<f64>, f64) {
        let gap = self.tool.surface_gap_m;
        let [xs, ys] = self.room.size_m;
        let _ = xs;
        let span = ys - 2.0 * gap;
        let n = (span / self.tool.stroke_spacing_m()).ceil().max(1.0) as usize;
        let spacing = span / n as f64;
        let ys: Vec<f64> = (0..=n).map(|i| gap + spacing * i as f64).collect();
        (ys, self.tool.stroke_speed_mps(spacing))
    }

    /// The part of the ceiling the nozzle reaches from `base`.
    fn ceiling_reach(&self, base: &Pose2) -> Rect {
        let gap = self.tool.surface_gap_m;
        let [xs, ys] = self.room.size_m;
        let [lo, hi] = inscribed_box(base, self.tool.planned_rail_m(), self.tool.planned_arm_m());
        Rect {
            u_m: [lo[0].max(gap), hi[0].min(xs - gap)],
            v_m: [lo[1].max(gap), hi[1].min(ys - gap)],
        }
    }

    /// The x the ceiling row at `y` is missed along by the reach `rects`,
    /// as intervals.
    fn missed_spans(&self, y: f64, rects: &[Rect]) -> Vec<[f64; 2]> {
        let gap = self.tool.surface_gap_m;
        let mut open = self.outline.row_spans(y, gap);
        for q in rects
            .iter()
            .filter(|q| y >= q.v_m[0] - 1e-9 && y <= q.v_m[1] + 1e-9)
        {
            cut_spans(&mut open, q.u_m);
        }
        open.retain(|o| o[1] - o[0] > 1e-3);
        open
    }

    /// Length of the ceiling row at `y` the reach `rects` miss, m.
    fn missed_m(&self, y: f64, rects: &[Rect]) -> f64 {
        self.missed_spans(y, rects)
            .iter()
            .map(|o| o[1] - o[0])
            .sum()
    }

    /// The ceiling rows the reach `rects` miss somewhere, lowest first.
    fn open_rows(&self, rows: &[f64], rects: &[Rect]) -> Vec<f64> {
        rows.iter()
            .copied()
            .filter(|&y| !self.missed_spans(y, rects).is_empty())
            .collect()
    }

    /// A lane heading east at `y` with its stations (east end first),
    /// placed only where the rows its arm reaches are still missed.
    fn middle_lane(&self, y: f64, index: usize, rows: &[f64], reached: &[Rect]) -> Vec<Station> {
        let tool = self.tool;
        let [a0, a1] = tool.planned_arm_m();
        let gap = tool.surface_gap_m;
        let xs = self.room.size_m[0];
        let pose_at = |x: f64| Pose2::new(x, y, 0.0);
        let n = ((xs + 2.0) / BASE_STEP_M).ceil() as i64;
        let feasible: Vec<f64> = (0..=n)
            .map(|k| -1.0 + k as f64 * BASE_STEP_M)
            .filter(|&x| self.free(&pose_at(x)))
            .collect();
        let x = tool.planned_rail_m();
        let mine: Vec<f64> = rows
            .iter()
            .copied()
            .filter(|&r| r >= y + a0 - 1e-9 && r <= y + a1 + 1e-9)
            .collect();
        let mut stations: Vec<Station> = Vec::new();
        // The farthest x at or below `below` that a row of this lane still
        // misses: where the next station must reach.
        let missing = |below: f64, placed: &[Station]| -> Option<f64> {
            let mut rects: Vec<Rect> = reached.to_vec();
            rects.extend(placed.iter().map(|s| self.ceiling_reach(&s.base)));
            mine.iter()
                .filter_map(|&r| {
                    self.missed_spans(r, &rects)
                        .iter()
                        .filter(|o| o[0] < below)
                        .map(|o| o[1].min(below))
                        .reduce(f64::max)
                })
                .reduce(f64::max)
        };
        let mut tf = missing(xs - gap, &stations).unwrap_or(gap);
        while tf > gap + 1e-6 {
            // A station must reach tf and leave less to do.
            let pick = feasible
                .iter()
                .filter(|&&t| t + x[1] >= tf - 1e-9 && t + x[0] < tf - 1e-6)
                .min_by(|a, b| a.total_cmp(b));
            match pick {
                Some(&tb) => {
                    stations.push(Station {
                        lane: Lane::Middle(index),
                        base: pose_at(tb),
                        passes: Vec::new(),
                    });
                    tf = missing(tb + x[0], &stations).unwrap_or(gap);
                }
                None => tf -= BASE_STEP_M,
            }
        }
        stations
    }

    /// Shares every ceiling stroke among the stations that reach it and
    /// gives each its ceiling pass.
    fn ceiling_passes(&self, stations: &mut [Station], strokes: &(Vec<f64>, f64)) {
        let rects: Vec<Rect> = stations
            .iter()
            .map(|s| self.ceiling_reach(&s.base))
            .collect();
        let mut lines: Vec<Vec<Line>> = vec![Vec::new(); stations.len()];
        // The walls' stations take their share first, whatever the order of
        // the visit: their part of a row then ends where the reach of the
        // wall's own stations ends, and the lanes in the middle take the
        // rest.
        let is_wall = |k: &usize| matches!(stations[*k].lane, Lane::Wall(_));
        let order: Vec<usize> = (0..stations.len())
            .filter(is_wall)
            .chain((0..stations.len()).filter(|k| !is_wall(k)))
            .collect();
        for &y in &strokes.0 {
            let inside = self.outline.row_spans(y, self.tool.surface_gap_m);
            let mut taken: Vec<[f64; 2]> = Vec::new();
            for &k in &order {
                let r = &rects[k];
                if y < r.v_m[0] - 1e-9 || y > r.v_m[1] + 1e-9 {
                    continue;
                }
                // The row's stretches inside the room, in the reach.
                let mut free: Vec<[f64; 2]> = inside
                    .iter()
                    .filter_map(|s| {
                        let (a, b) = (s[0].max(r.u_m[0]), s[1].min(r.u_m[1]));
                        (b > a).then_some([a, b])
                    })
                    .collect();
                for t in &taken {
                    cut_spans(&mut free, *t);
                }
                if free.is_empty() {
                    continue;
                }
                lines[k].push(Line {
                    pieces: free.iter().map(|p| ([p[0], y], [p[1], y])).collect(),
                    speed_mps: strokes.1,
                });
                taken.push(r.u_m);
            }
        }
        for (station, lines) in stations.iter_mut().zip(lines) {
            if !lines.is_empty() {
                station.passes.push(Pass {
                    surface: SurfaceId::Ceiling,
                    aim: Aim::Up,
                    moves: boustrophedon(&lines, self.tool.axis_speed_mps, true),
                });
            }
        }
    }
}

/// A stroke: pieces sprayed along one line, at one speed.
#[derive(Clone, Debug)]
struct Line {
    pieces: Vec<([f64; 2], [f64; 2])>,
    speed_mps: f64,
}

/// Moves over `lines`, the spray off between pieces at the axes' speed.
/// Consecutive lines cut into as many pieces each (strokes across a
/// window: below it and above it) are taken tier by tier, every line's
/// first piece and then every line's second, so the nozzle crosses the
/// opening once rather than once a stroke. Within a tier the lines are
/// taken alternately forward and backward, the first from the end nearer
/// the nozzle (the very first forward when `forward_first`, else
/// backward).
fn boustrophedon(lines: &[Line], axis_speed_mps: f64, forward_first: bool) -> Vec<Move> {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let mut moves: Vec<Move> = Vec::new();
    let mut at: Option<[f64; 2]> = None;
    let mut first = 0;
    while first < lines.len() {
        let k = lines[first].pieces.len();
        let run = &lines[first
            ..first
                + lines[first..]
                    .iter()
                    .take_while(|l| l.pieces.len() == k)
                    .count()];
        first += run.len();
        for tier in 0..k {
            let (a, b) = run[0].pieces[tier];
            let mut forward = at.map_or(forward_first, |p| dist(p, a) <= dist(p, b));
            for line in run {
                let (a, b) = line.pieces[tier];
                let (from, to) = if forward { (a, b) } else { (b, a) };
                if let Some(p) = at
                    && dist(p, from) > 1e-9
                {
                    moves.push(Move {
                        from_m: p,
                        to_m: from,
                        speed_mps: axis_speed_mps,
                        spray: false,
                    });
                }
                moves.push(Move {
                    from_m: from,
                    to_m: to,
                    speed_mps: line.speed_mps,
                    spray: true,
                });
                at = Some(to);
                forward = !forward;
            }
        }
    }
    moves
}

/// Lanes in the order of a greedy tour from `start`: always the lane whose
/// first station is nearest the last one visited.
fn order_lanes(mut lanes: Vec<(Lane, Vec<Station>)>, start: &Pose2) -> Vec<Station> {
    lanes.retain(|(_, s)| !s.is_empty());
    let mut out = Vec::new();
    let mut at = start.position();
    while !lanes.is_empty() {
        let next = lanes
            .iter()
            .enumerate()
            .map(|(i, (_, s))| (i, (s[0].base.position() - at).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(i, _)| i);
        let (_, stations) = lanes.remove(next);
        if let Some(last) = stations.last() {
            at = last.base.position();
        }
        out.extend(stations);
    }
    out
}

/// The band of a surface a spraying move coats: its path widened across
/// by the width its speed lays the coat over, and by half a cell all
/// round, so neighbouring bands (strokes at uneven spacing, pieces of one
/// stroke from two stations) leave no sliver between them.
fn band(m: &Move, tool: &SprayTool) -> Rect {
    let half = tool.area_rate_m2ps() / m.speed_mps / 2.0 + PLAN_CELL_M / 2.0;
    let e = PLAN_CELL_M / 2.0;
    let (u, v) = (
        [
            m.from_m[0].min(m.to_m[0]) - e,
            m.from_m[0].max(m.to_m[0]) + e,
        ],
        [
            m.from_m[1].min(m.to_m[1]) - e,
            m.from_m[1].max(m.to_m[1]) + e,
        ],
    );
    if u[1] - u[0] < v[1] - v[0] {
        Rect {
            u_m: [u[0] - half, u[1] + half],
            v_m: v,
        }
    } else {
        Rect {
            u_m: u,
            v_m: [v[0] - half, v[1] + half],
        }
    }
}

/// The cells of `surface` the coat reaches in full: those inside the
/// `bands` the strokes coat, less a ramp wherever the bands end on
/// plasterable ground (where they end at an edge or an opening's margin,
/// the margin takes the ramp).
fn reach_mask(surface: &Surface, bands: &[Rect], tool: &SprayTool) -> ReachMask {
    let [su, sv] = surface.size_m();
    let nu = ((su / PLAN_CELL_M).ceil() as usize).max(1);
    let nv = ((sv / PLAN_CELL_M).ceil() as usize).max(1);
    let center = |i: usize, j: usize| {
        [
            (i as f64 + 0.5) * PLAN_CELL_M,
            (j as f64 + 0.5) * PLAN_CELL_M,
        ]
    };
    let inside: Vec<bool> = (0..nv)
        .flat_map(|j| (0..nu).map(move |i| (i, j)))
        .map(|(i, j)| {
            let p = center(i, j);
            !surface.plasterable(p, tool) || bands.iter().any(|r| r.contains(p))
        })
        .collect();
    let r = (tool.ramp_m() / PLAN_CELL_M).ceil() as i64;
    let mut reached = vec![false; nu * nv];
    for j in 0..nv as i64 {
        for i in 0..nu as i64 {
            let mut ok = true;
            'n: for dj in -r..=r {
                for di in -r..=r {
                    if di * di + dj * dj > r * r {
                        continue;
                    }
                    let (a, b) = (i + di, j + dj);
                    if a < 0 || b < 0 || a >= nu as i64 || b >= nv as i64 {
                        continue;
                    }
                    if !inside[b as usize * nu + a as usize] {
                        ok = false;
                        break 'n;
                    }
                }
            }
            reached[j as usize * nu + i as usize] = ok;
        }
    }
    ReachMask {
        surface: surface.id,
        cell_m: PLAN_CELL_M,
        cells: [nu, nv],
        reached,
    }
}

/// The plasterable area of `surface` its mask leaves out, if any.
fn lost_area(surface: &Surface, mask: &ReachMask, tool: &SprayTool) -> Option<Unreachable> {
    let mut area = 0.0;
    let mut bounds = Rect {
        u_m: [f64::MAX, f64::MIN],
        v_m: [f64::MAX, f64::MIN],
    };
    let c = mask.cell_m;
    for j in 0..mask.cells[1] {
        for i in 0..mask.cells[0] {
            let p = [(i as f64 + 0.5) * c, (j as f64 + 0.5) * c];
            if surface.plasterable(p, tool) && !mask.reached[j * mask.cells[0] + i] {
                area += c * c;
                bounds.u_m = [
                    bounds.u_m[0].min(p[0] - c / 2.0),
                    bounds.u_m[1].max(p[0] + c / 2.0),
                ];
                bounds.v_m = [
                    bounds.v_m[0].min(p[1] - c / 2.0),
                    bounds.v_m[1].max(p[1] + c / 2.0),
                ];
            }
        }
    }
    (area > 0.0).then_some(Unreachable {
        surface: surface.id,
        area_m2: area,
        bounds,
    })
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use crate::surface::{Obstacle, OpeningKind, WallOpening};
    use crate::{Surface, predicted_score};
    use proptest::prelude::*;

    fn tool() -> SprayTool {
        SprayTool::default()
    }

    fn room(size_m: [f64; 2], height_m: f64, openings: Vec<WallOpening>) -> RoomModel {
        RoomModel {
            size_m,
            corners: Vec::new(),
            height_m,
            openings,
            obstacles: Vec::new(),
        }
    }

    fn make(r: &RoomModel) -> Plan {
        let start = Pose2::new(r.size_m[0] / 2.0, r.size_m[1] / 2.0, 0.0);
        plan(r, &tool(), &VehicleSpec::default(), &start).expect("a plan")
    }

    /// True when the axis-aligned segment `a → b` enters the open
    /// rectangle `r`.
    fn crosses(a: [f64; 2], b: [f64; 2], r: &Rect) -> bool {
        let (u0, u1) = (a[0].min(b[0]), a[0].max(b[0]));
        let (v0, v1) = (a[1].min(b[1]), a[1].max(b[1]));
        u1 > r.u_m[0] && u0 < r.u_m[1] && v1 > r.v_m[0] && v0 < r.v_m[1]
    }

    /// How many moves of `pass` cross `r` spray off, from below it to
    /// above it or back.
    fn crossings(pass: &Pass, r: &Rect) -> usize {
        pass.moves
            .iter()
            .filter(|m| {
                let (lo, hi) = (m.from_m[1].min(m.to_m[1]), m.from_m[1].max(m.to_m[1]));
                !m.spray && lo <= r.v_m[0] && hi >= r.v_m[1] && crosses(m.from_m, m.to_m, r)
            })
            .count()
    }

    /// Each move of `pass` starts where the last one ended.
    fn assert_continuous(pass: &Pass) {
        for w in pass.moves.windows(2) {
            let gap = (w[0].to_m[0] - w[1].from_m[0]).hypot(w[0].to_m[1] - w[1].from_m[1]);
            assert!(gap < 1e-9, "{w:?}");
        }
    }

    /// Every aim point lies on its surface, every spraying move stays
    /// `spray_off_m` clear of the openings, and the nozzle reaches every
    /// aim point from its station with the gantry's travel less the
    /// position tolerance.
    fn check_moves(p: &Plan) {
        let t = &p.tool;
        let (rail, arm) = (t.planned_rail_m(), t.planned_arm_m());
        for station in &p.stations {
            for pass in &station.passes {
                assert_continuous(pass);
                let s: &Surface = p.surface(pass.surface).expect("surface");
                let [su, sv] = s.size_m();
                for m in &pass.moves {
                    for q in [m.from_m, m.to_m] {
                        assert!(q[0] >= -1e-9 && q[0] <= su + 1e-9, "{q:?} off {:?}", s.id);
                        assert!(q[1] >= -1e-9 && q[1] <= sv + 1e-9, "{q:?} off {:?}", s.id);
                        let n = p.nozzle_point(pass.surface, q).expect("nozzle");
                        let local = station
                            .base
                            .inverse()
                            .transform_point(&nalgebra::Point2::new(n.x, n.y));
                        let e = 1e-6;
                        assert!(
                            local.x >= rail[0] - e && local.x <= rail[1] + e,
                            "{local:?}"
                        );
                        assert!(local.y >= arm[0] - e && local.y <= arm[1] + e, "{local:?}");
                        assert!(n.z >= t.lift_m[0] - e && n.z <= t.lift_m[1] + e, "{n:?}");
                    }
                    if m.spray {
                        for o in &s.openings {
                            let keep = o.rect.grown(t.spray_off_m - 1e-6);
                            assert!(!crosses(m.from_m, m.to_m, &keep), "{m:?} sprays {o:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_station_given_up_leaves_what_only_it_reached_unreachable() {
        // A hall: each end wall is coated from stations of its own.
        let mut p = make(&room([8.0, 1.2], 2.6, Vec::new()));
        assert!(p.unreachable.is_empty(), "{:?}", p.unreachable);
        let stations = p.stations.len();
        let west: Vec<usize> = (0..stations)
            .filter(|&k| p.stations[k].lane == Lane::Wall(WallName::WEST))
            .collect();
        assert!(!west.is_empty());
        let mut lost = 0.0;
        for (n, k) in west.iter().enumerate() {
            lost += p.give_up_station(k - n).expect("a station");
        }
        assert_eq!(p.stations.len(), stations - west.len());
        // The west wall less its edges (1.2 - 2 × 0.11 by 2.6 - 0.1 - 0.11),
        // and nothing of the other surfaces, which other stations reach.
        let [u] = p.unreachable.as_slice() else {
            panic!("{:?}", p.unreachable);
        };
        assert_eq!(u.surface, SurfaceId::Wall(WallName::WEST));
        assert!((u.area_m2 - 0.98 * 2.39).abs() < 0.05, "{u:?}");
        assert!((lost - u.area_m2).abs() < 1e-9, "{lost}");
        assert_eq!(p.give_up_station(p.stations.len()), None);
    }

    #[test]
    fn a_bare_room_is_coated_evenly_all_over() {
        let p = make(&room([4.0, 3.0], 2.5, Vec::new()));
        check_moves(&p);
        assert!(p.unreachable.is_empty(), "{:?}", p.unreachable);
        // A wall pass followed by the ceiling's ends up the wall, not at
        // its foot, whichever number of strokes it has.
        let mut ends = Vec::new();
        for s in &p.stations {
            for q in s.passes.windows(2) {
                if let (SurfaceId::Wall(_), SurfaceId::Ceiling) = (q[0].surface, q[1].surface) {
                    let first = q[0].moves.first().expect("a stroke");
                    let last = q[0].moves.last().expect("a stroke");
                    assert!(last.to_m[1] > 1.5, "{last:?}");
                    ends.push(first.to_m[1] > first.from_m[1]);
                }
            }
        }
        // Some begin at the top, some at the foot.
        assert!(ends.contains(&true) && ends.contains(&false), "{ends:?}");
        let s = predicted_score(&p);
        assert!(s.wall_coverage_pct >= 99.9, "{s:?}");
        assert!(s.ceiling_coverage_pct >= 99.9, "{s:?}");
        assert!(s.thickness_cv <= 0.02, "{s:?}");
        assert_eq!(s.overspray_pct, 0.0);
        // Every plasterable square metre is sprayed once: what left the
        // nozzle is the coat times the area, plus what the strokes lay
        // past the plasterable edges.
        let area: f64 = s.surfaces.iter().map(|x| x.plasterable_m2).sum();
        let coat_l = area * tool().thickness_m() * 1000.0;
        assert!(
            s.sprayed_l > coat_l && s.sprayed_l < 1.15 * coat_l,
            "{} {coat_l}",
            s.sprayed_l
        );
    }

    /// A room drawn by its corners, 2.5 m high, bare.
    fn drawn(corners: &[[f64; 2]]) -> RoomModel {
        let (mut xs, mut ys) = (0.0f64, 0.0f64);
        for c in corners {
            (xs, ys) = (xs.max(c[0]), ys.max(c[1]));
        }
        RoomModel {
            size_m: [xs, ys],
            corners: corners.to_vec(),
            height_m: 2.5,
            openings: Vec::new(),
            obstacles: Vec::new(),
        }
    }

    /// Rooms that are not rectangles: an L (its notch's two walls are
    /// walls, the notch is no floor and no ceiling), one with a wall at
    /// 45°, one with a chimney breast. Every wall gets its lane, every
    /// station stands inside the room clear of its walls, no stroke
    /// leaves the surfaces, and the coat covers the walls and the ceiling
    /// as in a rectangle.
    #[test]
    fn a_room_of_any_shape_is_planned_wall_by_wall() {
        let rooms = [
            (
                "L",
                drawn(&[
                    [0.0, 0.0],
                    [6.0, 0.0],
                    [6.0, 2.5],
                    [3.5, 2.5],
                    [3.5, 5.0],
                    [0.0, 5.0],
                ]),
                [1.5, 1.5],
            ),
            (
                "angled",
                drawn(&[[0.0, 0.0], [5.0, 0.0], [5.0, 2.5], [3.0, 4.5], [0.0, 4.5]]),
                [2.0, 2.0],
            ),
            (
                "chimney breast",
                drawn(&[
                    [0.0, 0.0],
                    [4.5, 0.0],
                    [4.5, 4.0],
                    [2.8, 4.0],
                    [2.8, 3.55],
                    [1.6, 3.55],
                    [1.6, 4.0],
                    [0.0, 4.0],
                ]),
                [2.2, 1.5],
            ),
        ];
        let t = tool();
        let v = VehicleSpec::default();
        for (name, room, [x, y]) in rooms {
            let p = plan(&room, &t, &v, &Pose2::new(x, y, 0.0)).expect("a plan");
            check_moves(&p);
            let walls = room.corners.len();
            assert_eq!(p.surfaces.len(), walls + 1, "{name}");
            let outline = room.outline();
            let body = Body::of(&v);
            for s in &p.stations {
                let corners = [
                    [body.x_m[0], -body.half_width_m],
                    [body.x_m[1], -body.half_width_m],
                    [body.x_m[1], body.half_width_m],
                    [body.x_m[0], body.half_width_m],
                ]
                .map(|[a, b]| s.base.transform_point(&nalgebra::Point2::new(a, b)));
                assert!(
                    outline.holds(&corners, t.clearance_m),
                    "{name}: {:?}",
                    s.base
                );
            }
            for k in 0..walls {
                let lane = Lane::Wall(WallName::new(k));
                assert!(
                    p.stations.iter().any(|s| s.lane == lane),
                    "{name}: no station for wall {k}"
                );
            }
            let s = predicted_score(&p);
            assert!(
                s.wall_coverage_pct >= 99.5,
                "{name}: {s:?} {:?}",
                p.unreachable
            );
            assert!(
                s.ceiling_coverage_pct >= 99.0,
                "{name}: {s:?} {:?}",
                p.unreachable
            );
            assert!(s.overspray_pct < 0.5, "{name}: {s:?}");
        }
    }

    #[test]
    fn strokes_stop_short_of_windows_and_doors() {
        let openings = vec![
            WallOpening {
                wall: WallName::SOUTH,
                kind: OpeningKind::Window,
                along_m: [1.3, 2.5],
                sill_head_m: [0.9, 2.1],
            },
            WallOpening {
                wall: WallName::EAST,
                kind: OpeningKind::Door,
                along_m: [0.4, 1.3],
                sill_head_m: [0.0, 2.0],
            },
        ];
        let p = make(&room([4.0, 3.0], 2.6, openings));
        check_moves(&p);
        let s = predicted_score(&p);
        assert!(s.wall_coverage_pct >= 99.9, "{s:?}");
        assert!(s.overspray_pct <= 0.5 && s.overspray_pct > 0.0, "{s:?}");
        // The strokes across the window are taken below it, then above
        // it: the nozzle crosses it once a pass, not once a stroke.
        let window = p
            .surface(SurfaceId::Wall(WallName::SOUTH))
            .expect("wall")
            .openings[0]
            .rect;
        let across: Vec<&Pass> = p
            .passes()
            .map(|(_, q)| q)
            .filter(|q| q.surface == SurfaceId::Wall(WallName::SOUTH))
            .filter(|q| {
                q.moves
                    .iter()
                    .any(|m| m.spray && m.from_m[0] > window.u_m[0] && m.from_m[0] < window.u_m[1])
            })
            .collect();
        assert!(!across.is_empty());
        for q in &across {
            assert!(crossings(q, &window) <= 1, "{q:?}");
        }
        // Taken again from what they spray, the passes are as planned.
        for (_, q) in p.passes() {
            let mut again = q.clone();
            again.restroke(p.tool.axis_speed_mps);
            assert_eq!(&again, q);
        }
    }

    #[test]
    fn floor_furniture_cuts_off_from_the_robot_is_reported_not_planned() {
        // A bed and a desk end to end across a 4 m bedroom, 1.5–2.45 m in
        // from its south wall; the robot stands south of them. The strip
        // north of them is floor it cannot get to: no station there, and
        // the north wall is reported unreachable, not dropped.
        let from_the_door = |r: &RoomModel| {
            let at_door = Pose2::new(3.4, 0.6, std::f64::consts::FRAC_PI_2);
            plan(r, &tool(), &VehicleSpec::default(), &at_door).expect("a plan")
        };
        let mut r = room([4.0, 3.65], 2.6, Vec::new());
        r.obstacles = vec![Obstacle {
            min_m: [0.0, 1.5],
            max_m: [4.0, 2.45],
            height_m: 0.75,
        }];
        let p = from_the_door(&r);
        check_moves(&p);
        assert!(!p.stations.is_empty());
        for s in &p.stations {
            assert!(
                s.base.y < 1.5,
                "a station beyond the furniture: {:?}",
                s.base
            );
        }
        let north = p
            .unreachable
            .iter()
            .find(|u| u.surface == SurfaceId::Wall(WallName::NORTH))
            .expect("the north wall behind the furniture");
        // All of it: the wall less its 10 cm edges, 3.8 × 2.4 m.
        assert!(north.area_m2 > 0.99 * 3.8 * 2.4, "{north:?}");
        // The same room with the strip joined to the rest by a gap the
        // robot passes (the desk 1.2 m short of the east wall): the
        // north wall is planned.
        r.obstacles[0].max_m[0] = 2.8;
        let p = from_the_door(&r);
        assert!(
            p.stations.iter().any(|s| s.base.y > 2.45),
            "{:?}",
            p.stations.len()
        );
    }

    #[test]
    fn what_furniture_hides_is_reported_not_dropped() {
        // A sofa along the west wall, 0.9 m deep, 0.8 m high: the robot
        // cannot stand at the west wall, and the wall behind it is
        // unreachable; a radiator on the south wall keeps the nozzle above
        // its top there.
        let mut r = room([5.0, 3.0], 2.6, Vec::new());
        r.obstacles = vec![
            Obstacle {
                min_m: [0.0, 0.6],
                max_m: [0.9, 2.6],
                height_m: 0.8,
            },
            Obstacle {
                min_m: [2.0, 0.04],
                max_m: [3.0, 0.14],
                height_m: 0.6,
            },
        ];
        let p = make(&r);
        check_moves(&p);
        let body = Body::of(&VehicleSpec::default());
        for s in &p.stations {
            let [lo, hi] = room_box(&s.base, body.x_m, [-body.half_width_m, body.half_width_m]);
            assert!(hi[0] <= 0.0 || lo[0] >= 0.9 + 0.12 - 1e-9 || lo[1] >= 2.6 || hi[1] <= 0.6);
        }
        let west = p
            .unreachable
            .iter()
            .find(|u| u.surface == SurfaceId::Wall(WallName::WEST))
            .expect("the west wall behind the sofa");
        // The sofa spans y 0.6–2.6 of the 3 m wall: most of the wall.
        assert!(west.area_m2 > 2.0 * 2.3, "{west:?}");
        let south = p
            .unreachable
            .iter()
            .find(|u| u.surface == SurfaceId::Wall(WallName::SOUTH))
            .expect("below the radiator");
        assert!(
            south.bounds.v_m[0] < 0.2 && south.bounds.v_m[1] > 0.7,
            "{south:?}"
        );
        assert!(
            south.bounds.u_m[0] < 2.0 && south.bounds.u_m[1] > 3.0,
            "{south:?}"
        );
        for (_, pass) in p
            .passes()
            .filter(|(_, p)| p.surface == SurfaceId::Wall(WallName::SOUTH))
        {
            for m in pass.moves.iter().filter(|m| m.spray) {
                if m.from_m[0] > 2.0 && m.from_m[0] < 3.0 {
                    assert!(m.from_m[1].min(m.to_m[1]) >= 0.72 - 1e-9, "{m:?}");
                }
            }
        }
        let s = predicted_score(&p);
        assert!(
            s.wall_coverage_pct >= 99.9 && s.ceiling_coverage_pct >= 99.9,
            "{s:?}"
        );
        assert!(
            (s.unreachable_m2 - p.unreachable.iter().map(|u| u.area_m2).sum::<f64>()).abs() < 0.05
        );
    }

    #[test]
    fn a_wall_beside_a_wardrobe_is_reached_from_farther_out() {
        // A wardrobe 0.6 m deep and 2 m high against the south wall, u
        // 0.9–1.9 m: at the tool's standoff the body (0.95 m long, and its
        // clearance) cannot stand between it and the west wall, nor reach
        // round it; farther out it stands beside the wardrobe, and the arm
        // reaches the wall between, never over the wardrobe.
        let mut r = room([5.0, 4.0], 2.6, Vec::new());
        let wardrobe = Obstacle {
            min_m: [0.9, 0.0],
            max_m: [1.9, 0.6],
            height_m: 2.0,
        };
        r.obstacles = vec![wardrobe];
        let p = make(&r);
        check_moves(&p);
        let t = tool();
        let body = Body::of(&VehicleSpec::default());
        let south = WallName::SOUTH;
        let mut farther = 0;
        for s in &p.stations {
            let [lo, hi] = room_box(&s.base, body.x_m, [-body.half_width_m, body.half_width_m]);
            let c = t.clearance_m - 1e-9;
            assert!(
                hi[0] <= wardrobe.min_m[0] - c
                    || lo[0] >= wardrobe.max_m[0] + c
                    || lo[1] >= wardrobe.max_m[1] + c,
                "{:?} meets the wardrobe",
                s.base
            );
            if s.lane == Lane::Wall(south) && s.base.y > t.robot_standoff_m + 1e-6 {
                farther += 1;
                assert!(s.base.y <= t.wall_standoff_m + t.planned_arm_m()[1] + 1e-9);
            }
        }
        assert!(farther > 0, "no station beside the wardrobe");
        for (_, pass) in p
            .passes()
            .filter(|(_, p)| p.surface == SurfaceId::Wall(south))
        {
            for m in pass.moves.iter().filter(|m| m.spray) {
                let u = m.from_m[0];
                assert!(
                    u <= wardrobe.min_m[0] || u >= wardrobe.max_m[0],
                    "sprays over the wardrobe: {m:?}"
                );
            }
        }
        // What is left of the south wall is what the wardrobe hides, and
        // the tool's margins beside it.
        let left = p
            .unreachable
            .iter()
            .find(|u| u.surface == SurfaceId::Wall(south))
            .expect("the wall behind the wardrobe");
        assert!(
            left.bounds.u_m[0] > 0.7 && left.bounds.u_m[1] < 2.1,
            "{left:?}"
        );
        // The coat even over what the plan reaches, the stations near and
        // far out meeting without a double band.
        let s = predicted_score(&p);
        assert!(
            s.wall_coverage_pct >= 99.9 && s.ceiling_coverage_pct >= 99.9,
            "{s:?}"
        );
    }

    #[test]
    fn wall_above_the_lift_is_reported() {
        // A 3.3 m room: the lift reaches 3.1 m, so each wall's top band
        // (up to the edge margin under the ceiling) is out of reach.
        let p = make(&room([4.0, 3.0], 3.3, Vec::new()));
        check_moves(&p);
        assert_eq!(p.unreachable.len(), 4, "{:?}", p.unreachable);
        for u in &p.unreachable {
            assert!(matches!(u.surface, SurfaceId::Wall(_)));
            assert!((u.bounds.v_m[1] - (3.3 - 0.08)).abs() < 0.021, "{u:?}");
            // Full coat only up to where the ramp above the last stroke
            // allows.
            assert!((u.bounds.v_m[0] - (3.1 - 0.07)).abs() < 0.021, "{u:?}");
        }
        let s = predicted_score(&p);
        assert!(
            s.wall_coverage_pct >= 99.9 && s.ceiling_coverage_pct >= 99.9,
            "{s:?}"
        );
    }

    #[test]
    fn a_ceiling_out_of_the_lifts_reach_is_refused() {
        let r = room([4.0, 3.0], 3.5, Vec::new());
        let e = plan(
            &r,
            &tool(),
            &VehicleSpec::default(),
            &Pose2::new(2.0, 1.5, 0.0),
        )
        .expect_err("too high");
        assert!(e.to_string().contains("lift"), "{e}");
    }

    fn opening() -> impl Strategy<Value = (usize, f64, f64, bool, f64, f64)> {
        // Wall, position share, width, door?, sill, height.
        (
            0usize..4,
            0.0..1.0f64,
            0.5..1.4f64,
            any::<bool>(),
            0.6..1.2f64,
            0.5..1.2f64,
        )
    }

    #[test]
    fn a_window_found_at_a_station_is_kept_out_of_the_passes_from_there_on() {
        let r = room([4.0, 3.0], 2.6, Vec::new());
        let mut p = make(&r);
        let wall = WallName::EAST;
        let id = SurfaceId::Wall(wall);
        let on_wall: Vec<usize> = p
            .stations
            .iter()
            .enumerate()
            .filter(|(_, s)| s.passes.iter().any(|q| q.surface == id))
            .map(|(i, _)| i)
            .collect();
        assert!(on_wall.len() >= 2, "{on_wall:?}");
        let (first, from) = (on_wall[0], on_wall[1]);
        let before = p.clone();
        let (along, sill_head) = ([0.9, 1.9], [1.0, 2.1]);
        assert!(p.add_window(wall, along, sill_head, from));
        // Seen again inside it: nothing more to do.
        assert!(!p.add_window(wall, [1.0, 1.8], [1.1, 2.0], from));
        let keep_out = Rect {
            u_m: along,
            v_m: sill_head,
        }
        .grown(p.tool.spray_off_m - 1e-9);
        for (k, (a, b)) in before.stations.iter().zip(&p.stations).enumerate() {
            for (qa, qb) in a.passes.iter().zip(&b.passes) {
                let sprays_in = qb
                    .moves
                    .iter()
                    .any(|m| m.spray && keep_out.clip(m.from_m, m.to_m).is_some());
                if qb.surface == id && k >= from {
                    assert!(!sprays_in, "station {k} sprays into the window");
                    // All it sprayed outside the window it still sprays,
                    // in one go: below the window, then above it, the
                    // window crossed once, spray off.
                    let outside = |q: &Pass| -> f64 {
                        q.moves
                            .iter()
                            .filter(|m| m.spray)
                            .map(|m| {
                                let inside = keep_out.clip(m.from_m, m.to_m);
                                m.length_m() * (1.0 - inside.map_or(0.0, |[t0, t1]| t1 - t0))
                            })
                            .sum()
                    };
                    assert!((outside(qa) - outside(qb)).abs() < 1e-6, "station {k}");
                    assert!(crossings(qb, &keep_out) <= 1, "station {k}: {qb:?}");
                    let sprayed_in = qa
                        .moves
                        .iter()
                        .any(|m| m.spray && keep_out.clip(m.from_m, m.to_m).is_some());
                    if sprayed_in {
                        assert!(qb.duration_s() < qa.duration_s(), "station {k}");
                    } else {
                        assert_eq!(qa, qb, "station {k}");
                    }
                    assert_continuous(qb);
                } else {
                    // Before the station it was found at, and elsewhere:
                    // as planned.
                    assert_eq!(qa, qb, "station {k}");
                }
            }
        }
        // The station before it had sprayed into it (the plan did not
        // know the window).
        let sprayed_before = before.stations[first]
            .passes
            .iter()
            .chain(before.stations[from].passes.iter())
            .filter(|q| q.surface == id)
            .any(|q| {
                q.moves
                    .iter()
                    .any(|m| m.spray && keep_out.clip(m.from_m, m.to_m).is_some())
            });
        assert!(sprayed_before);
        let s = p.surface(id).expect("the east wall");
        assert_eq!(s.openings.len(), 1);
        assert_eq!(p.room.openings.len(), 1);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Masking a pass keeps its time and its spraying outside the
        /// rectangle, and sprays nothing inside it.
        #[test]
        fn spray_off_inside_lays_nothing_there_and_keeps_the_rest(
            pts in proptest::collection::vec((0.0..3.0f64, 0.0..2.6f64, any::<bool>()), 2..12),
            u0 in 0.0..2.5f64, du in 0.05..1.5f64, v0 in 0.0..2.2f64, dv in 0.05..1.2f64,
        ) {
            let moves: Vec<Move> = pts.windows(2).map(|w| Move {
                from_m: [w[0].0, w[0].1],
                to_m: [w[1].0, w[1].1],
                speed_mps: 0.3,
                spray: w[0].2,
            }).collect();
            let mut pass = Pass { surface: SurfaceId::Wall(WallName::NORTH), aim: Aim::Left, moves };
            let before = pass.clone();
            let rect = Rect { u_m: [u0, u0 + du], v_m: [v0, v0 + dv] };
            pass.spray_off_inside(&rect);
            prop_assert!((pass.duration_s() - before.duration_s()).abs() < 1e-9);
            let inside = |q: &Pass| -> f64 {
                q.moves.iter().filter(|m| m.spray).map(|m| {
                    rect.clip(m.from_m, m.to_m).map_or(0.0, |[a, b]| (b - a) * m.length_m())
                }).sum()
            };
            prop_assert!(inside(&pass) < 1e-9, "{}", inside(&pass));
            let sprayed = |q: &Pass| -> f64 { q.moves.iter().filter(|m| m.spray).map(Move::length_m).sum() };
            prop_assert!((sprayed(&before) - inside(&before) - sprayed(&pass)).abs() < 1e-9);
        }

        /// A coverage plan stays inside its surfaces and clear of their
        /// openings, reaches every aim point, and its own prediction
        /// coats ≥ 99.9% of the plasterable area within tolerance.
        #[test]
        fn plans_cover_their_rooms(
            xs in 2.6..6.5f64,
            ys in 2.4..5.0f64,
            h in 2.3..3.1f64,
            ops in proptest::collection::vec(opening(), 0..3),
        ) {
            let mut openings: Vec<WallOpening> = Vec::new();
            for (w, at, width, door, sill, height) in ops {
                let wall = WallName::ALL[w];
                let len = crate::WallLine::of(wall, [xs, ys]).map_or(0.0, |l| l.length_m);
                let width = width.min(len - 0.6);
                let a = 0.3 + at * (len - 0.6 - width);
                let sill_head = if door { [0.0, 2.0_f64.min(h - 0.3)] } else { [sill, (sill + height).min(h - 0.2)] };
                let new = [a, a + width];
                // One opening per stretch of wall, as buildings have.
                if openings.iter().any(|o| o.wall == wall && o.along_m[0] < new[1] + 0.3 && o.along_m[1] > new[0] - 0.3) {
                    continue;
                }
                openings.push(WallOpening {
                    wall,
                    kind: if door { OpeningKind::Door } else { OpeningKind::Window },
                    along_m: new,
                    sill_head_m: sill_head,
                });
            }
            let p = make(&room([xs, ys], h, openings));
            check_moves(&p);
            prop_assert!(p.unreachable.is_empty(), "{:?}", p.unreachable);
            let s = predicted_score(&p);
            prop_assert!(s.wall_coverage_pct >= 99.9, "{:?}", s);
            prop_assert!(s.ceiling_coverage_pct >= 99.9, "{:?}", s);
            prop_assert!(s.overspray_pct <= 0.5, "{:?}", s);
        }
    }
}
