//! A fingerprint of everything the sensors delivered, so two runs can be
//! compared byte for byte without keeping their streams.

use stucco_core::Readings;

/// FNV-1a, 64 bits, over the readings' numbers in delivery order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceHash(u64);

impl Default for TraceHash {
    fn default() -> Self {
        TraceHash(0xcbf2_9ce4_8422_2325)
    }
}

impl TraceHash {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    fn int(&mut self, v: i64) {
        self.bytes(&v.to_le_bytes());
    }

    fn float(&mut self, v: f64) {
        self.bytes(&v.to_bits().to_le_bytes());
    }

    /// Folds `r` into the hash.
    pub fn add(&mut self, r: &Readings) {
        for e in &r.encoders {
            self.int(e.stamp.as_nanos());
            self.int(e.left_ticks);
            self.int(e.right_ticks);
        }
        for s in &r.scans {
            self.int(s.stamp.as_nanos());
            s.ranges_m.iter().for_each(|&x| self.float(x));
        }
        for p in &r.profiles {
            self.int(p.stamp.as_nanos());
            p.ranges_m.iter().for_each(|&x| self.float(x));
        }
        self.bytes(&[u8::from(r.bumper)]);
    }

    /// The hash so far, as 16 hex digits.
    pub fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}
