//! # fcc_board — `fcc_firmware` on the paper's MCU (TI TM4C129x, Cortex-M4F)
//!
//! - [`replay`]: a compact recording of sensor inputs, commands and motor outputs, replayed by
//!   the QEMU image (`qemu-replay`) and compared with the host build.
//! - [`drivers`]: sensor and actuator drivers on `embedded-hal` 1.0 traits, host-tested
//!   (`cargo test --features std`): MPU-9250 + AK8963 and MS5611 over SPI, u-blox UBX NAV-PVT,
//!   the ILM-150-R laser and MB7076 sonar serial lines, S.BUS, and the ESC pulses with the
//!   TM4C129x PWM0 implementation (feature `tm4c`). Their API is at the top of `drivers/mod.rs`.
//!
//! Binaries: `fcc-board` (TM4C129x, feature `tm4c`), `qemu-replay` (mps2-an386, feature `qemu`),
//! `record` (host, feature `host`). Build with `scripts/build-mcu.sh`, test with
//! `scripts/test-mcu.sh`.
#![cfg_attr(not(any(test, feature = "std")), no_std)]

pub mod drivers;
pub mod replay;

pub use fcc_firmware;
