//! Reading our bags back: every message with its topic, log time and CDR payload, from a
//! finished bag (summary) or a truncated one (SIGKILL: streamed up to the last whole chunk).

use fcc_msgs::ros::Odometry;
use fcc_ros::frames;

/// One message of a bag.
#[derive(Clone, Debug)]
pub struct BagMsg {
    pub topic: String,
    pub schema: String,
    pub log_time: u64,
    pub data: Vec<u8>,
}

/// What a [`read_bag`] progress report counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// Reading the file into memory: bytes of the file.
    FileBytes,
    /// Decoding, total from the summary's Statistics: messages.
    Messages,
    /// Decoding a bag without a summary (cut by SIGKILL): bytes of the file.
    Bytes,
}

/// A whole bag read back.
#[derive(Clone, Debug, Default)]
pub struct Bag {
    /// Every message in file order.
    pub msgs: Vec<BagMsg>,
    /// Why reading stopped early (a truncated bag), if it did.
    pub err: Option<String>,
    /// Each topic's channel metadata (`offered_qos_profiles`, …), first channel of the topic.
    pub channels: std::collections::BTreeMap<String, std::collections::BTreeMap<String, String>>,
    /// The summary's message count, when the bag has one.
    pub summary_messages: Option<u64>,
}

/// All messages of a bag in file order; `progress(unit, done, total)`. A truncated bag yields
/// what precedes the cut, and the error as the second value.
pub fn read_bag(
    path: &std::path::Path,
    mut progress: impl FnMut(Progress, u64, u64),
) -> std::io::Result<(Vec<BagMsg>, Option<String>)> {
    let b = read_bag_full(path, &mut progress)?;
    Ok((b.msgs, b.err))
}

/// Read the file in pieces, reporting bytes.
fn read_file(
    path: &std::path::Path,
    progress: &mut impl FnMut(Progress, u64, u64),
) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut f = std::fs::File::open(path)?;
    let total = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut buf = Vec::with_capacity(total as usize);
    progress(Progress::FileBytes, 0, total);
    let mut piece = vec![0u8; 4 << 20];
    loop {
        let n = f.read(&mut piece)?;
        if n == 0 {
            break;
        }
        buf.extend_from_slice(&piece[..n]);
        progress(
            Progress::FileBytes,
            buf.len() as u64,
            total.max(buf.len() as u64),
        );
    }
    Ok(buf)
}

/// [`read_bag`] with the channels' metadata. Progress: the file read in bytes, then one report
/// per message against the summary's message count (Statistics); a bag without a summary
/// (SIGKILL) reports the bytes of the file decoded so far instead.
pub fn read_bag_full(
    path: &std::path::Path,
    mut progress: impl FnMut(Progress, u64, u64),
) -> std::io::Result<Bag> {
    use mcap::records::Record;
    let buf = read_file(path, &mut progress)?;
    let total_bytes = buf.len() as u64;
    // A truncated bag has no footer: Summary::read fails or finds none → fall back to bytes.
    let summary_messages = mcap::Summary::read(&buf)
        .ok()
        .flatten()
        .and_then(|s| s.stats.map(|st| st.message_count));
    let mut bag = Bag {
        summary_messages,
        ..Default::default()
    };
    let mut channels = mcap::read::ChannelAccumulator::default();
    // Bytes of the file consumed (records are counted by their size; headers approximately).
    let mut done_bytes = 9u64;
    let mut n = 0u64;
    let mut report = |n: u64, done_bytes: u64| match summary_messages {
        Some(total) => progress(Progress::Messages, n, total.max(n)),
        None => progress(Progress::Bytes, done_bytes.min(total_bytes), total_bytes),
    };
    report(0, 0);
    let reader = mcap::read::LinearReader::new(&buf).map_err(std::io::Error::other)?;
    'outer: for r in reader {
        let r = match r {
            Ok(r) => r,
            Err(e) => {
                bag.err = Some(e.to_string());
                break;
            }
        };
        match r {
            Record::Chunk { header, data } => {
                let size = 9 + 40 + header.compression.len() as u64 + data.len() as u64;
                let chunk = match mcap::read::ChunkReader::new(header, &data) {
                    Ok(c) => c,
                    Err(e) => {
                        bag.err = Some(e.to_string());
                        break;
                    }
                };
                for r in chunk {
                    match r
                        .map_err(|e| e.to_string())
                        .and_then(|r| add_record(r, &mut channels, &mut bag))
                    {
                        Ok(true) => {
                            n += 1;
                            report(n, done_bytes);
                        }
                        Ok(false) => {}
                        Err(e) => {
                            bag.err = Some(e);
                            break 'outer;
                        }
                    }
                }
                done_bytes += size;
                report(n, done_bytes);
            }
            Record::MessageIndex(mi) => done_bytes += 9 + 6 + 16 * mi.records.len() as u64,
            Record::DataEnd(_) => break,
            r => {
                let msg = matches!(r, Record::Message { .. });
                let size = match &r {
                    Record::Message { data, .. } => 9 + 22 + data.len() as u64,
                    Record::Schema { data, .. } => 9 + 16 + data.len() as u64,
                    _ => 9 + 32,
                };
                match add_record(r, &mut channels, &mut bag) {
                    Ok(_) => {}
                    Err(e) => {
                        bag.err = Some(e);
                        break;
                    }
                }
                done_bytes += size;
                if msg {
                    n += 1;
                    report(n, done_bytes);
                }
            }
        }
    }
    if bag.err.is_none() {
        report(n, total_bytes);
    }
    Ok(bag)
}

/// One record of a bag's data section: schemas and channels into `channels` (and the channels'
/// metadata into `bag`), a message into `bag.msgs` (then true).
fn add_record(
    r: mcap::records::Record<'_>,
    channels: &mut mcap::read::ChannelAccumulator<'static>,
    bag: &mut Bag,
) -> Result<bool, String> {
    use mcap::records::Record;
    match r {
        Record::Schema { header, data } => channels
            .add_schema(header, std::borrow::Cow::Owned(data.into_owned()))
            .map_err(|e| e.to_string())?,
        Record::Channel(c) => {
            bag.channels
                .entry(c.topic.clone())
                .or_insert_with(|| c.metadata.clone());
            channels.add_channel(c).map_err(|e| e.to_string())?
        }
        Record::Message { header, data } => {
            let Some(ch) = channels.get(header.channel_id) else {
                return Err(
                    mcap::McapError::UnknownChannel(header.sequence, header.channel_id).to_string(),
                );
            };
            bag.msgs.push(BagMsg {
                topic: ch.topic.clone(),
                schema: ch
                    .schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default(),
                log_time: header.log_time,
                data: data.into_owned(),
            });
            return Ok(true);
        }
        _ => {}
    }
    Ok(false)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{QosInfo, RecordOptions, Tap};
    use fcc_msgs::ros::Imu;
    use std::time::Duration;

    /// Progress: the file in bytes, then per message against the summary's count; a bag cut
    /// short (no summary) reports bytes, and yields what precedes the cut.
    #[test]
    fn progress_counts_messages_from_the_summary_or_falls_back_to_bytes() {
        let dir = std::env::temp_dir().join(format!("fcc-bag-progress-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.mcap");
        let mut o = RecordOptions::new(&path);
        o.chunk_bytes = 8 << 10;
        let tap = Tap::recording("/fcc", o).unwrap();
        let n = 3000u64;
        for i in 0..n as i64 {
            tap.published(
                "imu/data_raw",
                QosInfo::TELEMETRY,
                &Imu::default(),
                1 + i * 1_000_000,
            );
        }
        tap.finish(Duration::from_secs(10)).unwrap();
        let mut seen: Vec<(Progress, u64, u64)> = Vec::new();
        let bag = read_bag_full(&path, |u, d, t| seen.push((u, d, t))).unwrap();
        assert!(bag.err.is_none());
        assert_eq!(bag.msgs.len() as u64, n);
        assert_eq!(bag.summary_messages, Some(n));
        assert!(
            bag.channels["/fcc/imu/data_raw"]["offered_qos_profiles"].starts_with("- history: 1")
        );
        let size = std::fs::metadata(&path).unwrap().len();
        assert_eq!(seen[0], (Progress::FileBytes, 0, size));
        assert!(seen.contains(&(Progress::FileBytes, size, size)));
        let msgs: Vec<_> = seen.iter().filter(|s| s.0 == Progress::Messages).collect();
        // One report per message (and one at 0 and one at the end), always against n.
        assert!(msgs.len() as u64 > n, "{}", msgs.len());
        assert!(msgs.iter().all(|s| s.2 == n));
        assert!(msgs.windows(2).all(|w| w[0].1 <= w[1].1));
        assert_eq!(msgs.last().unwrap().1, n);
        assert!(!seen.iter().any(|s| s.0 == Progress::Bytes));

        // Cut it at 60 % (as SIGKILL would): no summary → bytes of the file, the messages
        // before the cut, and the error.
        let buf = std::fs::read(&path).unwrap();
        let cut = dir.join("cut.mcap");
        std::fs::write(&cut, &buf[..buf.len() * 6 / 10]).unwrap();
        let mut seen: Vec<(Progress, u64, u64)> = Vec::new();
        let bag = read_bag_full(&cut, |u, d, t| seen.push((u, d, t))).unwrap();
        assert!(bag.err.is_some());
        assert_eq!(bag.summary_messages, None);
        assert!(bag.msgs.len() as u64 > n / 3 && (bag.msgs.len() as u64) < n);
        let bytes: Vec<_> = seen.iter().filter(|s| s.0 == Progress::Bytes).collect();
        let total = (buf.len() * 6 / 10) as u64;
        assert!(bytes.len() > 10 && bytes.iter().all(|s| s.2 == total && s.1 <= total));
        assert!(bytes.windows(2).all(|w| w[0].1 <= w[1].1));
        assert!(bytes.last().unwrap().1 > total / 2, "{:?}", bytes.last());
        assert!(!seen.iter().any(|s| s.0 == Progress::Messages));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
