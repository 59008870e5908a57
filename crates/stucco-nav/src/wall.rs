//! Walls: straight lines observed in a range scan.

use nalgebra::{Matrix2, Point2, Vector2};
use serde::{Deserialize, Serialize};
use stucco_core::{Pose2, wrap_angle};

/// A wall seen in one scan: the line `{p : p·(cos γ, sin γ) = d}` in the
/// sensor frame, with `d ≥ 0` (the wall faces the sensor), its uncertainty
/// and the part of it that was seen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wall {
    /// Perpendicular distance from the sensor, m.
    pub d_m: f64,
    /// Direction of the perpendicular, rad, in `(-π, π]`.
    pub gamma_rad: f64,
    /// Covariance of `(d, γ)`, m², m·rad, rad².
    pub covariance: Matrix2<f64>,
    /// Number of measurements the fit rests on.
    pub points: usize,
    /// Root-mean-square perpendicular residual of those measurements, m.
    pub rms_residual_m: f64,
    /// Ends of the seen part, ordered along [`Wall::direction`].
    pub ends: [Point2<f64>; 2],
}

impl Wall {
    /// Unit normal, pointing from the sensor to the wall.
    pub fn normal(&self) -> Vector2<f64> {
        let (s, c) = self.gamma_rad.sin_cos();
        Vector2::new(c, s)
    }

    /// Unit direction along the wall (the normal turned +90°).
    pub fn direction(&self) -> Vector2<f64> {
        let (s, c) = self.gamma_rad.sin_cos();
        Vector2::new(-s, c)
    }

    /// Signed distance of `p` from the line: positive beyond the wall.
    pub fn signed_distance(&self, p: &Point2<f64>) -> f64 {
        self.normal().dot(&p.coords) - self.d_m
    }

    /// Length of the seen part, m.
    pub fn length_m(&self) -> f64 {
        (self.ends[1] - self.ends[0]).norm()
    }

    /// Standard deviation of `d`, m.
    pub fn sigma_d_m(&self) -> f64 {
        self.covariance[(0, 0)].max(0.0).sqrt()
    }

    /// Standard deviation of `γ`, rad.
    pub fn sigma_gamma_rad(&self) -> f64 {
        self.covariance[(1, 1)].max(0.0).sqrt()
    }

    /// The same wall in the frame in which the sensor sits at `pose`, with
    /// its covariance carried through to first order (the pose itself is
    /// taken as exact).
    pub fn transformed(&self, pose: &Pose2) -> Wall {
        let gamma = wrap_angle(self.gamma_rad + pose.theta);
        let (s, c) = gamma.sin_cos();
        let mut d = self.d_m + c * pose.x + s * pose.y;
        // ∂d/∂γ of the moved line.
        let mut dd_dgamma = -s * pose.x + c * pose.y;
        let mut gamma_out = gamma;
        let mut dd_dd = 1.0;
        if d < 0.0 {
            d = -d;
            dd_dd = -1.0;
            dd_dgamma = -dd_dgamma;
            gamma_out = wrap_angle(gamma + std::f64::consts::PI);
        }
        let j = Matrix2::new(dd_dd, dd_dgamma, 0.0, 1.0);
        let ends = self.ends.map(|e| pose.transform_point(&e));
        let mut out = Wall {
            d_m: d,
            gamma_rad: gamma_out,
            covariance: j * self.covariance * j.transpose(),
            points: self.points,
            rms_residual_m: self.rms_residual_m,
            ends,
        };
        let u = out.direction();
        if u.dot(&(ends[1] - ends[0])) < 0.0 {
            out.ends.swap(0, 1);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_the_sensor_moves_the_wall_the_other_way() {
        // Wall x = 3 seen from the origin; sensor moved to (1, 0) heading 90°.
        let w = Wall {
            d_m: 3.0,
            gamma_rad: 0.0,
            covariance: Matrix2::identity() * 1e-4,
            points: 10,
            rms_residual_m: 0.0,
            ends: [Point2::new(3.0, -1.0), Point2::new(3.0, 1.0)],
        };
        // The wall expressed in a frame where this sensor sits at pose (1, 0, 90°).
        let t = w.transformed(&Pose2::new(1.0, 0.0, std::f64::consts::FRAC_PI_2));
        // Its points (3, y) land at (1 − y, 3): the line y = 3.
        assert!((t.d_m - 3.0).abs() < 1e-12, "{t:?}");
        assert!((t.gamma_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(
            (t.ends[0] - Point2::new(2.0, 3.0)).norm() < 1e-12,
            "{:?}",
            t.ends
        );
        // The wall seen from behind flips its normal.
        let back = w.transformed(&Pose2::new(-5.0, 0.0, 0.0));
        assert!(
            (back.d_m - 2.0).abs() < 1e-12
                && (back.gamma_rad.abs() - std::f64::consts::PI).abs() < 1e-12
        );
        assert!(back.covariance[(1, 1)] > 0.0);
    }
}
