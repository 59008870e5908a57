//! Corridor centring at 0.8 m/s (paper A §4.1) in the simulator: the robot
//! drives the 20 m corridor, doors open and closed on both sides, its pose
//! and the corridor's width from the room filter, the papers' line law on
//! the middle; the lateral offset from the true middle is scored over the
//! settled stretch.

use crate::closed_loop::Navigator;
use std::path::Path;
use stucco_control::{GainSchedule, LineFollower};
use stucco_nav::RoomState;
use stucco_sim::WorldSpec;

/// Lateral offsets from the corridor's true middle (y = 1) while the rear
/// axle runs from x = 6 to x = 16.
fn run(seed: u64) -> Vec<f64> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../sim/worlds/corridor.toml");
    let mut world = WorldSpec::load(Path::new(path)).unwrap();
    world.robot.at = [1.5, 0.75];
    world.robot.heading_deg = 5.0;
    let x0 = RoomState::new(1.52, 0.73, 0.1, 19.5, 2.1);
    let mut nav = Navigator::new(&world, seed, x0, [0.5, 0.1]);
    let law = LineFollower::new(GainSchedule::default());
    let mut out = Vec::new();
    for _ in 0..2000 {
        let x = nav.estimate();
        let now = nav.step(0.8, law.steer(x[1] - 0.5 * x[4], x[2], 0.8));
        if now.x > 16.0 {
            break;
        }
        if now.x > 6.0 {
            out.push(now.y - 1.0);
        }
    }
    out
}

#[test]
fn corridor_centring_at_08_mps_within_5_mm() {
    let mut all = Vec::new();
    for seed in 0..3 {
        let r = run(seed);
        assert!(r.len() > 500, "only {} samples", r.len());
        all.extend(r);
    }
    let m = all.iter().sum::<f64>() / all.len() as f64;
    let sd = (all.iter().map(|x| (x - m).powi(2)).sum::<f64>() / all.len() as f64).sqrt();
    println!(
        "corridor at 0.8 m/s: lateral σ {:.1} mm, mean {:+.1} mm over {} samples",
        sd * 1e3,
        m * 1e3,
        all.len()
    );
    assert!(sd <= 0.005, "σ {sd} m");
}
