//! `plaster`: plans stations and strokes on the room as the robot knows
//! it (after a survey loop round it, by default), drives from station to
//! station and sprays, a checkpoint keeping where it got.

use super::survey::{Legs, SURVEY_BLOCKED_S, survey_legs, survey_way};
use super::wall::MIN_RUN_IN_M;
use super::ways::{estimate_space, planned_way, run_out, run_outs};
use super::{
    Behaviours, REPLAN_AFTER_S, RUN_IN_M, Task, TaskCx, TaskFailure, TaskStep, Thaw,
    pivot_clearance,
};
use crate::behaviour::{Behaviour, BehaviourKind};
use crate::executive::{EventKind, ExecutiveConfig, GiveUpReason, PARK_NOZZLE_M};
use crate::manoeuvre::{self, Space};
use crate::model::{DoorEstimate, Estimate, WallGeometry, walls_or_all};
use crate::plaster::{Cursor, Phase, PlasterCoverage, PlasterProgress, PlasterRun, plan_digest};
use crate::route::{Floor, route};
use crate::task::{Region, SpraySettings, WallName, spray_with};
use stucco_core::{DriveCommand, Pose2, ToolCommand, VehicleSpec, wrap_angle};
use stucco_plan::{OpeningKind, Plan, RoomModel, SprayTool, SurfaceId, WallOpening};

/// Spraying time between checkpoints within a stroke, s.
const CHECKPOINT_SPRAY_S: f64 = 1.0;
/// Time the nozzle is given past its travel to be at a pass's first point,
/// s (a few control periods).
const NOZZLE_SETTLE_S: f64 = 0.1;
/// Heading off a station the gantry's geometry takes without a second
/// approach, rad (2°).
const HEADING_SPARE_RAD: f64 = 0.035;
/// How far a robot turned on its station backs off to come on again, m.
const REALIGN_M: f64 = 1.0;
/// An opening whose bottom the camera finds this near the floor is a
/// door, m.
const DOOR_SILL_M: f64 = 0.1;

/// Lowest height on the wall the aim runs at while the tool's camera
/// looks, m: its fan (35° below the horizontal to straight up) meets the
/// wall from 20 cm under it to the ceiling, past every sill above 0.6 m.
/// Behind furniture the look runs where the strokes start, above it.
const LOOK_HEIGHT_M: f64 = 0.8;
/// Speed of the aim along the wall while the tool's camera looks, m/s
/// (the axes' fastest): a profile every 2.5 cm at 20 a second, a window's
/// edge placed within half that.
const LOOK_SPEED_MPS: f64 = 0.5;
/// How far past what a station's passes reach on its wall the look runs
/// (as far as the rail goes), m.
const LOOK_SPARE_M: f64 = 0.15;

/// What a `plaster` task of the mission file asks for.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PlasterSpec {
    /// The walls to plaster; `None`: every wall of the room.
    pub walls: Option<Vec<WallName>>,
    pub ceiling: bool,
    pub speed_mps: f64,
    pub settle_s: f64,
    pub survey: bool,
    pub survey_speed_mps: f64,
    pub region: Option<Region>,
    pub spray: Option<SpraySettings>,
}

/// Plasters a room's walls and ceiling.
#[derive(Clone, Debug)]
pub(crate) struct Plaster {
    spec: PlasterSpec,
    /// The walls it plasters: the spec's, or every wall of the room it
    /// started in.
    walls: Vec<WallName>,
    ways: Behaviours,
    /// The survey's loop driven corner to corner.
    legs: Option<Legs>,
    /// The plan and where the task is in it.
    run: Option<PlasterRun>,
    /// The survey has looked again at the window edges it bracketed
    /// loosely.
    edges_looked_at: bool,
    /// The spray tool and the coat this task plans with: the mission's
    /// with the task's own settings over it.
    tool: Option<SprayTool>,
    /// Flow while spraying, when the task's is not the mission's tool's,
    /// m³/s (the sprayer is told with each command).
    flow_m3ps: Option<f64>,
}

impl Plaster {
    pub fn new(spec: PlasterSpec) -> Self {
        Plaster {
            walls: spec.walls.clone().unwrap_or_default(),
            spec,
            ways: Behaviours::default(),
            legs: None,
            run: None,
            edges_looked_at: false,
            tool: None,
            flow_m3ps: None,
        }
    }
}

impl Task for Plaster {
    fn start(&mut self, cx: &mut TaskCx<'_>, thaw: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        let (config, est, index) = (cx.config, cx.est, cx.index);
        let clearance = pivot_clearance(config);
        let s = &self.spec;
        self.tool = match (&config.spray, &s.spray) {
            (Some(base), Some(settings)) => Some(
                spray_with(base, settings).map_err(|error| TaskFailure::SpraySettings { error })?,
            ),
            (base, _) => base.clone(),
        };
        self.flow_m3ps = match (&self.tool, &config.spray) {
            (Some(t), Some(base)) if t.flow_l_per_min != base.flow_l_per_min => Some(t.flow_m3ps()),
            _ => None,
        };
        let resumed = thaw.as_ref().is_some_and(|t| t.progress.task == index);
        self.walls = walls_or_all(s.walls.as_deref(), est);
        let mut run = plaster_run(
            config,
            self.tool.as_ref(),
            thaw,
            index,
            (&self.walls, s.ceiling, s.region.as_ref()),
            est,
        )?;
        cx.emit(EventKind::PlanMade {
            task: index,
            stations: run.plan.stations.len(),
            unreachable_m2: run.plan.unreachable_m2(),
        });
        if !s.survey
            && !resumed
            && let Some(failure) = nothing_reachable(&run.plan)
        {
            return Err(failure);
        }
        if s.survey && !resumed {
            let (way, corner_to_corner) = survey_way(config, clearance, est, s.survey_speed_mps);
            self.ways.queue.extend(way);
            self.legs = corner_to_corner;
            run.phase = Phase::Surveying;
        } else {
            self.ways.queue.extend(next_station_way(
                cx,
                clearance,
                &mut run,
                &est.pose,
                s.speed_mps,
            ));
        }
        self.run = Some(run);
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        let (config, est) = (cx.config, cx.est);
        let (speed, settle) = (self.spec.speed_mps, self.spec.settle_s);
        let (walls, ceiling, region) = (
            &self.walls[..],
            self.spec.ceiling,
            self.spec.region.as_ref(),
        );
        let vehicle = config.vehicle.clone();
        let gains = config.gains.clone();
        let clearance = pivot_clearance(config);
        let dt = cx.dt;
        let loose = est.position_sigma_m > config.safety.spray_max_sigma_m;
        let spray_ok = !loose && cx.hazard.is_none();
        let index = cx.index;
        let Some(run) = self.run.as_mut() else {
            return TaskStep::Failed(TaskFailure::NoPlan);
        };
        // Never done when nothing could be reached: the job says why.
        if run.all_given_up() {
            return TaskStep::Failed(run.all_given_up_failure());
        }
        if run.finished() && !matches!(run.phase, Phase::Leaving) {
            return TaskStep::Done;
        }
        let park = ToolCommand {
            nozzle_m: PARK_NOZZLE_M,
            ..ToolCommand::default()
        };
        match run.phase {
            Phase::Surveying => {
                if let Some(cmd) = self.ways.step(cx) {
                    cx.effects.tool = park;
                    return TaskStep::Drive(cmd);
                }
                // The survey's legs, while a clear way reaches a corner;
                // then they are done with (a way blocked later in the
                // task must not be taken for one of them).
                match self.legs.as_mut() {
                    Some(l) if !l.stuck() => {
                        if let Some(way) = l.next(config, est) {
                            self.ways.queue.extend(way);
                            cx.effects.tool = park;
                            return TaskStep::Drive(DriveCommand::STOP);
                        }
                        self.legs = None;
                    }
                    Some(_) => self.legs = None,
                    None => {}
                }
                // A window edge the survey's camera bracketed loosely (seen
                // across the room, in a pivot) is looked at again, slowly,
                // before the plan keeps plaster out of the window.
                if !self.edges_looked_at {
                    self.edges_looked_at = true;
                    let looks = edge_looks(config, est, speed);
                    if !looks.is_empty() {
                        for (wall, along_m, sigma_m, way) in looks {
                            cx.emit(EventKind::WindowEdgeLook {
                                task: index,
                                wall,
                                along_m,
                                sigma_m,
                            });
                            self.ways.queue.extend(way);
                        }
                        cx.effects.tool = park;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                }
                // Every wall seen from its standoff: plan on what was found.
                let plan =
                    match plan_room(config, self.tool.as_ref(), (walls, ceiling, region), est) {
                        Ok(p) => p,
                        Err(e) => return TaskStep::Failed(e),
                    };
                let Some(run) = self.run.as_mut() else {
                    return TaskStep::Failed(TaskFailure::NoPlan);
                };
                cx.emit(EventKind::PlanMade {
                    task: index,
                    stations: plan.stations.len(),
                    unreachable_m2: plan.unreachable_m2(),
                });
                if let Some(failure) = nothing_reachable(&plan) {
                    return TaskStep::Failed(failure);
                }
                run.replan(plan);
                let way = next_station_way(cx, clearance, run, &est.pose, speed);
                self.ways.queue.extend(way);
                cx.effects.tool = park;
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Leaving => {
                cx.effects.tool = park;
                match self.ways.step(cx) {
                    Some(cmd) => TaskStep::Drive(cmd),
                    None => TaskStep::Done,
                }
            }
            Phase::Moving => {
                if let Some(cmd) = self.ways.step(cx) {
                    cx.effects.tool = park;
                    return TaskStep::Drive(cmd);
                }
                if let Some(r) = self.run.as_mut() {
                    r.phase = Phase::Settling { left_s: settle };
                }
                cx.effects.tool = park;
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Settling { left_s } => {
                let left_s = left_s - dt;
                if left_s > 0.0 {
                    run.phase = Phase::Settling { left_s };
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                let station = run.cursor.station;
                let base = run.plan.stations[station].base;
                let off = base.inverse() * est.pose;
                // Off the station by more than the gantry has spare: once
                // or twice more onto it, along the lane.
                let spare = run.plan.tool.position_tolerance_m;
                if run.retries < 2 {
                    if off.theta.abs() > HEADING_SPARE_RAD || off.y.abs() > spare {
                        // Turned or beside the station: back off along the
                        // lane and come on again, the line law taking out
                        // the heading and the offset.
                        run.retries += 1;
                        self.ways
                            .queue
                            .extend(realign_way(config, run, &est.pose, &base, speed));
                        run.phase = Phase::Moving;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if off.x.abs() > spare {
                        run.retries += 1;
                        self.ways.queue.push_back(if off.x > 0.0 {
                            Behaviour::reverse_to(&gains, base, 0.1)
                        } else {
                            Behaviour::regulate(&gains, base, 0.1)
                        });
                        run.phase = Phase::Moving;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                }
                run.retries = 0;
                let stations = run.plan.stations.len();
                cx.emit(EventKind::StationStarted {
                    task: index,
                    station,
                    stations,
                    offset_m: [off.x, off.y],
                    heading_off_rad: off.theta,
                });
                let look = run
                    .look(station, LOOK_SPARE_M, LOOK_HEIGHT_M)
                    .filter(|_| run.plan.tool.camera);
                run.phase = match look {
                    Some(look) => Phase::Looking {
                        look,
                        left_s: -1.0,
                        t_s: 0.0,
                    },
                    None => Phase::Positioning { left_s: -1.0 },
                };
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Looking { look, left_s, t_s } => {
                let station = run.cursor.station;
                let (surface, [u0, u1], v) = (look.surface, look.u_m, look.height_m);
                let sweep_s = (u1 - u0).abs() / LOOK_SPEED_MPS;
                let u = u0 + (u1 - u0) * (t_s / sweep_s.max(1e-9)).clamp(0.0, 1.0);
                let Some(aim) = run.nozzle_for(surface, [u, v], &est.pose, false) else {
                    run.phase = Phase::Positioning { left_s: -1.0 };
                    return TaskStep::Drive(DriveCommand::STOP);
                };
                if left_s != 0.0 {
                    // To the look's start first, as to a pass's.
                    let left_s = if left_s < 0.0 {
                        travel_s(&cx.effects.tool, &aim, run.plan.tool.axis_speed_mps)
                    } else {
                        left_s - dt
                    };
                    cx.effects.tool = aim;
                    run.phase = Phase::Looking {
                        look,
                        left_s: left_s.max(0.0),
                        t_s: 0.0,
                    };
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                cx.effects.tool = aim;
                if t_s < sweep_s {
                    run.phase = Phase::Looking {
                        look,
                        left_s: 0.0,
                        t_s: t_s + dt,
                    };
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                // Looked: windows the plan does not know are kept out of
                // this station's coat and the rest of the wall's.
                if let SurfaceId::Wall(wall) = surface {
                    for w in est
                        .windows
                        .iter()
                        .filter(|w| w.wall == wall && w.sill_head_m[0] >= DOOR_SILL_M)
                    {
                        if run.plan.add_window(wall, w.along_m, w.sill_head_m, station) {
                            cx.emit(EventKind::WindowFound {
                                task: index,
                                station,
                                wall: surface_name(surface),
                                along_m: w.along_m,
                                sill_head_m: w.sill_head_m,
                            });
                            run.digest = plan_digest(&run.plan);
                        }
                    }
                }
                run.phase = Phase::Positioning { left_s: -1.0 };
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Positioning { left_s } => {
                let Some(first) = run.first_point(est) else {
                    return TaskStep::Failed(TaskFailure::NotFacingSurface {
                        station: run.cursor.station,
                    });
                };
                let left_s = if left_s < 0.0 {
                    // Newly here: the axes travel at their speed.
                    travel_s(&cx.effects.tool, &first, run.plan.tool.axis_speed_mps)
                } else {
                    left_s - dt
                };
                cx.effects.tool = first;
                run.phase = if left_s > 0.0 {
                    Phase::Positioning { left_s }
                } else {
                    let in_move_s = std::mem::take(&mut run.resume_s);
                    Phase::Spraying { in_move_s }
                };
                TaskStep::Drive(DriveCommand::STOP)
            }
            Phase::Spraying { in_move_s } => {
                // Held for the estimate no longer than the supervisor
                // holds a lost one: a position that stays too loose to
                // spray on fails the task, saying so, instead of standing
                // at the station for ever (a hazard's hold is the
                // supervisor's to time).
                run.held_s = if loose && cx.hazard.is_none() {
                    run.held_s + dt
                } else {
                    0.0
                };
                // Loose for the supervisor's time, the station is left:
                // one not begun yet is put last, once (seen from the
                // others the walls that hold the position may show: a
                // person pacing a corridor hid both its end walls from
                // station 0, and the job failed there undone); one put
                // last before, or begun, is given up, what only it reaches
                // reported, and the task goes on (the far end of a 22 m
                // corridor, its end wall behind the robot and the other
                // 20 m ahead, failed the corridor with 30 of its 47
                // stations undone; a room's second station, 10.1 mm a
                // minute into its strokes, failed its last eight). The
                // task fails, saying why, when no station is left that was
                // not given up.
                let begun = run.cursor.pass > 0 || run.cursor.step > 0 || in_move_s > 0.0;
                if run.held_s > config.safety.lost_timeout_s {
                    let station = run.cursor.station;
                    let left = if !begun && run.defer_station() {
                        EventKind::StationDeferred {
                            task: index,
                            station,
                        }
                    } else {
                        match run.give_up_station(index, GiveUpReason::PositionLoose) {
                            Some(given_up) if !run.all_given_up() => given_up,
                            _ => {
                                return TaskStep::Failed(TaskFailure::PositionTooLoose {
                                    station,
                                    sigma_m: est.position_sigma_m,
                                    limit_m: config.safety.spray_max_sigma_m,
                                    waited_s: config.safety.lost_timeout_s,
                                });
                            }
                        }
                    };
                    run.held_s = 0.0;
                    cx.emit(left);
                    cx.effects.checkpoint = true;
                    cx.effects.tool = park;
                    if !run.finished() {
                        self.ways
                            .replace(next_station_way(cx, clearance, run, &est.pose, speed));
                        run.phase = Phase::Moving;
                    }
                    return TaskStep::Drive(DriveCommand::STOP);
                }
                let mut t = in_move_s + if spray_ok { dt } else { 0.0 };
                // A checkpoint every second of spraying: a run killed
                // mid-stroke takes it up within a second of where it
                // stopped.
                if spray_ok {
                    run.unsaved_s += dt;
                    if run.unsaved_s >= CHECKPOINT_SPRAY_S {
                        run.unsaved_s = 0.0;
                        cx.effects.checkpoint = true;
                    }
                }
                loop {
                    let c = run.cursor;
                    let Some(pass) = run
                        .plan
                        .stations
                        .get(c.station)
                        .and_then(|s| s.passes.get(c.pass))
                    else {
                        return TaskStep::Done;
                    };
                    let surface = pass.surface;
                    let Some(duration) = pass.moves.get(c.step).map(|m| m.duration_s()) else {
                        return TaskStep::Done;
                    };
                    if t < duration {
                        break;
                    }
                    t -= duration;
                    if pass.moves[c.step].spray {
                        cx.effects.checkpoint = true;
                    }
                    let station_done = run.advance();
                    if run.cursor.pass != c.pass || station_done {
                        cx.emit(EventKind::PassDone {
                            task: index,
                            station: c.station,
                            surface: surface_name(surface),
                        });
                        cx.effects.checkpoint = true;
                    }
                    if run.finished() {
                        cx.effects.tool = park;
                        let last = run.plan.stations.len().saturating_sub(1);
                        let floor = floor_of(run, &vehicle, clearance);
                        self.ways
                            .queue
                            .extend(lane_exit(config, &floor, run, last, &est.pose, speed));
                        run.phase = Phase::Leaving;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if station_done {
                        let k = run.cursor.station;
                        let floor = floor_of(run, &vehicle, clearance);
                        let mut way = Vec::new();
                        // Along the lane to the next station only when
                        // the body passes clear; out of it otherwise.
                        let along_clear = run.plan.stations.get(k).is_some_and(|s| {
                            let h =
                                nalgebra::Vector2::new(est.pose.theta.cos(), est.pose.theta.sin());
                            floor.sweep_clear(
                                &est.pose.position().coords,
                                &s.base.position().coords,
                                &h,
                            )
                        });
                        if run.lane(k) != run.lane(k - 1) || !along_clear {
                            way.extend(lane_exit(config, &floor, run, k - 1, &est.pose, speed));
                        }
                        let from = way
                            .last()
                            .and_then(|b| match b.kind() {
                                BehaviourKind::Regulate { goal } => Some(*goal),
                                _ => None,
                            })
                            .unwrap_or(est.pose);
                        way.extend(next_station_way(cx, clearance, run, &from, speed));
                        run.phase = Phase::Moving;
                        self.ways.queue.extend(way);
                        cx.effects.tool = park;
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                    if run.cursor.pass != c.pass {
                        run.phase = Phase::Positioning { left_s: -1.0 };
                        return TaskStep::Drive(DriveCommand::STOP);
                    }
                }
                run.phase = Phase::Spraying { in_move_s: t };
                if let Some(cmd) = run.command(t, est) {
                    cx.effects.tool = ToolCommand {
                        spray: cmd.spray && spray_ok,
                        flow_m3ps: self.flow_m3ps,
                        ..cmd
                    };
                }
                TaskStep::Drive(DriveCommand::STOP)
            }
        }
    }

    fn blocked(&mut self, cx: &mut TaskCx<'_>, blocked_s: f64) -> bool {
        let (config, est, index) = (cx.config, cx.est, cx.index);
        // Held on the last stretch onto a station it already stands on
        // within what the gantry has spare (the field reaches a wall the
        // station stands nearer than its margin): it is there.
        if let Some(run) = self.run.as_mut()
            && matches!(run.phase, Phase::Moving)
            && self.ways.queue.is_empty()
            && let Some(station) = run.plan.stations.get(run.cursor.station)
        {
            let off = station.base.inverse() * est.pose;
            let spare = run.plan.tool.position_tolerance_m;
            if off.x.abs() <= spare && off.y.abs() <= spare && off.theta.abs() <= HEADING_SPARE_RAD
            {
                self.ways.replace(Vec::new());
                run.phase = Phase::Settling {
                    left_s: self.spec.settle_s,
                };
                return true;
            }
        }
        // So on a leg of a loop driven corner to corner; planned again as
        // often as it may be and held still (someone the robot backs
        // toward, cornered at a corridor's end), the corner is left out
        // and the survey goes on with the next: the job failed there.
        if blocked_s > REPLAN_AFTER_S
            && let Some(legs) = self.legs.as_mut()
        {
            if let Some(q) = legs.again(config, est) {
                self.ways.replace(q);
                return true;
            }
            if self
                .run
                .as_ref()
                .is_some_and(|r| matches!(r.phase, Phase::Surveying))
            {
                self.ways
                    .replace(legs.next(config, est).unwrap_or_default());
                return true;
            }
        }
        // A plastering survey's loop turned on the move that something
        // blocks (it runs near the furniture it goes round): the survey
        // goes on corner to corner from the end of the side it was on
        // (the legs' sides are the loop's, in the same order), each leg
        // the planned way round what the map holds.
        if blocked_s > SURVEY_BLOCKED_S
            && self.legs.is_none()
            && self
                .run
                .as_ref()
                .is_some_and(|r| matches!(r.phase, Phase::Surveying))
            && let Some(mut legs) = survey_legs(&config.vehicle, est, self.spec.survey_speed_mps)
        {
            legs.take_over(self.ways.kind());
            self.legs = Some(legs);
            self.ways.replace(Vec::new());
            return true;
        }
        // On the way to a station, held: where no way was found clear to
        // it (a hall too narrow to turn across), given up at once, what
        // only it reached reported unreachable; on a way found clear
        // (someone standing in it; a wall nearer the station than the
        // field lets the robot come), after half the supervisor's
        // timeout (long enough for someone to walk past, and the task's
        // own decision before the supervisor's), put last, and given up
        // when held again, rather than the job failing with most of it
        // undone. Then the way to the next one is planned.
        if let Some(run) = self.run.as_mut()
            && matches!(run.phase, Phase::Moving)
            && ((run.way_unchecked && blocked_s > REPLAN_AFTER_S)
                || blocked_s > 0.5 * config.safety.blocked_timeout_s)
        {
            let station = run.cursor.station;
            let unchecked = run.way_unchecked;
            if !unchecked && run.defer_station() {
                cx.emit(EventKind::StationDeferred {
                    task: index,
                    station,
                });
            } else if let Some(given_up) = run.give_up_station(index, GiveUpReason::NoWay) {
                cx.emit(given_up);
            }
            // Held on a way not found clear (turning toward a hall's end
            // wall) where the body's margins are not kept clear, the
            // robot runs out first: from there no way is found clear, and
            // every station after would be given up in turn.
            let mut way = Vec::new();
            let mut from = est.pose;
            let space = plaster_space(config, run, self.spec.speed_mps);
            if unchecked
                && !space.pose_clear(&from)
                && let Some((d, out)) = run_outs(&space, from).next()
            {
                way.push(run_out(config, &from, d, self.spec.speed_mps));
                from = out;
            }
            let clearance = pivot_clearance(config);
            way.extend(next_station_way(
                cx,
                clearance,
                run,
                &from,
                self.spec.speed_mps,
            ));
            self.ways.replace(way);
            // None left: the task ends where the robot stands, and the
            // next task's way starts there.
            if run.finished() {
                run.phase = Phase::Leaving;
            }
            // The plan on disk and the checkpoint's cursor must name the
            // same stations.
            cx.effects.checkpoint = true;
            return true;
        }
        false
    }

    fn behaviour(&self) -> Option<&BehaviourKind> {
        self.ways.kind()
    }

    fn freeze(&self, index: usize) -> Option<PlasterProgress> {
        self.run.as_ref().map(|r| PlasterProgress {
            task: index,
            cursor: r.cursor,
            in_move_s: match r.phase {
                Phase::Spraying { in_move_s } => in_move_s,
                _ => r.resume_s,
            },
            plan_digest: r.digest.clone(),
        })
    }

    fn plan(&self) -> Option<&Plan> {
        self.run.as_ref().map(|r| &r.plan)
    }

    fn coverage(&self, index: usize) -> Option<PlasterCoverage> {
        self.run.as_ref().map(|r| r.coverage(index))
    }

    fn tool_look(&self) -> bool {
        self.run
            .as_ref()
            .is_some_and(|r| matches!(r.phase, Phase::Looking { left_s, .. } if left_s == 0.0))
    }

    fn clone_box(&self) -> Box<dyn Task> {
        Box::new(self.clone())
    }
}

/// The plan a `plaster` task carries out: the one a checkpoint left
/// (from its cursor), or a new one on the room as the robot knows it.
fn plaster_run(
    config: &ExecutiveConfig,
    tool: Option<&SprayTool>,
    thaw: &mut Option<Thaw>,
    index: usize,
    (walls, ceiling, region): (&[WallName], bool, Option<&Region>),
    est: &Estimate,
) -> Result<PlasterRun, TaskFailure> {
    if let Some(Thaw { progress: p, plan }) = thaw.take()
        && p.task == index
    {
        let Some(plan) = plan else {
            return Err(TaskFailure::CheckpointPlanMissing {
                station: p.cursor.station,
            });
        };
        let digest = plan_digest(&plan);
        if digest != p.plan_digest {
            return Err(TaskFailure::CheckpointPlanDiffers {
                found: digest,
                expected: p.plan_digest,
            });
        }
        let mut run = PlasterRun::new(plan, p.cursor);
        run.resume_s = p.in_move_s.max(0.0);
        return Ok(run);
    }
    let plan = plan_room(config, tool, (walls, ceiling, region), est)?;
    Ok(PlasterRun::new(plan, Cursor::default()))
}

/// A window edge more uncertain than this after a survey is looked at
/// again, m (standard deviation): the plan keeps plaster 2 cm of a window
/// or more, which such an edge misses 2.5 times in a hundred.
const LOOK_EDGE_SIGMA_M: f64 = 0.008;

/// How fast a look sweeps the body camera's fan along the wall, m/s: a
/// profile every centimetre at the camera's 20 a second.
const LOOK_SWEEP_MPS: f64 = 0.2;

/// How far a look sweeps either side of the edge, m (at least three of
/// its standard deviations): the turn onto the sweep's start stops within
/// 0.01 rad of it, 3 cm at 3 m.
const LOOK_REACH_M: f64 = 0.08;

/// Largest angle between the body camera's fan and a wall's normal a look
/// is made at, rad (the window finder takes profiles to 25°).
const LOOK_INCIDENCE_RAD: f64 = 0.26;

/// The looks at the window edges `est` knows loosely (not doors): for each, the way to
/// a place the robot can stand and turn, from which the body's camera
/// meets the edge squarely enough, and a slow turn sweeping the camera's
/// fan across it. Each with the wall, the edge and its spread. An edge no
/// clear way leads to a place for is left as it is; a body without a
/// camera makes none.
fn edge_looks(
    config: &ExecutiveConfig,
    est: &Estimate,
    speed: f64,
) -> Vec<(WallName, f64, f64, Vec<Behaviour>)> {
    let Some(camera_azimuth) = config.body_camera_azimuth_rad else {
        return Vec::new();
    };
    let space = estimate_space(config, est, speed);
    let mut from = est.pose;
    let mut out = Vec::new();
    // Doors are the laser's to measure (the camera finds them as openings
    // down to the floor too).
    for w in est
        .windows
        .iter()
        .filter(|w| w.sill_head_m[0] > DOOR_SILL_M)
    {
        let Some(g) = WallGeometry::in_room(est, w.wall) else {
            continue;
        };
        for k in 0..2 {
            let sigma = w.along_sigma_m[k];
            if sigma <= LOOK_EDGE_SIGMA_M {
                continue;
            }
            let edge = g.origin + g.along * w.along_m[k];
            // Places in front of the edge, nearest the robot's own
            // distance from the wall first, squarely before it first.
            let here = g.distance(&from.position().coords);
            let mut places: Vec<(f64, f64)> = Vec::new();
            for d in [here, 0.8, 1.2, 1.6, 2.0, 2.4, 2.8, 3.2] {
                for off in [0.0, -0.15, 0.15, -0.3, 0.3] {
                    places.push((d, off));
                }
            }
            let look = places.into_iter().find_map(|(d, off)| {
                let at = g.origin + g.along * (w.along_m[k] + off * d) + g.inward * d;
                let to_edge = edge - at;
                let across = to_edge.norm();
                let incidence = (-g.inward.dot(&to_edge) / across).clamp(-1.0, 1.0).acos();
                if !(d > 0.3 && incidence <= LOOK_INCIDENCE_RAD) {
                    return None;
                }
                let aim = to_edge.y.atan2(to_edge.x) - camera_azimuth;
                let reach = (LOOK_REACH_M.max(3.0 * sigma) / across).atan();
                let start = Pose2::new(at.x, at.y, aim - reach);
                let end = Pose2::new(at.x, at.y, aim + reach);
                if !(space.pose_clear(&start) && space.pose_clear(&end)) {
                    return None;
                }
                // The way ends near the heading (a small last turn is left
                // to the line law); the sweep starts on it.
                let (_, mut way) = planned_way(config, est, &from, &start, speed)?;
                way.push(Behaviour::pivot(start.theta));
                way.push(Behaviour::pivot_slowly(end.theta, LOOK_SWEEP_MPS / across));
                Some((end, way))
            });
            if let Some((end, way)) = look {
                out.push((w.wall, w.along_m[k], sigma, way));
                from = end;
            }
        }
    }
    out
}

/// A plastering plan for `walls` (and the ceiling) on the room as `est`
/// knows it. Openings the camera found come with their own top (one
/// reaching the floor is a door); a door only the laser found has the top
/// the floor plan gives it, else the tool's `door_head_m`, and so has a
/// door the plan gives shut, or the camera's top where it saw higher.
fn plan_room(
    config: &ExecutiveConfig,
    tool: Option<&SprayTool>,
    (walls, ceiling, region): (&[WallName], bool, Option<&Region>),
    est: &Estimate,
) -> Result<Plan, TaskFailure> {
    let (Some(tool), vehicle) = (tool, &config.vehicle) else {
        return Err(TaskFailure::NoSprayTool);
    };
    let mut openings: Vec<WallOpening> = est
        .windows
        .iter()
        .map(|w| WallOpening {
            wall: w.wall,
            kind: if w.sill_head_m[0] < DOOR_SILL_M {
                OpeningKind::Door
            } else {
                OpeningKind::Window
            },
            along_m: w.along_m,
            sill_head_m: if w.sill_head_m[0] < DOOR_SILL_M {
                [0.0, w.sill_head_m[1]]
            } else {
                w.sill_head_m
            },
        })
        .collect();
    // A door's top as the drawing gives it, else the tool's guess.
    let drawn_head = |door: Option<usize>| {
        door.and_then(|i| config.floor.as_ref()?.doors().get(i)?.height_m)
            .unwrap_or(tool.door_head_m)
    };
    for d in &est.doors {
        let half = d.width_m.unwrap_or(0.9) / 2.0;
        let along = [d.position_m - half, d.position_m + half];
        // The laser and the camera may each see part of a door: the
        // opening is what either saw, as high as the camera saw it.
        match openings
            .iter_mut()
            .find(|o| o.wall == d.wall && o.along_m[0] < along[1] && along[0] < o.along_m[1])
        {
            Some(o) => {
                o.kind = OpeningKind::Door;
                o.along_m = [o.along_m[0].min(along[0]), o.along_m[1].max(along[1])];
                o.sill_head_m[0] = 0.0;
            }
            None => openings.push(WallOpening {
                wall: d.wall,
                kind: OpeningKind::Door,
                along_m: along,
                sill_head_m: [0.0, drawn_head(d.plan_door)],
            }),
        }
    }
    // A shut door is no gap in a scan: the drawing gives it. What the
    // camera saw of it (its frame, its leaf's edge) is taken in.
    if let (Some(floor), Some(room)) = (config.floor.as_ref(), est.room) {
        for (door, side) in floor.shut_doors_of(room) {
            let half = floor.doors()[door].width_m / 2.0;
            let mut shut = WallOpening {
                wall: side.wall,
                kind: OpeningKind::ShutDoor,
                along_m: [side.along_m - half, side.along_m + half],
                sill_head_m: [0.0, drawn_head(Some(door))],
            };
            openings.retain(|o| {
                let apart = o.wall != shut.wall
                    || o.along_m[1] <= shut.along_m[0]
                    || shut.along_m[1] <= o.along_m[0];
                if !apart {
                    shut.along_m = [
                        shut.along_m[0].min(o.along_m[0]),
                        shut.along_m[1].max(o.along_m[1]),
                    ];
                    shut.sill_head_m[1] = shut.sill_head_m[1].max(o.sill_head_m[1]);
                }
                apart
            });
            openings.push(shut);
        }
    }
    // A region of one wall: the rest of that wall is kept out of the plan
    // as openings are (its edges get the tool's margin).
    if let (Some(r), [wall]) = (region, walls) {
        let length = WallGeometry::in_room(est, *wall).map_or(0.0, |g| g.length_m);
        let (a, z, h) = (r.along_m, r.height_m, est.height_m);
        let keep_out = [
            ([0.0, a[0]], [0.0, h]),
            ([a[1], length], [0.0, h]),
            ([a[0], a[1]], [0.0, z[0]]),
            ([a[0], a[1]], [z[1], h]),
        ];
        openings.extend(
            keep_out
                .into_iter()
                .filter(|(along, z)| along[1] - along[0] > 1e-6 && z[1] - z[0] > 1e-6)
                .map(|(along_m, sill_head_m)| WallOpening {
                    wall: *wall,
                    kind: OpeningKind::Window,
                    along_m,
                    sill_head_m,
                }),
        );
    }
    let room = RoomModel {
        size_m: est.room_m,
        corners: est.corners.clone(),
        height_m: est.height_m,
        openings,
        obstacles: est.obstacles.clone(),
    };
    let mut plan =
        stucco_plan::plan(&room, tool, vehicle, &est.pose).map_err(|e| TaskFailure::Planning {
            error: e.to_string(),
        })?;
    let wanted = |s: SurfaceId| match s {
        SurfaceId::Wall(w) => walls.contains(&w),
        SurfaceId::Ceiling => ceiling,
    };
    for station in &mut plan.stations {
        station.passes.retain(|p| wanted(p.surface));
    }
    plan.stations.retain(|s| !s.passes.is_empty());
    Ok(plan)
}

/// The way from `from` to station `k`: along its lane when the robot is
/// on it already (forward or backing), else onto the lane and along it to
/// the station — onto the lane's own line by a manoeuvre when the lane is
/// nearer its wall than a turn on the spot allows, else where the robot
/// can turn (`clearance` from every wall). The second of the pair is
/// false when the way found does not keep the body and the field clear
/// as the map holds them: it is then driven all the same, the supervisor
/// watching (a way not tried at all, none being needed or found, is
/// empty and true). Without `search`, no manoeuvre is searched for (a
/// search that finds none spends its whole budget, seconds of it): the
/// plain way is clear or not.
fn station_way(
    config: &ExecutiveConfig,
    floor: &Floor,
    run: &PlasterRun,
    k: usize,
    from: &Pose2,
    (speed, search): (f64, bool),
) -> (Vec<Behaviour>, bool) {
    let (Some(station), Some((line, dist))) = (run.plan.stations.get(k), run.lane_line(k)) else {
        return (Vec::new(), true);
    };
    let gains = &config.gains;
    let goal = station.base;
    let heading = nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin());
    let p = from.position().coords;
    let off = line.inward.dot(&(p - line.origin)) - dist;
    let on_lane = off.abs() < 0.15 && wrap_angle(from.theta - goal.theta).abs() < 0.2;
    if on_lane && floor.sweep_clear(&p, &goal.position().coords, &heading) {
        let ahead = heading.dot(&(goal.position().coords - p));
        return (
            vec![if ahead >= 0.0 {
                Behaviour::regulate(gains, goal, speed)
            } else {
                Behaviour::reverse_to(gains, goal, speed)
            }],
            true,
        );
    }
    let Some((entry, forward)) = lane_entry(floor, run, k) else {
        return (Vec::new(), true);
    };
    // A lane nearer its wall than a turn on the spot allows is entered
    // on its own line, in the moves that get there: from the turning
    // line, the run-in would end short of the lane and the robot would
    // come back for the station.
    let space = plaster_space(config, run, speed);
    let at = line.along.dot(&(entry.position().coords - line.origin));
    let on = line.point(at, dist);
    let onto = Pose2::new(on.x, on.y, entry.theta);
    let moves = (search && line.inward.dot(&(entry.position().coords - line.origin)) - dist > 0.01)
        .then(|| space.manoeuvre(from, &onto))
        .flatten();
    let mut way = match moves {
        Some((_, moves)) => manoeuvre::behaviours(gains, &moves, speed),
        None => route(gains, floor, from, &entry, speed),
    };
    way.push(if forward {
        Behaviour::regulate(gains, goal, speed)
    } else {
        Behaviour::reverse_to(gains, goal, speed)
    });
    // The way as it will be driven must keep the body and the field
    // clear; where the turning places are too few (a small room with a
    // counter along one wall), the manoeuvre onto the station itself.
    if space.way_cost(from, &way).is_some() {
        return (way, true);
    }
    if !search {
        return (way, false);
    }
    match space.manoeuvre(from, &goal) {
        Some((_, moves)) => (manoeuvre::behaviours(gains, &moves, speed), true),
        None => (way, false),
    }
}

/// The way from `from` to the plan's next station; notes in `run`
/// whether it was found clear. Where no clear way reaches it from
/// `from`, the first later station whose plain way is clear comes first
/// (a `station_deferred` event for the one put after it): the robot
/// drives a way it does not know clear only when no station left has
/// one it knows without a search. Driven at first, the way to a room's
/// far side took it in between two tables, where it could turn no more
/// and every station after was given up.
fn next_station_way(
    cx: &mut TaskCx<'_>,
    floor_clearance: f64,
    run: &mut PlasterRun,
    from: &Pose2,
    speed: f64,
) -> Vec<Behaviour> {
    let config = cx.config;
    let station = run.cursor.station;
    let floor = floor_of(run, &config.vehicle, floor_clearance);
    let (way, clear) = station_way(config, &floor, run, station, from, (speed, true));
    if clear {
        run.way_unchecked = false;
        return way;
    }
    let later = (station + 1..run.plan.stations.len()).find_map(|k| {
        let (way, clear) = station_way(config, &floor, run, k, from, (speed, false));
        clear.then_some((k, way))
    });
    if let Some((k, way)) = later
        && run.bring_forward(k)
    {
        cx.emit(EventKind::StationDeferred {
            task: cx.index,
            station,
        });
        run.way_unchecked = false;
        return way;
    }
    run.way_unchecked = true;
    way
}

/// The space the way between stations is checked in: the plan's room,
/// what stands on its floor and its doorways (a room too narrow to turn
/// in, a hall, is turned in with the front in a doorway).
fn plaster_space<'a>(config: &'a ExecutiveConfig, run: &'a PlasterRun, speed: f64) -> Space<'a> {
    let doors: Vec<DoorEstimate> = run
        .plan
        .room
        .openings
        .iter()
        .filter(|o| o.kind == OpeningKind::Door)
        .map(|o| DoorEstimate {
            wall: o.wall,
            position_m: 0.5 * (o.along_m[0] + o.along_m[1]),
            width_m: Some(o.along_m[1] - o.along_m[0]),
            sigma_m: 0.0,
            plan_door: None,
        })
        .collect();
    Space::new(
        run.plan.room.size_m,
        &run.plan.room.corners,
        &doors,
        &run.plan.room.obstacles,
        &config.vehicle,
        &config.safety,
        speed,
    )
}

/// Onto station `base` again from `from` beside it or turned on it: back
/// off along the lane (as far as `REALIGN_M`) and come on again, the line
/// law taking out the heading and the offset; where the lane is too short
/// behind the station (furniture, a corner), on past it and back onto it;
/// where neither is clear, the manoeuvre onto it; and where none is, no
/// second approach (the gantry sprays from where the robot stands).
fn realign_way(
    config: &ExecutiveConfig,
    run: &PlasterRun,
    from: &Pose2,
    base: &Pose2,
    speed: f64,
) -> Vec<Behaviour> {
    let gains = &config.gains;
    let space = plaster_space(config, run, speed);
    let runs = [1.0, 0.8, 0.6, 0.4].map(|f| f * REALIGN_M);
    let back = runs.iter().map(|&d| {
        vec![
            Behaviour::reverse_to(gains, *base * Pose2::new(-d, 0.0, 0.0), speed),
            Behaviour::regulate(gains, *base, 0.1),
        ]
    });
    let on = runs.iter().map(|&d| {
        vec![
            Behaviour::regulate(gains, *base * Pose2::new(d, 0.0, 0.0), speed),
            Behaviour::reverse_to(gains, *base, 0.1),
        ]
    });
    if let Some(way) = back.chain(on).find(|w| space.way_cost(from, w).is_some()) {
        return way;
    }
    space
        .manoeuvre(from, base)
        .map(|(_, moves)| manoeuvre::behaviours(gains, &moves, 0.1))
        .unwrap_or_default()
}

/// Where the robot comes onto the lane of station `k`: a place to turn,
/// `clearance` from every wall and from what stands on the floor, from
/// where the body runs clear along the lane to the station — a run-in
/// before it (driving on), or failing that, beyond it (backing onto it:
/// the second of the pair is false).
fn lane_entry(floor: &Floor, run: &PlasterRun, k: usize) -> Option<(Pose2, bool)> {
    let clearance = floor.clearance_m;
    let goal = run.plan.stations.get(k)?.base;
    let (line, dist) = run.lane_line(k)?;
    let heading = nalgebra::Vector2::new(goal.theta.cos(), goal.theta.sin());
    let dir = line.along.dot(&heading).signum();
    let at = line.along.dot(&(goal.position().coords - line.origin));
    let (lo, hi) = (
        clearance.min(line.length_m - clearance),
        (line.length_m - clearance).max(clearance),
    );
    let want = (at - dir * RUN_IN_M).clamp(lo, hi);
    // The robot turns there: nothing may stand within its sweep, and the
    // way along the lane to the station must be clear.
    let off = dist.max(clearance);
    let clear = |a: f64| {
        let e = line.point(a, off);
        floor.turnable_among_obstacles(&e)
            && floor.sweep_clear(&e, &goal.position().coords, &heading)
    };
    let candidates = (0..200)
        .flat_map(|k| [want - dir * 0.05 * k as f64, want + dir * 0.05 * k as f64])
        .filter(|a| (lo..=hi).contains(a) && (at - a) * dir > 0.05);
    let before = candidates
        .clone()
        .find(|&a| (at - a) * dir >= MIN_RUN_IN_M && clear(a))
        .or_else(|| candidates.clone().find(|&a| clear(a)));
    let pose = |a: f64| {
        let e = line.point(a, off);
        Pose2::new(e.x, e.y, goal.theta)
    };
    if let Some(a) = before {
        return Some((pose(a), true));
    }
    let beyond = (1..200)
        .map(|k| at + dir * 0.05 * k as f64)
        .filter(|a| (lo..=hi).contains(a))
        .find(|&a| clear(a));
    Some(match beyond {
        Some(a) => (pose(a), false),
        None => (pose(want), true),
    })
}

/// Out of the lane of station `k` (the robot at `from` on it) to where it
/// can turn: along the lane and away from its wall, to the place nearest
/// a run-in ahead (the front leading, as a pass along a wall ends) whose
/// way, forward or backing, is clear as it will be driven; nothing when
/// none is (a lane ending at a counter): the way on starts from the lane.
fn lane_exit(
    config: &ExecutiveConfig,
    floor: &Floor,
    run: &PlasterRun,
    k: usize,
    from: &Pose2,
    speed: f64,
) -> Vec<Behaviour> {
    let clearance = floor.clearance_m;
    let Some((line, dist)) = run.lane_line(k) else {
        return Vec::new();
    };
    let heading = nalgebra::Vector2::new(from.theta.cos(), from.theta.sin());
    let dir = line.along.dot(&heading).signum();
    let p = from.position().coords;
    let at = line.along.dot(&(p - line.origin));
    let (lo, hi) = (clearance, line.length_m - clearance);
    let (lo, hi) = (lo.min(hi), hi.max(lo));
    let want = (at + dir * RUN_IN_M).clamp(lo, hi);
    // The robot will turn there: the nearest place along the lane where
    // nothing stands within its sweep, reached with the body clear.
    let off = dist.max(clearance);
    let space = plaster_space(config, run, speed);
    (0..200)
        .flat_map(|k| [want + 0.05 * k as f64, want - 0.05 * k as f64])
        .filter(|a| (lo..=hi).contains(a))
        .find_map(|a| {
            let o = line.point(a, off);
            if !(floor.turnable_among_obstacles(&o) && floor.sweep_clear(&p, &o, &heading)) {
                return None;
            }
            let goal = Pose2::new(o.x, o.y, from.theta);
            let way = vec![if heading.dot(&(o - p)) >= 0.0 {
                Behaviour::regulate(&config.gains, goal, speed)
            } else {
                Behaviour::reverse_to(&config.gains, goal, speed)
            }];
            space.way_cost(from, &way).is_some().then_some(way)
        })
        .unwrap_or_default()
}

/// The floor of the plan's room as the way between stations sees it.
fn floor_of<'a>(run: &'a PlasterRun, vehicle: &VehicleSpec, clearance: f64) -> Floor<'a> {
    Floor::new(
        run.plan.room.size_m,
        &run.plan.room.obstacles,
        vehicle,
        clearance,
    )
}

/// Time the nozzle takes from `from` to `to`, each axis at `speed_mps`,
/// and a few control periods more to be there, s.
fn travel_s(from: &ToolCommand, to: &ToolCommand, speed_mps: f64) -> f64 {
    let far = (0..3)
        .map(|k| (to.nozzle_m[k] - from.nozzle_m[k]).abs())
        .fold(0.0, f64::max);
    far / speed_mps + NOZZLE_SETTLE_S
}

fn surface_name(s: SurfaceId) -> String {
    s.name().to_owned()
}

/// A plan with no station though surface was asked for: the task fails
/// saying so, never done (a room whose floor the map held all but where
/// the robot stood was planned 0 stations, 66.6 m² unreachable, and the
/// task reported done).
fn nothing_reachable(plan: &Plan) -> Option<TaskFailure> {
    let unreachable_m2 = plan.unreachable_m2();
    (plan.stations.is_empty() && unreachable_m2 > 0.0)
        .then_some(TaskFailure::NothingReachable { unreachable_m2 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::executive::Event;
    use crate::tasks::Effects;
    use stucco_core::Stamp;

    /// Where no clear way reaches the plan's next station (something the
    /// map holds stands where its body would), the first later station
    /// whose plain way is clear goes first and the robot drives to it,
    /// not at the first: driven at, held there, it was given up in 2 s,
    /// and so each after it from where the robot was held.
    #[test]
    #[allow(clippy::expect_used)]
    fn a_station_with_a_clear_way_comes_before_one_without() {
        let config = ExecutiveConfig {
            spray: Some(SprayTool::default()),
            ..ExecutiveConfig::driving(VehicleSpec::default())
        };
        let est = crate::model::known_room([5.0, 3.0], &[], Pose2::new(2.5, 1.5, 0.0));
        let walls = walls_or_all(None, &est);
        let plan =
            plan_room(&config, config.spray.as_ref(), (&walls, true, None), &est).expect("a plan");
        let first = plan.stations[0].base;
        let mut run = PlasterRun::new(plan, Cursor::default());
        // Something on the floor where the first station's body stands.
        let ahead = first * Pose2::new(0.3, 0.0, 0.0);
        run.plan.room.obstacles.push(stucco_plan::Obstacle {
            min_m: [ahead.x - 0.1, ahead.y - 0.1],
            max_m: [ahead.x + 0.1, ahead.y + 0.1],
            height_m: 1.0,
        });
        let mut events: Vec<Event> = Vec::new();
        let mut effects = Effects {
            tool: ToolCommand::default(),
            checkpoint: false,
            enter_room: None,
        };
        let mut cx = TaskCx {
            now: Stamp::ZERO,
            dt: 0.02,
            started: Stamp::ZERO,
            index: 0,
            est: &est,
            config: &config,
            hazard: None,
            answered: false,
            events: &mut events,
            effects: &mut effects,
        };
        let way = next_station_way(&mut cx, pivot_clearance(&config), &mut run, &est.pose, 0.5);
        assert!(!run.way_unchecked && !way.is_empty());
        assert_ne!(run.plan.stations[0].base, first);
        assert_eq!(run.plan.stations[1].base, first);
        assert!(matches!(
            events[..],
            [Event {
                kind: EventKind::StationDeferred { station: 0, .. },
                ..
            }]
        ));
    }
}
