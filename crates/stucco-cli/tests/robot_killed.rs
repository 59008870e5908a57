//! `stucco robot` killed in the middle of plastering (SIGKILL, no chance
//! to write anything) and started again with `--resume` finishes the job
//! from its last checkpoint: the walls and the ceiling covered, at most
//! 1 % of the area sprayed twice. The robot's process is the real binary;
//! the kill comes at whatever moment the first checkpoint past the first
//! station is seen, not at a control period's end.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn mission() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../missions/living-room.toml")
}

/// `stucco robot` on the living room's job, as fast as it goes, its job's
/// folder `out`.
fn robot(out: &Path, resume: bool) -> Child {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_stucco"));
    cmd.arg("robot")
        .arg(mission())
        .args(["--name", "killed", "--speed", "1e6", "--exit-when-done"])
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    if resume {
        cmd.arg("--resume");
    }
    cmd.spawn().expect("the stucco binary")
}

/// The checkpoint's plastering cursor: the station under way.
fn station(out: &Path) -> Option<u64> {
    let text = std::fs::read_to_string(out.join("checkpoint.json")).ok()?;
    let cp: serde_json::Value = serde_json::from_str(&text).ok()?;
    cp["progress"]["plaster"]["cursor"]["station"].as_u64()
}

#[test]
fn a_robot_killed_while_plastering_finishes_the_job_when_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let mut first = robot(out, false);
    let t0 = Instant::now();
    // Killed once it has sprayed past its second station.
    loop {
        if station(out).is_some_and(|s| s >= 2) {
            break;
        }
        assert!(
            first.try_wait().unwrap().is_none(),
            "the robot ended before it was killed"
        );
        assert!(t0.elapsed() < Duration::from_secs(900), "never plastered");
        std::thread::sleep(Duration::from_millis(20));
    }
    first.kill().unwrap();
    first.wait().unwrap();
    assert!(
        !out.join("report.json").exists(),
        "killed, it wrote nothing"
    );
    let killed_at = station(out).unwrap();
    let status = robot(out, true).wait().unwrap();
    assert!(status.success(), "{status}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let f = |k: &str| {
        report[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {report}"))
    };
    assert_eq!(report["outcome"], "done", "{report}");
    // It went on where it stopped: the tasks before plastering were not
    // done again.
    assert_eq!(report["first_task"], 2, "killed at station {killed_at}");
    assert!(f("double_sprayed_pct") <= 1.0, "{report}");
    assert!(f("wall_coverage_pct") >= 99.5, "{report}");
    assert!(f("ceiling_coverage_pct") >= 99.0, "{report}");
}

/// Asked to stop (SIGINT, as Ctrl-C sends; SIGTERM, as a service manager
/// does), the robot ends at a period's end and leaves its report and last
/// checkpoint; its recording (`--record`) replays through a fresh
/// executive to the same commands.
#[test]
fn a_robot_asked_to_stop_leaves_its_report() {
    for signal in ["-INT", "-TERM"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path();
        let mut child = Command::new(env!("CARGO_BIN_EXE_stucco"))
            .arg("robot")
            .arg(mission())
            .args(["--name", "asked", "--record", "--out"])
            .arg(out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Running: its loop has said so on its log.
        let mut log = BufReader::new(child.stderr.take().unwrap()).lines();
        assert!(
            log.by_ref()
                .map_while(Result::ok)
                .any(|l| l.contains("on zenoh")),
            "never started"
        );
        let rest = std::thread::spawn(move || log.count());
        // Some periods of the mission, in real time.
        std::thread::sleep(Duration::from_millis(500));
        let status = Command::new("kill")
            .arg(signal)
            .arg(child.id().to_string())
            .status()
            .unwrap();
        assert!(status.success());
        let status = child.wait().unwrap();
        rest.join().unwrap();
        assert!(status.success(), "{signal}: {status}");
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                .unwrap();
        assert_eq!(report["outcome"], "stopped", "{signal}: {report}");
        let replay = Command::new(env!("CARGO_BIN_EXE_stucco"))
            .arg("replay-run")
            .arg(out.join("run.mcap"))
            .arg("--json")
            .output()
            .unwrap();
        assert!(replay.status.success(), "{signal}: {replay:?}");
        let replay: serde_json::Value = serde_json::from_slice(&replay.stdout).unwrap();
        assert!(replay["ticks"].as_u64().unwrap() > 5, "{signal}: {replay}");
        assert_eq!(replay["identical"], replay["ticks"], "{signal}: {replay}");
    }
}
