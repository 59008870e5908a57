//! Acceptance tests: whole jobs on real data, asserted on what a user sees.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod acl;
mod calibration;
mod corridor;
mod door_passage;
mod floor;
mod link;
mod missions;
mod plastering;
mod replay_real_logs;
mod rooms;
mod study;
mod walls_on_real_logs;

/// `stucco run` on `missions/<name>.toml`, with the mission's own seed and
/// `runs` (or the mission's count).
fn run_mission_file(name: &str, runs: Option<u64>) -> anyhow::Result<stucco_cli::RunReport> {
    stucco_cli::run_mission(&stucco_cli::RunJob {
        mission: std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../missions")
            .join(format!("{name}.toml")),
        seed: None,
        runs,
    })
}

/// A `stucco robot` standing by (`missions/robot.toml`) in a thread, on
/// `link`, its simulated time `speed` times the wall clock; it stops when
/// [`RunningRobot::stop`] is called (or when dropped).
pub struct RunningRobot {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<anyhow::Result<stucco_cli::RobotRun>>>,
}

impl RunningRobot {
    /// Starts robot `name` (standing by in the apartment,
    /// `missions/robot.toml`) and gives it half a second to join the
    /// network.
    pub fn start(name: &str, link: stucco_cli::LinkConfig, speed: f64) -> Self {
        Self::start_on("robot", name, link, speed)
    }

    /// Starts robot `name` on `missions/<mission>.toml`.
    pub fn start_on(mission: &str, name: &str, link: stucco_cli::LinkConfig, speed: f64) -> Self {
        let job = stucco_cli::RobotJob {
            mission: std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("../missions/{mission}.toml")),
            name: name.to_owned(),
            link,
            speed,
            stop_after_s: Some(900.0),
            exit_when_done: false,
            out: None,
            resume: false,
            record: false,
            platform: stucco_cli::PlatformKind::Sim,
            platform_timeout: std::time::Duration::from_secs(10),
        };
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            std::thread::spawn(move || stucco_cli::run_robot(&job, &stop))
        };
        std::thread::sleep(std::time::Duration::from_millis(500));
        RunningRobot {
            stop,
            thread: Some(thread),
        }
    }

    /// Stops it, checks it ran without error and returns how it ended.
    pub fn stop(mut self) -> stucco_cli::RobotRun {
        self.halt().unwrap().unwrap()
    }

    fn halt(&mut self) -> anyhow::Result<Option<stucco_cli::RobotRun>> {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| anyhow::anyhow!("the robot panicked"))?
                .map(Some),
            None => Ok(None),
        }
    }
}

impl Drop for RunningRobot {
    fn drop(&mut self) {
        let _ = self.halt();
    }
}
