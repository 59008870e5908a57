//! Windows found in the profiles of a range camera looking at a wall while
//! the robot drives along it.
//!
//! Each profile is a vertical fan of rays in a plane across the wall. A ray
//! that meets the wall's face is on the wall; one that goes through it (no
//! echo, or an echo well behind the face) crosses a hole at the height where
//! it passes the face. A run of such rays in one profile is a gap in the
//! wall at that position along it; gaps in consecutive profiles that
//! overlap in height are one window. Its sill and head lie between the last
//! ray on the wall and the first through the hole — exactly where a ray
//! meets the sill's top or the lintel's underside inside the wall's
//! thickness — and its left and right edges halfway between the last
//! profile on the wall and the first through the hole, each as uncertain
//! as the two profiles are far apart. Windows seen on several passes are
//! fused, each edge weighed by how tightly its profiles bracketed it: a
//! pass swept fast (the robot turning on the spot) counts for little
//! beside one driven slowly past the edge.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use stucco_core::RangeProfile;

/// Settings of the window finder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindowConfig {
    /// An echo within this of the wall's face lies on it, m.
    pub face_tolerance_m: f64,
    /// Echoes this far behind the face are the opening's reveal (the
    /// sill's top, the lintel's underside), m.
    pub reveal_depth_m: f64,
    /// Smallest window reported, m (width and height).
    pub min_size_m: f64,
    /// Profiles meeting the wall more obliquely than this are not used
    /// (cosine of the angle between the fan's plane and the wall's normal).
    pub min_incidence_cos: f64,
}

impl Default for WindowConfig {
    fn default() -> Self {
        WindowConfig {
            face_tolerance_m: 0.04,
            reveal_depth_m: 0.35,
            min_size_m: 0.4,
            min_incidence_cos: 0.9,
        }
    }
}

/// Where the camera was for one profile, in the frame of the wall: its
/// position along the wall, its distance from the face, the height of the
/// sensor, and the fan's horizontal direction relative to the wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfilePose {
    /// Position along the wall of the sensor, m.
    pub along_m: f64,
    /// Distance of the sensor from the face, m (positive in the room).
    pub distance_m: f64,
    /// Height of the sensor above the floor, m.
    pub height_m: f64,
    /// The fan's horizontal direction as (toward the wall, along the
    /// wall) components: `(1, 0)` looks straight at it.
    pub direction: Vector2<f64>,
}

/// A window in a wall: its edges along the wall and its sill and head.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Window {
    /// Left and right edges along the wall (increasing), m.
    pub along_m: [f64; 2],
    /// Sill and head heights, m.
    pub sill_head_m: [f64; 2],
    /// Passes (tracks) fused into it.
    pub observations: usize,
    /// Standard deviation of each edge along the wall, m: the spacing of
    /// the profiles either side of it (the edge lies anywhere between
    /// them), with the camera's own position error; fused passes narrow
    /// it.
    #[serde(default = "unknown_edge_sigma")]
    pub along_sigma_m: [f64; 2],
}

/// Edge spread of a window kept without one (a checkpoint written before
/// edges carried theirs): a profile step of a slow pass.
fn unknown_edge_sigma() -> [f64; 2] {
    [EDGE_SIGMA_FLOOR_M * 2.0; 2]
}

/// The least standard deviation of an edge, m: the camera's position
/// error along the wall, however close its profiles fall.
const EDGE_SIGMA_FLOOR_M: f64 = 0.005;

/// Standard deviation of an edge lying anywhere between two profiles
/// `spacing_m` apart (uniform over it), with the camera's position error.
fn edge_sigma(spacing_m: f64) -> f64 {
    (spacing_m * spacing_m / 12.0 + EDGE_SIGMA_FLOOR_M * EDGE_SIGMA_FLOOR_M).sqrt()
}

impl Window {
    /// Width, m.
    pub fn width_m(&self) -> f64 {
        self.along_m[1] - self.along_m[0]
    }

    /// Height, m.
    pub fn height_m(&self) -> f64 {
        self.sill_head_m[1] - self.sill_head_m[0]
    }

    /// Takes `other`'s edges along the wall in, each weighed by the
    /// inverse of its variance, and its passes; sill and head stay.
    pub fn fuse_edges(&mut self, other: &Window) {
        for k in 0..2 {
            self.fuse_edge(k, other.along_m[k], other.along_sigma_m[k]);
        }
        self.observations += other.observations;
    }

    /// Takes edge `k` seen at `along_m`, `sigma_m` uncertain, into this
    /// window's, each weighed by the inverse of its variance.
    fn fuse_edge(&mut self, k: usize, along_m: f64, sigma_m: f64) {
        let (a, b) = (self.along_sigma_m[k].powi(-2), sigma_m.powi(-2));
        self.along_m[k] = (a * self.along_m[k] + b * along_m) / (a + b);
        self.along_sigma_m[k] = (a + b).sqrt().recip();
    }

    /// True when the two share more than a border: one window seen twice.
    pub fn overlaps(&self, other: &Window) -> bool {
        self.along_m[0] < other.along_m[1]
            && other.along_m[0] < self.along_m[1]
            && self.sill_head_m[0] < other.sill_head_m[1]
            && other.sill_head_m[0] < self.sill_head_m[1]
    }
}

/// One profile's gap: where along the wall, and from which height to which.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Gap {
    along_m: f64,
    z: [f64; 2],
}

/// Least distance along the wall between two profiles a pass takes in, m:
/// a tenth of the 2.5 cm between profiles of a look (the tool's camera,
/// 20 a second, at 0.5 m/s), while the camera on a robot standing still
/// looks at the same place over and over.
const MIN_STEP_M: f64 = 0.0025;

/// A window being followed from profile to profile.
#[derive(Clone, Debug)]
struct Track {
    /// Where the last profile on the wall before it was, if any.
    before_m: Option<f64>,
    gaps: Vec<Gap>,
    /// Profiles since the last gap.
    missed: usize,
}

/// Finds windows in one wall from the profiles of a pass along it.
#[derive(Clone, Debug, Default)]
pub struct WindowFinder {
    config: WindowConfig,
    tracks: Vec<Track>,
    /// Where the last profile met the wall.
    last_along_m: Option<f64>,
    /// The last profile's rays: the height each passed the face at, and
    /// whether it met the face there.
    last_rays: Vec<(f64, bool)>,
    found: Vec<Window>,
}

impl WindowFinder {
    /// A finder with `config`.
    pub fn new(config: WindowConfig) -> Self {
        WindowFinder {
            config,
            ..WindowFinder::default()
        }
    }

    /// Takes one profile shot from `pose`.
    pub fn add(&mut self, profile: &RangeProfile, pose: &ProfilePose) {
        let cfg = self.config.clone();
        let cfg = &cfg;
        let c = pose.direction.x;
        if c < cfg.min_incidence_cos || pose.distance_m <= 0.0 {
            return;
        }
        // Horizontal distance to the face along the fan, and where along
        // the wall the fan meets it.
        let to_face = pose.distance_m / c;
        let along = pose.along_m + pose.direction.y * to_face;
        // A camera standing still sees nothing new, and a stray profile
        // among its many alike must not end a window where it stands.
        if self
            .last_along_m
            .is_some_and(|last| (along - last).abs() < MIN_STEP_M)
        {
            return;
        }
        let (gaps, rays) = gaps_in(profile, pose, to_face, cfg);
        // Continue the tracks whose heights a gap overlaps; start new ones.
        let mut used = vec![false; gaps.len()];
        for t in &mut self.tracks {
            let Some(last) = t.gaps.last().copied() else {
                continue;
            };
            match gaps
                .iter()
                .enumerate()
                .find(|(i, g)| !used[*i] && g.z[0] < last.z[1] && last.z[0] < g.z[1])
            {
                Some((i, g)) => {
                    used[i] = true;
                    t.gaps.push(*g);
                    t.missed = 0;
                }
                None => t.missed += 1,
            }
        }
        // An edge is where the wall is seen beside the hole: a profile
        // before it (or after it) that did not meet the face at the hole's
        // heights (furniture in front) leaves that edge unknown.
        for (g, _) in gaps.iter().zip(&used).filter(|(_, u)| !**u) {
            self.tracks.push(Track {
                before_m: self.last_along_m.filter(|_| on_face(&self.last_rays, g.z)),
                gaps: vec![*g],
                missed: 0,
            });
        }
        // A track missed by this profile ends at it.
        let (done, open): (Vec<_>, Vec<_>) = std::mem::take(&mut self.tracks)
            .into_iter()
            .partition(|t| t.missed > 0);
        self.tracks = open;
        for t in done {
            let after = t
                .gaps
                .last()
                .is_some_and(|g| on_face(&rays, g.z))
                .then_some(along);
            if let Some(w) = close(&t, after, cfg) {
                self.fuse(w);
            } else {
                for e in edges_alone(&t, after) {
                    self.refine(e);
                }
            }
        }
        self.last_along_m = Some(along);
        self.last_rays = rays;
    }

    /// Ends the pass: tracks still open have no far edge (the window was
    /// not seen whole); the edge each crossed, if any, narrows that edge
    /// of a window found before.
    pub fn end_pass(&mut self) {
        for t in std::mem::take(&mut self.tracks) {
            for e in edges_alone(&t, None) {
                self.refine(e);
            }
        }
        self.last_along_m = None;
        self.last_rays.clear();
    }

    /// Where along the wall the last profile of the pass under way met
    /// it, if one is under way.
    pub fn last_along_m(&self) -> Option<f64> {
        self.last_along_m
    }

    /// Windows of the pass under way seen from one edge on, their far
    /// edge not yet reached: each as far as the hole has been seen (the
    /// least it is), for keeping plaster out of it before it is seen whole.
    pub fn seen_in_part(&self) -> Vec<Window> {
        self.tracks
            .iter()
            .filter(|t| t.gaps.len() >= 2)
            .filter_map(|t| {
                let last = *t.gaps.last()?;
                close(
                    t,
                    Some(last.along_m),
                    &WindowConfig {
                        min_size_m: 0.0,
                        ..self.config.clone()
                    },
                )
            })
            .filter(|w| w.height_m() >= self.config.min_size_m)
            .collect()
    }

    /// The windows found so far.
    pub fn windows(&self) -> &[Window] {
        &self.found
    }

    /// Takes `w` as found before (a window a checkpoint kept): later
    /// passes over it are fused in, its edges by their spread and its sill
    /// and head by its observations.
    pub fn know(&mut self, w: Window) {
        self.fuse(w);
    }

    /// Takes in one edge seen on its own, when it is an edge of a window
    /// found before: of one at its heights whose edge on that side lies
    /// within [`EDGE_GATE_SIGMAS`] of it, fused by their spreads. Alone, an
    /// edge says nothing of where the window ends, and is dropped.
    fn refine(&mut self, e: EdgeSighting) {
        let k = usize::from(e.far);
        let known = self.found.iter_mut().find(|w| {
            w.sill_head_m[0] < e.z[1]
                && e.z[0] < w.sill_head_m[1]
                && (w.along_m[k] - e.along_m).abs()
                    <= EDGE_GATE_SIGMAS * w.along_sigma_m[k].hypot(e.sigma_m)
        });
        if let Some(w) = known {
            w.fuse_edge(k, e.along_m, e.sigma_m);
        }
    }

    /// Adds `w`, fused with a window found before in the same place: its
    /// edges by their spread, its sill and head by passes.
    fn fuse(&mut self, w: Window) {
        let same = self.found.iter_mut().find(|f| f.overlaps(&w));
        match same {
            Some(f) => {
                let (n, m) = (f.observations as f64, w.observations as f64);
                let mix = |a: f64, b: f64| (a * n + b * m) / (n + m);
                f.sill_head_m = [
                    mix(f.sill_head_m[0], w.sill_head_m[0]),
                    mix(f.sill_head_m[1], w.sill_head_m[1]),
                ];
                f.fuse_edges(&w);
            }
            None => self.found.push(w),
        }
    }
}

/// One edge of a window seen without the other: a pass that crossed it and
/// ended in the hole, or began there (a slow look across an edge the
/// survey bracketed only loosely).
#[derive(Clone, Copy, Debug, PartialEq)]
struct EdgeSighting {
    /// Where along the wall, m: halfway between the profiles either side.
    along_m: f64,
    /// Its standard deviation, m (see [`edge_sigma`]).
    sigma_m: f64,
    /// True for the window's far edge (the greater along the wall).
    far: bool,
    /// The hole's sill and head as seen, m.
    z: [f64; 2],
}

/// The edges a pass crossed without seeing the window whole: into the
/// hole from the wall with no wall after it, or out of it with none
/// before, or into it and back out the same side (a look that turned
/// back). The hole must have been seen in two profiles or more.
fn edges_alone(t: &Track, after_m: Option<f64>) -> Vec<EdgeSighting> {
    let (Some(first), Some(last)) = (t.gaps.first(), t.gaps.last()) else {
        return Vec::new();
    };
    if t.gaps.len() < 2 {
        return Vec::new();
    }
    let mut z0: Vec<f64> = t.gaps.iter().map(|g| g.z[0]).collect();
    let mut z1: Vec<f64> = t.gaps.iter().map(|g| g.z[1]).collect();
    z0.sort_by(f64::total_cmp);
    z1.sort_by(f64::total_cmp);
    let z = [z0[z0.len() / 2], z1[z1.len() / 2]];
    let sighting = |wall: f64, hole: f64| EdgeSighting {
        along_m: 0.5 * (wall + hole),
        sigma_m: edge_sigma((hole - wall).abs()),
        far: wall > hole,
        z,
    };
    match (t.before_m, after_m) {
        (Some(b), None) => vec![sighting(b, first.along_m)],
        (None, Some(a)) => vec![sighting(a, last.along_m)],
        // Wall on the same side going in and coming out: one edge twice.
        (Some(b), Some(a)) if (first.along_m - b).signum() == (last.along_m - a).signum() => {
            vec![sighting(b, first.along_m), sighting(a, last.along_m)]
        }
        _ => Vec::new(),
    }
}

/// How far an edge seen alone may lie from a known window's edge on its
/// side, in their combined standard deviations, to be taken for it.
const EDGE_GATE_SIGMAS: f64 = 3.0;

/// The window of a finished track: edges halfway between the profiles on
/// either side of it, sill and head the medians of its gaps'.
fn close(t: &Track, after_m: Option<f64>, cfg: &WindowConfig) -> Option<Window> {
    let (first, last) = (t.gaps.first()?, t.gaps.last()?);
    let before = t.before_m?;
    let after = after_m?;
    let a = 0.5 * (before + first.along_m);
    let b = 0.5 * (last.along_m + after);
    let (lo, hi) = (a.min(b), a.max(b));
    let median = |f: &dyn Fn(&Gap) -> f64| {
        let mut v: Vec<f64> = t.gaps.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let spread = [
        edge_sigma((first.along_m - before).abs()),
        edge_sigma((after - last.along_m).abs()),
    ];
    let w = Window {
        along_m: [lo, hi],
        sill_head_m: [median(&|g| g.z[0]), median(&|g| g.z[1])],
        observations: 1,
        along_sigma_m: if a <= b {
            spread
        } else {
            [spread[1], spread[0]]
        },
    };
    (w.width_m() >= cfg.min_size_m && w.height_m() >= cfg.min_size_m).then_some(w)
}

/// True when most of a profile's rays that pass the face between the
/// heights `z` met it there.
fn on_face(rays: &[(f64, bool)], z: [f64; 2]) -> bool {
    let (mut n, mut face) = (0, 0);
    for &(_, on) in rays.iter().filter(|(zf, _)| (z[0]..=z[1]).contains(zf)) {
        n += 1;
        face += usize::from(on);
    }
    n > 0 && face as f64 >= ON_FACE_SHARE * n as f64
}

/// Two echoes this near in height lie on one level surface (the camera's
/// range noise along a slant ray), m.
const LEVEL_M: f64 = 0.025;

/// Share of the rays at a hole's heights that must meet the face beside
/// it for that side to be its edge.
const ON_FACE_SHARE: f64 = 0.8;

/// The gaps of one profile: runs of rays through the face, each bounded
/// by rays on it; and each ray's height at the face with whether it met
/// the face there.
fn gaps_in(
    profile: &RangeProfile,
    pose: &ProfilePose,
    to_face: f64,
    cfg: &WindowConfig,
) -> (Vec<Gap>, Vec<(f64, bool)>) {
    #[derive(Clone, Copy, PartialEq)]
    enum Ray {
        Face,
        Through,
        Front,
    }
    let c = pose.direction.x;
    let mut kinds = Vec::with_capacity(profile.ranges_m.len());
    let mut face_z = Vec::with_capacity(profile.ranges_m.len());
    let mut hit_z = Vec::with_capacity(profile.ranges_m.len());
    for (&e, &r) in profile.elevations_rad.iter().zip(&profile.ranges_m) {
        let (s, cos_e) = e.sin_cos();
        // Height where the ray passes the face.
        let zf = if cos_e > 1e-6 {
            pose.height_m + to_face * s / cos_e
        } else {
            f64::INFINITY
        };
        face_z.push(zf);
        // Depth of the echo behind the face (along the wall's normal).
        let depth = if r.is_finite() {
            (r * cos_e - to_face) * c
        } else {
            f64::INFINITY
        };
        hit_z.push(if r.is_finite() {
            pose.height_m + r * s
        } else {
            f64::NAN
        });
        kinds.push(if depth.abs() <= cfg.face_tolerance_m {
            Ray::Face
        } else if depth < 0.0 {
            Ray::Front
        } else {
            Ray::Through
        });
    }
    let mut out = Vec::new();
    let mut i = 0;
    while i < kinds.len() {
        if kinds[i] != Ray::Through {
            i += 1;
            continue;
        }
        let start = i;
        while i < kinds.len() && kinds[i] == Ray::Through {
            i += 1;
        }
        // Bounded by the face above; below, by the face, or by nothing
        // when the hole reaches under the fan's lowest ray (a door: its
        // bottom is the floor).
        if i >= kinds.len() || kinds[i] != Ray::Face {
            continue;
        }
        let door = start == 0 && face_z[0] > 0.0;
        if !door && kinds[start - 1] != Ray::Face {
            continue;
        }
        // Each edge lies between its face ray and its first through ray.
        // Rays that pass the face just inside the hole go on to meet the
        // sill's top or the lintel's underside within the wall's thickness:
        // two of them echoing at one height and apart in depth (a
        // horizontal surface; not the glass of a glazed window, which
        // echoes at one depth, its heights the rays' spacing apart) mark
        // the edge exactly. The ray taken for the face may be one of them:
        // met within the face's tolerance of it (a step the camera's noise
        // hides), taken for the face it put the edge that far into the
        // hole at its slant (a head 2 cm low).
        let depth =
            |k: usize| (profile.ranges_m[k] * profile.elevations_rad[k].cos() - to_face) * c;
        let reveal = |k: usize| {
            let d = depth(k);
            d > cfg.face_tolerance_m && d <= cfg.reveal_depth_m
        };
        let level = |a: usize, b: usize| {
            let dz = (hit_z[a] - hit_z[b]).abs();
            dz <= LEVEL_M && (depth(a) - depth(b)).abs() > dz
        };
        let edge = |face: usize, through: usize, next: Option<usize>| {
            if let Some(n) = next
                && reveal(through)
                && reveal(n)
                && level(through, n)
            {
                0.5 * (hit_z[through] + hit_z[n])
            } else if reveal(through) && level(face, through) {
                0.5 * (hit_z[face] + hit_z[through])
            } else {
                0.5 * (face_z[face] + face_z[through])
            }
        };
        let inner = |k: usize, toward: isize| {
            let n = k as isize + toward;
            (n >= start as isize && n < i as isize).then_some(n as usize)
        };
        let z0 = if door {
            0.0
        } else {
            edge(start - 1, start, inner(start, 1))
        };
        let z1 = edge(i, i - 1, inner(i - 1, -1));
        out.push(Gap {
            along_m: 0.0,
            z: [z0.min(z1), z0.max(z1)],
        });
    }
    let along = pose.along_m + pose.direction.y * to_face;
    for g in &mut out {
        g.along_m = along;
    }
    let rays = face_z
        .iter()
        .zip(&kinds)
        .map(|(&z, &k)| (z, k == Ray::Face))
        .collect();
    (out, rays)
}

#[cfg(test)]
mod tests {
    use super::*;
    use stucco_core::Stamp;

    /// A wall at x = 0 with a window `[u0, u1] × [sill, head]` in it, 0.15 m
    /// thick; a camera at `distance` in front of it at `along`, 1 m high,
    /// looking straight at it.
    fn profile(along: f64, distance: f64, window: [f64; 4]) -> RangeProfile {
        let [u0, u1, sill, head] = window;
        let elevations: Vec<f64> = (0..96).map(|i| -0.6 + 2.17 * i as f64 / 95.0).collect();
        let ranges = elevations
            .iter()
            .map(|&e| {
                let (s, c) = e.sin_cos();
                if c < 1e-9 {
                    return f64::INFINITY;
                }
                let r_face = distance / c;
                let z = 1.0 + r_face * s;
                let inside = (u0..=u1).contains(&along) && z > sill && z < head;
                if !inside {
                    return r_face;
                }
                // Through the hole: the sill's top or the lintel's underside
                // within the wall's thickness, else nothing.
                let plane = if s < 0.0 { sill } else { head };
                let r_plane = (plane - 1.0) / s;
                if s.abs() > 1e-9 && r_plane * c <= distance + 0.15 {
                    r_plane
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        RangeProfile {
            stamp: Stamp::ZERO,
            sensor: "cam".into(),
            origin_m: [0.0, 0.0, 1.0],
            azimuth_rad: 0.0,
            elevations_rad: elevations,
            ranges_m: ranges,
        }
    }

    /// [`profile`] of a glazed window, its glass halfway into the wall
    /// returning the rays that meet it within 25° of square on.
    fn glazed(along: f64, distance: f64, window: [f64; 4]) -> RangeProfile {
        let mut p = profile(along, distance, window);
        let glass = distance + 0.075;
        for (r, &e) in p.ranges_m.iter_mut().zip(&p.elevations_rad) {
            let (s, c) = e.sin_cos();
            let z = 1.0 + glass * s / c;
            let through = (window[0]..=window[1]).contains(&along)
                && (window[2]..window[3]).contains(&(1.0 + distance * s / c));
            if through && c >= 0.9 && (window[2]..window[3]).contains(&z) {
                *r = glass / c;
            }
        }
        p
    }

    fn pose(along: f64, distance: f64) -> ProfilePose {
        ProfilePose {
            along_m: along,
            distance_m: distance,
            height_m: 1.0,
            direction: Vector2::new(1.0, 0.0),
        }
    }

    #[test]
    fn a_window_seen_from_one_edge_is_known_in_part_until_it_is_seen_whole() {
        // A look that ends inside the window (a station's reach), and the
        // next one going on from there past its far edge.
        let window = [0.9, 1.9, 1.0, 2.1];
        let mut f = WindowFinder::new(WindowConfig::default());
        let step = 0.025;
        let look = |f: &mut WindowFinder, from: f64, to: f64| {
            let n = ((to - from) / step).round() as usize;
            for k in 0..=n {
                let u = from + step * k as f64;
                f.add(&profile(u, 0.3, window), &pose(u, 0.3));
            }
        };
        look(&mut f, 0.75, 1.85);
        assert!(f.windows().is_empty());
        let part = f.seen_in_part();
        assert_eq!(part.len(), 1, "{part:?}");
        assert!(
            (part[0].along_m[0] - 0.9).abs() <= step / 2.0 + 1e-9,
            "{part:?}"
        );
        assert!((part[0].along_m[1] - 1.85).abs() < 1e-9, "{part:?}");
        look(&mut f, 1.7, 2.2);
        assert!(f.seen_in_part().is_empty());
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        for (got, want) in w[0].along_m.iter().zip(&window[..2]) {
            assert!((got - want).abs() <= step / 2.0 + 1e-9, "{w:?}");
        }
    }

    #[test]
    fn furniture_before_part_of_a_window_leaves_no_edge_where_it_stands() {
        // A window 1.0-2.2 m along; a wardrobe 0.3 m before the camera,
        // 1.6-1.8 m along, hides the wall up to 1.5 m there. The window's
        // hole is cut by it, but its ends are not the window's edges.
        let window = [1.0, 2.2, 0.9, 2.1];
        let mut f = WindowFinder::new(WindowConfig::default());
        let step = 0.02;
        for k in 0..100 {
            let u = 0.5 + step * k as f64;
            let mut p = profile(u, 0.6, window);
            if (1.6..=1.8).contains(&u) {
                for (r, e) in p.ranges_m.iter_mut().zip(&p.elevations_rad) {
                    let z = 1.0 + 0.3 * e.tan();
                    if z < 1.5 {
                        *r = 0.3 / e.cos();
                    }
                }
            }
            f.add(&p, &pose(u, 0.6));
        }
        let w = f.windows();
        for x in w {
            for e in x.along_m {
                assert!((e - 1.6).abs() > 0.05 && (e - 1.8).abs() > 0.05, "{w:?}");
            }
        }
    }

    #[test]
    fn a_window_is_found_with_its_edges_within_a_profile_step() {
        let window = [1.83, 3.21, 0.9, 2.1];
        let mut f = WindowFinder::new(WindowConfig::default());
        let step = 0.02;
        for k in 0..250 {
            let u = 0.5 + step * k as f64;
            f.add(&profile(u, 0.6, window), &pose(u, 0.6));
        }
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        let w = w[0];
        assert!(
            (w.along_m[0] - window[0]).abs() <= step / 2.0 + 1e-9,
            "{w:?}"
        );
        assert!(
            (w.along_m[1] - window[1]).abs() <= step / 2.0 + 1e-9,
            "{w:?}"
        );
        // The head where two rays met the lintel's underside: exact (the
        // rays are 5.8 cm apart there). Fewer rays reach the sill's top
        // (the shallow rays meet it deep in the wall): within half their
        // spacing, 1.4 cm.
        assert!((w.sill_head_m[1] - 2.1).abs() < 1e-9, "{w:?}");
        assert!((w.sill_head_m[0] - 0.9).abs() <= 0.007, "{w:?}");
    }

    #[test]
    fn the_head_is_where_rays_meet_the_lintel_not_the_glass_nor_the_face() {
        // From close up under a glazed window's head: a ray meets the
        // lintel's underside 3.2 cm behind the face (within the face's
        // tolerance: taken for the face, it put the head 1.9 cm low), the
        // next 7.2 cm behind it at the same height; below them the rays
        // meet the glass square on, at one depth, 1.3 cm apart in height.
        let window = [1.0, 2.0, 0.7, 1.2];
        let mut f = WindowFinder::new(WindowConfig::default());
        for k in 0..150 {
            let u = 0.5 + 0.02 * k as f64;
            f.add(&glazed(u, 0.5, window), &pose(u, 0.5));
        }
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        // Half the rays' spacing at the face there.
        assert!((w[0].sill_head_m[1] - 1.2).abs() <= 0.0075, "{w:?}");
    }

    #[test]
    fn a_camera_standing_still_in_front_of_a_window_does_not_end_it_there() {
        // A robot stops in front of a window for a minute (a ceiling pass)
        // and one of its 1,200 profiles misses the hole (its sill
        // flickers), then it drives on past the window's far edge.
        let window = [1.8, 3.2, 0.9, 2.1];
        let mut f = WindowFinder::new(WindowConfig::default());
        let step = 0.025;
        let mut u = 1.5;
        while u < 2.8 {
            f.add(&profile(u, 0.7, window), &pose(u, 0.7));
            u += step;
        }
        for k in 0..1200 {
            let seen = if k == 600 { [0.0; 4] } else { window };
            f.add(&profile(u, 0.7, seen), &pose(u, 0.7));
        }
        while u < 3.5 {
            f.add(&profile(u, 0.7, window), &pose(u, 0.7));
            u += step;
        }
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        for (got, want) in w[0].along_m.iter().zip(&window[..2]) {
            assert!((got - want).abs() <= step / 2.0 + 1e-9, "{w:?}");
        }
    }

    #[test]
    fn small_holes_and_half_seen_windows_are_not_reported() {
        let mut f = WindowFinder::new(WindowConfig::default());
        for k in 0..100 {
            let u = 0.5 + 0.02 * k as f64;
            f.add(&profile(u, 0.6, [1.0, 1.3, 1.0, 1.5]), &pose(u, 0.6));
        }
        assert!(f.windows().is_empty(), "{:?}", f.windows());
        // A pass that ends inside a window: not seen whole.
        let mut f = WindowFinder::new(WindowConfig::default());
        for k in 0..60 {
            let u = 0.5 + 0.02 * k as f64;
            f.add(&profile(u, 0.6, [1.0, 2.5, 1.0, 1.9]), &pose(u, 0.6));
        }
        f.end_pass();
        assert!(f.windows().is_empty());
    }

    #[test]
    fn a_pass_swept_fast_counts_for_little_beside_a_slow_one() {
        let window = [1.0, 2.0, 0.8, 1.9];
        let mut f = WindowFinder::new(WindowConfig::default());
        // Profiles 15 cm apart (the robot turning on the spot): the left
        // edge lies between 0.88 and 1.03, taken as 0.955.
        for k in 0..14 {
            let u = 0.43 + 0.15 * k as f64;
            f.add(&profile(u, 0.7, window), &pose(u, 0.7));
        }
        f.end_pass();
        assert!((f.windows()[0].along_m[0] - 0.955).abs() < 1e-9);
        // 2.5 cm apart (driven past at half a metre a second).
        for k in 0..80 {
            let u = 0.41 + 0.025 * k as f64;
            f.add(&profile(u, 0.7, window), &pose(u, 0.7));
        }
        f.end_pass();
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].observations, 2);
        // Averaged pass for pass, the left edge would be 2.4 cm off.
        for (edge, truth) in w[0].along_m.iter().zip([1.0, 2.0]) {
            assert!((edge - truth).abs() < 0.005, "{w:?}");
        }
        assert!(w[0].along_sigma_m.iter().all(|&s| s < 0.009), "{w:?}");
    }

    #[test]
    fn a_window_kept_before_edges_carried_their_spread_is_read_as_one_slow_pass() {
        let w: Window = serde_json::from_str(
            r#"{"along_m": [1.0, 2.0], "sill_head_m": [0.9, 2.1], "observations": 3}"#,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(w.along_sigma_m, unknown_edge_sigma());
        let mut f = WindowFinder::new(WindowConfig::default());
        f.know(w);
        assert_eq!(f.windows()[0].along_m, [1.0, 2.0]);
    }

    #[test]
    fn a_look_across_one_edge_of_a_known_window_narrows_that_edge() {
        let window = [1.0, 2.0, 0.8, 1.9];
        let look = |f: &mut WindowFinder, from: f64, step: f64, n: usize| {
            for k in 0..n {
                let u = from + step * k as f64;
                f.add(&profile(u, 0.7, window), &pose(u, 0.7));
            }
            f.end_pass();
        };
        // Swept fast (profiles 15 cm apart): edges at 0.955 and 2.005,
        // each 4.4 cm uncertain.
        let mut f = WindowFinder::new(WindowConfig::default());
        look(&mut f, 0.43, 0.15, 14);
        let swept = f.windows()[0];
        assert!((swept.along_m[1] - 2.005).abs() < 1e-9, "{swept:?}");
        // Looks inside the hole only, toward the near edge: no wall seen,
        // nothing changed.
        look(&mut f, 1.905, -0.01, 20);
        assert_eq!(f.windows()[0], swept);
        // Slow looks, profiles 1 cm apart: from inside the hole out past
        // its far edge, and from the wall across its near edge into it.
        look(&mut f, 1.905, 0.01, 20);
        look(&mut f, 0.905, 0.01, 20);
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].observations, 1, "{w:?}");
        for (k, truth) in [1.0, 2.0].into_iter().enumerate() {
            assert!((w[0].along_m[k] - truth).abs() < 0.006, "{w:?}");
            assert!(w[0].along_sigma_m[k] < 0.006, "{w:?}");
        }
        assert_eq!(w[0].sill_head_m, swept.sill_head_m);
        // A look that turns back: from the wall into the hole across the
        // far edge, and out again the same way, in one pass.
        let mut f = WindowFinder::new(WindowConfig::default());
        look(&mut f, 0.43, 0.15, 14);
        for k in (0..12).chain((0..12).rev()) {
            let u = 2.055 - 0.01 * k as f64;
            f.add(&profile(u, 0.7, window), &pose(u, 0.7));
        }
        f.end_pass();
        let w = f.windows()[0];
        assert!((w.along_m[1] - 2.0).abs() < 0.006, "{w:?}");
        assert!(w.along_sigma_m[1] < 0.005, "{w:?}");
        // Where no window is known, an edge alone finds none.
        let mut g = WindowFinder::new(WindowConfig::default());
        look(&mut g, 1.905, 0.01, 20);
        look(&mut g, 0.905, 0.01, 20);
        assert!(g.windows().is_empty(), "{:?}", g.windows());
    }

    #[test]
    fn two_passes_are_fused() {
        let window = [1.0, 2.0, 0.8, 1.9];
        let mut f = WindowFinder::new(WindowConfig::default());
        for pass in 0..2 {
            for k in 0..80 {
                let u = if pass == 0 {
                    0.4 + 0.025 * k as f64
                } else {
                    2.4 - 0.025 * k as f64
                };
                f.add(&profile(u, 0.7, window), &pose(u, 0.7));
            }
            f.end_pass();
        }
        let w = f.windows();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].observations, 2);
        assert!(
            (w[0].along_m[0] - 1.0).abs() < 0.0125 + 1e-9
                && (w[0].along_m[1] - 2.0).abs() < 0.0125 + 1e-9
        );
    }
}
