//! # fcc_msgs — the MCU ↔ Linux link protocol
//!
//! `no_std`, no heap, sans-IO: the codec never touches a port or a clock. The MCU firmware
//! (`fcc_firmware::link`) and the Linux bridge use the same code.
//!
//! ## Layers (bottom-up)
//! 1. **Bytes**: a UART (921600 baud 8N1 = 92,160 B/s) or a pseudo-terminal.
//! 2. **Framing** ([`frame`]): COBS (the `cobs` crate encodes; the decoder hops from code to
//!    code in place) with a `0x00` delimiter after every frame. A receiver that starts
//!    mid-stream or meets garbage resynchronises at the next `0x00`.
//! 3. **Integrity** ([`crc32c`]): CRC-32C (Castagnoli, `crc::CRC_32_ISCSI`) over header and
//!    payload; the CPU's CRC instruction where a host has one.
//! 4. **Header**: protocol version, message id, per-direction sequence number, timestamp.
//! 5. **Payload** ([`messages`]): one struct per message, serialised with `postcard`
//!    (serde); the message id in the header says which struct. Decoding must consume the
//!    payload exactly; trailing bytes and unknown ids are counted errors.
//! 6. **Session**: the [`Hello`]/[`HelloRequest`] handshake checks [`PROTOCOL_VERSION`] and
//!    [`SCHEMA_HASH`] (FNV-1a of [`SCHEMA`]) and yields a readable [`HandshakeError`];
//!    time sync by [`TimeSyncPing`]/[`TimeSyncPong`]; telemetry rates in [`StreamRates`].
//!
//! Beside the link, with feature `ros` (std): `ros`, the ROS 2 (Jazzy) message structs for
//! ros2-client — the standard ones the nodes use and the custom `msg/*.msg` of this ROS 2
//! interface package, whose constants and field lists `build.rs` generates from the files.
//! Vocabulary tables both ends read: [`params`] (the MCU parameters settable over the link: id,
//! name, unit, default, range, doc — one table, [`for_each_mcu_param!`]); [`vocab`] (flight modes,
//! failsafe causes, altitude sources: ROS constant values and names, checked against `msg/*.msg`).
//! Where the messages' lat/lon live: [`geodesy`] (WGS-84 geodetic ↔ ECEF ↔ the local NED tangent
//! plane at home, `f64`), which the firmware's navigation and the mission node's lat/lon goals
//! both use.
//! Modules: [`crc32c`], [`fixed`], [`frame`], [`geodesy`], [`handshake`], [`messages`], [`params`], [`rates`], [`vocab`], `ros`
//! (feature `ros`).
//!
//! ## Frame layout
//! ```text
//! wire:  COBS( raw ) | 0x00
//! raw:   version u8 | msg_id u8 | seq u16 LE | t_us low u32 LE | payload (postcard) | crc32c u32 LE
//!        \_______________ header, 8 B ______________________/                      CRC over all
//!   or:  version u8 | msg_id u8 | seq u16 LE | t_us u64 LE     | …                   bytes before it
//!        \_______________ long header, 12 B: Hello, HelloRequest, Status ______/
//! ```
//! - `seq` counts frames per direction and wraps; the decoder counts gaps as lost frames.
//! - `t_us`: MCU µs since boot on MCU → Linux frames (the time the payload refers to: sample
//!   arrival for raw sensors, the navigation step for `NavState`); on Linux → MCU frames the
//!   Linux side's monotonic µs, for logs only. Most headers carry its low 32 bits (they wrap
//!   every 71.6 min); the decoder extends them from the previous frame's time
//!   ([`extend_time`]), and the long headers (`Status`, ten a second, and the handshake's,
//!   frozen across versions) carry all 64, so the time never wraps and is right after any gap
//!   shorter than 35 min. A sequence restart (the MCU rebooted) starts the time afresh.
//! - Payloads: fixed-point where a field's resolution is known ([`fixed`]: the IMU and
//!   magnetometer as the sensor's 16-bit counts, the navigation state's attitude, rates,
//!   velocity and accelerations, the baro temperature), `f32`/`f64` elsewhere; the home rides
//!   in one `NavState` a second. Link v6: 0.59× MAVLink v2's bytes for the same telemetry
//!   (BENCHMARKS.md row 1a).
//! - Overhead: 8 B header + 4 B CRC + 1–2 B COBS + 1 B delimiter ≈ 14 B per frame.
//!   The longest frame is [`MAX_FRAME_LEN`] bytes.
//!
//! ## Units and frames
//! NED (north, east, down) for navigation, FRD (forward, right, down) for the body, as in the
//! firmware; SI units named in every field (`vel_ned_mps`, `gyro_frd_radps`, `pressure_pa`,
//! `lat_deg`). `f32` everywhere except `f64` latitude/longitude.
//!
//! ## Use
//! ```
//! use fcc_msgs::{encode, FrameDecoder, Message, VelocitySetpoint, YawSetpoint, MAX_FRAME_LEN};
//! let sp = Message::VelocitySetpoint(VelocitySetpoint {
//!     vel_ned_mps: [1.0, 0.0, -0.5], yaw: YawSetpoint::Keep, ttl_ms: 500,
//! });
//! let mut buf = [0u8; MAX_FRAME_LEN];
//! let n = encode(&sp, 7, 1_000, &mut buf).unwrap();
//! let mut dec = FrameDecoder::new();
//! let frames: Vec<_> = dec.push_slice(&buf[..n]).collect();
//! assert_eq!(frames[0].unwrap().message, sp);
//! ```
#![cfg_attr(not(any(feature = "std", test)), no_std)]

pub mod crc32c;
pub mod fixed;
pub mod frame;
pub mod geodesy;
pub mod handshake;
pub mod messages;
pub mod params;
pub mod rates;
#[cfg(feature = "ros")]
pub mod ros;
pub mod vocab;

#[cfg(test)]
mod fuzz;
#[cfg(test)]
mod tests;

pub use frame::{
    encode, extend_time, header_len, long_header, DecodeError, EncodeError, Encoder, Frame,
    FrameDecoder, Header, CRC_LEN, HEADER_LEN, LONG_HEADER_LEN, MAX_FRAME_LEN, MAX_RAW_FRAME_LEN,
};
pub use handshake::{check_peer, HandshakeError};
pub use messages::*;
pub use params::{param_default, param_id, ParamSpec};
pub use rates::{max_frame_len, period_us, Stream, StreamRates, BAUD_921600_BYTES_PER_S};

/// Version of the frame layout and message set. Bump it for any incompatible change
/// (the schema hash catches changes that were not bumped).
pub const PROTOCOL_VERSION: u8 = 6;
