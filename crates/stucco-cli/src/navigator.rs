//! The robot's loop in the simulator, as the experiments close it: the
//! encoders and the room search's walls and doors feed the room filter, a
//! law's command goes through the vehicle's limits, the truth stays aside
//! (read only to score).

use nalgebra::{DVector, SVector};
use stucco_control::Limiter;
use stucco_core::{DriveCommand, EncoderSample, Platform, Pose2, Stamp};
use stucco_nav::{
    DoorConfig, OdometryConfig, RoomConfig, RoomCovariance, RoomEkf, RoomEkfConfig, RoomSearch,
    RoomState, ScanPoints, Wall, find_doors_moving, sensor_twist, twist_at,
};
use stucco_sim::{SimConfig, Simulator, WorldSpec};

/// Control period, s.
pub const DT_S: f64 = 0.02;

/// A simulated robot navigating a rectangular room with the room filter.
pub struct Navigator {
    sim: Simulator,
    ekf: RoomEkf,
    search: RoomSearch,
    limiter: Limiter,
    odometry: OdometryConfig,
    mount: Pose2,
    samples: Vec<EncoderSample>,
    doors: DoorConfig,
}

impl Navigator {
    /// The robot of `world` with `seed`, its filter starting at `x0` with
    /// a few centimetres and a degree of uncertainty on the pose and
    /// `size_sigma_m` on the room's size.
    pub fn new(
        world: &WorldSpec,
        seed: u64,
        x0: RoomState,
        size_sigma_m: [f64; 2],
    ) -> anyhow::Result<Self> {
        let cfg = SimConfig::default();
        let vehicle = cfg.vehicle.clone();
        let cfg_laser = cfg.laser.clone();
        let odometry = OdometryConfig::for_vehicle(&vehicle);
        let p0 = RoomCovariance::from_diagonal(&SVector::<f64, 5>::new(
            4e-4,
            4e-4,
            2e-4,
            size_sigma_m[0].powi(2),
            size_sigma_m[1].powi(2),
        ));
        Ok(Navigator {
            sim: Simulator::new(world, cfg, Some(seed)),
            ekf: RoomEkf::new(
                RoomEkfConfig::new(odometry.clone(), vehicle.laser_mount),
                x0,
                p0,
                Stamp::ZERO,
            ),
            search: RoomSearch::new(RoomConfig::default())?,
            limiter: Limiter::new(&vehicle),
            odometry,
            mount: vehicle.laser_mount,
            samples: Vec::new(),
            doors: DoorConfig::for_laser(&cfg_laser),
        })
    }

    /// The filter's estimate now.
    pub fn estimate(&self) -> DVector<f64> {
        self.ekf.now().0
    }

    /// Puts a door into the filter's state (see [`RoomEkf::add_door`]).
    pub fn add_door(&mut self, wall: usize, position_m: f64, sigma_m: f64) -> usize {
        self.ekf.add_door(wall, position_m, sigma_m).index
    }

    /// The true pose (for scoring only).
    pub fn truth(&self) -> Pose2 {
        self.sim.truth().drive.pose
    }

    /// One control period at `speed_mps` with steering `steer_rad`;
    /// returns the true pose after it, or `None` when the robot touched
    /// something (an experiment's lane must be clear).
    pub fn step(&mut self, speed_mps: f64, steer_rad: f64) -> Option<Pose2> {
        let cmd = self.limiter.limit(
            DriveCommand {
                speed_mps,
                steer_rad,
            },
            DT_S,
        );
        self.sim.command(cmd);
        let r = self.sim.advance(DT_S);
        for e in &r.encoders {
            self.ekf.odometry(*e);
            self.samples.push(*e);
        }
        for scan in &r.scans {
            let twist = sensor_twist(
                &twist_at(&self.samples, scan.stamp, &self.odometry),
                &self.mount,
            );
            let pts = ScanPoints::from_scan_deskewed(scan, &twist);
            let walls: Vec<Wall> = self
                .search
                .find(&pts)
                .map(|room| room.walls.into_iter().flatten().collect())
                .unwrap_or_default();
            let doors = find_doors_moving(scan, &twist, &walls, &self.doors);
            self.ekf.scan(scan.stamp, &walls, &doors);
        }
        let t = self.sim.truth();
        (!t.bumper).then_some(t.drive.pose)
    }
}
