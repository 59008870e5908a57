//! The `plaster` task's own state: the plan it carries out, where it is in
//! it (station, pass, move), and the nozzle's command at each tick.
//!
//! At each station the robot stands still; the nozzle first travels to the
//! pass's first aim point with the spray off, then runs the pass's moves
//! in time, each aim point turned into a nozzle position in the robot's
//! frame from the estimate of the moment (so the footprint lands where the
//! plan says even when the robot stands a little off its station). Time in
//! a move only runs while spraying is allowed: when the supervisor holds
//! the spray, the nozzle waits where it is and goes on after.

use crate::model::Estimate;
use nalgebra::{Point2, Point3, Vector3};
use serde::{Deserialize, Serialize};
use stucco_core::telemetry::{EventKind, GiveUpReason, TaskFailure};
pub use stucco_core::telemetry::{PlasterCoverage, SurfaceCoverage};
use stucco_core::{Aim, Pose2, ToolCommand};
use stucco_plan::{Lane, Plan, SurfaceId, WallLine};

/// Where a plastering task is: the next spray move to carry out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cursor {
    /// The station.
    pub station: usize,
    /// The pass at it.
    pub pass: usize,
    /// The move of the pass.
    pub step: usize,
}

/// The progress of the `plaster` task under way, as a checkpoint keeps it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlasterProgress {
    /// The task's index among the mission's.
    pub task: usize,
    /// Every move before this one is done.
    pub cursor: Cursor,
    /// How far into the cursor's move the nozzle got, s.
    #[serde(default)]
    pub in_move_s: f64,
    /// Digest of the plan carried out (the plan itself is kept beside the
    /// checkpoint): a resumed run must carry out the same one.
    pub plan_digest: String,
}

/// What the nozzle does at a station.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Phase {
    /// Looking at the walls before the plan is made again.
    Surveying,
    /// The robot on its way (behaviours in the queue).
    Moving,
    /// Standing, letting the estimate settle, since then.
    Settling { left_s: f64 },
    /// The camera on the tool looking along the station's wall, spray
    /// off: the nozzle travelling to the look's start (`left_s` to go; -1:
    /// not yet set off), then sweeping, `t_s` into it.
    Looking { look: Look, left_s: f64, t_s: f64 },
    /// The nozzle travelling to the pass's first point, spray off.
    Positioning { left_s: f64 },
    /// In the cursor's move, this far into it.
    Spraying { in_move_s: f64 },
    /// Every pass sprayed: out of the last station's lane to where the
    /// robot can turn, for whatever comes next.
    Leaving,
}

/// A look along a station's wall with the camera on the tool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Look {
    /// The wall.
    pub surface: SurfaceId,
    /// From and to along it, m.
    pub u_m: [f64; 2],
    /// Height on it the aim runs at, m.
    pub height_m: f64,
}

/// The `plaster` task's state.
#[derive(Clone, Debug)]
pub(crate) struct PlasterRun {
    pub plan: Plan,
    pub cursor: Cursor,
    pub phase: Phase,
    /// Times the robot tried again to stand on the current station.
    pub retries: usize,
    /// The plan's digest (made once: the plan is large).
    pub digest: String,
    /// Where in the cursor's move to take up spraying, s (a run resumed
    /// mid-stroke).
    pub resume_s: f64,
    /// Spraying time since the last checkpoint, s.
    pub unsaved_s: f64,
    /// The way to the current station was not found clear as the map
    /// holds it (it is driven all the same, the supervisor watching).
    pub way_unchecked: bool,
    /// Stations of this plan given up, and the area only they reached,
    /// m².
    pub given_up: (usize, f64),
    /// How many of them were given up for a position too loose to spray.
    pub given_up_loose: usize,
    /// The bases of the stations put last once already (their way stayed
    /// blocked): blocked again, they are given up.
    pub deferred: Vec<Pose2>,
    /// How long the spray has been held at this station for a position
    /// known too loosely to spray on, s (0 while it sprays).
    pub held_s: f64,
}

impl PlasterRun {
    /// A run of `plan` from `cursor`.
    pub fn new(plan: Plan, cursor: Cursor) -> PlasterRun {
        PlasterRun {
            digest: plan_digest(&plan),
            plan,
            cursor,
            phase: Phase::Moving,
            retries: 0,
            resume_s: 0.0,
            unsaved_s: 0.0,
            way_unchecked: false,
            given_up: (0, 0.0),
            given_up_loose: 0,
            deferred: Vec::new(),
            held_s: 0.0,
        }
    }

    /// True when every station of the plan was given up: none is left and
    /// some were (a plan reaching nothing is not one given up).
    pub fn all_given_up(&self) -> bool {
        self.plan.stations.is_empty() && self.given_up.0 > 0
    }

    /// Gives up the current station for `reason`: the plan goes on with
    /// the next one and reports what only it reached as unreachable. The
    /// event that tells it.
    pub fn give_up_station(&mut self, task: usize, reason: GiveUpReason) -> Option<EventKind> {
        let station = self.cursor.station;
        let lost = self.plan.give_up_station(station)?;
        self.station_changed();
        self.given_up = (self.given_up.0 + 1, self.given_up.1 + lost);
        self.given_up_loose += usize::from(reason == GiveUpReason::PositionLoose);
        Some(EventKind::StationGivenUp {
            task,
            station,
            unreachable_m2: lost,
            reason,
        })
    }

    /// The task's failure once every station was given up, saying why.
    pub fn all_given_up_failure(&self) -> TaskFailure {
        TaskFailure::AllStationsGivenUp {
            stations: self.given_up.0,
            loose: self.given_up_loose,
            unreachable_m2: self.given_up.1,
        }
    }

    /// Another station is now at the cursor: from its start, the plan's
    /// digest made again.
    fn station_changed(&mut self) {
        self.cursor.pass = 0;
        self.cursor.step = 0;
        self.resume_s = 0.0;
        self.retries = 0;
        self.digest = plan_digest(&self.plan);
        self.way_unchecked = false;
    }

    /// Puts the current station last, once: its way stayed blocked, and
    /// it is tried again after the rest. False when it was put last
    /// before, or is the last (then it is to be given up).
    pub fn defer_station(&mut self) -> bool {
        let k = self.cursor.station;
        let last = self.plan.stations.len().saturating_sub(1);
        let Some(base) = self.plan.stations.get(k).map(|s| s.base) else {
            return false;
        };
        if k >= last || self.deferred.contains(&base) {
            return false;
        }
        let station = self.plan.stations.remove(k);
        self.plan.stations.push(station);
        self.deferred.push(base);
        self.station_changed();
        true
    }

    /// Puts station `k` at the cursor, before the current one (no clear
    /// way reaches that from where the robot stands; one reaches `k`).
    /// False when the current one is begun (its passes done would be
    /// sprayed again) or `k` is not after it.
    pub fn bring_forward(&mut self, k: usize) -> bool {
        let at = self.cursor.station;
        let begun = self.cursor.pass > 0 || self.cursor.step > 0 || self.resume_s > 0.0;
        if begun || k <= at || k >= self.plan.stations.len() {
            return false;
        }
        let station = self.plan.stations.remove(k);
        self.plan.stations.insert(at, station);
        self.station_changed();
        true
    }

    /// Puts `plan` in place of the one carried out, from its start.
    pub fn replan(&mut self, plan: Plan) {
        *self = PlasterRun::new(plan, Cursor::default());
    }
}

impl PlasterRun {
    /// The plan's spraying carried out up to the cursor (and into its
    /// move while spraying), surface by surface, as task `task`.
    pub fn coverage(&self, task: usize) -> PlasterCoverage {
        let mut surfaces: Vec<SurfaceCoverage> = self
            .plan
            .surfaces
            .iter()
            .map(|s| SurfaceCoverage {
                surface: s.id,
                planned_spray_s: 0.0,
                done_spray_s: 0.0,
                unreachable_m2: 0.0,
            })
            .collect();
        fn entry(all: &mut [SurfaceCoverage], id: SurfaceId) -> Option<&mut SurfaceCoverage> {
            all.iter_mut().find(|c| c.surface == id)
        }
        let in_move_s = match self.phase {
            Phase::Spraying { in_move_s } => in_move_s,
            _ => 0.0,
        };
        for (station, st) in self.plan.stations.iter().enumerate() {
            for (pass, p) in st.passes.iter().enumerate() {
                let Some(c) = entry(&mut surfaces, p.surface) else {
                    continue;
                };
                for (step, m) in p.moves.iter().enumerate().filter(|(_, m)| m.spray) {
                    let here = Cursor {
                        station,
                        pass,
                        step,
                    };
                    let d = m.duration_s();
                    c.planned_spray_s += d;
                    c.done_spray_s += match here.cmp(&self.cursor) {
                        std::cmp::Ordering::Less => d,
                        std::cmp::Ordering::Equal => in_move_s.clamp(0.0, d),
                        std::cmp::Ordering::Greater => 0.0,
                    };
                }
            }
        }
        for u in &self.plan.unreachable {
            if let Some(c) = entry(&mut surfaces, u.surface) {
                c.unreachable_m2 += u.area_m2;
            }
        }
        PlasterCoverage {
            task,
            stations_done: self.cursor.station.min(self.plan.stations.len()),
            stations: self.plan.stations.len(),
            surfaces,
        }
    }

    /// True when every move is done.
    pub fn finished(&self) -> bool {
        self.cursor.station >= self.plan.stations.len()
    }

    /// Moves the cursor past its move; true when that ended a station.
    pub fn advance(&mut self) -> bool {
        let Some(station) = self.plan.stations.get(self.cursor.station) else {
            return true;
        };
        let pass = &station.passes[self.cursor.pass];
        self.cursor.step += 1;
        if self.cursor.step < pass.moves.len() {
            return false;
        }
        self.cursor.step = 0;
        self.cursor.pass += 1;
        if self.cursor.pass < station.passes.len() {
            return false;
        }
        self.cursor.pass = 0;
        self.cursor.station += 1;
        true
    }

    /// The lane of station `k`, if there is one.
    pub fn lane(&self, k: usize) -> Option<Lane> {
        self.plan.stations.get(k).map(|s| s.lane)
    }

    /// The nozzle's command for aim point `uv` on `surface`, seen from
    /// `pose`: placed so the spray, square to the robot, meets the surface
    /// at the aim point from the standoff.
    pub fn nozzle_for(
        &self,
        surface: SurfaceId,
        uv: [f64; 2],
        pose: &Pose2,
        spray: bool,
    ) -> Option<ToolCommand> {
        let s = self.plan.surface(surface)?;
        let tool = &self.plan.tool;
        let target = s.frame.point(uv);
        let (aim, standoff) = if s.is_ceiling() {
            (Aim::Up, tool.ceiling_standoff_m)
        } else {
            (Aim::Left, tool.wall_standoff_m)
        };
        let d = aim.direction();
        let (c, si) = (pose.theta.cos(), pose.theta.sin());
        let dir = Vector3::new(c * d.x - si * d.y, si * d.x + c * d.y, d.z);
        let toward = -s.into_room(&self.plan.room);
        let square = dir.dot(&toward);
        if square < 0.5 {
            // The robot does not face the surface (more than 60° off).
            return None;
        }
        let nozzle: Point3<f64> = target - dir * (standoff / square);
        let local = pose
            .inverse()
            .transform_point(&Point2::new(nozzle.x, nozzle.y));
        let clamp = |x: f64, r: [f64; 2]| x.clamp(r[0], r[1]);
        Some(ToolCommand {
            nozzle_m: [
                clamp(local.x, tool.rail_m),
                clamp(local.y, tool.arm_m),
                clamp(nozzle.z, tool.lift_m),
            ],
            aim,
            spray,
            flow_m3ps: None,
        })
    }

    /// Where the nozzle should be at the cursor now, and whether plaster
    /// flows.
    pub fn command(&self, in_move_s: f64, est: &Estimate) -> Option<ToolCommand> {
        let station = self.plan.stations.get(self.cursor.station)?;
        let pass = station.passes.get(self.cursor.pass)?;
        let m = pass.moves.get(self.cursor.step)?;
        self.nozzle_for(pass.surface, m.at(in_move_s), &est.pose, m.spray)
    }

    /// The nozzle's command where the cursor's move is to start (its
    /// beginning, or where a resumed run takes it up), spray off.
    pub fn first_point(&self, est: &Estimate) -> Option<ToolCommand> {
        self.command(self.resume_s, est).map(ToolCommand::off)
    }

    /// The look at station `k`'s wall before it is sprayed: the wall,
    /// from where to where along it the aim runs (what its passes there
    /// reach, and `spare_m` more either way), toward the next station on
    /// the wall (or on from the last one), so that one station's look
    /// takes up where the last one's ended, and the height it runs at: at
    /// least `height_m`, and nowhere below where the station's strokes
    /// start (above what stands in front of the wall). None: no wall at
    /// station `k`.
    pub fn look(&self, k: usize, spare_m: f64, height_m: f64) -> Option<Look> {
        // Where each stroke (a run of sprayed moves at one place along the
        // wall, by the millimetre) starts from below.
        let mut lowest = std::collections::BTreeMap::<i64, f64>::new();
        for m in self
            .plan
            .stations
            .get(k)?
            .passes
            .iter()
            .filter(|p| !matches!(p.surface, SurfaceId::Ceiling))
            .flat_map(|p| p.moves.iter().filter(|m| m.spray))
        {
            let low = m.from_m[1].min(m.to_m[1]);
            for u in [m.from_m[0], m.to_m[0]] {
                let e = lowest.entry((u * 1000.0).round() as i64).or_insert(low);
                *e = e.min(low);
            }
        }
        let height_m = lowest.values().copied().fold(height_m, f64::max);
        let span = |k: usize, id: Option<SurfaceId>| -> Option<(SurfaceId, [f64; 2])> {
            let st = self.plan.stations.get(k)?;
            let pass = st.passes.iter().find(|p| {
                !matches!(p.surface, SurfaceId::Ceiling) && id.is_none_or(|i| i == p.surface)
            })?;
            let us = pass.moves.iter().flat_map(|m| [m.from_m[0], m.to_m[0]]);
            let (lo, hi) = us.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), u| {
                (a.min(u), b.max(u))
            });
            Some((pass.surface, [lo, hi]))
        };
        let (id, [lo, hi]) = span(k, None)?;
        let length = self.plan.surface(id)?.size_m()[0];
        let (lo, hi) = ((lo - spare_m).max(0.0), (hi + spare_m).min(length));
        let mid = |s: [f64; 2]| 0.5 * (s[0] + s[1]);
        let here = mid([lo, hi]);
        let up = match (
            span(k + 1, Some(id)),
            k.checked_sub(1).and_then(|j| span(j, Some(id))),
        ) {
            (Some((_, next)), _) => mid(next) >= here,
            (None, Some((_, last))) => mid(last) <= here,
            (None, None) => true,
        };
        Some(Look {
            surface: id,
            u_m: if up { [lo, hi] } else { [hi, lo] },
            height_m,
        })
    }

    /// The wall line of station `k`'s lane, with the distance from it the
    /// robot's line runs at (middle lanes: the south wall's line). A
    /// wall's station stands at the tool's standoff, or farther out where
    /// what stands before the wall leaves the body no room there.
    pub fn lane_line(&self, k: usize) -> Option<(WallLine, f64)> {
        let s = self.plan.stations.get(k)?;
        Some(match s.lane {
            Lane::Wall(w) => {
                let line = self.plan.room.wall(w)?;
                let standoff = self.plan.tool.robot_standoff_m;
                let d = line.inward.dot(&(s.base.position().coords - line.origin));
                // The tool's own, where the base stands on it but for
                // rounding.
                (
                    line,
                    if (d - standoff).abs() < 1e-6 {
                        standoff
                    } else {
                        d
                    },
                )
            }
            // A middle lane runs east: along the x axis, at its y.
            Lane::Middle(_) => (
                WallLine::between([0.0, 0.0], [self.plan.room.size_m[0], 0.0]),
                s.base.y,
            ),
        })
    }
}

/// A short digest of a plan, to match a checkpoint to the plan beside it.
pub fn plan_digest(plan: &Plan) -> String {
    // FNV-1a over the plan's JSON: stable across runs and platforms.
    let text = serde_json::to_string(plan).unwrap_or_default();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}
