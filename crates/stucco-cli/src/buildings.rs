//! `stucco buildings`: generated buildings, each with its job run in the
//! simulator, seeds in parallel, a row a building: what the project is
//! accepted on (buildings nobody here has seen), measured.

use crate::task_mission::{TaskMissionJob, run_task_mission};
use anyhow::{Context, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use stucco_runtime::{BadInput, write_atomic};

/// One generated building and how its job went.
#[derive(Clone, Debug, Serialize)]
pub struct BuildingRow {
    /// Its seed.
    pub seed: u64,
    /// Its rooms' shapes, the corridor left out.
    pub shapes: Vec<String>,
    /// `done`, `failed`, `aborted`; `refused` when the job did not load
    /// (the reason says why).
    pub outcome: String,
    /// Why it failed or was refused.
    pub reason: Option<String>,
    /// The report's true scores, when it ran.
    pub true_wall_coverage_pct: Option<f64>,
    /// Ceilings, %.
    pub true_ceiling_coverage_pct: Option<f64>,
    /// Blocked, m².
    pub blocked_m2: Option<f64>,
    /// Unreached, m².
    pub unreached_m2: Option<f64>,
    /// Simulated seconds.
    pub sim_seconds: Option<f64>,
    /// Wall-clock seconds of its job.
    pub wall_seconds: Option<f64>,
    /// Its folder: the world, drawing, mission, and the job's report.
    pub dir: PathBuf,
}

/// Generates the buildings of `seeds` into `out/seed-N` and runs each
/// one's job there, in parallel; each stopped after `stop_after_s` of
/// simulated time when given (its outcome then `stopped`).
pub fn run_buildings(
    seeds: std::ops::Range<u64>,
    out: &Path,
    stop_after_s: Option<f64>,
) -> Result<Vec<BuildingRow>> {
    seeds
        .into_par_iter()
        .map(|seed| run_building(seed, &out.join(format!("seed-{seed}")), stop_after_s))
        .collect()
}

/// Writes `b`'s world, drawing and job into `dir` (made if missing):
/// `world.toml`, `plan.toml`, `mission.toml`.
pub fn write_building(b: &stucco_sim::Building, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot make {}", dir.display()))?;
    for (name, text) in [
        ("world.toml", b.world_toml()),
        ("plan.toml", b.plan_toml()),
        ("mission.toml", b.mission_toml()),
    ] {
        let path = dir.join(name);
        write_atomic(&path, text.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

fn run_building(seed: u64, dir: &Path, stop_after_s: Option<f64>) -> Result<BuildingRow> {
    let b = stucco_sim::generate(seed);
    write_building(&b, dir)?;
    let mut row = BuildingRow {
        seed,
        shapes: b.shapes.iter().map(|(_, k)| (*k).to_owned()).collect(),
        outcome: String::new(),
        reason: None,
        true_wall_coverage_pct: None,
        true_ceiling_coverage_pct: None,
        blocked_m2: None,
        unreached_m2: None,
        sim_seconds: None,
        wall_seconds: None,
        dir: dir.to_owned(),
    };
    let job = TaskMissionJob {
        mission: dir.join("mission.toml"),
        seed: None,
        runs: None,
        out: Some(dir.join("job")),
        resume: false,
        stop_after_s,
        record: false,
    };
    match run_task_mission(&job, &|_, _| {}) {
        Ok(summary) => {
            if let Some(r) = summary.runs.into_iter().next() {
                row.outcome = r.outcome;
                row.reason = r.reason;
                row.true_wall_coverage_pct = r.true_wall_coverage_pct;
                row.true_ceiling_coverage_pct = r.true_ceiling_coverage_pct;
                row.blocked_m2 = r.blocked_m2;
                row.unreached_m2 = r.unreached_m2;
                row.sim_seconds = Some(r.sim_seconds);
                row.wall_seconds = Some(r.wall_seconds);
            }
        }
        Err(e) if e.downcast_ref::<BadInput>().is_some() => {
            row.outcome = "refused".to_owned();
            row.reason = Some(format!("{e:#}"));
        }
        Err(e) => return Err(e.context(format!("building {seed}"))),
    }
    Ok(row)
}

/// The rows as a table, a line a building.
pub fn buildings_table(rows: &[BuildingRow]) -> String {
    let pct = |x: Option<f64>| x.map_or("—".to_owned(), |v| format!("{v:.2}"));
    let m2 = |x: Option<f64>| x.map_or("—".to_owned(), |v| format!("{v:.1}"));
    let mut s = format!(
        "{:>5}  {:<44} {:<8} {:>7} {:>7} {:>8} {:>8} {:>8}  {}\n",
        "seed", "rooms", "outcome", "walls%", "ceil%", "blocked", "unreach", "sim s", "why"
    );
    for r in rows {
        let why = r.reason.as_deref().unwrap_or("");
        let why = why.rsplit(": ").next().unwrap_or(why);
        s.push_str(&format!(
            "{:>5}  {:<44} {:<8} {:>7} {:>7} {:>8} {:>8} {:>8}  {}\n",
            r.seed,
            r.shapes.join(", "),
            r.outcome,
            pct(r.true_wall_coverage_pct),
            pct(r.true_ceiling_coverage_pct),
            m2(r.blocked_m2),
            m2(r.unreached_m2),
            r.sim_seconds.map_or("—".to_owned(), |v| format!("{v:.0}")),
            why
        ));
    }
    let done = rows.iter().filter(|r| r.outcome == "done").count();
    s.push_str(&format!("{done} of {} jobs done\n", rows.len()));
    s
}
