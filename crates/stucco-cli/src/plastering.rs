//! Plastering in a task mission: the simulated sprayer made from the
//! mission's `[spray]` table, the plaster the simulator laid scored on the
//! true surfaces of the robot's room, the world's plaster kept across a
//! kill, and a thickness map per surface.

use crate::room_frame::RoomFrame;
use anyhow::{Context, Result};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;
use stucco_core::{Pose2, ThicknessGrid, WallName};
use stucco_plan::{
    OpeningKind as PlanOpening, Plan, RoomModel, RoomScore, SprayTool, SurfaceId, SurfaceScore,
    WallLine, WallOpening, score,
};
use stucco_runtime::write_atomic;
use stucco_sim::{Coat, Layout, OpeningKind, Simulator, SprayerSpec, SurfaceKind, TrueOpening};

/// Cells of the simulator's thickness grids, m (the issue asks ≤ 2 cm).
pub const COAT_CELL_M: f64 = 0.02;

/// The simulator's sprayer for the mission's tool.
pub fn sprayer_of(tool: &SprayTool) -> SprayerSpec {
    SprayerSpec {
        flow_m3ps: tool.flow_m3ps(),
        sigma_m: tool.footprint_sigma_m,
        sigma_at_m: tool.wall_standoff_m,
        axis_speed_mps: tool.axis_speed_mps,
        cell_m: COAT_CELL_M,
        park_m: stucco_mission::PARK_NOZZLE_M,
        camera: tool.camera.then(stucco_sim::CameraSpec::on_tool),
    }
}

/// The true openings of the room of `frame`, each with the wall it is in
/// and its edges along that wall (room frame).
pub(crate) fn room_openings<'a>(
    layout: &'a Layout,
    frame: &'a RoomFrame,
) -> impl Iterator<Item = (&'a TrueOpening, WallName, [f64; 2])> + 'a {
    layout
        .openings
        .iter()
        .filter(|o| o.room == frame.name)
        .filter_map(|o| {
            let e: Vec<nalgebra::Vector2<f64>> = o
                .edges
                .iter()
                .map(|p| nalgebra::Vector2::new(p.x - frame.origin[0], p.y - frame.origin[1]))
                .collect();
            let mid = (e[0] + e[1]) / 2.0;
            WallName::ALL.iter().find_map(|&w| {
                let g = WallLine::of(w, frame.size_m)?;
                (g.inward.dot(&(mid - g.origin)).abs() < 0.2).then(|| {
                    let (a, b) = (
                        g.along.dot(&(e[0] - g.origin)),
                        g.along.dot(&(e[1] - g.origin)),
                    );
                    (o, w, [a.min(b), a.max(b)])
                })
            })
        })
}

/// The robot's room as it truly is, in the room frame: what the plaster
/// is scored on.
pub(crate) fn true_room(layout: &Layout, frame: &RoomFrame) -> RoomModel {
    let height_m = layout
        .rooms
        .iter()
        .find(|r| r.name == frame.name)
        .map_or(2.6, |r| r.height_m);
    let openings = room_openings(layout, frame)
        .map(|(o, wall, along_m)| WallOpening {
            wall,
            kind: match o.kind {
                OpeningKind::OpenDoor | OpeningKind::ClosedDoor => PlanOpening::Door,
                OpeningKind::Window | OpeningKind::GlazedWindow => PlanOpening::Window,
            },
            along_m,
            sill_head_m: o.z,
        })
        .collect();
    RoomModel {
        size_m: frame.size_m,
        corners: Vec::new(),
        height_m,
        openings,
        obstacles: Vec::new(),
    }
}

/// The plaster on each true surface of the room, resampled into the
/// planner's surface frames (room frame, `PLAN` conventions) at the
/// simulator's cell size.
pub(crate) fn room_coats(
    coats: &[Coat],
    frame: &RoomFrame,
    room: &RoomModel,
) -> Vec<ThicknessGrid> {
    let mine: Vec<&Coat> = coats.iter().filter(|c| c.room == frame.name).collect();
    room.surfaces()
        .iter()
        .map(|s| {
            let mut grid = ThicknessGrid::new(s.size_m(), COAT_CELL_M);
            let nu = grid.cells[0];
            for k in 0..grid.thickness_m.len() {
                let uv = grid.center(k % nu, k / nu);
                let p = s.frame.point(uv);
                let world =
                    nalgebra::Point3::new(p.x + frame.origin[0], p.y + frame.origin[1], p.z);
                let on = mine.iter().find_map(|c| {
                    let q = c.frame.uv(&world);
                    let off = (world - c.frame.point(q)).norm();
                    let [su, sv] = c.frame.size_m;
                    (off < 0.01 && q[0] >= 0.0 && q[1] >= 0.0 && q[0] <= su && q[1] <= sv)
                        .then_some((c, q))
                });
                if let Some((c, q)) = on {
                    let i = ((q[0] / c.grid.cell_m) as usize).min(c.grid.cells[0] - 1);
                    let j = ((q[1] / c.grid.cell_m) as usize).min(c.grid.cells[1] - 1);
                    grid.thickness_m[k] = c.grid.at(i, j);
                }
            }
            grid
        })
        .collect()
}

/// Top of the robot while it drives, its lift's mast telescoped, m: what
/// stands lower (a table's top) is in its body's way; a door's head
/// (2.0 m and up) is not.
pub const MAST_PARKED_M: f64 = 1.9;

/// Least margin the body keeps while it drives, as the truth's reach
/// takes it, m: the protective field in the tightest setting the shipped
/// missions use (the apartment's), about three times the laser's range
/// noise.
pub const DRIVE_MARGIN_M: f64 = 0.03;

/// The robot's reach and the job's finish as the truth scores them: the
/// body of `vehicle`, the travel and margins of `tool`.
pub fn true_terms(
    tool: &SprayTool,
    vehicle: &stucco_core::VehicleSpec,
) -> (stucco_sim::Reach, stucco_sim::Finish) {
    (
        stucco_sim::Reach {
            body_x_m: [-vehicle.rear_overhang_m, vehicle.front_m()],
            body_half_width_m: vehicle.width_m / 2.0,
            body_top_m: MAST_PARKED_M,
            clearance_m: tool.clearance_m,
            drive_margin_m: DRIVE_MARGIN_M,
            rail_m: tool.rail_m,
            arm_m: tool.arm_m,
            lift_m: tool.lift_m,
            wall_standoff_m: tool.wall_standoff_m,
            ceiling_standoff_m: tool.ceiling_standoff_m,
        },
        stucco_sim::Finish {
            coat_m: tool.thickness_m(),
            tolerance: tool.tolerance,
            skirting_m: tool.skirting_m,
            edge_margin_m: tool.edge_margin_m,
            opening_margin_m: tool.opening_margin_m,
        },
    )
}

/// The plaster on every true plasterable surface of the rooms the job
/// names, whatever the robot planned ([`stucco_sim::score_truth`]).
#[derive(Clone, Debug, Serialize)]
pub struct TruthReport {
    /// The rooms scored: each the job names.
    pub rooms: Vec<String>,
    /// Walls: plasterable, covered, blocked, unreached, m².
    pub walls: stucco_sim::Tally,
    /// Ceilings, the same.
    pub ceilings: stucco_sim::Tally,
    /// Each surface.
    pub surfaces: Vec<stucco_sim::SurfaceTruth>,
    /// What keeps surface from the tool, largest first, each with what
    /// to do about it.
    pub blockers: Vec<BlockerReport>,
}

/// Surface out of the tool's reach and what stands in the way.
#[derive(Clone, Debug, Serialize)]
pub struct BlockerReport {
    /// The room.
    pub room: String,
    /// `wall N` or `ceiling`.
    pub surface: String,
    /// What blocks it (`table`, `box`, …), none for the room's own shape.
    pub what: Option<&'static str>,
    /// Where it stands, m (world frame).
    pub at_m: Option<[f64; 2]>,
    /// The surface it keeps from the tool, m².
    pub area_m2: f64,
    /// What to do: "move the box at (2.50, 3.70) to reach 1.9 m² of wall 2".
    pub advice: String,
}

impl TruthReport {
    /// The true surfaces of `rooms` of `sim`'s world scored, the robot
    /// having started at `start`.
    pub fn of(
        sim: &Simulator,
        rooms: Vec<String>,
        start: &Pose2,
        tool: &SprayTool,
        vehicle: &stucco_core::VehicleSpec,
    ) -> TruthReport {
        let (reach, finish) = true_terms(tool, vehicle);
        let t = stucco_sim::score_truth(sim.layout(), sim.coats(), &rooms, start, &reach, &finish);
        let blockers = t
            .blockers
            .iter()
            .map(|b| {
                let surface = match b.surface {
                    SurfaceKind::Wall { index } => format!("wall {index}"),
                    SurfaceKind::Ceiling => "ceiling".to_owned(),
                };
                let advice = match (b.what, b.at) {
                    (Some(stucco_sim::SHUT_DOOR), Some([x, y])) => format!(
                        "open the shut door at ({x:.2}, {y:.2}) to reach {:.1} m² of the {} \
                         {surface}",
                        b.area_m2, b.room
                    ),
                    (Some(what), Some([x, y])) => format!(
                        "move the {what} at ({x:.2}, {y:.2}) to reach {:.1} m² of the {} {surface}",
                        b.area_m2, b.room
                    ),
                    _ => format!(
                        "{:.1} m² of the {} {surface} is out of this robot's reach (the room's \
                         shape or height)",
                        b.area_m2, b.room
                    ),
                };
                BlockerReport {
                    room: b.room.clone(),
                    surface,
                    what: b.what,
                    at_m: b.at,
                    area_m2: b.area_m2,
                    advice,
                }
            })
            .collect();
        TruthReport {
            rooms,
            walls: t.walls,
            ceilings: t.ceilings,
            surfaces: t.surfaces,
            blockers,
        }
    }
}

/// What a plastering run reports beyond the top-level scores (which sum
/// every room plastered).
#[derive(Clone, Debug, Serialize)]
pub struct PlasterReport {
    /// Stations planned, in all rooms.
    pub stations: usize,
    /// Plasterable area the plans left unreached, m² (reported, not
    /// scored).
    pub unreachable_m2: f64,
    /// Plaster sprayed, litres.
    pub sprayed_l: f64,
    /// Each room plastered, in the order of its `plaster` task.
    pub rooms: Vec<RoomPlaster>,
    /// The floor plan's rooms no `plaster` task plastered.
    pub rooms_left: Vec<RoomLeft>,
    /// Every true plasterable surface of the rooms the job names.
    pub truth: Option<TruthReport>,
}

/// A room of the floor plan the run did not plaster.
#[derive(Clone, Debug, Serialize)]
pub struct RoomLeft {
    /// Its name on the plan.
    pub room: String,
    /// Its floor (and ceiling) as drawn, m².
    pub floor_m2: f64,
    /// Why: no open door leads there, or none the robot fits through, or
    /// no task plastered it.
    pub why: String,
}

/// One room's plastering.
#[derive(Clone, Debug, Serialize)]
pub struct RoomPlaster {
    /// The room (the world's name for it).
    pub room: String,
    /// The `plaster` task.
    pub task: usize,
    /// Stations planned.
    pub stations: usize,
    /// Plasterable area the plan left unreached, m².
    pub unreachable_m2: f64,
    /// Each surface's scores, on the truth.
    pub surfaces: Vec<SurfaceScore>,
    /// What the plan itself predicted, on the room as the robot knew it.
    pub predicted: PredictedScores,
}

/// The plan's own prediction.
#[derive(Clone, Debug, Serialize)]
pub struct PredictedScores {
    /// Walls within tolerance, %.
    pub wall_coverage_pct: f64,
    /// Ceiling within tolerance, %.
    pub ceiling_coverage_pct: f64,
    /// Thickness CV.
    pub thickness_cv: f64,
}

/// Each room's surfaces scored (see [`score_surfaces`]) and all of them
/// summed, over what the simulator sprayed in the run.
pub(crate) fn score_run(
    sim: &Simulator,
    layout: &Layout,
    rooms: &[(&RoomFrame, &Plan)],
) -> (RoomScore, Vec<Vec<SurfaceScore>>) {
    let each: Vec<Vec<SurfaceScore>> = rooms
        .iter()
        .map(|(frame, plan)| score_surfaces(sim, layout, frame, plan))
        .collect();
    let all = each.iter().flatten().cloned().collect();
    (RoomScore::of(all, sim.sprayed_m3() * 1000.0), each)
}

/// The plaster the simulator laid in one room, surface by surface,
/// against the plan's reach (what the plan reports unreachable is not
/// counted), less the robot's position tolerance along the reach's
/// borders: the map's frame, where the plan was made, may sit that far
/// off the true one.
fn score_surfaces(
    sim: &Simulator,
    layout: &Layout,
    frame: &RoomFrame,
    plan: &Plan,
) -> Vec<SurfaceScore> {
    let room = true_room(layout, frame);
    let grids = room_coats(sim.coats(), frame, &room);
    room.surfaces()
        .iter()
        .zip(&grids)
        .filter_map(|(s, g)| {
            let reach = plan.reach_of(s.id)?.eroded(plan.tool.position_tolerance_m);
            Some(score(s, g, &reach, &plan.tool))
        })
        .collect()
}

/// The least time plastering can take: the least area any plan must spray
/// for the plasterable area the plan reaches ([`stucco_plan::minimum_spray_m2`])
/// at the tool's area rate, plus the straight-line travel between
/// stations at the robot's top speed.
pub fn time_lower_bound(plan: &Plan, start: &stucco_core::Pose2, top_speed_mps: f64) -> f64 {
    let area = stucco_plan::minimum_spray_m2(plan);
    let mut at = start.position();
    let mut travel = 0.0;
    for s in &plan.stations {
        travel += (s.base.position() - at).norm();
        at = s.base.position();
    }
    area / plan.tool.area_rate_m2ps() + travel / top_speed_mps
}

/// The simulated world's state (the plaster, where the robot stands) in a
/// job's folder, written with every checkpoint: a resumed run goes on in
/// it.
pub const WORLD_FILE: &str = "world.json";

/// The simulated world's state, written with every checkpoint and kept
/// across a kill: the plaster stays on the walls and the robot stands
/// where it stopped, so a resumed run goes on in the same world and scores
/// the whole job. It is the simulator's: the robot's checkpoint knows
/// nothing of it.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldState {
    /// Where the robot truly stood (world frame).
    pub robot: Pose2,
    /// Coats with plaster on them: room, surface, grid.
    pub coats: Vec<(String, SurfaceKindSer, ThicknessGrid)>,
    /// Plaster sprayed so far, m³.
    pub sprayed_m3: f64,
}

/// A surface's kind as the world state file writes it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKindSer {
    /// A wall by index.
    Wall(usize),
    /// The ceiling.
    Ceiling,
}

impl WorldState {
    /// The state of `sim`: where its robot stands, its plaster.
    pub fn of(sim: &Simulator) -> WorldState {
        WorldState {
            robot: sim.truth().drive.pose,
            coats: sim
                .coats()
                .iter()
                .filter(|c| c.grid.volume_m3() > 0.0)
                .map(|c| {
                    let kind = match c.kind {
                        SurfaceKind::Wall { index } => SurfaceKindSer::Wall(index),
                        SurfaceKind::Ceiling => SurfaceKindSer::Ceiling,
                    };
                    (c.room.clone(), kind, c.grid.clone())
                })
                .collect(),
            sprayed_m3: sim.sprayed_m3(),
        }
    }

    /// Puts the plaster back on `sim`'s surfaces.
    pub fn restore(&self, sim: &mut Simulator) {
        let coats: Vec<(String, SurfaceKind, ThicknessGrid)> = self
            .coats
            .iter()
            .map(|(room, k, g)| {
                let kind = match k {
                    SurfaceKindSer::Wall(index) => SurfaceKind::Wall { index: *index },
                    SurfaceKindSer::Ceiling => SurfaceKind::Ceiling,
                };
                (room.clone(), kind, g.clone())
            })
            .collect();
        sim.restore_coats(&coats, self.sprayed_m3);
    }

    /// Writes it atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        Ok(write_atomic(path, serde_json::to_string(self)?.as_bytes())?)
    }

    /// Reads it back.
    pub fn load(path: &Path) -> Result<WorldState> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{}: not a world state", path.display()))
    }
}

/// Draws a thickness map of each surface of the room (`DIR/coat-NAME.svg`):
/// thickness as colour from bare (white) through the coat (green) to
/// double (red), openings outlined.
pub(crate) fn draw_coats(
    dir: &Path,
    prefix: &str,
    layout: &Layout,
    frame: &RoomFrame,
    sim: &Simulator,
    tool: &SprayTool,
) -> Result<()> {
    let room = true_room(layout, frame);
    let grids = room_coats(sim.coats(), frame, &room);
    for (s, g) in room.surfaces().iter().zip(&grids) {
        let name = match s.id {
            SurfaceId::Ceiling => "ceiling".to_owned(),
            SurfaceId::Wall(w) => format!("wall{}", w.index()),
        };
        let path = dir.join(format!("coat-{prefix}{name}.svg"));
        let [su, sv] = s.size_m();
        let px = 160.0;
        let size = ((su * px) as u32 + 80, (sv * px) as u32 + 70);
        let root = SVGBackend::new(&path, size).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{name}: plaster thickness (coat {} mm)", tool.thickness_mm),
                ("sans-serif", 16),
            )
            .margin(8)
            .x_label_area_size(28)
            .y_label_area_size(36)
            .build_cartesian_2d(0.0..su, 0.0..sv)?;
        chart.configure_mesh().disable_mesh().draw()?;
        let target = tool.thickness_m();
        let c = g.cell_m;
        chart.draw_series(g.iter().filter(|(_, t)| *t > 0.0).map(|(p, t)| {
            let x = (t / target).clamp(0.0, 2.0);
            let colour = if x < 1.0 - tool.tolerance {
                RGBColor(255, (255.0 - 90.0 * x) as u8, (255.0 - 255.0 * x) as u8)
            } else if x <= 1.0 + tool.tolerance {
                RGBColor(60, 170, 80)
            } else {
                RGBColor(200, 40, 40)
            };
            Rectangle::new(
                [
                    (p[0] - c / 2.0, p[1] - c / 2.0),
                    (p[0] + c / 2.0, p[1] + c / 2.0),
                ],
                colour.filled(),
            )
        }))?;
        chart.draw_series(s.openings.iter().map(|o| {
            Rectangle::new(
                [
                    (o.rect.u_m[0], o.rect.v_m[0]),
                    (o.rect.u_m[1], o.rect.v_m[1]),
                ],
                BLACK.stroke_width(2),
            )
        }))?;
        root.present()
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
