//! `stucco sim serve`: a simulated robot served over zenoh as a platform
//! (`stucco/NAME/platform/...`, see [`stucco_link::platform`]), for a
//! brain in another process — `stucco robot --platform zenoh`, or anyone's
//! in any language.

use crate::plastering::WorldState;
use crate::sim_robot::mission_sim_config;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use stucco_core::{DriveCommand, Platform, ToolCommand};
use stucco_link::platform::{PlatformCommand, PlatformInfo, PlatformReadings};
use stucco_link::{LinkConfig, PlatformServer};
use stucco_runtime::{BadInput, DT_S, Mission};
use stucco_sim::{SimConfig, Simulator, WorldSpec};

/// What `stucco sim serve` was asked to do.
#[derive(Clone, Debug)]
pub struct ServeJob {
    /// The world file.
    pub world: PathBuf,
    /// The platform's name on the network (`stucco/NAME/platform/...`).
    pub name: String,
    /// How to join the network.
    pub link: LinkConfig,
    /// A mission whose robot to simulate: its sprayer (`[spray]`), its
    /// seed, its people (none when it closes the site to them).
    pub mission: Option<PathBuf>,
    /// Seed, instead of the mission's or the world's.
    pub seed: Option<u64>,
    /// Step only when the period's command has come.
    pub lockstep: bool,
    /// Free-running: simulated seconds per wall-clock second.
    pub speed: f64,
    /// Stop after this much simulated time.
    pub stop_after_s: Option<f64>,
}

/// How a served simulation ended.
#[derive(Clone, Debug, Serialize)]
pub struct ServeRun {
    /// Control periods simulated.
    pub periods: u64,
    /// Simulated seconds.
    pub simulated_s: f64,
    /// Commands refused as malformed or unsafe (each one logged).
    pub refused: u64,
}

/// A free-running platform holding a command that long without a new one
/// stops the drive and the spray: the brain is gone or its link is.
const WATCHDOG: Duration = Duration::from_millis(500);

/// Serves the simulated robot until `stop` is set or its time is up.
pub fn serve(job: &ServeJob, stop: &AtomicBool) -> Result<ServeRun> {
    crate::init_logging();
    let mut world = WorldSpec::load(&job.world)
        .map_err(|e| BadInput(format!("{}: {e:#}", job.world.display())))?;
    let (config, seed) = match &job.mission {
        Some(path) => {
            let mission = Mission::load(path)?;
            if !mission.people {
                world.people.clear();
            }
            (
                mission_sim_config(&mission),
                job.seed.unwrap_or(mission.seed),
            )
        }
        None => (SimConfig::default(), job.seed.unwrap_or(world.seed)),
    };
    if !(job.speed.is_finite() && job.speed > 0.0) {
        return Err(BadInput("--speed: a positive number".to_owned()).into());
    }
    let spec = config.robot();
    let mut sim = Simulator::new(&world, config, Some(seed));
    let session = stucco_link::open(&job.link).context("joining the zenoh network")?;
    let mut server = PlatformServer::new(&session, &job.name)?;
    tracing::info!(
        platform = %job.name,
        lockstep = job.lockstep,
        seed,
        "serving the simulated robot on stucco/{}/platform/",
        job.name
    );
    let info = |sim: &Simulator| PlatformInfo {
        name: job.name.clone(),
        spec: spec.clone(),
        now: sim.now(),
        lockstep: job.lockstep,
        period_s: DT_S,
    };
    let world_json = |sim: &Simulator| {
        serde_json::to_vec(&WorldState::of(sim)).map_err(|e| format!("world state: {e}"))
    };
    let mut run = ServeRun {
        periods: 0,
        simulated_s: 0.0,
        refused: 0,
    };
    // Lockstep: the number of the last command carried out.
    let mut carried = None;
    // The last command held, and (free-running) when it came.
    let mut held = (DriveCommand::STOP, ToolCommand::default());
    let mut heard = Instant::now();
    let mut stopped_by_watchdog = false;
    let t0 = Instant::now();
    loop {
        if stop.load(Ordering::Relaxed)
            || job
                .stop_after_s
                .is_some_and(|t| sim.now().as_secs_f64() >= t)
        {
            break;
        }
        server.answer(|| info(&sim), || world_json(&sim))?;
        let readings = if job.lockstep {
            let Some(cmd) = server.next_command(Duration::from_millis(50)) else {
                continue;
            };
            // The brain did not hear this period's readings: they go again,
            // the simulation does not step twice.
            if carried == Some(cmd.period) {
                server.republish(cmd.period)?;
                continue;
            }
            let (drive, tool, dt_s) = checked(&cmd, held.1, &mut run.refused);
            held = (drive, tool);
            sim.command(drive);
            Platform::tool(&mut sim, tool);
            carried = Some(cmd.period);
            (cmd.period, sim.advance(dt_s))
        } else {
            for cmd in server.take_commands() {
                let (drive, tool, _) = checked(&cmd, held.1, &mut run.refused);
                held = (drive, tool);
                heard = Instant::now();
                stopped_by_watchdog = false;
            }
            if heard.elapsed() > WATCHDOG && !stopped_by_watchdog {
                tracing::warn!(platform = %job.name, "no command for {WATCHDOG:?}: drive stopped, spray off");
                held = (DriveCommand::STOP, held.1.off());
                stopped_by_watchdog = true;
            }
            sim.command(held.0);
            Platform::tool(&mut sim, held.1);
            let r = sim.advance(DT_S);
            // Paced by the wall clock.
            let due = t0 + Duration::from_secs_f64((run.periods + 1) as f64 * DT_S / job.speed);
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
            (run.periods + 1, r)
        };
        run.periods += 1;
        server.publish(&PlatformReadings {
            period: readings.0,
            now: sim.now(),
            readings: readings.1,
            truth: Some(sim.truth().drive.pose),
        })?;
    }
    run.simulated_s = sim.now().as_secs_f64();
    Ok(run)
}

/// The drive and tool commands and the period's length of `cmd`; one
/// that is not finite, a negative flow, or a period not in (0, 1] s, is refused (logged,
/// counted): the drive stops and the spray goes off (the nozzle held where
/// `last_tool` put it) for a control period.
fn checked(
    cmd: &PlatformCommand,
    last_tool: ToolCommand,
    refused: &mut u64,
) -> (DriveCommand, ToolCommand, f64) {
    let finite = [cmd.drive.speed_mps, cmd.drive.steer_rad, cmd.dt_s]
        .into_iter()
        .chain(cmd.tool.nozzle_m)
        .chain(cmd.tool.flow_m3ps)
        .all(f64::is_finite);
    let flow_ok = cmd.tool.flow_m3ps.is_none_or(|f| f >= 0.0);
    if finite && flow_ok && cmd.dt_s > 0.0 && cmd.dt_s <= 1.0 {
        return (cmd.drive, cmd.tool, cmd.dt_s);
    }
    *refused += 1;
    tracing::warn!(
        period = cmd.period,
        "a command not finite or with a period not in (0, 1] s refused: drive stopped, spray off"
    );
    (DriveCommand::STOP, last_tool.off(), DT_S)
}

#[cfg(test)]
mod tests {
    use super::*;
    use stucco_core::Aim;

    fn command(speed_mps: f64, dt_s: f64, nozzle_z: f64) -> PlatformCommand {
        PlatformCommand {
            period: 3,
            dt_s,
            drive: DriveCommand {
                speed_mps,
                steer_rad: 0.1,
            },
            tool: ToolCommand {
                nozzle_m: [0.5, 0.4, nozzle_z],
                aim: Aim::Up,
                spray: true,
                ..ToolCommand::default()
            },
        }
    }

    #[test]
    fn a_command_not_finite_or_out_of_range_stops_drive_and_spray() {
        let last = ToolCommand {
            nozzle_m: [0.3, 0.2, 1.0],
            spray: true,
            ..ToolCommand::default()
        };
        let mut refused = 0;
        let good = command(0.3, 0.02, 1.2);
        assert_eq!(
            checked(&good, last, &mut refused),
            (good.drive, good.tool, 0.02)
        );
        assert_eq!(refused, 0);
        for bad in [
            command(f64::NAN, 0.02, 1.2),
            command(0.3, 0.0, 1.2),
            command(0.3, 5.0, 1.2),
            command(0.3, 0.02, f64::INFINITY),
            PlatformCommand {
                tool: ToolCommand {
                    flow_m3ps: Some(-1e-4),
                    ..good.tool
                },
                ..good
            },
        ] {
            let (drive, tool, dt_s) = checked(&bad, last, &mut refused);
            assert_eq!(drive, DriveCommand::STOP);
            assert!(!tool.spray);
            assert_eq!(tool.nozzle_m, last.nozzle_m, "the nozzle held");
            assert_eq!(dt_s, DT_S);
        }
        assert_eq!(refused, 5);
    }
}
