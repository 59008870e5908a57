//! Where `map_room` looks at a room's walls from: view planning on the
//! room's outline and on what the laser has found standing on its floor.
//!
//! The laser takes a stretch of wall for a line when its echoes lie close
//! enough along it: near enough, and not too slant. From every place the
//! body's middle reaches over the floor, each wall is checked point by
//! point for a clear line of sight, past the room's other walls (an L's
//! notch) and past the furniture; the place that sees the most walls still
//! unseen for the least time is chosen, faced so the laser's fan takes
//! them in, and reached by the planned way.

use crate::behaviour::{Behaviour, go_to};
use crate::executive::ExecutiveConfig;
use crate::model::{Estimate, WallGeometry, room_walls};
use crate::route::rect_clear;
use crate::task::WallName;
use crate::tasks::planned_way;
use nalgebra::{Point2, Vector2};
use stucco_core::{Obstacle, Pose2, wrap_angle};
use stucco_plan::{Outline, segments_meet};

/// Spacing of the points along a wall checked for a line of sight, m.
const SAMPLE_M: f64 = 0.1;
/// The shortest stretch of wall the wall extractor takes for a line (its
/// fit keeps lines of 0.4 m and more), with a margin, m. A shorter wall
/// (a chimney breast's side) is never seen as one.
pub(crate) const LINE_MIN_M: f64 = 0.5;
/// A wall is seen from a place when a stretch of it this long is in sight
/// in one piece (of a shorter wall, [`RUN_SHARE`] of it), m.
const RUN_M: f64 = 1.0;
/// Share of a wall shorter than [`RUN_M`] that must be in sight.
const RUN_SHARE: f64 = 0.8;
/// Nearest the laser ranges, m.
const NEAR_M: f64 = 0.3;
/// How slant a beam may meet the wall: its range over the cosine of its
/// angle off the wall's normal, m. At the laser's 0.6° between beams the
/// echoes then lie at most 6 cm apart along the wall (a line of 0.5 m
/// holds eight of them, as the fit asks).
const SPREAD_M: f64 = 6.0;
/// Steepest angle off the wall's normal a beam counts at, rad (75°).
const SLANT_MAX_RAD: f64 = 75.0 * std::f64::consts::PI / 180.0;
/// Half the laser's fan that the walls looked at are kept within, rad:
/// 120° of its 135° (the walls' ends then lie in it too).
const HALF_FAN_RAD: f64 = 120.0 * std::f64::consts::PI / 180.0;
/// Places checked: every this many cells of the floor-reach grid
/// (0.1 m), so 0.2 m apart.
const EVERY_CELLS: usize = 2;
/// Time reckoned to stand at a place looking, s (the laser's scans used
/// in the wall's sightings come at 8–10 a second).
pub(crate) const DWELL_S: f64 = 3.0;
/// A place where a wall was looked at and not seen does not count for it
/// again within this distance, m.
const AGAIN_M: f64 = 1.0;
/// Places, best first, whose plain ways are checked.
const PLACES_TRIED: usize = 12;
/// Of them, those whose ways are searched for before the walls are given
/// up as out of reach for now (a search that finds none spends seconds).
const WAYS_TRIED: usize = 2;

/// The room's walls as the laser meets them: each wall's line, and what
/// may stand in a beam's way.
pub(crate) struct Sight<'a> {
    walls: Vec<(WallName, WallGeometry)>,
    obstacles: &'a [Obstacle],
}

impl<'a> Sight<'a> {
    /// The walls of the room `est` holds and what stands on its floor.
    pub(crate) fn new(est: &'a Estimate) -> Self {
        Sight {
            walls: room_walls(est),
            obstacles: &est.obstacles,
        }
    }

    /// True when the laser can see wall `w` as a line at all (it is long
    /// enough).
    pub(crate) fn seeable(&self, w: WallName) -> bool {
        self.wall(w).is_some_and(|g| g.length_m >= LINE_MIN_M)
    }

    fn wall(&self, w: WallName) -> Option<&WallGeometry> {
        self.walls.iter().find(|(n, _)| *n == w).map(|(_, g)| g)
    }

    /// The middle of the stretch of wall `w` seen from `p` (the laser
    /// there): its longest piece of points in sight, when that is long
    /// enough for a line; `None` when it is not.
    pub(crate) fn sees(&self, p: &Vector2<f64>, w: WallName) -> Option<Vector2<f64>> {
        let g = self.wall(w)?;
        if g.length_m < LINE_MIN_M {
            return None;
        }
        let need = RUN_M.min(RUN_SHARE * g.length_m).max(LINE_MIN_M);
        let n = (g.length_m / SAMPLE_M).floor().max(1.0) as usize;
        let step = g.length_m / n as f64;
        // The longest run of points in sight: where it starts and ends.
        let (mut best, mut start): ((f64, f64), Option<f64>) = ((0.0, 0.0), None);
        for k in 0..=n {
            let at = (k as f64 + 0.5) * step;
            let seen = at < g.length_m && self.in_sight(p, w, g, at);
            match (seen, start) {
                (true, None) => start = Some(at),
                (false, Some(s)) => {
                    if at - step - s > best.1 - best.0 {
                        best = (s, at - step);
                    }
                    start = None;
                }
                _ => {}
            }
        }
        // Each point stands for a step of wall.
        (best.1 - best.0 + step >= need).then(|| g.point(0.5 * (best.0 + best.1), 0.0))
    }

    /// True when the point `at_m` along wall `w` (its line `g`) is in the
    /// laser's sight from `p`: in front of the wall, in range, not too
    /// slant, and no other wall nor anything on the floor in the beam's
    /// way.
    fn in_sight(&self, p: &Vector2<f64>, w: WallName, g: &WallGeometry, at_m: f64) -> bool {
        let q = g.point(at_m, 0.0);
        let d = p - q;
        let r = d.norm();
        let facing = g.inward.dot(&d);
        if r < NEAR_M || facing <= 0.0 {
            return false;
        }
        let cos = facing / r;
        if cos < SLANT_MAX_RAD.cos() || r / cos > SPREAD_M {
            return false;
        }
        let (from, to) = (Point2::from(*p), Point2::from(q));
        let walls_clear = self.walls.iter().all(|(n, o)| {
            *n == w
                || !segments_meet(
                    &from,
                    &to,
                    &o.origin.into(),
                    &o.point(o.length_m, 0.0).into(),
                )
        });
        // The beam as a rectangle of no width, and nothing on the floor
        // within it.
        let beam = q - p;
        walls_clear
            && beam.try_normalize(1e-9).is_none_or(|f| {
                rect_clear(self.obstacles, &(p + 0.5 * beam), &f, [0.5 * r, 0.0], 0.0)
            })
    }
}

/// A place to look from: the pose to stand at, the walls it sees, and the
/// way there.
#[derive(Clone, Debug)]
pub(crate) struct View {
    /// The rear axle's pose.
    pub goal: Pose2,
    /// Where the laser stands looking (the body's middle), room frame.
    pub place: Vector2<f64>,
    /// The walls it is chosen to see.
    pub walls: Vec<WallName>,
    /// The planned way there from where the robot stood.
    pub way: Vec<Behaviour>,
}

/// Why no place was chosen.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum NoView {
    /// No place the body reaches sees any of the walls (hidden behind
    /// what stands before them, or too short for a line).
    Hidden,
    /// Places see them, but no clear way was found to any tried.
    NoWay,
}

/// A place a wall was looked at from and not seen.
pub(crate) type Spent = (Vector2<f64>, WallName);

/// The place to look at `targets` from next: of every place the body's
/// middle reaches over the floor from where the robot stands, the one
/// that sees most of them for the least time (driving there, turning to
/// face them, [`DWELL_S`] looking), faced so the laser's fan takes them
/// in, reached by a clear way. A place in `spent` within [`AGAIN_M`] of
/// where a wall was looked at and not seen does not count for that wall.
pub(crate) fn next_view(
    config: &ExecutiveConfig,
    est: &Estimate,
    targets: &[WallName],
    spent: &[Spent],
    speed_mps: f64,
) -> Result<View, NoView> {
    let space = crate::tasks::estimate_space(config, est, speed_mps);
    let reach = space.reach(&est.pose);
    let sight = Sight::new(est);
    let ahead = space.middle_ahead_m();
    let rectangle;
    let outline = if est.corners.is_empty() {
        let [xs, ys] = est.room_m;
        rectangle = [[0.0, 0.0], [xs, 0.0], [xs, ys], [0.0, ys]];
        Outline::new(&rectangle)
    } else {
        Outline::new(&est.corners)
    };
    let here = est.pose;
    let pose_at = |place: &Vector2<f64>, heading: f64| {
        Pose2::new(
            place.x - ahead * heading.cos(),
            place.y - ahead * heading.sin(),
            heading,
        )
    };
    // (score, place, pose, walls)
    let mut places: Vec<(f64, Vector2<f64>, Pose2, Vec<WallName>)> = reach
        .reached(EVERY_CELLS)
        .filter(|(c, _)| outline.contains(&(*c).into()))
        .filter_map(|(c, metres)| {
            let seen: Vec<(WallName, f64)> = targets
                .iter()
                .filter(|&&w| {
                    !spent
                        .iter()
                        .any(|(p, s)| *s == w && (p - c).norm() < AGAIN_M)
                })
                .filter_map(|&w| {
                    let m = sight.sees(&c, w)?;
                    Some((w, (m.y - c.y).atan2(m.x - c.x)))
                })
                .collect();
            // The heading that takes in most of them where the body fits
            // (along a corridor, not across it).
            let (goal, walls) = facings(&seen)
                .into_iter()
                .map(|(h, walls)| (pose_at(&c, h), walls))
                .find(|(goal, _)| space.pose_clear(goal))?;
            let turn = wrap_angle(goal.theta - here.theta).abs();
            let time = DWELL_S + metres / speed_mps.max(0.05) + turn / crate::manoeuvre::TURN_RADPS;
            Some((walls.len() as f64 / time, c, goal, walls))
        })
        .collect();
    if places.is_empty() {
        return Err(NoView::Hidden);
    }
    places.sort_by(|a, b| b.0.total_cmp(&a.0));
    places.truncate(PLACES_TRIED);
    // The plain way (turn, drive, turn) to the first of them it reaches
    // clear: no search. A search that finds no way spends its whole
    // budget, seconds of it.
    let gains = &config.gains;
    if let Some((_, place, goal, walls)) = places.iter().find(|(_, _, goal, _)| {
        space
            .way_cost(&here, &go_to(gains, &here, goal, speed_mps))
            .is_some()
    }) {
        return Ok(View {
            goal: *goal,
            place: *place,
            walls: walls.clone(),
            way: go_to(gains, &here, goal, speed_mps),
        });
    }
    for (_, place, goal, walls) in places.into_iter().take(WAYS_TRIED) {
        if let Some((_, way)) = planned_way(config, est, &here, &goal, speed_mps) {
            return Ok(View {
                goal,
                place,
                walls,
                way,
            });
        }
    }
    Err(NoView::NoWay)
}

/// Headings to look at the walls `seen` (each with the bearing of its
/// stretch in sight) from, best first, each with the walls it takes into
/// the laser's fan: the most walls, of as many the one they lie nearest
/// its middle of. Tried are the bearings themselves, the middles between
/// each two, and every [`HEADING_STEP_RAD`] round. Empty when none is
/// seen.
fn facings(seen: &[(WallName, f64)]) -> Vec<(f64, Vec<WallName>)> {
    if seen.is_empty() {
        return Vec::new();
    }
    let within = |h: f64| -> Vec<WallName> {
        seen.iter()
            .filter(|(_, b)| wrap_angle(b - h).abs() <= HALF_FAN_RAD)
            .map(|(w, _)| *w)
            .collect()
    };
    let spread = |h: f64| -> f64 {
        seen.iter()
            .map(|(_, b)| wrap_angle(b - h).abs())
            .filter(|&o| o <= HALF_FAN_RAD)
            .fold(0.0, f64::max)
    };
    let mut headings: Vec<f64> = seen.iter().map(|(_, b)| *b).collect();
    for (i, (_, a)) in seen.iter().enumerate() {
        for (_, b) in &seen[i + 1..] {
            headings.push(wrap_angle(a + 0.5 * wrap_angle(b - a)));
        }
    }
    let steps = (std::f64::consts::TAU / HEADING_STEP_RAD).round() as usize;
    headings.extend((0..steps).map(|k| wrap_angle(k as f64 * HEADING_STEP_RAD)));
    let mut out: Vec<(f64, f64, Vec<WallName>)> = headings
        .into_iter()
        .map(|h| (h, spread(h), within(h)))
        .filter(|(_, _, w)| !w.is_empty())
        .collect();
    out.sort_by(|a, b| b.2.len().cmp(&a.2.len()).then(a.1.total_cmp(&b.1)));
    out.into_iter().map(|(h, _, w)| (h, w)).collect()
}

/// Step of the headings tried round a place, rad (30°).
const HEADING_STEP_RAD: f64 = std::f64::consts::PI / 6.0;

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use stucco_core::VehicleSpec;

    fn room(corners: &[[f64; 2]], obstacles: Vec<Obstacle>, pose: Pose2) -> Estimate {
        let xs = corners.iter().map(|c| c[0]).fold(0.0, f64::max);
        let ys = corners.iter().map(|c| c[1]).fold(0.0, f64::max);
        Estimate {
            position_sigma_m: 0.01,
            room_sigma_m: [0.01; 2],
            walls_seen: vec![0; corners.len()],
            obstacles,
            ..crate::model::known_room([xs, ys], corners, pose)
        }
    }

    fn config() -> ExecutiveConfig {
        ExecutiveConfig::driving(VehicleSpec::default())
    }

    const L: [[f64; 2]; 6] = [
        [0.0, 0.0],
        [6.0, 0.0],
        [6.0, 3.0],
        [3.0, 3.0],
        [3.0, 5.0],
        [0.0, 5.0],
    ];

    /// From the L's long arm its notch's walls hide each other's far
    /// ends; the arm's end wall (wall 4, along the top of the short arm)
    /// is not in sight from the far end of the long arm, and is from the
    /// short arm.
    #[test]
    fn an_l_rooms_walls_hide_behind_its_corner() {
        let est = room(&L, Vec::new(), Pose2::new(0.0, 0.0, 0.0));
        let sight = Sight::new(&est);
        let top = WallName::from_index(4).unwrap();
        assert!(sight.sees(&Vector2::new(5.0, 1.5), top).is_none());
        assert!(sight.sees(&Vector2::new(1.5, 3.0), top).is_some());
        // The long arm's end wall (1) from its far end is too slant at
        // 0.3 m and too near; from 2.5 m off it is seen.
        let east = WallName::from_index(1).unwrap();
        assert!(sight.sees(&Vector2::new(3.5, 1.5), east).is_some());
        // A wardrobe the length of the east wall hides it.
        let wardrobe = Obstacle {
            min_m: [5.4, 0.05],
            max_m: [5.95, 2.95],
            height_m: 2.0,
        };
        let est = room(&L, vec![wardrobe], Pose2::new(0.0, 0.0, 0.0));
        let sight = Sight::new(&est);
        assert!(sight.sees(&Vector2::new(3.5, 1.5), east).is_none());
        // Too short to be a line: never seen.
        let notch = [
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 3.0],
            [2.0, 3.0],
            [2.0, 2.7],
            [1.0, 2.7],
            [1.0, 3.0],
            [0.0, 3.0],
        ];
        let est = room(&notch, Vec::new(), Pose2::new(0.0, 0.0, 0.0));
        let sight = Sight::new(&est);
        assert!(!sight.seeable(WallName::from_index(3).unwrap()));
        assert!(
            sight
                .sees(&Vector2::new(1.5, 1.0), WallName::from_index(3).unwrap())
                .is_none()
        );
        assert!(sight.seeable(WallName::from_index(4).unwrap()));
    }

    /// A robot in the long arm of an L, the short arm's walls unseen: the
    /// place chosen sees them, is reached, and is faced so they lie in
    /// the laser's fan; a wall hidden from every place is reported so.
    #[test]
    fn the_place_chosen_sees_the_walls_unseen_and_a_hidden_wall_is_told() {
        let config = config();
        let est = room(&L, Vec::new(), Pose2::new(4.5, 1.5, 0.0));
        let targets: Vec<WallName> = [3, 4]
            .iter()
            .map(|&k| WallName::from_index(k).unwrap())
            .collect();
        let view = next_view(&config, &est, &targets, &[], 0.4).unwrap();
        let sight = Sight::new(&est);
        for &w in &targets {
            let mid = sight.sees(&view.place, w);
            assert!(mid.is_some(), "{w} unseen from {:?}", view.place);
            let m = mid.unwrap();
            let b = (m.y - view.place.y).atan2(m.x - view.place.x);
            assert!(wrap_angle(b - view.goal.theta).abs() <= HALF_FAN_RAD);
        }
        assert!(!view.way.is_empty());
        // Spent: looked at from there and not seen, the next place is
        // elsewhere.
        let spent: Vec<Spent> = targets.iter().map(|&w| (view.place, w)).collect();
        let other = next_view(&config, &est, &targets, &spent, 0.4).unwrap();
        assert!((other.place - view.place).norm() >= AGAIN_M);
        // The east wall behind a wardrobe its whole length.
        let wardrobe = Obstacle {
            min_m: [5.4, 0.0],
            max_m: [6.0, 3.0],
            height_m: 2.0,
        };
        let est = room(&L, vec![wardrobe], Pose2::new(1.5, 1.5, 0.0));
        let east = [WallName::from_index(1).unwrap()];
        assert_eq!(
            next_view(&config, &est, &east, &[], 0.4).err(),
            Some(NoView::Hidden)
        );
    }
}
