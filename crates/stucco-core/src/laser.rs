//! Scanning range-finder models and the presets of the source papers.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Width of the laser footprint at range `R`: `base_m + per_m * R`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamWidth {
    /// Footprint diameter at the exit window, m.
    pub base_m: f64,
    /// Growth of the footprint per metre of range (full divergence, rad).
    pub per_m: f64,
}

impl BeamWidth {
    /// Footprint diameter at `range_m`.
    pub fn at(&self, range_m: f64) -> f64 {
        self.base_m + self.per_m * range_m
    }
}

/// A scanning range-finder: a fan of beams swept by a rotating mirror.
///
/// Beam `i` points at `angle_min_rad + i * increment_rad` in the sensor's
/// frame (x forward, y left). Datasheet accuracies quoted as `±x` are
/// taken as two standard deviations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaserSpec {
    /// Name, used as the sensor id of its scans.
    pub name: String,
    /// Bearing of the first beam, rad.
    pub angle_min_rad: f64,
    /// Angular step between beams, rad.
    pub increment_rad: f64,
    /// Number of beams in a scan.
    pub beams: usize,
    /// Scans per second.
    pub rate_hz: f64,
    /// Standard deviation of the range noise, m.
    pub range_sigma_m: f64,
    /// Shortest range the sensor reports, m.
    pub min_range_m: f64,
    /// Longest range the sensor reports; anything farther is "no return", m.
    pub max_range_m: f64,
    /// Footprint of the beam.
    pub beam_width: BeamWidth,
}

impl LaserSpec {
    fn preset(name: &str, fov_deg: f64, step_deg: f64, endpoints: bool) -> Self {
        let increment_rad = step_deg.to_radians();
        let spans = (fov_deg / step_deg).round() as usize;
        let beams = if endpoints { spans + 1 } else { spans };
        LaserSpec {
            name: name.to_owned(),
            angle_min_rad: -fov_deg.to_radians() / 2.0,
            increment_rad,
            beams,
            rate_hz: 0.0,
            range_sigma_m: 0.0,
            min_range_m: 0.0,
            max_range_m: 0.0,
            beam_width: BeamWidth {
                base_m: 0.0,
                per_m: 0.0,
            },
        }
    }

    /// IBEO Ladar-2D, the laser of the Luleå papers: 450 beams at 0.6° over
    /// 270°, 8 scans/s, σ ≈ 2 cm, 32 m, footprint 0.04 + 0.002·R m.
    pub fn ibeo_ladar_2d() -> Self {
        LaserSpec {
            rate_hz: 8.0,
            range_sigma_m: 0.02,
            min_range_m: 0.3,
            max_range_m: 32.0,
            beam_width: BeamWidth {
                base_m: 0.04,
                per_m: 0.002,
            },
            ..Self::preset("ibeo-ladar-2d", 270.0, 0.6, false)
        }
    }

    /// Hokuyo URG as de-featured in the sensor-precision paper: 271 beams at
    /// 1° over 270°, 10 scans/s, ±1 cm, 5.6 m.
    pub fn hokuyo_urg() -> Self {
        LaserSpec {
            rate_hz: 10.0,
            range_sigma_m: 0.005,
            min_range_m: 0.02,
            max_range_m: 5.6,
            beam_width: BeamWidth {
                base_m: 0.01,
                per_m: 0.0035,
            },
            ..Self::preset("hokuyo-urg", 270.0, 1.0, true)
        }
    }

    /// Hokuyo UTM-30LX: 1081 beams at 0.25° over 270°, 40 scans/s, ±3 cm,
    /// 30 m.
    pub fn hokuyo_utm30() -> Self {
        LaserSpec {
            rate_hz: 40.0,
            range_sigma_m: 0.015,
            min_range_m: 0.1,
            max_range_m: 30.0,
            beam_width: BeamWidth {
                base_m: 0.01,
                per_m: 0.0025,
            },
            ..Self::preset("hokuyo-utm30", 270.0, 0.25, true)
        }
    }

    /// SICK LMS291: 181 beams at 1° over 180°, 75 scans/s, ±3.5 cm, 80 m.
    pub fn sick_lms291() -> Self {
        LaserSpec {
            rate_hz: 75.0,
            range_sigma_m: 0.0175,
            min_range_m: 0.1,
            max_range_m: 80.0,
            beam_width: BeamWidth {
                base_m: 0.01,
                per_m: 0.0044,
            },
            ..Self::preset("sick-lms291", 180.0, 1.0, true)
        }
    }

    /// All presets, by name.
    pub fn presets() -> Vec<LaserSpec> {
        vec![
            Self::ibeo_ladar_2d(),
            Self::hokuyo_urg(),
            Self::hokuyo_utm30(),
            Self::sick_lms291(),
        ]
    }

    /// The preset called `name`, if there is one.
    pub fn by_name(name: &str) -> Option<LaserSpec> {
        Self::presets().into_iter().find(|p| p.name == name)
    }

    /// Angle between the first and the last beam, rad.
    pub fn fov_rad(&self) -> f64 {
        self.increment_rad * self.beams.saturating_sub(1) as f64
    }

    /// Bearing of beam `i`, rad.
    pub fn beam_angle(&self, i: usize) -> f64 {
        self.angle_min_rad + i as f64 * self.increment_rad
    }

    /// Time the mirror takes to sweep from the first to the last beam, s
    /// (one full turn of the mirror per scan).
    pub fn sweep_duration_s(&self) -> f64 {
        if self.rate_hz > 0.0 {
            self.fov_rad() / (2.0 * PI) / self.rate_hz
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_their_datasheets() {
        let ibeo = LaserSpec::ibeo_ladar_2d();
        assert_eq!(ibeo.beams, 450);
        assert!((ibeo.beam_width.at(10.0) - 0.06).abs() < 1e-12);
        assert!((ibeo.sweep_duration_s() - 0.0935).abs() < 1e-3);
        assert_eq!(LaserSpec::hokuyo_utm30().beams, 1081);
        assert_eq!(LaserSpec::sick_lms291().beams, 181);
        assert_eq!(LaserSpec::hokuyo_urg().beams, 271);
        let sick = LaserSpec::sick_lms291();
        assert!((sick.beam_angle(180) - PI / 2.0).abs() < 1e-12);
        for p in LaserSpec::presets() {
            assert_eq!(LaserSpec::by_name(&p.name).as_ref(), Some(&p));
        }
    }
}
