//! A laser made worse on purpose, as the sensor-precision paper (Rogers et
//! al.) does to its logged scans in post-processing: a shorter maximum
//! range, beams dropped for a coarser angular resolution, a narrower field
//! of view centred forward, Gaussian noise added to every range. Applied to
//! scans of the full sensor, so one recorded run serves every setting.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use stucco_core::{LaserSpec, Scan, Stamp};

use crate::error::NavError;

/// How much worse than its preset a laser is made. `None` keeps the
/// preset's value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Defeature {
    /// Longest range reported, m; echoes beyond are no returns.
    pub max_range_m: Option<f64>,
    /// Angle between kept beams, rad: a whole multiple of the preset's
    /// step (beams are dropped, never invented).
    pub resolution_rad: Option<f64>,
    /// Field of view, rad, centred on the laser's forward axis.
    pub fov_rad: Option<f64>,
    /// Standard deviation of the Gaussian noise added to each range, m.
    pub noise_sigma_m: f64,
}

/// A preset with a [`Defeature`] applied: the laser it makes and which of
/// the preset's beams it keeps.
#[derive(Clone, Debug, PartialEq)]
pub struct DefeaturedLaser {
    /// The laser as the software sees it (its noise the preset's and the
    /// added noise together).
    pub spec: LaserSpec,
    /// The preset's beams kept, in sweep order, evenly spaced.
    keep: Vec<usize>,
    noise_sigma_m: f64,
    preset_beams: usize,
}

fn invalid(field: &'static str, reason: String) -> NavError {
    NavError::InvalidConfig { field, reason }
}

impl DefeaturedLaser {
    /// `preset` made worse by `how`; refused when it would ask for more
    /// than the preset has (a finer step, a wider view, a longer range) or
    /// for a value that means nothing.
    pub fn new(preset: &LaserSpec, how: &Defeature) -> Result<DefeaturedLaser, NavError> {
        let step = preset.increment_rad.abs();
        let n = preset.beams;
        if n == 0 || step <= 0.0 {
            return Err(invalid(
                "beams",
                format!("the preset `{}` has no beams", preset.name),
            ));
        }
        let k = match how.resolution_rad {
            None => 1,
            Some(r) => {
                let k = (r / step).round();
                if !(r.is_finite() && k >= 1.0 && (k * step - r).abs() <= 1e-3 * step) {
                    return Err(invalid(
                        "resolution",
                        format!(
                            "{:.4}° is not a whole multiple of the {:.4}° step of `{}`",
                            r.to_degrees(),
                            step.to_degrees(),
                            preset.name
                        ),
                    ));
                }
                k as usize
            }
        };
        let fov = preset.fov_rad();
        let half = match how.fov_rad {
            None => f64::INFINITY,
            Some(f) if f.is_finite() && f > 0.0 && f <= fov + 1e-9 => 0.5 * f,
            Some(f) => {
                return Err(invalid(
                    "fov",
                    format!(
                        "{:.1}° is not within (0°, {:.1}°], the view of `{}`",
                        f.to_degrees(),
                        fov.to_degrees(),
                        preset.name
                    ),
                ));
            }
        };
        let max_range_m = match how.max_range_m {
            None => preset.max_range_m,
            Some(r) if r.is_finite() && r > preset.min_range_m && r <= preset.max_range_m => r,
            Some(r) => {
                return Err(invalid(
                    "range",
                    format!(
                        "{r} m is not within ({}, {}] m, the ranges of `{}`",
                        preset.min_range_m, preset.max_range_m, preset.name
                    ),
                ));
            }
        };
        if !(how.noise_sigma_m.is_finite() && how.noise_sigma_m >= 0.0) {
            return Err(invalid(
                "noise",
                format!("{} m is not a standard deviation", how.noise_sigma_m),
            ));
        }
        // The beam nearest straight ahead is always kept; the others every
        // k-th from it, within the view.
        let ahead = ((-preset.angle_min_rad / preset.increment_rad)
            .round()
            .max(0.0) as usize)
            .min(n - 1);
        let keep: Vec<usize> = (0..n)
            .filter(|&i| i.abs_diff(ahead) % k == 0)
            .filter(|&i| preset.beam_angle(i).abs() <= half + 1e-9)
            .collect();
        let Some(&first) = keep.first() else {
            return Err(invalid(
                "fov",
                format!(
                    "{:.2}° keeps no beam of `{}`",
                    2.0 * half.to_degrees(),
                    preset.name
                ),
            ));
        };
        let spec = LaserSpec {
            name: preset.name.clone(),
            angle_min_rad: preset.beam_angle(first),
            increment_rad: preset.increment_rad * k as f64,
            beams: keep.len(),
            range_sigma_m: preset.range_sigma_m.hypot(how.noise_sigma_m),
            max_range_m,
            ..preset.clone()
        };
        Ok(DefeaturedLaser {
            spec,
            noise_sigma_m: how.noise_sigma_m,
            preset_beams: n,
            keep,
        })
    }

    /// When the scan made from the preset's `scan` starts: the time of its
    /// first kept beam.
    pub fn stamp_of(&self, scan: &Scan) -> Stamp {
        let first = self.keep.first().copied().unwrap_or(0);
        Stamp::from_secs_f64(scan.stamp.as_secs_f64() + scan.beam_time_s(first))
    }

    /// The scan this laser would have taken where the preset took `scan`
    /// (a scan of the preset, beam for beam); the noise drawn from `rng`.
    /// `None` when `scan` is not one of the preset's.
    pub fn apply(&self, scan: &Scan, rng: &mut impl Rng) -> Option<Scan> {
        if scan.ranges_m.len() != self.preset_beams {
            return None;
        }
        let noise = self.noise_sigma_m;
        let ranges = self.keep.iter().map(|&i| {
            let r = scan.ranges_m[i];
            if r.is_finite() && noise > 0.0 {
                let g: f64 = StandardNormal.sample(rng);
                r + noise * g
            } else {
                r
            }
        });
        let (first, last) = match (self.keep.first(), self.keep.last()) {
            (Some(&a), Some(&b)) => (a, b),
            _ => return None,
        };
        let sweep = scan.beam_time_s(last) - scan.beam_time_s(first);
        let start = self.stamp_of(scan).as_secs_f64();
        Some(Scan::new(
            Stamp::from_secs_f64(start),
            scan.sensor.clone(),
            self.spec.angle_min_rad,
            self.spec.increment_rad,
            sweep,
            self.spec.min_range_m,
            self.spec.max_range_m,
            ranges,
        ))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn scan_of(spec: &LaserSpec, range: impl Fn(usize) -> f64) -> Scan {
        Scan::from_spec(spec, Stamp::from_secs_f64(2.0), (0..spec.beams).map(range))
    }

    #[test]
    fn the_preset_unchanged_is_the_preset() {
        let utm = LaserSpec::hokuyo_utm30();
        let same = DefeaturedLaser::new(&utm, &Defeature::default()).unwrap();
        assert_eq!(same.spec, utm);
        let scan = scan_of(&utm, |i| 1.0 + i as f64 * 1e-3);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert_eq!(same.apply(&scan, &mut rng), Some(scan));
    }

    #[test]
    fn coarser_resolution_keeps_every_kth_beam_and_straight_ahead() {
        let utm = LaserSpec::hokuyo_utm30(); // 0.25°, 1081 beams, ±135°
        let how = Defeature {
            resolution_rad: Some(1f64.to_radians()),
            ..Defeature::default()
        };
        let d = DefeaturedLaser::new(&utm, &how).unwrap();
        assert_eq!(d.spec.beams, 271);
        assert!((d.spec.increment_rad - 1f64.to_radians()).abs() < 1e-12);
        let scan = scan_of(&utm, |i| 1.0 + i as f64 * 1e-3);
        let out = d.apply(&scan, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(out.ranges_m.len(), 271);
        // Beam 540 looks straight ahead; in the coarse scan it is beam 135.
        assert!(out.angle(135).abs() < 1e-12);
        assert_eq!(out.ranges_m[135], scan.ranges_m[540]);
        assert_eq!(out.ranges_m[136], scan.ranges_m[544]);
        assert!((out.sweep_duration_s - scan.sweep_duration_s).abs() < 1e-12);
        // A step that is not a multiple of the preset's is refused, named.
        let bad = Defeature {
            resolution_rad: Some(0.3f64.to_radians()),
            ..Defeature::default()
        };
        let e = DefeaturedLaser::new(&utm, &bad).unwrap_err().to_string();
        assert!(e.contains("resolution") && e.contains("0.2500°"), "{e}");
    }

    #[test]
    fn a_narrower_view_is_centred_forward_and_starts_later_in_the_sweep() {
        let urg = LaserSpec::hokuyo_urg(); // 1°, 271 beams, ±135°
        let how = Defeature {
            fov_rad: Some(90f64.to_radians()),
            ..Defeature::default()
        };
        let d = DefeaturedLaser::new(&urg, &how).unwrap();
        assert_eq!(d.spec.beams, 91);
        assert!((d.spec.angle_min_rad + 45f64.to_radians()).abs() < 1e-12);
        let scan = scan_of(&urg, |i| 1.0 + i as f64 * 1e-2);
        let out = d.apply(&scan, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        // Each kept beam keeps its bearing, range and time of sweep.
        for (j, &r) in out.ranges_m.iter().enumerate() {
            let i = j + 90;
            assert_eq!(r, scan.ranges_m[i]);
            assert!((out.angle(j) - scan.angle(i)).abs() < 1e-12);
            let t_out = out.stamp.as_secs_f64() + out.beam_time_s(j);
            let t_in = scan.stamp.as_secs_f64() + scan.beam_time_s(i);
            assert!((t_out - t_in).abs() < 1e-9, "beam {j}: {t_out} vs {t_in}");
        }
        let wide = Defeature {
            fov_rad: Some(300f64.to_radians()),
            ..Defeature::default()
        };
        let e = DefeaturedLaser::new(&urg, &wide).unwrap_err().to_string();
        assert!(e.contains("fov") && e.contains("270.0°"), "{e}");
    }

    #[test]
    fn a_shorter_range_drops_the_far_echoes() {
        let sick = LaserSpec::sick_lms291();
        let how = Defeature {
            max_range_m: Some(1.6),
            ..Defeature::default()
        };
        let d = DefeaturedLaser::new(&sick, &how).unwrap();
        let scan = scan_of(&sick, |i| if i % 2 == 0 { 1.0 } else { 3.0 });
        let out = d.apply(&scan, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(out.returns().count(), 91);
        assert!(out.returns().all(|b| b.range_m == 1.0));
        let far = Defeature {
            max_range_m: Some(100.0),
            ..Defeature::default()
        };
        assert!(DefeaturedLaser::new(&sick, &far).is_err());
    }

    #[test]
    fn added_noise_has_the_asked_deviation_and_the_filter_is_told() {
        let utm = LaserSpec::hokuyo_utm30();
        let how = Defeature {
            noise_sigma_m: 0.02,
            ..Defeature::default()
        };
        let d = DefeaturedLaser::new(&utm, &how).unwrap();
        assert!((d.spec.range_sigma_m - 0.015f64.hypot(0.02)).abs() < 1e-12);
        let scan = scan_of(&utm, |_| 5.0);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut sum2 = 0.0;
        let mut n = 0usize;
        for _ in 0..20 {
            let out = d.apply(&scan, &mut rng).unwrap();
            for r in &out.ranges_m {
                sum2 += (r - 5.0).powi(2);
                n += 1;
            }
        }
        let sd = (sum2 / n as f64).sqrt();
        assert!((sd - 0.02).abs() < 0.0005, "{sd}");
        // The same seed draws the same noise.
        let a = d.apply(&scan, &mut ChaCha8Rng::seed_from_u64(9));
        let b = d.apply(&scan, &mut ChaCha8Rng::seed_from_u64(9));
        assert_eq!(a, b);
        // A scan of another laser is not taken for one of the preset's.
        let other = scan_of(&LaserSpec::hokuyo_urg(), |_| 1.0);
        assert_eq!(d.apply(&other, &mut rng), None);
    }
}
