//! The spray tool and the plaster it lays on the true surfaces: the
//! nozzle follows its commanded position at the axes' speed, and while
//! plaster flows the footprint is laid along the nozzle's true path, step
//! by step, on a thickness grid of every true wall and ceiling.

use crate::layout::Layout;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};
use stucco_core::{Aim, FOOTPRINT_REACH_SIGMAS, Pose2, SurfaceFrame, ThicknessGrid, ToolCommand};

/// The sprayer the robot carries, as the simulator needs it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SprayerSpec {
    /// Flow while spraying, m³/s.
    pub flow_m3ps: f64,
    /// Standard deviation of the footprint at `sigma_at_m` from the
    /// nozzle, m; it grows in proportion to the distance (a cone).
    pub sigma_m: f64,
    /// The distance `sigma_m` holds at, m.
    pub sigma_at_m: f64,
    /// Fastest each axis of the gantry moves, m/s.
    pub axis_speed_mps: f64,
    /// Side of the cells of the thickness grids, m.
    pub cell_m: f64,
    /// Where the nozzle is parked at the start, robot frame, m.
    pub park_m: [f64; 3],
    /// A range camera on the carriage beside the nozzle, if it carries
    /// one: its profiles are taken from where the nozzle truly is.
    #[serde(default)]
    pub camera: Option<crate::CameraSpec>,
}

/// What a true surface is.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// Wall `index` of its room (the room's corners' order).
    Wall {
        /// Its index.
        index: usize,
    },
    /// The room's ceiling (over its bounding box).
    Ceiling,
}

/// A true surface with the plaster on it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Coat {
    /// The room it bounds.
    pub room: String,
    /// Wall or ceiling.
    pub kind: SurfaceKind,
    /// Its plane: a wall's `u` runs from its first corner to its second,
    /// `v` up; a ceiling's `u, v` are the world's `x, y` from the room's
    /// south-west corner.
    pub frame: SurfaceFrame,
    /// Its openings in its own frame: `[u0, u1, v0, v1]`, m.
    pub openings: Vec<[f64; 4]>,
    /// The plaster.
    pub grid: ThicknessGrid,
}

/// The sprayer's true state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ToolState {
    /// Where the nozzle is in the robot's frame, m.
    pub nozzle_m: [f64; 3],
    /// Where it points.
    pub aim: Aim,
    /// Plaster flowing.
    pub spray: bool,
}

/// The sprayer and the plaster of a whole world.
#[derive(Clone, Debug)]
pub struct Deposition {
    spec: SprayerSpec,
    coats: Vec<Coat>,
    command: ToolCommand,
    state: ToolState,
    sprayed_m3: f64,
}

impl Deposition {
    /// Bare surfaces of `layout`, the nozzle parked, spray off.
    pub fn new(spec: SprayerSpec, layout: &Layout) -> Deposition {
        let park = spec.park_m;
        let mut coats = Vec::new();
        for w in &layout.walls {
            let along = w.b - w.a;
            let len = along.norm();
            if len < 1e-9 {
                continue;
            }
            let u = along / len;
            let openings = layout
                .openings
                .iter()
                .filter(|o| o.room == w.room && o.wall == w.index)
                .map(|o| {
                    let s: Vec<f64> = o.edges.iter().map(|e| (e - w.a).dot(&u)).collect();
                    [s[0].min(s[1]), s[0].max(s[1]), o.z[0], o.z[1]]
                })
                .collect();
            let frame = SurfaceFrame {
                origin: Point3::new(w.a.x, w.a.y, 0.0),
                u: Vector3::new(u.x, u.y, 0.0),
                v: Vector3::new(0.0, 0.0, 1.0),
                size_m: [len, w.height_m],
            };
            coats.push(Coat {
                room: w.room.clone(),
                kind: SurfaceKind::Wall { index: w.index },
                grid: ThicknessGrid::new(frame.size_m, spec.cell_m),
                frame,
                openings,
            });
        }
        for r in &layout.rooms {
            let (x0, x1) = span(r.corners.iter().map(|c| c.x));
            let (y0, y1) = span(r.corners.iter().map(|c| c.y));
            let frame = SurfaceFrame {
                origin: Point3::new(x0, y0, r.height_m),
                u: Vector3::new(1.0, 0.0, 0.0),
                v: Vector3::new(0.0, 1.0, 0.0),
                size_m: [x1 - x0, y1 - y0],
            };
            coats.push(Coat {
                room: r.name.clone(),
                kind: SurfaceKind::Ceiling,
                grid: ThicknessGrid::new(frame.size_m, spec.cell_m),
                frame,
                openings: Vec::new(),
            });
        }
        let state = ToolState {
            nozzle_m: park,
            ..ToolState::default()
        };
        Deposition {
            spec,
            coats,
            command: ToolCommand {
                nozzle_m: park,
                ..ToolCommand::default()
            },
            state,
            sprayed_m3: 0.0,
        }
    }

    /// The command to follow from now on.
    pub fn command(&mut self, cmd: ToolCommand) {
        self.command = cmd;
    }

    /// The sprayer's true state.
    pub fn state(&self) -> ToolState {
        self.state
    }

    /// Every true surface with its plaster.
    pub fn coats(&self) -> &[Coat] {
        &self.coats
    }

    /// Puts back plaster laid before (a run resumed from a checkpoint):
    /// the grids of `coats`, matched by room and kind.
    pub fn restore(&mut self, coats: &[(String, SurfaceKind, ThicknessGrid)], sprayed_m3: f64) {
        for (room, kind, grid) in coats {
            if let Some(c) = self
                .coats
                .iter_mut()
                .find(|c| &c.room == room && &c.kind == kind && c.grid.cells == grid.cells)
            {
                c.grid = grid.clone();
            }
        }
        self.sprayed_m3 = sprayed_m3;
    }

    /// Plaster that has left the nozzle, m³.
    pub fn sprayed_m3(&self) -> f64 {
        self.sprayed_m3
    }

    /// One step of `dt_s` during which the robot moved from `before` to
    /// `after` (true poses): the axes move toward the command, and while
    /// plaster flows the footprint is laid along the nozzle's path.
    pub fn step(&mut self, dt_s: f64, before: &Pose2, after: &Pose2) {
        let from = self.state;
        let max = self.spec.axis_speed_mps * dt_s;
        let mut to = from;
        for k in 0..3 {
            let d = self.command.nozzle_m[k] - from.nozzle_m[k];
            to.nozzle_m[k] = from.nozzle_m[k] + d.clamp(-max, max);
        }
        to.aim = self.command.aim;
        to.spray = self.command.spray;
        self.state = to;
        // Plaster flows over the step when the valve was open at its start
        // and the nozzle kept its aim.
        if !from.spray || from.aim != to.aim {
            return;
        }
        let volume = self.command.flow_m3ps.unwrap_or(self.spec.flow_m3ps) * dt_s;
        self.sprayed_m3 += volume;
        let ray = |pose: &Pose2, nozzle: [f64; 3], aim: Aim| {
            let p = pose.transform_point(&nalgebra::Point2::new(nozzle[0], nozzle[1]));
            let d = aim.direction();
            let (c, s) = (pose.theta.cos(), pose.theta.sin());
            (
                Point3::new(p.x, p.y, nozzle[2]),
                Vector3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z),
            )
        };
        let (p0, d0) = ray(before, from.nozzle_m, from.aim);
        let (p1, d1) = ray(after, to.nozzle_m, to.aim);
        let Some((k, h0)) = self.nearest_hit(&p0, &d0) else {
            return;
        };
        let frame = &self.coats[k].frame;
        let h1 = frame.hit(&p1, &d1, 0.0).map_or(h0, |h| h);
        let distance = 0.5 * (h0.distance_m + h1.distance_m);
        let sigma = self.spec.sigma_m * distance / self.spec.sigma_at_m;
        self.coats[k].grid.deposit(h0.uv, h1.uv, volume, sigma);
    }

    /// The surface the spray meets first, and where.
    fn nearest_hit(
        &self,
        from: &Point3<f64>,
        dir: &Vector3<f64>,
    ) -> Option<(usize, stucco_core::SurfaceHit)> {
        // A hit just past a surface's edge still lays its footprint's
        // near half on it.
        let pad = FOOTPRINT_REACH_SIGMAS * self.spec.sigma_m;
        self.coats
            .iter()
            .enumerate()
            .filter_map(|(k, c)| c.frame.hit(from, dir, pad).map(|h| (k, h)))
            .min_by(|a, b| a.1.distance_m.total_cmp(&b.1.distance_m))
    }
}

fn span(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    })
}
