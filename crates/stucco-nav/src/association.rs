//! The decision-directed classifier of paper B: which wall of the map each
//! observed wall is.
//!
//! For every observation the approximate Bayes probability of each pairing
//! with a wall of the map is computed under a Gaussian assumption, with one
//! more hypothesis, "none of them" (a new wall or clutter), of density
//! `λ`. An observation is matched only when one pairing is probable beyond
//! doubt; when it is about equally likely to be two walls it is discarded,
//! never forced, because a wrong match corrupts the estimate while it
//! shrinks its covariance.
//!
//! Observations the individual test leaves in doubt are then classified
//! jointly: every assignment of them (each to one of its candidates or to
//! none) is scored by the joint Gaussian density of all innovations,
//! including those already decided, through the pose they share. So the
//! shape of what is seen (a corridor's width, a step in a wall) decides
//! what no observation could decide alone.

use nalgebra::{DMatrix, DVector, Matrix2, Matrix2x3, Vector2};

/// One way an observation could be a wall of the map: the innovation and
/// the Jacobian of the predicted observation (with respect to the robot's
/// pose and to that wall's `(ρ, α)`).
#[derive(Clone, Debug)]
pub(crate) struct Pairing {
    /// Index of the wall's `(ρ, α)` block in the state (its first row).
    pub state_row: usize,
    /// Observed minus predicted `(d, γ)`.
    pub innovation: Vector2<f64>,
    /// ∂h/∂(x, y, θ).
    pub h_pose: Matrix2x3<f64>,
    /// ∂h/∂(ρ, α).
    pub h_wall: Matrix2<f64>,
}

/// The settings of the classifier.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Classifier {
    /// Squared Mahalanobis distance beyond which a pairing is not
    /// considered at all.
    pub gate_chi2: f64,
    /// Probability a pairing must reach to be accepted.
    pub accept_probability: f64,
    /// Density of "none of them", per m·rad.
    pub clutter_density: f64,
    /// Most assignments scored jointly; beyond it doubtful observations are
    /// discarded.
    pub max_hypotheses: usize,
}

/// What the classifier decided for one observation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Decision {
    /// It is this candidate (index into the observation's candidates).
    Match(usize),
    /// No wall of the map is anywhere near it.
    Unknown,
    /// It could be more than one thing: discarded.
    Doubtful,
}

impl Classifier {
    /// Decides every observation: `candidates[j]` are the pairings of
    /// observation `j` (already gated by where the walls were seen),
    /// `noise[j]` its covariance, `p` the filter's covariance.
    pub fn classify(
        &self,
        candidates: &[Vec<Pairing>],
        noise: &[Matrix2<f64>],
        p: &DMatrix<f64>,
    ) -> Vec<Decision> {
        let mut gated: Vec<Vec<(usize, f64)>> = Vec::with_capacity(candidates.len());
        for (j, pairs) in candidates.iter().enumerate() {
            let mut kept = Vec::new();
            for (k, pair) in pairs.iter().enumerate() {
                let s = cross_covariance(pair, pair, p) + noise[j];
                if let Some(ll) = log_density(&pair.innovation, &s, self.gate_chi2) {
                    kept.push((k, ll));
                }
            }
            gated.push(kept);
        }
        let log_none = self.clutter_density.ln();
        let decisions: Vec<Decision> = gated
            .iter()
            .map(|kept| {
                if kept.is_empty() {
                    return Decision::Unknown;
                }
                let logs: Vec<f64> = kept.iter().map(|&(_, ll)| ll).collect();
                let post = posteriors(&logs, log_none);
                match argmax(&post) {
                    Some(i) if i < kept.len() && post[i] >= self.accept_probability => {
                        Decision::Match(kept[i].0)
                    }
                    _ => Decision::Doubtful,
                }
            })
            .collect();
        // A wall of the map is one line of the scan: two observations
        // decided for the same wall are both in doubt (the scan's pieces of
        // one line were joined before).
        let mut decisions = decisions;
        for a in 0..decisions.len() {
            for b in a + 1..decisions.len() {
                if let (Decision::Match(ka), Decision::Match(kb)) = (decisions[a], decisions[b])
                    && candidates[a][ka].state_row == candidates[b][kb].state_row
                {
                    decisions[a] = Decision::Doubtful;
                    decisions[b] = Decision::Doubtful;
                }
            }
        }
        let doubtful: Vec<usize> = (0..decisions.len())
            .filter(|&j| decisions[j] == Decision::Doubtful)
            .collect();
        if doubtful.is_empty() {
            return decisions;
        }
        let count = doubtful
            .iter()
            .try_fold(1usize, |n, &j| n.checked_mul(gated[j].len() + 1));
        if count.is_none_or(|n| n > self.max_hypotheses) {
            return decisions;
        }
        // The decided pairings, fixed in every hypothesis.
        let fixed: Vec<(usize, &Pairing)> = decisions
            .iter()
            .enumerate()
            .filter_map(|(j, d)| match d {
                Decision::Match(k) => Some((j, &candidates[j][*k])),
                _ => None,
            })
            .collect();
        // Each hypothesis: for each doubtful observation, an index into its
        // gated list, or its length for "none".
        let mut choice = vec![0usize; doubtful.len()];
        let mut hypotheses: Vec<(Vec<usize>, f64)> = Vec::new();
        loop {
            let mut set = fixed.clone();
            let mut nones = 0;
            for (c, &j) in choice.iter().zip(&doubtful) {
                match gated[j].get(*c) {
                    Some(&(k, _)) => set.push((j, &candidates[j][k])),
                    None => nones += 1,
                }
            }
            let exclusive = set.iter().enumerate().all(|(a, (_, pa))| {
                set[a + 1..]
                    .iter()
                    .all(|(_, pb)| pa.state_row != pb.state_row)
            });
            if !exclusive {
                // Not a hypothesis: one wall would be two lines of the scan.
            } else if let Some(ll) = joint_log_density(&set, noise, p) {
                hypotheses.push((choice.clone(), ll + nones as f64 * log_none));
            }
            // Next assignment (odometer order).
            let mut i = 0;
            loop {
                if i == choice.len() {
                    return self.decide_jointly(decisions, &doubtful, &gated, &hypotheses);
                }
                choice[i] += 1;
                if choice[i] <= gated[doubtful[i]].len() {
                    break;
                }
                choice[i] = 0;
                i += 1;
            }
        }
    }

    /// Marginal probabilities of each doubtful observation's options over
    /// the scored hypotheses, and the decisions they allow.
    fn decide_jointly(
        &self,
        mut decisions: Vec<Decision>,
        doubtful: &[usize],
        gated: &[Vec<(usize, f64)>],
        hypotheses: &[(Vec<usize>, f64)],
    ) -> Vec<Decision> {
        let Some(top) = hypotheses.iter().map(|h| h.1).reduce(f64::max) else {
            return decisions;
        };
        let weights: Vec<f64> = hypotheses.iter().map(|h| (h.1 - top).exp()).collect();
        let total: f64 = weights.iter().sum();
        for (i, &j) in doubtful.iter().enumerate() {
            let mut marginal = vec![0.0; gated[j].len() + 1];
            for ((choice, _), w) in hypotheses.iter().zip(&weights) {
                marginal[choice[i]] += w / total;
            }
            if let Some(best) = argmax(&marginal)
                && marginal[best] >= self.accept_probability
            {
                decisions[j] = match gated[j].get(best) {
                    Some(&(k, _)) => Decision::Match(k),
                    // Near walls of the map yet none of them: neither
                    // matched nor a new wall.
                    None => Decision::Doubtful,
                };
            }
        }
        decisions
    }
}

/// `H_a P H_bᵀ` for two pairings.
pub(crate) fn cross_covariance(a: &Pairing, b: &Pairing, p: &DMatrix<f64>) -> Matrix2<f64> {
    let pose_pose = p.fixed_view::<3, 3>(0, 0);
    let pose_b = p.fixed_view::<3, 2>(0, b.state_row);
    let a_pose = p.fixed_view::<2, 3>(a.state_row, 0);
    let a_b = p.fixed_view::<2, 2>(a.state_row, b.state_row);
    a.h_pose * pose_pose * b.h_pose.transpose()
        + a.h_pose * pose_b * b.h_wall.transpose()
        + a.h_wall * a_pose * b.h_pose.transpose()
        + a.h_wall * a_b * b.h_wall.transpose()
}

/// The stacked innovation covariance `H P Hᵀ + R` of `set` (observation
/// index, pairing).
pub(crate) fn stacked_covariance(
    set: &[(usize, &Pairing)],
    noise: &[Matrix2<f64>],
    p: &DMatrix<f64>,
) -> DMatrix<f64> {
    let m = set.len();
    let mut s = DMatrix::zeros(2 * m, 2 * m);
    for (a, (ja, pa)) in set.iter().enumerate() {
        for (b, (jb, pb)) in set.iter().enumerate().skip(a) {
            let mut block = cross_covariance(pa, pb, p);
            if ja == jb && a == b {
                block += noise[*ja];
            }
            s.fixed_view_mut::<2, 2>(2 * a, 2 * b).copy_from(&block);
            s.fixed_view_mut::<2, 2>(2 * b, 2 * a)
                .copy_from(&block.transpose());
        }
    }
    s
}

/// Log of the joint Gaussian density of the innovations of `set`; `None`
/// when their covariance is not positive definite.
fn joint_log_density(
    set: &[(usize, &Pairing)],
    noise: &[Matrix2<f64>],
    p: &DMatrix<f64>,
) -> Option<f64> {
    if set.is_empty() {
        return Some(0.0);
    }
    let s = stacked_covariance(set, noise, p);
    let nu = DVector::from_iterator(
        2 * set.len(),
        set.iter().flat_map(|(_, pr)| pr.innovation.iter().copied()),
    );
    let chol = s.cholesky()?;
    let d2 = nu.dot(&chol.solve(&nu));
    let log_det: f64 = chol.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum();
    Some(-0.5 * (d2 + log_det + nu.len() as f64 * (2.0 * std::f64::consts::PI).ln()))
}

/// Log density of innovation `nu` with covariance `s`, or `None` beyond the
/// gate (or for a singular `s`).
fn log_density(nu: &Vector2<f64>, s: &Matrix2<f64>, gate_chi2: f64) -> Option<f64> {
    let inv = s.try_inverse()?;
    let d2 = nu.dot(&(inv * nu));
    let det = s.determinant();
    (d2 <= gate_chi2 && det > 0.0)
        .then(|| -0.5 * d2 - 0.5 * det.ln() - (2.0 * std::f64::consts::PI).ln())
}

/// Posterior probabilities of the hypotheses with log-likelihoods `logs`
/// and of "none" (last) with log-likelihood `log_none`, equal priors.
fn posteriors(logs: &[f64], log_none: f64) -> Vec<f64> {
    let top = logs.iter().copied().fold(log_none, f64::max);
    let mut w: Vec<f64> = logs.iter().map(|l| (l - top).exp()).collect();
    w.push((log_none - top).exp());
    let total: f64 = w.iter().sum();
    w.iter().map(|v| v / total).collect()
}

fn argmax(v: &[f64]) -> Option<usize> {
    (0..v.len()).max_by(|&a, &b| v[a].total_cmp(&v[b]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn classifier() -> Classifier {
        Classifier {
            gate_chi2: 13.8,
            accept_probability: 0.95,
            clutter_density: 0.02,
            max_hypotheses: 1024,
        }
    }

    /// A state of pose and `walls` walls, pose σ `pose_sigma` in x and y,
    /// walls known to 5 mm.
    fn covariance(walls: usize, pose_sigma: f64) -> DMatrix<f64> {
        let mut p = DMatrix::identity(3 + 2 * walls, 3 + 2 * walls) * 0.005f64.powi(2);
        p[(0, 0)] = pose_sigma.powi(2);
        p[(1, 1)] = pose_sigma.powi(2);
        p[(2, 2)] = 0.01f64.powi(2);
        p
    }

    /// A pairing with a wall facing +y (`h_pose` sees the pose's y).
    fn facing_y(wall: usize, innovation_m: f64) -> Pairing {
        Pairing {
            state_row: 3 + 2 * wall,
            innovation: Vector2::new(innovation_m, 0.0),
            h_pose: Matrix2x3::new(0.0, -1.0, 0.0, 0.0, 0.0, -1.0),
            h_wall: Matrix2::identity(),
        }
    }

    fn noise(n: usize) -> Vec<Matrix2<f64>> {
        vec![Matrix2::new(0.01f64.powi(2), 0.0, 0.0, 0.01f64.powi(2)); n]
    }

    #[test]
    fn an_observation_between_two_walls_is_discarded_not_forced() {
        // Two parallel walls 10 cm apart; the observation lies 4.5 cm from
        // one and 5.5 cm from the other.
        let p = covariance(2, 0.02);
        let c = vec![vec![facing_y(0, 0.045), facing_y(1, -0.055)]];
        assert_eq!(
            classifier().classify(&c, &noise(1), &p),
            [Decision::Doubtful]
        );
        // Right on one of them: matched.
        let c = vec![vec![facing_y(0, 0.002), facing_y(1, -0.098)]];
        assert_eq!(
            classifier().classify(&c, &noise(1), &p),
            [Decision::Match(0)]
        );
    }

    #[test]
    fn the_shape_of_what_is_seen_decides_what_one_wall_cannot() {
        // Walls 0 and 1 both face +y, 0.3 m apart (a step in a wall); wall 2
        // faces +y 1.3 m beyond wall 0. The robot's y is known only to
        // 0.3 m and it is 0.25 m from where it thinks, so each wall is seen
        // 0.25 m off: alone, the observations of walls 0 and 1 could each
        // be either.
        let p = covariance(3, 0.3);
        let c = vec![
            vec![facing_y(0, 0.25), facing_y(1, -0.05), facing_y(2, -1.05)],
            vec![facing_y(0, 0.55), facing_y(1, 0.25), facing_y(2, -0.75)],
            vec![facing_y(0, 1.55), facing_y(1, 1.25), facing_y(2, 0.25)],
        ];
        let alone: Vec<Decision> = c
            .iter()
            .map(|one| classifier().classify(std::slice::from_ref(one), &noise(1), &p)[0])
            .collect();
        assert_eq!(
            alone[..2],
            [Decision::Doubtful, Decision::Doubtful],
            "each alone is in doubt: {alone:?}"
        );
        // Together, through the pose they share, they are told apart.
        let together = classifier().classify(&c, &noise(3), &p);
        assert_eq!(
            together,
            [Decision::Match(0), Decision::Match(1), Decision::Match(2)]
        );
    }

    #[test]
    fn nothing_near_is_unknown() {
        let p = covariance(1, 0.02);
        let c = vec![vec![facing_y(0, 1.0)], vec![]];
        // 1 m off a wall known to 2 cm: gated out.
        assert_eq!(
            classifier().classify(&c, &noise(2), &p),
            [Decision::Unknown, Decision::Unknown]
        );
    }
}
