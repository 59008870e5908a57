//! A mission's job in the simulator, as `stucco run` does it: the robot
//! maps the reference room and follows its south wall; the run is scored
//! against the simulator's truth and its report, events, map and
//! checkpoint written into the job's folder (docs/checkpoint.md). The
//! map and, when the job plastered, the south wall's coat are drawn as
//! PNG too (`map.png`, `coat-south.png`: README's pictures).
//!
//! `cargo run --release -p stucco-examples --example sim_job [MISSION] [OUT]`
//! (default `missions/wall-pass.toml`, `out/sim-job`).

use anyhow::{Context, Result};
use std::path::PathBuf;
use stucco_cli::{TaskMissionJob, run_task_mission};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let mission = args
        .next()
        .map_or_else(|| root.join("missions/wall-pass.toml"), PathBuf::from);
    let out = args
        .next()
        .map_or_else(|| root.join("out/sim-job"), PathBuf::from);
    let job = TaskMissionJob {
        mission,
        seed: None,
        runs: None,
        out: Some(out.clone()),
        resume: false,
        stop_after_s: None,
        record: false,
    };
    let summary = run_task_mission(&job, &|_, _| {})?;
    for run in &summary.runs {
        println!(
            "{} (seed {}): {} in {:.0} simulated s; pose error {:.1} mm RMS, {:.1} mm at worst",
            run.mission,
            run.seed,
            run.outcome,
            run.sim_seconds,
            run.pose_rms_m * 1e3,
            run.pose_max_m * 1e3,
        );
        for task in &run.tasks {
            println!("  {:<18} {:?}", task.name, task.status);
        }
    }
    for name in ["map", "coat-wall1"] {
        let svg = out.join(name).with_extension("svg");
        if svg.exists() {
            let text = std::fs::read_to_string(&svg).with_context(|| svg.display().to_string())?;
            stucco_cli::rasterise(&text, &svg.with_extension("png"))?;
        }
    }
    println!("report, events, map: {}", out.display());
    Ok(())
}
