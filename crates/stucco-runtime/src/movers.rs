//! People followed scan to scan: the echoes of something the laser has
//! seen move are of a mover while it is in view, even where it stops.
//!
//! Scan differencing ([`RecentScans`](crate::RecentScans)) tells an echo
//! of something moving only where a beam of the last half second passed:
//! a person who stops (waits for the robot, turns back at the end of a
//! corridor) is still after half a second, and was mapped as furniture
//! and kept for minutes behind a robot that turned its back on them
//! (generated building 10: a robot held backing in a corridor by where a
//! person had waited for it a minute before).
//!
//! So the echoes of what stands on the room's floor (inside it, off its
//! walls) are grouped, beam by beam, into blobs no wider than a person's
//! legs ([`PERSON_M`]), and each blob is followed from scan to scan (the
//! nearest blob within a walker's reach since last seen). A blob becomes
//! a mover once it has shown both signs of moving: half its echoes
//! where beams had just passed, [`THROUGH_SCANS`] scans in a row, and
//! its middle [`MOVED_M`] from where it was first seen. Either alone is
//! seen of things that stand: a beam grazing a table's leg or a face at
//! a slant passes where the last scan's echo was, and the piece of a
//! radiator's face the laser sees slides along it as the robot turns.
//! It stays a mover while it is followed, standing or walking, until it
//! has stood still for [`REST_S`]: someone standing that long is in the
//! way like furniture, and is mapped so ways are planned round them.
//!
//! A blob lost from view for [`LOST_S`] is forgotten: a person out of
//! view is where the echo memory's short keep of a mover's echoes puts
//! them.

use nalgebra::Point2;
use stucco_core::Stamp;

/// Echoes next to each other in the scan this close are of one blob, m:
/// a leg's echoes are a centimetre or two apart, a person's two legs
/// 8–30 cm.
pub const JOIN_M: f64 = 0.3;
/// The widest blob followed, m (its box's diagonal): a person's legs
/// seen from any side, and not a sofa's face or a wall.
pub const PERSON_M: f64 = 0.6;
/// How far a blob's middle must have gone from where it was first seen
/// for it to be a mover, m: a stride (someone seen first a few steps
/// before they stop for the robot).
pub const MOVED_M: f64 = 0.3;
/// Scans in a row with half a blob's echoes where beams had passed that
/// a mover shows: one could be an edge grazed, and a table's leg a few
/// centimetres thick, followed for minutes, is grazed now and then (its
/// echoes were then kept seconds, not minutes, and backed into).
pub const THROUGH_SCANS: u32 = 3;
/// How far a blob may have gone since last seen, m, and per second
/// more (a person walking briskly), m/s.
pub const GATE_M: f64 = 0.25;
/// See [`GATE_M`].
pub const WALK_MPS: f64 = 2.0;
/// A blob not seen for this long is forgotten, s.
pub const LOST_S: f64 = 1.0;
/// A mover that has stood within [`REST_M`] for this long is no longer
/// one, s: it is in the way, mapped like what stands in the room.
pub const REST_S: f64 = 10.0;
/// See [`REST_S`], m.
pub const REST_M: f64 = 0.15;

/// A blob followed.
#[derive(Clone, Debug)]
struct Track {
    /// Its middle when last seen (room frame).
    at: Point2<f64>,
    /// Its middle when first seen, or when it last came to rest.
    first: Point2<f64>,
    seen: Stamp,
    /// Scans in a row, to the last, with half its echoes where beams had
    /// passed, and whether there were ever [`THROUGH_SCANS`].
    through: (u32, bool),
    mover: bool,
    /// Where it has stood since when, within [`REST_M`].
    rest: (Point2<f64>, Stamp),
}

impl Track {
    fn born(at: Point2<f64>, stamp: Stamp) -> Self {
        Track {
            at,
            first: at,
            seen: stamp,
            through: (0, false),
            mover: false,
            rest: (at, stamp),
        }
    }

    /// Seen at `at` in the scan at `stamp`, with half its echoes or more
    /// where beams had passed when `through`.
    fn seen(&mut self, at: Point2<f64>, stamp: Stamp, through: bool) {
        self.at = at;
        self.seen = stamp;
        let run = if through { self.through.0 + 1 } else { 0 };
        self.through = (run, self.through.1 || run >= THROUGH_SCANS);
        if (at - self.rest.0).norm() > REST_M {
            self.rest = (at, stamp);
        }
        if self.through.1 && (at - self.first).norm() > MOVED_M {
            self.mover = true;
        }
        if self.mover && stamp.seconds_since(self.rest.1) > REST_S {
            *self = Track::born(at, stamp);
        }
    }
}

/// The blobs followed.
#[derive(Clone, Debug, Default)]
pub struct Movers {
    tracks: Vec<Track>,
}

/// A blob of one scan: its echoes (indices into the scan's) and middle.
struct Blob {
    echoes: Vec<usize>,
    at: Point2<f64>,
    through: bool,
}

impl Movers {
    /// Forgets every blob (the room frame moved).
    pub fn clear(&mut self) {
        self.tracks.clear();
    }

    /// Blobs followed.
    pub fn len(&self) -> usize {
        self.tracks.len()
    }

    /// True when no blob is followed.
    pub fn is_empty(&self) -> bool {
        self.tracks.is_empty()
    }

    /// Where the movers followed were last seen (room frame).
    pub fn movers(&self) -> impl Iterator<Item = Point2<f64>> + '_ {
        self.tracks.iter().filter(|t| t.mover).map(|t| t.at)
    }

    /// Takes in a scan at `stamp`: `echoes` in the room frame in beam
    /// order, `standing` true for each of something on the floor (the
    /// rest, the room's walls and what is seen beyond them, are never
    /// part of a blob), `through` true for each where a recent beam had
    /// passed.
    /// Returns, echo by echo, those of something moving: `through`, and
    /// every echo of a mover's blob.
    pub fn scan(
        &mut self,
        stamp: Stamp,
        echoes: &[Point2<f64>],
        standing: &[bool],
        through: &[bool],
    ) -> Vec<bool> {
        let blobs = blobs(echoes, standing, through);
        self.tracks
            .retain(|t| stamp.seconds_since(t.seen) <= LOST_S);
        // Each track takes the nearest blob within its reach, nearest
        // pairs first.
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for (t, track) in self.tracks.iter().enumerate() {
            let reach = GATE_M + WALK_MPS * stamp.seconds_since(track.seen).max(0.0);
            for (b, blob) in blobs.iter().enumerate() {
                let d = (blob.at - track.at).norm();
                if d <= reach {
                    pairs.push((d, t, b));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        let mut taken = vec![false; self.tracks.len()];
        let mut owner: Vec<Option<usize>> = vec![None; blobs.len()];
        for (_, t, b) in pairs {
            if !taken[t] && owner[b].is_none() {
                taken[t] = true;
                owner[b] = Some(t);
            }
        }
        let mut moving = through.to_vec();
        moving.resize(echoes.len(), false);
        for (blob, owner) in blobs.iter().zip(owner) {
            let t = match owner {
                Some(t) => {
                    self.tracks[t].seen(blob.at, stamp, blob.through);
                    t
                }
                None => {
                    self.tracks.push(Track::born(blob.at, stamp));
                    let t = self.tracks.len() - 1;
                    self.tracks[t].seen(blob.at, stamp, blob.through);
                    t
                }
            };
            if self.tracks[t].mover {
                for &k in &blob.echoes {
                    moving[k] = true;
                }
            }
        }
        moving
    }
}

/// The scan's blobs: runs of echoes of what stands, each within
/// [`JOIN_M`] of the last, a run joined to the next when both fit in
/// [`PERSON_M`] (two legs with the wall seen between them); runs wider
/// than [`PERSON_M`] are left out.
fn blobs(echoes: &[Point2<f64>], standing: &[bool], through: &[bool]) -> Vec<Blob> {
    let off = |k: usize| standing.get(k).copied().unwrap_or(false);
    // Runs of echoes off the walls, each near the last.
    let mut runs: Vec<std::ops::Range<usize>> = Vec::new();
    for k in (0..echoes.len()).filter(|&k| off(k)) {
        match runs.last_mut() {
            Some(r) if r.end == k && (echoes[k] - echoes[k - 1]).norm() <= JOIN_M => r.end = k + 1,
            _ => runs.push(k..k + 1),
        }
    }
    let extent = |r: &std::ops::Range<usize>| {
        let (mut lo, mut hi) = (echoes[r.start], echoes[r.start]);
        for (k, p) in echoes[r.clone()].iter().enumerate() {
            if off(r.start + k) {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        }
        (hi - lo).norm()
    };
    // A run joined to the next across the echoes between (the wall seen
    // between two legs) when their nearest ends are close and both fit.
    let mut joined: Vec<std::ops::Range<usize>> = Vec::new();
    for r in runs {
        match joined.last_mut() {
            Some(j)
                if (echoes[r.start] - echoes[j.end - 1]).norm() <= JOIN_M
                    && extent(&(j.start..r.end)) <= PERSON_M =>
            {
                j.end = r.end
            }
            _ => joined.push(r),
        }
    }
    joined
        .into_iter()
        .filter(|r| extent(r) <= PERSON_M)
        .map(|r| {
            let ks: Vec<usize> = r.clone().filter(|&k| off(k)).collect();
            let n = ks.len() as f64;
            let at = ks
                .iter()
                .fold(Point2::origin(), |a, &k| a + echoes[k].coords / n);
            let through_n = ks
                .iter()
                .filter(|&&k| through.get(k).copied().unwrap_or(false))
                .count();
            let through = 2 * through_n >= ks.len();
            Blob {
                echoes: ks,
                at,
                through,
            }
        })
        .collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A person's two legs (6 cm radius, 20 cm apart) about `at`, seen
    /// from the origin, with the wall behind them at `x = 4`: echoes in
    /// beam order, and which are of something standing (the legs').
    fn legs(at: Point2<f64>) -> (Vec<Point2<f64>>, Vec<bool>) {
        let leg = |dy: f64| Point2::new(at.x, at.y + dy);
        let mut out = Vec::new();
        // Beams every half degree from -60° to 60°.
        for k in 0..=240 {
            let b = (-60.0 + 0.5 * k as f64).to_radians();
            let u = nalgebra::Vector2::new(b.cos(), b.sin());
            let mut best = (4.0 / b.cos(), false);
            for c in [leg(-0.1), leg(0.1)] {
                // Nearest hit of the ray on the leg's circle.
                let along = u.dot(&c.coords);
                let miss = (c.coords - along * u).norm();
                if miss < 0.06 && along > 0.0 {
                    let r = along - (0.06f64.powi(2) - miss * miss).sqrt();
                    if r < best.0 {
                        best = (r, true);
                    }
                }
            }
            out.push((Point2::from(best.0 * u), best.1));
        }
        out.into_iter().unzip()
    }

    fn t(s: f64) -> Stamp {
        Stamp::from_secs_f64(s)
    }

    /// A person walks toward the laser (their echoes where its beams had
    /// just passed), waits 4 s, and turns back: a mover throughout,
    /// standing too. A post stood by is never one, nor a blob seen
    /// through in a row that does not go anywhere.
    #[test]
    fn a_person_who_stops_is_still_a_mover_and_a_post_never_is() {
        let mut m = Movers::default();
        let post = Point2::new(2.0, -1.0);
        let mut at = Point2::new(3.0, 0.3);
        let mut clock = 0.0;
        // A scan of the person at `at` and the post, the person's echoes
        // seen through when `walking`: the person's flags and the post's.
        let mut step = |m: &mut Movers, at: Point2<f64>, walking: bool| {
            let (mut e, mut standing) = legs(at);
            let mut through = if walking {
                standing.clone()
            } else {
                vec![false; e.len()]
            };
            // The post: 3 echoes, grazed through every scan.
            for dy in [-0.02, 0.0, 0.02] {
                e.push(post + nalgebra::Vector2::new(0.0, dy));
                standing.push(true);
                through.push(true);
            }
            clock += 0.125;
            let moving = m.scan(t(clock), &e, &standing, &through);
            let person = e
                .iter()
                .zip(&moving)
                .filter(|(p, _)| (*p - at).norm() < 0.2)
                .map(|(_, m)| *m)
                .collect::<Vec<bool>>();
            let posts = moving[moving.len() - 3..].to_vec();
            (person, posts)
        };
        // Walking 1 m/s toward the laser for 2 s.
        for _ in 0..16 {
            at.x -= 0.125;
            let (person, posts) = step(&mut m, at, true);
            assert!(!person.is_empty());
            let _ = posts;
        }
        let (person, _) = step(&mut m, at, false);
        assert!(person.iter().all(|m| *m), "walked 2 m: a mover");
        // Waiting 4 s.
        for _ in 0..32 {
            let (person, posts) = step(&mut m, at, false);
            assert!(person.iter().all(|m| *m), "waiting: still a mover");
            assert!(posts.iter().all(|m| *m), "the post: only as seen through");
        }
        assert_eq!(m.movers().count(), 1, "the post is no mover");
        // Standing on past REST_S: in the way, no longer a mover.
        for _ in 0..((REST_S - 4.0) / 0.125) as usize + 2 {
            step(&mut m, at, false);
        }
        let (person, _) = step(&mut m, at, false);
        assert!(person.iter().all(|m| !*m), "stood {REST_S} s: mapped");
        assert_eq!(m.len(), 2);
    }

    /// A blob seen through in a row is a mover only once it has gone
    /// somewhere; seen through now and then, never (a thin leg grazed,
    /// and a blob that slides); a blob wider than a person is never
    /// followed.
    #[test]
    fn a_blob_that_goes_somewhere_seen_through_in_a_row_is_a_mover() {
        let mut clock = 0.0;
        let mut scan = |m: &mut Movers, at: Point2<f64>, through: bool| {
            let (e, standing) = legs(at);
            let flags = if through {
                standing.clone()
            } else {
                vec![false; e.len()]
            };
            clock += 0.125;
            let moving = m.scan(t(clock), &e, &standing, &flags);
            moving
                .iter()
                .zip(&standing)
                .any(|(m, s)| *m && *s && !through)
        };
        // Sliding 2 m, seen through every other scan: never a mover.
        let mut m = Movers::default();
        for k in 0..16 {
            let at = Point2::new(3.0 - 0.125 * k as f64, 0.0);
            assert!(!scan(&mut m, at, k % 2 == 0), "scan {k}");
        }
        // Seen through in a row, standing: not a mover; once it has gone
        // a stride, one.
        let mut m = Movers::default();
        for _ in 0..=THROUGH_SCANS {
            scan(&mut m, Point2::new(3.0, 0.0), true);
        }
        assert!(!scan(&mut m, Point2::new(3.0, 0.0), false), "in place");
        for k in 1..=5 {
            scan(&mut m, Point2::new(3.0 - 0.125 * k as f64, 0.0), false);
        }
        assert!(scan(&mut m, Point2::new(3.0 - 0.75, 0.0), false), "gone");
        // A sofa's face, 2 m long, off the walls: no blob.
        let sofa: Vec<Point2<f64>> = (0..100)
            .map(|k| Point2::new(1.0, 0.02 * k as f64))
            .collect();
        let mut far = Movers::default();
        far.scan(t(0.0), &sofa, &[true; 100], &[true; 100]);
        assert!(far.is_empty());
    }

    /// A blob not seen for `LOST_S` is forgotten.
    #[test]
    fn a_blob_out_of_view_is_forgotten() {
        let mut m = Movers::default();
        let (e, standing) = legs(Point2::new(2.0, 0.0));
        m.scan(t(0.0), &e, &standing, &[]);
        assert_eq!(m.len(), 1);
        m.scan(t(LOST_S + 0.1), &[], &[], &[]);
        assert!(m.is_empty());
    }
}
