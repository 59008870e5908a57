//! People in the simulator walk round the robot: a person whose way runs
//! into a standing robot waits short of it, then turns back; one the
//! robot comes at steps out of its way.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use stucco_core::{DriveCommand, Platform};
use stucco_sim::{SimConfig, Simulator, WorldSpec};

/// An 8 × 3 m room, the robot `at` heading `heading_deg`, and one person
/// walking `path` at `speed_mps`.
fn room_with_person(
    seed: u64,
    at: &str,
    heading_deg: f64,
    path: &str,
    speed_mps: f64,
) -> WorldSpec {
    let text = format!(
        "name = \"p\"\nseed = {seed}\n[robot]\nat = {at}\nheading_deg = {heading_deg:?}\n\
         [[room]]\nname = \"r\"\ncorners = [[0.0, 0.0], [8.0, 0.0], [8.0, 3.0], [0.0, 3.0]]\n\
         [[person]]\npath = {path}\nspeed_mps = {speed_mps:?}\n"
    );
    WorldSpec::parse(&text, "p").unwrap()
}

#[test]
fn a_person_walking_at_the_standing_robot_waits_then_turns_back() {
    let world =
        |seed: u64| room_with_person(seed, "[2.0, 1.5]", 0.0, "[[7.5, 1.5], [0.5, 1.5]]", 1.0);
    // The first seed whose person starts east of the robot walking west,
    // at it (each person starts somewhere along their path).
    let mut sim = (1..100)
        .map(|seed| Simulator::new(&world(seed), SimConfig::default(), None))
        .find(|sim| {
            let p = sim.truth().people[0];
            p.x > 4.0 && p.theta.cos() < 0.0
        })
        .unwrap();
    sim.command(DriveCommand::STOP);
    let mut nearest = f64::INFINITY;
    let mut xs = Vec::new();
    for _ in 0..600 {
        let r = sim.advance(0.05);
        assert!(
            !r.bumper,
            "the person walked into the robot at {:?}",
            sim.truth().people[0]
        );
        let p = sim.truth().people[0];
        // The robot's body spans x 1.85–2.75, y 1.19–1.81.
        let dx = (1.85 - p.x).max(p.x - 2.75).max(0.0);
        let dy = (1.19 - p.y).max(p.y - 1.81).max(0.0);
        nearest = nearest.min(dx.hypot(dy));
        xs.push(p.x);
    }
    assert!(nearest > 0.3, "came within {nearest} m");
    // It stood a while short of the robot, then walked away from it.
    let waited = xs.windows(2).filter(|w| (w[1] - w[0]).abs() < 1e-9).count();
    assert!(
        waited as f64 * 0.05 >= 4.0,
        "waited {} s",
        waited as f64 * 0.05
    );
    assert!(
        xs.windows(2).any(|w| w[1] - w[0] > 0.01),
        "never turned back"
    );
}

/// A robot backing (its laser looks ahead: it does not see them) at a
/// person who stands short of it steps them out of its way: they are not
/// touched, and go back to their path once it is off.
#[test]
fn a_person_the_robot_backs_at_steps_out_of_its_way() {
    let world = room_with_person(1, "[4.0, 1.5]", 180.0, "[[7.5, 1.5], [5.5, 1.5]]", 0.8);
    let mut sim = Simulator::new(&world, SimConfig::default(), None);
    // Backing east along the person's path, 3.4 m: its rear ends 35 cm
    // short of the wall, past the path's end.
    sim.command(DriveCommand {
        speed_mps: -0.3,
        steer_rad: 0.0,
    });
    let mut off_path = 0.0f64;
    for k in 0..227 {
        let r = sim.advance(0.05);
        assert!(
            !r.bumper,
            "the robot backed into the person at {:?} after {:.2} s",
            sim.truth().people[0],
            k as f64 * 0.05
        );
        let p = sim.truth().people[0];
        let along = p.x.clamp(5.5, 7.5);
        off_path = off_path.max((p.x - along).hypot(p.y - 1.5));
    }
    assert!(off_path > 0.2, "stepped {off_path:.2} m off the path");
    // The robot drives off west; the person goes back to their path.
    sim.command(DriveCommand {
        speed_mps: 0.5,
        steer_rad: 0.0,
    });
    for _ in 0..200 {
        sim.advance(0.05);
    }
    sim.command(DriveCommand::STOP);
    for _ in 0..200 {
        sim.advance(0.05);
    }
    let p = sim.truth().people[0];
    assert!((p.y - 1.5).abs() < 1e-6, "{p:?}");
}

/// A person a robot backed at along a hall, who stepped out of its way
/// (back along the hall: it is too narrow to pass), walks on when the
/// robot then stays (it waits for them: they stand in its field), the way
/// along their path that leads off it; they do not stand by it for good.
#[test]
fn a_person_stood_aside_by_a_robot_that_stays_walks_on() {
    let world = |seed: u64| {
        let text = format!(
            "name = \"hall\"\nseed = {seed}\n[robot]\nat = [4.0, 0.6]\nheading_deg = 0.0\n\
             [[room]]\nname = \"hall\"\ncorners = [[0.0, 0.0], [8.0, 0.0], [8.0, 1.2], [0.0, 1.2]]\n\
             [[person]]\npath = [[0.5, 0.6], [7.5, 0.6]]\nspeed_mps = 0.8\n"
        );
        WorldSpec::parse(&text, "hall").unwrap()
    };
    // The first seed whose person starts west of the robot walking east,
    // at its back.
    let mut sim = (1..100)
        .map(|seed| Simulator::new(&world(seed), SimConfig::default(), None))
        .find(|sim| {
            let p = sim.truth().people[0];
            p.x < 2.5 && p.theta.cos() > 0.0
        })
        .unwrap();
    let near = |sim: &Simulator| {
        let (p, r) = (sim.truth().people[0], sim.truth().drive.pose);
        (p.x - r.x).hypot(p.y - r.y)
    };
    // Standing till they wait at its back, then backing at them a
    // second, then standing.
    sim.command(DriveCommand::STOP);
    let mut k = 0;
    while near(&sim) > 1.0 {
        sim.advance(0.05);
        k += 1;
        assert!(k < 400, "never came near: {:?}", sim.truth().people[0]);
    }
    sim.command(DriveCommand {
        speed_mps: -0.3,
        steer_rad: 0.0,
    });
    for _ in 0..20 {
        sim.advance(0.05);
    }
    sim.command(DriveCommand::STOP);
    let mut stood_by = 0;
    for _ in 0..600 {
        let r = sim.advance(0.05);
        assert!(!r.bumper, "touched at {:?}", sim.truth().people[0]);
        if near(&sim) < 0.9 {
            stood_by += 1;
        }
    }
    assert!(
        (stood_by as f64) * 0.05 < 15.0,
        "stood by the robot {:.1} s of 30",
        stood_by as f64 * 0.05
    );
}
