//! The simulator: a world, a robot and its sensors stepped in fixed
//! physics steps of simulated time. It is a [`Platform`]; ground truth is
//! kept apart, in [`Simulator::truth`] and [`Simulator::layout`].

use crate::deposition::{Coat, Deposition, SprayerSpec, SurfaceKind, ToolState};
use crate::layout::Layout;
use crate::plane::PlaneCaster;
use crate::scene::Scene;
use crate::sensors::{CameraRig, FaultConfig, LaserRig};
use crate::vehicle::{ActuatorFaults, Drive, DriveState, DynamicsConfig};
use crate::world::WorldSpec;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use stucco_core::{
    CameraSpec, DriveCommand, EncoderSample, LaserSpec, Platform, PlatformError, Pose2, Readings,
    RobotSpec, Scan, Stamp, ThicknessGrid, ToolCommand, VehicleSpec,
};

/// How to simulate: the robot, its sensors, the floor and the faults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// The robot.
    pub vehicle: VehicleSpec,
    /// Its scanning laser.
    pub laser: LaserSpec,
    /// Its range camera, if it has one.
    pub camera: Option<CameraSpec>,
    /// Tyres, slip and encoder errors.
    pub dynamics: DynamicsConfig,
    /// Sensor faults.
    pub faults: FaultConfig,
    /// Physics steps per second.
    pub physics_rate_hz: f64,
    /// Its sprayer, if it carries one: then plaster is laid on the true
    /// surfaces.
    pub sprayer: Option<SprayerSpec>,
}

impl Default for SimConfig {
    /// The papers' robot with the IBEO laser, a range camera looking left,
    /// physics at 100 Hz.
    fn default() -> Self {
        SimConfig {
            vehicle: VehicleSpec::default(),
            laser: LaserSpec::ibeo_ladar_2d(),
            camera: Some(CameraSpec::default()),
            dynamics: DynamicsConfig::default(),
            faults: FaultConfig::default(),
            physics_rate_hz: 100.0,
            sprayer: None,
        }
    }
}

impl SimConfig {
    /// The simulated robot as its software knows it: vehicle and sensors.
    pub fn robot(&self) -> RobotSpec {
        RobotSpec {
            vehicle: self.vehicle.clone(),
            laser: self.laser.clone(),
            camera: self.camera.clone(),
        }
    }
}

/// The run's random streams, one per source of noise: what one source
/// draws leaves every other's draws as they were, so carrying another
/// laser (or a camera) drives the same drive, slip for slip.
#[derive(Clone, Copy)]
#[repr(u64)]
enum Stream {
    /// The people's walks and the drive's slip and creep.
    World = 0,
    /// The laser's range noise and faults.
    Laser = 1,
    /// The fixed camera's noise.
    Camera = 2,
    /// The sprayer carriage's camera's noise.
    ToolCamera = 3,
}

impl Stream {
    /// This stream of the run seeded `seed`.
    fn of(self, seed: u64) -> ChaCha8Rng {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(self as u64);
        rng
    }
}

/// The truth about the robot, for tests and reports only.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Truth {
    /// Simulated time.
    pub stamp: Stamp,
    /// The drive's true state.
    pub drive: DriveState,
    /// True when the robot is pressed against something.
    pub bumper: bool,
    /// People's poses.
    pub people: Vec<Pose2>,
}

/// A simulation of one robot in one world.
pub struct Simulator {
    layout: Layout,
    scene: Scene,
    drive: Drive,
    laser: LaserRig,
    laser_rng: ChaCha8Rng,
    camera: Option<(CameraRig, ChaCha8Rng)>,
    /// The camera on the sprayer's carriage.
    tool_camera: Option<(CameraRig, ChaCha8Rng)>,
    faults: FaultConfig,
    /// The world's noise: the people's walks, the drive's slip and creep.
    rng: ChaCha8Rng,
    step_ns: i64,
    now_ns: i64,
    odometry_period_ns: i64,
    next_odometry_ns: i64,
    command: DriveCommand,
    bumper: bool,
    /// Scans held back by a delay fault: (due, scan).
    delayed: VecDeque<(i64, Scan)>,
    /// Encoder counts frozen by a stuck-encoder fault.
    frozen: Option<EncoderSample>,
    /// The sprayer and the plaster laid.
    deposition: Option<Deposition>,
}

impl Simulator {
    /// Advances the simulation by `dt_s` seconds (whole physics steps)
    /// and returns what its sensors delivered meanwhile: [`Platform::advance`],
    /// which a simulation never fails.
    pub fn advance(&mut self, dt_s: f64) -> Readings {
        let mut out = Readings::default();
        let steps = (dt_s * 1e9 / self.step_ns as f64).round().max(1.0) as usize;
        for _ in 0..steps {
            self.step(&mut out);
        }
        out
    }

    /// A simulation of `world` with `config`; `seed` overrides the world's.
    pub fn new(world: &WorldSpec, config: SimConfig, seed: Option<u64>) -> Simulator {
        let seed = seed.unwrap_or(world.seed);
        let mut rng = Stream::World.of(seed);
        let layout = Layout::of(world);
        let start = Pose2::new(
            world.robot.at[0],
            world.robot.at[1],
            world.robot.heading_deg.to_radians(),
        );
        let scene = Scene::build(&layout, &world.people, &config.vehicle, &mut rng);
        let odometry_period_ns = (1e9 / config.vehicle.odometry_rate_hz.max(1e-6)).round() as i64;
        Simulator {
            laser: LaserRig::new(
                config.laser.clone(),
                config.vehicle.laser_mount,
                PlaneCaster::new(&layout, config.vehicle.laser_height_m),
            ),
            laser_rng: Stream::Laser.of(seed),
            camera: config
                .camera
                .clone()
                .map(|c| (CameraRig::new(c), Stream::Camera.of(seed))),
            tool_camera: config
                .sprayer
                .as_ref()
                .and_then(|s| s.camera.clone())
                .map(|c| (CameraRig::new(c), Stream::ToolCamera.of(seed))),
            drive: Drive::new(config.vehicle.clone(), config.dynamics.clone(), start),
            faults: config.faults,
            scene,
            rng,
            step_ns: (1e9 / config.physics_rate_hz.max(1.0)).round() as i64,
            now_ns: 0,
            odometry_period_ns,
            next_odometry_ns: odometry_period_ns,
            command: DriveCommand::STOP,
            bumper: false,
            delayed: VecDeque::new(),
            frozen: None,
            deposition: config.sprayer.map(|s| Deposition::new(s, &layout)),
            layout,
        }
    }

    /// The true state of the robot.
    pub fn truth(&self) -> Truth {
        Truth {
            stamp: Stamp::from_nanos(self.now_ns),
            drive: self.drive.state().clone(),
            bumper: self.bumper,
            people: self.scene.people(),
        }
    }

    /// Casts the cameras' rays through rapier's query pipeline, as the
    /// simulator did before its own caster: the benchmarks' baseline (the
    /// readings differ by rapier's f32 rounding).
    pub fn cast_cameras_through_rapier(&mut self) {
        self.scene.rapier_cameras = true;
    }

    /// The true walls, openings and rooms.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The plaster on every true surface, when the robot carries a
    /// sprayer.
    pub fn coats(&self) -> &[Coat] {
        self.deposition.as_ref().map_or(&[], |d| d.coats())
    }

    /// The sprayer's true state, when the robot carries one.
    pub fn tool_state(&self) -> Option<ToolState> {
        self.deposition.as_ref().map(Deposition::state)
    }

    /// Plaster that has left the nozzle, m³.
    pub fn sprayed_m3(&self) -> f64 {
        self.deposition.as_ref().map_or(0.0, Deposition::sprayed_m3)
    }

    /// Puts back plaster laid by an earlier run (resuming from a
    /// checkpoint): grids matched by room and surface.
    pub fn restore_coats(
        &mut self,
        coats: &[(String, SurfaceKind, ThicknessGrid)],
        sprayed_m3: f64,
    ) {
        if let Some(d) = &mut self.deposition {
            d.restore(coats, sprayed_m3);
        }
    }

    /// One physics step: the drive moves unless something is in the way,
    /// the people walk, the sensors read.
    fn step(&mut self, out: &mut Readings) {
        let dt = self.step_ns as f64 * 1e-9;
        let (t0, t1) = (self.now_ns, self.now_ns + self.step_ns);
        let before = self.drive.state().pose;
        // The people where they are at the step's end, none walking into
        // the robot.
        self.scene.step_to(t1 as f64 * 1e-9, Some(&before));
        let t = t0 as f64 * 1e-9;
        let faults = ActuatorFaults {
            stalled: self.faults.stalled_drive.is_some_and(|i| i.contains(t)),
            steering_stuck: self.faults.stuck_steering.is_some_and(|i| i.contains(t)),
        };
        let next = self.drive.propose(&self.command, dt, faults, &mut self.rng);
        self.bumper = self.scene.blocked(&before, &next.pose);
        if self.bumper {
            self.drive.halt();
            out.bumper = true;
        } else {
            self.drive.commit(next, dt, &mut self.rng);
        }
        let twist = self.drive.state().twist;
        let pose = self.drive.state().pose;
        if let Some(d) = &mut self.deposition {
            d.step(dt, &before, &pose);
        }
        for scan in self.laser.sweep(
            &self.scene,
            t0,
            t1,
            &before,
            &twist,
            &self.faults,
            &mut self.laser_rng,
        ) {
            let due = scan.stamp.as_nanos() + (self.faults.scan_delay_s * 1e9).round() as i64;
            self.delayed.push_back((due, scan));
        }
        if let Some((cam, rng)) = &mut self.camera {
            let origin = [0.0, 0.0, cam.spec().height_m];
            out.profiles
                .extend(cam.shoot(&self.scene, t0, t1, &before, &twist, origin, rng));
        }
        if let (Some((cam, rng)), Some(d)) = (&mut self.tool_camera, &self.deposition) {
            let origin = d.state().nozzle_m;
            out.profiles
                .extend(cam.shoot(&self.scene, t0, t1, &before, &twist, origin, rng));
        }
        while self.next_odometry_ns <= t1 {
            let stamp = Stamp::from_nanos(self.next_odometry_ns);
            out.encoders.push(self.read_encoders(stamp));
            self.next_odometry_ns += self.odometry_period_ns;
        }
        self.now_ns = t1;
        while self.delayed.front().is_some_and(|(due, _)| *due <= t1) {
            if let Some((_, scan)) = self.delayed.pop_front() {
                out.scans.push(scan);
            }
        }
    }

    fn read_encoders(&mut self, stamp: Stamp) -> EncoderSample {
        let mut sample = self.drive.encoders(stamp);
        let t = stamp.as_secs_f64();
        match &self.faults.stuck_encoder {
            Some(f) if (f.from_s..f.until_s).contains(&t) => {
                let held = *self.frozen.get_or_insert(sample);
                if f.wheel == 0 {
                    sample.left_ticks = held.left_ticks;
                } else {
                    sample.right_ticks = held.right_ticks;
                }
            }
            _ => self.frozen = None,
        }
        sample
    }
}

impl Platform for Simulator {
    fn now(&self) -> Stamp {
        Stamp::from_nanos(self.now_ns)
    }

    fn command(&mut self, drive: DriveCommand) {
        self.command = drive;
    }

    fn tool(&mut self, cmd: ToolCommand) {
        if let Some(d) = &mut self.deposition {
            d.command(cmd);
        }
    }

    fn advance(&mut self, dt_s: f64) -> Result<Readings, PlatformError> {
        Ok(Simulator::advance(self, dt_s))
    }
}
