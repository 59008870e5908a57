//! Reader for CARMEN robot logs (the text "CLF" format of the Radish data
//! sets: Intel, ACES, Freiburg 079 and 101, Örebro).
//!
//! # Lines understood
//!
//! ```text
//! FLASER n r1 .. rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp
//! RLASER (same layout as FLASER, rear laser)
//! ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp
//! PARAM name value [hostname timestamp ..]
//! ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy
//!     remission_mode num_readings r.. num_remissions rem.. laser_x laser_y laser_theta
//!     robot_x robot_y robot_theta tv rv forward_safety_dist side_safety_dist turn_axis
//!     ipc_timestamp hostname logger_timestamp
//! ```
//!
//! Lines starting with `#` and blank lines are ignored. Every other message
//! type (`NEFF`, `SYNC`, `TRUEPOS`, `RAWLASER1`, `ROBOTLASER2`, ...) is
//! skipped and counted per type ([`CarmenReader::skipped`]), never an error.
//! Tokens after `logger_timestamp` are ignored, as CARMEN's own reader
//! ignores them (it stops parsing after the hostname).
//!
//! # Beam angles of old-style laser lines
//!
//! FLASER and RLASER lines carry no angles, only the number of readings.
//! CARMEN guesses the layout from that number, and this reader follows it
//! exactly: `carmen_string_to_robot_laser_message_orig` in CARMEN's
//! `readlog.c` (logger module; e.g. `src/logger/readlog.c` in the
//! LCAD-UFES/carmen_lcad fork) sets `start_angle = -M_PI / 2`,
//! `fov = carmen_laser_guess_fov(n)`,
//! `angular_resolution = carmen_laser_guess_angle_increment(n)` and
//! `maximum_range = 80.0`:
//!
//! | readings | first beam | increment | field of view               |
//! |---------:|-----------:|----------:|-----------------------------|
//! | 181      | −90°       | 1°        | 180°                        |
//! | 180      | −90°       | 1°        | 179° (last beam "ignored")  |
//! | 361      | −90°       | 0.5°      | 180°                        |
//! | 360      | −90°       | 0.5°      | 179.5° (last beam "ignored")|
//! | other n  | −90°       | 180°/(n−1)| 180°                        |
//!
//! Beams sweep counter-clockwise (right to left) in the laser frame. For 400
//! and 401 readings CARMEN guesses a 100° (99.75°) field at 0.25° but still
//! starts it at −90°; a SICK LMS sweeps its 100° mode centred on the
//! forward axis, so here those two start at −fov/2 instead (the only
//! departure from CARMEN). See [`CarmenBeamLayout::for_readings`].
//!
//! # Maximum range and no-returns
//!
//! A SICK LMS reports "no echo" and its error conditions as the top codes of
//! its range word: 81.83–81.91 m in centimetre mode (the 81.91 of Freiburg,
//! the 81.83 of Intel), 32.759–32.767 m in millimetre mode (Örebro). The
//! ACES log was clipped at exactly 50.0 m. A beam at or beyond the maximum
//! range of its line becomes a no-return (`INFINITY`, see [`Scan::new`]).
//! The maximum range of a FLASER / RLASER line is the smaller of:
//!
//! 1. the logged parameter, if a PARAM line has set it before:
//!    `laser_front_laser_max_range`, else `robot_front_laser_max` (Freiburg:
//!    80.99); `laser_rear_laser_max_range` / `robot_rear_laser_max` for
//!    RLASER; without one, CARMEN's own assumption of 80.0 m
//!    ([`CARMEN_DEFAULT_MAX_RANGE_M`]);
//! 2. the log's saturation level, when the data has one
//!    ([`CarmenSaturation`], [`survey_carmen_saturation`]): the largest
//!    reading of the log, if it appears in at least 5 % of that laser's
//!    lines (and at least 3), lowered to the smallest distinct reading
//!    within 1 cm below it, so that all of a SICK's error codes go together.
//!    This gives 50.0 m for ACES and 32.759 m for Örebro; in Intel and
//!    Freiburg the saturation level lies above 80 m and changes nothing.
//!    Genuine far readings are never repeated like that (in all six Radish
//!    logs the largest genuine reading occurs once or twice).
//!
//! [`read_carmen_file`] and [`open_carmen_file`] apply both; a
//! [`CarmenReader`] over an arbitrary stream applies only the first, plus
//! whatever caps the caller passes to [`CarmenReader::with_saturation_caps`].
//! ROBOTLASER1 lines carry their own `maximum_range`, which is used as is.
//!
//! # Poses
//!
//! The first pose of a FLASER line (`x y theta`) is taken as the robot's
//! pose, the second (`odom_x ..`) as its raw odometry, as GMapping's CARMEN
//! reader does with the `robot_frontlaser_offset` parameter. (CARMEN's robot
//! module, in raw logs, wrote the laser's pose first; the Radish "corrected"
//! logs hold the same corrected pose in both.) The laser sits on the robot
//! at `robot * (robot_frontlaser_offset, 0, 0)`; the rear laser, facing
//! backwards, at `robot * (-robot_rearlaser_offset, 0, π)`, as CARMEN's
//! `robot_laser.c` places it (heading + π, offset along that heading).
//! Offsets default to 0. ROBOTLASER1 lines carry both poses explicitly; their
//! odometry pose is the robot pose.
//!
//! # Time
//!
//! A record's stamp is its `ipc_timestamp`: that is the time CARMEN's
//! `readlog.c` puts in the message (the acquisition time stamped by the
//! sensor's driver), while `logger_timestamp` is when the logger wrote the
//! line. In the Radish logs the two are equal. Both must be present and be
//! decimal seconds; they are parsed exactly with [`Stamp`]'s `FromStr`. Tiny
//! or zero stamps (Örebro's `3.44361e-86`, `0`) are accepted as they are: the
//! reader invents no times and does not require them to increase.
//!
//! The sweep duration of a scan is estimated for a SICK LMS spinning at
//! 75 Hz: `fov / 2π / 75` s (6.6 ms for 179°).

use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

use flate2::read::MultiGzDecoder;
use serde::{Deserialize, Serialize};
use stucco_core::{Pose2, Scan, Stamp};
use thiserror::Error;

/// The maximum range CARMEN's `readlog.c` assumes for old-style laser lines
/// (FLASER, RLASER), m.
pub const CARMEN_DEFAULT_MAX_RANGE_M: f64 = 80.0;

/// Mirror rotation rate of a SICK LMS, Hz: the basis of the sweep-duration
/// estimate.
const SICK_ROTATION_HZ: f64 = 75.0;

/// Readings within this distance below a log's saturation value belong to
/// the saturation band (a SICK's error codes span 8 mm in millimetre mode).
const SATURATION_BAND_M: f64 = 0.01;

/// Share of a laser's lines that must hold the top reading for it to count
/// as a saturation value.
const SATURATION_MIN_SHARE: f64 = 0.05;

/// Fewest lines that must hold the top reading for it to count as a
/// saturation value.
const SATURATION_MIN_LINES: usize = 3;

/// A CARMEN log that cannot be read: which file, which line, which field,
/// and what is wrong with it.
///
/// `line` is 1-based; it is 0 when the file cannot be opened at all. `field`
/// names the message type and field, such as `FLASER range[17]`,
/// `ODOM theta` or `FLASER num_readings`, or `open` / `read` for I/O errors.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error("{file}:{line}: {field}: {message}")]
pub struct CarmenError {
    /// The log's name, as given to the reader (the path for files).
    pub file: String,
    /// 1-based line number; 0 for a file that cannot be opened.
    pub line: usize,
    /// The field at fault, prefixed with its message type.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// Which laser a scan came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum LaserKind {
    /// The front laser: `FLASER` lines.
    Front,
    /// The rear laser: `RLASER` lines.
    Rear,
    /// A new-style robot laser message: `ROBOTLASER1` lines.
    Robot,
}

impl LaserKind {
    /// The sensor id given to the [`Scan`]: `carmen-front`, `carmen-rear` or
    /// `carmen-robotlaser`.
    pub fn sensor_id(self) -> &'static str {
        match self {
            LaserKind::Front => "carmen-front",
            LaserKind::Rear => "carmen-rear",
            LaserKind::Robot => "carmen-robotlaser",
        }
    }

    /// The message type of the log line: `FLASER`, `RLASER` or
    /// `ROBOTLASER1`.
    pub fn message_type(self) -> &'static str {
        match self {
            LaserKind::Front => "FLASER",
            LaserKind::Rear => "RLASER",
            LaserKind::Robot => "ROBOTLASER1",
        }
    }
}

/// One laser line of a log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoggedScan {
    /// 1-based line number in the log.
    pub line: usize,
    /// Which laser.
    pub kind: LaserKind,
    /// The ranges, with no-returns marked, stamped with the `ipc_timestamp`.
    pub scan: Scan,
    /// The robot's pose (FLASER/RLASER: the first pose of the line).
    pub robot_pose: Pose2,
    /// The laser's pose: `robot_pose` composed with the mounting offset
    /// (ROBOTLASER1: the logged laser pose).
    pub laser_pose: Pose2,
    /// The raw odometry pose (FLASER/RLASER: the second pose of the line;
    /// ROBOTLASER1: the robot pose).
    pub odom_pose: Pose2,
}

/// One `ODOM` line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdomRecord {
    /// 1-based line number in the log.
    pub line: usize,
    /// The `ipc_timestamp`.
    pub stamp: Stamp,
    /// The odometry pose.
    pub pose: Pose2,
    /// Forward speed, m/s.
    pub tv_mps: f64,
    /// Turn rate, rad/s.
    pub rv_radps: f64,
    /// Acceleration, m/s².
    pub accel_mps2: f64,
}

/// One record of a log, in file order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Record {
    /// A laser scan (FLASER, RLASER or ROBOTLASER1).
    Laser(LoggedScan),
    /// An odometry reading (ODOM).
    Odometry(OdomRecord),
    /// A parameter (PARAM).
    Param {
        /// Parameter name, such as `robot_frontlaser_offset`.
        name: String,
        /// Its value, as logged.
        value: String,
        /// 1-based line number in the log.
        line: usize,
    },
}

/// A whole log, read into memory by [`read_carmen_file`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CarmenLog {
    /// Where it came from (the path).
    pub source: String,
    /// Laser scans, in file order.
    pub scans: Vec<LoggedScan>,
    /// Odometry readings, in file order.
    pub odometry: Vec<OdomRecord>,
    /// Parameters (the last value wins when one is logged twice).
    pub params: BTreeMap<String, String>,
    /// Lines of other message types, counted per type.
    pub skipped: BTreeMap<String, usize>,
}

/// Beam layout of an old-style (FLASER/RLASER) laser line, which CARMEN
/// guesses from the number of readings alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CarmenBeamLayout {
    /// Bearing of the first beam in the laser frame, rad.
    pub angle_min_rad: f64,
    /// Step between beams, rad (positive: counter-clockwise).
    pub angle_increment_rad: f64,
    /// Field of view, rad.
    pub fov_rad: f64,
}

impl CarmenBeamLayout {
    /// CARMEN's guess for `num_readings` beams (`carmen_laser_guess_fov`
    /// and `carmen_laser_guess_angle_increment` in `readlog.c`; see the
    /// module documentation for the table). 180 readings: −90° to +89° in
    /// 1° steps; 181: −90° to +90°; 360: −90° to +89.5° in 0.5° steps; 361:
    /// −90° to +90°.
    pub fn for_readings(num_readings: usize) -> Self {
        let deg = PI / 180.0;
        let (fov_rad, angle_increment_rad) = match num_readings {
            181 => (PI, deg),
            180 => (179.0 * deg, deg),
            361 => (PI, 0.5 * deg),
            360 => (179.5 * deg, 0.5 * deg),
            401 => (100.0 * deg, 0.25 * deg),
            // CARMEN writes `M_PI / 100.0 * 99.75`; 99.75° is what it means.
            400 => (99.75 * deg, 0.25 * deg),
            0 | 1 => (PI, 0.0),
            n => (PI, PI / (n - 1) as f64),
        };
        let angle_min_rad = match num_readings {
            400 | 401 => -0.5 * fov_rad,
            _ => -FRAC_PI_2,
        };
        CarmenBeamLayout {
            angle_min_rad,
            angle_increment_rad,
            fov_rad,
        }
    }
}

/// Saturation levels found in a log's data: readings at or beyond them are
/// no-returns even where the logged or default maximum range is larger.
/// See the module documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CarmenSaturation {
    /// For FLASER lines, m.
    pub front_m: Option<f64>,
    /// For RLASER lines, m.
    pub rear_m: Option<f64>,
}

impl CarmenSaturation {
    /// The level for one laser (always `None` for ROBOTLASER1, whose lines
    /// carry their own maximum range).
    pub fn for_kind(&self, kind: LaserKind) -> Option<f64> {
        match kind {
            LaserKind::Front => self.front_m,
            LaserKind::Rear => self.rear_m,
            LaserKind::Robot => None,
        }
    }
}

/// Scans a log's FLASER and RLASER lines for a saturation level (see the
/// module documentation), without building any records. Lines that do not
/// parse are passed over here; the reader reports them.
pub fn survey_carmen_saturation<R: BufRead>(
    mut reader: R,
    source_name: &str,
) -> Result<CarmenSaturation, CarmenError> {
    let mut bands = [TopBand::default(), TopBand::default()];
    let mut buf = Vec::new();
    let mut ranges = Vec::new();
    let mut line = 0usize;
    loop {
        buf.clear();
        let read = reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| io_error(source_name, line + 1, "read", &e))?;
        if read == 0 {
            break;
        }
        line += 1;
        let bytes = buf.trim_ascii_start();
        let idx = if bytes.starts_with(b"FLASER") {
            0
        } else if bytes.starts_with(b"RLASER") {
            1
        } else {
            continue;
        };
        let Ok(text) = std::str::from_utf8(bytes) else {
            continue;
        };
        let mut toks = text.split_ascii_whitespace();
        if !matches!(toks.next(), Some("FLASER" | "RLASER")) {
            continue;
        }
        let Some(n) = toks.next().and_then(|t| t.parse::<usize>().ok()) else {
            continue;
        };
        ranges.clear();
        ranges.extend(toks.take(n).filter_map(|t| t.parse::<f64>().ok()));
        bands[idx].add_line(&ranges);
    }
    Ok(CarmenSaturation {
        front_m: bands[0].level(),
        rear_m: bands[1].level(),
    })
}

/// The readings near the top of one laser's log, for finding a saturation
/// level in one pass.
#[derive(Clone, Debug, Default)]
struct TopBand {
    /// Laser lines seen.
    lines: usize,
    /// Distinct readings within [`SATURATION_BAND_M`] of the largest,
    /// ascending.
    entries: Vec<TopEntry>,
}

#[derive(Clone, Copy, Debug)]
struct TopEntry {
    value: f64,
    /// Lines holding this reading.
    lines: usize,
    /// The last line counted, so a line counts once.
    last_line: usize,
}

impl TopBand {
    fn add_line(&mut self, ranges: &[f64]) {
        self.lines += 1;
        let line = self.lines;
        for &r in ranges {
            if !(r.is_finite() && r > 0.0) {
                continue;
            }
            if let Some(top) = self.entries.last()
                && r < top.value - SATURATION_BAND_M
            {
                continue;
            }
            match self.entries.binary_search_by(|e| e.value.total_cmp(&r)) {
                Ok(i) => {
                    let e = &mut self.entries[i];
                    if e.last_line != line {
                        e.lines += 1;
                        e.last_line = line;
                    }
                }
                Err(i) => {
                    self.entries.insert(
                        i,
                        TopEntry {
                            value: r,
                            lines: 1,
                            last_line: line,
                        },
                    );
                    if i + 1 == self.entries.len() {
                        let floor = r - SATURATION_BAND_M;
                        self.entries.retain(|e| e.value >= floor);
                    }
                }
            }
        }
    }

    fn level(&self) -> Option<f64> {
        let top = self.entries.last()?;
        let repeated = top.lines >= SATURATION_MIN_LINES
            && top.lines as f64 >= SATURATION_MIN_SHARE * self.lines as f64;
        repeated.then(|| self.entries.first().map_or(top.value, |e| e.value))
    }
}

/// What the PARAM lines have said about one old-style laser.
#[derive(Clone, Copy, Debug, Default)]
struct LaserParams {
    /// `robot_frontlaser_offset` / `robot_rearlaser_offset`, m.
    offset_m: f64,
    /// `laser_front_laser_max_range` / `laser_rear_laser_max_range`, m.
    laser_max_m: Option<f64>,
    /// `robot_front_laser_max` / `robot_rear_laser_max`, m.
    robot_max_m: Option<f64>,
}

impl LaserParams {
    fn max_range_m(&self) -> f64 {
        self.laser_max_m
            .or(self.robot_max_m)
            .unwrap_or(CARMEN_DEFAULT_MAX_RANGE_M)
    }
}

/// A streaming reader of CARMEN log lines: an iterator of [`Record`]s.
///
/// PARAM lines update the reader's state (laser offsets, maximum ranges), so
/// later laser lines use them. After a malformed line the iterator yields
/// the error and carries on with the next line; after an I/O error it ends.
pub struct CarmenReader<R: BufRead> {
    input: R,
    source: String,
    line_no: usize,
    buf: Vec<u8>,
    finished: bool,
    skipped: BTreeMap<String, usize>,
    front: LaserParams,
    rear: LaserParams,
    caps: CarmenSaturation,
    /// Saturation survey of the lines read so far: front, rear.
    survey: [TopBand; 2],
}

impl<R: BufRead> CarmenReader<R> {
    /// A reader of `reader`; `source_name` names it in errors.
    pub fn new(reader: R, source_name: impl Into<String>) -> Self {
        CarmenReader {
            input: reader,
            source: source_name.into(),
            line_no: 0,
            buf: Vec::new(),
            finished: false,
            skipped: BTreeMap::new(),
            front: LaserParams::default(),
            rear: LaserParams::default(),
            caps: CarmenSaturation::default(),
            survey: [TopBand::default(), TopBand::default()],
        }
    }

    /// Also treats readings at or beyond `caps` as no-returns (typically
    /// from [`survey_carmen_saturation`] over the same log).
    pub fn with_saturation_caps(mut self, caps: CarmenSaturation) -> Self {
        self.caps = caps;
        self
    }

    /// Lines of message types this reader does not parse, counted per type.
    pub fn skipped(&self) -> &BTreeMap<String, usize> {
        &self.skipped
    }

    /// The log's name, as given to [`CarmenReader::new`].
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Number of lines read so far.
    pub fn lines_read(&self) -> usize {
        self.line_no
    }

    /// The maximum range the next FLASER (`Front`) or RLASER (`Rear`) line
    /// will be read with, m; ROBOTLASER1 lines carry their own (`INFINITY`
    /// is returned for `Robot`).
    pub fn max_range_m(&self, kind: LaserKind) -> f64 {
        let base = match kind {
            LaserKind::Front => self.front.max_range_m(),
            LaserKind::Rear => self.rear.max_range_m(),
            LaserKind::Robot => return f64::INFINITY,
        };
        match self.caps.for_kind(kind) {
            Some(cap) if cap < base => cap,
            _ => base,
        }
    }

    /// The mounting of an old-style laser on the robot, from the offsets
    /// logged so far.
    fn mount(&self, kind: LaserKind) -> Pose2 {
        match kind {
            LaserKind::Rear => Pose2::new(-self.rear.offset_m, 0.0, PI),
            _ => Pose2::new(self.front.offset_m, 0.0, 0.0),
        }
    }

    /// The saturation levels of the lines read so far.
    fn observed_saturation(&self) -> CarmenSaturation {
        CarmenSaturation {
            front_m: self.survey[0].level(),
            rear_m: self.survey[1].level(),
        }
    }

    fn error(&self, field: impl Into<String>, message: impl Into<String>) -> CarmenError {
        CarmenError {
            file: self.source.clone(),
            line: self.line_no,
            field: field.into(),
            message: message.into(),
        }
    }

    fn parse_line(&mut self, bytes: &[u8]) -> Result<Option<Record>, CarmenError> {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| self.error("line", format!("not valid UTF-8 ({e})")))?;
        let Some(kind) = text.split_ascii_whitespace().next() else {
            return Ok(None);
        };
        if kind.starts_with('#') {
            return Ok(None);
        }
        let known = matches!(kind, "FLASER" | "RLASER" | "ODOM" | "PARAM" | "ROBOTLASER1");
        if !known {
            if let Some(count) = self.skipped.get_mut(kind) {
                *count += 1;
            } else {
                self.skipped.insert(kind.to_owned(), 1);
            }
            return Ok(None);
        }
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        let record = match kind {
            "FLASER" => self.parse_old_laser(&toks, LaserKind::Front)?,
            "RLASER" => self.parse_old_laser(&toks, LaserKind::Rear)?,
            "ROBOTLASER1" => self.parse_robot_laser(&toks)?,
            "ODOM" => self.parse_odom(&toks)?,
            _ => self.parse_param(&toks)?,
        };
        Ok(Some(record))
    }

    /// FLASER / RLASER.
    fn parse_old_laser(&mut self, toks: &[&str], kind: LaserKind) -> Result<Record, CarmenError> {
        let t = kind.message_type();
        let mut f = Fields::new(toks, t, &self.source, self.line_no);
        let n = f.count("num_readings")?;
        if n == 0 {
            return Err(f.err("num_readings", "is 0: a laser line needs readings".into()));
        }
        // 2 + n ranges, 6 pose values, ipc_timestamp, then the hostname.
        let host_idx = 2 + n + 7;
        if let Some(h) = misplaced_host(toks, host_idx) {
            let found = h.saturating_sub(2 + 7);
            return Err(f.err(
                "num_readings",
                format!(
                    "says {n} readings, but the line holds {found} (counting back from \
                     the hostname `{}`)",
                    toks[h]
                ),
            ));
        }
        if toks.len() < 2 + n {
            return Err(f.err(
                "num_readings",
                format!(
                    "says {n} readings, but only {} values follow",
                    toks.len() - 2
                ),
            ));
        }
        let mut ranges = Vec::with_capacity(n);
        for (i, tok) in toks[2..2 + n].iter().enumerate() {
            let r: f64 = tok
                .parse()
                .map_err(|_| f.err(&format!("range[{i}]"), format!("not a number: `{tok}`")))?;
            ranges.push(r);
        }
        f.pos = 2 + n;
        let robot_pose = f.pose(["x", "y", "theta"])?;
        let odom_pose = f.pose(["odom_x", "odom_y", "odom_theta"])?;
        let stamp = f.stamp("ipc_timestamp")?;
        f.token("hostname")?;
        f.stamp("logger_timestamp")?;

        let idx = if kind == LaserKind::Rear { 1 } else { 0 };
        self.survey[idx].add_line(&ranges);
        let layout = CarmenBeamLayout::for_readings(n);
        let scan = Scan::new(
            stamp,
            kind.sensor_id(),
            layout.angle_min_rad,
            layout.angle_increment_rad,
            sick_sweep_duration_s(layout.fov_rad),
            0.0,
            self.max_range_m(kind),
            ranges,
        );
        Ok(Record::Laser(LoggedScan {
            line: self.line_no,
            kind,
            scan,
            robot_pose,
            laser_pose: robot_pose * self.mount(kind),
            odom_pose,
        }))
    }

    /// ROBOTLASER1.
    fn parse_robot_laser(&mut self, toks: &[&str]) -> Result<Record, CarmenError> {
        let mut f = Fields::new(toks, "ROBOTLASER1", &self.source, self.line_no);
        f.integer("laser_type")?;
        let start_angle = f.finite("start_angle")?;
        let fov = f.finite("field_of_view")?;
        let resolution = f.finite("angular_resolution")?;
        let max_range = f.finite("maximum_range")?;
        if max_range <= 0.0 {
            return Err(f.err("maximum_range", format!("not positive: {max_range}")));
        }
        f.number("accuracy")?;
        f.integer("remission_mode")?;
        let n = f.count("num_readings")?;
        // Ranges start at token 9; num_remissions follows them.
        let Some(rem_tok) = toks.get(9 + n) else {
            return Err(f.err(
                "num_readings",
                format!(
                    "says {n} readings, but only {} values follow",
                    toks.len().saturating_sub(9)
                ),
            ));
        };
        if let Ok(m) = rem_tok.parse::<usize>() {
            // remissions, 6 pose values, 5 motion values, ipc_timestamp.
            let host_idx = 10 + n + m + 12;
            if let Some(h) = misplaced_host(toks, host_idx) {
                return Err(f.err(
                    "num_readings",
                    format!(
                        "num_readings {n} and num_remissions {m} put the hostname at token \
                         {}, but `{}` stands at token {}",
                        host_idx + 1,
                        toks[h],
                        h + 1
                    ),
                ));
            }
        }
        let mut ranges = Vec::with_capacity(n);
        for (i, tok) in toks[9..9 + n].iter().enumerate() {
            let r: f64 = tok
                .parse()
                .map_err(|_| f.err(&format!("range[{i}]"), format!("not a number: `{tok}`")))?;
            ranges.push(r);
        }
        f.pos = 9 + n;
        let m = f.count("num_remissions")?;
        if toks.len() < f.pos + m {
            return Err(f.err(
                "num_remissions",
                format!(
                    "says {m} remissions, but only {} values follow",
                    toks.len() - f.pos
                ),
            ));
        }
        for (i, tok) in toks[f.pos..f.pos + m].iter().enumerate() {
            tok.parse::<f64>()
                .map_err(|_| f.err(&format!("remission[{i}]"), format!("not a number: `{tok}`")))?;
        }
        f.pos += m;
        let laser_pose = f.pose(["laser_x", "laser_y", "laser_theta"])?;
        let robot_pose = f.pose(["robot_x", "robot_y", "robot_theta"])?;
        for field in [
            "tv",
            "rv",
            "forward_safety_dist",
            "side_safety_dist",
            "turn_axis",
        ] {
            f.number(field)?;
        }
        let stamp = f.stamp("ipc_timestamp")?;
        f.token("hostname")?;
        f.stamp("logger_timestamp")?;

        let scan = Scan::new(
            stamp,
            LaserKind::Robot.sensor_id(),
            start_angle,
            resolution,
            sick_sweep_duration_s(fov),
            0.0,
            max_range,
            ranges,
        );
        Ok(Record::Laser(LoggedScan {
            line: self.line_no,
            kind: LaserKind::Robot,
            scan,
            robot_pose,
            laser_pose,
            odom_pose: robot_pose,
        }))
    }

    /// ODOM.
    fn parse_odom(&self, toks: &[&str]) -> Result<Record, CarmenError> {
        let mut f = Fields::new(toks, "ODOM", &self.source, self.line_no);
        const HOST_IDX: usize = 8;
        if let Some(h) = misplaced_host(toks, HOST_IDX) {
            let (count, what) = if h > HOST_IDX {
                (h - HOST_IDX, "too many")
            } else {
                (HOST_IDX - h, "too few")
            };
            return Err(f.err(
                "hostname",
                format!(
                    "expected as token {} (after x y theta tv rv accel ipc_timestamp), but \
                     `{}` stands at token {}: {count} value(s) {what} before it",
                    HOST_IDX + 1,
                    toks[h],
                    h + 1
                ),
            ));
        }
        let pose = f.pose(["x", "y", "theta"])?;
        let tv_mps = f.finite("tv")?;
        let rv_radps = f.finite("rv")?;
        let accel_mps2 = f.finite("accel")?;
        let stamp = f.stamp("ipc_timestamp")?;
        f.token("hostname")?;
        f.stamp("logger_timestamp")?;
        Ok(Record::Odometry(OdomRecord {
            line: self.line_no,
            stamp,
            pose,
            tv_mps,
            rv_radps,
            accel_mps2,
        }))
    }

    /// PARAM: name and value are required; anything after them (hostname,
    /// timestamps, which older logs lack) is ignored.
    fn parse_param(&mut self, toks: &[&str]) -> Result<Record, CarmenError> {
        let mut f = Fields::new(toks, "PARAM", &self.source, self.line_no);
        let name = f.token("name")?;
        let value = f.token("value")?;
        let number = |positive: bool| -> Result<f64, CarmenError> {
            match value.parse::<f64>() {
                Ok(v) if v.is_finite() && (!positive || v > 0.0) => Ok(v),
                _ => Err(f.err(
                    name,
                    format!(
                        "not a {} number: `{value}`",
                        if positive { "positive" } else { "finite" }
                    ),
                )),
            }
        };
        match name {
            "robot_frontlaser_offset" => self.front.offset_m = number(false)?,
            "robot_rearlaser_offset" => self.rear.offset_m = number(false)?,
            "laser_front_laser_max_range" => self.front.laser_max_m = Some(number(true)?),
            "robot_front_laser_max" => self.front.robot_max_m = Some(number(true)?),
            "laser_rear_laser_max_range" => self.rear.laser_max_m = Some(number(true)?),
            "robot_rear_laser_max" => self.rear.robot_max_m = Some(number(true)?),
            _ => {}
        }
        Ok(Record::Param {
            name: name.to_owned(),
            value: value.to_owned(),
            line: self.line_no,
        })
    }
}

impl<R: BufRead> Iterator for CarmenReader<R> {
    type Item = Result<Record, CarmenError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.finished {
                return None;
            }
            self.buf.clear();
            match self.input.read_until(b'\n', &mut self.buf) {
                Ok(0) => {
                    self.finished = true;
                    return None;
                }
                Ok(_) => {}
                Err(e) => {
                    self.finished = true;
                    return Some(Err(io_error(&self.source, self.line_no + 1, "read", &e)));
                }
            }
            self.line_no += 1;
            let buf = std::mem::take(&mut self.buf);
            let parsed = self.parse_line(&buf);
            self.buf = buf;
            match parsed {
                Ok(Some(record)) => return Some(Ok(record)),
                Ok(None) => {}
                Err(e) => return Some(Err(e)),
            }
        }
    }
}

/// Reads a whole log into memory. Gzip-compressed files (recognised by
/// their magic bytes, whatever their name) are decompressed on the fly. The
/// first malformed line ends the read with its error.
pub fn read_carmen_file(path: &Path) -> Result<CarmenLog, CarmenError> {
    let source = path.display().to_string();
    let mut reader = CarmenReader::new(open_decoded(path)?, source.clone());
    let mut log = CarmenLog {
        source,
        ..CarmenLog::default()
    };
    for record in reader.by_ref() {
        match record? {
            Record::Laser(scan) => log.scans.push(scan),
            Record::Odometry(odom) => log.odometry.push(odom),
            Record::Param { name, value, .. } => {
                log.params.insert(name, value);
            }
        }
    }
    // Lowering the maximum range after the fact only turns more finite
    // readings into no-returns: the same result as reading with the caps.
    let caps = reader.observed_saturation();
    for logged in &mut log.scans {
        if let Some(cap) = caps.for_kind(logged.kind)
            && cap < logged.scan.max_range_m
        {
            for r in &mut logged.scan.ranges_m {
                if *r >= cap {
                    *r = f64::INFINITY;
                }
            }
            logged.scan.max_range_m = cap;
        }
    }
    log.skipped = std::mem::take(&mut reader.skipped);
    Ok(log)
}

/// Opens a log for streaming, gunzipping it when it starts with the gzip
/// magic bytes. The file is read twice: once to survey its saturation level
/// ([`survey_carmen_saturation`]), then by the returned reader, so the
/// records equal those of [`read_carmen_file`].
pub fn open_carmen_file(path: &Path) -> Result<CarmenReader<Box<dyn BufRead>>, CarmenError> {
    let source = path.display().to_string();
    let caps = survey_carmen_saturation(open_decoded(path)?, &source)?;
    Ok(CarmenReader::new(open_decoded(path)?, source).with_saturation_caps(caps))
}

/// Opens `path`, decompressing when it starts with the gzip magic bytes.
fn open_decoded(path: &Path) -> Result<Box<dyn BufRead>, CarmenError> {
    let source = path.display().to_string();
    let file = File::open(path).map_err(|e| io_error(&source, 0, "open", &e))?;
    let mut reader = BufReader::new(file);
    let head = reader
        .fill_buf()
        .map_err(|e| io_error(&source, 0, "open", &e))?;
    if head.starts_with(&[0x1f, 0x8b]) {
        Ok(Box::new(BufReader::new(MultiGzDecoder::new(reader))))
    } else {
        Ok(Box::new(reader))
    }
}

fn io_error(file: &str, line: usize, field: &str, e: &std::io::Error) -> CarmenError {
    CarmenError {
        file: file.to_owned(),
        line,
        field: field.to_owned(),
        message: e.to_string(),
    }
}

/// Sweep duration of a SICK LMS covering `fov_rad`: its mirror turns at
/// 75 Hz.
fn sick_sweep_duration_s(fov_rad: f64) -> f64 {
    fov_rad.abs() / (2.0 * PI) / SICK_ROTATION_HZ
}

/// Where the hostname is, when it is not at `host_idx`: the last token that
/// is not a number. `None` when the slot holds a non-number (the layout
/// fits) or when no token is a non-number (nothing to locate it by).
fn misplaced_host(toks: &[&str], host_idx: usize) -> Option<usize> {
    let is_number = |t: &str| t.parse::<f64>().is_ok();
    if toks.get(host_idx).is_some_and(|t| !is_number(t)) {
        return None;
    }
    (2..toks.len()).rev().find(|&i| !is_number(toks[i]))
}

/// A cursor over the tokens of one line, producing errors that name the
/// field.
struct Fields<'a> {
    toks: &'a [&'a str],
    /// Index of the next token.
    pos: usize,
    message_type: &'static str,
    file: &'a str,
    line: usize,
}

impl<'a> Fields<'a> {
    fn new(toks: &'a [&'a str], message_type: &'static str, file: &'a str, line: usize) -> Self {
        Fields {
            toks,
            pos: 1,
            message_type,
            file,
            line,
        }
    }

    fn err(&self, field: &str, message: String) -> CarmenError {
        CarmenError {
            file: self.file.to_owned(),
            line: self.line,
            field: format!("{} {field}", self.message_type),
            message,
        }
    }

    fn token(&mut self, field: &str) -> Result<&'a str, CarmenError> {
        let tok = self.toks.get(self.pos).copied().ok_or_else(|| {
            self.err(
                field,
                format!("missing: the line ends after {} tokens", self.toks.len()),
            )
        })?;
        self.pos += 1;
        Ok(tok)
    }

    fn number(&mut self, field: &str) -> Result<f64, CarmenError> {
        let tok = self.token(field)?;
        tok.parse()
            .map_err(|_| self.err(field, format!("not a number: `{tok}`")))
    }

    fn finite(&mut self, field: &str) -> Result<f64, CarmenError> {
        let v = self.number(field)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(field, format!("not finite: `{}`", self.toks[self.pos - 1])))
        }
    }

    fn count(&mut self, field: &str) -> Result<usize, CarmenError> {
        let tok = self.token(field)?;
        tok.parse()
            .map_err(|_| self.err(field, format!("not a non-negative integer: `{tok}`")))
    }

    fn integer(&mut self, field: &str) -> Result<i64, CarmenError> {
        let tok = self.token(field)?;
        tok.parse()
            .map_err(|_| self.err(field, format!("not an integer: `{tok}`")))
    }

    fn stamp(&mut self, field: &str) -> Result<Stamp, CarmenError> {
        let tok = self.token(field)?;
        tok.parse()
            .map_err(|_| self.err(field, format!("not a time in decimal seconds: `{tok}`")))
    }

    fn pose(&mut self, names: [&str; 3]) -> Result<Pose2, CarmenError> {
        let x = self.finite(names[0])?;
        let y = self.finite(names[1])?;
        let theta = self.finite(names[2])?;
        Ok(Pose2::new(x, y, theta))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use std::io::{Cursor, Write};

    const EPS: f64 = 1e-12;

    fn reader(text: &str) -> CarmenReader<Cursor<Vec<u8>>> {
        CarmenReader::new(Cursor::new(text.as_bytes().to_vec()), "mem.log")
    }

    fn records(text: &str) -> Vec<Result<Record, CarmenError>> {
        reader(text).collect()
    }

    fn scans(text: &str) -> Vec<LoggedScan> {
        records(text)
            .into_iter()
            .filter_map(|r| match r.expect("parses") {
                Record::Laser(s) => Some(s),
                _ => None,
            })
            .collect()
    }

    /// A FLASER (or RLASER) line with the given ranges and both poses equal.
    fn laser_line(kind: &str, ranges: &[f64], pose: (f64, f64, f64), stamp: &str) -> String {
        let rs: Vec<String> = ranges.iter().map(|r| r.to_string()).collect();
        let (x, y, t) = pose;
        format!(
            "{kind} {} {} {x} {y} {t} {x} {y} {t} {stamp} pippo {stamp}",
            ranges.len(),
            rs.join(" ")
        )
    }

    /// The error of the first failing record.
    fn first_error(text: &str) -> CarmenError {
        records(text)
            .into_iter()
            .find_map(|r| r.err())
            .expect("an error")
    }

    fn assert_error(text: &str, line: usize, field: &str) -> CarmenError {
        let e = first_error(text);
        assert_eq!(
            (e.file.as_str(), e.line, e.field.as_str()),
            ("mem.log", line, field),
            "{e}"
        );
        assert!(
            e.to_string()
                .starts_with(&format!("mem.log:{line}: {field}: ")),
            "{e}"
        );
        e
    }

    #[test]
    fn valid_flaser_line_parses_to_carmen_angles_ranges_and_poses() {
        let ranges: Vec<f64> = (0..181).map(|i| 1.0 + 0.01 * i as f64).collect();
        let mut line = laser_line("FLASER", &ranges, (1.0, 2.0, 0.5), "1071078718.462310");
        // Make the odometry pose differ from the robot pose.
        line = line.replacen(" 1 2 0.5 1 2 0.5 ", " 1 2 0.5 1.5 -2.5 3 ", 1);
        let text = format!("# comment\n\n{line}\n");
        let s = scans(&text).remove(0);
        assert_eq!(s.line, 3);
        assert_eq!(s.kind, LaserKind::Front);
        assert_eq!(s.scan.sensor, "carmen-front");
        assert_eq!(s.scan.len(), 181);
        assert!((s.scan.angle_min_rad + FRAC_PI_2).abs() < EPS);
        assert!((s.scan.angle_increment_rad - PI / 180.0).abs() < EPS);
        assert!((s.scan.angle(90)).abs() < EPS);
        assert!((s.scan.angle(180) - FRAC_PI_2).abs() < 1e-9);
        assert_eq!(s.scan.ranges_m, ranges);
        assert_eq!(s.scan.max_range_m, CARMEN_DEFAULT_MAX_RANGE_M);
        assert_eq!(s.scan.stamp.as_nanos(), 1_071_078_718_462_310_000);
        assert!((s.scan.sweep_duration_s - 1.0 / 150.0).abs() < EPS);
        assert_eq!(s.robot_pose, Pose2::new(1.0, 2.0, 0.5));
        assert_eq!(s.laser_pose, s.robot_pose);
        assert_eq!(s.odom_pose, Pose2::new(1.5, -2.5, 3.0));
    }

    #[test]
    fn beam_layouts_follow_carmen_guesses() {
        let deg = PI / 180.0;
        let last = |n: usize| {
            let l = CarmenBeamLayout::for_readings(n);
            l.angle_min_rad + (n - 1) as f64 * l.angle_increment_rad
        };
        for (n, inc, fov, last_deg) in [
            (180, 1.0, 179.0, 89.0),
            (181, 1.0, 180.0, 90.0),
            (360, 0.5, 179.5, 89.5),
            (361, 0.5, 180.0, 90.0),
        ] {
            let l = CarmenBeamLayout::for_readings(n);
            assert!((l.angle_min_rad + FRAC_PI_2).abs() < EPS, "{n}");
            assert!((l.angle_increment_rad - inc * deg).abs() < EPS, "{n}");
            assert!((l.fov_rad - fov * deg).abs() < EPS, "{n}");
            assert!((last(n) - last_deg * deg).abs() < 1e-9, "{n}");
        }
        let other = CarmenBeamLayout::for_readings(91);
        assert!((other.angle_increment_rad - 2.0 * deg).abs() < EPS);
        assert!((last(91) - FRAC_PI_2).abs() < 1e-9);
        let narrow = CarmenBeamLayout::for_readings(401);
        assert!((narrow.angle_min_rad + 50.0 * deg).abs() < EPS);
        assert!((last(401) - 50.0 * deg).abs() < 1e-9);
    }

    #[test]
    fn sick_no_return_codes_become_no_returns() {
        let text = laser_line(
            "FLASER",
            &[1.0, 81.91, 81.83, 79.99, 80.0],
            (0.0, 0.0, 0.0),
            "5",
        );
        let s = scans(&text).remove(0);
        assert!(s.scan.is_return(0) && s.scan.is_return(3));
        for i in [1, 2, 4] {
            assert!(!s.scan.is_return(i), "beam {i}");
            assert_eq!(s.scan.ranges_m[i], f64::INFINITY);
        }
    }

    #[test]
    fn max_range_params_apply_to_later_lines() {
        let ranges = [10.0, 30.0, 50.0];
        let text = [
            laser_line("FLASER", &ranges, (0.0, 0.0, 0.0), "1"),
            "PARAM robot_front_laser_max 40.0 nohost 0".to_owned(),
            laser_line("FLASER", &ranges, (0.0, 0.0, 0.0), "2"),
            "PARAM laser_front_laser_max_range 20.0".to_owned(),
            "PARAM robot_front_laser_max 45.0 nohost 0".to_owned(),
            laser_line("FLASER", &ranges, (0.0, 0.0, 0.0), "3"),
            laser_line("RLASER", &ranges, (0.0, 0.0, 0.0), "4"),
        ]
        .join("\n");
        let returns: Vec<(usize, f64)> = scans(&text)
            .iter()
            .map(|s| (s.scan.returns().count(), s.scan.max_range_m))
            .collect();
        assert_eq!(returns, vec![(3, 80.0), (2, 40.0), (1, 20.0), (3, 80.0)]);
    }

    #[test]
    fn param_offsets_place_the_lasers() {
        let text = [
            "PARAM robot_frontlaser_offset 0.25 nohost 0".to_owned(),
            "PARAM robot_rearlaser_offset 0.1".to_owned(),
            laser_line("FLASER", &[1.0; 180], (1.0, 2.0, FRAC_PI_2), "1"),
            laser_line("RLASER", &[1.0; 180], (1.0, 2.0, FRAC_PI_2), "1"),
        ]
        .join("\n");
        let all = records(&text);
        assert!(matches!(
            &all[0],
            Ok(Record::Param { name, value, line: 1 }) if name == "robot_frontlaser_offset" && value == "0.25"
        ));
        let got = scans(&text);
        let (front, rear) = (&got[0], &got[1]);
        assert_eq!(front.robot_pose, Pose2::new(1.0, 2.0, FRAC_PI_2));
        let lp = front.laser_pose;
        assert!(
            (lp.x - 1.0).abs() < EPS && (lp.y - 2.25).abs() < EPS,
            "{lp:?}"
        );
        assert!((lp.theta - FRAC_PI_2).abs() < EPS);
        assert_eq!(rear.kind, LaserKind::Rear);
        assert_eq!(rear.scan.sensor, "carmen-rear");
        let rp = rear.laser_pose;
        assert!(
            (rp.x - 1.0).abs() < EPS && (rp.y - 1.9).abs() < EPS,
            "{rp:?}"
        );
        assert!((rp.theta + FRAC_PI_2).abs() < EPS, "{rp:?}");
    }

    #[test]
    fn odometry_and_tiny_stamps_parse() {
        let text = "ODOM 0.255856 0.0163473 0.618883 0.1 -0.2 0.3 6.979 pippo 6.979\n\
                    ODOM 0 0 0 0 0 0 3.44361e-86 pippo 0\n";
        let odo: Vec<OdomRecord> = records(text)
            .into_iter()
            .map(|r| match r.expect("parses") {
                Record::Odometry(o) => o,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(odo[0].line, 1);
        assert_eq!(odo[0].stamp, Stamp::from_nanos(6_979_000_000));
        assert_eq!(odo[0].pose, Pose2::new(0.255856, 0.0163473, 0.618883));
        assert_eq!(
            (odo[0].tv_mps, odo[0].rv_radps, odo[0].accel_mps2),
            (0.1, -0.2, 0.3)
        );
        assert_eq!(odo[1].stamp, Stamp::ZERO);
        assert_eq!(odo[1].line, 2);
    }

    #[test]
    fn robotlaser1_uses_its_own_configuration() {
        let text = "ROBOTLASER1 0 -1.5 3.0 0.75 20.0 0.01 0 5 1 2 25 3 4 2 7 8 \
                    1.1 2.0 0.0 1.0 2.0 0.0 0.5 0.1 0.6 0.3 1000000 12.5 host 12.6 extra";
        let s = scans(text).remove(0);
        assert_eq!(s.kind, LaserKind::Robot);
        assert_eq!(s.scan.sensor, "carmen-robotlaser");
        assert_eq!(
            (s.scan.angle_min_rad, s.scan.angle_increment_rad),
            (-1.5, 0.75)
        );
        assert_eq!(s.scan.max_range_m, 20.0);
        assert_eq!(s.scan.ranges_m, vec![1.0, 2.0, f64::INFINITY, 3.0, 4.0]);
        assert_eq!(s.laser_pose, Pose2::new(1.1, 2.0, 0.0));
        assert_eq!(s.robot_pose, Pose2::new(1.0, 2.0, 0.0));
        assert_eq!(s.odom_pose, s.robot_pose);
        assert_eq!(s.scan.stamp, Stamp::from_nanos(12_500_000_000));
    }

    #[test]
    fn extra_trailing_tokens_are_ignored() {
        let line = laser_line("FLASER", &[1.0, 2.0], (0.0, 0.0, 0.0), "1.5");
        let s = scans(&format!("{line} 7 more tokens")).remove(0);
        assert_eq!(s.scan.ranges_m, vec![1.0, 2.0]);
        let o = records("ODOM 1 2 3 0 0 0 1.0 host 1.0 extra 9");
        assert!(matches!(o[0], Ok(Record::Odometry(_))));
    }

    #[test]
    fn unknown_types_are_counted_not_errors() {
        let text = "# message formats defined: PARAM SYNC ODOM FLASER\n\
                    #PARAM simulator_num_readings 181 nohost 0\n\
                    NEFF 30\n\n   \nNEFF 29.9\nSYNC tag\nTRUEPOS 1 2 3 4 5 6 0 h 0\n\
                    ODOM 0 0 0 0 0 0 0.1 h 0.1\n";
        let mut r = reader(text);
        let got: Vec<_> = r.by_ref().collect::<Result<_, _>>().expect("parses");
        assert_eq!(got.len(), 1);
        let want: BTreeMap<String, usize> = [("NEFF", 2), ("SYNC", 1), ("TRUEPOS", 1)]
            .into_iter()
            .map(|(k, v)| (k.to_owned(), v))
            .collect();
        assert_eq!(r.skipped(), &want);
        assert_eq!(r.lines_read(), 9);
    }

    #[test]
    fn wrong_reading_counts_name_num_readings() {
        // Three ranges where num_readings says five.
        let e = assert_error(
            "PARAM a b\nFLASER 5 1 2 3 0 0 0 0 0 0 1.0 host 1.0\n",
            2,
            "FLASER num_readings",
        );
        assert!(
            e.message.contains("says 5") && e.message.contains("holds 3"),
            "{e}"
        );
        // One range too many.
        assert_error(
            "FLASER 2 1 2 3 0 0 0 0 0 0 1.0 host 1.0\n",
            1,
            "FLASER num_readings",
        );
        // Cut short inside the ranges.
        assert_error("FLASER 5 1 2\n", 1, "FLASER num_readings");
        assert_error("FLASER\n", 1, "FLASER num_readings");
        assert_error("FLASER abc 1 2\n", 1, "FLASER num_readings");
        assert_error("RLASER 0 0 0 0 0 0 0 1 h 1\n", 1, "RLASER num_readings");
    }

    #[test]
    fn non_numeric_range_names_its_index() {
        let mut ranges = vec![1.0; 20];
        ranges[17] = 123.456;
        let line = laser_line("FLASER", &ranges, (0.0, 0.0, 0.0), "1").replace("123.456", "abc");
        let e = assert_error(
            &format!("ODOM 0 0 0 0 0 0 1 h 1\n\n{line}\n"),
            3,
            "FLASER range[17]",
        );
        assert!(e.message.contains("`abc`"), "{e}");
    }

    #[test]
    fn non_finite_poses_are_errors() {
        assert_error(
            "FLASER 1 1.0 0 0 nan 0 0 0 1.0 host 1.0\n",
            1,
            "FLASER theta",
        );
        assert_error(
            "FLASER 1 1.0 0 0 0 0 inf 0 1.0 host 1.0\n",
            1,
            "FLASER odom_y",
        );
        assert_error("ODOM 0 0 x 0 0 0 1.0 host 1.0\n", 1, "ODOM theta");
        assert_error("ODOM 0 0 0 NaN 0 0 1.0 host 1.0\n", 1, "ODOM tv");
    }

    #[test]
    fn missing_or_bad_timestamps_are_errors() {
        assert_error("FLASER 2 1.0 2.0 0 0 0 0 0 0\n", 1, "FLASER ipc_timestamp");
        assert_error(
            "FLASER 2 1.0 2.0 0 0 0 0 0 0 1.0 host\n",
            1,
            "FLASER logger_timestamp",
        );
        assert_error(
            "FLASER 1 1.0 0 0 0 0 0 0 12:30 host 1.0\n",
            1,
            "FLASER ipc_timestamp",
        );
        assert_error("ODOM 0 0 0 0 0 0 1.0 host\n", 1, "ODOM logger_timestamp");
        assert_error("ODOM 0 0 0 0 0 0 1e999 host 1\n", 1, "ODOM ipc_timestamp");
        assert_error("ODOM 0 0 0 0 0 1.0 host 1.0\n", 1, "ODOM hostname");
    }

    #[test]
    fn bad_params_are_errors() {
        assert_error("PARAM\n", 1, "PARAM name");
        assert_error("PARAM robot_frontlaser_offset\n", 1, "PARAM value");
        assert_error(
            "PARAM robot_frontlaser_offset abc nohost 0\n",
            1,
            "PARAM robot_frontlaser_offset",
        );
        assert_error(
            "PARAM robot_front_laser_max -3\n",
            1,
            "PARAM robot_front_laser_max",
        );
    }

    #[test]
    fn reading_continues_after_a_malformed_line() {
        let text = "ODOM 0 0 0 0 0 0 1.0 host\nODOM 0 0 0 0 0 0 2.0 host 2.0\n";
        let got = records(text);
        assert_eq!(got.len(), 2);
        assert!(got[0].is_err());
        assert!(matches!(&got[1], Ok(Record::Odometry(o)) if o.line == 2));
    }

    #[test]
    fn saturation_survey_finds_clip_levels() {
        let mut text = String::new();
        for i in 0..20 {
            let r = [1.0 + i as f64, 32.767, 32.763, 32.63, 32.759];
            text.push_str(&laser_line("FLASER", &r, (0.0, 0.0, 0.0), "1"));
            text.push('\n');
            text.push_str(&laser_line(
                "RLASER",
                &[5.0, 6.0 + i as f64],
                (0.0, 0.0, 0.0),
                "1",
            ));
            text.push('\n');
        }
        let caps = survey_carmen_saturation(Cursor::new(text.as_bytes()), "mem").expect("ok");
        assert_eq!(
            caps,
            CarmenSaturation {
                front_m: Some(32.759),
                rear_m: None
            }
        );
        let s = reader(&text)
            .with_saturation_caps(caps)
            .next()
            .expect("one")
            .expect("ok");
        let Record::Laser(s) = s else { panic!() };
        assert_eq!(s.scan.max_range_m, 32.759);
        assert_eq!(s.scan.returns().count(), 2);
    }

    #[test]
    fn gzip_is_detected_by_magic_bytes_not_name() {
        let text = format!(
            "PARAM robot_frontlaser_offset 0.5 nohost 0\n{}\nODOM 1 2 3 0 0 0 1.0 h 1.0\nNEFF 3\n",
            laser_line("FLASER", &[1.0, 81.91], (0.0, 0.0, 0.0), "1.0")
        );
        let dir = tempfile::tempdir().expect("tempdir");
        let gz_path = dir.path().join("plain-looking.log");
        let mut enc = flate2::write::GzEncoder::new(
            File::create(&gz_path).expect("create"),
            flate2::Compression::default(),
        );
        enc.write_all(text.as_bytes()).expect("write");
        enc.finish().expect("finish");
        let txt_path = dir.path().join("looks-compressed.log.gz");
        std::fs::write(&txt_path, &text).expect("write");
        let a = read_carmen_file(&gz_path).expect("gz reads");
        let b = read_carmen_file(&txt_path).expect("text reads");
        assert_eq!(a.scans, b.scans);
        assert_eq!(a.scans.len(), 1);
        assert_eq!(a.odometry.len(), 1);
        assert_eq!(a.params["robot_frontlaser_offset"], "0.5");
        assert_eq!(a.skipped["NEFF"], 1);
        assert_eq!(a.scans[0].laser_pose, Pose2::new(0.5, 0.0, 0.0));
        assert!(!a.scans[0].scan.is_return(1));
        let streamed: Vec<Record> = open_carmen_file(&gz_path)
            .expect("opens")
            .collect::<Result<_, _>>()
            .expect("parses");
        assert_eq!(streamed.len(), 3);
    }

    #[test]
    fn missing_file_error_names_it() {
        let e = read_carmen_file(Path::new("/nonexistent/x.log")).expect_err("missing");
        assert_eq!(
            (e.file.as_str(), e.line, e.field.as_str()),
            ("/nonexistent/x.log", 0, "open")
        );
        assert!(
            e.to_string().starts_with("/nonexistent/x.log:0: open: "),
            "{e}"
        );
    }

    const INTEL: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/carmen/intel-corrected.log.gz"
    );
    const ACES: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/carmen/aces-corrected.log.gz"
    );

    #[test]
    fn reads_the_intel_log() {
        let log = read_carmen_file(Path::new(INTEL)).expect("intel reads");
        assert_eq!(log.scans.len(), 910);
        assert_eq!(log.odometry.len(), 14541);
        assert!(log.scans.iter().all(|s| s.scan.len() == 180));
        assert!(log.scans.iter().all(|s| s.scan.max_range_m == 80.0));
        // Its 81.83 m error code is a no-return; nothing finite is that far.
        assert!(
            log.scans
                .iter()
                .all(|s| s.scan.returns().all(|b| b.range_m < 30.0))
        );
        assert_eq!(log.skipped.get("NEFF"), Some(&910));
        assert_eq!(log.params.len(), 2);
    }

    #[test]
    fn aces_clip_at_50_m_is_no_return_read_or_streamed() {
        let log = read_carmen_file(Path::new(ACES)).expect("aces reads");
        assert_eq!(log.scans.len(), 440);
        assert!(log.scans.iter().all(|s| s.scan.max_range_m == 50.0));
        assert!(
            log.scans
                .iter()
                .all(|s| s.scan.returns().all(|b| b.range_m < 50.0))
        );
        let streamed: Vec<LoggedScan> = open_carmen_file(Path::new(ACES))
            .expect("opens")
            .filter_map(|r| match r.expect("parses") {
                Record::Laser(s) => Some(s),
                _ => None,
            })
            .collect();
        assert_eq!(streamed, log.scans);
    }
}
