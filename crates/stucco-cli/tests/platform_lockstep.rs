//! The brain on a platform served over zenoh: `stucco sim serve --lockstep`
//! in one process, `stucco robot --platform zenoh` in another, give the
//! same job as `stucco run` in one process — the report's every field but
//! the wall-clock ones, and the executive's events, equal. The living
//! room's job to past its first strokes of plaster (400 s: mapped,
//! surveyed, planned, spraying).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

const STOP_AFTER_S: &str = "400";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn stucco() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stucco"))
}

/// Kills the served simulator however the test ends.
struct Served(Child);

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn report(dir: &Path) -> serde_json::Map<String, serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("report.json")).unwrap();
    let serde_json::Value::Object(mut r) = serde_json::from_str(&text).unwrap() else {
        panic!("not an object: {text}");
    };
    // How fast the machine ran it is not the run.
    for k in ["wall_seconds", "real_time_factor"] {
        assert!(r.remove(k).is_some(), "{k} missing");
    }
    r
}

#[test]
fn a_lockstep_platform_over_zenoh_runs_the_job_as_one_process_does() {
    let dir = tempfile::tempdir().unwrap();
    let (here, there) = (dir.path().join("here"), dir.path().join("there"));
    let mission = root().join("missions/living-room.toml");
    // A run stopped as asked exits 1: its report says "stopped".
    let status = stucco()
        .arg("run")
        .arg(&mission)
        .args(["--stop-after", STOP_AFTER_S, "--out"])
        .arg(&here)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert_eq!(status.code(), Some(1), "stucco run: {status}");

    let endpoint = format!("unixsock-stream/{}", dir.path().join("z.sock").display());
    let _served = Served(
        stucco()
            .args(["sim", "serve"])
            .arg(root().join("sim/worlds/apartment.toml"))
            .args(["--name", "lockstep", "--lockstep", "--mission"])
            .arg(&mission)
            .args(["--listen", &endpoint])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let out = stucco()
        .arg("robot")
        .arg(&mission)
        .args(["--name", "lockstep", "--platform", "zenoh"])
        .args(["--connect", &endpoint, "--speed", "1e6"])
        .args(["--stop-after", STOP_AFTER_S, "--out"])
        .arg(&there)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "stucco robot: {}",
        String::from_utf8_lossy(&out.stderr)
    );

    let (a, b) = (report(&here), report(&there));
    // The job got somewhere: plaster on the walls.
    assert_eq!(a["outcome"], "stopped", "{a:?}");
    assert!(a["wall_coverage_pct"].as_f64().unwrap() > 0.0, "{a:?}");
    for (k, v) in &a {
        assert_eq!(Some(v), b.get(k), "report field {k}");
    }
    assert_eq!(a.len(), b.len());
    let events = |d: &Path| std::fs::read_to_string(d.join("events.jsonl")).unwrap();
    assert_eq!(events(&here), events(&there), "the executive's events");
}
