//! Room to room on a floor plan (`missions/office-rounds.toml`): the
//! robot goes from the corridor of the office floor into office A, through
//! A's door into B, across the corridor into the lab and back, by
//! `go_to_room` tasks. Its filter keeps one room's frame at a time; each
//! door of the plan moves the frame into the next room. Asserted over
//! several seeds: every task done, every move of the frame made when the
//! robot truly stood in the room it moved into, the estimate within a few
//! centimetres of the truth all the way.

use std::path::Path;
use stucco_cli::{TaskMissionJob, run_task_mission};

/// The task mission at `mission`, `runs` seeds of it (the file's when
/// none), with no folder.
fn run_job(mission: &Path, runs: Option<u64>) -> stucco_cli::MissionSummary {
    run_task_mission(
        &TaskMissionJob {
            mission: mission.to_owned(),
            seed: None,
            runs,
            out: None,
            resume: false,
            stop_after_s: None,
            record: false,
        },
        &|_, _| {},
    )
    .unwrap()
}

/// `runs` seeds of the task mission `missions/NAME`, each checked to be
/// done with every move of the frame made, in order, into the rooms of
/// `way`, each when the robot truly stood in it.
fn rounds(name: &str, runs: u64, way: &[&str]) -> Vec<stucco_cli::MissionReport> {
    let s = run_job(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../missions")
            .join(name),
        Some(runs),
    );
    assert_eq!(s.runs.len(), runs as usize);
    for r in &s.runs {
        let seed = r.seed;
        assert_eq!(r.outcome, "done", "seed {seed}: {:?}", r.reason);
        let entered: Vec<Option<&str>> = r.room_changes.iter().map(|c| c.room.as_deref()).collect();
        let way: Vec<Option<&str>> = way.iter().map(|w| Some(*w)).collect();
        assert_eq!(entered, way, "seed {seed}");
        for c in &r.room_changes {
            assert_eq!(c.room, c.room_true, "seed {seed}: {c:?}");
        }
        assert_eq!(r.room_true.as_deref(), *way.last().unwrap());
        eprintln!(
            "{name} seed {seed}: {:.0} s, position RMS {:.1} mm, max {:.1} mm, heading RMS {:.2}°",
            r.sim_seconds,
            r.pose_rms_m * 1e3,
            r.pose_max_m * 1e3,
            r.heading_rms_rad.to_degrees()
        );
    }
    s.runs
}

#[test]
fn go_to_room_takes_the_robot_round_the_office_floor() {
    let way = ["office-a", "office-b", "corridor", "lab", "corridor"];
    for r in rounds("office-rounds.toml", 4, &way) {
        let seed = r.seed;
        assert_eq!(r.room.as_deref(), Some("corridor"));
        assert!(r.pose_max_m < 0.05, "seed {seed}: {} m", r.pose_max_m);
        assert!(r.pose_rms_m < 0.01, "seed {seed}: {} m", r.pose_rms_m);
    }
}

/// The apartment's rounds (`missions/apartment-rounds.toml`): living room
/// → kitchen → bedroom → living room, every way through the 1.2 m hall,
/// where the robot cannot turn on the spot and turns in several moves.
/// Asserted on seeds 11–14: every task done, every frame move made in the
/// room the robot truly stood in, the estimate within 3 cm RMS.
#[test]
fn go_to_room_takes_the_robot_through_the_apartments_narrow_hall() {
    let way = ["hall", "kitchen", "hall", "bedroom", "hall", "living"];
    for r in rounds("apartment-rounds.toml", 4, &way) {
        assert!(r.pose_rms_m < 0.03, "seed {}: {} m", r.seed, r.pose_rms_m);
    }
}

/// Glazing down to 15 cm in a room with a drawing: the laser sees
/// through the glass as through a doorway, but the drawing gives the
/// doors: the glazing is never taken for one.
#[test]
fn glazing_near_the_floor_is_not_taken_for_a_door_where_the_drawing_has_none() {
    let s = office_and_hall(
        "glazed office",
        3,
        r#"
# Glazing from 15 cm up in the north wall, the laser's plane (30 cm)
# crossing it.
[[window]]
room = "office"
wall = 2
offset_m = 1.5
width_m = 2.0
sill_m = 0.15
head_m = 2.2
glazed = true
"#,
        "map_room",
    );
    let r = &s.runs[0];
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    // The drawing's door, and no other.
    assert_eq!(r.doors.len(), 1, "{:?}", r.doors);
    assert_eq!(r.doors[0].wall, stucco_core::WallName::EAST);
    assert!(r.doors[0].error_m < 0.05, "{:?}", r.doors);
}

/// A chair just inside the room beyond a door, where the passage's end
/// would put the robot's front: the robot, held with its body through
/// the door, is in that room, and the passage ends there (it failed,
/// the way blocked, in four of the first eighteen generated buildings).
#[test]
fn a_chair_inside_the_next_room_ends_the_passage_once_the_body_is_through() {
    let s = office_and_hall(
        "a chair past the door",
        5,
        r#"
# Its near legs 0.3 m short of where the passage's end puts the front:
# the field meets them with the body 0.25 m through the door.
[[chair]]
at = [6.65, 1.95]
size_m = [0.45, 0.45]
heading_deg = 0.0
height_m = 0.45
leg_radius_m = 0.015
"#,
        "go_to_room\"\nroom = \"hall",
    );
    let r = &s.runs[0];
    assert_eq!(r.outcome, "done", "{:?}", r.reason);
    assert_eq!(r.room.as_deref(), Some("hall"));
    assert_eq!(r.room_true.as_deref(), Some("hall"));
}

/// A job in an office 5 × 4 m with a hall 1.85 m wide east of it through a
/// 0.9 m door, both drawn, the robot starting in the office: the world's
/// `extra` tables (furniture, windows) and the one task `task` (its name,
/// and any keys after it), run once with `seed`.
fn office_and_hall(name: &str, seed: u64, extra: &str, task: &str) -> stucco_cli::MissionSummary {
    let dir = tempfile::tempdir().unwrap();
    let write = |file: &str, text: &str| std::fs::write(dir.path().join(file), text).unwrap();
    let rooms = r#"
[[room]]
name = "office"
corners = [[0.0, 0.0], [5.0, 0.0], [5.0, 4.0], [0.0, 4.0]]

[[room]]
name = "hall"
corners = [[5.15, 0.0], [7.0, 0.0], [7.0, 4.0], [5.15, 4.0]]
"#;
    write(
        "world.toml",
        &format!(
            r#"name = "{name}"
seed = {seed}

[robot]
at = [1.2, 1.0]
heading_deg = 0.0
{rooms}shared_walls = [3]

[[door]]
room = "office"
wall = 1
offset_m = 1.5
width_m = 0.9
{extra}"#
        ),
    );
    write(
        "mission.toml",
        &format!(
            r#"name = "{name}"
world = "world.toml"
seed = {seed}
people = false

[start]
room = "office"
{rooms}
[[door]]
rooms = ["office", "hall"]
at_m = [5.075, 1.95]
width_m = 0.9

[[task]]
task = "{task}"
"#
        ),
    );
    run_job(&dir.path().join("mission.toml"), None)
}
