//! The `stucco` command-line tool. Start reading here: each subcommand is a
//! job of the library (`stucco_cli`), this file only parses arguments,
//! shows progress and prints reports.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use stucco_cli::{Axis, StudyJob, run_study};
use stucco_cli::{
    BadInput, ExtractorKind, Mission, MissionReport, MissionSummary, RunJob, SimbenchJob,
    TaskMissionJob, WallsJob, replay_run, run_mission, run_simbench, run_task_mission, run_walls,
};
use stucco_cli::{LinkConfig, Operator, PlatformKind, RobotJob, ServeJob, run_robot, serve};
use stucco_cli::{LogReplayJob, OdomNoise, OdometrySource, Reference, run_log_replay};
use stucco_core::{Command as Tc, Reply, Side, SurfaceId, WallName};
use stucco_link::Mode;

/// stucco: software of an autonomous spray-plastering robot.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Extract walls and door openings from every scan of a CARMEN laser log,
    /// place them in the world with the log's poses, and report timing and
    /// consistency.
    Walls {
        /// The log (`.log` or `.log.gz`).
        log: PathBuf,
        /// The line extractor.
        #[arg(long, value_enum, default_value = "rwht")]
        extractor: ExtractorKind,
        /// Write `walls.jsonl` (per scan, in the laser frame) and `walls.svg`
        /// (the world wall map) here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
        /// Run the previous implementation of the RWHT extractor and the
        /// door search instead (`stucco_nav::baseline`), to time and
        /// compare them side by side.
        #[arg(long)]
        baseline: bool,
    },
    /// Run a mission in the simulator — its tasks carried out by the
    /// executive, or one of the navigation experiments — seeds in
    /// parallel, and report against the truth. Exit code: 0 mission done,
    /// 1 mission failed, 2 bad input.
    Run {
        /// The mission file (`missions/*.toml`).
        mission: PathBuf,
        /// Seed of the first run, instead of the mission's.
        #[arg(long)]
        seed: Option<u64>,
        /// Runs (per condition, for experiments), instead of the mission's.
        #[arg(long)]
        runs: Option<u64>,
        /// Write report.json, events.jsonl, map.svg and checkpoint.json here
        /// (task missions; one folder per seed with --runs).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Go on from DIR/checkpoint.json, never redoing a finished task.
        #[arg(long)]
        resume: bool,
        /// Stop after this many simulated seconds, as if switched off (a
        /// task mission's checkpoint keeps what was finished).
        #[arg(long, value_parser = parse_seconds)]
        stop_after: Option<f64>,
        /// Record the run to DIR/run.mcap (sensor-derived inputs, commands,
        /// events, the true pose; open it in Foxglove).
        #[arg(long)]
        record: bool,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// The robot process: the mission's world in the simulator paced to the
    /// wall clock, its tasks then the operator's, commanded and watched over
    /// zenoh under `stucco/NAME/...`.
    Robot {
        /// The mission file (its world, start and failsafe; its tasks).
        mission: PathBuf,
        /// The robot's name on the network.
        #[arg(long)]
        name: String,
        /// Endpoints to listen on (e.g. `tcp/127.0.0.1:7447`).
        #[arg(long)]
        listen: Vec<String>,
        /// Endpoints (peers, a router) to connect to.
        #[arg(long)]
        connect: Vec<String>,
        /// A zenoh configuration file (JSON5).
        #[arg(long)]
        zenoh_config: Option<PathBuf>,
        /// Simulated seconds per wall-clock second.
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
        /// Stop after this many simulated seconds.
        #[arg(long, value_parser = parse_seconds)]
        stop_after: Option<f64>,
        /// Join as a client of the router `--connect` names, not as a peer.
        #[arg(long)]
        client: bool,
        /// The job's folder: a checkpoint after every unit of work (as
        /// `stucco run` writes), the events, the report when it stops.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Go on from the checkpoint in `--out`: a robot switched off in
        /// the middle of a job finishes it.
        #[arg(long)]
        resume: bool,
        /// Record the run to `--out`/run.mcap (open it in Foxglove).
        #[arg(long)]
        record: bool,
        /// Leave when the mission's tasks are over, instead of waiting for
        /// the operator's commands.
        #[arg(long)]
        exit_when_done: bool,
        /// The robot's body: the simulator in this process, or a platform
        /// on zenoh under `stucco/NAME/platform/` (`stucco sim serve`, a
        /// real robot's driver).
        #[arg(long, value_enum, default_value_t = PlatformKind::Sim)]
        platform: PlatformKind,
        /// How long a platform on zenoh may stay silent (to be found, or
        /// within a period) before the robot stops, s.
        #[arg(long, default_value_t = 10.0)]
        platform_timeout: f64,
    },
    /// The simulator on its own: `stucco sim serve WORLD --name NAME`.
    Sim {
        /// What to do.
        #[command(subcommand)]
        action: SimAction,
    },
    /// A zenoh router for a site: robots and operators connect to it
    /// (`--client`) and it routes between them; runs until stopped.
    Router {
        /// Endpoints to listen on (e.g. `tcp/0.0.0.0:7447`).
        #[arg(long, required = true)]
        listen: Vec<String>,
        /// A zenoh configuration file (JSON5).
        #[arg(long)]
        zenoh_config: Option<PathBuf>,
    },
    /// The operator's console: `stucco op list`, or `stucco op NAME
    /// <command>` (a telecommand, `watch` or `bench`). Exit code: 0 done or
    /// accepted, 1 rejected or failed, 2 bad input.
    Op {
        /// A robot's name, or `list`.
        target: String,
        /// What to do.
        #[command(subcommand)]
        action: Option<OpAction>,
        /// Endpoints (peers, a router) to connect to.
        #[arg(long, global = true)]
        connect: Vec<String>,
        /// A zenoh configuration file (JSON5).
        #[arg(long, global = true)]
        zenoh_config: Option<PathBuf>,
        /// Who is commanding.
        #[arg(long = "as", global = true, default_value = "operator")]
        identity: String,
        /// Wait for the command to be done or failed, at most this many
        /// seconds.
        #[arg(long, global = true)]
        wait: Option<f64>,
        /// The command is stale after this many seconds of the robot's time.
        #[arg(long, global = true, default_value_t = 10.0)]
        deadline: f64,
        /// Print the result as JSON.
        #[arg(long, global = true)]
        json: bool,
        /// Join as a client of the router `--connect` names, not as a peer.
        #[arg(long, global = true)]
        client: bool,
    },
    /// Build a map of walls from a CARMEN log with the map-building EKF
    /// (odometry and front-laser scans), write the trajectory and the map,
    /// and with a reference print the relative pose error of the filter
    /// and of the odometry.
    Replay {
        /// The log (`.log` or `.log.gz`).
        log: PathBuf,
        /// Compare with the robot poses of this log (matched by stamp).
        #[arg(long, conflicts_with = "reference_from_log")]
        reference: Option<PathBuf>,
        /// Compare with the robot poses written in the log itself.
        #[arg(long)]
        reference_from_log: bool,
        /// Where the odometry comes from: the laser lines' odometry pose or
        /// the log's ODOM lines.
        #[arg(long, value_enum, default_value = "scan")]
        odometry: OdometrySource,
        /// Make the odometry worse: `scale=0.02,drift_deg_per_m=1,
        /// trans_sigma_m=0.01,rot_sigma_deg=0.5,seed=1` (any keys omitted
        /// are 0).
        #[arg(long)]
        odom_noise: Option<OdomNoise>,
        /// Write trajectory.csv, map.json and map.svg here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Pair each pose for the RPE with the first one this far along the
        /// reference path, m.
        #[arg(long, default_value_t = stucco_cli::RPE_PAIR_DISTANCE_M)]
        rpe_distance: f64,
        /// Move the filter by the odometry alone, not corrected by scan
        /// matching (only the walls correct it).
        #[arg(long)]
        no_scan_matching: bool,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Replay a run recorded with `stucco run --record` through the
    /// executive and check it gives the same command at every tick. Exit
    /// code: 0 identical, 1 not, 2 bad input.
    ReplayRun {
        /// The recording (`DIR/run.mcap`).
        recording: PathBuf,
        /// Print the result as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// The sensor study (the sensor-precision paper): drive a world's tour,
    /// make the laser worse one axis at a time (maximum range, angular
    /// resolution, field of view, range noise), map each setting with the
    /// wall-map EKF over several seeds and score its relative pose error
    /// and map against the truth; compare the paper's three scanners on the
    /// same drive. Writes DIR/{range,resolution,fov,noise,scanners}.csv,
    /// a plot per axis (SVG and PNG) and DIR/study.json. Exit code: 0 done,
    /// 1 failed, 2 bad input.
    Study {
        /// The study file (`missions/studies/*.toml`).
        study: PathBuf,
        /// Seeds per setting, instead of the file's.
        #[arg(long)]
        seeds: Option<u64>,
        /// Where the CSVs and plots go.
        #[arg(long, default_value = "out/study")]
        out: PathBuf,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// The operator link's figures (`stucco bench stop`, `stucco bench
    /// commands`).
    Bench {
        /// What to measure.
        #[command(subcommand)]
        action: BenchAction,
    },
    /// Run the simulator with one robot driving its world's tour and report
    /// the real-time factor and a hash of every sensor reading.
    Simbench {
        /// The world file (`sim/worlds/*.toml`).
        world: PathBuf,
        /// Seed, instead of the world's.
        #[arg(long)]
        seed: Option<u64>,
        /// Simulated seconds to run.
        #[arg(long, default_value_t = 60.0)]
        sim_seconds: f64,
        /// Run it again with the previous implementation (the cameras cast
        /// through rapier) and print both.
        #[arg(long)]
        baseline: bool,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Generate buildings and run each one's job (plaster every room) in
    /// the simulator, seeds in parallel; print a row a building: its
    /// rooms, the job's outcome and its true scores.
    Buildings {
        /// The first seed.
        #[arg(long, default_value_t = 0)]
        from: u64,
        /// How many seeds.
        #[arg(long, default_value_t = 10)]
        count: u64,
        /// Folder for the buildings and their jobs (`DIR/seed-N`).
        #[arg(long)]
        out: PathBuf,
        /// Stop each job after this many simulated seconds (as if switched
        /// off: its outcome `stopped`, its scores as far as it got).
        #[arg(long, value_parser = parse_seconds)]
        stop_after: Option<f64>,
        /// Print the rows as one JSON array on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Generate a building nobody has seen: `DIR/world.toml` (the truth),
    /// `DIR/plan.toml` (its drawing, exact or off by up to 3 cm) and
    /// `DIR/mission.toml` (plaster every room, nothing else).
    Worldgen {
        /// The building's seed: the same seed, the same building.
        #[arg(long)]
        seed: u64,
        /// Folder to write into (made if missing).
        #[arg(long)]
        out: PathBuf,
    },
}

/// What `stucco sim` does.
#[derive(Subcommand, Clone, Debug)]
enum SimAction {
    /// Serve a simulated robot as a platform over zenoh: its readings on
    /// `stucco/NAME/platform/readings`, its drive and tool commands taken
    /// on `stucco/NAME/platform/command` (docs/platform.md). Runs until
    /// stopped.
    Serve {
        /// The world file (`sim/worlds/*.toml`).
        world: PathBuf,
        /// The platform's name on the network.
        #[arg(long)]
        name: String,
        /// A mission whose robot to simulate: its sprayer, seed and people.
        #[arg(long)]
        mission: Option<PathBuf>,
        /// Seed, instead of the mission's or the world's.
        #[arg(long)]
        seed: Option<u64>,
        /// Step only when the period's command has come (a run the same
        /// whatever the link's delays).
        #[arg(long)]
        lockstep: bool,
        /// Free-running: simulated seconds per wall-clock second.
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
        /// Stop after this many simulated seconds.
        #[arg(long, value_parser = parse_seconds)]
        stop_after: Option<f64>,
        /// Endpoints to listen on (e.g. `tcp/127.0.0.1:7447`).
        #[arg(long)]
        listen: Vec<String>,
        /// Endpoints (peers, a router) to connect to.
        #[arg(long)]
        connect: Vec<String>,
        /// A zenoh configuration file (JSON5).
        #[arg(long)]
        zenoh_config: Option<PathBuf>,
        /// Join as a client of the router `--connect` names, not as a peer.
        #[arg(long)]
        client: bool,
    },
}

/// What `stucco op NAME` does.
#[derive(Subcommand, Clone, Debug)]
enum OpAction {
    /// Is it there? (a harmless query)
    Status,
    /// Stop now (the e-stop lane).
    Stop,
    /// Pause the mission.
    Pause,
    /// Resume it.
    Resume,
    /// Give the mission up.
    Abort,
    /// Give the current task up.
    Skip,
    /// Answer a task waiting for the operator.
    Continue,
    /// Map the room.
    MapRoom,
    /// Plaster one surface of the room, whole (the robot surveys, plans
    /// and sprays with the mission's spray tool).
    Plaster {
        /// The surface: a wall by its index (in a rectangular room also
        /// west, south, east or north) or ceiling.
        #[arg(long, value_parser = parse_surface)]
        surface: SurfaceId,
        /// Only a part of the wall: FROM,TO along it and BOTTOM,TOP above
        /// the floor, m (e.g. `--region 1.0,2.5,0.0,1.2`).
        #[arg(long, value_parser = parse_region)]
        region: Option<stucco_core::Region>,
    },
    /// Go to a room of the floor plan, through the doors on the way.
    GoToRoom {
        /// The room, by its name on the plan.
        #[arg(long)]
        room: String,
    },
    /// Drive through a door the robot knows.
    PassDoor {
        /// The door's index.
        #[arg(long)]
        door: usize,
    },
    /// Move relative to where the robot is.
    Move {
        /// Forward, m.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        dx: f64,
        /// Left, m.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        dy: f64,
        /// Turn, degrees.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        dtheta: f64,
        /// Move to (dx, dy, dθ) in this wall's frame (facing it from
        /// inside, origin at its middle, y to the left) instead of the
        /// robot's.
        #[arg(long, value_parser = parse_wall, conflicts_with = "door")]
        wall: Option<WallName>,
        /// Move to (dx, dy, dθ) in this door's frame (facing it from
        /// inside, origin at its middle): `--door 0 --dx -1` stands a
        /// metre before it.
        #[arg(long)]
        door: Option<usize>,
    },
    /// Follow a wall at a standoff.
    FollowWall {
        /// The wall: its index (in a rectangular room also west, south,
        /// east or north).
        #[arg(long, value_parser = parse_wall)]
        wall: WallName,
        /// Distance from the wall, m.
        #[arg(long)]
        standoff: f64,
        /// Start along the wall, m.
        #[arg(long)]
        from: f64,
        /// End along the wall, m.
        #[arg(long)]
        to: f64,
    },
    /// Stop parallel to a wall.
    Align {
        /// The wall: its index (in a rectangular room also west, south,
        /// east or north).
        #[arg(long, value_parser = parse_wall)]
        wall: WallName,
        /// Distance from the wall, m.
        #[arg(long)]
        standoff: f64,
        /// Position along it, m.
        #[arg(long)]
        at: f64,
        /// The wall on the robot's right (left by default).
        #[arg(long)]
        right: bool,
    },
    /// Drive directly for a moment.
    Jog {
        /// Front-wheel speed, m/s (negative: backwards).
        #[arg(long, allow_negative_numbers = true)]
        speed: f64,
        /// Steering, degrees (negative: to the right).
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        steer: f64,
        /// Time to live, s.
        #[arg(long, default_value_t = 0.5)]
        ttl: f64,
    },
    /// Follow the robot: its state, events, replies, map and plastering
    /// coverage as lines a person reads (with --json, every message as it
    /// comes, one JSON object a line).
    Watch {
        /// Stop after this many seconds.
        #[arg(long)]
        seconds: Option<f64>,
    },
    /// Command → acknowledgement latency over N status queries.
    Bench {
        /// Commands to send.
        #[arg(long, default_value_t = 1000)]
        count: usize,
    },
    /// Subscribe to everything the robot publishes and never read it (a
    /// client that froze): for tests and `stucco bench stop`.
    #[command(hide = true)]
    Stall,
}

/// What `stucco bench` measures.
#[derive(Subcommand, Clone, Debug)]
enum BenchAction {
    /// Stop → zero velocity: a robot on loopback jogs and is stopped, again
    /// and again, while another operator sends it other commands and a
    /// client that froze (a `stucco` process of its own) subscribes to
    /// everything it publishes.
    Stop {
        /// The robot's mission.
        #[arg(long, default_value = "missions/robot.toml")]
        mission: PathBuf,
        /// Stops to time.
        #[arg(long, default_value_t = 200)]
        stops: usize,
        /// Other commands a second.
        #[arg(long, default_value_t = 1000.0)]
        other_per_s: f64,
        /// Without the client that froze.
        #[arg(long)]
        no_frozen_client: bool,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Memory over many commands: a robot on loopback takes N status
    /// commands, each with its own id, and this process's resident memory
    /// is read at every tenth.
    Commands {
        /// The robot's mission.
        #[arg(long, default_value = "missions/robot.toml")]
        mission: PathBuf,
        /// Commands to send.
        #[arg(long, default_value_t = 1_000_000)]
        count: u64,
        /// Their rate, per second.
        #[arg(long, default_value_t = 5000.0)]
        per_s: f64,
        /// Print the report as one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
}

fn parse_surface(s: &str) -> Result<SurfaceId, String> {
    match s {
        "ceiling" => Ok(SurfaceId::Ceiling),
        wall => parse_wall(wall).map(SurfaceId::Wall).map_err(|_| {
            format!("{s}: a wall's index (0, 1, ...), west, south, east, north or ceiling")
        }),
    }
}

fn parse_region(s: &str) -> Result<stucco_core::Region, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [a0, a1, z0, z1] => Ok(stucco_core::Region {
            along_m: [a0, a1],
            height_m: [z0, z1],
        }),
        _ => Err(format!(
            "{s:?}: four numbers FROM,TO,BOTTOM,TOP (m), not {}",
            v.len()
        )),
    }
}

fn parse_wall(s: &str) -> Result<WallName, String> {
    s.parse()
}

/// A span of time in seconds: a number more than 0.
fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(_) => Err(format!("{s} s: a time more than 0 s, and finite")),
        Err(e) => Err(format!("{s}: {e}")),
    }
}

/// `stucco bench`.
fn bench(action: BenchAction) -> ExitCode {
    match action {
        BenchAction::Stop {
            mission,
            stops,
            other_per_s,
            no_frozen_client,
            json,
        } => {
            let frozen_client = if no_frozen_client {
                None
            } else {
                match std::env::current_exe() {
                    Ok(exe) => Some(exe),
                    Err(e) => return fail(&anyhow::anyhow!("finding this program: {e}")),
                }
            };
            match stucco_cli::bench_stop(&stucco_cli::StopBenchJob {
                mission,
                stops,
                flood_per_s: other_per_s,
                frozen_client,
            }) {
                Ok(r) if json => print_json(&r),
                Ok(r) => {
                    println!(
                        "{} stops, {} other commands at {:.0}/s{}: stop sent → a state showing the drive at zero received in {:.1} ms (median), {:.1} ms (p99), {:.1} ms at most; zero from control period {} after the stop at the latest",
                        r.stops,
                        r.other_commands,
                        r.other_commands_per_s,
                        if r.frozen_client {
                            ", a client that froze subscribed"
                        } else {
                            ""
                        },
                        r.stop_to_zero_ms_p50,
                        r.stop_to_zero_ms_p99,
                        r.stop_to_zero_ms_max,
                        r.periods_to_zero_max
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&e),
            }
        }
        BenchAction::Commands {
            mission,
            count,
            per_s,
            json,
        } => match stucco_cli::bench_commands(&stucco_cli::CommandsBenchJob {
            mission,
            count,
            per_s,
        }) {
            Ok(r) if json => print_json(&r),
            Ok(r) => {
                println!(
                    "{} commands at {:.0}/s: resident memory {:.1} MB after a tenth, {:.1} MB at the end ({:+.1} MB), {:.1} MB at most",
                    r.commands,
                    r.per_s,
                    r.rss_at_tenth_mb,
                    r.rss_at_end_mb,
                    r.rss_at_end_mb - r.rss_at_tenth_mb,
                    r.rss_max_mb
                );
                ExitCode::SUCCESS
            }
            Err(e) => fail(&e),
        },
    }
}

/// `stucco op`.
#[allow(clippy::too_many_arguments)]
fn op(
    target: String,
    action: Option<OpAction>,
    link: LinkConfig,
    identity: String,
    wait: Option<f64>,
    deadline: f64,
    json: bool,
) -> ExitCode {
    let mut operator = match Operator::connect(&link, &identity) {
        Ok(o) => o,
        Err(e) => return fail(&e),
    };
    let Some(action) = action else {
        if target == "list" {
            return match operator.list() {
                Ok(names) if json => print_json(&names),
                Ok(names) => {
                    for n in names {
                        println!("{n}");
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&e),
            };
        }
        eprintln!("error: stucco op {target}: what? (a command, watch or bench; see --help)");
        return ExitCode::from(2);
    };
    let command = match action {
        OpAction::Watch { seconds } => {
            return match operator.watch(&target, seconds, json, |line| println!("{line}")) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => fail(&e),
            };
        }
        OpAction::Bench { count } => {
            return match operator.bench(&target, count.max(1)) {
                Ok(r) if json => print_json(&r),
                Ok(r) => {
                    println!(
                        "{} commands to {target}: acknowledged in {:.3} ms (median), {:.3} ms (p99), {:.3} ms at most",
                        r.count, r.p50_ms, r.p99_ms, r.max_ms
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&e),
            };
        }
        OpAction::Stall => {
            return match operator.stall(&target) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => fail(&e),
            };
        }
        OpAction::Status => Tc::Status,
        OpAction::Stop => Tc::Stop,
        OpAction::Pause => Tc::Pause,
        OpAction::Resume => Tc::Resume,
        OpAction::Abort => Tc::Abort,
        OpAction::Skip => Tc::Skip,
        OpAction::Continue => Tc::Continue,
        OpAction::MapRoom => Tc::MapRoom,
        OpAction::Plaster { surface, region } => Tc::PlasterSurface { surface, region },
        OpAction::PassDoor { door } => Tc::PassDoor { door },
        OpAction::GoToRoom { room } => Tc::GoToRoom { room },
        OpAction::Move {
            dx,
            dy,
            dtheta,
            wall,
            door,
        } => Tc::MoveRelative {
            dx_m: dx,
            dy_m: dy,
            dtheta_deg: dtheta,
            landmark: wall
                .map(stucco_core::Landmark::Wall)
                .or(door.map(stucco_core::Landmark::Door)),
        },
        OpAction::FollowWall {
            wall,
            standoff,
            from,
            to,
        } => Tc::FollowWall {
            wall,
            standoff_m: standoff,
            from_m: from,
            to_m: to,
        },
        OpAction::Align {
            wall,
            standoff,
            at,
            right,
        } => Tc::AlignToWall {
            wall,
            standoff_m: standoff,
            at_m: at,
            side: if right { Side::Right } else { Side::Left },
        },
        OpAction::Jog { speed, steer, ttl } => Tc::Jog {
            speed_mps: speed,
            steer_rad: steer.to_radians(),
            ttl_s: ttl,
        },
    };
    let wait = wait.map(std::time::Duration::from_secs_f64);
    match operator.send(&target, command, deadline, wait) {
        Ok(r) => {
            let last = r.last.as_ref().unwrap_or(&r.ack);
            if json {
                print_json(&r);
            } else {
                println!("{target}: {}", describe(&r.ack.reply));
                if let Some(l) = &r.last {
                    println!("{target}: {}", describe(&l.reply));
                }
            }
            match last.reply {
                Reply::Accepted | Reply::Done => ExitCode::SUCCESS,
                _ => ExitCode::FAILURE,
            }
        }
        Err(e) => fail(&e),
    }
}

fn describe(r: &Reply) -> String {
    match r {
        Reply::Accepted => "accepted".to_owned(),
        Reply::Done => "done".to_owned(),
        Reply::Rejected { reason } => format!("rejected: {reason}"),
        Reply::Failed { reason, .. } => format!("failed: {reason}"),
    }
}

/// Prints `value` as one line of JSON.
fn print_json(value: &impl serde::Serialize) -> ExitCode {
    match serde_json::to_string(value) {
        Ok(s) => {
            println!("{s}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Reports `e`; exit code 2 for bad input, 1 for the rest.
fn fail(e: &anyhow::Error) -> ExitCode {
    eprintln!("error: {e:#}");
    let bad_config = matches!(
        e.downcast_ref::<stucco_link::LinkError>(),
        Some(stucco_link::LinkError::Config { .. })
    );
    if e.downcast_ref::<BadInput>().is_some() || bad_config {
        ExitCode::from(2)
    } else {
        ExitCode::FAILURE
    }
}

/// `stucco study`: progress over the mapping runs, then a table per axis.
fn run_study_command(job: StudyJob, json: bool) -> ExitCode {
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} runs mapped, {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(job.study.display().to_string());
    let result = run_study(&job, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    let report = match result {
        Ok(r) => r,
        Err(e) => return fail(&e),
    };
    if json {
        return print_json(&report);
    }
    println!(
        "{}: {} de-featured on {}, walls by {}, {} seeds × {:.0} s, RPE pairs {} m apart; {} runs mapped from {} drives in {:.1} s",
        report.study,
        report.laser,
        report.world,
        report.extractor,
        report.seeds,
        report.seconds,
        report.rpe_pair_m,
        report.runs_mapped,
        report.runs_driven,
        report.wall_seconds
    );
    let table = |title: &str, rows: &[stucco_cli::SettingReport]| {
        if rows.is_empty() {
            return;
        }
        println!(
            "{title:<14} {:>20} {:>22} {:>18} {:>9}",
            "trans m (mean ± std)", "rot rad (mean ± std)", "odometry m / rad", "map σ mm"
        );
        for r in rows {
            println!(
                "{:<14} {:>9.4} ± {:<8.4} {:>10.5} ± {:<9.5} {:>8.4} / {:<7.4} {:>9.1}",
                r.setting,
                r.rpe.trans_mean_m,
                r.rpe.trans_std_m,
                r.rpe.rot_mean_rad,
                r.rpe.rot_std_rad,
                r.odom_rpe.trans_mean_m,
                r.odom_rpe.rot_mean_rad,
                r.map_dist_rms_m * 1e3
            );
        }
    };
    for axis in Axis::ALL {
        table(axis.name(), report.axis(axis));
    }
    table("scanner", &report.scanners);
    if !report.scanner_differences.is_empty() {
        println!(
            "{:<30} {:>22} {:>22}",
            "drive by drive (mean ± s.e.)", "trans m", "rot rad"
        );
        let se = |s: Option<f64>| s.map_or_else(|| "—".to_owned(), |s| format!("{s:.5}"));
        for d in &report.scanner_differences {
            println!(
                "{:<30} {:>+10.5} ± {:<9} {:>+10.5} ± {:<9}",
                format!("{} − {}", d.a, d.b),
                d.trans_m.mean,
                se(d.trans_m.se),
                d.rot_rad.mean,
                se(d.rot_rad.se),
            );
        }
    }
    if let Some(dir) = &job.out {
        println!(
            "wrote {0}/{{range,resolution,fov,noise,scanners}}.csv, {0}/*.svg, {0}/*.png and {0}/study.json",
            dir.display()
        );
    }
    ExitCode::SUCCESS
}

/// `stucco run` on a task mission.
fn run_tasks(job: TaskMissionJob, json: bool) -> ExitCode {
    let bar = ProgressBar::new_spinner().with_style(
        ProgressStyle::with_template("{spinner} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let hear = |sim_s: f64, task: &str| {
        bar.set_message(format!("{sim_s:7.1} s simulated · {task}"));
        bar.tick();
    };
    let result = run_task_mission(&job, &hear);
    bar.finish_and_clear();
    let summary = match result {
        Ok(s) => s,
        Err(e) => return fail(&e),
    };
    if json {
        if summary.runs.len() == 1 {
            print_json(&summary.runs[0]);
        } else {
            print_json(&summary);
        }
    } else {
        print_summary(&summary);
    }
    if summary.outcome == "done" {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

fn print_run(r: &MissionReport) {
    println!(
        "{} (seed {}): {}{} — {:.1} s simulated in {:.2} s ({:.0}× real time)",
        r.mission,
        r.seed,
        r.outcome,
        r.reason
            .as_ref()
            .map(|w| format!(": {w}"))
            .unwrap_or_default(),
        r.sim_seconds,
        r.wall_seconds,
        r.real_time_factor
    );
    for (i, t) in r.tasks.iter().enumerate() {
        let secs = t.seconds.map(|s| format!("{s:6.1} s")).unwrap_or_default();
        println!(
            "  {i:>2} {:<18} {:<8} {secs}",
            t.name,
            status_name(&t.status)
        );
    }
    println!(
        "  room {:.3} × {:.3} m (true {:.3} × {:.3}, σ {:.1}/{:.1} mm); position RMS {:.1} mm (max {:.1}), heading RMS {:.2}°; {:.1} m driven, {} safety stops",
        r.room_m[0],
        r.room_m[1],
        r.room_true_m[0],
        r.room_true_m[1],
        r.room_sigma_m[0] * 1e3,
        r.room_sigma_m[1] * 1e3,
        r.pose_rms_m * 1e3,
        r.pose_max_m * 1e3,
        r.heading_rms_rad.to_degrees(),
        r.path_length_m,
        r.safety_stops
    );
    if let Some(c) = &r.consistency {
        println!(
            "  the filter's covariance against its errors: mean NEES {:.1} (position, 2 if honest), {:.1} (heading, 1 if honest); heading σ RMS {:.3}°",
            c.position_nees,
            c.heading_nees,
            c.heading_sigma_rms_rad.to_degrees()
        );
    }
    if let Some(e) = &r.rpe_1m {
        println!(
            "  relative pose error over 1 m ({} pairs): {:.1} ± {:.1} mm, {:.3} ± {:.3}°",
            e.pairs,
            e.trans_mean_m * 1e3,
            e.trans_std_m * 1e3,
            e.rot_mean_rad.to_degrees(),
            e.rot_std_rad.to_degrees()
        );
    }
    for p in &r.passes {
        println!(
            "  pass along {} (task {}): standoff {:.2} m held to {:.1} mm RMS (max {:.1}, mean {:+.1})",
            p.wall,
            p.task,
            p.standoff_m,
            p.rms_error_m * 1e3,
            p.max_error_m * 1e3,
            p.mean_error_m * 1e3
        );
    }
    for w in &r.windows {
        println!(
            "  window in {} from {:.3} to {:.3} m, sill {:.3} m, head {:.3} m ({} passes){}",
            w.wall,
            w.along_m[0],
            w.along_m[1],
            w.sill_head_m[0],
            w.sill_head_m[1],
            w.observations,
            w.edge_error_m
                .map(|e| format!(": edges within {:.1} cm of the true window", e * 1e2))
                .unwrap_or_else(|| ": no true window there".to_owned())
        );
    }
    if r.windows_total > 0 {
        println!(
            "  windows found: {} of {}",
            r.windows_found, r.windows_total
        );
    }
    for d in &r.doors {
        println!(
            "  door in {} at {:.3} m{}: {:.1} cm from the true door",
            d.wall,
            d.position_m,
            d.width_m
                .map(|w| format!(", {w:.2} m wide"))
                .unwrap_or_default(),
            d.error_m * 1e2
        );
    }
    if let Some(t) = r.plaster.as_ref().and_then(|p| p.truth.as_ref()) {
        println!(
            "  on every true surface of {}: walls {}%, ceiling {}% of what the tool can reach \
             within the coat's tolerance; {:.2} m² left unreached, {:.2} m² blocked",
            t.rooms.join(", "),
            pct_or_dash(t.walls.coverage_pct()),
            pct_or_dash(t.ceilings.coverage_pct()),
            t.walls.unreached_m2 + t.ceilings.unreached_m2,
            t.walls.blocked_m2 + t.ceilings.blocked_m2,
        );
        for b in t.blockers.iter().filter(|b| b.area_m2 >= 0.1) {
            println!("    {}", b.advice);
        }
    }
    if let Some(p) = &r.plaster {
        let pct = |x: Option<f64>| x.unwrap_or(0.0);
        println!(
            "  as planned, from {} stations: walls {:.2}%, ceiling {:.2}% of the plan's reach within \
             the coat's tolerance; CV {:.2}%, over-thick {:.2}%, {:.1} L sprayed, {:.2}% into openings",
            p.stations,
            pct(r.wall_coverage_pct),
            pct(r.ceiling_coverage_pct),
            100.0 * pct(r.thickness_cv),
            pct(r.double_sprayed_pct),
            p.sprayed_l,
            pct(r.overspray_pct)
        );
        println!(
            "  unreachable (reported, not plastered): {:.2} m²; plastering took {:.0} s against a \
             lower bound of {:.0} s",
            p.unreachable_m2,
            pct(r.mission_time_s),
            pct(r.mission_time_lower_bound_s)
        );
        for left in &p.rooms_left {
            println!(
                "  not plastered: {} ({:.1} m² of floor): {}",
                left.room, left.floor_m2, left.why
            );
        }
    }
}

/// A percentage to two places, or a dash when there is none.
fn pct_or_dash(x: Option<f64>) -> String {
    x.map_or("—".to_owned(), |v| format!("{v:.2}"))
}

fn status_name(s: &stucco_mission::TaskStatus) -> String {
    match s {
        stucco_mission::TaskStatus::Failed { reason } => format!("failed: {reason}"),
        other => serde_json::to_value(other)
            .ok()
            .and_then(|v| v["state"].as_str().map(str::to_owned))
            .unwrap_or_default(),
    }
}

fn print_summary(s: &MissionSummary) {
    for r in &s.runs {
        print_run(r);
    }
    if s.runs.len() > 1 {
        println!(
            "{}: {}/{} runs done, {:.0} s simulated in {:.1} s ({:.0}× real time)",
            s.mission,
            s.done,
            s.runs.len(),
            s.sim_seconds,
            s.wall_seconds,
            s.real_time_factor
        );
    }
}

/// `stucco run` on an experiment mission.
fn run_experiment(job: RunJob, json: bool) -> ExitCode {
    match run_mission(&job) {
        Ok(report) if json => print_json(&report),
        Ok(r) => {
            println!("{}: {} runs from seed {}", r.mission, r.runs, r.seed);
            for c in &r.conditions {
                println!(
                    "  {:>18}: lateral σ {:.1} mm (mean {:+.1}), heading σ {:.2} mrad (mean {:+.2})",
                    c.name,
                    c.lateral_std_m * 1e3,
                    c.lateral_mean_m * 1e3,
                    c.heading_std_rad * 1e3,
                    c.heading_mean_rad * 1e3
                );
                if let Some(e) = c.door_estimate_rms_m {
                    println!("  {:>18}  door estimate RMS {:.1} mm", "", e * 1e3);
                }
            }
            if let (Some(sd), Some(m)) = (r.room_size_std_m, r.room_size_mean_m) {
                println!(
                    "  room {:.4} × {:.4} m, σ {:.1} mm; position RMS {:.1} mm, heading RMS {:.3}°",
                    m[0],
                    m[1],
                    sd * 1e3,
                    r.pose_rms_m.unwrap_or(f64::NAN) * 1e3,
                    r.heading_rms_rad.unwrap_or(f64::NAN).to_degrees()
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => fail(&e),
    }
}

/// Writes the building of `seed` into `out`, and says what it is.
fn worldgen(seed: u64, out: &std::path::Path) -> anyhow::Result<()> {
    let b = stucco_sim::generate(seed);
    stucco_cli::write_building(&b, out)?;
    let w = &b.world;
    // How much of it this robot could plaster at all: every surface bare,
    // scored on the truth.
    let tool = stucco_plan::SprayTool::default();
    let layout = stucco_sim::Layout::of(w);
    let coats = stucco_sim::Deposition::new(stucco_cli::sprayer_of(&tool), &layout);
    let (reach, finish) = stucco_cli::true_terms(&tool, &stucco_core::VehicleSpec::default());
    let rooms: Vec<String> = w.rooms.iter().map(|r| r.name.clone()).collect();
    let start = stucco_core::Pose2::new(
        w.robot.at[0],
        w.robot.at[1],
        w.robot.heading_deg.to_radians(),
    );
    let t = stucco_sim::score_truth(&layout, coats.coats(), &rooms, &start, &reach, &finish);
    let shapes: Vec<String> = b.shapes.iter().map(|(n, k)| format!("{n} {k}")).collect();
    println!(
        "building {seed}: a {:.2} m corridor and {} room(s) ({}); {} door(s), {} shut; {} window(s); \
         {} piece(s) of furniture; {} people; plasterable: walls {:.1} m² ({:.1} m² out of this \
         robot's reach), ceilings {:.1} m² ({:.1} m² out of reach); written to {}",
        w.rooms[0].corners[2][1],
        b.shapes.len(),
        shapes.join(", "),
        w.doors.len(),
        w.doors.iter().filter(|d| !d.open).count(),
        w.windows.len(),
        w.tables.len() + w.chairs.len() + w.boxes.len() + w.columns.len(),
        w.people.len(),
        t.walls.plasterable_m2,
        t.walls.blocked_m2,
        t.ceilings.plasterable_m2,
        t.ceilings.blocked_m2,
        out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            mission,
            seed,
            runs,
            out,
            resume,
            stop_after,
            record,
            json,
        } => {
            let tasks = match Mission::load(&mission) {
                Ok(m) => !m.tasks.is_empty(),
                Err(e) => return fail(&e.into()),
            };
            if tasks {
                run_tasks(
                    TaskMissionJob {
                        mission,
                        seed,
                        runs,
                        out,
                        resume,
                        stop_after_s: stop_after,
                        record,
                    },
                    json,
                )
            } else {
                run_experiment(
                    RunJob {
                        mission,
                        seed,
                        runs,
                    },
                    json,
                )
            }
        }
        Command::Robot {
            mission,
            name,
            listen,
            connect,
            zenoh_config,
            speed,
            stop_after,
            client,
            out,
            resume,
            record,
            exit_when_done,
            platform,
            platform_timeout,
        } => {
            if !(platform_timeout.is_finite() && platform_timeout > 0.0) {
                eprintln!("error: --platform-timeout: a positive number of seconds");
                return ExitCode::from(2);
            }
            let job = RobotJob {
                mission,
                name,
                link: LinkConfig {
                    mode: if client { Mode::Client } else { Mode::Peer },
                    listen,
                    connect,
                    config_file: zenoh_config,
                },
                speed,
                stop_after_s: stop_after,
                exit_when_done,
                out,
                resume,
                record,
                platform,
                platform_timeout: std::time::Duration::from_secs_f64(platform_timeout),
            };
            match run_robot(&job, &stop_on_signal()) {
                Ok(run) => {
                    eprintln!(
                        "robot {}: mission {}, {:.1} s simulated, {} message(s) refused by access control",
                        job.name,
                        run.outcome,
                        run.simulated_s,
                        run.denials.len()
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&e),
            }
        }
        Command::Sim {
            action:
                SimAction::Serve {
                    world,
                    name,
                    mission,
                    seed,
                    lockstep,
                    speed,
                    stop_after,
                    listen,
                    connect,
                    zenoh_config,
                    client,
                },
        } => {
            let job = ServeJob {
                world,
                name,
                link: LinkConfig {
                    mode: if client { Mode::Client } else { Mode::Peer },
                    listen,
                    connect,
                    config_file: zenoh_config,
                },
                mission,
                seed,
                lockstep,
                speed,
                stop_after_s: stop_after,
            };
            match serve(&job, &stop_on_signal()) {
                Ok(run) => {
                    eprintln!(
                        "platform {}: {} periods, {:.1} s simulated, {} command(s) refused",
                        job.name, run.periods, run.simulated_s, run.refused
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&e),
            }
        }
        Command::Op {
            target,
            action,
            connect,
            zenoh_config,
            identity,
            wait,
            deadline,
            json,
            client,
        } => op(
            target,
            action,
            LinkConfig {
                mode: if client { Mode::Client } else { Mode::Peer },
                listen: Vec::new(),
                connect,
                config_file: zenoh_config,
            },
            identity,
            wait,
            deadline,
            json,
        ),
        Command::Router {
            listen,
            zenoh_config,
        } => {
            let cfg = LinkConfig {
                mode: Mode::Router,
                listen,
                connect: Vec::new(),
                config_file: zenoh_config,
            };
            match stucco_link::router(&cfg) {
                Ok(_session) => {
                    eprintln!("router on {:?} (Ctrl-C stops it)", cfg.listen);
                    loop {
                        std::thread::park();
                    }
                }
                Err(e) => fail(&anyhow::Error::from(e)),
            }
        }
        Command::Replay {
            log,
            reference,
            reference_from_log,
            odometry,
            odom_noise,
            out,
            rpe_distance,
            no_scan_matching,
            json,
        } => {
            let reference = match (reference, reference_from_log) {
                (Some(path), _) => Reference::Log(path),
                (None, true) => Reference::FromLog,
                (None, false) => Reference::None,
            };
            let job = LogReplayJob {
                log,
                reference,
                odometry,
                odom_noise,
                out,
                rpe_distance_m: rpe_distance,
                scan_matching: !no_scan_matching,
            };
            let bar = ProgressBar::new(0).with_style(
                ProgressStyle::with_template("{bar:30} {pos}/{len} scans {per_sec} {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar.set_message(job.log.display().to_string());
            let result = run_log_replay(&job, |done, total| {
                if done % 16 == 0 || done == total {
                    bar.set_length(total as u64);
                    bar.set_position(done as u64);
                }
            });
            bar.finish_and_clear();
            match result {
                Ok(report) if json => print_json(&report),
                Ok(report) => {
                    println!(
                        "{}: {} scans, {} walls in the map ({} of the building); {:.2} walls matched and {:.2} discarded as doubtful a scan; scan median {:.0} µs, p99 {:.0} µs",
                        report.log,
                        report.scans,
                        report.map_walls,
                        report.building_walls,
                        report.matched_per_scan,
                        report.doubtful_per_scan,
                        report.median_scan_us,
                        report.p99_scan_us
                    );
                    let show = |name: &str, r: &Option<stucco_nav::Rpe>| {
                        if let Some(r) = r {
                            println!(
                                "  {name:<9} RPE over {} pairs {} m apart: {:.4} ± {:.4} m, {:.4} ± {:.4} rad",
                                r.pairs,
                                report.rpe_pair_distance_m,
                                r.trans_mean_m,
                                r.trans_std_m,
                                r.rot_mean_rad,
                                r.rot_std_rad
                            );
                        }
                    };
                    if report.scan_matching {
                        println!(
                            "  scan matching: {:.1} % of the scans registered on the last ones",
                            100.0 * report.scans_matched_share
                        );
                    }
                    show("filter", &report.rpe);
                    show("odometry", &report.odom_rpe);
                    if let Some(dir) = &job.out {
                        println!(
                            "wrote {0}/trajectory.csv, {0}/map.json and {0}/map.svg",
                            dir.display()
                        );
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(2)
                }
            }
        }
        Command::ReplayRun { recording, json } => match replay_run(&recording) {
            Ok(r) => {
                if json {
                    print_json(&r);
                } else {
                    println!(
                        "{}: {} ticks replayed, {} commands identical{}",
                        r.mission,
                        r.ticks,
                        r.identical,
                        r.first_difference
                            .map(|(t, a, b)| format!(
                                "; first difference at {:.2} s: recorded {a:?}, replayed {b:?}",
                                t.as_secs_f64()
                            ))
                            .unwrap_or_default()
                    );
                }
                if r.identical == r.ticks && r.ticks > 0 {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::FAILURE
                }
            }
            Err(e) => fail(&e),
        },
        Command::Study {
            study,
            seeds,
            out,
            json,
        } => run_study_command(
            StudyJob {
                study,
                seeds,
                out: Some(out),
            },
            json,
        ),
        Command::Bench { action } => bench(action),
        Command::Buildings {
            from,
            count,
            out,
            stop_after,
            json,
        } => match stucco_cli::run_buildings(from..from.saturating_add(count), &out, stop_after) {
            Ok(rows) if json => print_json(&rows),
            Ok(rows) => {
                print!("{}", stucco_cli::buildings_table(&rows));
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        },
        Command::Worldgen { seed, out } => match worldgen(seed, &out) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        },
        Command::Simbench {
            world,
            seed,
            sim_seconds,
            baseline,
            json,
        } => match run_simbench(&SimbenchJob {
            world,
            seed,
            sim_seconds,
            baseline,
        }) {
            Ok(report) if json => print_json(&report),
            Ok(r) => {
                println!(
                    "{}: {:.0} simulated s in {:.2} s — {:.0}× real time; {} scans ({} beams), {} odometry samples, {} profiles, {} bumps; trace {}",
                    r.world,
                    r.sim_seconds,
                    r.wall_seconds,
                    r.real_time_factor,
                    r.scans,
                    r.beams,
                    r.encoder_samples,
                    r.profiles,
                    r.bumps,
                    r.trace_hash
                );
                if let Some(b) = r.baseline {
                    println!(
                        "  baseline ({}): {:.2} s — {:.0}× real time; trace {}; {:.2}× faster now",
                        b.implementation,
                        b.wall_seconds,
                        b.real_time_factor,
                        b.trace_hash,
                        b.speedup
                    );
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        },
        Command::Walls {
            log,
            extractor,
            out,
            json,
            baseline,
        } => {
            let bar = ProgressBar::new_spinner().with_style(
                ProgressStyle::with_template("{spinner} {pos} scans {per_sec} {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            bar.set_message(log.display().to_string());
            let job = WallsJob {
                log,
                extractor,
                out,
                baseline,
            };
            let result = run_walls(&job, |n| {
                if n % 64 == 0 {
                    bar.set_position(n as u64);
                }
            });
            bar.finish_and_clear();
            match result {
                Ok(report) => {
                    if json {
                        return print_json(&report);
                    } else {
                        println!(
                            "{} scans of {} with {:?}: {:.2} walls and {:.2} doors a scan; extraction median {:.0} µs, p99 {:.0} µs; \
                             {} world walls re-observed {} times, spread {:.4} m / {:.5} rad",
                            report.scans,
                            report.log,
                            report.extractor,
                            report.walls_per_scan,
                            report.doors_per_scan,
                            report.median_extract_us,
                            report.p99_extract_us,
                            report.world_walls,
                            report.reobservations,
                            report.wall_spread_m,
                            report.wall_spread_rad
                        );
                        if let Some(dir) = &job.out {
                            println!("wrote {0}/walls.jsonl and {0}/walls.svg", dir.display());
                        }
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}

/// A flag set when the process is asked to stop (Ctrl-C, SIGTERM): a
/// robot ends its loop at a period's end, writes its last checkpoint and
/// report, and leaves.
fn stop_on_signal() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    if let Err(e) =
        ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed))
    {
        eprintln!("warning: Ctrl-C will kill the process at once: {e}");
    }
    stop
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic)]
mod tests {
    use super::*;

    /// Moves and jogs backwards or to the right take negative numbers as
    /// the README writes them.
    #[test]
    fn negative_moves_and_jogs_parse() {
        let action = |args: &[&str]| match Cli::try_parse_from(args).unwrap().command {
            Command::Op {
                action: Some(a), ..
            } => a,
            _ => panic!("not an op command"),
        };
        let back = action(&["stucco", "op", "r1", "move", "--door", "0", "--dx", "-1"]);
        assert!(
            matches!(back, OpAction::Move { dx, .. } if dx == -1.0),
            "{back:?}"
        );
        let jog = action(&[
            "stucco", "op", "r1", "jog", "--speed", "-0.2", "--steer", "-10",
        ]);
        assert!(
            matches!(jog, OpAction::Jog { speed, steer, .. } if speed == -0.2 && steer == -10.0),
            "{jog:?}"
        );
    }
}
