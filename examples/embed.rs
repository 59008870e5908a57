//! The robot's runtime on a platform of your own: what putting stucco on
//! a real robot takes. Implement [`Platform`] for the robot's driver —
//! hold the drive and tool commands, advance, return what the encoders,
//! the laser and the cameras read — then hand it to a [`Robot`] with a
//! mission; nothing of the simulator, zenoh or the terminal comes in.
//!
//! The "driver" here is a toy: a tricycle in an empty 5 × 4 m room, its
//! laser cast against the four walls, its encoders counting the rear
//! wheels' travel. The mission maps the room (walls, size) and then
//! follows the south wall; the events print as JSON lines.
//!
//! `cargo run --release -p stucco-examples --example embed`

use anyhow::Result;
use std::path::Path;
use stucco_control::Limiter;
use stucco_core::{
    DriveCommand, EncoderSample, Platform, PlatformError, Pose2, Readings, RobotSpec, Scan, Stamp,
    ToolCommand,
};
use stucco_nav::RoomState;
use stucco_runtime::{EventLog, Mission, Perception, Robot};

/// The mission, as a file would hold it (docs/mission.md): no world, no
/// seed — this robot is not simulated by stucco.
const MISSION: &str = r#"
name = "the toy room"

# The room's size as the drawing gives it, to 10 cm; the robot put where
# the operator says, to 3 cm.
[start]
room_m = [5.1, 3.9]
room_sigma_m = 0.1
pose_sigma_m = 0.03

[[task]]
task = "map_room"
path = [[1.5, 1.3], [3.5, 1.3], [3.5, 2.7], [1.5, 2.7]]
max_size_sigma_m = 0.005

[[task]]
task = "follow_wall"
wall = "south"
standoff_m = 0.8
from_m = 2.6
to_m = 4.0
"#;

/// Steps of the toy's kinematics within a control period, s.
const STEP_S: f64 = 0.002;

/// A tricycle in an empty rectangular room (its south-west corner the
/// origin), what a real robot's driver would be.
struct ToyRobot {
    spec: RobotSpec,
    room_m: [f64; 2],
    /// The true pose: only this driver knows it.
    pose: Pose2,
    now: Stamp,
    drive: DriveCommand,
    /// Each rear wheel's travel since start, m.
    wheels_m: [f64; 2],
    next_odometry: Stamp,
    next_scan: Stamp,
}

impl ToyRobot {
    fn new(spec: RobotSpec, room_m: [f64; 2], pose: Pose2) -> Self {
        ToyRobot {
            spec,
            room_m,
            pose,
            now: Stamp::ZERO,
            drive: DriveCommand::STOP,
            wheels_m: [0.0; 2],
            next_odometry: Stamp::ZERO,
            next_scan: Stamp::ZERO,
        }
    }

    /// Range from `from` along `bearing` (world frame) to the nearest
    /// wall of the room.
    fn range(&self, from: &Pose2, bearing: f64) -> f64 {
        let (s, c) = bearing.sin_cos();
        let [w, h] = self.room_m;
        // Each wall: where the ray starts across it, how fast it closes,
        // where the wall stands.
        [
            (from.x, c, 0.0),
            (from.x, c, w),
            (from.y, s, 0.0),
            (from.y, s, h),
        ]
        .into_iter()
        .filter(|(_, rate, _)| rate.abs() > 1e-12)
        .map(|(start, rate, wall)| (wall - start) / rate)
        .filter(|t| *t > 0.0)
        .fold(f64::INFINITY, f64::min)
    }

    /// One laser scan, every beam cast from where the laser is now.
    fn scan(&self) -> Scan {
        let laser = &self.spec.laser;
        let at = self.pose * self.spec.vehicle.laser_mount;
        let ranges = (0..laser.beams).map(|i| {
            let a = laser.angle_min_rad + i as f64 * laser.increment_rad;
            self.range(&at, at.theta + a)
        });
        Scan::new(
            self.now,
            laser.name.clone(),
            laser.angle_min_rad,
            laser.increment_rad,
            0.0,
            laser.min_range_m,
            laser.max_range_m,
            ranges,
        )
    }
}

impl Platform for ToyRobot {
    fn now(&self) -> Stamp {
        self.now
    }

    fn command(&mut self, drive: DriveCommand) {
        self.drive = drive;
    }

    /// This toy carries no spray tool.
    fn tool(&mut self, _cmd: ToolCommand) {}

    fn advance(&mut self, dt_s: f64) -> Result<Readings, PlatformError> {
        let v = &self.spec.vehicle;
        let mut out = Readings::default();
        let end = self.now.offset_secs(dt_s);
        while self.now < end {
            // The front wheel drives and steers; the rear axle's middle
            // moves at its speed's component along the body.
            let DriveCommand {
                speed_mps,
                steer_rad,
            } = self.drive;
            let (speed, turn) = (
                speed_mps * steer_rad.cos(),
                speed_mps * steer_rad.sin() / v.wheelbase_m,
            );
            let mid = self.pose.theta + turn * STEP_S / 2.0;
            self.pose.x += speed * mid.cos() * STEP_S;
            self.pose.y += speed * mid.sin() * STEP_S;
            self.pose.theta += turn * STEP_S;
            self.wheels_m[0] += (speed - turn * v.track_m / 2.0) * STEP_S;
            self.wheels_m[1] += (speed + turn * v.track_m / 2.0) * STEP_S;
            self.now = self.now.offset_secs(STEP_S);
            if self.now >= self.next_odometry {
                let ticks = |m: f64| (m / v.metres_per_tick()).round() as i64;
                out.encoders.push(EncoderSample {
                    stamp: self.now,
                    left_ticks: ticks(self.wheels_m[0]),
                    right_ticks: ticks(self.wheels_m[1]),
                });
                self.next_odometry = self.next_odometry.offset_secs(1.0 / v.odometry_rate_hz);
            }
            if self.now >= self.next_scan {
                out.scans.push(self.scan());
                self.next_scan = self.next_scan.offset_secs(1.0 / self.spec.laser.rate_hz);
            }
        }
        Ok(out)
    }
}

fn main() -> Result<()> {
    // What the robot carries: the papers' tricycle and laser, no camera.
    let spec = RobotSpec {
        camera: None,
        ..RobotSpec::default()
    };
    let mission = Mission::parse(MISSION, Path::new("toy-room.toml"))?;
    let truth = Pose2::new(1.5, 1.3, 0.0);
    let platform = ToyRobot::new(spec.clone(), [5.0, 4.0], truth);
    // The filter starts where the operator says the robot stands, in the
    // room the drawing gives, each as sure as the mission's [start] says.
    let start = mission
        .start
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("the mission has a [start]"))?;
    let room_m = start.room_m.unwrap_or([5.0, 4.0]);
    let x0: RoomState = start.filter_start(&Pose2::new(1.5, 1.3, 0.0), room_m);
    let perception = Perception::new(&spec, x0, [start.room_sigma_m; 2], platform.now())?;
    let mut robot = Robot::new(
        platform,
        perception,
        mission.executive(&spec, true),
        Limiter::new(&spec.vehicle),
    );
    let mut events = EventLog::new(std::io::stdout().lock());
    while !robot.executive().mode().is_final() && robot.now().as_secs_f64() < 600.0 {
        robot
            .step(&[], &mut [&mut events])
            .map_err(anyhow::Error::from_boxed)?;
    }
    let estimate = robot.estimate();
    let truth = robot.platform().pose;
    eprintln!(
        "{:?} after {:.1} s: the room {:.3} × {:.3} m (truly 5 × 4), the robot at ({:.3}, {:.3}) \
         estimated, ({:.3}, {:.3}) truly",
        robot.executive().mode(),
        robot.now().as_secs_f64(),
        estimate.room_m[0],
        estimate.room_m[1],
        estimate.pose.x,
        estimate.pose.y,
        truth.x,
        truth.y,
    );
    Ok(())
}
