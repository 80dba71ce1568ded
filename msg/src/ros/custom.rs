//! The custom messages of the ROS 2 interface package `fcc_msgs` (`msg/msg/*.msg`; its actions
//! are in [`super::action`]).
//! The `.msg` files are the source of truth: these structs follow their field order (checked by
//! the `custom_fields_match_msg_files` test against [`Altitude::FIELDS`] etc.), and their
//! constants (`Status::MODE_HOLD`, `Altitude::SOURCE_LASER`, …) and `FIELDS` are generated
//! from the files by `msg/build.rs`, never copied by hand.

use super::{ros_msg, Header};
use serde::{Deserialize, Serialize};

/// fcc_msgs/msg/Altitude (see `msg/msg/Altitude.msg` for units).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Altitude {
    pub header: Header,
    pub baro_alt_m: f32,
    pub alt_m: f32,
    pub vertical_speed_mps: f32,
    pub ground_height_m: f32,
    pub ground_variance_m2: f32,
    pub laser_range_m: f32,
    pub sonar_range_m: f32,
    pub source: u8,
}
ros_msg!(
    Altitude,
    "fcc_msgs",
    "Altitude",
    include_str!("../../msg/Altitude.msg"),
    [Header]
);

/// fcc_msgs/msg/Status (see `msg/msg/Status.msg`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub header: Header,
    pub mode: u8,
    pub mode_name: String,
    pub armed: bool,
    pub landed: bool,
    pub failsafe: u8,
    pub failsafe_name: String,
    pub gps_ok: bool,
    pub mag_disturbed: bool,
    pub mag_rejects: u32,
    pub laser_ok: bool,
    pub sonar_ok: bool,
    pub mag_disturbed_s: f32,
    pub nav_faults: u8,
    pub loop_time_max_us: u32,
    pub loop_time_avg_us: u32,
    pub last_reject: String,
    pub setpoint_rejects: u32,
    pub command_rejects: u32,
    pub mcu_tx_frames: u32,
    pub mcu_tx_dropped: u32,
    pub rx_bytes: u64,
    pub rx_frames: u64,
    pub crc_errors: u64,
    pub framing_errors: u64,
    pub resyncs: u64,
    pub decode_errors: u64,
    pub frames_lost: u64,
    pub dropped: u64,
    pub mcu_rx_frames: u32,
    pub mcu_crc_errors: u32,
    pub mcu_resyncs: u32,
    pub mcu_frames_lost: u32,
    pub setpoints_forwarded: u64,
    pub setpoint_rejects_bridge: u64,
    pub commands_forwarded: u64,
    pub time_synced: bool,
    pub time_sync_offset_ns: i64,
    pub time_sync_rtt_us: u32,
}
ros_msg!(
    Status,
    "fcc_msgs",
    "Status",
    include_str!("../../msg/Status.msg"),
    [Header]
);

/// fcc_msgs/msg/LinkFrame (see `msg/msg/LinkFrame.msg`): one raw link frame, as recorded.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LinkFrame {
    pub header: Header,
    pub direction: u8,
    pub t_us: u64,
    pub data: Vec<u8>,
}
ros_msg!(
    LinkFrame,
    "fcc_msgs",
    "LinkFrame",
    include_str!("../../msg/LinkFrame.msg"),
    [Header]
);

/// fcc_msgs/msg/Waypoint (see `msg/msg/Waypoint.msg`): a goal's point, local ENU metres in
/// `map` or WGS-84 latitude/longitude; altitude above home in both.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    pub frame: u8,
    pub x_m: f64,
    pub y_m: f64,
    pub z_m: f64,
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    pub altitude_m: f64,
}
ros_msg!(
    Waypoint,
    "fcc_msgs",
    "Waypoint",
    include_str!("../../msg/Waypoint.msg")
);

include!(concat!(env!("OUT_DIR"), "/ros_msg_consts.rs"));
