//! The time series of a flight decoded from a bag's topics ([`decode`] → [`Series`]): odometry
//! (ENU → NED), accelerometer angles, status, observer and measured acceleration, setpoints.
//! [`super::figures`] and [`super::sysid`] compute from it.

use super::bag::{euler, odom_ned, BagMsg};
use crate::record::from_cdr;
use fcc_msgs::ros::*;
use serde::Deserialize;

/// The head of `fcc_msgs/Status` (the fields the report needs). CDR is sequential, so this
/// prefix decodes every version of the message (later fields were added after `landed`).
#[derive(Deserialize)]
struct StatusHead {
    header: Header,
    mode: u8,
    _mode_name: String,
    armed: bool,
    landed: bool,
}

/// `geometry_msgs/AccelStamped` (decoded here so bags of any bridge version read alike).
#[derive(Deserialize)]
struct AccelIn {
    header: Header,
    linear: Vector3,
    _angular: Vector3,
}

/// Decoded time series (t in s of ROS time).
#[derive(Default)]
pub struct Series {
    /// t, pos NED, vel NED, euler (roll, pitch, yaw).
    pub odom: Vec<(f64, [f64; 3], [f64; 3], [f64; 3])>,
    /// t, accelerometer roll/pitch (rad) from imu/data_raw.
    pub acc_angles: Vec<(f64, f64, f64)>,
    /// t, baro altitude, fused altitude, ground height, laser, sonar.
    pub alt: Vec<(f64, f64, f64, f64, f64, f64)>,
    /// t, commanded velocity NED (received setpoints).
    pub vel_cmd: Vec<(f64, [f64; 3])>,
    /// t, armed, mode, landed.
    pub status: Vec<(f64, bool, u8, bool)>,
    /// Mode commands the mission computer sent (`cmd/mode`): receive time, lower-case text.
    pub mode_cmds: Vec<(f64, String)>,
    /// Receive times of the velocity setpoints (`setpoint/velocity`).
    pub setpoint_times: Vec<f64>,
    /// t, the MCU's acceleration observer, horizontal N, E (m/s²) — `accel/observer`.
    pub accel_obs: Vec<(f64, [f64; 2])>,
    /// t, the measured (gravity-compensated) acceleration N, E, D (m/s²) — `accel/measured`.
    pub accel_meas: Vec<(f64, [f64; 3])>,
    /// first cmd/arm receive time.
    pub first_arm_cmd: Option<f64>,
    pub topics: std::collections::BTreeMap<String, u64>,
}

fn t_of(h: &Header) -> f64 {
    h.stamp.to_nanos() as f64 * 1e-9
}

pub fn decode(msgs: &[BagMsg]) -> Series {
    let mut s = Series::default();
    for m in msgs {
        *s.topics.entry(m.topic.clone()).or_default() += 1;
        let log_t = m.log_time as f64 * 1e-9;
        match (m.schema.as_str(), m.topic.rsplit('/').next().unwrap_or("")) {
            ("nav_msgs/msg/Odometry", _) => {
                if let Some(o) = from_cdr::<Odometry>(&m.data) {
                    let (p, v, q) = odom_ned(&o);
                    s.odom.push((t_of(&o.header), p, v, euler(q)));
                }
            }
            ("sensor_msgs/msg/Imu", "data_raw") => {
                if let Some(i) = from_cdr::<Imu>(&m.data) {
                    let a = i.linear_acceleration.to_array(); // FLU specific force
                    let roll = a[1].atan2(a[2]);
                    let pitch = a[0].atan2(a[1].hypot(a[2]));
                    s.acc_angles.push((t_of(&i.header), roll, pitch));
                }
            }
            ("fcc_msgs/msg/Altitude", _) => {
                if let Some(a) = from_cdr::<Altitude>(&m.data) {
                    s.alt.push((
                        t_of(&a.header),
                        a.baro_alt_m as f64,
                        a.alt_m as f64,
                        a.ground_height_m as f64,
                        a.laser_range_m as f64,
                        a.sonar_range_m as f64,
                    ));
                }
            }
            ("geometry_msgs/msg/TwistStamped", _) => {
                if let Some(tw) = from_cdr::<TwistStamped>(&m.data) {
                    let v = tw.twist.linear.to_array();
                    s.vel_cmd.push((log_t, [v[1], v[0], -v[2]]));
                    s.setpoint_times.push(log_t);
                }
            }
            ("fcc_msgs/msg/Status", _) => {
                if let Some(st) = from_cdr::<StatusHead>(&m.data) {
                    s.status
                        .push((t_of(&st.header), st.armed, st.mode, st.landed));
                }
            }
            ("std_msgs/msg/String", "mode") if m.topic.ends_with("cmd/mode") => {
                if let Some(c) = from_cdr::<StringMsg>(&m.data) {
                    s.mode_cmds
                        .push((log_t, c.data.trim().to_ascii_lowercase()));
                }
            }
            ("geometry_msgs/msg/AccelStamped", "observer" | "measured") => {
                if let Some(a) = from_cdr::<AccelIn>(&m.data) {
                    let (t, v) = (t_of(&a.header), a.linear.to_array()); // ENU
                    if m.topic.ends_with("accel/observer") {
                        s.accel_obs.push((t, [v[1], v[0]]));
                    } else if m.topic.ends_with("accel/measured") {
                        s.accel_meas.push((t, [v[1], v[0], -v[2]]));
                    }
                }
            }
            ("std_msgs/msg/Bool", "arm") => {
                if from_cdr::<Bool>(&m.data).is_some_and(|b| b.data) && s.first_arm_cmd.is_none() {
                    s.first_arm_cmd = Some(log_t);
                }
            }
            _ => {}
        }
    }
    s.odom.sort_by(|a, b| a.0.total_cmp(&b.0));
    s.status.sort_by(|a, b| a.0.total_cmp(&b.0));
    s.accel_obs.sort_by(|a, b| a.0.total_cmp(&b.0));
    s.accel_meas.sort_by(|a, b| a.0.total_cmp(&b.0));
    s
}
