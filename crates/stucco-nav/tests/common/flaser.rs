//! The front-laser scans (`FLASER` lines) of a CARMEN log, read just well
//! enough to run extractors on real scans in tests and benches: the beam
//! layout CARMEN guesses from the number of readings, readings of 80 m or
//! more as no returns (the Radish logs' 80.99 and 81.9x mean none). The
//! full reader is `stucco-cli`'s `carmen` module.
#![allow(dead_code)]

use flate2::read::GzDecoder;
use std::f64::consts::{FRAC_PI_2, PI};
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use stucco_core::{Scan, Stamp};

/// Readings at or beyond this are no returns, m.
const MAX_RANGE_M: f64 = 80.0;

/// The repository's copies of the Radish logs (`tests/data/carmen`).
pub fn repo_log(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/carmen")
        .join(name)
}

/// A log of the shared data beside the repository
/// (`../shared/data/carmen`), which the repository does not copy.
pub fn shared_log(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/carmen")
        .join(name)
}

/// Every FLASER scan of the log at `path`, in order.
pub fn flaser_scans(path: &Path) -> std::io::Result<Vec<Scan>> {
    let file = std::fs::File::open(path)?;
    let input: Box<dyn Read> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(GzDecoder::new(file))
    } else {
        Box::new(file)
    };
    let bad = |what: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_owned());
    let mut scans = Vec::new();
    for line in BufReader::new(input).lines() {
        let line = line?;
        let mut toks = line.split_whitespace();
        if toks.next() != Some("FLASER") {
            continue;
        }
        let n: usize = toks
            .next()
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| bad("FLASER num_readings"))?;
        let ranges = toks
            .take(n)
            .map(|t| t.parse::<f64>().map_err(|_| bad("FLASER range")))
            .collect::<Result<Vec<_>, _>>()?;
        if ranges.len() != n {
            return Err(bad("FLASER: fewer ranges than num_readings"));
        }
        let deg = PI / 180.0;
        let step = match n {
            180 | 181 => deg,
            360 | 361 => 0.5 * deg,
            n => PI / (n.max(2) - 1) as f64,
        };
        scans.push(Scan::new(
            Stamp::ZERO,
            "front",
            -FRAC_PI_2,
            step,
            0.0,
            0.0,
            MAX_RANGE_M,
            ranges,
        ));
    }
    Ok(scans)
}
