//! `map_room`: loops inside the room until its walls and size are known;
//! and the loops a plastering survey drives round a room.

use super::ways::{planned_way, way};
use super::{Behaviours, MAX_REPLANS, REPLAN_AFTER_S, Task, TaskCx, TaskFailure, TaskStep, Thaw};
use crate::behaviour::{Behaviour, BehaviourKind, go_to};
use crate::executive::{EventKind, ExecutiveConfig};
use crate::manoeuvre::Space;
use crate::model::{Estimate, WallGeometry, anchor_wall, wall_sigma, walls_or_all};
use crate::task::{OnTimeout, WallName};
use crate::views::{NoView, Sight, Spent, View, next_view};
use stucco_core::{DriveCommand, Obstacle, Pose2, VehicleSpec};
use stucco_plan::Outline;

/// Seconds a `map_room` loop driven corner to corner stands before its
/// first leg: the floor map needs a score of echoes in a cell (the scans
/// come at 10 Hz) to take something as standing there.
const LOOK_ROUND_S: f64 = 6.0;

/// Observes the room's walls: from the places view planning chooses, or
/// while driving a loop a mission gives.
#[derive(Clone, Debug)]
pub(crate) struct MapRoom {
    path: Option<Vec<[f64; 2]>>,
    /// The walls to observe; `None`: every wall of the room.
    walls: Option<Vec<WallName>>,
    min_sightings: usize,
    speed_mps: f64,
    max_size_sigma_m: f64,
    timeout_s: f64,
    on_loose_size: OnTimeout,
    ways: Behaviours,
    /// The loop driven corner to corner.
    legs: Option<Legs>,
    /// Walls looked at from where the robot was held, unseen.
    looked: Vec<WallName>,
    /// Without a loop given: the places looked from.
    looks: Looks,
}

/// The places a `map_room` without a loop looks at the walls from.
#[derive(Clone, Debug, Default)]
struct Looks {
    /// The place driven to or looked from, and when the robot stood there
    /// (the task's time, s).
    at: Option<(View, Option<f64>)>,
    /// Places walls were looked at from and not seen.
    spent: Vec<Spent>,
    /// Walls no place the body reaches sees (behind what stands before
    /// them, or too short for the laser to take for a line): left out.
    hidden: Vec<WallName>,
    /// No place was found (none sees the walls left, or no clear way
    /// reaches one): since when, and what the floor map held then. The
    /// places are chosen again once it holds something else (someone
    /// who stood in the way walked on); the walls left are given up as
    /// hidden after [`HIDDEN_WAIT_S`] of it.
    stuck_on: Option<(f64, Vec<Obstacle>)>,
    /// Times the way to the place was planned again.
    replans: usize,
}

/// Longest a place is looked from while the walls it was chosen for are
/// not all seen, s: twice the time reckoned (a wall seen in every other
/// scan, across a doorway someone passes, is seen by then).
const LOOK_MAX_S: f64 = 2.0 * crate::views::DWELL_S;

/// How long no place is found for the walls still unseen, the floor map
/// looked at again as it changes, before they are given up as hidden, s:
/// someone who stood in the way has walked on by then.
const HIDDEN_WAIT_S: f64 = 15.0;

/// A robot this near a place's pose stands at it, m.
const AT_PLACE_M: f64 = 0.25;

impl MapRoom {
    pub fn new(
        path: Option<Vec<[f64; 2]>>,
        walls: Option<Vec<WallName>>,
        min_sightings: usize,
        speed_mps: f64,
        max_size_sigma_m: f64,
        timeout_s: f64,
        on_loose_size: OnTimeout,
    ) -> Self {
        MapRoom {
            path,
            walls,
            min_sightings,
            speed_mps,
            max_size_sigma_m,
            timeout_s,
            on_loose_size,
            ways: Behaviours::default(),
            legs: None,
            looked: Vec::new(),
            looks: Looks::default(),
        }
    }

    /// The walls to observe: those asked for, less those no place sees.
    fn observed(&self, est: &Estimate) -> Vec<WallName> {
        walls_or_all(self.walls.as_deref(), est)
            .into_iter()
            .filter(|w| !self.looks.hidden.contains(w))
            .collect()
    }

    /// The walls still to be seen.
    fn unseen(&self, est: &Estimate) -> Vec<WallName> {
        self.observed(est)
            .into_iter()
            .filter(|w| {
                est.walls_seen
                    .get(w.index())
                    .is_none_or(|&n| n < self.min_sightings)
            })
            .collect()
    }

    /// The uncertainty of each wall observed whose place is not known to
    /// `max_size_sigma_m` yet, m (σ): of the walls whose place is measured
    /// against a wall that fixes the frame and is observed too.
    fn loose(&self, est: &Estimate) -> Vec<f64> {
        let observed = self.observed(est);
        observed
            .iter()
            .map(|w| w.index())
            .filter(|&k| observed.iter().any(|a| a.index() == anchor_wall(est, k)))
            .map(|k| wall_sigma(est, k))
            .filter(|&s| s > self.max_size_sigma_m)
            .collect()
    }

    /// Leaves out the walls `walls` as hidden, telling the log.
    fn hide(&mut self, cx: &mut TaskCx<'_>, walls: Vec<WallName>) {
        if walls.is_empty() {
            return;
        }
        self.looks.hidden.extend(walls.iter().copied());
        cx.emit(EventKind::WallsHidden {
            task: cx.index,
            walls,
        });
    }

    /// One tick without a loop given: to the place that sees the most of
    /// the walls still unseen (once all are seen and the room's size is
    /// still loose, of all of them, place after place), looking from it
    /// until they are seen; walls no place sees are left out.
    fn step_views(&mut self, cx: &mut TaskCx<'_>, unseen: Vec<WallName>) -> TaskStep {
        let (config, est) = (cx.config, cx.est);
        let elapsed = cx.elapsed_s();
        if !self.ways.idle() {
            return TaskStep::Drive(self.ways.step(cx).unwrap_or(DriveCommand::STOP));
        }
        // The first place waits for the laser to have found what stands
        // on the floor near the robot (the plan stands on it).
        if self.looks.at.is_none() && elapsed < LOOK_ROUND_S {
            return TaskStep::Drive(DriveCommand::STOP);
        }
        if let Some((view, arrived)) = self.looks.at.as_mut() {
            // The walls it was chosen for and not seen yet (once the room's
            // size is all that is left, all of them).
            let still: Vec<WallName> = view
                .walls
                .iter()
                .filter(|w| unseen.is_empty() || unseen.contains(w))
                .copied()
                .collect();
            let off = (est.pose.position() - view.goal.position()).norm();
            if arrived.is_none() && off > AT_PLACE_M {
                // Stopped short (the way gave up): the way again.
                self.looks.replans += 1;
                let way = (self.looks.replans <= MAX_REPLANS)
                    .then(|| planned_way(config, est, &est.pose, &view.goal, self.speed_mps))
                    .flatten();
                if let Some((_, w)) = way {
                    self.ways.replace(w);
                    return TaskStep::Drive(self.ways.step(cx).unwrap_or(DriveCommand::STOP));
                }
            } else {
                let since = *arrived.get_or_insert(elapsed);
                // Looking: until its walls are seen (once the room's size
                // is all that is left, the while reckoned).
                let dwell = if unseen.is_empty() {
                    crate::views::DWELL_S
                } else {
                    LOOK_MAX_S
                };
                if elapsed - since < dwell && !still.is_empty() {
                    return TaskStep::Drive(DriveCommand::STOP);
                }
            }
            let place = view.place;
            self.looks.at = None;
            self.looks
                .spent
                .extend(still.into_iter().map(|w| (place, w)));
        }
        if let Some((since, held)) = &self.looks.stuck_on
            && elapsed - since < HIDDEN_WAIT_S
            && !floor_changed(held, &est.obstacles)
        {
            return TaskStep::Drive(DriveCommand::STOP);
        }
        let targets = if unseen.is_empty() {
            self.observed(est)
        } else {
            unseen.clone()
        };
        match next_view(config, est, &targets, &self.looks.spent, self.speed_mps) {
            Ok(view) => {
                self.ways.replace(view.way.clone());
                self.looks.at = Some((view, None));
                self.looks.replans = 0;
                self.looks.stuck_on = None;
            }
            // Only the size left: round the places again (none seen from
            // any place, even so: wait as below, not a search a tick).
            Err(NoView::Hidden) if unseen.is_empty() && !self.looks.spent.is_empty() => {
                self.looks.spent.clear();
            }
            // Seen from no place the body fits, or no clear way to one:
            // looked for again as the floor map changes, given up as
            // hidden after a while of it.
            Err(_) => match self.looks.stuck_on.as_mut() {
                Some((since, _)) if elapsed - *since >= HIDDEN_WAIT_S && !unseen.is_empty() => {
                    self.looks.stuck_on = None;
                    self.hide(cx, unseen);
                }
                // Only the size left: another while before looking again.
                Some((since, held)) => {
                    if unseen.is_empty() {
                        *since = elapsed;
                    }
                    *held = est.obstacles.clone();
                }
                None => self.looks.stuck_on = Some((elapsed, est.obstacles.clone())),
            },
        }
        TaskStep::Drive(self.ways.step(cx).unwrap_or(DriveCommand::STOP))
    }

    /// Held on the way to a place: the way planned again on what the
    /// floor map holds now, at most `MAX_REPLANS` times; then the place is
    /// given up for its walls, and the next chosen next tick.
    fn views_blocked(&mut self, cx: &mut TaskCx<'_>) -> bool {
        let (config, est) = (cx.config, cx.est);
        let Some((view, _)) = self.looks.at.as_ref() else {
            return false;
        };
        if self.looks.replans < MAX_REPLANS {
            self.looks.replans += 1;
            if let Some((_, way)) = planned_way(config, est, &est.pose, &view.goal, self.speed_mps)
            {
                self.ways.replace(way);
                return true;
            }
        }
        let place = view.place;
        let walls = view.walls.clone();
        self.looks.at = None;
        self.looks
            .spent
            .extend(walls.into_iter().map(|w| (place, w)));
        self.ways.replace(Vec::new());
        true
    }

    /// Held where it stands (no way reaches a corner, or someone stands
    /// in the way): a look at the first wall still unseen not looked at
    /// yet, turned toward it as far as a clear way turns the robot on its
    /// spot (the laser does not see behind it: a corridor's end wall
    /// behind a robot that someone pacing the corridor holds at the
    /// other). The leg under way is planned again after it. True when a
    /// look was queued.
    fn look_at_unseen(&mut self, config: &ExecutiveConfig, est: &Estimate) -> bool {
        for wall in self.unseen(est) {
            if self.looked.contains(&wall) {
                continue;
            }
            self.looked.push(wall);
            if let Some(way) = look_at(config, est, wall, self.speed_mps) {
                self.ways.replace(way);
                if let Some(legs) = self.legs.as_mut() {
                    legs.under_way = legs.under_way.and_then(|k| k.checked_sub(1));
                }
                return true;
            }
        }
        false
    }
}

/// The way that turns the robot on its spot toward the middle of `wall`,
/// or failing that as far toward it as a clear way does, in steps of
/// [`LOOK_STEP_RAD`] back toward its heading; `None` when it faces the
/// wall within a step already, or no clear way turns it toward it at all.
fn look_at(
    config: &ExecutiveConfig,
    est: &Estimate,
    wall: WallName,
    speed_mps: f64,
) -> Option<Vec<Behaviour>> {
    let g = WallGeometry::in_room(est, wall)?;
    let middle = g.point(0.5 * g.length_m, 0.0);
    let here = est.pose;
    let toward = (middle.y - here.y).atan2(middle.x - here.x);
    let off = stucco_core::wrap_angle(toward - here.theta);
    let steps = (off.abs() / LOOK_STEP_RAD).ceil() as usize;
    (0..steps).find_map(|k| {
        let heading = stucco_core::wrap_angle(toward - off.signum() * LOOK_STEP_RAD * k as f64);
        let goal = Pose2::new(here.x, here.y, heading);
        planned_way(config, est, &here, &goal, speed_mps).map(|w| w.1)
    })
}

/// Steps of a look turned short of facing its wall, rad.
const LOOK_STEP_RAD: f64 = std::f64::consts::FRAC_PI_6;

impl Task for MapRoom {
    fn start(&mut self, cx: &mut TaskCx<'_>, _: &mut Option<Thaw>) -> Result<(), TaskFailure> {
        // Walls too short for the laser to take for a line (a chimney
        // breast's sides) are never seen: left out from the start.
        let sight = Sight::new(cx.est);
        let short: Vec<WallName> = walls_or_all(self.walls.as_deref(), cx.est)
            .into_iter()
            .filter(|&w| !sight.seeable(w))
            .collect();
        self.hide(cx, short);
        let Some(path) = self.path.as_deref() else {
            return Ok(());
        };
        let (config, est, pose) = (cx.config, cx.est, cx.est.pose);
        let speed_mps = self.speed_mps;
        let corners = path.to_vec();
        if turns_on_the_move(&corners, est.room_m, &est.corners, &config.vehicle) {
            let loop_ = closed(&corners);
            let (a, b) = (loop_[0], loop_[1]);
            let towards = (b[1] - a[1]).atan2(b[0] - a[0]);
            let queue = &mut self.ways.queue;
            queue.extend(way(
                config,
                est,
                &pose,
                &Pose2::new(a[0], a[1], towards),
                speed_mps,
            ));
            queue.push_back(Behaviour::path(&config.gains, loop_, speed_mps));
        } else {
            self.legs = Some(Legs::new(corners, None, speed_mps));
        }
        Ok(())
    }

    fn step(&mut self, cx: &mut TaskCx<'_>) -> TaskStep {
        let (config, est) = (cx.config, cx.est);
        let elapsed = cx.elapsed_s();
        let timeout_s = self.timeout_s;
        let unseen = self.unseen(est);
        let loose = self.loose(est);
        // Known, yet held between corners all this time (someone pacing
        // the corridor it maps): done where it stands, not failed.
        if elapsed > timeout_s && unseen.is_empty() && loose.is_empty() {
            return TaskStep::Done;
        }
        if elapsed > timeout_s {
            let stuck = self.legs.as_ref().is_some_and(Legs::stuck);
            let sigma_m = loose.iter().fold(0.0f64, |m, &s| m.max(s));
            // Every wall seen, only the size loose: done with it as known
            // when the task says so (the plaster task after it guards its
            // own spraying).
            if !stuck
                && self.looks.stuck_on.is_none()
                && unseen.is_empty()
                && self.on_loose_size == OnTimeout::Continue
            {
                cx.emit(EventKind::RoomSizeLoose {
                    task: cx.index,
                    sigma_m,
                });
                return TaskStep::Done;
            }
            return TaskStep::Failed(if stuck {
                TaskFailure::NoWayToCorners
            } else if self.looks.stuck_on.is_some() {
                TaskFailure::NoWayToViews
            } else if unseen.is_empty() {
                TaskFailure::RoomSizeLoose { sigma_m, timeout_s }
            } else {
                TaskFailure::WallsNotSeen {
                    walls: unseen,
                    timeout_s,
                }
            });
        }
        if self.path.is_none() {
            if unseen.is_empty() && loose.is_empty() {
                return TaskStep::Done;
            }
            return self.step_views(cx, unseen);
        }
        if let (true, Some(legs)) = (self.ways.idle(), self.legs.as_mut()) {
            // The first leg waits for the laser to have found what
            // stands on the floor near the robot (the plan that
            // follows stands on it too).
            if legs.under_way.is_none() && elapsed < LOOK_ROUND_S {
                return TaskStep::Drive(DriveCommand::STOP);
            }
            // Corner to corner: done at any corner once the walls
            // are known.
            if unseen.is_empty() && loose.is_empty() {
                return TaskStep::Done;
            }
            // No way reached a corner: the robot waits for the floor map
            // to change (someone standing in the way steps off) until the
            // timeout.
            if legs.stuck_on_map(est) {
                if !unseen.is_empty() && self.look_at_unseen(config, est) {
                    return TaskStep::Drive(self.ways.step(cx).unwrap_or(DriveCommand::STOP));
                }
                return TaskStep::Drive(DriveCommand::STOP);
            }
            let way = legs.next(config, est).unwrap_or_default();
            if way.is_empty() {
                // No clear way to this corner: the next one, next
                // tick.
                return TaskStep::Drive(DriveCommand::STOP);
            }
            self.ways.queue.extend(way);
        }
        if self.legs.is_none() && self.ways.idle() {
            if unseen.is_empty() && loose.is_empty() {
                return TaskStep::Done;
            }
            // Another loop, from where the last one ended: each one
            // sees the walls again.
            let gains = &config.gains;
            let l = closed(self.path.as_deref().unwrap_or_default());
            if let (Some(a), Some(b)) = (l.first(), l.get(1)) {
                let start = Pose2::new(a[0], a[1], (b[1] - a[1]).atan2(b[0] - a[0]));
                let speed_mps = self.speed_mps;
                self.ways
                    .queue
                    .extend(go_to(gains, &est.pose, &start, speed_mps));
                self.ways
                    .queue
                    .push_back(Behaviour::path(gains, l, speed_mps));
            }
        }
        // Let the task-level check decide on the next tick (a survey may
        // loop again); stand still meanwhile.
        TaskStep::Drive(self.ways.step(cx).unwrap_or(DriveCommand::STOP))
    }

    fn blocked(&mut self, cx: &mut TaskCx<'_>, blocked_s: f64) -> bool {
        if blocked_s <= REPLAN_AFTER_S {
            return false;
        }
        // A loop turned on the move (or the way to its start) that
        // something blocks, seen only once the robot was in the room (a
        // box beside the door it came in by): the loop goes on corner to
        // corner from the end of the side it was on, each leg the planned
        // way round what the map holds by then.
        if self.path.is_none() {
            return self.views_blocked(cx);
        }
        if self.legs.is_none()
            && let Some(corners) = self.path.clone()
        {
            let mut legs = Legs::new(corners, None, self.speed_mps);
            legs.take_over(self.ways.kind());
            self.legs = Some(legs);
            self.ways.replace(Vec::new());
            return true;
        }
        if self.look_at_unseen(cx.config, cx.est) {
            return true;
        }
        // So on a leg of a loop driven corner to corner.
        if let Some(legs) = self.legs.as_mut()
            && let Some(q) = legs.again(cx.config, cx.est)
        {
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

/// A loop driven corner to corner (a `map_room`'s, or a plastering
/// survey's where the room is too small to turn its corners on the move),
/// each leg planned as it starts, on what the laser has found on the floor
/// by then.
#[derive(Clone, Debug)]
pub(crate) struct Legs {
    corners: Vec<[f64; 2]>,
    /// A survey's loop: its corners are fitted again, as each leg starts,
    /// to what the laser has found on the floor by then (a column in a
    /// corner seen only once the loop is under way), with the margins and
    /// the body's reach of `survey_rect`. None: a mission's own corners.
    refit: Option<([f64; 2], [f64; 2])>,
    /// Legs to drive in all; none: round and round until the task ends.
    count: Option<usize>,
    /// The leg under way (the first to the first corner); none before it.
    pub(crate) under_way: Option<usize>,
    /// Times the leg under way was planned again.
    replans: usize,
    /// Legs in a row that no clear way reached (a corner the robot stood
    /// at already neither counts nor breaks the row).
    unreached: usize,
    /// What the floor map held when no corner was reached: the legs are
    /// planned again only once it holds something else (each try is a
    /// search through every way about the room).
    stuck_on: Option<Vec<Obstacle>>,
    speed_mps: f64,
}

impl Legs {
    fn new(corners: Vec<[f64; 2]>, count: Option<usize>, speed_mps: f64) -> Legs {
        Legs {
            corners,
            refit: None,
            count,
            under_way: None,
            replans: 0,
            unreached: 0,
            stuck_on: None,
            speed_mps,
        }
    }

    /// Takes over from the loop driven on the move whose behaviour under
    /// way is `kind`: the next leg goes to the end of the side it was on
    /// (the legs' sides are the loop's, in the same order); from its
    /// start, before the loop began.
    pub(crate) fn take_over(&mut self, kind: Option<&BehaviourKind>) {
        self.under_way = match kind {
            Some(BehaviourKind::Path { segment, .. }) => Some(*segment),
            _ => None,
        };
    }

    /// True when no clear way reached any corner the last time round.
    pub(crate) fn stuck(&self) -> bool {
        self.unreached >= self.corners.len().max(1)
    }

    /// True when the legs are [`Legs::stuck`] on the floor map `est` holds:
    /// no clear way reached a corner on this map. A map that changed since
    /// (what blocked the ways moved, or was seen to be less) lets them be
    /// planned again.
    fn stuck_on_map(&mut self, est: &Estimate) -> bool {
        if !self.stuck() {
            return false;
        }
        match &self.stuck_on {
            Some(held) if floor_changed(held, &est.obstacles) => {
                self.stuck_on = None;
                self.unreached = 0;
                false
            }
            Some(_) => true,
            None => {
                self.stuck_on = Some(est.obstacles.clone());
                true
            }
        }
    }

    /// The next leg's way from where the robot stands; `None` when every
    /// leg is driven. A corner no clear way reaches is left out (an
    /// empty way).
    pub(crate) fn next(
        &mut self,
        config: &ExecutiveConfig,
        est: &Estimate,
    ) -> Option<Vec<Behaviour>> {
        let next = self.under_way.map_or(0, |k| k + 1);
        if self.count.is_some_and(|c| next >= c) {
            return None;
        }
        self.under_way = Some(next);
        self.replans = 0;
        if let Some((margins, half)) = self.refit
            && let Some(corners) = survey_rect(est, margins, half, SURVEY_LEGS_MIN_M)
        {
            self.corners = corners.to_vec();
        }
        let way = self.leg(config, est, next);
        match &way {
            // Standing at the corner: nothing reached, nothing tried (a
            // robot at one corner that no way leaves is stuck there).
            Some(w) if w.is_empty() => {}
            Some(_) => self.unreached = 0,
            None => self.unreached += 1,
        }
        Some(way.unwrap_or_default())
    }

    /// The leg under way planned again (something the map did not hold
    /// blocks it), at most `MAX_REPLANS` times.
    pub(crate) fn again(
        &mut self,
        config: &ExecutiveConfig,
        est: &Estimate,
    ) -> Option<Vec<Behaviour>> {
        let k = self.under_way?;
        (self.replans < MAX_REPLANS).then(|| {
            self.replans += 1;
            self.leg(config, est, k).unwrap_or_default()
        })
    }

    /// Leg `leg`: to corner `leg` (modulo their number), arriving faced to
    /// the next, by the planned way; where no way arrives so, faced away
    /// from it (the next leg is backed: a corridor's end where the robot
    /// cannot turn). A robot already at the corner needs no way (the
    /// corner is where the walls are looked at from, a few centimetres
    /// either way alike): an empty one. `None`: no clear way.
    fn leg(&self, config: &ExecutiveConfig, est: &Estimate, leg: usize) -> Option<Vec<Behaviour>> {
        let n = self.corners.len();
        if n == 0 {
            return None;
        }
        let (a, b) = (self.corners[leg % n], self.corners[(leg + 1) % n]);
        if (est.pose.position().coords - nalgebra::Vector2::from(a)).norm() <= AT_CORNER_M {
            return Some(Vec::new());
        }
        let toward = (b[1] - a[1]).atan2(b[0] - a[0]);
        [
            toward,
            stucco_core::wrap_angle(toward + std::f64::consts::PI),
        ]
        .into_iter()
        .find_map(|heading| {
            let goal = Pose2::new(a[0], a[1], heading);
            planned_way(config, est, &est.pose, &goal, self.speed_mps).map(|w| w.1)
        })
    }
}

/// True when the floor map `now` holds something `then` did not, or no
/// longer holds something it did: a piece more or less, or a side of one
/// moved by more than [`FLOOR_MOVED_M`] (less is the map's own jitter: a
/// cell more of an edge, the room's size refined).
fn floor_changed(then: &[Obstacle], now: &[Obstacle]) -> bool {
    then.len() != now.len()
        || then.iter().zip(now).any(|(a, b)| {
            a.min_m
                .iter()
                .chain(&a.max_m)
                .zip(b.min_m.iter().chain(&b.max_m))
                .any(|(p, q)| (p - q).abs() > FLOOR_MOVED_M)
        })
}

/// A side of something on the floor map moved by more than this has
/// moved, m (the map's cells are 5 cm).
const FLOOR_MOVED_M: f64 = 0.1;

/// A robot this near a loop's corner is at it, m.
const AT_CORNER_M: f64 = 0.1;

/// A look at every wall before the plan is made again on what the camera
/// found: one loop round the room, clockwise so the camera (looking left)
/// faces each wall in turn. Where the room leaves room for it, the loop
/// stands `clearance` from the walls and is turned on the move; where it
/// does not (a small kitchen, a furnished bedroom), it runs nearer the
/// walls, at `SURVEY_LEG_STANDOFF_M`, corner to corner, each leg the
/// planned way as it starts (the legs returned). Either keeps clear of
/// what stands on the floor; its start is reached by the planned way.
pub(crate) fn survey_way(
    config: &ExecutiveConfig,
    clearance: f64,
    est: &Estimate,
    speed: f64,
) -> (Vec<Behaviour>, Option<Legs>) {
    let vehicle = &config.vehicle;
    let [xs, ys] = est.room_m;
    // What the body reaches toward the furniture beside the loop's long
    // sides (half its width) and at its ends (its front, turning).
    let side = survey_side_reach(vehicle);
    let front = vehicle.front_m() + 0.15;
    let half = if xs >= ys {
        [front, side]
    } else {
        [side, front]
    };
    // The loop's ends stand off a little more: its corners are turned
    // on the move, the front swinging out past them.
    let ends = clearance + 0.2;
    let margins = if xs >= ys {
        [ends, clearance]
    } else {
        [clearance, ends]
    };
    // The loop, where a clear way reaches its start (driven blind to a
    // start beyond two tables, the robot was held between them, where it
    // could turn no more) and its line keeps inside the room (laid in
    // the box of an L, it ran through the notch's walls). What stands on
    // the floor near it the loop meets on the move, and goes on corner
    // to corner from there (`SURVEY_BLOCKED_S`).
    if let Some(corners) = survey_rect(est, margins, half, SURVEY_LOOP_MIN_M) {
        let path = closed(&corners);
        let (a, b) = (path[0], path[1]);
        let start = Pose2::new(a[0], a[1], (b[1] - a[1]).atan2(b[0] - a[0]));
        let walls = Space::new(
            est.room_m,
            &est.corners,
            &est.doors,
            &[],
            vehicle,
            &config.safety,
            speed,
        );
        if let Some((_, mut way)) = planned_way(config, est, &est.pose, &start, speed)
            && walls.path_open(&path)
        {
            way.push(Behaviour::path(&config.gains, path, speed));
            return (way, None);
        }
    }
    (Vec::new(), survey_legs(vehicle, est, speed))
}

/// What the body reaches toward the furniture beside a survey loop's
/// side: half its width and 0.15 m, m.
fn survey_side_reach(vehicle: &VehicleSpec) -> f64 {
    0.5 * vehicle.width_m + 0.15
}

/// A survey loop driven corner to corner, `SURVEY_LEG_STANDOFF_M` off the
/// walls, stopping at each: to the first, then round to it, each leg the
/// planned way, the corners fitted again to the floor map as each starts.
/// None: the room leaves no loop.
pub(crate) fn survey_legs(vehicle: &VehicleSpec, est: &Estimate, speed: f64) -> Option<Legs> {
    let side = survey_side_reach(vehicle);
    let fit = ([SURVEY_LEG_STANDOFF_M; 2], [side, side]);
    let corners = survey_rect(est, fit.0, fit.1, SURVEY_LEGS_MIN_M)?;
    let mut legs = Legs::new(corners.to_vec(), Some(corners.len() + 1), speed);
    legs.refit = Some(fit);
    Some(legs)
}

/// A plastering survey's loop turned on the move, stopped this long by
/// something in its way, goes on corner to corner, s: the stops it meets
/// at furniture it passes near mostly clear within 3.5 s (the two
/// offices' table), and going on corner to corner costs ten times that.
pub(crate) const SURVEY_BLOCKED_S: f64 = 5.0;

/// Shortest side of a survey loop driven corner to corner, m.
const SURVEY_LEGS_MIN_M: f64 = 0.3;

/// Sides shorter than this make the survey loop, turned on the move, too
/// small to see a window whole (a kitchen's 0.4 m): it is driven corner to
/// corner nearer the walls instead, m.
const SURVEY_LOOP_MIN_M: f64 = 0.6;

/// How far from the walls a survey loop driven corner to corner runs, m.
const SURVEY_LEG_STANDOFF_M: f64 = 0.6;

/// The corners of a survey loop `margins` (along x, along y) inside the
/// walls, moved off the furniture near the walls (each piece moves the
/// side it stands before in by `half` — what the body reaches toward it
/// across x and across y; of two, the one that costs the loop least), in
/// the order it is driven: west along the south side first, the camera
/// on the south wall. `None` when a side is shorter than `min_side`.
fn survey_rect(
    est: &Estimate,
    margins: [f64; 2],
    half: [f64; 2],
    min_side: f64,
) -> Option<[[f64; 2]; 4]> {
    let [xs, ys] = est.room_m;
    let [half_x, half_y] = half;
    let (mut x0, mut x1, mut y0, mut y1) =
        (margins[0], xs - margins[0], margins[1], ys - margins[1]);
    for o in &est.obstacles {
        let (cx, cy) = (
            0.5 * (o.min_m[0] + o.max_m[0]),
            0.5 * (o.min_m[1] + o.max_m[1]),
        );
        let (w, h) = (x1 - x0, y1 - y0);
        // (loss of area, side, new place)
        let mut moves: Vec<(f64, usize, f64)> = Vec::new();
        if cx < 0.5 * xs && o.max_m[0] + half_x > x0 && o.max_m[0] < 0.5 * xs {
            moves.push(((o.max_m[0] + half_x - x0) * h, 0, o.max_m[0] + half_x));
        }
        if cx > 0.5 * xs && o.min_m[0] - half_x < x1 && o.min_m[0] > 0.5 * xs {
            moves.push(((x1 - (o.min_m[0] - half_x)) * h, 1, o.min_m[0] - half_x));
        }
        if cy < 0.5 * ys && o.max_m[1] + half_y > y0 && o.max_m[1] < 0.5 * ys {
            moves.push(((o.max_m[1] + half_y - y0) * w, 2, o.max_m[1] + half_y));
        }
        if cy > 0.5 * ys && o.min_m[1] - half_y < y1 && o.min_m[1] > 0.5 * ys {
            moves.push(((y1 - (o.min_m[1] - half_y)) * w, 3, o.min_m[1] - half_y));
        }
        // A piece reaching across the middle (a bed and a desk along a
        // bedroom) that the body would meet: whichever side it cuts least.
        // (Within the loop, clear of its sides by the body's half width
        // and more, it is driven round.)
        let r = half_x.min(half_y);
        let meets = o.max_m[0] + r > x0
            && o.min_m[0] - r < x1
            && o.max_m[1] + r > y0
            && o.min_m[1] - r < y1
            && !(o.min_m[0] - r > x0
                && o.max_m[0] + r < x1
                && o.min_m[1] - r > y0
                && o.max_m[1] + r < y1);
        if moves.is_empty() && meets {
            let cuts = [
                (0, o.max_m[0] + half_x, x1 - (o.max_m[0] + half_x)),
                (1, o.min_m[0] - half_x, (o.min_m[0] - half_x) - x0),
                (2, o.max_m[1] + half_y, y1 - (o.max_m[1] + half_y)),
                (3, o.min_m[1] - half_y, (o.min_m[1] - half_y) - y0),
            ];
            // On the robot's side of it, when it stands clear of it one
            // way or the other (a piece across the whole room leaves no
            // way to the other side).
            let p = est.pose.position();
            let robots_side = |side: usize| match side {
                0 => p.x > o.max_m[0],
                1 => p.x < o.min_m[0],
                2 => p.y > o.max_m[1],
                _ => p.y < o.min_m[1],
            };
            let any_side = cuts.iter().any(|c| c.2 > 0.0 && robots_side(c.0));
            moves.extend(
                cuts.into_iter()
                    .filter(|c| c.2 > 0.0 && (!any_side || robots_side(c.0)))
                    .map(|(side, at, left)| {
                        let loss = if side < 2 {
                            (w - left) * h
                        } else {
                            (h - left) * w
                        };
                        (loss, side, at)
                    }),
            );
        }
        if let Some(&(_, side, at)) = moves.iter().min_by(|a, b| a.0.total_cmp(&b.0)) {
            match side {
                0 => x0 = at,
                1 => x1 = at,
                2 => y0 = at,
                _ => y1 = at,
            }
        }
    }
    (x1 - x0 >= min_side && y1 - y0 >= min_side).then_some([[x1, y0], [x0, y0], [x0, y1], [x1, y1]])
}

/// Margin a loop's corners keep from the walls beyond the front's reach
/// ahead of the rear axle, for the loop to be turned on the move, m.
const ON_THE_MOVE_SPARE_M: f64 = 0.1;

/// True when a `map_room` loop through `corners` can be driven as one path,
/// its corners turned on the move: the front swings out past each corner
/// by as much as its reach ahead of the rear axle, and every corner stands
/// that far and `ON_THE_MOVE_SPARE_M` more from every wall. A loop in a
/// furnished bedroom, between the bed and the wall, does not.
fn turns_on_the_move(
    corners: &[[f64; 2]],
    room_m: [f64; 2],
    outline: &[[f64; 2]],
    vehicle: &VehicleSpec,
) -> bool {
    let reach = vehicle.front_m() + ON_THE_MOVE_SPARE_M;
    if !outline.is_empty() {
        let room = Outline::new(outline);
        return corners
            .iter()
            .all(|c| room.clearance_m(&(*c).into()) >= reach);
    }
    corners
        .iter()
        .all(|&[x, y]| x.min(room_m[0] - x) >= reach && y.min(room_m[1] - y) >= reach)
}

/// The loop through `points` as a path that starts and ends halfway along
/// its first side: every corner is turned on the move, and the next loop
/// goes on from where this one ends, heading its way.
fn closed(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let (Some(&a), Some(&b)) = (points.first(), points.get(1)) else {
        return points.to_vec();
    };
    let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    let mut p = vec![mid];
    p.extend_from_slice(&points[1..]);
    p.push(a);
    p.push(mid);
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::known_room;

    /// A plastering survey's loop is laid in the room's box: in an L
    /// room it ran through the notch's walls. Where its line leaves the
    /// room (or no clear way reaches its start), the survey goes corner to
    /// corner, each leg the planned way.
    #[test]
    fn a_survey_loop_through_a_wall_is_driven_corner_to_corner() {
        let config = ExecutiveConfig::driving(VehicleSpec::default());
        let clearance = super::super::pivot_clearance(&config);
        let rectangle = [[0.0, 0.0], [7.0, 0.0], [7.0, 6.0], [0.0, 6.0]];
        let l_room = [
            [0.0, 0.0],
            [7.0, 0.0],
            [7.0, 3.5],
            [3.5, 3.5],
            [3.5, 6.0],
            [0.0, 6.0],
        ];
        let pose = Pose2::new(2.0, 2.0, 0.0);
        let (way, legs) = survey_way(
            &config,
            clearance,
            &known_room([7.0, 6.0], &rectangle, pose),
            0.2,
        );
        assert!(legs.is_none() && way.last().is_some_and(|b| b.name() == "path"));
        let (way, legs) = survey_way(
            &config,
            clearance,
            &known_room([7.0, 6.0], &l_room, pose),
            0.2,
        );
        assert!(legs.is_some() && way.is_empty(), "{way:?}");
    }

    #[test]
    fn the_floor_map_has_changed_when_a_piece_comes_goes_or_moves_not_when_it_jitters() {
        let table = |x: f64| Obstacle {
            min_m: [x, 1.0],
            max_m: [x + 0.8, 1.6],
            height_m: 0.8,
        };
        let map = [table(1.0)];
        // A cell more of an edge, the room's size refined: the same map.
        assert!(!floor_changed(&map, &[table(1.05)]));
        // Moved, gone, or another one seen: changed.
        assert!(floor_changed(&map, &[table(1.2)]));
        assert!(floor_changed(&map, &[]));
        assert!(floor_changed(&map, &[table(1.0), table(3.0)]));
    }
}
