//! Reading our bags back: every message with its topic, log time and CDR payload, from a
//! finished bag (summary) or a truncated one (SIGKILL: streamed up to the last whole chunk).

use crate::frames;
use crate::ros_types::Odometry;

/// One message of a bag.
#[derive(Clone, Debug)]
pub struct BagMsg {
    pub topic: String,
    pub schema: String,
    pub log_time: u64,
    pub data: Vec<u8>,
}

/// All messages of a bag in file order; `progress(done_bytes, total_bytes)`. A truncated bag
/// yields what precedes the cut, and the error as the second value.
pub fn read_bag(
    path: &std::path::Path,
    mut progress: impl FnMut(u64, u64),
) -> std::io::Result<(Vec<BagMsg>, Option<String>)> {
    let buf = std::fs::read(path)?;
    let total = buf.len() as u64;
    let mut out = Vec::new();
    let mut err = None;
    let mut n = 0u64;
    for m in mcap::MessageStream::new(&buf).map_err(std::io::Error::other)? {
        match m {
            Ok(m) => {
                n += 1;
                if n % 4096 == 0 {
                    // Messages are read chunk by chunk; estimate by count share of the size.
                    progress((n * 200).min(total), total);
                }
                out.push(BagMsg {
                    topic: m.channel.topic.clone(),
                    schema: m
                        .channel
                        .schema
                        .as_ref()
                        .map(|s| s.name.clone())
                        .unwrap_or_default(),
                    log_time: m.log_time,
                    data: m.data.into_owned(),
                });
            }
            Err(e) => {
                err = Some(e.to_string());
                break;
            }
        }
    }
    progress(total, total);
    Ok((out, err))
}

/// Position (NED, m), velocity (NED, m/s) and attitude (FRD→NED quaternion) of an ENU/FLU odom.
pub fn odom_ned(o: &Odometry) -> ([f64; 3], [f64; 3], [f64; 4]) {
    let p = &o.pose.pose.position;
    let pos = frames::enu_to_ned([p.x, p.y, p.z]);
    let q = &o.pose.pose.orientation;
    let q_ned = frames::q_flu_enu_to_q_frd_ned([q.w, q.x, q.y, q.z]);
    let v_frd = frames::flu_to_frd(o.twist.twist.linear.to_array());
    let vel = frames::quat_rotate(q_ned, v_frd);
    (pos, vel, q_ned)
}

/// ZYX Euler angles (roll, pitch, yaw) of an FRD→NED quaternion.
pub fn euler(q: [f64; 4]) -> [f64; 3] {
    let [w, x, y, z] = frames::quat_normalize(q);
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
}
