//! A scan's returns as points in the sensor frame, optionally corrected for
//! the sensor's motion during the sweep.

use nalgebra::Point2;
use stucco_core::{Pose2, Scan, Twist2};

/// One echo of a scan, as a point in the sensor frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPoint {
    /// Position in the sensor frame at the scan's stamp, m.
    pub p: Point2<f64>,
    /// Range as measured, m: the weight of the range-weighted transform.
    pub range_m: f64,
    /// Bearing of `p` in the sensor frame, rad.
    pub bearing_rad: f64,
    /// Index of the beam in its scan.
    pub beam: usize,
}

/// The echoes of one scan as points, ready for line extraction.
///
/// Buffers are reused: refill with [`ScanPoints::fill`] or
/// [`ScanPoints::fill_deskewed`] to extract scan after scan without
/// allocating.
#[derive(Clone, Debug, Default)]
pub struct ScanPoints {
    points: Vec<ScanPoint>,
    angle_increment_rad: f64,
    bearings: Bearings,
}

/// The sines and cosines of a scan's bearings, worked out once for scans
/// of the same geometry (first bearing, step, beams): the same numbers as
/// each beam's own `sin_cos`, without its cost scan after scan.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bearings {
    key: (u64, u64, usize),
    sin_cos: Vec<(f64, f64)>,
}

impl Bearings {
    /// `(sin, cos)` of each of `scan`'s bearings, in beam order.
    pub fn of(&mut self, scan: &Scan) -> &[(f64, f64)] {
        let key = (
            scan.angle_min_rad.to_bits(),
            scan.angle_increment_rad.to_bits(),
            scan.len(),
        );
        if key != self.key || self.sin_cos.len() != scan.len() {
            self.key = key;
            self.sin_cos.clear();
            self.sin_cos
                .extend((0..scan.len()).map(|i| scan.angle(i).sin_cos()));
        }
        &self.sin_cos
    }
}

impl ScanPoints {
    /// The returns of `scan`, as measured.
    pub fn from_scan(scan: &Scan) -> Self {
        let mut pts = ScanPoints::default();
        pts.fill(scan);
        pts
    }

    /// The returns of `scan`, corrected for a sensor moving with constant
    /// body-frame velocity `twist` during the sweep: every point is expressed
    /// in the sensor's frame at the scan's stamp (its first beam).
    pub fn from_scan_deskewed(scan: &Scan, twist: &Twist2) -> Self {
        let mut pts = ScanPoints::default();
        pts.fill_deskewed(scan, twist);
        pts
    }

    /// Refills from `scan`, as measured.
    pub fn fill(&mut self, scan: &Scan) {
        self.points.clear();
        self.angle_increment_rad = scan.angle_increment_rad.abs();
        let sin_cos = self.bearings.of(scan);
        self.points.extend(scan.returns().map(|b| {
            let (s, c) = sin_cos[b.index];
            ScanPoint {
                // As `b.point()` makes it.
                p: Point2::new(b.range_m * c, b.range_m * s),
                range_m: b.range_m,
                bearing_rad: b.angle_rad,
                beam: b.index,
            }
        }));
    }

    /// Refills from `scan`, undoing the distortion of constant-velocity
    /// motion during the sweep (see [`ScanPoints::from_scan_deskewed`]).
    pub fn fill_deskewed(&mut self, scan: &Scan, twist: &Twist2) {
        self.points.clear();
        self.angle_increment_rad = scan.angle_increment_rad.abs();
        let sin_cos = self.bearings.of(scan);
        self.points.extend(scan.returns().map(|b| {
            let at_beam = twist.displacement(scan.beam_time_s(b.index));
            let (s, c) = sin_cos[b.index];
            let p = at_beam.transform_point(&Point2::new(b.range_m * c, b.range_m * s));
            ScanPoint {
                p,
                range_m: b.range_m,
                bearing_rad: p.y.atan2(p.x),
                beam: b.index,
            }
        }));
    }

    /// The same points seen from a sensor moved by `pose`'s inverse: every
    /// point `p` becomes `pose · p`, with its range and bearing recomputed.
    pub fn transformed(&self, pose: &Pose2) -> ScanPoints {
        ScanPoints {
            points: self
                .points
                .iter()
                .map(|q| {
                    let p = pose.transform_point(&q.p);
                    ScanPoint {
                        p,
                        range_m: p.coords.norm(),
                        bearing_rad: p.y.atan2(p.x),
                        beam: q.beam,
                    }
                })
                .collect(),
            angle_increment_rad: self.angle_increment_rad,
            bearings: Bearings::default(),
        }
    }

    /// The points, in sweep order.
    pub fn points(&self) -> &[ScanPoint] {
        &self.points
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the scan had no returns.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Angular step of the scan the points came from, rad.
    pub fn angle_increment_rad(&self) -> f64 {
        self.angle_increment_rad
    }
}
