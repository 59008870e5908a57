//! Plans the living room of the apartment and prints its stations and the
//! coat the plan predicts.

use stucco_core::{Pose2, VehicleSpec, WallName};
use stucco_plan::{OpeningKind, RoomModel, SprayTool, WallOpening, plan, predicted_score};

fn main() -> Result<(), stucco_plan::PlanError> {
    let room = RoomModel {
        size_m: [5.0, 2.85],
        corners: Vec::new(),
        height_m: 2.6,
        openings: vec![
            WallOpening {
                wall: WallName::SOUTH,
                kind: OpeningKind::Window,
                along_m: [2.0, 3.2],
                sill_head_m: [0.9, 2.1],
            },
            WallOpening {
                wall: WallName::EAST,
                kind: OpeningKind::Door,
                along_m: [1.0, 1.9],
                sill_head_m: [0.0, 2.0],
            },
        ],
        obstacles: Vec::new(),
    };
    let tool = SprayTool::default();
    let p = plan(
        &room,
        &tool,
        &VehicleSpec::default(),
        &Pose2::new(2.5, 1.4, 0.0),
    )?;
    for s in &p.stations {
        let t: f64 = s.passes.iter().map(|p| p.duration_s()).sum();
        println!(
            "{:?} at ({:.2}, {:.2}, {:.0}°): {} passes, {:.0} s",
            s.lane,
            s.base.x,
            s.base.y,
            s.base.theta.to_degrees(),
            s.passes.len(),
            t
        );
    }
    let score = predicted_score(&p);
    println!(
        "{}",
        serde_json::to_string_pretty(&score).unwrap_or_default()
    );
    for u in &p.unreachable {
        println!(
            "unreachable {:?}: {:.3} m² in {:?}",
            u.surface, u.area_m2, u.bounds
        );
    }
    Ok(())
}
