//! `stucco worldgen`: a building's three files written, the world one the
//! simulator takes, the same seed the same files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::Command;

fn worldgen(seed: u64, out: &std::path::Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_stucco"))
        .args(["worldgen", "--seed", &seed.to_string(), "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

#[test]
fn worldgen_writes_a_world_its_drawing_and_a_job() {
    let dir = tempfile::tempdir().unwrap();
    let said = worldgen(3, dir.path());
    assert!(said.starts_with("building 3: "), "{said}");
    assert!(said.contains("plasterable: walls"), "{said}");
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap();
    let world = stucco_sim::WorldSpec::load(&dir.path().join("world.toml")).unwrap();
    assert_eq!(world, stucco_sim::generate(3).world);
    let plan = read("plan.toml");
    assert!(plan.contains("[[room]]") && plan.contains("corners = ") && plan.contains("[[door]]"));
    let mission = read("mission.toml");
    assert!(mission.contains("rooms = \"all\""), "{mission}");
    // Again, into another folder: the same bytes.
    let again = tempfile::tempdir().unwrap();
    worldgen(3, again.path());
    for name in ["world.toml", "plan.toml", "mission.toml"] {
        assert_eq!(
            read(name),
            std::fs::read_to_string(again.path().join(name)).unwrap(),
            "{name}"
        );
    }
}

#[test]
fn the_buildings_study_runs_each_job_or_says_why_it_could_not() {
    let dir = tempfile::tempdir().unwrap();
    // Ten seeds: L, T, chimney breasts and walls at an angle off
    // corridors, furniture and people; each job is run (stopped after 10
    // simulated minutes: the study's plumbing and the runtime on ten
    // buildings are under test here, its figures are the study's), and
    // one not done says why, with its true scores.
    let rows = stucco_cli::run_buildings(0..10, dir.path(), Some(600.0)).unwrap();
    assert_eq!(
        rows.iter().map(|r| r.seed).collect::<Vec<_>>(),
        (0..10).collect::<Vec<_>>()
    );
    for r in &rows {
        assert!(
            ["done", "failed", "stopped"].contains(&r.outcome.as_str()),
            "{r:?}"
        );
        assert_eq!(r.outcome != "done", r.reason.is_some(), "{r:?}");
        assert!(
            r.true_wall_coverage_pct.is_some() && r.sim_seconds.is_some(),
            "{r:?}"
        );
        assert!(r.dir.join("world.toml").exists());
    }
    let done = rows.iter().filter(|r| r.outcome == "done").count();
    let table = stucco_cli::buildings_table(&rows);
    assert_eq!(table.lines().count(), 12, "{table}");
    assert!(
        table.ends_with(&format!("{done} of 10 jobs done\n")),
        "{table}"
    );
}

/// A stop that is no time (0, negative, not a number) is refused before
/// anything runs, naming the option, with the usage error's exit code.
#[test]
fn a_stop_after_that_is_no_time_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for bad in ["0", "-5", "inf", "soon"] {
        let o = Command::new(env!("CARGO_BIN_EXE_stucco"))
            .args(["buildings", "--count", "1", "--out"])
            .arg(dir.path())
            .arg(format!("--stop-after={bad}"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("--stop-after"), "{bad}: {err}");
    }
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
}
