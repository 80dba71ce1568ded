//! Message payloads, their ids and the schema description that the schema hash is computed from.
//!
//! Conventions (as in the firmware): navigation frame NED (x north, y east, z down), body frame
//! FRD (x forward, y right, z down); SI units named in every field (`_m`, `_mps`, `_radps`,
//! `_mps2`, `_pa`, `_c`, `_ut`, `_v`, `_a`, `_us`, `_ns`, `_deg`). Angles in radians unless the
//! name says `_deg`. A payload's time is the frame header's `t_us` (MCU µs since boot): the
//! sample's arrival time for raw sensors, the navigation step time for `NavState`.
//!
//! **Changing anything here** (a field, its type, its order, a variant, an id) changes the wire
//! format: update [`SCHEMA`] / [`SCHEMA_MESSAGES`] in the same change (the test `schema_matches_types` fails if a
//! type's maximum encoded size no longer matches the size written in [`SCHEMA`]) and, for an
//! incompatible change, bump [`crate::PROTOCOL_VERSION`].

use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

// ---------------------------------------------------------------------------------------------
// Shared enums
// ---------------------------------------------------------------------------------------------

/// Which downward rangefinder a [`RangeRaw`] comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum RangeSensor {
    /// ILM-150-R class laser altimeter.
    Laser,
    /// Ultrasonic rangefinder.
    Sonar,
}

/// Which measurement the altitude-above-ground fusion is using.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum AltitudeSource {
    /// No above-ground estimate.
    #[default]
    None,
    Laser,
    Sonar,
    /// Laser and sonar both valid and blended.
    Both,
    /// No valid range: the estimate is predicted from baro/accel only.
    Predicted,
}

/// Flight mode of the MCU core (`fcc_firmware::commands::Mode` is this type; ROS codes and
/// names in [`crate::vocab`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum FlightMode {
    #[default]
    Disarmed,
    Hold,
    Velocity,
    Land,
    /// The R/C pilot flies (override switch on; `fcc_firmware::pilot`).
    Pilot,
}

/// Why the core left the operator's mode (`fcc_firmware::commands::FailsafeCause` is this type;
/// ROS codes and names in [`crate::vocab`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum FailsafeCause {
    #[default]
    None,
    SetpointStale,
    SetpointLost,
    Geofence,
    GpsLost,
    /// Wind beyond the vehicle's authority: landing where it is.
    WindLimit,
    /// A navigation filter diverged (`SensorHealth::nav_faults`): hold, then land.
    EstimatorFault,
    /// Motors stopped by the emergency kill.
    EmergencyKill,
}

/// Operator command (mirror of `fcc_firmware::commands::Command`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum CommandKind {
    Arm,
    Disarm,
    /// Position hold at the current point.
    Hold,
    /// Land here; disarm on touchdown.
    Land,
    /// Follow velocity setpoints.
    Velocity,
    /// Emergency motor stop, also in flight; `Command::confirm` must be [`KILL_CONFIRM`].
    Kill,
}

/// The confirmation an emergency kill carries (`"KILL"` in ASCII); the MCU refuses a kill
/// without it ([`CommandResult::KillNotConfirmed`]).
pub const KILL_CONFIRM: u32 = 0x4B49_4C4C;

/// The setpoint time-to-live range both ends enforce (issue 14): the MCU refuses a
/// `VelocitySetpoint` whose `ttl_ms` is outside it (`CommandResult::InvalidSetpoint`), and the
/// bridge's `ttl_ms` parameter has this range. Above a few seconds one setpoint would fly on
/// with no stale-setpoint failsafe; below 50 ms (25 ticks) normal link jitter would trip it.
pub const SETPOINT_TTL_MS_MIN: u16 = 50;
/// Upper end of the setpoint time-to-live range (see [`SETPOINT_TTL_MS_MIN`]).
pub const SETPOINT_TTL_MS_MAX: u16 = 3000;

/// Outcome of a command or setpoint on the MCU (mirror of `fcc_firmware::commands::CommandError`
/// plus `Accepted` and link-level refusals).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum CommandResult {
    #[default]
    Accepted,
    NotCalibrated,
    NoHome,
    NotLanded,
    Disarmed,
    InvalidSetpoint,
    /// The peer announced a protocol version or schema hash the MCU does not share.
    Incompatible,
    /// The pilot's override switch is on: setpoints and mode commands are refused.
    PilotOverride,
    /// An emergency kill without its confirmation.
    KillNotConfirmed,
}

/// Outcome of a [`ParamSet`] on the MCU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum ParamResult {
    #[default]
    Accepted,
    /// No parameter with this id (see [`crate::param_id`]).
    UnknownId,
    /// NaN or infinite (a NaN set is also how the Linux side reads the current value).
    NotFinite,
    /// Outside the parameter's range, or inconsistent with another parameter.
    OutOfRange,
    /// The peer announced a protocol version or schema hash the MCU does not share.
    Incompatible,
}

/// Receive-side link statistics of one endpoint (all counters wrap at `u32::MAX`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct LinkCounters {
    /// Bytes fed to the decoder.
    pub rx_bytes: u32,
    /// Frames that passed every check and were returned as messages.
    pub rx_frames: u32,
    /// Frames whose CRC-32C did not match.
    pub crc_errors: u32,
    /// Frames that were not valid COBS or too short to hold a header and a CRC.
    pub framing_errors: u32,
    /// Frames longer than the decoder's buffer (discarded up to the next 0x00).
    pub overruns: u32,
    /// Times the decoder threw data away and waited for the next 0x00
    /// (= crc_errors + framing_errors + overruns).
    pub resyncs: u32,
    /// Valid frames whose payload did not decode (bad value, short, or trailing bytes).
    pub decode_errors: u32,
    /// Valid frames with an unknown message id.
    pub unknown_ids: u32,
    /// Valid frames with another protocol version (only `Hello`/`HelloRequest` pass).
    pub version_errors: u32,
    /// Sequence discontinuities (forward gaps).
    pub seq_gaps: u32,
    /// Frames missing according to the sequence numbers (sum of the gaps).
    pub frames_lost: u32,
    /// Sequence numbers that went backwards or jumped by ≥ 32768 (peer restart, duplicates).
    pub seq_resets: u32,
}

// ---------------------------------------------------------------------------------------------
// MCU → Linux
// ---------------------------------------------------------------------------------------------

/// Handshake from the MCU (answer to [`HelloRequest`]; also sent once at start-up).
/// Its layout is frozen across protocol versions so that a mismatch is always readable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct Hello {
    pub protocol_version: u8,
    pub schema_hash: u32,
    /// Firmware version major, minor, patch.
    pub firmware_version: [u8; 3],
}

/// One raw IMU sample, body FRD. Specific force: level and at rest `accel = [0, 0, -9.81]`.
/// On the wire: the sensor's 16-bit counts ([`crate::fixed::gyro`], [`crate::fixed::accel`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImuRaw {
    #[serde(with = "crate::fixed::gyro")]
    pub gyro_frd_radps: [f32; 3],
    #[serde(with = "crate::fixed::accel")]
    pub accel_frd_mps2: [f32; 3],
}

impl MaxSize for ImuRaw {
    const POSTCARD_MAX_SIZE: usize = 2 * 6;
}

/// Raw magnetometer, body FRD, microtesla. On the wire: 16-bit counts ([`crate::fixed::mag`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MagRaw {
    #[serde(with = "crate::fixed::mag")]
    pub mag_frd_ut: [f32; 3],
}

impl MaxSize for MagRaw {
    const POSTCARD_MAX_SIZE: usize = 2 * 3;
}

/// Raw barometer. On the wire the temperature is 16-bit at the sensor's 0.01 °C
/// ([`crate::fixed::temp`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BaroRaw {
    pub pressure_pa: f32,
    #[serde(with = "crate::fixed::temp::scalar")]
    pub temperature_c: f32,
}

impl MaxSize for BaroRaw {
    const POSTCARD_MAX_SIZE: usize = 4 + 2;
}

/// Raw GPS solution (header time = arrival at the MCU).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct GpsRaw {
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Height above the WGS-84 ellipsoid.
    pub alt_m: f32,
    pub vel_ned_mps: [f32; 3],
    /// Receiver's horizontal accuracy (1σ).
    pub h_acc_m: f32,
    pub num_sats: u8,
    /// 3-D fix valid.
    pub fix_ok: bool,
}

/// One downward rangefinder reading along the sensor axis. The laser's no-return value
/// (99 999 m) is passed through unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct RangeRaw {
    pub sensor: RangeSensor,
    pub range_m: f32,
}

/// Battery monitor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct Battery {
    pub voltage_v: f32,
    pub current_a: f32,
}

/// Navigation solution: NED relative to home, body FRD. On the wire the attitude, rates,
/// velocity and accelerations are fixed-point ([`crate::fixed`]), the position stays `f32`, and
/// the three flags share one byte (bit 0 `gps_ok`, 1 `home_set`, 2 `calibrated`; other bits
/// set = an invalid payload).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NavState {
    /// Attitude quaternion rotating body FRD vectors into NED, `[w, x, y, z]`.
    pub q_body_to_ned: [f32; 4],
    /// Bias-corrected gyro rate, body FRD.
    pub rate_frd_radps: [f32; 3],
    pub pos_ned_m: [f32; 3],
    pub vel_ned_mps: [f32; 3],
    /// Gravity-compensated acceleration, NED.
    pub accel_ned_mps2: [f32; 3],
    /// Horizontal acceleration estimated by the Luenberger observer (paper A eqs. 15-17) that
    /// the acceleration controller feeds back on, NED (north, east).
    pub accel_obs_ne_mps2: [f32; 2],
    /// Home = NED origin, in about one frame a second and in the first after it changes
    /// (`None` in the others: the receiver keeps the last; `home_set` says whether there is
    /// one).
    pub home: Option<HomePosition>,
    /// GPS currently feeds the horizontal filter.
    pub gps_ok: bool,
    pub home_set: bool,
    /// Gyro/baro calibration done.
    pub calibrated: bool,
}

/// [`NavState`] as it is on the wire.
#[derive(Serialize, Deserialize)]
struct NavStateWire {
    #[serde(with = "crate::fixed::unit")]
    q_body_to_ned: [f32; 4],
    #[serde(with = "crate::fixed::gyro")]
    rate_frd_radps: [f32; 3],
    pos_ned_m: [f32; 3],
    #[serde(with = "crate::fixed::vel")]
    vel_ned_mps: [f32; 3],
    #[serde(with = "crate::fixed::accel_est")]
    accel_ned_mps2: [f32; 3],
    #[serde(with = "crate::fixed::accel_est")]
    accel_obs_ne_mps2: [f32; 2],
    home: Option<HomePosition>,
    flags: u8,
}

const NAV_GPS_OK: u8 = 1;
const NAV_HOME_SET: u8 = 2;
const NAV_CALIBRATED: u8 = 4;

impl Serialize for NavState {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let flag = |on: bool, bit: u8| if on { bit } else { 0 };
        NavStateWire {
            q_body_to_ned: self.q_body_to_ned,
            rate_frd_radps: self.rate_frd_radps,
            pos_ned_m: self.pos_ned_m,
            vel_ned_mps: self.vel_ned_mps,
            accel_ned_mps2: self.accel_ned_mps2,
            accel_obs_ne_mps2: self.accel_obs_ne_mps2,
            home: self.home,
            flags: flag(self.gps_ok, NAV_GPS_OK)
                | flag(self.home_set, NAV_HOME_SET)
                | flag(self.calibrated, NAV_CALIBRATED),
        }
        .serialize(s)
    }
}

impl TryFrom<NavStateWire> for NavState {
    type Error = PayloadError;
    /// Unpack the flags byte; a bit beyond the three is an invalid payload.
    fn try_from(w: NavStateWire) -> Result<Self, PayloadError> {
        if w.flags & !(NAV_GPS_OK | NAV_HOME_SET | NAV_CALIBRATED) != 0 {
            return Err(PayloadError::Invalid);
        }
        Ok(NavState {
            q_body_to_ned: w.q_body_to_ned,
            rate_frd_radps: w.rate_frd_radps,
            pos_ned_m: w.pos_ned_m,
            vel_ned_mps: w.vel_ned_mps,
            accel_ned_mps2: w.accel_ned_mps2,
            accel_obs_ne_mps2: w.accel_obs_ne_mps2,
            home: w.home,
            gps_ok: w.flags & NAV_GPS_OK != 0,
            home_set: w.flags & NAV_HOME_SET != 0,
            calibrated: w.flags & NAV_CALIBRATED != 0,
        })
    }
}

impl<'de> Deserialize<'de> for NavState {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        NavState::try_from(NavStateWire::deserialize(d)?)
            .map_err(|_| serde::de::Error::custom("unknown NavState flag bits"))
    }
}

impl MaxSize for NavState {
    const POSTCARD_MAX_SIZE: usize =
        2 * (4 + 3) + 4 * 3 + 2 * (3 + 3 + 2) + <Option<HomePosition>>::POSTCARD_MAX_SIZE + 1;
}

/// Home: the NED origin as WGS-84 coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct HomePosition {
    pub lat_deg: f64,
    pub lon_deg: f64,
    /// Height above the WGS-84 ellipsoid.
    pub alt_m: f32,
}

/// Altitude fusion: barometric/inertial altitude and the above-ground estimate from the
/// rangefinders. `NaN` = not available.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AltitudeFusion {
    /// Barometric altitude above the calibration point (up).
    pub baro_alt_m: f32,
    /// Fused altitude above home (up) = −pos_ned_m[2].
    pub alt_m: f32,
    /// Vertical speed, NED down positive (16-bit on the wire, [`crate::fixed::vel`]).
    #[serde(with = "crate::fixed::vel::scalar")]
    pub vel_down_mps: f32,
    /// Fused height above ground (up).
    pub ground_height_m: f32,
    /// Variance of `ground_height_m`.
    pub ground_var_m2: f32,
    /// Latest raw laser range (NaN if none, 99 999 = no return).
    pub laser_m: f32,
    /// Latest raw sonar range (NaN if none).
    pub sonar_m: f32,
    pub source: AltitudeSource,
}

impl MaxSize for AltitudeFusion {
    const POSTCARD_MAX_SIZE: usize = 6 * 4 + 2 + AltitudeSource::POSTCARD_MAX_SIZE;
}

/// Health of the navigation sensors as the MCU's filters see them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct SensorHealth {
    /// GPS feeds the horizontal filter (a fix, fresh).
    pub gps_ok: bool,
    /// The magnetometer is being rejected by the attitude filter's innovation gate (a magnetic
    /// disturbance is suspected; yaw runs on the gyro).
    pub mag_disturbed: bool,
    /// Magnetometer readings rejected since boot.
    pub mag_rejects: u32,
    /// The laser altimeter gave a plausible reading recently.
    pub laser_ok: bool,
    /// The ultrasonic rangefinder gave a plausible reading recently.
    pub sonar_ok: bool,
    /// How long the magnetometer has been rejected in a row (0 = fused), 0.1 s (saturates at
    /// 6553.5 s).
    pub mag_disturbed_ds: u16,
    /// Estimator faults (bits: 1 vertical, 2 horizontal/GPS, 4 attitude), latched until arming.
    pub nav_faults: u8,
}

/// Vehicle and link status.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct Status {
    pub mode: FlightMode,
    pub armed: bool,
    pub landed: bool,
    pub failsafe: FailsafeCause,
    /// Navigation sensor health.
    pub sensors: SensorHealth,
    /// Longest and mean control-loop execution time since the previous `Status`.
    pub loop_time_max_us: u32,
    pub loop_time_avg_us: u32,
    /// Receive statistics as the MCU sees the Linux → MCU direction.
    pub link_rx: LinkCounters,
    /// Frames sent by the MCU.
    pub tx_frames: u32,
    /// Telemetry frames the MCU dropped because the transmit buffer was full.
    pub tx_dropped: u32,
    /// Setpoints the core refused.
    pub setpoint_rejects: u32,
    /// Commands the core refused.
    pub command_rejects: u32,
    /// Reason of the most recent refusal (`Accepted` = none yet).
    pub last_reject: CommandResult,
}

/// Answer to [`TimeSyncPing`] (NTP-style: t1 = `linux_time_ns`, t2 = `mcu_rx_time_us`,
/// t3 = `mcu_tx_time_us`, t4 = Linux receive time).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct TimeSyncPong {
    /// The ping's `linux_time_ns`, echoed.
    pub linux_time_ns: u64,
    /// MCU time when the ping was received.
    pub mcu_rx_time_us: u64,
    /// MCU time when the pong was written.
    pub mcu_tx_time_us: u64,
}

/// Result of one [`Command`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct CommandAck {
    pub command: CommandKind,
    pub result: CommandResult,
}

/// Answer to one [`ParamSet`]: always carries the parameter's value now in use (so a refused
/// set, or a NaN "read" set, reports the current value).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct ParamAck {
    pub id: u16,
    pub value: f32,
    pub result: ParamResult,
}

// ---------------------------------------------------------------------------------------------
// Linux → MCU
// ---------------------------------------------------------------------------------------------

/// Asks the MCU for its [`Hello`] and announces the Linux side's version and schema.
/// Its layout is frozen across protocol versions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct HelloRequest {
    pub protocol_version: u8,
    pub schema_hash: u32,
}

/// What a [`VelocitySetpoint`] asks of the heading (NED: yaw from north towards east,
/// positive = clockwise seen from above). The MCU refuses a non-finite value, and a rate over
/// [`SETPOINT_YAW_RATE_ABS_MAX_RADPS`]; it clamps a rate to its yaw-rate limit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, MaxSize)]
pub enum YawSetpoint {
    /// Keep the heading being held (the one reached, or the last commanded).
    #[default]
    Keep,
    /// Hold this heading, NED, rad (any finite angle; the MCU wraps it to (−π, π]).
    Heading { yaw_ned_rad: f32 },
    /// Turn at this rate, NED (clockwise seen from above positive), rad/s: the MCU advances the
    /// heading it holds at this rate while the setpoint is valid.
    Rate { yaw_rate_ned_radps: f32 },
}

/// Largest yaw rate a [`YawSetpoint::Rate`] may carry before it is refused as absurd (one turn
/// per second), rad/s; below it the MCU clamps the rate to its yaw-rate limit.
pub const SETPOINT_YAW_RATE_ABS_MAX_RADPS: f32 = core::f32::consts::TAU;

/// Velocity setpoint, NED, with a heading or yaw-rate request. Valid for `ttl_ms` after it
/// arrives; then the core holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct VelocitySetpoint {
    pub vel_ned_mps: [f32; 3],
    pub yaw: YawSetpoint,
    pub ttl_ms: u16,
}

/// Operator command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct Command {
    pub command: CommandKind,
    /// [`KILL_CONFIRM`] for [`CommandKind::Kill`]; 0 for every other command.
    pub confirm: u32,
}

/// Time-sync request; the MCU answers with [`TimeSyncPong`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct TimeSyncPing {
    /// Linux clock when the ping was written.
    pub linux_time_ns: u64,
}

/// Set one tunable MCU parameter (ids in [`crate::param_id`]); answered by [`ParamAck`]. A NaN value
/// changes nothing and reads the current value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct ParamSet {
    pub id: u16,
    pub value: f32,
}

// ---------------------------------------------------------------------------------------------
// The message enum, ids and schema
// ---------------------------------------------------------------------------------------------

/// Every message of the protocol, one variant per payload struct.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message {
    Hello(Hello),
    ImuRaw(ImuRaw),
    MagRaw(MagRaw),
    BaroRaw(BaroRaw),
    GpsRaw(GpsRaw),
    RangeRaw(RangeRaw),
    Battery(Battery),
    NavState(NavState),
    AltitudeFusion(AltitudeFusion),
    Status(Status),
    TimeSyncPong(TimeSyncPong),
    CommandAck(CommandAck),
    ParamAck(ParamAck),
    HelloRequest(HelloRequest),
    VelocitySetpoint(VelocitySetpoint),
    Command(Command),
    TimeSyncPing(TimeSyncPing),
    ParamSet(ParamSet),
}

/// Which way a message travels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    McuToLinux,
    LinuxToMcu,
}

/// The message table, the one place a message's id is written: invokes `$m!(Variant, ID =
/// value)` for every message, in id order (the payload struct is named as its variant). Message
/// ids (the header's `msg_id`): MCU → Linux in 0x01..=0x3F, Linux → MCU in 0x40..=0x7F.
macro_rules! for_each_message {
    ($m:ident) => {
        $m! {
            Hello, HELLO = 0x01;
            ImuRaw, IMU_RAW = 0x02;
            MagRaw, MAG_RAW = 0x03;
            BaroRaw, BARO_RAW = 0x04;
            GpsRaw, GPS_RAW = 0x05;
            RangeRaw, RANGE_RAW = 0x06;
            Battery, BATTERY = 0x07;
            NavState, NAV_STATE = 0x08;
            AltitudeFusion, ALTITUDE_FUSION = 0x09;
            Status, STATUS = 0x0A;
            TimeSyncPong, TIME_SYNC_PONG = 0x0B;
            CommandAck, COMMAND_ACK = 0x0C;
            ParamAck, PARAM_ACK = 0x0D;
            HelloRequest, HELLO_REQUEST = 0x40;
            VelocitySetpoint, VELOCITY_SETPOINT = 0x41;
            Command, COMMAND = 0x42;
            TimeSyncPing, TIME_SYNC_PING = 0x43;
            ParamSet, PARAM_SET = 0x44;
        }
    };
}

macro_rules! impl_message {
    ($($variant:ident, $id:ident = $value:literal;)*) => {
        /// Message ids (the header's `msg_id`), from the message table.
        pub mod id {
            $(#[doc = concat!("[`", stringify!($variant), "`](super::", stringify!($variant), ")")]
            pub const $id: u8 = $value;)*
        }

        impl Message {
            /// The header's message id.
            pub const fn id(&self) -> u8 {
                match self {
                    $(Message::$variant(_) => id::$id,)*
                }
            }

            /// Human-readable name (the variant's).
            pub const fn name(&self) -> &'static str {
                match self {
                    $(Message::$variant(_) => stringify!($variant),)*
                }
            }

            /// Serialise the payload (postcard) into `out`; returns the length.
            pub(crate) fn serialize_payload(&self, out: &mut [u8]) -> postcard::Result<usize> {
                match self {
                    $(Message::$variant(p) => postcard::to_slice(p, out).map(|s| s.len()),)*
                }
            }

            /// Decode a payload for `msg_id`; the payload must be consumed exactly.
            pub(crate) fn deserialize_payload(msg_id: u8, payload: &[u8]) -> Result<Message, PayloadError> {
                if let Some(r) = fast::decode(msg_id, payload) {
                    return r;
                }
                Self::deserialize_payload_postcard(msg_id, payload)
            }

            /// [`Self::deserialize_payload`] through serde and postcard, for every message.
            pub(crate) fn deserialize_payload_postcard(msg_id: u8, payload: &[u8]) -> Result<Message, PayloadError> {
                match msg_id {
                    $(id::$id => {
                        let (p, rest) = postcard::take_from_bytes::<$variant>(payload)
                            .map_err(|_| PayloadError::Invalid)?;
                        if !rest.is_empty() {
                            return Err(PayloadError::TrailingBytes(rest.len()));
                        }
                        Ok(Message::$variant(p))
                    })*
                    _ => Err(PayloadError::UnknownId),
                }
            }
        }

        /// Largest postcard payload of any message.
        pub const MAX_PAYLOAD_LEN: usize = {
            let mut m = 0;
            $(if <$variant as MaxSize>::POSTCARD_MAX_SIZE > m { m = <$variant as MaxSize>::POSTCARD_MAX_SIZE; })*
            m
        };

        /// Largest postcard payload for a message id (`None` for an unknown id).
        pub const fn max_payload_len(msg_id: u8) -> Option<usize> {
            match msg_id {
                $(id::$id => Some(<$variant as MaxSize>::POSTCARD_MAX_SIZE),)*
                _ => None,
            }
        }

        /// All known message ids.
        pub const ALL_IDS: &[u8] = &[$(id::$id),*];
    };
}

for_each_message!(impl_message);

/// Fixed-layout decoding of the busiest payloads (IMU 200 Hz, navigation 100 Hz, magnetometer
/// 50 Hz: their serde path makes one call per byte of a fixed-point field): the same bytes,
/// values and errors as postcard's (the test `fast_decoding_equals_postcard` feeds both
/// arbitrary payloads).
mod fast {
    use super::{HomePosition, ImuRaw, MagRaw, Message, NavState, NavStateWire, PayloadError};
    use crate::fixed::{self, from_count};
    use crate::id;

    /// The payload read from the front.
    struct Rd<'a>(&'a [u8]);

    impl Rd<'_> {
        fn take<const N: usize>(&mut self) -> Result<[u8; N], PayloadError> {
            let (head, tail) = self
                .0
                .split_first_chunk::<N>()
                .ok_or(PayloadError::Invalid)?;
            self.0 = tail;
            Ok(*head)
        }
        fn counts<const N: usize>(&mut self, lsb: f32) -> Result<[f32; N], PayloadError> {
            let mut out = [0.0f32; N];
            for o in &mut out {
                *o = from_count(i16::from_le_bytes(self.take::<2>()?), lsb);
            }
            Ok(out)
        }
        fn f32s<const N: usize>(&mut self) -> Result<[f32; N], PayloadError> {
            let mut out = [0.0f32; N];
            for o in &mut out {
                *o = f32::from_le_bytes(self.take::<4>()?);
            }
            Ok(out)
        }
        fn f64(&mut self) -> Result<f64, PayloadError> {
            Ok(f64::from_le_bytes(self.take::<8>()?))
        }
        fn u8(&mut self) -> Result<u8, PayloadError> {
            Ok(self.take::<1>()?[0])
        }
        /// `v` if the payload is used up, else the trailing bytes.
        fn end<T>(self, v: T) -> Result<T, PayloadError> {
            if self.0.is_empty() {
                Ok(v)
            } else {
                Err(PayloadError::TrailingBytes(self.0.len()))
            }
        }
    }

    /// The message, or `None` for an id this module leaves to postcard.
    pub(super) fn decode(msg_id: u8, payload: &[u8]) -> Option<Result<Message, PayloadError>> {
        let mut r = Rd(payload);
        Some(match msg_id {
            id::IMU_RAW => (|| {
                let m = ImuRaw {
                    gyro_frd_radps: r.counts(fixed::gyro::LSB)?,
                    accel_frd_mps2: r.counts(fixed::accel::LSB)?,
                };
                r.end(Message::ImuRaw(m))
            })(),
            id::MAG_RAW => (|| {
                let m = MagRaw {
                    mag_frd_ut: r.counts(fixed::mag::LSB)?,
                };
                r.end(Message::MagRaw(m))
            })(),
            id::NAV_STATE => (|| {
                let w = NavStateWire {
                    q_body_to_ned: r.counts(fixed::unit::LSB)?,
                    rate_frd_radps: r.counts(fixed::gyro::LSB)?,
                    pos_ned_m: r.f32s()?,
                    vel_ned_mps: r.counts(fixed::vel::LSB)?,
                    accel_ned_mps2: r.counts(fixed::accel_est::LSB)?,
                    accel_obs_ne_mps2: r.counts(fixed::accel_est::LSB)?,
                    home: match r.u8()? {
                        0 => None,
                        1 => Some(HomePosition {
                            lat_deg: r.f64()?,
                            lon_deg: r.f64()?,
                            alt_m: f32::from_le_bytes(r.take::<4>()?),
                        }),
                        _ => return Err(PayloadError::Invalid),
                    },
                    flags: r.u8()?,
                };
                let m = NavState::try_from(w)?;
                r.end(Message::NavState(m))
            })(),
            _ => return None,
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PayloadError {
    UnknownId,
    Invalid,
    TrailingBytes(usize),
}

impl Message {
    /// Which way this message travels.
    pub const fn direction(&self) -> Direction {
        if self.id() >= 0x40 {
            Direction::LinuxToMcu
        } else {
            Direction::McuToLinux
        }
    }
}

/// Wire schema: every message with its id, payload fields in order with their postcard types,
/// and the payload's maximum encoded size (`max=`, checked against the types by a test).
/// Integers other than u8 are postcard varints; f32/f64 are little-endian IEEE 754; bool is one
/// byte 0/1; enums are a varint variant index in the order listed; `Option` is a 0/1 byte then
/// the value; `[i16 NAME; N]` is `N` little-endian i16 counts of the LSB of [`crate::fixed`]'s
/// encoding `NAME`, whose value the `fixed` line lists (so a changed resolution changes the
/// hash; the test `schema_lists_the_fixed_point_resolutions` checks the line). The full schema is this text,
/// then the `params` line derived from the parameter table ([`crate::param_id::ALL`]: `params
/// 1=limits.max_horiz_speed_mps 2=…`), then [`SCHEMA_MESSAGES`]; [`SCHEMA_HASH`] is FNV-1a 32
/// over the whole (`schema_text()`, with std, writes it out).
pub const SCHEMA: &str = "\
enum RangeSensor { Laser, Sonar }
enum AltitudeSource { None, Laser, Sonar, Both, Predicted }
enum FlightMode { Disarmed, Hold, Velocity, Land, Pilot }
enum FailsafeCause { None, SetpointStale, SetpointLost, Geofence, GpsLost, WindLimit, EstimatorFault, EmergencyKill }
enum CommandKind { Arm, Disarm, Hold, Land, Velocity, Kill }
enum CommandResult { Accepted, NotCalibrated, NoHome, NotLanded, Disarmed, InvalidSetpoint, Incompatible, PilotOverride, KillNotConfirmed }
enum ParamResult { Accepted, UnknownId, NotFinite, OutOfRange, Incompatible }
enum YawSetpoint { Keep, Heading { yaw_ned_rad: f32 }, Rate { yaw_rate_ned_radps: f32 } }
fixed gyro=1.0652644e-3 accel=4.7884033e-3 mag=0.15 unit=3.0518509e-5 vel=0.002 accel_est=0.005 temp=0.01
";

/// The schema's messages (after the `params` line): see [`SCHEMA`].
pub const SCHEMA_MESSAGES: &str = "\
struct LinkCounters max=60 { rx_bytes: u32, rx_frames: u32, crc_errors: u32, framing_errors: u32, overruns: u32, resyncs: u32, decode_errors: u32, unknown_ids: u32, version_errors: u32, seq_gaps: u32, frames_lost: u32, seq_resets: u32 }
struct HomePosition max=20 { lat_deg: f64, lon_deg: f64, alt_m: f32 }
struct SensorHealth max=13 { gps_ok: bool, mag_disturbed: bool, mag_rejects: u32, laser_ok: bool, sonar_ok: bool, mag_disturbed_ds: u16, nav_faults: u8 }
msg 0x01 Hello max=9 { protocol_version: u8, schema_hash: u32, firmware_version: [u8; 3] }
msg 0x02 ImuRaw max=12 { gyro_frd_radps: [i16 gyro; 3], accel_frd_mps2: [i16 accel; 3] }
msg 0x03 MagRaw max=6 { mag_frd_ut: [i16 mag; 3] }
msg 0x04 BaroRaw max=6 { pressure_pa: f32, temperature_c: i16 temp }
msg 0x05 GpsRaw max=38 { lat_deg: f64, lon_deg: f64, alt_m: f32, vel_ned_mps: [f32; 3], h_acc_m: f32, num_sats: u8, fix_ok: bool }
msg 0x06 RangeRaw max=5 { sensor: RangeSensor, range_m: f32 }
msg 0x07 Battery max=8 { voltage_v: f32, current_a: f32 }
msg 0x08 NavState max=64 { q_body_to_ned: [i16 unit; 4], rate_frd_radps: [i16 gyro; 3], pos_ned_m: [f32; 3], vel_ned_mps: [i16 vel; 3], accel_ned_mps2: [i16 accel_est; 3], accel_obs_ne_mps2: [i16 accel_est; 2], home: Option<HomePosition>, flags: u8 (1 gps_ok, 2 home_set, 4 calibrated) }
msg 0x09 AltitudeFusion max=27 { baro_alt_m: f32, alt_m: f32, vel_down_mps: i16 vel, ground_height_m: f32, ground_var_m2: f32, laser_m: f32, sonar_m: f32, source: AltitudeSource }
msg 0x0A Status max=108 { mode: FlightMode, armed: bool, landed: bool, failsafe: FailsafeCause, sensors: SensorHealth, loop_time_max_us: u32, loop_time_avg_us: u32, link_rx: LinkCounters, tx_frames: u32, tx_dropped: u32, setpoint_rejects: u32, command_rejects: u32, last_reject: CommandResult }
msg 0x0B TimeSyncPong max=30 { linux_time_ns: u64, mcu_rx_time_us: u64, mcu_tx_time_us: u64 }
msg 0x0C CommandAck max=2 { command: CommandKind, result: CommandResult }
msg 0x0D ParamAck max=8 { id: u16, value: f32, result: ParamResult }
msg 0x40 HelloRequest max=6 { protocol_version: u8, schema_hash: u32 }
msg 0x41 VelocitySetpoint max=20 { vel_ned_mps: [f32; 3], yaw: YawSetpoint, ttl_ms: u16 }
msg 0x42 Command max=6 { command: CommandKind, confirm: u32 }
msg 0x43 TimeSyncPing max=10 { linux_time_ns: u64 }
msg 0x44 ParamSet max=7 { id: u16, value: f32 }
";

/// FNV-1a, 32 bit, usable in `const` context.
pub const fn fnv1a32(bytes: &[u8]) -> u32 {
    fnv1a32_from(0x811c_9dc5, bytes)
}

/// FNV-1a 32 continued from the running hash `h` over `bytes`.
const fn fnv1a32_from(mut h: u32, bytes: &[u8]) -> u32 {
    let mut i = 0;
    while i < bytes.len() {
        h ^= bytes[i] as u32;
        h = h.wrapping_mul(0x0100_0193);
        i += 1;
    }
    h
}

/// FNV-1a 32 continued over the decimal digits of `n`.
const fn fnv1a32_decimal(h: u32, n: u16) -> u32 {
    let mut digits = [0u8; 5];
    let (mut n, mut len) = (n, 0);
    loop {
        digits[len] = b'0' + (n % 10) as u8;
        len += 1;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    let mut h = h;
    while len > 0 {
        len -= 1;
        h = fnv1a32_from(h, &[digits[len]]);
    }
    h
}

/// Hash of the full schema ([`SCHEMA`], the `params` line of the parameter table,
/// [`SCHEMA_MESSAGES`]), exchanged in the handshake: a parameter added to the table changes it.
pub const SCHEMA_HASH: u32 = {
    let mut h = fnv1a32_from(0x811c_9dc5, SCHEMA.as_bytes());
    h = fnv1a32_from(h, b"params");
    let params = crate::param_id::ALL;
    let mut i = 0;
    while i < params.len() {
        h = fnv1a32_from(h, b" ");
        h = fnv1a32_decimal(h, params[i].0);
        h = fnv1a32_from(h, b"=");
        h = fnv1a32_from(h, params[i].1.as_bytes());
        i += 1;
    }
    h = fnv1a32_from(h, b"\n");
    fnv1a32_from(h, SCHEMA_MESSAGES.as_bytes())
};

/// The full schema text that [`SCHEMA_HASH`] hashes.
#[cfg(any(test, feature = "std"))]
pub fn schema_text() -> std::string::String {
    use std::fmt::Write;
    let mut t = std::string::String::from(SCHEMA);
    t.push_str("params");
    for (id, name) in crate::param_id::ALL {
        let _ = write!(t, " {id}={name}");
    }
    t.push('\n');
    t.push_str(SCHEMA_MESSAGES);
    t
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::String;
    use std::vec::Vec;

    fn max_size_of(name: &str) -> usize {
        macro_rules! lookup {
            ($($variant:ident, $id:ident = $value:literal;)*) => {
                match name {
                    $(stringify!($variant) => <$variant as MaxSize>::POSTCARD_MAX_SIZE,)*
                    "LinkCounters" => LinkCounters::POSTCARD_MAX_SIZE,
                    "SensorHealth" => SensorHealth::POSTCARD_MAX_SIZE,
                    "HomePosition" => HomePosition::POSTCARD_MAX_SIZE,
                    _ => panic!("no type {name}"),
                }
            };
        }
        for_each_message!(lookup)
    }

    /// Fails when a payload type changes without [`SCHEMA`] being updated (sizes, ids, count).
    #[test]
    fn schema_matches_types() {
        let mut ids: Vec<(u8, String)> = Vec::new();
        for line in schema_text().lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            let (name, max, id) = match words.first() {
                Some(&"msg") => (
                    words[2],
                    words[3],
                    Some(u8::from_str_radix(&words[1][2..], 16).unwrap()),
                ),
                Some(&"struct") => (words[1], words[2], None),
                _ => continue,
            };
            let max: usize = max
                .strip_prefix("max=")
                .expect("max= after the name")
                .parse()
                .unwrap();
            assert_eq!(
                max_size_of(name),
                max,
                "SCHEMA says max={max} for {name}: update SCHEMA"
            );
            // The number of fields listed must be plausible for the size (each field ≥ 1 byte).
            let fields = line.matches(':').count();
            assert!(
                fields >= 1 && fields <= max,
                "{name}: {fields} fields for {max} bytes"
            );
            if let Some(id) = id {
                assert_eq!(
                    max_payload_len(id),
                    Some(max),
                    "{name}: SCHEMA id 0x{id:02x} does not match"
                );
                ids.push((id, String::from(name)));
            }
        }
        assert_eq!(ids.len(), ALL_IDS.len(), "every message must be in SCHEMA");
        for (i, (id, _)) in ids.iter().enumerate() {
            assert_eq!(*id, ALL_IDS[i], "SCHEMA lists messages in id order");
        }
    }

    /// The `fixed` line of the schema is the encodings' LSBs (within 10⁻⁶): a resolution
    /// changed in `fixed.rs` alone fails here, and changing the line changes the hash.
    #[test]
    fn schema_lists_the_fixed_point_resolutions() {
        use crate::fixed::*;
        let line = SCHEMA.lines().find(|l| l.starts_with("fixed ")).unwrap();
        let listed: Vec<(&str, f64)> = line
            .split_whitespace()
            .skip(1)
            .map(|kv| {
                let (k, v) = kv.split_once('=').unwrap();
                (k, v.parse().unwrap())
            })
            .collect();
        let ours = [
            ("gyro", gyro::LSB),
            ("accel", accel::LSB),
            ("mag", mag::LSB),
            ("unit", unit::LSB),
            ("vel", vel::LSB),
            ("accel_est", accel_est::LSB),
            ("temp", temp::LSB),
        ];
        assert_eq!(listed.len(), ours.len(), "{line}");
        for ((name, v), (ours_name, lsb)) in listed.iter().zip(ours) {
            assert_eq!(*name, ours_name);
            let lsb = f64::from(lsb);
            assert!(
                (v - lsb).abs() <= 1e-6 * lsb,
                "{name}: schema {v}, fixed.rs {lsb}"
            );
        }
    }

    #[test]
    fn schema_hash_is_fnv1a_of_schema() {
        assert_eq!(fnv1a32(b""), 0x811c_9dc5);
        assert_eq!(fnv1a32(b"a"), 0xe40c_292c);
        assert_eq!(SCHEMA_HASH, fnv1a32(schema_text().as_bytes()));
        std::println!("schema hash 0x{SCHEMA_HASH:08x}, max payload {MAX_PAYLOAD_LEN} B");
    }

    #[test]
    fn ids_are_unique_and_directional() {
        let mut v = ALL_IDS.to_vec();
        v.sort();
        v.dedup();
        assert_eq!(v.len(), ALL_IDS.len());
        assert!(ALL_IDS.iter().all(|&i| i != 0 && i < 0x80));
    }

    /// The `params` line of the schema text is the parameter table's.
    #[test]
    fn param_ids_in_schema() {
        use crate::param_id;
        let text = schema_text();
        let line = text.lines().find(|l| l.starts_with("params ")).unwrap();
        let listed: Vec<String> = line.split_whitespace().skip(1).map(String::from).collect();
        let table: Vec<String> = param_id::ALL
            .iter()
            .map(|(i, n)| std::format!("{i}={n}"))
            .collect();
        assert_eq!(listed, table, "the params line is the table's");
        assert_eq!(
            param_id::by_name("limits.max_tilt_deg"),
            Some(param_id::MAX_TILT_DEG)
        );
        assert_eq!(
            param_id::name(param_id::VEL_P_PER_S),
            Some("control.vel_p_per_s")
        );
        assert_eq!(param_id::name(999), None);
    }
}
