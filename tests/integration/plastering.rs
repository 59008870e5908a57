//! Plastering in the simulator: the apartment's living room
//! (`missions/living-room.toml`): mapped, surveyed, planned on what the
//! robot found, sprayed, and scored on the true walls and ceiling against
//! ACCEPTANCE.md; and the same job killed halfway and resumed from its
//! checkpoint, spraying nothing twice.

use std::path::{Path, PathBuf};
use stucco_cli::{MissionReport, TaskMissionJob, run_task_mission};
use stucco_core::WallName;
use stucco_plan::SurfaceId;

fn mission(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../missions/{name}.toml"))
}

fn run(out: &Path, resume: bool, stop_after_s: Option<f64>) -> MissionReport {
    run_file("living-room", out, resume, stop_after_s)
}

fn run_file(name: &str, out: &Path, resume: bool, stop_after_s: Option<f64>) -> MissionReport {
    let s = run_task_mission(
        &TaskMissionJob {
            mission: mission(name),
            seed: None,
            runs: None,
            out: Some(out.to_owned()),
            resume,
            stop_after_s,
            record: false,
        },
        &|_, _| {},
    )
    .unwrap();
    s.runs.into_iter().next().unwrap()
}

/// The scores of ACCEPTANCE.md's plastering table, windows with them.
fn assert_targets(r: &MissionReport) {
    assert_coat_targets(r);
    assert_eq!(r.windows_found, r.windows_total);
    assert!(r.windows_total >= 1);
    let edge = r.window_edge_err_max_m.unwrap();
    assert!(edge <= 0.02, "window edges {edge}");
}

/// The coat's scores of ACCEPTANCE.md's plastering table.
fn assert_coat_targets(r: &MissionReport) {
    let pct = |x: Option<f64>| x.unwrap();
    assert!(
        pct(r.wall_coverage_pct) >= 99.5,
        "walls {:?}",
        r.wall_coverage_pct
    );
    assert!(
        pct(r.ceiling_coverage_pct) >= 99.0,
        "ceiling {:?}",
        r.ceiling_coverage_pct
    );
    assert!(
        pct(r.overspray_pct) <= 0.5,
        "overspray {:?}",
        r.overspray_pct
    );
    assert!(pct(r.thickness_cv) <= 0.08, "CV {:?}", r.thickness_cv);
    assert!(
        pct(r.double_sprayed_pct) <= 1.0,
        "twice {:?}",
        r.double_sprayed_pct
    );
}

/// What the sofa hides is reported, never silently dropped: by the plan,
/// and on the truth as blocked by it.
fn assert_sofa_reported(r: &MissionReport) {
    let plaster = r.plaster.as_ref().unwrap();
    assert!(plaster.unreachable_m2 > 5.0, "{}", plaster.unreachable_m2);
    let truth = plaster.truth.as_ref().unwrap();
    let sofa: f64 = truth
        .blockers
        .iter()
        .filter(|b| b.what == Some("box") && b.at_m == Some([0.45, 1.5]))
        .map(|b| b.area_m2)
        .sum();
    // The whole west wall behind it (2.85 × 2.6 m less its bands) at
    // least: the arm cannot reach over its 0.8 m depth.
    assert!(sofa > 6.0, "{:?}", truth.blockers);
}

/// Every true plasterable surface of the rooms the job names is counted:
/// covered, blocked or unreached, and the top-level figures are the
/// truth's.
fn assert_truth_accounts(r: &MissionReport, rooms: &[&str]) {
    let truth = r.plaster.as_ref().unwrap().truth.as_ref().unwrap();
    assert_eq!(truth.rooms, rooms);
    for t in [&truth.walls, &truth.ceilings] {
        let sum = t.covered_m2 + t.blocked_m2 + t.unreached_m2;
        assert!((sum - t.plasterable_m2).abs() < 1e-6, "{t:?}");
    }
    let surfaces: f64 = truth.surfaces.iter().map(|s| s.tally.plasterable_m2).sum();
    assert!((surfaces - truth.walls.plasterable_m2 - truth.ceilings.plasterable_m2).abs() < 1e-6);
    assert_eq!(r.true_wall_coverage_pct, truth.walls.coverage_pct());
    assert_eq!(r.true_ceiling_coverage_pct, truth.ceilings.coverage_pct());
    let blocked = truth.walls.blocked_m2 + truth.ceilings.blocked_m2;
    assert!((r.blocked_m2.unwrap() - blocked).abs() < 1e-9);
    let unreached = truth.walls.unreached_m2 + truth.ceilings.unreached_m2;
    assert!((r.unreached_m2.unwrap() - unreached).abs() < 1e-9);
    eprintln!(
        "{rooms:?} on the truth: walls {:.2}%, ceiling {:.2}% of the reachable; \
         {unreached:.2} m² unreached, {blocked:.2} m² blocked; of {:.1} m² plasterable",
        truth.walls.coverage_pct().unwrap_or(f64::NAN),
        truth.ceilings.coverage_pct().unwrap_or(f64::NAN),
        truth.walls.plasterable_m2 + truth.ceilings.plasterable_m2
    );
}

#[test]
fn the_living_room_is_plastered_within_the_targets() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(dir.path(), false, None);
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    assert_targets(&r);
    assert_sofa_reported(&r);
    assert_truth_accounts(&r, &["living"]);
    let (t, bound) = (
        r.mission_time_s.unwrap(),
        r.mission_time_lower_bound_s.unwrap(),
    );
    assert!(t <= 1.25 * bound, "{t} s against a bound of {bound} s");
    for name in [
        "coat-wall1.svg",
        "coat-ceiling.svg",
        "plan.json",
        "world.json",
    ] {
        assert!(dir.path().join(name).exists(), "{name}");
    }
}

#[test]
fn a_plastering_run_killed_and_resumed_sprays_nothing_twice() {
    let dir = tempfile::tempdir().unwrap();
    // Killed while spraying the second wall.
    let first = run(dir.path(), false, Some(1200.0));
    assert_eq!(first.outcome, "stopped");
    let cp: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("checkpoint.json")).unwrap())
            .unwrap();
    let station = cp["progress"]["plaster"]["cursor"]["station"]
        .as_u64()
        .unwrap();
    assert!(station > 0, "{cp}");
    // The window the camera found before the kill is kept: the resumed
    // run does not drive the survey loop again.
    assert!(
        cp["map"]["windows"]
            .as_array()
            .is_some_and(|w| w.iter().any(|w| w[0] == 1)),
        "{cp}"
    );
    let resumed = run(dir.path(), true, None);
    assert_eq!(resumed.outcome, "done", "{:?}", resumed.reason);
    assert_eq!(resumed.first_task, 2);
    // The whole job's coat: the first run's plaster stayed on the walls.
    assert_targets(&resumed);
    assert_sofa_reported(&resumed);
    // And the whole job's time, which no run beats its bound in: the part
    // before the kill counts too (the resumed part alone is about 60 %
    // of the bound).
    let (t, bound) = (
        resumed.mission_time_s.unwrap(),
        resumed.mission_time_lower_bound_s.unwrap(),
    );
    assert!(
        (bound..=1.25 * bound).contains(&t),
        "{t} s against a bound of {bound} s"
    );
}

/// The reference room (`missions/reference-plaster.toml`): plastered
/// round the table in its middle within every target; the way between
/// stations on either side of the table goes round it.
#[test]
fn the_reference_room_is_plastered_round_its_table_within_the_targets() {
    let dir = tempfile::tempdir().unwrap();
    let r = run_file("reference-plaster", dir.path(), false, None);
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    assert_coat_targets(&r);
    let pct = |x: Option<f64>| x.unwrap();
    let (t, bound) = (pct(r.mission_time_s), pct(r.mission_time_lower_bound_s));
    assert!(t <= 1.25 * bound, "{t} s against a bound of {bound} s");
    eprintln!(
        "reference room: walls {:.2}%, ceiling {:.2}%, overspray {:.3}%, CV {:.2}%, \
         {t:.0} s against {bound:.0} s ({:.3})",
        pct(r.wall_coverage_pct),
        pct(r.ceiling_coverage_pct),
        pct(r.overspray_pct),
        100.0 * pct(r.thickness_cv),
        t / bound
    );
}

/// The two-room job (`missions/two-offices.toml`): from the corridor into
/// office A, mapped and plastered round its table and window, through
/// the door between the offices into B, mapped and plastered round its
/// cabinet; both rooms within every target, scored on the true walls of
/// each, the mission time against the sum of both rooms' bounds.
#[test]
fn two_offices_are_plastered_one_after_the_other_within_the_targets() {
    let dir = tempfile::tempdir().unwrap();
    let r = run_file("two-offices", dir.path(), false, None);
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    assert_targets(&r);
    let rooms: Vec<&str> = r
        .plaster
        .as_ref()
        .unwrap()
        .rooms
        .iter()
        .map(|p| p.room.as_str())
        .collect();
    assert_eq!(rooms, ["office-a", "office-b"]);
    for p in &r.plaster.as_ref().unwrap().rooms {
        for s in &p.surfaces {
            assert!(s.coverage_pct >= 99.5, "{}: {s:?}", p.room);
        }
    }
    let (t, bound) = (
        r.mission_time_s.unwrap(),
        r.mission_time_lower_bound_s.unwrap(),
    );
    assert!(t <= 1.25 * bound, "{t} s against a bound of {bound} s");
    for name in ["coat-office-a-wall3.svg", "coat-office-b-ceiling.svg"] {
        assert!(dir.path().join(name).exists(), "{name}");
    }
    eprintln!(
        "two offices: walls {:.2}%, ceiling {:.2}%, overspray {:.3}%, CV {:.2}%, \
         window edges {:.1} cm, {t:.0} s against {bound:.0} s ({:.3})",
        r.wall_coverage_pct.unwrap(),
        r.ceiling_coverage_pct.unwrap(),
        r.overspray_pct.unwrap(),
        100.0 * r.thickness_cv.unwrap(),
        100.0 * r.window_edge_err_max_m.unwrap(),
        t / bound
    );
}

/// The demo, the apartment as one job (`missions/demo.toml`): the
/// living room, then through the 1.2 m hall the kitchen (a counter along
/// one wall, a column in a corner) and the bedroom (a bed and a desk
/// across it), and last the hall itself (turned in with the front in its
/// doorways, the bathroom's shut door left out of the coat as the drawing
/// gives it), each mapped, planned and plastered to the end without a
/// touch; every room's plan covers what it reaches (≥ 99.9 %,
/// ACCEPTANCE.md's planning target), and what the furniture or the
/// hall's width cuts off from the robot is reported, and the coat on the
/// true walls and the windows are within ACCEPTANCE.md's targets, and so
/// is the time.
#[test]
fn the_apartment_is_plastered_room_by_room_in_one_job() {
    let dir = tempfile::tempdir().unwrap();
    let r = run_file("demo", dir.path(), false, None);
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    let plaster = r.plaster.as_ref().unwrap();
    let rooms: Vec<&str> = plaster.rooms.iter().map(|p| p.room.as_str()).collect();
    assert_eq!(rooms, ["living", "kitchen", "bedroom", "hall"]);
    assert_truth_accounts(&r, &rooms);
    for p in &plaster.rooms {
        assert!(p.stations > 0, "{}", p.room);
        assert!(
            p.predicted.wall_coverage_pct >= 99.9,
            "{}: {:?}",
            p.room,
            p.predicted
        );
        assert!(
            p.predicted.ceiling_coverage_pct >= 99.9,
            "{}: {:?}",
            p.room,
            p.predicted
        );
        let sprayed: f64 = p.surfaces.iter().map(|s| s.material_l).sum();
        assert!(sprayed > 50.0, "{}: {sprayed} L", p.room);
    }
    // The bedroom's far side, beyond the bed and the desk, is reported,
    // and so are the hall's end walls (2.6 × 1.2 m less their edges: the
    // robot cannot turn across the hall to face them).
    assert!(
        plaster.rooms[2].unreachable_m2 > 5.0,
        "{}",
        plaster.rooms[2].unreachable_m2
    );
    // The bathroom, behind its shut door, is reported with its floor.
    let left: Vec<(&str, &str)> = plaster
        .rooms_left
        .iter()
        .map(|r| (r.room.as_str(), r.why.as_str()))
        .collect();
    assert_eq!(left, [("bath", "no open door leads there")]);
    assert!((plaster.rooms_left[0].floor_m2 - 3.85 * 3.65).abs() < 1e-9);
    let hall = &plaster.rooms[3];
    for s in &hall.surfaces {
        let end_wall = matches!(s.surface, SurfaceId::Wall(WallName::EAST | WallName::WEST));
        assert_eq!(s.unreachable_m2 > 2.0, end_wall, "hall: {s:?}");
    }
    // Within ACCEPTANCE.md's coat: every window found (the kitchen's by
    // the tool's camera at its first station, where the body's camera
    // cannot see its south edge past the counter), its edges within 2 cm
    // (the bedroom's, beyond the bed, seen from 2.9 m), and kept out of the
    // coat.
    assert_coat_targets(&r);
    assert_eq!((r.windows_found, r.windows_total), (3, 3));
    let edge = r.window_edge_err_max_m.unwrap();
    assert!(edge <= 0.02, "window edges {edge} m off");
    // And the time.
    let (t, bound) = (
        r.mission_time_s.unwrap(),
        r.mission_time_lower_bound_s.unwrap(),
    );
    assert!(t <= 1.25 * bound, "{t} s against a bound of {bound} s");
    eprintln!(
        "apartment: walls {:.2}%, ceiling {:.2}%, overspray {:.3}%, CV {:.2}%, \
         window edges within {:.1} cm, {t:.0} s against {bound:.0} s ({:.3})",
        r.wall_coverage_pct.unwrap(),
        r.ceiling_coverage_pct.unwrap(),
        r.overspray_pct.unwrap(),
        100.0 * r.thickness_cv.unwrap(),
        100.0 * edge,
        t / bound
    );
}

/// The demo killed in the kitchen and resumed: the resumed run reports
/// the whole job, its plastering time (the part before the kill counts)
/// and the windows of the rooms left before the kill with the rest.
/// The whole job twice over the default run's budget (340 s in debug):
/// the living room's kill and resume stays in it.
#[test]
#[ignore = "slow: the whole apartment job; run with --release -- --ignored"]
fn the_apartment_killed_in_the_kitchen_and_resumed_reports_the_whole_job() {
    let dir = tempfile::tempdir().unwrap();
    let first = run_file("demo", dir.path(), false, Some(3000.0));
    assert_eq!(first.outcome, "stopped");
    assert_eq!(first.room.as_deref(), Some("kitchen"));
    let r = run_file("demo", dir.path(), true, None);
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    assert_coat_targets(&r);
    assert_eq!((r.windows_found, r.windows_total), (3, 3));
    let rooms: Vec<&str> = r.windows.iter().map(|w| w.room.as_str()).collect();
    assert!(rooms.contains(&"living"), "{rooms:?}");
    let (t, bound) = (
        r.mission_time_s.unwrap(),
        r.mission_time_lower_bound_s.unwrap(),
    );
    assert!(
        (bound..=1.25 * bound).contains(&t),
        "{t} s against a bound of {bound} s"
    );
}

/// A `[spray]` table the tool cannot lay its coat with, or a `plaster`
/// task without one, is refused at load with the file, the line and the
/// key.
#[test]
fn a_bad_spray_table_names_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    let head = "name = \"x\"\nworld = \"w.toml\"\nseed = 1\n\n[start]\nroom_m = [5.0, 3.0]\nroom_sigma_m = 0.1\n\n";
    let task = "[[task]]\ntask = \"plaster\"\n";
    std::fs::write(
        &path,
        format!("{head}[spray]\nthickness_mm = 10.0\nflow_l_per_min = 40.0\n\n{task}"),
    )
    .unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:11") && err.contains("flow_l_per_min"),
        "{err}"
    );
    std::fs::write(&path, format!("{head}[spray]\nnozzle = 1\n\n{task}")).unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:10") && err.contains("nozzle"),
        "{err}"
    );
    // The tool's camera is on or off, nothing else.
    std::fs::write(&path, format!("{head}[spray]\ncamera = \"yes\"\n\n{task}")).unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:10") && err.contains("camera"),
        "{err}"
    );
    std::fs::write(&path, format!("{head}{task}")).unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:10") && err.contains("[spray]"),
        "{err}"
    );
}
