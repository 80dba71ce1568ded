//! MEAS (TE Connectivity) MS5611-01BA03 barometric pressure sensor, over SPI.
//!
//! Sources:
//! - **MS5611-01BA03 datasheet** (DA5611-01BA03, "Barometric Pressure Sensor, with stainless
//!   steel cap"): commands (reset 0x1E, convert D1 0x40 + 2·OSRi, convert D2 0x50 + 2·OSRi,
//!   ADC read 0x00 → 24 bits, PROM read 0xA0 + 2·addr → 16 bits), maximum conversion times
//!   (0.60 / 1.17 / 2.28 / 4.54 / 9.04 ms at OSR 256 … 4096), reset reload 2.8 ms, the
//!   "pressure and temperature calculation" flow chart with its example (C1 = 40127, C2 = 36924,
//!   C3 = 23317, C4 = 23282, C5 = 33464, C6 = 28312, D1 = 9085466, D2 = 8569150 → dT = 2366,
//!   TEMP = 2007, OFF = 2420281617, SENS = 1315097036, P = 100009), and the second-order
//!   temperature compensation (T2, OFF2, SENS2 below 20 °C, more below −15 °C).
//! - **AN520** "C-code example for MS56xx, MS57xx (except analog sensor), and MS58xx series
//!   pressure sensors": the CRC-4 over the 8 PROM words (the low 4 bits of word 7 hold the CRC
//!   and are zeroed for the calculation), and its example PROM {0x3132, 0x3334, 0x3536, 0x3738,
//!   0x3940, 0x4142, 0x4344, 0x4500} → CRC 0x0B.
//!
//! The driver never reads a clock: [`Ms5611::poll`] gets `now_us` and starts or reads the
//! conversions whose (datasheet maximum) time has passed. An ADC read of 0 (read too early or
//! an interrupted conversion, datasheet: "If the conversion is not executed before the ADC read
//! command, or the ADC read command is repeated, it will give 0 as the output result") is
//! rejected and counted.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};
use fcc_firmware::sensors::BaroSample;

pub const CMD_RESET: u8 = 0x1E;
pub const CMD_ADC_READ: u8 = 0x00;
pub const CMD_CONVERT_D1: u8 = 0x40;
pub const CMD_CONVERT_D2: u8 = 0x50;
pub const CMD_PROM_READ: u8 = 0xA0;

/// Oversampling ratio.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Osr {
    Osr256 = 0,
    Osr512 = 1,
    Osr1024 = 2,
    Osr2048 = 3,
    Osr4096 = 4,
}

impl Osr {
    /// Offset added to the convert commands (0x40/0x50 + 2·i).
    pub fn cmd_offset(self) -> u8 {
        (self as u8) * 2
    }
    /// Datasheet maximum conversion time, µs.
    pub fn conversion_time_us(self) -> u64 {
        match self {
            Osr::Osr256 => 600,
            Osr::Osr512 => 1170,
            Osr::Osr1024 => 2280,
            Osr::Osr2048 => 4540,
            Osr::Osr4096 => 9040,
        }
    }
}

/// Factory calibration C1..C6 (PROM words 1..6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Calibration {
    pub c: [u16; 6],
}

/// CRC-4 of the 8 PROM words, AN520's algorithm (the low nibble of word 7 is the stored CRC
/// and is masked out of the calculation).
pub fn crc4(prom: &[u16; 8]) -> u8 {
    let mut n_rem: u16 = 0;
    for cnt in 0..16usize {
        let word = if cnt == 14 || cnt == 15 {
            prom[7] & 0xFF00
        } else {
            prom[cnt >> 1]
        };
        n_rem ^= if cnt % 2 == 1 {
            word & 0x00FF
        } else {
            word >> 8
        };
        for _ in 0..8 {
            n_rem = if n_rem & 0x8000 != 0 {
                (n_rem << 1) ^ 0x3000
            } else {
                n_rem << 1
            };
        }
    }
    ((n_rem >> 12) & 0x000F) as u8
}

/// Check the PROM's CRC and extract C1..C6. `None` if the CRC does not match, or the PROM is
/// all zeros / all ones (no chip: both would otherwise pass a CRC-4 by chance 1 in 16).
pub fn calibration_from_prom(prom: &[u16; 8]) -> Option<Calibration> {
    if prom.iter().all(|&w| w == 0) || prom.iter().all(|&w| w == 0xFFFF) {
        return None;
    }
    if crc4(prom) != (prom[7] & 0x000F) as u8 {
        return None;
    }
    Some(Calibration {
        c: [prom[1], prom[2], prom[3], prom[4], prom[5], prom[6]],
    })
}

/// Result of the datasheet calculation: TEMP in 0.01 °C, P in Pa (= 0.01 mbar).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Compensated {
    pub temp_centi_c: i32,
    pub pressure_pa: i32,
}

/// The datasheet's 1st-order calculation followed by its 2nd-order compensation, in integer
/// arithmetic as the flow chart gives it (64-bit, so any 24-bit D1/D2 and 16-bit C cannot
/// overflow). Division truncates towards zero like the datasheet's C.
pub fn compensate(cal: &Calibration, d1: u32, d2: u32) -> Compensated {
    let [c1, c2, c3, c4, c5, c6] = cal.c.map(|v| v as i64);
    let d1 = (d1 & 0x00FF_FFFF) as i64;
    let d2 = (d2 & 0x00FF_FFFF) as i64;
    let dt = d2 - c5 * (1 << 8);
    let mut temp = 2000 + dt * c6 / (1 << 23);
    let mut off = c2 * (1 << 16) + c4 * dt / (1 << 7);
    let mut sens = c1 * (1 << 15) + c3 * dt / (1 << 8);
    if temp < 2000 {
        let t2 = dt * dt / (1i64 << 31);
        let d = temp - 2000;
        let mut off2 = 5 * d * d / 2;
        let mut sens2 = 5 * d * d / 4;
        if temp < -1500 {
            let e = temp + 1500;
            off2 += 7 * e * e;
            sens2 += 11 * e * e / 2;
        }
        temp -= t2;
        off -= off2;
        sens -= sens2;
    }
    let p = (d1 * sens / (1 << 21) - off) / (1 << 15);
    Compensated {
        temp_centi_c: temp.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
        pressure_pa: p.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<E> {
    Spi(E),
    /// PROM CRC-4 mismatch (or blank PROM): no valid calibration.
    PromCrc,
    /// `poll` before a successful `init`.
    NotInitialised,
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Error::Spi(e)
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ms5611Stats {
    pub samples: u32,
    /// ADC read returned 0 (conversion not done / interrupted).
    pub zero_reads: u32,
    /// Result outside the datasheet's operating range (10–1200 mbar, −40…85 °C).
    pub out_of_range: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    ConvertingD2 { since_us: u64 },
    ConvertingD1 { since_us: u64 },
}

/// The driver: a D2 (temperature) → D1 (pressure) conversion cycle, or several pressure
/// conversions per temperature conversion (`pressure_per_temperature`).
pub struct Ms5611<SPI> {
    spi: SPI,
    osr: Osr,
    cal: Option<Calibration>,
    state: State,
    d2: Option<u32>,
    /// How many D1 conversions reuse one D2 (≥ 1). 1 = alternate (≈ 55 Hz at OSR 4096).
    pub pressure_per_temperature: u8,
    since_temperature: u8,
    pub stats: Ms5611Stats,
}

impl<SPI: SpiDevice> Ms5611<SPI> {
    pub fn new(spi: SPI, osr: Osr) -> Self {
        Self {
            spi,
            osr,
            cal: None,
            state: State::Idle,
            d2: None,
            pressure_per_temperature: 1,
            since_temperature: 0,
            stats: Ms5611Stats::default(),
        }
    }

    pub fn release(self) -> SPI {
        self.spi
    }

    pub fn calibration(&self) -> Option<Calibration> {
        self.cal
    }

    /// Reset (then wait the 2.8 ms PROM reload), read the 8 PROM words, check the CRC-4.
    pub fn init<D: DelayNs>(&mut self, delay: &mut D) -> Result<Calibration, Error<SPI::Error>> {
        self.spi.write(&[CMD_RESET])?;
        delay.delay_us(2800 + 200);
        let mut prom = [0u16; 8];
        for (i, w) in prom.iter_mut().enumerate() {
            let mut b = [0u8; 2];
            self.spi.transaction(&mut [
                Operation::Write(&[CMD_PROM_READ + 2 * i as u8]),
                Operation::Read(&mut b),
            ])?;
            *w = u16::from_be_bytes(b);
        }
        let cal = calibration_from_prom(&prom).ok_or(Error::PromCrc)?;
        self.cal = Some(cal);
        self.state = State::Idle;
        Ok(cal)
    }

    fn read_adc(&mut self) -> Result<u32, Error<SPI::Error>> {
        let mut b = [0u8; 3];
        self.spi
            .transaction(&mut [Operation::Write(&[CMD_ADC_READ]), Operation::Read(&mut b)])?;
        Ok(u32::from_be_bytes([0, b[0], b[1], b[2]]))
    }

    fn start(&mut self, d1: bool, now_us: u64) -> Result<(), Error<SPI::Error>> {
        let cmd = if d1 { CMD_CONVERT_D1 } else { CMD_CONVERT_D2 } + self.osr.cmd_offset();
        self.spi.write(&[cmd])?;
        self.state = if d1 {
            State::ConvertingD1 { since_us: now_us }
        } else {
            State::ConvertingD2 { since_us: now_us }
        };
        Ok(())
    }

    /// Advance the conversion cycle at `now_us`; returns a sample when a pressure conversion
    /// completes. Call every tick (it does one SPI transaction at most, two on a transition).
    pub fn poll(&mut self, now_us: u64) -> Result<Option<BaroSample>, Error<SPI::Error>> {
        let cal = self.cal.ok_or(Error::NotInitialised)?;
        let t_conv = self.osr.conversion_time_us();
        match self.state {
            State::Idle => {
                let need_temp = self.d2.is_none()
                    || self.since_temperature >= self.pressure_per_temperature.max(1);
                self.start(!need_temp, now_us)?;
                Ok(None)
            }
            State::ConvertingD2 { since_us } => {
                if now_us.saturating_sub(since_us) < t_conv {
                    return Ok(None);
                }
                let d2 = self.read_adc()?;
                if d2 == 0 {
                    self.stats.zero_reads = self.stats.zero_reads.wrapping_add(1);
                    self.start(false, now_us)?;
                    return Ok(None);
                }
                self.d2 = Some(d2);
                self.since_temperature = 0;
                self.start(true, now_us)?;
                Ok(None)
            }
            State::ConvertingD1 { since_us } => {
                if now_us.saturating_sub(since_us) < t_conv {
                    return Ok(None);
                }
                let d1 = self.read_adc()?;
                self.since_temperature = self.since_temperature.saturating_add(1);
                let need_temp = self.since_temperature >= self.pressure_per_temperature.max(1);
                self.start(!need_temp, now_us)?;
                let d2 = match self.d2 {
                    Some(d2) => d2,
                    None => return Ok(None),
                };
                if d1 == 0 {
                    self.stats.zero_reads = self.stats.zero_reads.wrapping_add(1);
                    return Ok(None);
                }
                let c = compensate(&cal, d1, d2);
                if !(1_000..=120_000).contains(&c.pressure_pa)
                    || !(-4_000..=8_500).contains(&c.temp_centi_c)
                {
                    self.stats.out_of_range = self.stats.out_of_range.wrapping_add(1);
                    return Ok(None);
                }
                self.stats.samples = self.stats.samples.wrapping_add(1);
                Ok(Some(BaroSample {
                    t_us: now_us,
                    pressure_pa: c.pressure_pa as f32,
                    temperature_c: c.temp_centi_c as f32 / 100.0,
                }))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::testutil::{FakeChip, FakeDelay, FakeSpi, Rng};

    const DS_CAL: Calibration = Calibration {
        c: [40127, 36924, 23317, 23282, 33464, 28312],
    };

    #[test]
    fn datasheet_example() {
        // DA5611-01BA03 example: TEMP = 2007 (20.07 °C), P = 100009 (1000.09 mbar).
        let c = compensate(&DS_CAL, 9_085_466, 8_569_150);
        assert_eq!(
            c,
            Compensated {
                temp_centi_c: 2007,
                pressure_pa: 100_009
            }
        );
    }

    #[test]
    fn second_order_below_20c_and_below_minus_15c() {
        // Expected values: the datasheet's flow chart (1st + 2nd order) evaluated independently
        // (exact integer arithmetic, C truncating division) for colder D2 values.
        // D2 = 8469150: dT = −97634, TEMP1 = 1671 (< 20 °C: T2 = 4, OFF2, SENS2) → 1667, 99350 Pa.
        assert_eq!(
            compensate(&DS_CAL, 9_085_466, 8_469_150),
            Compensated {
                temp_centi_c: 1667,
                pressure_pa: 99_350
            }
        );
        // D2 = 8000000: TEMP = −0.61 °C.
        assert_eq!(
            compensate(&DS_CAL, 9_085_466, 8_000_000),
            Compensated {
                temp_centi_c: -61,
                pressure_pa: 95_989
            }
        );
        // D2 = 7500000: TEMP1 < −15 °C, so OFF2 += 7·(TEMP+1500)², SENS2 += 11·(TEMP+1500)²/2.
        assert_eq!(
            compensate(&DS_CAL, 9_085_466, 7_500_000),
            Compensated {
                temp_centi_c: -2129,
                pressure_pa: 91_910
            }
        );
    }

    #[test]
    fn an520_crc_example() {
        let prom = [
            0x3132, 0x3334, 0x3536, 0x3738, 0x3940, 0x4142, 0x4344, 0x4500,
        ];
        assert_eq!(crc4(&prom), 0x0B);
        let mut ok = prom;
        ok[7] |= 0x000B;
        assert!(calibration_from_prom(&ok).is_some());
        // The stored nibble does not enter the calculation.
        assert_eq!(crc4(&ok), 0x0B);
        let mut bad = ok;
        bad[3] ^= 0x0100;
        assert!(calibration_from_prom(&bad).is_none());
        assert!(calibration_from_prom(&[0; 8]).is_none());
        assert!(calibration_from_prom(&[0xFFFF; 8]).is_none());
    }

    /// An MS5611 model: commands, PROM, conversions that take time (read too early → 0).
    struct FakeBaro {
        prom: [u16; 8],
        d1: u32,
        d2: u32,
        cmd: Option<u8>,
        out: [u8; 3],
        pos: usize,
        pending: Option<u32>,
        log: Vec<u8>,
    }

    impl FakeBaro {
        fn new() -> Self {
            let mut prom = [0u16, 40127, 36924, 23317, 23282, 33464, 28312, 0x1230];
            prom[7] |= crc4(&prom) as u16;
            Self {
                prom,
                d1: 9_085_466,
                d2: 8_569_150,
                cmd: None,
                out: [0; 3],
                pos: 0,
                pending: None,
                log: vec![],
            }
        }
    }

    impl FakeChip for FakeBaro {
        fn select(&mut self) {
            self.cmd = None;
            self.pos = 0;
        }
        fn xfer(&mut self, mosi: u8) -> u8 {
            match self.cmd {
                None => {
                    self.cmd = Some(mosi);
                    self.log.push(mosi);
                    match mosi {
                        0x00 => {
                            let v = self.pending.take().unwrap_or(0);
                            self.out = [(v >> 16) as u8, (v >> 8) as u8, v as u8];
                        }
                        0x40..=0x48 => self.pending = Some(self.d1),
                        0x50..=0x58 => self.pending = Some(self.d2),
                        0xA0..=0xAE => {
                            let w = self.prom[((mosi - 0xA0) / 2) as usize];
                            self.out = [(w >> 8) as u8, w as u8, 0];
                        }
                        _ => {}
                    }
                    0
                }
                Some(_) => {
                    let v = self.out.get(self.pos).copied().unwrap_or(0);
                    self.pos += 1;
                    v
                }
            }
        }
    }

    #[test]
    fn init_reads_prom_and_cycle_gives_the_datasheet_sample() {
        let mut b = Ms5611::new(FakeSpi::new(FakeBaro::new()), Osr::Osr4096);
        let mut d = FakeDelay::default();
        assert_eq!(b.init(&mut d).unwrap(), DS_CAL);
        assert!(d.total_ns >= 2_800_000);
        assert_eq!(
            &b.spi.chip.log[..9],
            &[0x1E, 0xA0, 0xA2, 0xA4, 0xA6, 0xA8, 0xAA, 0xAC, 0xAE]
        );
        let mut t = 1_000_000u64;
        let mut got = vec![];
        for _ in 0..100 {
            // 2 ms ticks
            if let Some(s) = b.poll(t).unwrap() {
                got.push(s);
            }
            t += 2000;
        }
        // D2 (0x58) then D1 (0x48) at OSR 4096, each ≥ 9.04 ms: one sample per ≈ 20 ms.
        assert!(b.spi.chip.log.contains(&0x58) && b.spi.chip.log.contains(&0x48));
        assert!((9..=11).contains(&got.len()), "{}", got.len());
        let s = got[0];
        assert_eq!(s.pressure_pa, 100_009.0);
        assert!((s.temperature_c - 20.07).abs() < 1e-4);
        assert_eq!(b.stats.zero_reads, 0);
    }

    #[test]
    fn early_adc_read_gives_zero_and_is_counted() {
        let mut chip = FakeBaro::new();
        chip.d1 = 0; // a conversion that was interrupted
        let mut b = Ms5611::new(FakeSpi::new(chip), Osr::Osr256);
        b.init(&mut FakeDelay::default()).unwrap();
        let mut t = 0;
        for _ in 0..20 {
            assert!(b.poll(t).unwrap().is_none());
            t += 1000;
        }
        assert!(b.stats.zero_reads > 0);
    }

    #[test]
    fn bad_prom_is_an_error_and_poll_refuses() {
        let mut chip = FakeBaro::new();
        chip.prom[2] ^= 1;
        let mut b = Ms5611::new(FakeSpi::new(chip), Osr::Osr4096);
        assert_eq!(b.init(&mut FakeDelay::default()), Err(Error::PromCrc));
        assert_eq!(b.poll(0), Err(Error::NotInitialised));
    }

    #[test]
    fn pressure_per_temperature() {
        let mut b = Ms5611::new(FakeSpi::new(FakeBaro::new()), Osr::Osr1024);
        b.init(&mut FakeDelay::default()).unwrap();
        b.pressure_per_temperature = 4;
        let mut t = 0;
        for _ in 0..400 {
            let _ = b.poll(t).unwrap();
            t += 500;
        }
        let log = &b.spi.chip.log;
        let d1 = log.iter().filter(|&&c| c == 0x44).count();
        let d2 = log.iter().filter(|&&c| c == 0x54).count();
        assert!(d1 >= 3 * d2 && d2 >= 2, "d1 {d1} d2 {d2}");
    }

    #[test]
    fn any_raw_values_never_panic() {
        let mut rng = Rng(5611);
        for _ in 0..50_000 {
            let cal = Calibration {
                c: [0; 6].map(|_: u16| rng.next_u64() as u16),
            };
            let c = compensate(&cal, rng.next_u64() as u32, rng.next_u64() as u32);
            let _ = c;
            let mut prom = [0u16; 8];
            prom.iter_mut().for_each(|w| *w = rng.next_u64() as u16);
            let _ = calibration_from_prom(&prom);
        }
        // Extremes.
        for c in [0u16, 0xFFFF] {
            for d in [0u32, 0xFF_FFFF, u32::MAX] {
                let _ = compensate(&Calibration { c: [c; 6] }, d, d);
            }
        }
    }
}
