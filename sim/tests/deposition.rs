//! The sprayer lays its footprint on the true wall where the nozzle
//! points, conserves the plaster that leaves it, and counts what flies
//! into a window.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use stucco_core::{Aim, DriveCommand, Platform, ToolCommand};
use stucco_sim::{
    CameraSpec, Coat, SimConfig, Simulator, SprayerSpec, SurfaceKind, TOOL_CAMERA, WorldSpec,
};

const FLOW_M3PS: f64 = 10.0 / 60_000.0;

/// In the apartment's living room, 0.7 m north of its south wall, heading
/// west: the wall (and its window, x 1.8–3.2 m, 0.9–2.1 m high) on the
/// left.
fn sim() -> Simulator {
    sim_with(None)
}

fn sim_with(camera: Option<CameraSpec>) -> Simulator {
    let path = format!("{}/worlds/apartment.toml", env!("CARGO_MANIFEST_DIR"));
    let mut w = WorldSpec::load(Path::new(&path)).unwrap();
    w.robot.at = [3.0, 0.7];
    w.robot.heading_deg = 180.0;
    w.people.clear();
    let config = SimConfig {
        sprayer: Some(SprayerSpec {
            flow_m3ps: FLOW_M3PS,
            sigma_m: 0.04,
            sigma_at_m: 0.3,
            axis_speed_mps: 0.5,
            cell_m: 0.01,
            park_m: [0.3, 0.0, 1.0],
            camera,
        }),
        ..SimConfig::default()
    };
    let mut s = Simulator::new(&w, config, Some(1));
    s.command(DriveCommand::STOP);
    s
}

fn south(sim: &Simulator) -> &Coat {
    sim.coats()
        .iter()
        .find(|c| c.room == "living" && c.kind == SurfaceKind::Wall { index: 0 })
        .unwrap()
}

/// Volume, centroid and spread of the plaster on a coat.
fn moments(c: &Coat) -> (f64, [f64; 2], [f64; 2]) {
    let (mut m, mut su, mut sv, mut suu, mut svv) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (p, t) in c.grid.iter() {
        m += t;
        su += t * p[0];
        sv += t * p[1];
        suu += t * p[0] * p[0];
        svv += t * p[1] * p[1];
    }
    let (u, v) = (su / m, sv / m);
    let a = c.grid.cell_area_m2();
    (
        m * a,
        [u, v],
        [(suu / m - u * u).sqrt(), (svv / m - v * v).sqrt()],
    )
}

fn in_openings(c: &Coat) -> f64 {
    c.grid
        .iter()
        .filter(|(p, _)| {
            c.openings
                .iter()
                .any(|o| p[0] > o[0] && p[0] < o[1] && p[1] > o[2] && p[1] < o[3])
        })
        .map(|(_, t)| t)
        .sum::<f64>()
        * c.grid.cell_area_m2()
}

#[test]
fn a_standing_nozzle_lays_its_footprint_where_it_points() {
    let mut s = sim();
    // 0.3 m ahead of the rear axle and 0.4 m to its left: x = 2.7, 0.3 m
    // off the wall, 0.5 m up. The axes get there, then plaster flows 1 s.
    let at = ToolCommand {
        nozzle_m: [0.3, 0.4, 0.5],
        aim: Aim::Left,
        spray: false,
        flow_m3ps: None,
    };
    s.tool(at);
    s.advance(2.0);
    assert_eq!(s.tool_state().unwrap().nozzle_m, [0.3, 0.4, 0.5]);
    assert_eq!(s.sprayed_m3(), 0.0);
    s.tool(ToolCommand { spray: true, ..at });
    s.advance(1.0);
    s.tool(at);
    s.advance(0.1);
    assert!(
        (s.sprayed_m3() - FLOW_M3PS).abs() < 0.02 * FLOW_M3PS,
        "{}",
        s.sprayed_m3()
    );
    let (volume, centre, spread) = moments(south(&s));
    assert!((volume - s.sprayed_m3()).abs() < 1e-3 * volume, "{volume}");
    let pose = s.truth().drive.pose;
    let x = pose.transform_point(&nalgebra::Point2::new(0.3, 0.4)).x;
    assert!(
        (centre[0] - x).abs() < 1e-3 && (centre[1] - 0.5).abs() < 1e-3,
        "{centre:?}"
    );
    // σ at 0.3 m is 4 cm; the robot stands a hair off 0.7 m.
    for s in spread {
        assert!((s - 0.04).abs() < 0.002, "{spread:?}");
    }
    assert_eq!(in_openings(south(&s)), 0.0);
    // Nothing else was touched.
    let elsewhere: f64 = s
        .coats()
        .iter()
        .filter(|c| !(c.room == "living" && c.kind == SurfaceKind::Wall { index: 0 }))
        .map(|c| c.grid.volume_m3())
        .sum();
    assert_eq!(elsewhere, 0.0);
}

#[test]
fn a_stroke_up_into_the_window_counts_its_overspray() {
    let mut s = sim();
    let low = ToolCommand {
        nozzle_m: [0.3, 0.4, 0.3],
        aim: Aim::Left,
        spray: false,
        flow_m3ps: None,
    };
    s.tool(low);
    s.advance(2.0);
    // The lift moves at 0.5 m/s: from 0.3 m to 1.5 m in 2.4 s, spraying.
    s.tool(ToolCommand {
        nozzle_m: [0.3, 0.4, 1.5],
        spray: true,
        ..low
    });
    s.advance(1.0);
    let z = s.tool_state().unwrap().nozzle_m[2];
    assert!((z - 0.8).abs() < 0.011, "the lift at {z}");
    s.advance(1.6);
    let coat = south(&s);
    let window = in_openings(coat);
    // Half a second of the stroke ran over the window's 0.9–1.5 m.
    let total = coat.grid.volume_m3();
    assert!(
        window > 0.4 * total && window < 0.6 * total,
        "{window} of {total}"
    );
}

#[test]
fn the_ceiling_takes_what_is_sprayed_up() {
    let mut s = sim();
    let up = ToolCommand {
        nozzle_m: [0.3, 0.0, 2.3],
        aim: Aim::Up,
        spray: false,
        flow_m3ps: None,
    };
    s.tool(up);
    s.advance(3.0);
    s.tool(ToolCommand { spray: true, ..up });
    s.advance(0.5);
    let ceiling = s
        .coats()
        .iter()
        .find(|c| c.room == "living" && c.kind == SurfaceKind::Ceiling)
        .unwrap();
    let (volume, centre, _) = moments(ceiling);
    assert!((volume - s.sprayed_m3()).abs() < 1e-3 * volume, "{volume}");
    let p = s
        .truth()
        .drive
        .pose
        .transform_point(&nalgebra::Point2::new(0.3, 0.0));
    assert!((centre[0] - p.x).abs() < 1e-3 && (centre[1] - p.y).abs() < 1e-3);
}

#[test]
fn the_camera_on_the_tool_looks_from_where_the_nozzle_is() {
    // Facing west 0.7 m off the living room's south wall, the nozzle
    // 0.3 m off the wall in front of its window (x 1.8–3.2 m, sill 0.9 m,
    // head 2.1 m), 0.8 m up: the tool's camera meets the wall below the
    // sill at the nozzle's standoff and looks through the window above.
    let mut s = sim_with(Some(CameraSpec::on_tool()));
    s.tool(ToolCommand {
        nozzle_m: [0.3, 0.4, 0.8],
        aim: Aim::Left,
        spray: false,
        flow_m3ps: None,
    });
    s.advance(2.0);
    let p = loop {
        let r = s.advance(0.05);
        if let Some(p) = r.profiles.into_iter().find(|p| p.sensor == TOOL_CAMERA) {
            break p;
        }
    };
    assert_eq!(p.origin_m, [0.3, 0.4, 0.8]);
    let range_at = |el: f64| {
        let i = p
            .elevations_rad
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - el).abs().total_cmp(&(b.1 - el).abs()))
            .unwrap()
            .0;
        (p.elevations_rad[i], p.ranges_m[i])
    };
    let (el, r) = range_at(0.0);
    assert!((r * el.cos() - 0.3).abs() < 0.04, "{r} at {el}");
    // Aimed at 1.5 m on the wall: into the window, past its reveal.
    let (el, r) = range_at((0.7_f64 / 0.3).atan());
    assert!(!r.is_finite() || r * el.cos() > 0.3 + 0.35, "{r} at {el}");
    // The camera on the body is where it always was.
    let body = loop {
        let r = s.advance(0.05);
        if let Some(p) = r.profiles.into_iter().find(|p| p.sensor != TOOL_CAMERA) {
            break p;
        }
    };
    assert_eq!(body.origin_m, [0.0, 0.0, CameraSpec::default().height_m]);
}

#[test]
fn a_command_with_its_own_flow_sprays_that_flow() {
    // A task's own spray settings (a second coat at another flow): the
    // sprayer lays what the command says, not its own flow.
    let mut s = sim();
    let at = ToolCommand {
        nozzle_m: [0.3, 0.4, 0.5],
        aim: Aim::Left,
        spray: false,
        flow_m3ps: Some(0.6 * FLOW_M3PS),
    };
    s.tool(at);
    s.advance(2.0);
    s.tool(ToolCommand { spray: true, ..at });
    s.advance(1.0);
    s.tool(at);
    s.advance(0.1);
    assert!(
        (s.sprayed_m3() - 0.6 * FLOW_M3PS).abs() < 0.02 * FLOW_M3PS,
        "{}",
        s.sprayed_m3()
    );
    let (volume, _, _) = moments(south(&s));
    assert!((volume - s.sprayed_m3()).abs() < 1e-3 * volume, "{volume}");
}
