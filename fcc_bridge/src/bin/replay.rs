//! `fcc-replay BAG [--rate R] [--decode-raw] [--ns-prefix P]`: republish a bag's topics with
//! their original timing (like `ros2 bag play`; `--rate 2` twice as fast), or with
//! `--decode-raw` re-decode its raw link frames through `fcc_msgs` and print per-type counts.
//! Each topic is republished with the QoS recorded in its channel's `offered_qos_profiles`
//! (reliability, durability, history, depth; several publishers combine as in rosbag2: reliable
//! only if all were, transient local only if all were), so `/tf_static` is transient local again
//! and a late joiner gets it. A topic without a usable profile gets the default (reliable,
//! volatile, keep last 1000); such topics are counted and printed.
//! DDS by default; Zenoh (rmw_zenoh's wire protocol, through a Zenoh router) with
//! `RMW_IMPLEMENTATION=rmw_zenoh_cpp`, as the bridge and the mission node (`fcc_ros::rmw`).
//! Run DDS only in a loopback-only namespace (netns-run) on shared machines.

use clap::Parser;
use fcc_bridge::record::from_cdr;
use fcc_bridge::report::bag::{read_bag_full, BagMsg};
use fcc_msgs::ros::LinkFrame;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "fcc-replay",
    about = "Republish a flight bag, or re-decode its raw link frames"
)]
struct Cli {
    bag: PathBuf,
    /// Playback rate (1 = original timing).
    #[arg(long, default_value_t = 1.0)]
    rate: f64,
    /// Only re-decode the raw link frames and print per-type counts (no DDS).
    #[arg(long)]
    decode_raw: bool,
    /// Republish under this prefix (`/replay`: `/fcc/imu/data_raw` → `/replay/fcc/imu/data_raw`),
    /// e.g. beside a live bridge.
    #[arg(long)]
    ns_prefix: Option<String>,
}

fn decode_raw(msgs: &[BagMsg]) {
    let mut counts: BTreeMap<String, u64> = BTreeMap::new();
    let mut dec = fcc_msgs::FrameDecoder::new();
    let mut frames = [0u64; 2];
    for m in msgs.iter().filter(|m| m.schema == "fcc_msgs/msg/LinkFrame") {
        let Some(f) = from_cdr::<LinkFrame>(&m.data) else {
            continue;
        };
        frames[(f.direction & 1) as usize] += 1;
        dec.reset();
        for r in dec.push_slice(&f.data) {
            let dir = if f.direction == LinkFrame::DIRECTION_MCU_TO_LINUX {
                "mcu→linux"
            } else {
                "linux→mcu"
            };
            let k = match r {
                Ok(fr) => format!("{dir} {}", fr.message.name()),
                Err(e) => format!("{dir} error {e:?}"),
            };
            *counts.entry(k).or_default() += 1;
        }
    }
    println!(
        "raw frames: {} mcu→linux, {} linux→mcu",
        frames[0], frames[1]
    );
    for (k, n) in counts {
        println!("  {k:36} {n}");
    }
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    anyhow::ensure!(cli.rate > 0.0 && cli.rate.is_finite(), "--rate must be > 0");
    let bag = read_bag_full(&cli.bag, |_, _, _| {})?;
    let (mut msgs, err) = (bag.msgs, bag.err);
    if let Some(e) = err {
        eprintln!(
            "fcc-replay: the bag is cut short ({e}); using the {} messages before it",
            msgs.len()
        );
    }
    if cli.decode_raw {
        decode_raw(&msgs);
        return Ok(());
    }
    msgs.sort_by_key(|m| m.log_time);
    let rt = tokio::runtime::Runtime::new()?;
    let prefix = cli
        .ns_prefix
        .as_deref()
        .map(|p| format!("/{}", p.trim_matches('/')))
        .filter(|p| p != "/")
        .unwrap_or_default();
    rt.block_on(play(msgs, &bag.channels, cli.rate, &prefix))
}

/// The QoS of one recorded profile (rmw's integer enums, or their names).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct RecordedQos {
    reliable: bool,
    transient_local: bool,
    /// `None` = keep all.
    depth: Option<usize>,
}

/// An rmw enum field: an integer, or a name (`reliable`, `transient_local`, `keep_last`, …).
fn enum_field(p: &serde_yaml::Value, key: &str, names: &[(&str, u64)]) -> Option<u64> {
    let v = p.get(key)?;
    if let Some(n) = v.as_u64() {
        return Some(n);
    }
    let s = v.as_str()?.trim().to_ascii_lowercase();
    names.iter().find(|(n, _)| *n == s).map(|(_, i)| *i)
}

/// Parse a channel's `offered_qos_profiles` YAML; `None` when missing or unusable.
fn parse_offered_qos(yaml: &str) -> Option<RecordedQos> {
    let v: serde_yaml::Value = serde_yaml::from_str(yaml).ok()?;
    let list = v.as_sequence()?;
    let mut out: Option<RecordedQos> = None;
    for p in list {
        // rmw: reliability 0 system default (reliable), 1 reliable, 2 best effort;
        // durability 0 system default (volatile), 1 transient local, 2 volatile;
        // history 0 system default (keep last), 1 keep last, 2 keep all.
        let rel = enum_field(
            p,
            "reliability",
            &[("system_default", 0), ("reliable", 1), ("best_effort", 2)],
        )?;
        let dur = enum_field(
            p,
            "durability",
            &[
                ("system_default", 0),
                ("transient_local", 1),
                ("volatile", 2),
            ],
        )?;
        let hist = enum_field(
            p,
            "history",
            &[("system_default", 0), ("keep_last", 1), ("keep_all", 2)],
        )?;
        let reliable = match rel {
            0 | 1 => true,
            2 => false,
            _ => return None,
        };
        let transient_local = match dur {
            1 => true,
            0 | 2 => false,
            _ => return None,
        };
        let depth = match hist {
            0 | 1 => {
                let d = p.get("depth")?.as_u64()? as usize;
                Some(if d == 0 { 1 } else { d })
            }
            2 => None,
            _ => return None,
        };
        let q = RecordedQos {
            reliable,
            transient_local,
            depth,
        };
        out = Some(match out {
            None => q,
            // Several publishers: as rosbag2 does, downgrade to what every one offered.
            Some(o) => RecordedQos {
                reliable: o.reliable && q.reliable,
                transient_local: o.transient_local && q.transient_local,
                depth: match (o.depth, q.depth) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    _ => None,
                },
            },
        });
    }
    out
}

fn describe(q: &RecordedQos) -> String {
    format!(
        "{}, {}, {}",
        if q.reliable {
            "reliable"
        } else {
            "best effort"
        },
        if q.transient_local {
            "transient local"
        } else {
            "volatile"
        },
        q.depth
            .map_or("keep all".to_string(), |d| format!("keep last {d}"))
    )
}

fn profile(q: &RecordedQos) -> ros2_client::QosProfile {
    use ros2_client::qos::{Durability, History, WhenFull};
    let p = ros2_client::QosProfile::publisher_default();
    let p = if q.reliable {
        p.reliability_reliable(WhenFull::DEFAULT)
    } else {
        p.reliability_best_effort()
    };
    p.durability(if q.transient_local {
        Durability::TransientLocal
    } else {
        Durability::Volatile
    })
    .history(match q.depth {
        Some(depth) => History::KeepLast { depth },
        None => History::KeepAll,
    })
}

/// Without a usable recorded profile: reliable, and a writer history deep enough that a
/// subscriber that falls behind for a moment gets the samples resent instead of overwritten.
const DEFAULT_QOS: RecordedQos = RecordedQos {
    reliable: true,
    transient_local: false,
    depth: Some(1000),
};

async fn play(
    msgs: Vec<BagMsg>,
    channels: &BTreeMap<String, BTreeMap<String, String>>,
    rate: f64,
    prefix: &str,
) -> anyhow::Result<()> {
    use fcc_ros::rmw::{Pub, RawCdr, Rmw, RosNode};
    use ros2_client::{MessageTypeName, NodeOptions};
    // DDS or Zenoh as ROS chooses (`RMW_IMPLEMENTATION`, fcc_ros::rmw). On DDS the one
    // participant builder: ROS_DOMAIN_ID, and loopback only unless ROS_LOCALHOST_ONLY=0 or
    // ROS_AUTOMATIC_DISCOVERY_RANGE says otherwise (as the bridge and the mission node); on Zenoh
    // the session from rmw_zenoh's variables (ZENOH_SESSION_CONFIG_URI, ZENOH_CONFIG_OVERRIDE).
    let rmw = Rmw::from_env().map_err(anyhow::Error::msg)?;
    let dds = fcc_ros::ros_node::DdsEnv::from_env(&fcc_ros::params::RosArgs::default())
        .map_err(anyhow::Error::msg)?;
    let ctx = fcc_ros::rmw::context(rmw, dds).map_err(anyhow::Error::msg)?;
    let mut node = ctx
        .new_node("/", "fcc_replay", NodeOptions::new())
        .map_err(anyhow::Error::msg)?;
    if let RosNode::Dds(n) = &mut node {
        tokio::spawn(n.spinner()?.spin());
    }
    eprintln!("fcc-replay: on {}", rmw.label());
    let mut from_bag = 0usize;
    let mut defaulted: Vec<String> = Vec::new();
    // Raw CDR passthrough: publish the recorded bytes as they are.
    let mut pubs: BTreeMap<String, Pub<RawCdr>> = BTreeMap::new();
    for m in &msgs {
        if pubs.contains_key(&m.topic) {
            continue;
        }
        let (pkg, name) = match m.schema.split_once("/msg/") {
            Some(x) => x,
            None => continue,
        };
        let full = format!("{prefix}{}", m.topic);
        let recorded = channels
            .get(&m.topic)
            .and_then(|md| md.get("offered_qos_profiles"))
            .and_then(|y| parse_offered_qos(y));
        let q = match recorded {
            Some(q) => {
                from_bag += 1;
                q
            }
            None => {
                defaulted.push(m.topic.clone());
                DEFAULT_QOS
            }
        };
        eprintln!(
            "fcc-replay: {full}: {}{}",
            describe(&q),
            if recorded.is_some() { "" } else { " (default)" }
        );
        let p = node
            .raw_publisher(&full, MessageTypeName::new(pkg, name), &profile(&q))
            .map_err(anyhow::Error::msg)?;
        pubs.insert(m.topic.clone(), p);
    }
    eprintln!(
        "fcc-replay: QoS from the bag's offered_qos_profiles on {from_bag} topics; {} without a usable profile → default ({}){}",
        defaulted.len(),
        describe(&DEFAULT_QOS),
        if defaulted.is_empty() {
            String::new()
        } else {
            format!(": {}", defaulted.join(", "))
        }
    );
    let Some(t0) = msgs.first().map(|m| m.log_time) else {
        return Ok(());
    };
    // Let subscribers match before the first message.
    tokio::time::sleep(Duration::from_millis(500)).await;
    eprintln!("fcc-replay: publishing");
    let start = Instant::now();
    let mut sent = 0u64;
    for m in &msgs {
        let due = Duration::from_secs_f64((m.log_time - t0) as f64 * 1e-9 / rate);
        if let Some(w) = due.checked_sub(start.elapsed()) {
            tokio::time::sleep(w).await;
        }
        if let Some(p) = pubs.get(&m.topic) {
            if p.publish(RawCdr(m.data[4.min(m.data.len())..].to_vec()))
                .is_ok()
            {
                sent += 1;
            }
        }
    }
    eprintln!(
        "fcc-replay: {sent} messages on {} topics in {:.1} s",
        pubs.len(),
        start.elapsed().as_secs_f64()
    );
    std::process::exit(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offered_qos_profiles_parse() {
        let inf = "{sec: 9223372036, nsec: 854775807}";
        let y = format!("- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n  deadline: {inf}\n  lifespan: {inf}\n  liveliness: 1\n  liveliness_lease_duration: {inf}\n  avoid_ros_namespace_conventions: false\n");
        assert_eq!(
            parse_offered_qos(&y),
            Some(RecordedQos {
                reliable: true,
                transient_local: true,
                depth: Some(1)
            })
        );
        // The recorder's own YAML.
        let t = fcc_bridge::record::QosInfo {
            reliable: false,
            transient_local: false,
            depth: 10,
        };
        assert_eq!(
            parse_offered_qos(&t.yaml()),
            Some(RecordedQos {
                reliable: false,
                transient_local: false,
                depth: Some(10)
            })
        );
        // Names, keep all, and two publishers (one volatile → volatile).
        let y2 = "- {history: keep_all, depth: 0, reliability: reliable, durability: transient_local}\n- {history: 1, depth: 5, reliability: 1, durability: 2}\n";
        assert_eq!(
            parse_offered_qos(y2),
            Some(RecordedQos {
                reliable: true,
                transient_local: false,
                depth: None
            })
        );
        // Unusable → None (the caller falls back to the default and counts it).
        for bad in [
            "",
            "not: a list",
            "- {history: 1, depth: 10}",
            "- {history: 9, depth: 1, reliability: 1, durability: 1}",
            "[: bad",
        ] {
            assert_eq!(parse_offered_qos(bad), None, "{bad:?}");
        }
    }
}
