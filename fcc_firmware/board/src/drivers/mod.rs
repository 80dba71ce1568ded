//! Sensor and actuator drivers for the TM4C129x board, on `embedded-hal` 1.0 traits.
//!
//! All of them are `no_std`, allocate nothing, never read a clock (the caller passes `now_us`,
//! MCU microseconds since boot, as everywhere in `fcc_firmware`), and never panic on any input:
//! byte-stream parsers take one byte at a time and count what they reject. Each is host-tested
//! (`cargo test --features std` in `fcc_firmware/board`) on the datasheets' own numbers.
//! Checked in November 2026: the thumbv7em-none-eabihf release code of every parser, and of
//! `Mpu9250::{init, read}` / `Ms5611::{init, poll}` monomorphised on a stand-in `SpiDevice`,
//! references no `core::panicking` function at all.
//!
//! # API for the board binary (how to wire them)
//!
//! | driver | bus | construct | per tick / per byte | gives |
//! |---|---|---|---|---|
//! | [`mpu9250::Mpu9250`] | SPI (`SpiDevice`, mode 3, ≤ 1 MHz for config, ≤ 20 MHz for data) | `Mpu9250::new(spi, Mpu9250Config::default())`, then `.init(&mut delay)` once | `.read(now_us)` at the sample rate (500 Hz) | [`mpu9250::Mpu9250Reading`]: `ImuSample` (FRD, SI), die temperature, `Option<MagSample>` (new AK8963 data only) |
//! | [`ms5611::Ms5611`] | SPI (`SpiDevice`, mode 0 or 3, ≤ 20 MHz) | `Ms5611::new(spi, Osr::Osr4096)`, then `.init(&mut delay)` (reset + PROM + CRC-4) | `.poll(now_us)` every tick: starts/reads conversions when their time has passed | `Option<BaroSample>` (Pa, °C) |
//! | [`gps_ubx::UbxParser`] | UART (u-blox, UBX out) | `UbxParser::new()` | `.push(byte)` for each received byte | `Option<UbxMessage>` (NAV-PVT, ACK/NAK); `NavPvt::to_gps_fix(now_us)` → `GpsFix`; `gps_ubx::config::{cfg_prt_uart1, cfg_rate, cfg_msg}` build the setup frames (NMEA is not parsed: configure the receiver for UBX output) |
//! | [`laser::LaserParser`] | UART (RS-232 via a level shifter) | `LaserParser::new()` | `.push(byte)` | `Option<LaserReading>`; `.to_range_sample(now_us)` (no return → 99 999 m sentinel) |
//! | [`sonar::SonarParser`] | UART 9600 8N1, inverted TTL | `SonarParser::new(SonarConfig::MB7076)` | `.push(byte)` | `Option<SonarReading>` (m, at-min/at-max flags); `.to_range_sample(now_us)` |
//! | [`sbus::SbusDecoder`] | UART 100 000 8E2, inverted | `SbusDecoder::new()` | `.push(byte)`; `.idle()` on a UART idle gap | `Option<SbusFrame>` (16 + 2 channels, frame-lost, failsafe); [`sbus::pilot_override`] |
//! | [`pwm`] | PWM0 generators 0–3 (M0PWM0–7) | `pwm::tm4c::Pwm0Esc::new(dp.PWM0, &pc, 120_000_000, PwmConfig::default())` (feature `tm4c`) | `EscOutputs::write(now_us, &motors)` (`fcc_firmware::sensors::MotorOutputs`) | 1000–2000 µs pulses at 400 Hz |
//!
//! A UART that implements `embedded_hal_nb::serial::Read<u8>` can be drained into any of the
//! byte parsers with [`drain_serial`]. `tm4c129x-hal` 0.9 implements only `embedded-hal` 0.2
//! traits (and exports no SPI module), so the board binary needs a small adapter (or
//! register-level SSI/UART code) that implements `SpiDevice` / hands bytes to `push`.
//!
//! Frames: everything that leaves a driver is in the body FRD frame (x forward, y right,
//! z down) and SI units, like `fcc_firmware::sensors`.

pub mod gps_ubx;
pub mod laser;
pub mod mpu9250;
pub mod ms5611;
pub mod pwm;
pub mod sbus;
pub mod sonar;

#[cfg(test)]
pub(crate) mod testutil;

/// Read every byte a non-blocking serial port has ready and hand each to `sink` (e.g.
/// `|b| if let Some(m) = ubx.push(b) { … }`). Stops at `WouldBlock`; a read error (framing,
/// overrun, parity) is counted in the returned tuple and the byte dropped — the parsers
/// resynchronise on their own. Returns `(bytes read, errors)`. At most `max_bytes` bytes are
/// read per call, so a babbling line cannot starve the tick.
pub fn drain_serial<S, F>(serial: &mut S, max_bytes: usize, mut sink: F) -> (usize, usize)
where
    S: embedded_hal_nb::serial::Read<u8>,
    F: FnMut(u8),
{
    let mut n = 0;
    let mut errors = 0;
    while n + errors < max_bytes {
        match serial.read() {
            Ok(b) => {
                n += 1;
                sink(b);
            }
            Err(embedded_hal_nb::nb::Error::WouldBlock) => break,
            Err(embedded_hal_nb::nb::Error::Other(_)) => errors += 1,
        }
    }
    (n, errors)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Port<'a> {
        data: &'a [u8],
        pos: usize,
    }
    impl embedded_hal_nb::serial::ErrorType for Port<'_> {
        type Error = embedded_hal_nb::serial::ErrorKind;
    }
    impl embedded_hal_nb::serial::Read<u8> for Port<'_> {
        fn read(&mut self) -> embedded_hal_nb::nb::Result<u8, Self::Error> {
            let b = self.data.get(self.pos).copied();
            self.pos += 1;
            match b {
                Some(0xEE) => Err(embedded_hal_nb::nb::Error::Other(
                    embedded_hal_nb::serial::ErrorKind::Parity,
                )),
                Some(b) => Ok(b),
                None => Err(embedded_hal_nb::nb::Error::WouldBlock),
            }
        }
    }

    #[test]
    fn drain_reads_until_would_block_and_counts_errors() {
        let mut p = Port {
            data: b"R0123\r\xEEabc",
            pos: 0,
        };
        let mut sonar = sonar::SonarParser::new(sonar::SonarConfig::MB7076);
        let mut got = None;
        let (n, e) = drain_serial(&mut p, 100, |b| {
            if let Some(r) = sonar.push(b) {
                got = Some(r);
            }
        });
        assert_eq!((n, e), (9, 1));
        assert!((got.unwrap().range_m - 1.23).abs() < 1e-6);
        let mut p = Port {
            data: &[0u8; 50],
            pos: 0,
        };
        assert_eq!(drain_serial(&mut p, 10, |_| {}), (10, 0));
    }
}
