//! Laser altimeter of paper B (ILM-150-R): ASCII serial output parser (sans-IO).
//!
//! The sensor: paper B (`../shared/seeds/001_…`, Table 1 and its ref. [5] "MDL, ILM-150
//! Leaflet") uses the ILM-150-R by the UK company MDL — 0.5–150 m reflectorless (650 m to a
//! reflector), accuracy 5 cm, resolution 1 cm, 9 Hz, RS-232 — and reports that over a dark
//! surface (105–184 s of its ground test) "the laser altimeter diverges to 99999 m". Our SITL
//! model (`fcc_firmware/sim/src/rangefinders.rs`) uses the same figures.
//!
//! **Format ASSUMPTION.** The leaflet's exact ASCII framing is not available to us, so this
//! parser accepts the family of formats such laser distance modules use (one reading per line,
//! CR, LF or CR LF terminated), and the byte-exact line must be checked against the unit before
//! flight:
//! - a decimal distance in metres, optionally right-aligned with spaces and optionally prefixed
//!   by a one-letter tag and spaces, optionally followed by spaces and `m`:
//!   `"  12.345\r\n"`, `"12.34\r"`, `"D 00001.23\r\n"` (the SITL's line), `"5.20 m\r\n"`;
//! - an error / no-return report: `E` followed by a code, e.g. `"E15\r\n"` (the usual "no
//!   target / signal too weak" report of such modules), → [`LaserReading::NoReturn`];
//! - a distance of 99 999 m or more (what paper B's unit printed with no return), → `NoReturn`.
//!
//! `NoReturn` becomes `fcc_firmware::sensors::LASER_NO_RETURN_M` (99 999 m) in the
//! [`RangeSample`], which is the sentinel the core's ground-altitude fusion understands.
//! Anything else (letters in the number, two points, an over-long line) is rejected and counted.

use fcc_firmware::sensors::{RangeSample, LASER_NO_RETURN_M};

/// Longest line accepted (bytes before the terminator).
pub const MAX_LINE: usize = 24;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LaserReading {
    /// A distance, metres.
    Range { range_m: f32 },
    /// No return: an `E<code>` report (`code`) or the 99 999 m reading (`code = None`).
    NoReturn { code: Option<u16> },
}

impl LaserReading {
    /// Metres, with no return as the 99 999 m sentinel.
    pub fn range_m(&self) -> f32 {
        match *self {
            LaserReading::Range { range_m } => range_m,
            LaserReading::NoReturn { .. } => LASER_NO_RETURN_M,
        }
    }

    pub fn to_range_sample(&self, now_us: u64) -> RangeSample {
        RangeSample {
            t_us: now_us,
            range_m: self.range_m(),
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaserStats {
    pub ranges: u32,
    pub no_returns: u32,
    /// Lines that are neither a distance nor an error report.
    pub malformed: u32,
    /// Lines longer than [`MAX_LINE`] (dropped up to the next terminator).
    pub overlong: u32,
}

/// Byte-at-a-time line parser.
#[derive(Clone, Debug)]
pub struct LaserParser {
    buf: [u8; MAX_LINE],
    len: usize,
    overflow: bool,
    pub stats: LaserStats,
}

impl Default for LaserParser {
    fn default() -> Self {
        Self::new()
    }
}

impl LaserParser {
    pub fn new() -> Self {
        Self {
            buf: [0; MAX_LINE],
            len: 0,
            overflow: false,
            stats: LaserStats::default(),
        }
    }

    pub fn push(&mut self, byte: u8) -> Option<LaserReading> {
        if byte == b'\r' || byte == b'\n' {
            let (len, overflow) = (self.len, self.overflow);
            self.len = 0;
            self.overflow = false;
            if overflow {
                self.stats.overlong = self.stats.overlong.wrapping_add(1);
                return None;
            }
            if len == 0 {
                return None; // the LF of CR LF, or an empty line
            }
            let r = parse_line(self.buf.get(..len).unwrap_or(&[]));
            match r {
                Some(LaserReading::Range { .. }) => {
                    self.stats.ranges = self.stats.ranges.wrapping_add(1)
                }
                Some(LaserReading::NoReturn { .. }) => {
                    self.stats.no_returns = self.stats.no_returns.wrapping_add(1)
                }
                None => self.stats.malformed = self.stats.malformed.wrapping_add(1),
            }
            return r;
        }
        match self.buf.get_mut(self.len) {
            Some(slot) if !self.overflow => {
                *slot = byte;
                self.len += 1;
            }
            _ => self.overflow = true,
        }
        None
    }
}

/// Parse one line (without its terminator). `None` if malformed.
pub fn parse_line(line: &[u8]) -> Option<LaserReading> {
    let mut s = trim(line);
    // Error report: E + 1..4 digits.
    if let Some((&b'E', code)) = s.split_first() {
        let code = trim(code);
        if (1..=4).contains(&code.len()) && code.iter().all(u8::is_ascii_digit) {
            let v = code.iter().fold(0u16, |a, &d| a * 10 + (d - b'0') as u16);
            return Some(LaserReading::NoReturn { code: Some(v) });
        }
        return None;
    }
    // Optional one-letter tag ("D 00001.23").
    if let Some((&c, rest)) = s.split_first() {
        if c.is_ascii_alphabetic() {
            s = trim(rest);
        }
    }
    // Optional unit suffix.
    if let Some((&b'm', rest)) = s.split_last() {
        s = trim(rest);
    }
    if s.is_empty() {
        return None;
    }
    let mut int: u32 = 0;
    let mut int_digits = 0;
    let mut frac: u32 = 0;
    let mut frac_scale: u32 = 1;
    let mut seen_point = false;
    for &c in s {
        match c {
            b'0'..=b'9' if !seen_point => {
                int_digits += 1;
                if int_digits > 7 {
                    return None;
                }
                int = int * 10 + (c - b'0') as u32;
            }
            b'0'..=b'9' => {
                // Keep up to 4 decimals (0.1 mm); more are accepted and truncated.
                if frac_scale < 10_000 {
                    frac = frac * 10 + (c - b'0') as u32;
                    frac_scale *= 10;
                }
            }
            b'.' if !seen_point => seen_point = true,
            _ => return None,
        }
    }
    if int_digits == 0 {
        return None;
    }
    let m = int as f32 + frac as f32 / frac_scale as f32;
    if m >= LASER_NO_RETURN_M {
        return Some(LaserReading::NoReturn { code: None });
    }
    Some(LaserReading::Range { range_m: m })
}

fn trim(mut s: &[u8]) -> &[u8] {
    while let Some((&b' ', rest)) = s.split_first() {
        s = rest;
    }
    while let Some((&b' ', rest)) = s.split_last() {
        s = rest;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::testutil::Rng;

    fn feed(p: &mut LaserParser, s: &[u8]) -> Vec<LaserReading> {
        s.iter().filter_map(|&b| p.push(b)).collect()
    }

    #[test]
    fn distances() {
        let mut p = LaserParser::new();
        let r = feed(&mut p, b"  12.345\r\n12.34\r0.5\n150\r\n5.20 m\r\n");
        let m: Vec<f32> = r.iter().map(|x| x.range_m()).collect();
        assert_eq!(m.len(), 5);
        for (a, b) in m.iter().zip([12.345, 12.34, 0.5, 150.0, 5.2]) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        assert_eq!(p.stats.ranges, 5);
    }

    #[test]
    fn no_return_reports_map_to_the_sentinel() {
        let mut p = LaserParser::new();
        let r = feed(&mut p, b"E15\r\nE 2\r\n99999.00\r\nD 99999.00\r\n");
        assert_eq!(r.len(), 4);
        assert_eq!(r[0], LaserReading::NoReturn { code: Some(15) });
        assert_eq!(r[1], LaserReading::NoReturn { code: Some(2) });
        assert_eq!(r[2], LaserReading::NoReturn { code: None });
        for x in &r {
            assert_eq!(x.range_m(), LASER_NO_RETURN_M);
            assert_eq!(
                x.to_range_sample(42),
                RangeSample {
                    t_us: 42,
                    range_m: 99_999.0
                }
            );
        }
        assert_eq!(p.stats.no_returns, 4);
    }

    #[test]
    fn simulator_line_format() {
        // fcc_firmware's SITL laser line: "D " + {m:08.2} + "\r\n".
        let mut p = LaserParser::new();
        for m in [0.0f64, 1.23, 12.5, 149.99] {
            let line = format!("D {m:08.2}\r\n");
            let r = feed(&mut p, line.as_bytes());
            assert!((r[0].range_m() as f64 - m).abs() < 1e-4, "{line:?}");
        }
    }

    #[test]
    fn malformed_and_overlong() {
        let mut p = LaserParser::new();
        let r = feed(&mut p, b"1.2.3\r\nabc\r\nE\r\nE12345\r\n-1.0\r\n.5\r\n");
        assert!(r.is_empty());
        assert_eq!(p.stats.malformed, 6);
        let r = feed(&mut p, b"0000000000000000000000000001.0\r\n7.5\r\n");
        assert_eq!(r.len(), 1);
        assert_eq!(p.stats.overlong, 1);
    }

    #[test]
    fn any_bytes_never_panic() {
        let mut rng = Rng(150);
        let mut p = LaserParser::new();
        for _ in 0..200_000 {
            if let Some(r) = p.push(rng.biased(b" 0123456789.E\r\nDm")) {
                let m = r.range_m();
                assert!(m.is_finite() && m >= 0.0);
            }
        }
        assert!(p.stats.ranges > 0 && p.stats.malformed > 0);
    }
}
