//! Task missions through `stucco run`: the living room's survey carried out end to end and
//! scored against the truth, the files a run writes, a run stopped and
//! resumed from its checkpoint, bad checkpoints and bad tasks refused.

use std::path::{Path, PathBuf};
use stucco_cli::{BadInput, MissionSummary, TaskMissionJob, run_task_mission};

fn mission(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../missions")
        .join(format!("{name}.toml"))
}

fn run(
    path: &Path,
    out: Option<&Path>,
    resume: bool,
    stop_after_s: Option<f64>,
) -> anyhow::Result<MissionSummary> {
    job(path, out, resume, stop_after_s, false)
}

/// `stucco run` on a task mission, recording when asked.
fn job(
    path: &Path,
    out: Option<&Path>,
    resume: bool,
    stop_after_s: Option<f64>,
    record: bool,
) -> anyhow::Result<MissionSummary> {
    run_task_mission(
        &TaskMissionJob {
            mission: path.to_owned(),
            seed: None,
            runs: None,
            out: out.map(Path::to_owned),
            resume,
            stop_after_s,
            record,
        },
        &|_, _| {},
    )
}

fn events(dir: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("events.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The survey maps the living room (the walls it can see, the room's size,
/// the door), makes a pass along the south wall finding its window with
/// the range camera, and leaves through the door it found.
#[test]
fn the_survey_maps_the_room_and_leaves_through_the_door_it_found() {
    let dir = tempfile::tempdir().unwrap();
    let s = run(&mission("survey"), Some(dir.path()), false, None).unwrap();
    let r = &s.runs[0];
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    assert!(r.tasks.iter().all(|t| t.seconds.is_some()));
    // North and south walls seen: the depth within 5 mm; the sofa hides
    // most of the west wall, the width still within 1 cm.
    assert!(
        (r.room_m[1] - r.room_true_m[1]).abs() < 0.005,
        "{:?}",
        r.room_m
    );
    assert!(
        (r.room_m[0] - r.room_true_m[0]).abs() < 0.01,
        "{:?}",
        r.room_m
    );
    // The door in the north wall, found within 3 cm, about its width.
    assert_eq!(r.doors.len(), 1, "{:?}", r.doors);
    let door = &r.doors[0];
    assert!(door.error_m < 0.03, "{door:?}");
    assert!(
        door.width_m.is_some_and(|w| (w - 0.9).abs() < 0.05),
        "{door:?}"
    );
    assert!(
        r.pose_max_m < 0.05,
        "position off by up to {} m",
        r.pose_max_m
    );
    // What the run writes.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    for key in [
        "outcome",
        "seed",
        "sim_seconds",
        "wall_seconds",
        "real_time_factor",
    ] {
        assert!(!report[key].is_null(), "report.json has no {key}");
    }
    let ev = events(dir.path());
    assert_eq!(ev.first().unwrap()["event"], "mission_started");
    assert_eq!(ev.last().unwrap()["event"], "mission_done");
    let svg = std::fs::read_to_string(dir.path().join("map.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.len() > 1000);
}

/// The same seed gives the same run, event for event.
#[test]
fn the_same_seed_gives_the_same_events() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(&mission("survey"), Some(a.path()), false, Some(35.0)).unwrap();
    run(&mission("survey"), Some(b.path()), false, Some(35.0)).unwrap();
    let read = |d: &Path| std::fs::read(d.join("events.jsonl")).unwrap();
    assert_eq!(read(a.path()), read(b.path()));
}

/// Switched off during its third task and started again with `--resume`,
/// the survey finishes without doing the first two again.
#[test]
fn a_stopped_run_resumes_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let first = run(&mission("survey"), Some(dir.path()), false, Some(40.0)).unwrap();
    assert_eq!(first.outcome, "stopped");
    let cp: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("checkpoint.json")).unwrap())
            .unwrap();
    let states: Vec<&str> = cp["progress"]["status"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["state"].as_str().unwrap())
        .collect();
    assert_eq!(states, ["done", "done", "active", "pending"]);
    let before = events(dir.path()).len();
    let second = run(&mission("survey"), Some(dir.path()), true, None).unwrap();
    assert_eq!(second.outcome, "done", "{:?}", second.reason);
    assert_eq!(second.runs[0].first_task, 2);
    // The unfinished task started again, then the next; the finished ones
    // never.
    let again: Vec<u64> = events(dir.path())[before..]
        .iter()
        .filter(|e| e["event"] == "task_started")
        .map(|e| e["task"].as_u64().unwrap())
        .collect();
    assert_eq!(again, [2, 3]);
}

/// A corrupt checkpoint, or one of another mission, is refused as bad
/// input and left as it was.
#[test]
fn a_bad_checkpoint_is_refused_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("checkpoint.json");
    std::fs::write(&path, "{\"mission\": \"demo").unwrap();
    let err = run(&mission("survey"), Some(dir.path()), true, None).unwrap_err();
    assert!(err.downcast_ref::<BadInput>().is_some(), "{err:#}");
    assert!(format!("{err:#}").contains("corrupt"), "{err:#}");
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "{\"mission\": \"demo"
    );
    // A checkpoint written by another version of the mission file.
    run(&mission("survey"), Some(dir.path()), false, Some(5.0)).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let other = text.replace("fnv1a64:", "fnv1a64:0");
    std::fs::write(&path, &other).unwrap();
    let err = run(&mission("survey"), Some(dir.path()), true, None).unwrap_err();
    assert!(format!("{err:#}").contains("not this file"), "{err:#}");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), other);
}

/// A task with a value out of range is refused with the file, the line
/// and the key; an unknown task with what was expected.
#[test]
fn a_bad_task_names_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    let head = "name = \"x\"\nworld = \"w.toml\"\nseed = 1\n\n[start]\nroom_m = [5.0, 3.0]\nroom_sigma_m = 0.1\n\n";
    std::fs::write(
        &path,
        format!("{head}[[task]]\ntask = \"map_room\"\n\n[[task]]\ntask = \"follow_wall\"\nwall = \"south\"\nstandoff_m = 0.6\nfrom_m = 3.0\nto_m = 4.0\nspeed_mps = 2.0\n"),
    )
    .unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:18") && err.contains("speed_mps"),
        "{err}"
    );
    std::fs::write(&path, format!("{head}[[task]]\ntask = \"fly\"\n")).unwrap();
    let err = format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err());
    assert!(
        err.contains("bad.toml:10:8") && err.contains("map_room"),
        "{err}"
    );
}

/// A checkpoint made on one drawing of the building is refused when the
/// plan file the mission names has changed since (its doors are numbered
/// by the plan), and the checkpoint is kept.
#[test]
fn a_checkpoint_of_another_plan_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let plan = dir.path().join("plan.toml");
    std::fs::copy(root.join("missions/plans/office-floor.toml"), &plan).unwrap();
    let text = std::fs::read_to_string(root.join("missions/office-rounds.toml"))
        .unwrap()
        .replace(
            "../sim/worlds/floor.toml",
            &root.join("sim/worlds/floor.toml").display().to_string(),
        )
        .replace("plans/office-floor.toml", "plan.toml");
    let path = dir.path().join("rounds.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    run(&path, Some(&out), false, Some(5.0)).unwrap();
    let checkpoint = std::fs::read_to_string(out.join("checkpoint.json")).unwrap();
    // The drawing changes: a door moved.
    let drawn = std::fs::read_to_string(&plan).unwrap();
    std::fs::write(
        &plan,
        drawn.replace("at_m = [8.0, 3.075]", "at_m = [8.2, 3.075]"),
    )
    .unwrap();
    let err = run(&path, Some(&out), true, None).unwrap_err();
    assert!(format!("{err:#}").contains("not this file"), "{err:#}");
    assert_eq!(
        std::fs::read_to_string(out.join("checkpoint.json")).unwrap(),
        checkpoint
    );
}

/// A floor plan's fault is refused with the file, the line and the
/// field: a door that lies in no wall of its rooms, a room the plan does
/// not have in `go_to_room` or `[start]`, a plan with a room size given
/// twice.
#[test]
fn a_bad_floor_plan_names_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plan.toml");
    let head = "name = \"x\"\nworld = \"w.toml\"\nseed = 1\n\n[start]\nroom = \"hall\"\nroom_sigma_m = 0.05\n\n\
        [[room]]\nname = \"hall\"\norigin_m = [0.0, 0.0]\nsize_m = [10.0, 3.0]\n\n\
        [[room]]\nname = \"office\"\norigin_m = [0.0, 3.15]\nsize_m = [5.0, 4.0]\n\n";
    let load = |text: String| {
        std::fs::write(&path, text).unwrap();
        format!("{:#}", stucco_cli::Mission::load(&path).unwrap_err())
    };
    let task = "[[task]]\ntask = \"go_to_room\"\nroom = \"office\"\n";
    // The door 1 m south of the wall between the rooms (line 21).
    let err = load(format!(
        "{head}[[door]]\nrooms = [\"hall\", \"office\"]\nat_m = [2.5, 2.0]\nwidth_m = 1.0\n\n{task}"
    ));
    assert!(
        err.contains("plan.toml:21") && err.contains("at_m") && err.contains("[[door]] 1"),
        "{err}"
    );
    let door = "[[door]]\nrooms = [\"hall\", \"office\"]\nat_m = [2.5, 3.075]\nwidth_m = 1.0\n\n";
    let err = load(format!(
        "{head}{door}[[task]]\ntask = \"go_to_room\"\nroom = \"kitchen\"\n"
    ));
    assert!(
        err.contains("plan.toml:26") && err.contains("kitchen"),
        "{err}"
    );
    // A room no door leads to.
    let island = "[[room]]\nname = \"store\"\norigin_m = [20.0, 0.0]\nsize_m = [2.0, 2.0]\n\n";
    let err = load(format!(
        "{head}{island}{door}[[task]]\ntask = \"go_to_room\"\nroom = \"store\"\n"
    ));
    assert!(
        err.contains("plan.toml:31") && err.contains("no way"),
        "{err}"
    );
    let err = load(format!("{head}{door}{task}").replace("room = \"hall\"", "room = \"lobby\""));
    assert!(
        err.contains("plan.toml:6") && err.contains("lobby"),
        "{err}"
    );
    let err =
        load(format!("{head}{door}{task}").replace("[start]\n", "[start]\nroom_m = [10.0, 3.0]\n"));
    assert!(
        err.contains("plan.toml:6") && err.contains("room_m"),
        "{err}"
    );
    // A door at a place that is no number (TOML reads nan; no range
    // check sees it): its own line and field.
    let text = format!("{head}{door}{task}").replace("[2.5, 3.075]", "[nan, 3.075]");
    let line = text.lines().position(|l| l.contains("nan")).unwrap() + 1;
    let err = load(text);
    assert!(
        err.contains(&format!("plan.toml:{line}:"))
            && err.contains("`door[0].at_m`: numbers must be finite"),
        "{err}"
    );
    // Written right, it loads.
    std::fs::write(&path, format!("{head}{door}{task}")).unwrap();
    let m = stucco_cli::Mission::load(&path).unwrap();
    assert_eq!(m.floor_plan().unwrap().route(0, 1), Some(vec![0]));
}

/// A plastering pass along the reference room's south wall, past a
/// radiator, after mapping the room: the true standoff holds within 5 mm
/// over the whole pass.
#[test]
fn a_wall_pass_holds_its_standoff() {
    let s = run(&mission("wall-pass"), None, false, None).unwrap();
    let r = &s.runs[0];
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    for i in 0..2 {
        assert!(
            (r.room_m[i] - r.room_true_m[i]).abs() < 0.003,
            "{:?}",
            r.room_m
        );
    }
    assert_eq!(r.passes.len(), 1);
    let p = &r.passes[0];
    // 1.3 m at 0.25 m/s and 50 Hz, less the slowing at the end.
    assert!(p.samples > 200, "{p:?}");
    assert!(p.max_error_m < 0.005, "{p:?}");
}

/// A recorded run replayed through a fresh executive gives the same
/// command at every tick — also for a run resumed from a checkpoint.
#[test]
fn a_recorded_run_replays_to_the_same_commands() {
    let dir = tempfile::tempdir().unwrap();
    job(
        &mission("survey"),
        Some(dir.path()),
        false,
        Some(36.0),
        true,
    )
    .unwrap();
    let r = stucco_cli::replay_run(&dir.path().join("run.mcap")).unwrap();
    assert_eq!(r.mission, "survey: living room");
    assert!(r.ticks > 1500, "{r:?}");
    assert_eq!(r.identical, r.ticks, "{r:?}");
    job(&mission("survey"), Some(dir.path()), true, None, true).unwrap();
    let r = stucco_cli::replay_run(&dir.path().join("run.mcap")).unwrap();
    assert!(r.ticks > 100, "{r:?}");
    assert_eq!(r.identical, r.ticks, "{r:?}");
}

/// A recording whose plan is not a plan is refused, the fault named in
/// the recording's copy of the plan by line and key.
#[test]
fn a_recording_with_a_bad_plan_names_the_recorded_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(mission("two-offices")).unwrap();
    let drawn = std::fs::read_to_string(root.join("missions/plans/office-floor.toml")).unwrap();
    let bad = drawn.replacen("width_m = 1.1", "width_m = \"wide\"", 1);
    let line = bad.lines().position(|l| l.contains("\"wide\"")).unwrap() + 1;
    let path = dir.path().join("run.mcap");
    stucco_cli::Recorder::create(
        &path,
        &stucco_cli::RecordedMission {
            path: mission("two-offices").display().to_string(),
            text,
            plan_text: Some(bad),
            seed: 21,
            resumed_from: None,
        },
    )
    .unwrap()
    .finish()
    .unwrap();
    let err = format!("{:#}", stucco_cli::replay_run(&path).unwrap_err());
    assert!(
        err.contains(&format!("office-floor.toml (as recorded):{line}:")),
        "{err}"
    );
    assert!(err.contains("width_m"), "{err}");
    assert!(err.contains("run.mcap: /mission: "), "{err}");
}

/// A recording keeps the building plan its mission was run with: it
/// replays to the same commands after the mission and plan files are
/// gone.
#[test]
fn a_recording_keeps_the_plan_its_mission_ran_with() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let world = root.join("sim/worlds/floor.toml").canonicalize().unwrap();
    let text = std::fs::read_to_string(mission("two-offices"))
        .unwrap()
        .replace("../sim/worlds/floor.toml", &world.display().to_string())
        .replace("plans/office-floor.toml", "plan.toml");
    let (path, plan) = (dir.path().join("job.toml"), dir.path().join("plan.toml"));
    std::fs::write(&path, &text).unwrap();
    std::fs::copy(root.join("missions/plans/office-floor.toml"), &plan).unwrap();
    let out = dir.path().join("out");
    job(&path, Some(&out), false, Some(10.0), true).unwrap();
    std::fs::remove_file(&plan).unwrap();
    std::fs::remove_file(&path).unwrap();
    let r = stucco_cli::replay_run(&out.join("run.mcap")).unwrap();
    assert_eq!(r.mission, "two offices");
    assert!(r.ticks > 400, "{r:?}");
    assert_eq!(r.identical, r.ticks, "{r:?}");
}
