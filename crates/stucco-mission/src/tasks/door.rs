//! `pass_door` and `go_to_room`: through a door of the room, or through
//! the floor plan's doors one after another to a room, the frame moving
//! into each room beyond.

use super::ways::planned_way;
use super::{Behaviours, MAX_REPLANS, REPLAN_AFTER_S, Task, TaskCx, TaskFailure, TaskStep, Thaw};
use crate::behaviour::{Behaviour, BehaviourKind, go_to};
use crate::executive::{EventKind, ExecutiveConfig};
use crate::model::{DoorEstimate, Estimate, WallGeometry, depth_from, depth_of_room};
use nalgebra::Point2;
use std::collections::VecDeque;
use stucco_core::{DriveCommand, Pose2, wrap_angle};

/// A robot this near a door's line and this near its heading is on it,
/// m and rad.
const ON_LINE_M: f64 = 0.03;
const ON_LINE_RAD: f64 = 0.05;
/// How far beyond a door's wall line a robot backing through it stops
/// with its laser, m: through a wall's thickness and the laser's shortest
/// range.
const BACKED_LASER_BEYOND_M: f64 = 0.5;
/// Room left between the body and the far wall at a door's approach and
/// beyond it, m (the apartment's missions set the protective field's
/// margin to 3 cm; a mission with a longer field may be stopped there).
const DOOR_FIT_M: f64 = 0.1;
/// How much nearer a door its approach is taken at a time where no clear
/// way reaches it, m.
const APPROACH_STEP_M: f64 = 0.1;
/// A body whose trailing end is this far past the far face of a door's
/// wall is through the door, m.
const THROUGH_M: f64 = 0.05;

/// Where a door task goes.
#[derive(Clone, Debug)]
enum Goal {
    /// Through this door of the room.
    Door(usize),
    /// To this room of the floor plan.
    Room(String),
}

/// A `pass_door` or a `go_to_room`.
#[derive(Clone, Debug)]
pub(crate) struct DoorTask {
    goal: Goal,
    /// Distance before each door, beyond it, m; and the speed, m/s.
    approach_beyond_speed: [f64; 3],
    ways: Behaviours,
    /// The way through doors of the floor plan.
    doorway: Option<Doorway>,
}

impl DoorTask {
    pub fn pass_door(door: usize, approach_beyond_speed: [f64; 3]) -> Self {
        DoorTask {
            goal: Goal::Door(door),
            approach_beyond_speed,
            ways: Behaviours::default(),
            doorway: None,
        }
    }

    pub fn go_to_room(room: String, approach_beyond_speed: [f64; 3]) -> Self {
        DoorTask {
            goal: Goal::Room(room),
            approach_beyond_speed,
            ways: Behaviours::default(),
            doorway: None,
        }
    }

    fn name(&self) -> &'static str {
        match self.goal {
            Goal::Door(_) => "pass_door",
            Goal::Room(_) => "go_to_room",
        }
    }

    /// A doorway's step before its behaviours: once the robot was said to
    /// have gone through a door, the estimate must be in the room beyond
    /// it; then the next door's passage is planned, or the task is done.
    fn step_doorway(&mut self, cx: &mut TaskCx<'_>) -> Option<TaskStep> {
        let task = self.name();
        let w = self.doorway.as_mut()?;
        let room = w.entering?;
        let config = cx.config;
        let name = |r: usize| {
            config
                .floor
                .as_ref()
                .and_then(|f| f.rooms().get(r))
                .map_or_else(|| format!("room {r}"), |r| r.name.clone())
        };
        if cx.est.room != Some(room) {
            return Some(TaskStep::Failed(TaskFailure::EstimateNotBeyondDoor {
                task: task.to_owned(),
                room: name(room),
            }));
        }
        w.entering = None;
        if let Some(door) = w.passed {
            cx.emit(EventKind::RoomEntered {
                door,
                room: name(room),
            });
        }
        let Some(next) = w.hops.pop_front() else {
            return Some(TaskStep::Done);
        };
        match plan_door_pass(
            config,
            cx.est,
            next,
            [w.approach_m, w.beyond_m],
            w.speed_mps,
        ) {
            Ok(q) => {
                w.through = Some(next);
                w.replans = 0;
                self.ways.queue.extend(q);
                None
            }
            Err(e) => Some(TaskStep::Failed(e)),
        }
    }
}

impl DoorTask {
    /// True on the run through a door of the plan with the body's
    /// trailing end past the wall's far face by [`THROUGH_M`].
    fn through_the_wall(&self, cx: &TaskCx<'_>) -> bool {
        let (config, est) = (cx.config, cx.est);
        let Some(door) = self
            .doorway
            .as_ref()
            .filter(|w| w.entering.is_none())
            .and_then(|w| w.through)
        else {
            return false;
        };
        let v = &config.vehicle;
        let trailing_m = match self.ways.kind() {
            _ if !self.ways.queue.is_empty() => return false,
            Some(BehaviourKind::Regulate { .. }) => -v.rear_overhang_m,
            Some(BehaviourKind::Reverse { .. }) => v.front_m(),
            _ => return false,
        };
        let depth = config.floor.as_ref().and_then(|f| f.door_depth(door));
        let wall = seen_plan_door(est, door).and_then(|d| WallGeometry::in_room(est, d.wall));
        let (Some(depth), Some(wall)) = (depth, wall) else {
            return false;
        };
        let tail = est.pose.transform_point(&Point2::new(trailing_m, 0.0));
        -wall.distance(&tail.coords) >= depth + THROUGH_M
    }
}

impl Task for DoorTask {
    fn start(&mut self, cx: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        let (config, est) = (cx.config, cx.est);
        let [approach_m, beyond_m, speed_mps] = self.approach_beyond_speed;
        match &self.goal {
            Goal::Door(door) => {
                let door = *door;
                let Some(d) = est.doors.get(door) else {
                    return Err(TaskFailure::UnknownDoor {
                        task: "pass_door".to_owned(),
                        door,
                        found: est.doors.len(),
                    });
                };
                let next_depth = d.plan_door.and_then(|p| next_room_depth(config, est, p));
                self.ways.queue.extend(door_pass(
                    config,
                    est,
                    d,
                    [approach_m, beyond_m],
                    next_depth,
                    speed_mps,
                ));
                // Through a door of the plan, the frame moves on.
                if let (Some(plan_door), Some(_), Some(_)) = (d.plan_door, &config.floor, est.room)
                {
                    self.doorway = Some(Doorway::through(
                        plan_door,
                        VecDeque::new(),
                        self.approach_beyond_speed,
                    ));
                }
            }
            Goal::Room(room) => {
                let mut hops: VecDeque<usize> = route(config, room, est)?.into();
                if let Some(first) = hops.pop_front() {
                    self.ways.queue.extend(plan_door_pass(
                        config,
                        est,
                        first,
                        [approach_m, beyond_m],
                        speed_mps,
                    )?);
                    self.doorway = Some(Doorway::through(first, hops, self.approach_beyond_speed));
                }
            }
        }
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        if self.doorway.as_ref().is_some_and(|w| w.entering.is_some()) {
            if let Some(step) = self.step_doorway(cx) {
                return step;
            }
            return self.step(cx);
        }
        if let Some(cmd) = self.ways.step(cx) {
            return TaskStep::Drive(cmd);
        }
        if let Some(w) = self.doorway.as_mut()
            && let Some(door) = w.through.take()
        {
            // Beyond the door: the frame moves to the next room, and the
            // next tick checks it did.
            let beyond = cx
                .est
                .room
                .and_then(|r| cx.config.floor.as_ref().and_then(|f| f.beyond(door, r)));
            let Some(beyond) = beyond else {
                return TaskStep::Failed(TaskFailure::DoorNotOfThisRoom {
                    task: self.name().to_owned(),
                    door,
                });
            };
            w.entering = Some(beyond);
            w.passed = Some(door);
            cx.effects.enter_room = Some(door);
            return TaskStep::Drive(DriveCommand::STOP);
        }
        TaskStep::Done
    }

    fn blocked(&mut self, cx: &mut TaskCx<'_>, blocked_s: f64) -> bool {
        // Held on the run through a door with the body through it
        // (furniture or a person just inside the room beyond, which the
        // passage's fixed end did not know): the passage ends where the
        // robot stands, in the room beyond.
        if blocked_s > REPLAN_AFTER_S && self.through_the_wall(cx) {
            self.ways.replace(VecDeque::new());
            return true;
        }
        // On the way to a door, something the room's map did not hold
        // when the way was planned (furniture first seen from the
        // doorway): the way is planned again on what the map holds now.
        if blocked_s > REPLAN_AFTER_S
            && !self.ways.queue.is_empty()
            && let Some(w) = self.doorway.as_mut()
            && w.entering.is_none()
            && w.replans < MAX_REPLANS
            && let Some(door) = w.through
            && let Ok(q) = plan_door_pass(
                cx.config,
                cx.est,
                door,
                [w.approach_m, w.beyond_m],
                w.speed_mps,
            )
        {
            w.replans += 1;
            self.ways.replace(q);
            return true;
        }
        false
    }

    fn behaviour(&self) -> Option<&BehaviourKind> {
        self.ways.kind()
    }

    fn clone_box(&self) -> Box<dyn Task> {
        Box::new(self.clone())
    }
}

/// The doors of the plan's way from the robot's room to `room`.
pub(crate) fn route(
    config: &ExecutiveConfig,
    room: &str,
    est: &Estimate,
) -> Result<Vec<usize>, TaskFailure> {
    let Some(floor) = &config.floor else {
        return Err(TaskFailure::NoFloorPlan);
    };
    let Some(to) = floor.room(room) else {
        return Err(TaskFailure::UnknownRoom {
            room: room.to_owned(),
            rooms: floor.rooms().iter().map(|r| r.name.clone()).collect(),
        });
    };
    let Some(here) = est.room else {
        return Err(TaskFailure::RoomNotKnown);
    };
    let fits = config.safety.door_width_m(&config.vehicle);
    floor.route_for(here, to, fits).ok_or_else(|| {
        let from = floor.rooms().get(here).map_or("here", |r| r.name.as_str());
        TaskFailure::NoRoute {
            from: from.to_owned(),
            to: room.to_owned(),
        }
    })
}

/// A task's way through doors of the floor plan, one at a time.
#[derive(Clone, Debug)]
struct Doorway {
    /// The door being driven through.
    through: Option<usize>,
    /// The doors after it.
    hops: VecDeque<usize>,
    /// The room the robot was said to have entered, until the estimate
    /// is in it.
    entering: Option<usize>,
    /// The door it went through last.
    passed: Option<usize>,
    approach_m: f64,
    beyond_m: f64,
    speed_mps: f64,
    /// Times the way to the door was planned again.
    replans: usize,
}

impl Doorway {
    /// Through `door` first, then `hops`, each passage from `approach_m`
    /// before to `beyond_m` beyond at `speed_mps`.
    fn through(
        door: usize,
        hops: VecDeque<usize>,
        [approach_m, beyond_m, speed_mps]: [f64; 3],
    ) -> Self {
        Doorway {
            through: Some(door),
            hops,
            entering: None,
            passed: None,
            approach_m,
            beyond_m,
            speed_mps,
            replans: 0,
        }
    }
}

/// The behaviours through door `d` of the room `est` knows: onto the line
/// through its middle `approach` before it, facing out, then along the
/// line to `beyond` past it. Where no clear way reaches that approach (a
/// corridor too narrow to turn in: standing across it that deep, the
/// robot's trailing end and the field behind it reach the far wall, so
/// the turn into the door must be made nearer the door), the approach is
/// taken nearer, [`APPROACH_STEP_M`] at a time, down to the body's
/// leading end at the wall's line. Standing on that line facing into the
/// room (just come in through the door), the robot may back out instead,
/// when that is quicker than turning round (a bedroom cramped by its
/// door). Both distances
/// are fitted to the rooms: at the approach the body must be in this
/// room, and beyond, in the next, whose depth across the door is
/// `next_depth_m` when the plan gives it.
fn door_pass(
    config: &ExecutiveConfig,
    est: &Estimate,
    d: &DoorEstimate,
    [approach_m, beyond_m]: [f64; 2],
    next_depth_m: Option<f64>,
    speed_mps: f64,
) -> Vec<Behaviour> {
    let v = &config.vehicle;
    let (rear, front) = (v.rear_overhang_m, v.front_m());
    let Some(g) = WallGeometry::in_room(est, d.wall) else {
        return Vec::new();
    };
    let depth = depth_from(est, &g);
    let out_heading = (-g.inward.y).atan2(-g.inward.x);
    // Already on the door's line, facing along the passage, the robot
    // needs no approach from further in than where it stands.
    let here = est.pose.position().coords;
    let (off_line, standing) = (g.position(&here) - d.position_m, g.distance(&here));
    let pass = |forward: bool, nearer_m: f64| {
        // The end of the body that leads and the one that trails.
        let (leads, trails) = if forward {
            (front, rear)
        } else {
            (rear, front)
        };
        let heading = if forward {
            out_heading
        } else {
            wrap_angle(out_heading + std::f64::consts::PI)
        };
        let on_line = off_line.abs() < ON_LINE_M
            && wrap_angle(est.pose.theta - heading).abs() < ON_LINE_RAD
            && standing > 0.0;
        let mut approach = approach_m.min(depth - trails - DOOR_FIT_M);
        if on_line {
            approach = approach.min(standing);
        }
        let approach = (approach - nearer_m).max(leads);
        // Backing, the laser trails: the robot stops with it through the
        // wall and past the laser's shortest range, so that the next
        // room's filter starts on that room's walls, not on the room
        // left seen through the door.
        let beyond = if forward {
            beyond_m
        } else {
            beyond_m.max(v.laser_mount.x + BACKED_LASER_BEYOND_M)
        };
        let beyond = next_depth_m.map_or(beyond, |n| beyond.min(n - leads - DOOR_FIT_M));
        let (a, b) = (
            g.point(d.position_m, approach),
            g.point(d.position_m, -beyond),
        );
        (
            on_line,
            Pose2::new(a.x, a.y, heading),
            Pose2::new(b.x, b.y, heading),
        )
    };
    let through = |forward: bool, b: Pose2| {
        if forward {
            Behaviour::regulate(&config.gains, b, speed_mps)
        } else {
            Behaviour::reverse_to(&config.gains, b, speed_mps)
        }
    };
    // Facing out, or backing out the way it came in when it stands on the
    // door's line facing into the room (the laser looks ahead: the robot
    // backs only where it has just driven), whichever is the quicker.
    let best = |nearer_m: f64| {
        [true, false]
            .into_iter()
            .filter_map(|forward| {
                let (on_line, a, b) = pass(forward, nearer_m);
                if !forward && !on_line {
                    return None;
                }
                let (cost, way) = planned_way(config, est, &est.pose, &a, speed_mps)?;
                Some((cost, forward, way, b))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0))
    };
    // Nearer the door by steps while the approach can come nearer.
    let deepest = approach_m.min(depth - rear - DOOR_FIT_M) - front;
    let steps = (deepest / APPROACH_STEP_M).ceil().max(0.0) as usize;
    let found = (0..=steps).find_map(|k| best(k as f64 * APPROACH_STEP_M));
    if let Some((_, forward, mut out, b)) = found {
        out.push(through(forward, b));
        return out;
    }
    let (_, a, b) = pass(true, 0.0);
    let mut out = go_to(&config.gains, &est.pose, &a, speed_mps);
    out.push(through(true, b));
    out
}

/// [`door_pass`] through door `door` of the floor plan, as the robot knows
/// it in its room.
fn plan_door_pass(
    config: &ExecutiveConfig,
    est: &Estimate,
    door: usize,
    approach_beyond_m: [f64; 2],
    speed_mps: f64,
) -> Result<Vec<Behaviour>, TaskFailure> {
    let d = seen_plan_door(est, door).ok_or(TaskFailure::PlanDoorNotSeen { door })?;
    Ok(door_pass(
        config,
        est,
        d,
        approach_beyond_m,
        next_room_depth(config, est, door),
        speed_mps,
    ))
}

/// The depth across door `door` of the plan of the room beyond it from
/// the robot's room, m.
fn next_room_depth(config: &ExecutiveConfig, est: &Estimate, door: usize) -> Option<f64> {
    let floor = config.floor.as_ref()?;
    let next = floor.beyond(door, est.room?)?;
    let side = floor.side(door, next)?;
    let room = floor.rooms().get(next)?;
    let g = room.wall(side.wall)?;
    Some(depth_of_room(&room.outline(), room.size_m, &g))
}

/// The door of the room `est` knows that is door `door` of the floor
/// plan, once the robot has found it.
fn seen_plan_door(est: &Estimate, door: usize) -> Option<&DoorEstimate> {
    est.doors.iter().find(|d| d.plan_door == Some(door))
}
