//! Rigid motions of the plane.

use nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::ops::Mul;

/// Wraps an angle to `(-π, π]`.
pub fn wrap_angle(angle_rad: f64) -> f64 {
    let a = angle_rad.rem_euclid(2.0 * PI);
    if a > PI { a - 2.0 * PI } else { a }
}

/// A pose in the plane: position `(x, y)` in metres and heading `theta` in
/// radians, counter-clockwise from the x axis.
///
/// `a * b` composes poses (`b` expressed in `a`'s frame), so the pose of a
/// laser mounted at `mount` on a robot at `robot` is `robot * mount`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose2 {
    /// Position along the x axis, metres.
    pub x: f64,
    /// Position along the y axis, metres.
    pub y: f64,
    /// Heading, radians.
    pub theta: f64,
}

impl Pose2 {
    /// The identity pose.
    pub const IDENTITY: Pose2 = Pose2 {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    /// A pose from its components; the heading is wrapped to `(-π, π]`.
    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Pose2 {
            x,
            y,
            theta: wrap_angle(theta),
        }
    }

    /// The position as a point.
    pub fn position(&self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }

    /// Maps a point from this pose's frame to the parent frame.
    pub fn transform_point(&self, p: &Point2<f64>) -> Point2<f64> {
        let (s, c) = self.theta.sin_cos();
        Point2::new(self.x + c * p.x - s * p.y, self.y + s * p.x + c * p.y)
    }

    /// Rotates a vector from this pose's frame to the parent frame.
    pub fn rotate_vector(&self, v: &Vector2<f64>) -> Vector2<f64> {
        let (s, c) = self.theta.sin_cos();
        Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
    }

    /// The inverse motion: `p.inverse() * p` is the identity.
    pub fn inverse(&self) -> Pose2 {
        let (s, c) = self.theta.sin_cos();
        Pose2::new(
            -(c * self.x + s * self.y),
            s * self.x - c * self.y,
            -self.theta,
        )
    }

    /// The pose of `other` seen from `self`: `self.inverse() * other`.
    pub fn between(&self, other: &Pose2) -> Pose2 {
        self.inverse() * *other
    }

    /// The pose reached after moving with constant body-frame `twist` for
    /// `dt_s` seconds (the exponential map of SE(2)).
    pub fn advanced(&self, twist: &Twist2, dt_s: f64) -> Pose2 {
        *self * twist.displacement(dt_s)
    }
}

impl Mul for Pose2 {
    type Output = Pose2;
    /// Composition of rigid motions: rotations add.
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn mul(self, rhs: Pose2) -> Pose2 {
        let p = self.transform_point(&Point2::new(rhs.x, rhs.y));
        Pose2::new(p.x, p.y, self.theta + rhs.theta)
    }
}

/// A planar velocity in the body frame: forward and lateral speed, m/s, and
/// turn rate, rad/s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Twist2 {
    /// Forward speed, m/s.
    pub vx_mps: f64,
    /// Lateral speed (to the left), m/s.
    pub vy_mps: f64,
    /// Turn rate, rad/s, counter-clockwise.
    pub omega_radps: f64,
}

impl Twist2 {
    /// A twist from its components.
    pub const fn new(vx_mps: f64, vy_mps: f64, omega_radps: f64) -> Self {
        Twist2 {
            vx_mps,
            vy_mps,
            omega_radps,
        }
    }

    /// The body-frame displacement after `dt_s` seconds of constant twist:
    /// an arc, exact for any turn rate.
    pub fn displacement(&self, dt_s: f64) -> Pose2 {
        let th = self.omega_radps * dt_s;
        let (vx, vy) = (self.vx_mps * dt_s, self.vy_mps * dt_s);
        // V(θ) = [[sinθ/θ, -(1-cosθ)/θ], [(1-cosθ)/θ, sinθ/θ]], by series near 0.
        let (a, b) = if th.abs() < 1e-6 {
            (1.0 - th * th / 6.0, th / 2.0)
        } else {
            (th.sin() / th, (1.0 - th.cos()) / th)
        };
        Pose2::new(a * vx - b * vy, b * vx + a * vy, th)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-9
            && (a.y - b.y).abs() < 1e-9
            && wrap_angle(a.theta - b.theta).abs() < 1e-9
    }

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn quarter_circle_arc_ends_where_geometry_says() {
        // 1 m radius, quarter turn: from the origin to (1, 1) heading +90°.
        let t = Twist2::new(1.0, 0.0, 1.0);
        let p = t.displacement(PI / 2.0);
        assert!(close(&p, &Pose2::new(1.0, 1.0, PI / 2.0)), "{p:?}");
    }

    proptest! {
        #[test]
        fn inverse_undoes_composition(x in -10.0..10.0f64, y in -10.0..10.0f64, th in -4.0..4.0f64,
                                      u in -10.0..10.0f64, v in -10.0..10.0f64, ph in -4.0..4.0f64) {
            let a = Pose2::new(x, y, th);
            let b = Pose2::new(u, v, ph);
            prop_assert!(close(&(a.inverse() * (a * b)), &b));
            prop_assert!(close(&(a * a.between(&b)), &b));
        }

        #[test]
        fn arcs_compose(vx in -1.0..1.0f64, w in -2.0..2.0f64, t1 in 0.0..2.0f64, t2 in 0.0..2.0f64) {
            let tw = Twist2::new(vx, 0.0, w);
            let joined = tw.displacement(t1) * tw.displacement(t2);
            prop_assert!(close(&joined, &tw.displacement(t1 + t2)));
        }
    }
}
