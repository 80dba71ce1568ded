//! # fcc_board — `fcc_firmware` on the paper's MCU (TI TM4C129x, Cortex-M4F)
//!
//! - [`replay`]: a compact recording of sensor inputs, commands and motor outputs, replayed by
//!   the QEMU image (`qemu-replay`) and compared with the host build.
//! - [`drivers`]: placeholder for the sensor drivers on `embedded-hal` 1.0 traits (MPU-9250,
//!   MS5611, GPS, laser and sonar serial lines) — NOT written yet.
//!
//! Binaries: `fcc-board` (TM4C129x, feature `tm4c`), `qemu-replay` (mps2-an386, feature `qemu`),
//! `record` (host, feature `host`). Build with `scripts/build-mcu.sh`, test with
//! `scripts/test-mcu.sh`.
#![cfg_attr(not(any(test, feature = "std")), no_std)]

pub mod drivers;
pub mod replay;

pub use fcc_firmware;
