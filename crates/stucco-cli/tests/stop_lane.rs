//! A stop always wins: a robot on loopback jogs and is stopped, again and
//! again, while another operator sends it a thousand commands a second and
//! a client that froze (the real binary, `stucco op NAME stall`, in a
//! process of its own) subscribes to everything it publishes and never
//! reads. Every stop brings the drive command to zero in the very next
//! control period. The wall-clock figures are `stucco bench stop`'s.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

#[test]
fn a_stop_zeroes_the_drive_in_the_next_period_whatever_else_the_link_carries() {
    let report = stucco_cli::bench_stop(&stucco_cli::StopBenchJob {
        mission: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../missions/robot.toml"),
        stops: 12,
        flood_per_s: 1000.0,
        frozen_client: Some(PathBuf::from(env!("CARGO_BIN_EXE_stucco"))),
    })
    .unwrap();
    println!("{report:?}");
    assert_eq!(report.stops, 12);
    assert!(report.frozen_client);
    assert!(report.other_commands > 0, "{report:?}");
    assert!(report.periods_to_zero_max <= 1, "{report:?}");
}
