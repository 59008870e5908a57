//! Ways across a room that keep the robot's body off what stands on the
//! floor: a straight move is checked with the body swept along it, and
//! when it would touch something, the way goes round through places where
//! the robot can turn on the spot (Dijkstra over a grid of them).

use crate::behaviour::{Behaviour, go_to};
use nalgebra::Vector2;
use std::collections::BTreeSet;
use stucco_control::GainSchedule;
use stucco_core::{Pose2, VehicleSpec};
use stucco_plan::Obstacle;

/// Room left between the body and what stands on the floor, m.
const MARGIN_M: f64 = 0.05;
/// Spacing of the places the way may turn at, m.
const GRID_M: f64 = 0.2;

/// What a way is planned around: the room, what stands in it, the body.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Floor<'a> {
    /// The room's size, m.
    pub room_m: [f64; 2],
    /// What stands on the floor.
    pub obstacles: &'a [Obstacle],
    /// Behind the rear axle, m.
    pub rear_m: f64,
    /// Ahead of it, m.
    pub front_m: f64,
    /// Half the body's width, m.
    pub half_width_m: f64,
    /// Distance from every wall and obstacle a turn on the spot needs, m.
    pub clearance_m: f64,
}

impl<'a> Floor<'a> {
    /// The room `room_m` with `obstacles`, for `vehicle` turning within
    /// `clearance_m`.
    pub fn new(
        room_m: [f64; 2],
        obstacles: &'a [Obstacle],
        vehicle: &VehicleSpec,
        clearance_m: f64,
    ) -> Self {
        Floor {
            room_m,
            obstacles,
            rear_m: vehicle.rear_overhang_m,
            front_m: vehicle.front_m(),
            half_width_m: 0.5 * vehicle.width_m,
            clearance_m,
        }
    }

    /// Distance from `p` to the nearest obstacle, m.
    fn nearest(&self, p: &Vector2<f64>) -> f64 {
        self.obstacles
            .iter()
            .map(|o| {
                let dx = (o.min_m[0] - p.x).max(p.x - o.max_m[0]).max(0.0);
                let dy = (o.min_m[1] - p.y).max(p.y - o.max_m[1]).max(0.0);
                dx.hypot(dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// True when the body, driven straight from `a` to `b` (the rear
    /// axle's middle) heading along the move, touches nothing on the
    /// floor.
    pub fn move_clear(&self, a: &Vector2<f64>, b: &Vector2<f64>) -> bool {
        let d = b - a;
        match d.try_normalize(1e-9) {
            Some(h) => self.sweep_clear(a, b, &h),
            None => self.nearest(a) >= self.half_width_m + MARGIN_M,
        }
    }

    /// True when the body, facing `facing` (a unit vector) and moved from
    /// `a` to `b` (forward or backing, drifting sideways as the line law
    /// takes it onto a parallel line), touches nothing: the rectangle it
    /// sweeps, from its rear at the hindmost place to its front at the
    /// foremost and across both sideways places, against each obstacle
    /// grown by the margin (separating axes).
    pub fn sweep_clear(&self, a: &Vector2<f64>, b: &Vector2<f64>, facing: &Vector2<f64>) -> bool {
        let f = *facing;
        let n = Vector2::new(-f.y, f.x);
        let (s, l) = (f.dot(&(b - a)), n.dot(&(b - a)));
        let (back, ahead) = (s.min(0.0) - self.rear_m, s.max(0.0) + self.front_m);
        let c = a + f * (0.5 * (back + ahead)) + n * (0.5 * l);
        let (hl, hw) = (0.5 * (ahead - back), self.half_width_m + 0.5 * l.abs());
        rect_clear(self.obstacles, &c, &f, [hl, hw], MARGIN_M)
    }

    /// True when nothing on the floor stands within the turning clearance
    /// of `p` (the walls not looked at).
    pub fn turnable_among_obstacles(&self, p: &Vector2<f64>) -> bool {
        self.nearest(p) >= self.clearance_m
    }

    /// True when the robot can turn on the spot at `p`.
    fn turnable(&self, p: &Vector2<f64>) -> bool {
        let c = self.clearance_m;
        let [xs, ys] = self.room_m;
        (c..=xs - c).contains(&p.x)
            && (c..=ys - c).contains(&p.y)
            && self.turnable_among_obstacles(p)
    }

    /// The places to turn at between `from` and `to` (both where the
    /// robot can turn) on the shortest way whose every move is clear:
    /// none when the straight move is; `None` when no way is.
    pub fn waypoints(&self, from: &Vector2<f64>, to: &Vector2<f64>) -> Option<Vec<Vector2<f64>>> {
        if self.move_clear(from, to) {
            return Some(Vec::new());
        }
        let [xs, ys] = self.room_m;
        let (nx, ny) = ((xs / GRID_M) as usize, (ys / GRID_M) as usize);
        let mut nodes = vec![*from, *to];
        for i in 1..nx {
            for j in 1..ny {
                let p = Vector2::new(i as f64 * GRID_M, j as f64 * GRID_M);
                if self.turnable(&p) {
                    nodes.push(p);
                }
            }
        }
        // Dijkstra from node 0 to node 1; edges checked as they are met.
        let n = nodes.len();
        let mut dist = vec![f64::INFINITY; n];
        let mut prev: Vec<Option<usize>> = vec![None; n];
        let mut open = BTreeSet::new();
        dist[0] = 0.0;
        open.insert((0u64, 0usize));
        while let Some((_, k)) = open.pop_first() {
            if k == 1 {
                let mut way = Vec::new();
                let mut at = prev[1];
                while let Some(p) = at {
                    if p == 0 {
                        break;
                    }
                    way.push(nodes[p]);
                    at = prev[p];
                }
                way.reverse();
                return Some(way);
            }
            for m in 1..n {
                let step = (nodes[m] - nodes[k]).norm();
                let d = dist[k] + step;
                if d < dist[m] && self.move_clear(&nodes[k], &nodes[m]) {
                    open.remove(&(dist[m].to_bits(), m));
                    dist[m] = d;
                    prev[m] = Some(k);
                    open.insert((d.to_bits(), m));
                }
            }
        }
        None
    }
}

/// True when the rectangle centred at `c`, its long axis along the unit
/// vector `f` and its half sizes `[along, across]`, keeps `margin_m` from
/// every obstacle (separating axes).
pub(crate) fn rect_clear(
    obstacles: &[Obstacle],
    c: &Vector2<f64>,
    f: &Vector2<f64>,
    [hl, hw]: [f64; 2],
    margin_m: f64,
) -> bool {
    let n = Vector2::new(-f.y, f.x);
    obstacles.iter().all(|o| {
        let bc = Vector2::new(
            0.5 * (o.min_m[0] + o.max_m[0]),
            0.5 * (o.min_m[1] + o.max_m[1]),
        );
        let bh = Vector2::new(
            0.5 * (o.max_m[0] - o.min_m[0]) + margin_m,
            0.5 * (o.max_m[1] - o.min_m[1]) + margin_m,
        );
        let d = c - bc;
        d.x.abs() > hl * f.x.abs() + hw * n.x.abs() + bh.x
            || d.y.abs() > hl * f.y.abs() + hw * n.y.abs() + bh.y
            || f.dot(&d).abs() > hl + bh.x * f.x.abs() + bh.y * f.y.abs()
            || n.dot(&d).abs() > hw + bh.x * n.x.abs() + bh.y * n.y.abs()
    })
}

/// The behaviours from `from` to `goal` (both places the robot can turn
/// at) round what stands on the floor: turn, drive, turn at each place of
/// the way; the straight [`go_to`] when nothing is in the way or no way
/// round is found (the supervisor stops the robot before it touches
/// anything).
pub(crate) fn route(
    gains: &GainSchedule,
    floor: &Floor,
    from: &Pose2,
    goal: &Pose2,
    speed_mps: f64,
) -> Vec<Behaviour> {
    let (a, b) = (from.position().coords, goal.position().coords);
    let Some(via) = floor.waypoints(&a, &b) else {
        return go_to(gains, from, goal, speed_mps);
    };
    let mut out = Vec::new();
    let mut at = *from;
    for (i, p) in via.iter().enumerate() {
        let next = via.get(i + 1).copied().unwrap_or(b);
        let d = next - p;
        let stop = Pose2::new(p.x, p.y, d.y.atan2(d.x));
        out.extend(go_to(gains, &at, &stop, speed_mps));
        at = stop;
    }
    out.extend(go_to(gains, &at, goal, speed_mps));
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn table() -> Vec<Obstacle> {
        vec![Obstacle {
            min_m: [2.25, 1.9],
            max_m: [3.1, 3.55],
            height_m: 1.0,
        }]
    }

    #[test]
    fn a_move_past_a_table_is_checked_with_the_whole_body() {
        let obstacles = table();
        let floor = Floor::new([5.4, 5.6], &obstacles, &VehicleSpec::default(), 1.01);
        // Along a line 8 cm clear of the table's edge: the body (0.31 m
        // half-width) touches it.
        let (a, b) = (Vector2::new(0.5, 3.63), Vector2::new(4.4, 3.63));
        assert!(!floor.move_clear(&a, &b));
        // 0.45 m clear: free.
        let (a, b) = (Vector2::new(0.5, 4.0), Vector2::new(4.4, 4.0));
        assert!(floor.move_clear(&a, &b));
        // Ending short of the table, but the front reaches it.
        let (a, b) = (Vector2::new(0.5, 2.5), Vector2::new(1.8, 2.5));
        assert!(!floor.move_clear(&a, &b));
        // Stopping 0.4 m short of it with the front: free.
        let (a, b) = (Vector2::new(0.5, 2.5), Vector2::new(1.1, 2.5));
        assert!(floor.move_clear(&a, &b));
        // Backing away from it, facing it: the front starts in it.
        let east = Vector2::new(1.0, 0.0);
        let (a, b) = (Vector2::new(1.9, 2.5), Vector2::new(1.2, 2.5));
        assert!(!floor.sweep_clear(&a, &b, &east));
        let (a, b) = (Vector2::new(1.1, 2.5), Vector2::new(0.6, 2.5));
        assert!(floor.sweep_clear(&a, &b, &east));
        // Drifting sideways onto a line past the table's edge, facing
        // along it: what lies between the two lines counts.
        let (a, b) = (Vector2::new(2.6, 4.3), Vector2::new(3.6, 3.4));
        assert!(!floor.sweep_clear(&a, &b, &east));
        let (a, b) = (Vector2::new(3.4, 4.3), Vector2::new(4.4, 3.4));
        assert!(floor.sweep_clear(&a, &b, &east));
    }

    #[test]
    fn a_way_round_a_table_turns_only_where_it_can() {
        let obstacles = table();
        let floor = Floor::new([5.4, 5.6], &obstacles, &VehicleSpec::default(), 1.01);
        let (from, to) = (Vector2::new(1.2, 1.2), Vector2::new(4.3, 4.4));
        let via = floor.waypoints(&from, &to).unwrap();
        assert!(!via.is_empty());
        let mut at = from;
        for p in via.iter().chain([&to]) {
            assert!(floor.move_clear(&at, p), "{at:?} → {p:?}");
            at = *p;
        }
        for p in &via {
            assert!(floor.turnable(p), "{p:?}");
        }
        // Nothing in the way: straight there.
        let floor = Floor::new([5.4, 5.6], &[], &VehicleSpec::default(), 1.01);
        assert_eq!(floor.waypoints(&from, &to), Some(Vec::new()));
    }
}
