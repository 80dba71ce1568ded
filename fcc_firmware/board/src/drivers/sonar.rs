//! MaxBotix XL-MaxSonar-WRLA1 (MB7076) ultrasonic rangefinder: serial output parser (sans-IO).
//!
//! Source: MaxBotix "XL-MaxSonar-WR/WRC Datasheet" (the MB7060–MB7092 family; paper B cites
//! "XL-MaxSonar-WRLA1 (MB7076), Datasheet", its ref. [6]). Pin 5 "Serial output": RS-232 format
//! (9600 baud, 8 data bits, no parity, 1 stop bit) but at 0–Vcc levels, i.e. **inverted TTL**
//! — the MCU UART needs an inverter (or a true RS-232 line through a MAX3232). The output is an
//! ASCII capital "R", then ASCII digits of the range, then a carriage return (ASCII 13).
//! - The 10-metre "L" models (MB7066, MB7076: 1 cm resolution) send **four** digits in
//!   centimetres, "R0000".."R1068"; 1068 cm is the maximum and is also what they report when no
//!   target is detected. Objects closer than 20 cm are reported as 20 cm.
//! - The 7.65 m models (MB7060/MB7070, also cm) send three digits, "R765" maximum; accepted too.
//!
//! The digits are centimetres for these -WR/-WRL/-XL models (the millimetre "HRXL" family, MB73xx,
//! sends "R" + 4 digits in mm: select that with [`SonarConfig::unit_m`] = 0.001).
//! Readings at the limits are flagged: `at_min` (≤ 20 cm: the target may be closer),
//! `at_max` (≥ the maximum: no target, the range is unknown).

use fcc_firmware::sensors::RangeSample;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SonarConfig {
    /// Metres per count (0.01 for the cm models).
    pub unit_m: f32,
    /// Reported minimum, counts (20 cm).
    pub min_counts: u16,
    /// Reported maximum / no target, counts (1068 cm for MB7066/MB7076).
    pub max_counts: u16,
}

impl SonarConfig {
    /// MB7076 XL-MaxSonar-WRLA1 (and MB7066 WRL1): cm, 20..1068.
    pub const MB7076: SonarConfig = SonarConfig {
        unit_m: 0.01,
        min_counts: 20,
        max_counts: 1068,
    };
}

/// One reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SonarReading {
    pub range_m: f32,
    pub raw: u16,
    /// At (or below) the minimum the sensor reports: the target may be nearer.
    pub at_min: bool,
    /// At (or above) the maximum: no target detected.
    pub at_max: bool,
}

impl SonarReading {
    /// As the flight core's sample. The flight core's range-validity logic (paper B fusion)
    /// decides what to do with limit readings; this passes the reported range through.
    pub fn to_range_sample(&self, now_us: u64) -> RangeSample {
        RangeSample {
            t_us: now_us,
            range_m: self.range_m,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SonarStats {
    pub readings: u32,
    /// A line with a non-digit, too many or too few digits, or a byte outside a line.
    pub malformed: u32,
    pub at_limits: u32,
}

/// Byte-at-a-time parser: `R`, 3 or 4 digits, CR. An `R` always starts a new reading, so a
/// corrupted line costs only itself.
#[derive(Clone, Debug)]
pub struct SonarParser {
    cfg: SonarConfig,
    in_line: bool,
    digits: u8,
    value: u16,
    bad: bool,
    pub stats: SonarStats,
}

impl SonarParser {
    pub fn new(cfg: SonarConfig) -> Self {
        Self {
            cfg,
            in_line: false,
            digits: 0,
            value: 0,
            bad: false,
            stats: SonarStats::default(),
        }
    }

    fn reject(&mut self) {
        self.stats.malformed = self.stats.malformed.wrapping_add(1);
        self.in_line = false;
    }

    pub fn push(&mut self, byte: u8) -> Option<SonarReading> {
        match byte {
            b'R' => {
                if self.in_line {
                    self.reject(); // previous line never ended
                }
                self.in_line = true;
                self.digits = 0;
                self.value = 0;
                self.bad = false;
                None
            }
            b'\r' | b'\n' => {
                if !self.in_line {
                    return None; // stray terminator (e.g. an LF after the CR): ignore
                }
                self.in_line = false;
                if self.bad || !(3..=4).contains(&self.digits) {
                    self.stats.malformed = self.stats.malformed.wrapping_add(1);
                    return None;
                }
                let raw = self.value;
                let at_min = raw <= self.cfg.min_counts;
                let at_max = raw >= self.cfg.max_counts;
                if at_min || at_max {
                    self.stats.at_limits = self.stats.at_limits.wrapping_add(1);
                }
                self.stats.readings = self.stats.readings.wrapping_add(1);
                Some(SonarReading {
                    range_m: raw as f32 * self.cfg.unit_m,
                    raw,
                    at_min,
                    at_max,
                })
            }
            b'0'..=b'9' if self.in_line => {
                if self.digits >= 4 {
                    self.bad = true;
                } else {
                    self.value = self.value * 10 + (byte - b'0') as u16;
                    self.digits += 1;
                }
                None
            }
            _ => {
                if self.in_line {
                    self.reject();
                }
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::testutil::Rng;

    fn feed(p: &mut SonarParser, s: &[u8]) -> Vec<SonarReading> {
        s.iter().filter_map(|&b| p.push(b)).collect()
    }

    #[test]
    fn datasheet_format() {
        let mut p = SonarParser::new(SonarConfig::MB7076);
        let r = feed(&mut p, b"R0123\rR1068\rR0020\rR0512\r");
        assert_eq!(r.len(), 4);
        assert!((r[0].range_m - 1.23).abs() < 1e-6 && !r[0].at_min && !r[0].at_max);
        assert!((r[1].range_m - 10.68).abs() < 1e-5 && r[1].at_max);
        assert!((r[2].range_m - 0.20).abs() < 1e-6 && r[2].at_min);
        assert_eq!(r[3].raw, 512);
        assert_eq!(p.stats.at_limits, 2);
        assert_eq!(r[0].to_range_sample(7).t_us, 7);
    }

    #[test]
    fn three_digit_models_and_rejections() {
        let mut p = SonarParser::new(SonarConfig::MB7076);
        let r = feed(&mut p, b"R765\r");
        assert_eq!(r[0].raw, 765);
        // Too many digits, too few, a letter, an unterminated line cut by the next R.
        let r = feed(&mut p, b"R01234\rR12\rR01x3\rR01R0456\r");
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].raw, 456);
        assert_eq!(p.stats.malformed, 4);
        // Garbage between lines is ignored; CR LF tolerated.
        let r = feed(&mut p, b"\x00\xff\nR0300\r\n");
        assert_eq!(r.len(), 1);
    }

    #[test]
    fn simulator_lines_parse_the_same() {
        // fcc_firmware's SITL sonar model writes "R" + {cm:04} + "\r".
        let mut p = SonarParser::new(SonarConfig::MB7076);
        for cm in [20u16, 99, 100, 999, 1068] {
            let line = format!("R{cm:04}\r");
            let r = feed(&mut p, line.as_bytes());
            assert_eq!(r[0].raw, cm);
        }
    }

    #[test]
    fn any_bytes_never_panic() {
        let mut rng = Rng(7076);
        let mut p = SonarParser::new(SonarConfig::MB7076);
        for _ in 0..200_000 {
            if let Some(r) = p.push(rng.biased(b"R0123456789\r\n")) {
                assert!(r.raw <= 9999 && r.range_m.is_finite());
            }
        }
        assert!(p.stats.readings > 0 && p.stats.malformed > 0);
    }
}
