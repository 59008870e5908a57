//! The `stucco` command-line tool. Start reading here: each subcommand is a
//! job of the library (`stucco_cli`), this file only parses arguments,
//! shows progress and prints reports.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;
use stucco_cli::{ExtractorKind, WallsJob, run_walls};

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
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Walls {
            log,
            extractor,
            out,
            json,
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
                        match serde_json::to_string(&report) {
                            Ok(s) => println!("{s}"),
                            Err(e) => {
                                eprintln!("error: {e}");
                                return ExitCode::FAILURE;
                            }
                        }
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
