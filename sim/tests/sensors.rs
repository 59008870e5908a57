//! The range camera sees wall, ceiling and a window's hole; the faults a
//! configuration injects reach the robot's software as configured.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use stucco_core::{DriveCommand, Platform, RangeProfile};
use stucco_sim::{
    FaultConfig, Interval, SimConfig, Simulator, StuckEncoder, TOOL_CAMERA, WorldSpec,
};

fn world_at(name: &str, at: [f64; 2], heading_deg: f64) -> WorldSpec {
    let path = format!("{}/worlds/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let mut w = WorldSpec::load(Path::new(&path)).unwrap();
    w.robot.at = at;
    w.robot.heading_deg = heading_deg;
    w.people.clear();
    w
}

fn first_profile(sim: &mut Simulator) -> RangeProfile {
    loop {
        if let Some(p) = sim.advance(0.01).profiles.into_iter().next() {
            return p;
        }
    }
}

/// Range of the ray of `p` nearest elevation `el`.
fn at_elevation(p: &RangeProfile, el: f64) -> f64 {
    let i = p
        .elevations_rad
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - el).abs().total_cmp(&(b.1 - el).abs()))
        .unwrap()
        .0;
    p.ranges_m[i]
}

#[test]
fn the_camera_sees_the_wall_up_to_the_ceiling() {
    // In the corridor (2 m wide, 2.7 m high), facing east at y = 1: the
    // camera (1 m up) looks north at the wall 1 m away.
    let w = world_at("corridor", [10.0, 1.0], 0.0);
    let mut sim = Simulator::new(&w, SimConfig::default(), Some(1));
    let p = first_profile(&mut sim);
    let mut wall = 0;
    let mut ceiling = 0;
    for (el, r) in p.elevations_rad.iter().zip(&p.ranges_m) {
        let (horizontal, up) = (r * el.cos(), 1.0 + r * el.sin());
        if (horizontal - 1.0).abs() < 0.04 && up < 2.7 + 0.04 {
            wall += 1;
        } else if (up - 2.7).abs() < 0.04 {
            ceiling += 1;
        }
    }
    assert!(
        wall >= 40 && ceiling >= 10,
        "wall {wall}, ceiling {ceiling} of {}",
        p.ranges_m.len()
    );
}

#[test]
fn the_camera_sees_through_a_window() {
    // In the apartment's living room, 1 m from the south wall, facing west:
    // the camera looks south at the window (sill 0.9 m, head 2.1 m).
    let w = world_at("apartment", [2.5, 1.0], 180.0);
    let mut sim = Simulator::new(&w, SimConfig::default(), Some(1));
    let p = first_profile(&mut sim);
    let low = at_elevation(&p, -0.5); // meets the radiator under the sill
    assert!(
        (low * (-0.5f64).cos() - 0.9).abs() < 0.05,
        "low ray at {low}"
    );
    let level = at_elevation(&p, 0.2); // through the window
    assert!(level > 1.5, "the window's hole is seen through: {level}");
    let high = at_elevation(&p, 1.0); // the wall above the head
    assert!(
        (high * 1.0f64.cos() - 1.0).abs() < 0.05,
        "high ray at {high}"
    );
}

/// What a run delivered: scans, encoder counts (left, right), each scan's
/// lateness, and each scan's range straight ahead.
struct Run {
    scans: usize,
    ticks: Vec<(i64, i64)>,
    late_s: Vec<f64>,
    ahead_m: Vec<f64>,
}

fn run(faults: FaultConfig, seconds: f64) -> Run {
    let w = world_at("reference-room", [1.5, 1.3], 0.0);
    let cfg = SimConfig {
        faults,
        ..SimConfig::default()
    };
    let mut sim = Simulator::new(&w, cfg, Some(4));
    sim.command(DriveCommand {
        speed_mps: 0.2,
        steer_rad: 0.0,
    });
    let (mut scans, mut ticks, mut arrival, mut first) = (0, vec![], vec![], vec![]);
    for _ in 0..(seconds / 0.01) as usize {
        let r = sim.advance(0.01);
        for s in &r.scans {
            arrival.push(sim.now().as_secs_f64() - s.stamp.as_secs_f64());
            first.push(s.ranges_m[225]);
        }
        scans += r.scans.len();
        ticks.extend(r.encoders.iter().map(|e| (e.left_ticks, e.right_ticks)));
    }
    Run {
        scans,
        ticks,
        late_s: arrival,
        ahead_m: first,
    }
}

#[test]
fn faults_reach_the_robot_as_configured() {
    let Run {
        scans,
        ticks,
        late_s: arrival,
        ahead_m: ahead,
    } = run(FaultConfig::default(), 2.0);
    assert_eq!(
        scans, 16,
        "8 Hz over 2 s: the last sweep, from 1.875 s, ends at 1.97 s"
    );
    assert!(arrival.iter().all(|&a| a < 0.11), "{arrival:?}");
    // Dropped scans.
    let none = run(
        FaultConfig {
            scan_drop_probability: 1.0,
            ..FaultConfig::default()
        },
        2.0,
    )
    .scans;
    assert_eq!(none, 0);
    // Delayed scans: each arrives 0.5 s after its stamp (plus the sweep).
    let late = run(
        FaultConfig {
            scan_delay_s: 0.5,
            ..FaultConfig::default()
        },
        2.0,
    )
    .late_s;
    assert!(late.iter().all(|&a| (0.5..0.52).contains(&a)), "{late:?}");
    // Spurious echoes: every beam short of the surface (up to its noise),
    // and well short on average.
    let short = run(
        FaultConfig {
            spurious_return_probability: 1.0,
            ..FaultConfig::default()
        },
        2.0,
    )
    .ahead_m;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(
        short.iter().zip(&ahead).all(|(s, t)| *s < t + 0.1) && mean(&short) < mean(&ahead) - 0.1,
        "{short:?} vs {ahead:?}"
    );
    // A stuck left encoder from 0.5 s to 1.5 s.
    let stuck = run(
        FaultConfig {
            stuck_encoder: Some(StuckEncoder {
                wheel: 0,
                from_s: 0.5,
                until_s: 1.5,
            }),
            ..FaultConfig::default()
        },
        2.0,
    )
    .ticks;
    let (during, after) = (&stuck[30..70], &stuck[80..]);
    assert!(during.windows(2).all(|w| w[0].0 == w[1].0), "left froze");
    assert!(
        during.first().unwrap().1 < during.last().unwrap().1,
        "right kept counting"
    );
    assert!(
        after.last().unwrap().0 > during.last().unwrap().0,
        "left counts again"
    );
    assert_eq!(ticks.len(), stuck.len());
}

#[test]
fn glass_returns_only_near_normal_incidence() {
    // At the corridor's east end, facing south: the camera looks east at
    // the glazed window (sill 0.9 m, head 2.1 m) 1 m away.
    let w = world_at("corridor", [19.0, 1.0], -90.0);
    let mut sim = Simulator::new(&w, SimConfig::default(), Some(1));
    let p = first_profile(&mut sim);
    let square = at_elevation(&p, 0.0);
    assert!(
        (square - 1.075).abs() < 0.04,
        "the pane, mid-wall: {square}"
    );
    let slanted = at_elevation(&p, 0.35); // 20° off the pane's normal
    assert!(slanted > 3.0, "the beam passes the glass: {slanted}");
}

#[test]
fn a_stalled_drive_rolls_to_a_stop_and_a_stuck_steering_holds() {
    let w = world_at("reference-room", [1.5, 1.3], 0.0);
    let faults = FaultConfig {
        stalled_drive: Some(Interval {
            from_s: 1.0,
            until_s: 2.0,
        }),
        stuck_steering: Some(Interval {
            from_s: 0.0,
            until_s: 3.0,
        }),
        ..FaultConfig::default()
    };
    let mut sim = Simulator::new(
        &w,
        SimConfig {
            faults,
            ..SimConfig::default()
        },
        Some(2),
    );
    sim.command(DriveCommand {
        speed_mps: 0.3,
        steer_rad: 0.5,
    });
    sim.advance(1.0);
    let moving = sim.truth().drive;
    assert!(
        moving.wheel_speed_mps > 0.29 && moving.steer_rad == 0.0,
        "{moving:?}"
    );
    sim.advance(0.9);
    let stalled = sim.truth().drive;
    assert!(stalled.wheel_speed_mps.abs() < 1e-9, "{stalled:?}");
    sim.advance(1.5);
    let after = sim.truth().drive;
    assert!(
        after.steer_rad > 0.4 && after.wheel_speed_mps > 0.29,
        "{after:?}"
    );
}

/// Each profile is shot from where the robot is at its stamp, not where a
/// physics step leaves it: pivoting at about 1 rad/s in the corridor, the
/// camera's reach to the north wall along its fan is the one the pose at
/// the stamp gives (10 ms later the turn has moved it by 7 mm or more).
#[test]
fn a_profile_is_shot_from_where_the_robot_is_at_its_stamp() {
    use std::f64::consts::FRAC_PI_2;
    let w = world_at("corridor", [9.0, 1.0], 0.0);
    let mut sim = Simulator::new(&w, SimConfig::default(), Some(1));
    sim.command(DriveCommand {
        speed_mps: 0.6,
        steer_rad: FRAC_PI_2,
    });
    let mut poses = std::collections::BTreeMap::new();
    poses.insert(0, sim.truth().drive.pose);
    // The north wall (y = 2) along the fan, from a camera at the pose.
    let reach = |p: &stucco_core::Pose2| (2.0 - p.y) / (p.theta + FRAC_PI_2).sin();
    let (mut checked, mut moved) = (0, f64::INFINITY);
    // The mean of some 90 rays' reach, each with the camera's 1 cm noise.
    const TOLERANCE_M: f64 = 0.003;
    for _ in 0..150 {
        let r = sim.advance(0.01);
        let truth = sim.truth();
        poses.insert(truth.stamp.as_nanos(), truth.drive.pose);
        for p in r.profiles.iter().filter(|p| p.sensor != TOOL_CAMERA) {
            let at = poses[&p.stamp.as_nanos()];
            if !(0.5..1.0).contains(&at.theta) {
                continue;
            }
            let on_wall: Vec<f64> = p
                .elevations_rad
                .iter()
                .zip(&p.ranges_m)
                .filter(|(e, r)| r.is_finite() && (0.2..2.5).contains(&(1.0 + *r * e.sin())))
                .map(|(e, r)| r * e.cos())
                .collect();
            assert!(on_wall.len() > 50, "{} rays on the wall", on_wall.len());
            let mean = on_wall.iter().sum::<f64>() / on_wall.len() as f64;
            assert!(
                (mean - reach(&at)).abs() < TOLERANCE_M,
                "reach {mean:.4} m, {:.4} m from the pose at the stamp",
                reach(&at)
            );
            let later = poses[&(p.stamp.as_nanos() + 10_000_000)];
            moved = moved.min((reach(&later) - reach(&at)).abs());
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked} profiles in the turn");
    // Shot 10 ms late, every profile would have been outside the tolerance.
    assert!(
        moved > 2.0 * TOLERANCE_M,
        "the turn moved the reach {moved} m in 10 ms"
    );
}
