//! `fcc-record-bench [N]`: recorder throughput — our recorder (`fcc_bridge::record::Tap`: CDR
//! serialise, queue, writer thread, chunk policy, zstd) vs the bare `mcap` crate writer writing
//! the same messages (serialised inline, same write options), same machine, same run. Prints
//! `ROW|recorder throughput|ours msg/s|mcap msg/s|ratio|goal ≥0.8×|met`.

use fcc_bridge::record::{cdr_bytes, write_options, QosInfo, RecordOptions, Tap};
use fcc_msgs::ros::{full_definition, Imu, RosMsg, Time};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

fn msgs(n: usize) -> Vec<Imu> {
    (0..n)
        .map(|i| {
            let mut m = Imu::default();
            m.header.stamp = Time::from_nanos(i as i64 * 5_000_000);
            m.header.frame_id = "imu_link".into();
            m.linear_acceleration.x = (i as f64 * 0.01).sin();
            m.linear_acceleration.z = 9.81 + (i as f64 * 0.37).cos() * 0.3;
            m.angular_velocity.y = (i as f64 * 0.013).cos() * 0.1;
            m
        })
        .collect()
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200_000);
    let dir = std::env::temp_dir().join(format!("fcc-record-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let data = msgs(n);
    let mut best = (0.0f64, 0.0f64);
    for _ in 0..3 {
        // Ours.
        let tap = Tap::recording("/fcc", RecordOptions::new(dir.join("ours.mcap"))).unwrap();
        let t = Instant::now();
        for (i, m) in data.iter().enumerate() {
            tap.published("imu/data_raw", QosInfo::TELEMETRY, m, i as i64 * 5_000_000);
        }
        let rep = tap.finish(Duration::from_secs(120)).expect("finished");
        let ours = n as f64 / t.elapsed().as_secs_f64();
        assert_eq!(rep.recorded.values().sum::<u64>(), n as u64);
        // Bare mcap writer.
        let t = Instant::now();
        let f = std::io::BufWriter::with_capacity(
            1 << 20,
            std::fs::File::create(dir.join("bare.mcap")).unwrap(),
        );
        let mut w = write_options(true, 4 << 20).create(f).unwrap();
        let s = w
            .add_schema(
                &Imu::schema_name(),
                "ros2msg",
                full_definition::<Imu>().as_bytes(),
            )
            .unwrap();
        let mut md = BTreeMap::new();
        md.insert(
            "offered_qos_profiles".to_string(),
            QosInfo::TELEMETRY.yaml(),
        );
        let c = w.add_channel(s, "/fcc/imu/data_raw", "cdr", &md).unwrap();
        for (i, m) in data.iter().enumerate() {
            let t = i as u64 * 5_000_000;
            let h = mcap::records::MessageHeader {
                channel_id: c,
                sequence: i as u32,
                log_time: t,
                publish_time: t,
            };
            w.write_to_known_channel(&h, &cdr_bytes(m)).unwrap();
        }
        w.finish().unwrap();
        drop(w);
        let bare = n as f64 / t.elapsed().as_secs_f64();
        best = (best.0.max(ours), best.1.max(bare));
    }
    let _ = std::fs::remove_dir_all(&dir);
    let ratio = best.0 / best.1;
    println!("recorder throughput, {n} sensor_msgs/Imu, zstd, best of 3: ours {:.0} msg/s, bare mcap writer {:.0} msg/s", best.0, best.1);
    println!(
        "ROW|recorder throughput|{:.0} msg/s|{:.0} msg/s|{:.2}×|goal ≥0.8×|{}",
        best.0,
        best.1,
        ratio,
        if ratio >= 0.8 { "met" } else { "NOT met" }
    );
}
