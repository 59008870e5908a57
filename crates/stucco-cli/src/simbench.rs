//! `stucco simbench`: the simulator's speed, one robot on its world's tour.

use anyhow::{Result, bail};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;
use stucco_core::Platform;
use stucco_sim::{SimConfig, Simulator, TourDriver, TraceHash, WorldSpec};

/// What `stucco simbench` was asked to do.
#[derive(Clone, Debug)]
pub struct SimbenchJob {
    /// The world file.
    pub world: PathBuf,
    /// Seed overriding the world's.
    pub seed: Option<u64>,
    /// Simulated time to run, s.
    pub sim_seconds: f64,
    /// Run the same job again right after with the previous implementation
    /// (the cameras cast through rapier) and report it beside.
    pub baseline: bool,
}

/// The summary `stucco simbench --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct SimbenchReport {
    /// The world's name.
    pub world: String,
    /// The seed run.
    pub seed: u64,
    /// Simulated time, s.
    pub sim_seconds: f64,
    /// Wall-clock time the simulation took, s.
    pub wall_seconds: f64,
    /// `sim_seconds / wall_seconds`.
    pub real_time_factor: f64,
    /// Hash of every sensor reading, to compare runs.
    pub trace_hash: String,
    /// Laser scans delivered.
    pub scans: usize,
    /// Laser beams cast (scans × beams).
    pub beams: usize,
    /// Encoder samples delivered.
    pub encoder_samples: usize,
    /// Range-camera profiles delivered.
    pub profiles: usize,
    /// Control steps in which the bumper touched something.
    pub bumps: usize,
    /// With `--baseline`: the same job with the previous implementation,
    /// run right after in the same process.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline: Option<Baseline>,
}

/// The previous implementation's run of the same job.
#[derive(Clone, Debug, Serialize)]
pub struct Baseline {
    /// What the baseline is.
    pub implementation: String,
    /// Wall-clock time it took, s.
    pub wall_seconds: f64,
    /// Its real-time factor.
    pub real_time_factor: f64,
    /// Its hash of every sensor reading (the cameras' ranges differ by
    /// rapier's f32 rounding).
    pub trace_hash: String,
    /// The job's real-time factor over the baseline's.
    pub speedup: f64,
}

/// Control period of the tour driver, s.
const CONTROL_DT_S: f64 = 0.02;

/// Runs the job: the robot follows the world's tour at 0.5 m/s, driven on
/// its true pose, with the default robot and sensors.
pub fn run_simbench(job: &SimbenchJob) -> Result<SimbenchReport> {
    let world = WorldSpec::load(&job.world)?;
    if world.tour.len() < 2 {
        bail!("{}: the world has no tour to drive", job.world.display());
    }
    if job.sim_seconds.is_nan() || job.sim_seconds <= 0.0 {
        bail!("--sim-seconds must be positive");
    }
    let seed = job.seed.unwrap_or(world.seed);
    let run = |rapier_cameras: bool| -> Run {
        let config = SimConfig::default();
        let vehicle = config.vehicle.clone();
        let beams_per_scan = config.laser.beams;
        let started = Instant::now();
        let mut sim = Simulator::new(&world, config, Some(seed));
        if rapier_cameras {
            sim.cast_cameras_through_rapier();
        }
        let mut driver = TourDriver::new(world.tour.clone(), 0.5);
        let mut hash = TraceHash::default();
        let (mut scans, mut samples, mut profiles, mut bumps) = (0, 0, 0, 0);
        let steps = (job.sim_seconds / CONTROL_DT_S).round() as usize;
        for _ in 0..steps {
            let pose = sim.truth().drive.pose;
            sim.command(driver.command(&pose, &vehicle));
            let r = sim.advance(CONTROL_DT_S);
            hash.add(&r);
            scans += r.scans.len();
            samples += r.encoders.len();
            profiles += r.profiles.len();
            bumps += usize::from(r.bumper);
        }
        Run {
            wall_seconds: started.elapsed().as_secs_f64(),
            sim_seconds: sim.now().as_secs_f64(),
            hash: hash.hex(),
            scans,
            beams: scans * beams_per_scan,
            samples,
            profiles,
            bumps,
        }
    };
    let now = run(false);
    let rtf = |r: &Run| r.sim_seconds / r.wall_seconds.max(1e-9);
    let baseline = job.baseline.then(|| {
        let before = run(true);
        Baseline {
            implementation: "cameras cast through rapier".to_owned(),
            wall_seconds: before.wall_seconds,
            real_time_factor: rtf(&before),
            trace_hash: before.hash.clone(),
            speedup: rtf(&now) / rtf(&before),
        }
    });
    Ok(SimbenchReport {
        world: world.name.clone(),
        seed,
        sim_seconds: now.sim_seconds,
        wall_seconds: now.wall_seconds,
        real_time_factor: rtf(&now),
        trace_hash: now.hash,
        scans: now.scans,
        beams: now.beams,
        encoder_samples: now.samples,
        profiles: now.profiles,
        bumps: now.bumps,
        baseline,
    })
}

/// One run of the job.
struct Run {
    wall_seconds: f64,
    sim_seconds: f64,
    hash: String,
    scans: usize,
    beams: usize,
    samples: usize,
    profiles: usize,
    bumps: usize,
}
