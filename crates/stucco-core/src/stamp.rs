//! Time stamps: time is always an argument, never read from a clock.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A point in time, in integer nanoseconds since the start of a run (or any
/// epoch the source chooses, such as a log's first line).
///
/// Integer nanoseconds keep arithmetic exact, so the same inputs give the
/// same outputs byte for byte. Nothing in stucco's core crates reads the
/// wall clock: every `Stamp` comes in from the caller.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct Stamp(i64);

impl Stamp {
    /// The epoch.
    pub const ZERO: Stamp = Stamp(0);

    /// A stamp `nanos` nanoseconds after the epoch.
    pub const fn from_nanos(nanos: i64) -> Self {
        Stamp(nanos)
    }

    /// A stamp `secs` seconds after the epoch, rounded to the nearest
    /// nanosecond.
    pub fn from_secs_f64(secs: f64) -> Self {
        Stamp((secs * 1e9).round() as i64)
    }

    /// Nanoseconds since the epoch.
    pub const fn as_nanos(self) -> i64 {
        self.0
    }

    /// Seconds since the epoch.
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 * 1e-9
    }

    /// Seconds from `earlier` to `self` (negative when `earlier` is later).
    pub fn seconds_since(self, earlier: Stamp) -> f64 {
        (self.0 - earlier.0) as f64 * 1e-9
    }

    /// This stamp moved by `dt_s` seconds (rounded to the nanosecond).
    pub fn offset_secs(self, dt_s: f64) -> Self {
        Stamp(self.0 + (dt_s * 1e9).round() as i64)
    }
}

/// A decimal seconds string that is not a time stamp.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseStampError(String);

impl fmt::Display for ParseStampError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "not a time in decimal seconds: {:?}", self.0)
    }
}

impl std::error::Error for ParseStampError {}

impl std::str::FromStr for Stamp {
    type Err = ParseStampError;

    /// Parses decimal seconds (`"1071078718.462310"`) exactly to the
    /// nanosecond, as `f64` cannot for stamps of the Unix era. Exponent
    /// forms (`"4.65e-86"`, as some logs hold) are read through `f64`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || ParseStampError(s.to_owned());
        let t = s.trim();
        if t.contains(['e', 'E']) {
            let secs: f64 = t.parse().map_err(|_| err())?;
            return if secs.is_finite() && secs.abs() < 9.2e9 {
                Ok(Stamp::from_secs_f64(secs))
            } else {
                Err(err())
            };
        }
        let (neg, body) = match t.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, t.strip_prefix('+').unwrap_or(t)),
        };
        let (int, frac) = body.split_once('.').unwrap_or((body, ""));
        if int.is_empty() && frac.is_empty()
            || !int.bytes().all(|b| b.is_ascii_digit())
            || !frac.bytes().all(|b| b.is_ascii_digit())
        {
            return Err(err());
        }
        let whole: i64 = if int.is_empty() {
            0
        } else {
            int.parse().map_err(|_| err())?
        };
        let mut nanos: i64 = 0;
        for (k, b) in frac.bytes().take(9).enumerate() {
            nanos += i64::from(b - b'0') * 10i64.pow(8 - k as u32);
        }
        if frac.len() > 9 && frac.as_bytes()[9] >= b'5' {
            nanos += 1;
        }
        let total = whole
            .checked_mul(1_000_000_000)
            .and_then(|w| w.checked_add(nanos))
            .ok_or_else(err)?;
        Ok(Stamp(if neg { -total } else { total }))
    }
}

impl fmt::Display for Stamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.9} s", self.as_secs_f64())
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn decimal_seconds_parse_to_the_nanosecond() {
        let t: Stamp = "1071078718.462310".parse().expect("parses");
        assert_eq!(t.as_nanos(), 1_071_078_718_462_310_000);
        let later = t.offset_secs(0.125);
        assert_eq!(later.seconds_since(t), 0.125);
        assert!(later > t);
        assert_eq!("-0.5".parse::<Stamp>(), Ok(Stamp::from_nanos(-500_000_000)));
        assert_eq!("3.44361e-86".parse::<Stamp>(), Ok(Stamp::ZERO));
        assert_eq!("7".parse::<Stamp>(), Ok(Stamp::from_nanos(7_000_000_000)));
        for bad in ["", ".", "1.2.3", "abc", "1e400", "--1"] {
            assert!(bad.parse::<Stamp>().is_err(), "{bad:?} parsed");
        }
    }
}
