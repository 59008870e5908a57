//! One sweep of a scanning range-finder.

use crate::{LaserSpec, Stamp};
use nalgebra::Point2;
use serde::{Deserialize, Serialize};

/// A range scan: one range per beam, beams evenly spaced in bearing.
///
/// A beam that saw nothing (no echo, or an echo at or beyond the sensor's
/// maximum range, or below its minimum) holds [`f64::INFINITY`]: "no return"
/// is explicit, never a magic number such as the 81.91 m of a SICK log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scan {
    /// Time of the first beam.
    pub stamp: Stamp,
    /// The sensor it came from (a preset name, or a log's laser id).
    pub sensor: String,
    /// Bearing of the first beam in the sensor frame, rad.
    pub angle_min_rad: f64,
    /// Angular step between beams, rad (negative for clockwise scanners).
    pub angle_increment_rad: f64,
    /// Time from the first beam to the last, s.
    pub sweep_duration_s: f64,
    /// Longest range the sensor reports, m.
    pub max_range_m: f64,
    /// Range of each beam, m; `INFINITY` marks no return (`null` in JSON).
    #[serde(with = "no_return_as_null")]
    pub ranges_m: Vec<f64>,
}

/// JSON has no infinity: no-returns travel as `null`.
pub(crate) mod no_return_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(ranges: &[f64], s: S) -> Result<S::Ok, S::Error> {
        let opt: Vec<Option<f64>> = ranges.iter().map(|r| r.is_finite().then_some(*r)).collect();
        opt.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let opt = Vec::<Option<f64>>::deserialize(d)?;
        Ok(opt
            .into_iter()
            .map(|r| r.unwrap_or(f64::INFINITY))
            .collect())
    }
}

/// One beam that returned an echo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Index of the beam in its scan.
    pub index: usize,
    /// Bearing in the sensor frame, rad.
    pub angle_rad: f64,
    /// Measured range, m.
    pub range_m: f64,
}

impl Beam {
    /// The echo as a point in the sensor frame.
    pub fn point(&self) -> Point2<f64> {
        let (s, c) = self.angle_rad.sin_cos();
        Point2::new(self.range_m * c, self.range_m * s)
    }
}

impl Scan {
    /// A scan from raw ranges. Ranges that are not finite, not positive,
    /// below `min_range_m` or at or beyond `max_range_m` become no-returns.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        stamp: Stamp,
        sensor: impl Into<String>,
        angle_min_rad: f64,
        angle_increment_rad: f64,
        sweep_duration_s: f64,
        min_range_m: f64,
        max_range_m: f64,
        ranges_m: impl IntoIterator<Item = f64>,
    ) -> Self {
        let ranges_m = ranges_m
            .into_iter()
            .map(|r| {
                if r.is_finite() && r > 0.0 && r >= min_range_m && r < max_range_m {
                    r
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        Scan {
            stamp,
            sensor: sensor.into(),
            angle_min_rad,
            angle_increment_rad,
            sweep_duration_s,
            max_range_m,
            ranges_m,
        }
    }

    /// A scan laid out as `spec` sweeps it.
    pub fn from_spec(
        spec: &LaserSpec,
        stamp: Stamp,
        ranges_m: impl IntoIterator<Item = f64>,
    ) -> Self {
        Self::new(
            stamp,
            spec.name.clone(),
            spec.angle_min_rad,
            spec.increment_rad,
            spec.sweep_duration_s(),
            spec.min_range_m,
            spec.max_range_m,
            ranges_m,
        )
    }

    /// Number of beams, returns or not.
    pub fn len(&self) -> usize {
        self.ranges_m.len()
    }

    /// True when the scan has no beams at all.
    pub fn is_empty(&self) -> bool {
        self.ranges_m.is_empty()
    }

    /// Bearing of beam `i`, rad.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min_rad + i as f64 * self.angle_increment_rad
    }

    /// True when beam `i` saw an echo.
    pub fn is_return(&self, i: usize) -> bool {
        self.ranges_m.get(i).is_some_and(|r| r.is_finite())
    }

    /// Time of beam `i` relative to the scan's stamp, s.
    pub fn beam_time_s(&self, i: usize) -> f64 {
        match self.ranges_m.len() {
            0 | 1 => 0.0,
            n => self.sweep_duration_s * i as f64 / (n - 1) as f64,
        }
    }

    /// The beams that returned an echo, in sweep order.
    pub fn returns(&self) -> impl Iterator<Item = Beam> + '_ {
        self.ranges_m
            .iter()
            .enumerate()
            .filter(|(_, r)| r.is_finite())
            .map(|(index, &range_m)| Beam {
                index,
                angle_rad: self.angle(index),
                range_m,
            })
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_readings_become_no_returns() {
        let scan = Scan::new(
            Stamp::ZERO,
            "t",
            -1.0,
            0.5,
            0.1,
            0.1,
            10.0,
            [1.0, 0.05, 10.0, f64::NAN, -2.0, 9.99],
        );
        let kept: Vec<usize> = scan.returns().map(|b| b.index).collect();
        assert_eq!(kept, vec![0, 5]);
        assert!(!scan.is_return(2));
        assert!(!scan.is_return(99));
        assert_eq!(scan.beam_time_s(5), 0.1);
        let p = scan.returns().next().map(|b| b.point()).unwrap_or_default();
        assert!((p.x - 1.0f64.cos()).abs() < 1e-12 && (p.y + 1.0f64.sin()).abs() < 1e-12);
    }

    #[test]
    fn serde_keeps_no_returns() {
        let scan = Scan::new(
            Stamp::from_nanos(5),
            "t",
            0.0,
            0.1,
            0.0,
            0.0,
            5.0,
            [1.0, 7.0],
        );
        let json = serde_json::to_string(&scan).expect("serialize");
        assert!(json.contains("[1.0,null]"), "{json}");
        let back: Scan = serde_json::from_str(&json).expect("deserialize");
        assert_eq!(back, scan);
    }
}
