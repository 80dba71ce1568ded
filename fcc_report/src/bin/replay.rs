//! `fcc-replay BAG [--rate R] [--decode-raw] [--ns-prefix P]`: republish a bag's topics with
//! their original timing (like `ros2 bag play`; `--rate 2` twice as fast), or with
//! `--decode-raw` re-decode its raw link frames through `fcc_msgs` and print per-type counts.
//! Run DDS only in a loopback-only namespace (netns-run) on shared machines.

use clap::Parser;
use fcc_bridge::record::from_cdr;
use fcc_bridge::report::bag::{read_bag, BagMsg};
use fcc_bridge::ros_types::LinkFrame;
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
    let (mut msgs, err) = read_bag(&cli.bag, |_, _| {})?;
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
    rt.block_on(play(msgs, cli.rate, &prefix))
}

async fn play(msgs: Vec<BagMsg>, rate: f64, prefix: &str) -> anyhow::Result<()> {
    use ros2_client::{Context, MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
    let ctx = Context::new()?;
    let mut node = ctx.new_node(NodeName::new("/", "fcc_replay")?, NodeOptions::new())?;
    tokio::spawn(node.spinner()?.spin());
    // Reliable, and a writer history deep enough that a subscriber that falls behind for a
    // moment gets the samples resent instead of overwritten (the default keeps only 1).
    let qos = QosProfile::publisher_default()
        .history(ros2_client::qos::History::KeepLast { depth: 1000 });
    // Raw CDR passthrough: publish the recorded bytes as they are.
    let mut pubs: BTreeMap<String, ros2_client::Publisher<RawCdr>> = BTreeMap::new();
    for m in &msgs {
        if pubs.contains_key(&m.topic) {
            continue;
        }
        let (pkg, name) = match m.schema.split_once("/msg/") {
            Some(x) => x,
            None => continue,
        };
        let full = format!("{prefix}{}", m.topic);
        let topic = node.create_topic(
            &Name::parse(&full).map_err(|e| anyhow::anyhow!("{full}: {e:?}"))?,
            MessageTypeName::new(pkg, name),
            &qos,
        )?;
        pubs.insert(
            m.topic.clone(),
            node.create_publisher::<RawCdr>(&topic, None)?,
        );
    }
    let Some(t0) = msgs.first().map(|m| m.log_time) else {
        return Ok(());
    };
    // Let subscribers match before the first message.
    tokio::time::sleep(Duration::from_millis(500)).await;
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

/// A CDR body passed through unchanged (serialised as raw bytes, without a length).
#[derive(Clone, Debug)]
struct RawCdr(Vec<u8>);
impl serde::Serialize for RawCdr {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let mut t = s.serialize_tuple(self.0.len())?;
        for b in &self.0 {
            t.serialize_element(b)?;
        }
        t.end()
    }
}
impl<'de> serde::Deserialize<'de> for RawCdr {
    fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
        Err(serde::de::Error::custom("RawCdr is publish-only"))
    }
}
impl ros2_client::Message for RawCdr {}
