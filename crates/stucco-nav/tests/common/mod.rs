//! Helpers shared by the tests and benches of stucco-nav.

pub mod flaser;

use stucco_core::LaserSpec;
use stucco_nav::{DoorConfig, RwhtConfig};

/// Extraction tuned to the SICK scanners of the CARMEN logs, as `stucco
/// walls` runs it.
pub fn log_settings() -> (RwhtConfig, DoorConfig) {
    let laser = LaserSpec {
        range_sigma_m: 0.015,
        ..LaserSpec::sick_lms291()
    };
    (RwhtConfig::for_laser(&laser), DoorConfig::for_laser(&laser))
}
