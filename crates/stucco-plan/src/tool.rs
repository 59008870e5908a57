//! The spray tool: a nozzle on a three-axis gantry carried by the robot (a
//! rail along the body, an arm across it, a lift), spraying to the left at
//! a wall or straight up at the ceiling, and the coat it is to lay.

use crate::PlanError;
use serde::{Deserialize, Serialize};

/// The spray tool and the coat, as a mission file's `[spray]` table gives
/// them. Positions are in the robot's frame: x forward of the rear axle,
/// y to the left of the centre line, z up from the floor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SprayTool {
    /// Travel of the nozzle along the body (the rail), m. It reaches past
    /// both ends of the body so the nozzle gets into corners.
    pub rail_m: [f64; 2],
    /// Travel across the body (the arm), m, left positive.
    pub arm_m: [f64; 2],
    /// Travel of the nozzle's height (the lift), m.
    pub lift_m: [f64; 2],
    /// Fastest each axis moves, m/s.
    pub axis_speed_mps: f64,
    /// Distance from the nozzle to a wall it sprays, m.
    pub wall_standoff_m: f64,
    /// Distance from the nozzle to the ceiling it sprays, m.
    pub ceiling_standoff_m: f64,
    /// Distance from the robot's centre line to a wall it plasters, m.
    pub robot_standoff_m: f64,
    /// Standard deviation of the footprint at the standoff, m (a cone: it
    /// grows in proportion to the distance).
    pub footprint_sigma_m: f64,
    /// Flow of plaster while spraying, litres per minute.
    pub flow_l_per_min: f64,
    /// The coat to lay, mm.
    pub thickness_mm: f64,
    /// Accepted deviation from the coat, as a share of it (0.1: ±10%).
    pub tolerance: f64,
    /// While spraying, the nozzle's aim stays this far outside an opening,
    /// m.
    pub spray_off_m: f64,
    /// Band around an opening left to be finished by hand (its reveal and
    /// bead), m: not plasterable, not counted.
    pub opening_margin_m: f64,
    /// Band along a surface's edges (corners, ceiling line) left to be
    /// finished by hand, m.
    pub edge_margin_m: f64,
    /// Height above the floor where a wall's plaster starts (behind the
    /// skirting board), m.
    pub skirting_m: f64,
    /// Closest the nozzle comes to a surface it is not spraying, m.
    pub surface_gap_m: f64,
    /// Clearance the body keeps from walls and obstacles, m.
    pub clearance_m: f64,
    /// How far the robot may stand from a station's pose: plans keep this
    /// much of the rail and arm spare at each end, m.
    pub position_tolerance_m: f64,
    /// Height of a door whose top the map does not know, m.
    pub door_head_m: f64,
    /// The carriage carries a range camera beside the nozzle: at each
    /// station the wall is looked at, spray off, before it is sprayed, and
    /// a window found there is kept out of the coat.
    pub camera: bool,
}

impl Default for SprayTool {
    /// A 10 L/min plaster pump laying a 10 mm coat through a nozzle with a
    /// 4 cm footprint 30 cm from the surface; axes at 0.5 m/s; a 1.1 m
    /// rail reaching 10 cm past each end of the Luleå tricycle's body.
    fn default() -> Self {
        SprayTool {
            rail_m: [-0.25, 0.85],
            arm_m: [-0.3, 0.9],
            lift_m: [0.02, 3.1],
            axis_speed_mps: 0.5,
            wall_standoff_m: 0.3,
            ceiling_standoff_m: 0.3,
            robot_standoff_m: 0.7,
            footprint_sigma_m: 0.04,
            flow_l_per_min: 10.0,
            thickness_mm: 10.0,
            tolerance: 0.1,
            spray_off_m: 0.03,
            opening_margin_m: 0.1,
            edge_margin_m: 0.11,
            skirting_m: 0.1,
            surface_gap_m: 0.02,
            clearance_m: 0.12,
            position_tolerance_m: 0.03,
            door_head_m: 2.1,
            camera: true,
        }
    }
}

impl SprayTool {
    /// Flow while spraying, m³/s.
    pub fn flow_m3ps(&self) -> f64 {
        self.flow_l_per_min / 60_000.0
    }

    /// The coat, m.
    pub fn thickness_m(&self) -> f64 {
        self.thickness_mm / 1000.0
    }

    /// Area one coat covers per second of spraying, m²/s.
    pub fn area_rate_m2ps(&self) -> f64 {
        self.flow_m3ps() / self.thickness_m()
    }

    /// Widest spacing of parallel strokes that still lays an even coat:
    /// 1.5 σ leaves a ripple of 3·10⁻⁴.
    pub fn stroke_spacing_m(&self) -> f64 {
        1.5 * self.footprint_sigma_m
    }

    /// Speed of a stroke that lays the coat over a band `width_m` wide.
    pub fn stroke_speed_mps(&self, width_m: f64) -> f64 {
        (self.area_rate_m2ps() / width_m).min(self.axis_speed_mps)
    }

    /// How far past the last stroke the coat is still within tolerance
    /// everywhere a stroke can end: where the plasterable area must stop
    /// short of what the nozzle reaches, m.
    pub fn ramp_m(&self) -> f64 {
        self.opening_margin_m - self.spray_off_m
    }

    /// The rail's travel a plan may use: its ends kept spare for the
    /// robot's position error, m.
    pub fn planned_rail_m(&self) -> [f64; 2] {
        [
            self.rail_m[0] + self.position_tolerance_m,
            self.rail_m[1] - self.position_tolerance_m,
        ]
    }

    /// The arm's travel a plan may use, m.
    pub fn planned_arm_m(&self) -> [f64; 2] {
        [
            self.arm_m[0] + self.position_tolerance_m,
            self.arm_m[1] - self.position_tolerance_m,
        ]
    }

    /// The nozzle's distance from the centre line at a wall, m.
    pub fn wall_arm_m(&self) -> f64 {
        self.robot_standoff_m - self.wall_standoff_m
    }

    /// Checks that the tool can lay the coat it is asked for; `body_width_m`
    /// is the robot's.
    pub fn validate(&self, body_width_m: f64) -> Result<(), PlanError> {
        let bad = |field: &'static str, why: String| Err(PlanError::Tool { field, why });
        for (field, range) in [
            ("rail_m", self.rail_m),
            ("arm_m", self.arm_m),
            ("lift_m", self.lift_m),
        ] {
            if range[0].partial_cmp(&range[1]) != Some(std::cmp::Ordering::Less) {
                return bad(field, format!("{range:?} is not an increasing range"));
            }
        }
        let positive = [
            ("axis_speed_mps", self.axis_speed_mps),
            ("wall_standoff_m", self.wall_standoff_m),
            ("ceiling_standoff_m", self.ceiling_standoff_m),
            ("footprint_sigma_m", self.footprint_sigma_m),
            ("flow_l_per_min", self.flow_l_per_min),
            ("thickness_mm", self.thickness_mm),
            ("tolerance", self.tolerance),
        ];
        for (field, x) in positive {
            if !(x > 0.0 && x.is_finite()) {
                return bad(field, format!("{x} must be positive"));
            }
        }
        let arm = self.wall_arm_m();
        if arm < body_width_m / 2.0 || arm > self.arm_m[1] {
            return bad(
                "robot_standoff_m",
                format!(
                    "puts the nozzle {arm:.2} m from the centre line; the arm reaches \
                     {:.2}..{:.2} m and the body is {:.2} m wide",
                    body_width_m / 2.0,
                    self.arm_m[1],
                    body_width_m
                ),
            );
        }
        let speed = self.area_rate_m2ps() / self.stroke_spacing_m();
        if speed > self.axis_speed_mps {
            return bad(
                "flow_l_per_min",
                format!(
                    "a {:.1} mm coat at this flow needs strokes at {speed:.2} m/s; the axes \
                     move at {:.2} m/s",
                    self.thickness_mm, self.axis_speed_mps
                ),
            );
        }
        // A stroke ending short of an opening must still lay the coat on
        // the plasterable edge: the ramp must span 1.28 σ (90%).
        if self.ramp_m() < 1.5 * self.footprint_sigma_m {
            return bad(
                "opening_margin_m",
                format!(
                    "leaves {:.3} m between where spraying stops and the plasterable edge; \
                     a {:.3} m footprint needs {:.3} m",
                    self.ramp_m(),
                    self.footprint_sigma_m,
                    1.5 * self.footprint_sigma_m
                ),
            );
        }
        let corner = self.surface_gap_m + self.position_tolerance_m;
        if self.edge_margin_m < corner + 1.5 * self.footprint_sigma_m {
            return bad(
                "edge_margin_m",
                format!(
                    "{:.3} m: the nozzle may stop {corner:.3} m from a corner, so a {:.3} m \
                     footprint needs {:.3} m",
                    self.edge_margin_m,
                    self.footprint_sigma_m,
                    corner + 1.5 * self.footprint_sigma_m
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn the_default_tool_lays_its_coat() {
        let t = SprayTool::default();
        t.validate(0.62).expect("valid");
        // 10 L/min at 10 mm: 1 m² a minute.
        assert!((t.area_rate_m2ps() * 60.0 - 1.0).abs() < 1e-12);
        assert!(t.stroke_speed_mps(t.stroke_spacing_m()) < t.axis_speed_mps);
    }

    #[test]
    fn a_tool_that_cannot_lay_its_coat_is_refused() {
        let fast = SprayTool {
            flow_l_per_min: 40.0,
            ..SprayTool::default()
        };
        let e = fast.validate(0.62).expect_err("too fast").to_string();
        assert!(e.contains("flow_l_per_min"), "{e}");
        let tight = SprayTool {
            opening_margin_m: 0.05,
            ..SprayTool::default()
        };
        let e = tight.validate(0.62).expect_err("margin").to_string();
        assert!(e.contains("opening_margin_m"), "{e}");
        let far = SprayTool {
            robot_standoff_m: 2.0,
            ..SprayTool::default()
        };
        assert!(far.validate(0.62).is_err());
    }
}
