//! Relative pose error (Kümmerle et al. 2009, "On measuring the accuracy
//! of SLAM algorithms"): for pairs of poses `(i, j)`, the motion from `i`
//! to `j` as estimated against the motion as it truly was,
//! `ε = (x̂ᵢ⁻¹ x̂ⱼ)⁻¹ (xᵢ⁻¹ xⱼ)`; its translation and rotation, averaged over
//! the pairs. Unlike the absolute error it does not depend on the frame the
//! map was built in, and it charges an error once, where it was made.

use serde::Serialize;
use stucco_core::{Pose2, wrap_angle};

/// Which pairs of poses to compare.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pairs {
    /// Each pose with the one `n` samples later.
    Step(usize),
    /// Each pose with the first one at least this far along the true path,
    /// m.
    Distance(f64),
}

/// The relative pose error over a trajectory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Rpe {
    /// Pairs compared.
    pub pairs: usize,
    /// Mean translational error, m.
    pub trans_mean_m: f64,
    /// Its standard deviation, m.
    pub trans_std_m: f64,
    /// Mean rotational error, rad.
    pub rot_mean_rad: f64,
    /// Its standard deviation, rad.
    pub rot_std_rad: f64,
}

/// The relative pose error of `estimated` against `truth` (the same
/// instants, in order) over `pairs`; `None` when there is no pair to
/// compare (or the trajectories differ in length).
pub fn relative_pose_error(estimated: &[Pose2], truth: &[Pose2], pairs: Pairs) -> Option<Rpe> {
    if estimated.len() != truth.len() {
        return None;
    }
    let n = truth.len();
    let mut trans = Vec::new();
    let mut rot = Vec::new();
    let mut push = |i: usize, j: usize| {
        let est = estimated[i].inverse() * estimated[j];
        let real = truth[i].inverse() * truth[j];
        let e = est.inverse() * real;
        trans.push(e.x.hypot(e.y));
        rot.push(wrap_angle(e.theta).abs());
    };
    match pairs {
        Pairs::Step(step) => {
            let step = step.max(1);
            for i in 0..n.saturating_sub(step) {
                push(i, i + step);
            }
        }
        Pairs::Distance(d) => {
            // Distance along the true path from the start to each pose.
            let mut along = Vec::with_capacity(n);
            let mut s = 0.0;
            for (k, p) in truth.iter().enumerate() {
                if k > 0 {
                    s += (p.position() - truth[k - 1].position()).norm();
                }
                along.push(s);
            }
            let mut j = 0;
            for i in 0..n {
                j = j.max(i + 1);
                while j < n && along[j] - along[i] < d {
                    j += 1;
                }
                if j >= n {
                    break;
                }
                push(i, j);
            }
        }
    }
    if trans.is_empty() {
        return None;
    }
    let stats = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64;
        (m, var.sqrt())
    };
    let (tm, ts) = stats(&trans);
    let (rm, rs) = stats(&rot);
    Some(Rpe {
        pairs: trans.len(),
        trans_mean_m: tm,
        trans_std_m: ts,
        rot_mean_rad: rm,
        rot_std_rad: rs,
    })
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    fn square(n: usize) -> Vec<Pose2> {
        (0..n)
            .map(|k| {
                let t = k as f64 * 0.1;
                Pose2::new(
                    t.cos() * 2.0,
                    t.sin() * 2.0,
                    t + std::f64::consts::FRAC_PI_2,
                )
            })
            .collect()
    }

    #[test]
    fn a_perfect_estimate_and_one_in_another_frame_have_no_error() {
        let truth = square(50);
        let r = relative_pose_error(&truth, &truth, Pairs::Step(1)).expect("pairs");
        assert_eq!(r.pairs, 49);
        assert!(r.trans_mean_m < 1e-12 && r.rot_mean_rad < 1e-12);
        // The whole estimate moved and turned: relative motions unchanged.
        let frame = Pose2::new(3.0, -1.0, 0.7);
        let moved: Vec<Pose2> = truth.iter().map(|p| frame * *p).collect();
        let r = relative_pose_error(&moved, &truth, Pairs::Distance(0.5)).expect("pairs");
        assert!(r.trans_mean_m < 1e-9 && r.rot_mean_rad < 1e-9, "{r:?}");
    }

    #[test]
    fn one_error_is_charged_once_per_pair_that_spans_it() {
        // A straight line along x; the estimate jumps 0.1 m sideways once.
        let truth: Vec<Pose2> = (0..11).map(|k| Pose2::new(k as f64, 0.0, 0.0)).collect();
        let est: Vec<Pose2> = truth
            .iter()
            .enumerate()
            .map(|(k, p)| Pose2::new(p.x, if k >= 5 { 0.1 } else { 0.0 }, 0.0))
            .collect();
        let r = relative_pose_error(&est, &truth, Pairs::Step(1)).expect("pairs");
        assert_eq!(r.pairs, 10);
        // One pair of ten carries the 0.1 m.
        assert!((r.trans_mean_m - 0.01).abs() < 1e-12, "{r:?}");
        assert!((r.trans_std_m - 0.03).abs() < 1e-12, "{r:?}");
        assert_eq!(r.rot_mean_rad, 0.0);
        // Pairs 2 m apart: 2 of 9 span the jump.
        let r = relative_pose_error(&est, &truth, Pairs::Distance(2.0)).expect("pairs");
        assert_eq!(r.pairs, 9);
        assert!((r.trans_mean_m - 0.2 / 9.0).abs() < 1e-12, "{r:?}");
        assert!(relative_pose_error(&est[..3], &truth, Pairs::Step(1)).is_none());
    }
}
