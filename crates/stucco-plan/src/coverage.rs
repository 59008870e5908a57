//! Scores of a coat: how much of the plasterable area lies within the
//! thickness tolerance, how even it is, how much plaster went where it
//! should not. The same scores rate the planner's own prediction and the
//! simulator's deposition on the true surfaces.

use crate::{Plan, ReachMask, SprayTool, Surface, SurfaceId};
use serde::{Deserialize, Serialize};
use stucco_core::ThicknessGrid;

/// The scores of one surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceScore {
    /// The surface.
    pub surface: SurfaceId,
    /// Plasterable area the plan reaches: what is to be coated, m².
    pub plasterable_m2: f64,
    /// Plasterable area no station reaches, m².
    pub unreachable_m2: f64,
    /// Share of the plasterable area within tolerance of the coat, %.
    pub coverage_pct: f64,
    /// Share of the plasterable area thicker than the tolerance allows
    /// (what spraying a part twice leaves), %.
    pub over_pct: f64,
    /// Mean thickness over the plasterable area, mm.
    pub mean_mm: f64,
    /// Coefficient of variation of the thickness over the plasterable
    /// area.
    pub thickness_cv: f64,
    /// Plaster on the surface, litres.
    pub material_l: f64,
    /// Plaster in its doors and windows, litres.
    pub overspray_l: f64,
}

/// Scores `grid`, the coat on `surface`, counting only what `reach` says
/// the plan reaches.
pub fn score(
    surface: &Surface,
    grid: &ThicknessGrid,
    reach: &ReachMask,
    tool: &SprayTool,
) -> SurfaceScore {
    let target = tool.thickness_m();
    let (lo, hi) = (
        target * (1.0 - tool.tolerance),
        target * (1.0 + tool.tolerance),
    );
    let cell = grid.cell_area_m2();
    let (mut n, mut unreached, mut within, mut over) = (0usize, 0usize, 0usize, 0usize);
    let (mut sum, mut sum2, mut overspray) = (0.0, 0.0, 0.0);
    for (p, t) in grid.iter() {
        if surface.in_opening(p) {
            overspray += t * cell;
            continue;
        }
        if !surface.plasterable(p, tool) {
            continue;
        }
        if !reach.reaches(p) {
            unreached += 1;
            continue;
        }
        n += 1;
        sum += t;
        sum2 += t * t;
        if t >= lo && t <= hi {
            within += 1;
        } else if t > hi {
            over += 1;
        }
    }
    let nf = n.max(1) as f64;
    let mean = sum / nf;
    let var = (sum2 / nf - mean * mean).max(0.0);
    SurfaceScore {
        surface: surface.id,
        plasterable_m2: n as f64 * cell,
        unreachable_m2: unreached as f64 * cell,
        coverage_pct: 100.0 * within as f64 / nf,
        over_pct: 100.0 * over as f64 / nf,
        mean_mm: mean * 1000.0,
        thickness_cv: if mean > 0.0 { var.sqrt() / mean } else { 0.0 },
        material_l: grid.volume_m3() * 1000.0,
        overspray_l: overspray * 1000.0,
    }
}

/// The scores of a whole room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomScore {
    /// Walls' plasterable area within tolerance, %.
    pub wall_coverage_pct: f64,
    /// The ceiling's, %.
    pub ceiling_coverage_pct: f64,
    /// Plaster sprayed that landed in doors and windows, % of all sprayed.
    pub overspray_pct: f64,
    /// Coefficient of variation of the thickness over all plasterable
    /// area.
    pub thickness_cv: f64,
    /// Plasterable area thicker than the tolerance allows, %.
    pub over_pct: f64,
    /// Plaster sprayed, litres.
    pub sprayed_l: f64,
    /// Plasterable area no station reaches, m².
    pub unreachable_m2: f64,
    /// Each surface.
    pub surfaces: Vec<SurfaceScore>,
}

impl RoomScore {
    /// Sums the scores of the surfaces of a room where `sprayed_l` litres
    /// left the nozzle.
    pub fn of(surfaces: Vec<SurfaceScore>, sprayed_l: f64) -> RoomScore {
        let share = |pick: &dyn Fn(&SurfaceScore) -> bool, f: &dyn Fn(&SurfaceScore) -> f64| {
            let area: f64 = surfaces
                .iter()
                .filter(|s| pick(s))
                .map(|s| s.plasterable_m2)
                .sum();
            let weighted: f64 = surfaces
                .iter()
                .filter(|s| pick(s))
                .map(|s| f(s) * s.plasterable_m2)
                .sum();
            if area > 0.0 { weighted / area } else { 0.0 }
        };
        let walls = |s: &SurfaceScore| s.surface != SurfaceId::Ceiling;
        let ceiling = |s: &SurfaceScore| s.surface == SurfaceId::Ceiling;
        let all = |_: &SurfaceScore| true;
        // The CV of all cells together, from each surface's mean and CV.
        let area: f64 = surfaces.iter().map(|s| s.plasterable_m2).sum();
        let mean = share(&all, &|s| s.mean_mm);
        let second = share(&all, &|s| {
            let sd = s.thickness_cv * s.mean_mm;
            sd * sd + s.mean_mm * s.mean_mm
        });
        let cv = if mean > 0.0 && area > 0.0 {
            (second - mean * mean).max(0.0).sqrt() / mean
        } else {
            0.0
        };
        let overspray: f64 = surfaces.iter().map(|s| s.overspray_l).sum();
        RoomScore {
            wall_coverage_pct: share(&walls, &|s| s.coverage_pct),
            ceiling_coverage_pct: share(&ceiling, &|s| s.coverage_pct),
            overspray_pct: if sprayed_l > 0.0 {
                100.0 * overspray / sprayed_l
            } else {
                0.0
            },
            thickness_cv: cv,
            over_pct: share(&all, &|s| s.over_pct),
            sprayed_l,
            unreachable_m2: surfaces.iter().map(|s| s.unreachable_m2).sum(),
            surfaces,
        }
    }
}

/// The coat the plan itself predicts: every spraying move deposited at
/// the nominal standoff, one grid per surface in [`Plan::surfaces`] order.
pub fn predict(plan: &Plan) -> Vec<ThicknessGrid> {
    let mut grids: Vec<ThicknessGrid> = plan
        .surfaces
        .iter()
        .map(|s| ThicknessGrid::new(s.size_m(), crate::PLAN_CELL_M))
        .collect();
    let q = plan.tool.flow_m3ps();
    for (_, pass) in plan.passes() {
        let Some(k) = plan.surfaces.iter().position(|s| s.id == pass.surface) else {
            continue;
        };
        for m in pass.moves.iter().filter(|m| m.spray) {
            grids[k].deposit(
                m.from_m,
                m.to_m,
                q * m.duration_s(),
                plan.tool.footprint_sigma_m,
            );
        }
    }
    grids
}

/// The scores of the coat the plan predicts.
pub fn predicted_score(plan: &Plan) -> RoomScore {
    let grids = predict(plan);
    let scores = plan
        .surfaces
        .iter()
        .zip(&grids)
        .zip(&plan.reach)
        .map(|((s, g), r)| score(s, g, r, &plan.tool))
        .collect();
    RoomScore::of(scores, plan.spray_s() * plan.tool.flow_m3ps() * 1000.0)
}

/// The least area any plan must spray to lay the coat on the plasterable
/// area `plan` reaches, m²: that area, plus along each of its borders the
/// band a footprint of σ must spray past a border to leave the coat's
/// tolerance on it (a stroke ending `z₀σ` past the border, `Φ(z₀) = 1 −
/// tolerance`, lays `σ(φ(z₀) + z₀Φ(z₀))` of coat per metre of border
/// beyond it). At the tool's area rate, the spraying time no plan can
/// beat.
pub fn minimum_spray_m2(plan: &Plan) -> f64 {
    let tool = &plan.tool;
    let s = tool.footprint_sigma_m;
    let z0 = inverse_normal_cdf(1.0 - tool.tolerance);
    let phi = (-0.5 * z0 * z0).exp() / std::f64::consts::TAU.sqrt();
    let band = s * (phi + z0 * stucco_core::normal_cdf(z0));
    let mut total = 0.0;
    for (surface, reach) in plan.surfaces.iter().zip(&plan.reach) {
        let [nu, nv] = reach.cells;
        let c = reach.cell_m;
        let target = |i: i64, j: i64| {
            i >= 0
                && j >= 0
                && (i as usize) < nu
                && (j as usize) < nv
                && reach.reached[j as usize * nu + i as usize]
                && surface.plasterable([(i as f64 + 0.5) * c, (j as f64 + 0.5) * c], tool)
        };
        let (mut area, mut border) = (0.0, 0.0);
        for j in 0..nv as i64 {
            for i in 0..nu as i64 {
                if !target(i, j) {
                    continue;
                }
                area += c * c;
                for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    if !target(i + di, j + dj) {
                        border += c;
                    }
                }
            }
        }
        total += area + border * band;
    }
    total
}

/// `x` with `Φ(x) = p`, by bisection.
fn inverse_normal_cdf(p: f64) -> f64 {
    let (mut lo, mut hi) = (-10.0, 10.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if stucco_core::normal_cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inverse_of_the_normal_distribution() {
        for x in [-2.0, -0.3, 0.0, 1.2816, 2.5] {
            assert!((inverse_normal_cdf(stucco_core::normal_cdf(x)) - x).abs() < 1e-9);
        }
    }

    #[test]
    fn a_border_band_is_what_a_lone_stroke_end_lays_past_it() {
        // Strokes ending z0 σ past a border (the coat at 90% on it): the
        // plaster past the border, per metre, in coat-metres.
        let (s, tol) = (0.04, 0.1);
        let z0 = inverse_normal_cdf(1.0 - tol);
        let band = {
            let phi = (-0.5 * z0 * z0).exp() / std::f64::consts::TAU.sqrt();
            s * (phi + z0 * stucco_core::normal_cdf(z0))
        };
        // Numerically: ∫₀^∞ Φ((z0 σ − x)/σ) dx.
        let n = 200_000;
        let dx = 1.0 / n as f64;
        let numeric: f64 = (0..n)
            .map(|k| stucco_core::normal_cdf((z0 * s - (k as f64 + 0.5) * dx) / s) * dx)
            .sum();
        assert!((band - numeric).abs() < 1e-6, "{band} {numeric}");
    }
}
