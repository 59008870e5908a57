//! The robot as its software sees it: its range camera and the whole
//! set of its sensors and drive (presets, not constants).

use crate::{LaserSpec, VehicleSpec};
use serde::{Deserialize, Serialize};

/// A range camera scanning a vertical fan of rays.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSpec {
    /// Name, the sensor id of its profiles.
    pub name: String,
    /// Heading of the fan's plane in the robot's frame, rad (π/2: left).
    pub azimuth_rad: f64,
    /// Lowest and highest elevation, rad.
    pub elevation_rad: [f64; 2],
    /// Rays in the fan.
    pub rays: usize,
    /// Profiles per second.
    pub rate_hz: f64,
    /// Height of the sensor above the floor, m.
    pub height_m: f64,
    /// Range noise, m (σ).
    pub range_sigma_m: f64,
    /// Longest range, m.
    pub max_range_m: f64,
}

impl CameraSpec {
    /// A camera on the spray tool's carriage, beside the nozzle, looking
    /// left at the wall the nozzle sprays: it profiles the wall before
    /// plaster is laid on it (its height is the nozzle's).
    pub fn on_tool() -> Self {
        CameraSpec {
            name: TOOL_CAMERA.to_owned(),
            ..CameraSpec::default()
        }
    }
}

/// The sensor id of the camera on the spray tool.
pub const TOOL_CAMERA: &str = "tool-camera";

impl Default for CameraSpec {
    /// Looking left, from 35° below the horizontal to straight up in 192
    /// rays (0.65° apart, as a line scanner turned on its side; at 96 rays,
    /// 1.3° apart, a window's head seen across a bedroom from 2.9 m came
    /// out 3–4.5 cm low, a ray's spacing there being 7 cm), 20 profiles a
    /// second.
    fn default() -> Self {
        CameraSpec {
            name: "range-camera".to_owned(),
            azimuth_rad: std::f64::consts::FRAC_PI_2,
            elevation_rad: [-0.6, std::f64::consts::FRAC_PI_2],
            rays: 192,
            rate_hz: 20.0,
            height_m: 1.0,
            range_sigma_m: 0.01,
            max_range_m: 8.0,
        }
    }
}

/// What a robot carries and how it drives: what its software must know of
/// it, whichever platform (the simulator, a real robot) it runs on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSpec {
    /// The vehicle, its limits and sensor mounts.
    pub vehicle: VehicleSpec,
    /// The horizontal laser.
    pub laser: LaserSpec,
    /// The range camera on the body, if it has one.
    pub camera: Option<CameraSpec>,
}

impl Default for RobotSpec {
    /// The papers' robot with the IBEO laser and a range camera looking
    /// left.
    fn default() -> Self {
        RobotSpec {
            vehicle: VehicleSpec::default(),
            laser: LaserSpec::ibeo_ladar_2d(),
            camera: Some(CameraSpec::default()),
        }
    }
}
