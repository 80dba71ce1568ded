//! Flight recorder: every message the bridge publishes and receives, and the raw link frames,
//! into rosbag2-compatible MCAP files (profile `ros2`, `ros2msg` schemas with their full
//! dependency text, `cdr` payloads with the 4-byte encapsulation header, `offered_qos_profiles`
//! channel metadata, a Statistics record).
//!
//! The bridge's link task calls a [`Tap`] (cheap: CDR-serialise and queue); one writer thread
//! owns the file, so a slow disk never stalls the serial loop.
//!
//! **Chunking policy (crash safety)**: a chunk is closed and the file flushed to the OS every
//! [`RecordOptions::chunk_interval`] (default 500 ms of wall time) or when it reaches
//! [`RecordOptions::chunk_bytes`] (default 4 MiB), whichever comes first. A SIGKILL (or power
//! loss after the kernel wrote its cache) therefore loses at most the open chunk: ≤ 0.5 s plus
//! the queue, measured 0.3–0.5 s. A SIGINT/SIGTERM finishes the file (summary, footer). Chunks
//! follow the wall clock (crash safety is about real time); file splits follow log time.
//! Chunks are built in memory and written whole (`disable_seeking`), so a killed recording
//! ends at a record boundary: no half chunk with the placeholder length 2^64−1 that makes
//! readers reject the file. It still has no summary: `fcc-bag-recover` ([`crate::recover`])
//! rewrites it into a complete MCAP that every reader opens.
//!
//! **Files**: the first file is `PATH`; a split (`record_split_s`, `record_split_mb`) or a new
//! arm period (`record_on_arm`) opens `STEM_1.mcap`, `STEM_2.mcap`, … beside it.
//! `record_split_s` splits on the messages' **log time**, as rosbag2 does: a message whose log
//! time is ≥ the file's first log time + split_s starts the next file, so a file spans < split_s
//! of log time however far the writer thread lags (deterministic for a given stream of
//! messages). `record_split_mb` splits by bytes: a file holds ≤ MB·10^6 B of messages plus one.
//! At the end the bridge writes `PATH.counts.json`: the per-topic counts it published/received
//! and recorded.
//!
//! **Write errors** (disk full, …): one error is logged, the recording stops, the bridge runs on.

mod options;

pub use fcc_ros::topics::QosInfo;
pub use options::{record_options, RecordOptions, RECORD_PARAMS};

use fcc_msgs::ros::{full_definition, Header, LinkFrame, RosMsg, Time};
use fcc_ros::topics::{self, Topic};
use std::collections::{BTreeMap, HashMap};
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The channel of `topic` carrying `T` with `qos` (ROS 2 schema text, offered QoS).
fn channel_desc<T: RosMsg>(topic: &str, qos: QosInfo) -> ChannelDesc {
    ChannelDesc {
        topic: topic.to_string(),
        schema_name: T::schema_name(),
        schema: full_definition::<T>(),
        qos: qos.yaml(),
    }
}

/// Initial capacity of a serialised message (see [`cdr_bytes`]).
const CDR_START_CAPACITY: usize = 512;

/// CDR (little endian) with the 4-byte encapsulation header `00 01 00 00`.
pub fn cdr_bytes<T: serde::Serialize>(m: &T) -> Vec<u8> {
    // Room for the common messages at once (sensor_msgs/Imu is 324 bytes): the serializer
    // writes field by field, and growing from 4 bytes cost a fifth of the recorder's
    // instructions in reallocations (callgrind of fcc-record-bench).
    cdr_into(Vec::with_capacity(CDR_START_CAPACITY), m)
}

/// [`cdr_bytes`] into a buffer that is reused (cleared first).
fn cdr_into<T: serde::Serialize>(mut v: Vec<u8>, m: &T) -> Vec<u8> {
    v.clear();
    v.extend_from_slice(&[0u8, 1, 0, 0]);
    if let Err(e) = cdr_encoding::to_writer::<T, byteorder::LittleEndian, _>(&mut v, m) {
        tracing::error!("CDR serialisation failed: {e}");
    }
    v
}

/// Message buffers the writer thread hands back for reuse, at most this many. Freed on the
/// writer thread, each buffer malloc'd by the bridge's threads went back to their malloc arena
/// under its lock: glibc's futex wait/wake on every message (`perf` of fcc-record-bench).
const RECYCLED_BUFFERS: usize = 1024;

/// Decode a CDR payload (with its 4-byte header) into `T`.
pub fn from_cdr<T: serde::de::DeserializeOwned>(data: &[u8]) -> Option<T> {
    if data.len() < 4 {
        return None;
    }
    let r = if data[1] == 1 {
        cdr_encoding::from_bytes::<T, byteorder::LittleEndian>(&data[4..])
    } else {
        cdr_encoding::from_bytes::<T, byteorder::BigEndian>(&data[4..])
    };
    r.ok().map(|(t, _)| t)
}

/// Join a ROS name to the namespace (`imu` + `/fcc` → `/fcc/imu`; absolute names stay).
pub fn full_topic(namespace: &str, name: &str) -> String {
    if name.starts_with('/') {
        name.to_string()
    } else {
        format!("{}/{}", namespace.trim_end_matches('/'), name)
    }
}

/// Per-topic counts of what the bridge published and received.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Counts {
    pub published: BTreeMap<String, u64>,
    pub received: BTreeMap<String, u64>,
    /// Raw link frames by direction (`mcu_to_linux`, `linux_to_mcu`).
    pub raw_frames: BTreeMap<String, u64>,
}

impl Counts {
    /// Everything by topic (published + received + raw frames on their topic).
    pub fn by_topic(&self, raw_topic: &str) -> BTreeMap<String, u64> {
        let mut m = self.published.clone();
        for (k, v) in &self.received {
            *m.entry(k.clone()).or_default() += v;
        }
        let raw: u64 = self.raw_frames.values().sum();
        if raw > 0 {
            *m.entry(raw_topic.to_string()).or_default() += raw;
        }
        m
    }
}

struct ChannelDesc {
    topic: String,
    schema_name: String,
    schema: String,
    qos: String,
}

enum Ev {
    Channel(u16, ChannelDesc),
    Msg { ch: u16, t: u64, data: Vec<u8> },
    Armed(bool),
    Finish(Counts, mpsc::Sender<RecorderReport>),
}

/// What the writer thread did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RecorderReport {
    pub files: Vec<PathBuf>,
    /// Messages written, by topic.
    pub recorded: BTreeMap<String, u64>,
    /// Messages not written (not armed with record_on_arm, or after a write error).
    pub not_recorded: u64,
    pub error: Option<String>,
}

/// The bridge's side of the recorder: counts every message, and queues it for the writer
/// thread when recording.
pub struct Tap {
    namespace: String,
    /// `-r from:=to` remaps: a message is filed under the topic it really went out on.
    remaps: Vec<(String, String)>,
    inner: Mutex<TapInner>,
    tx: Option<mpsc::Sender<Ev>>,
    thread: Mutex<Option<std::thread::JoinHandle<()>>>,
    pub path: Option<PathBuf>,
}

/// What the tap keeps per name a message was counted on.
struct NameEntry {
    /// The full topic.
    topic: String,
    published: u64,
    received: u64,
    /// The recorder's channel of the topic, once it has one.
    channel: Option<u16>,
}

struct TapInner {
    counts: Counts,
    /// Relative or absolute name → its counts and channel (one lookup per message). FNV: the
    /// names are ours, short, and not chosen by a peer (SipHash cost ~180 instructions a look-up).
    names: HashMap<String, NameEntry, fnv::FnvBuildHasher>,
    channels: HashMap<String, u16>,
    raw_in: Vec<u8>,
    raw_decoder: fcc_msgs::FrameDecoder,
    armed: Option<bool>,
    /// Message buffers back from the writer thread ([`RECYCLED_BUFFERS`]).
    recycled: Option<mpsc::Receiver<Vec<u8>>>,
}

impl Tap {
    /// A tap that only counts.
    pub fn counting(namespace: &str) -> Arc<Tap> {
        Arc::new(Tap {
            namespace: namespace.to_string(),
            remaps: Vec::new(),
            inner: Mutex::new(TapInner {
                counts: Counts::default(),
                names: HashMap::default(),
                channels: HashMap::new(),
                raw_in: Vec::new(),
                raw_decoder: fcc_msgs::FrameDecoder::new(),
                armed: None,
                recycled: None,
            }),
            tx: None,
            thread: Mutex::new(None),
            path: None,
        })
    }

    /// A recording tap; the writer thread starts now (the first file is created at once,
    /// unless `on_arm`).
    pub fn recording(namespace: &str, opts: RecordOptions) -> std::io::Result<Arc<Tap>> {
        if let Some(d) = opts.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(d)?;
        }
        let (tx, rx) = mpsc::channel();
        let path = opts.path.clone();
        let (recycle_tx, recycle_rx) = mpsc::sync_channel(RECYCLED_BUFFERS);
        let mut w = WriterThread::new(opts);
        w.recycle = Some(recycle_tx);
        if !w.opts.on_arm {
            w.open();
        }
        let th = std::thread::Builder::new()
            .name("fcc-recorder".into())
            .spawn(move || w.run(rx))?;
        let mut t = Arc::try_unwrap(Tap::counting(namespace))
            .ok()
            .expect("fresh Arc");
        t.tx = Some(tx);
        t.inner.get_mut().expect("fresh mutex").recycled = Some(recycle_rx);
        t.thread = Mutex::new(Some(th));
        t.path = Some(path);
        Ok(Arc::new(t))
    }

    /// The same tap, filing messages under their remapped topics (`-r /tf:=tf` records the
    /// bridge's TF under `NAMESPACE/tf`, where it was published). Call before sharing the tap.
    pub fn with_remaps(self: Arc<Self>, remaps: &[(String, String)]) -> Arc<Self> {
        match Arc::try_unwrap(self) {
            Ok(mut t) => {
                t.remaps = remaps.to_vec();
                Arc::new(t)
            }
            Err(shared) => shared,
        }
    }

    /// Full topic of a name the bridge publishes or subscribes to (namespace + remaps).
    fn topic_of(&self, name: &str) -> String {
        let remapped = fcc_ros::params::remap(&self.remaps, &self.namespace, name);
        full_topic(&self.namespace, &remapped)
    }

    pub fn is_recording(&self) -> bool {
        self.tx.is_some()
    }

    fn channel_id(
        &self,
        inner: &mut TapInner,
        topic: &str,
        make: impl FnOnce() -> ChannelDesc,
    ) -> u16 {
        if let Some(id) = inner.channels.get(topic) {
            return *id;
        }
        let id = inner.channels.len() as u16;
        inner.channels.insert(topic.to_string(), id);
        if let Some(tx) = &self.tx {
            let _ = tx.send(Ev::Channel(id, make()));
        }
        id
    }

    fn record<T: RosMsg + serde::Serialize>(
        &self,
        inner: &mut TapInner,
        topic: &str,
        qos: QosInfo,
        m: &T,
        t_ns: i64,
    ) {
        if self.tx.is_none() {
            return;
        }
        let ch = self.channel_id(inner, topic, || channel_desc::<T>(topic, qos));
        self.send_msg(inner, ch, m, t_ns);
    }

    /// One message on channel `ch` to the writer thread.
    fn send_msg<T: serde::Serialize>(&self, inner: &mut TapInner, ch: u16, m: &T, t_ns: i64) {
        if let Some(tx) = &self.tx {
            let buf = inner
                .recycled
                .as_ref()
                .and_then(|r| r.try_recv().ok())
                .unwrap_or_else(|| Vec::with_capacity(CDR_START_CAPACITY));
            let _ = tx.send(Ev::Msg {
                ch,
                t: t_ns.max(0) as u64,
                data: cdr_into(buf, m),
            });
        }
    }

    /// A message the bridge published on `name` (relative to the namespace or absolute), at ROS
    /// time `t_ns`.
    pub fn published<T: RosMsg + serde::Serialize>(
        &self,
        name: &str,
        qos: QosInfo,
        m: &T,
        t_ns: i64,
    ) {
        self.count_and_record(name, true, qos, m, t_ns);
    }

    /// A message the bridge received.
    pub fn received<T: RosMsg + serde::Serialize>(
        &self,
        name: &str,
        qos: QosInfo,
        m: &T,
        t_ns: i64,
    ) {
        self.count_and_record(name, false, qos, m, t_ns);
    }

    /// A message the bridge published on a topic of the table (its name and QoS).
    pub fn published_on<T: RosMsg + serde::Serialize>(&self, topic: &Topic<T>, m: &T, t_ns: i64) {
        self.published(topic.name, topic.qos, m, t_ns);
    }

    /// A message the bridge received on a topic of the table.
    pub fn received_on<T: RosMsg + serde::Serialize>(&self, topic: &Topic<T>, m: &T, t_ns: i64) {
        self.received(topic.name, topic.qos, m, t_ns);
    }

    fn count_and_record<T: RosMsg + serde::Serialize>(
        &self,
        name: &str,
        publ: bool,
        qos: QosInfo,
        m: &T,
        t_ns: i64,
    ) {
        let mut g = self.inner.lock().unwrap();
        let g = &mut *g;
        let e = match g.names.get_mut(name) {
            Some(e) => e,
            None => {
                let topic = self.topic_of(name);
                g.names.entry(name.to_string()).or_insert(NameEntry {
                    topic,
                    published: 0,
                    received: 0,
                    channel: None,
                })
            }
        };
        if publ {
            e.published += 1;
        } else {
            e.received += 1;
        }
        if self.tx.is_none() {
            return;
        }
        let ch = match e.channel {
            Some(c) => c,
            None => {
                let topic = e.topic.clone();
                let c = self.channel_id(g, &topic, || channel_desc::<T>(&topic, qos));
                if let Some(e) = g.names.get_mut(name) {
                    e.channel = Some(c);
                }
                c
            }
        };
        self.send_msg(g, ch, m, t_ns);
    }

    /// Bytes read from the MCU (any split): recorded frame by frame at each 0x00.
    pub fn raw_in(&self, bytes: &[u8], t_ns: i64) {
        let mut g = self.inner.lock().unwrap();
        let g = &mut *g;
        // Each piece ends at a 0x00 (a frame's end), but the last one may not (a half frame,
        // kept for the next read).
        for piece in bytes.split_inclusive(|b| *b == 0) {
            if piece.last() != Some(&0) {
                g.raw_in.extend_from_slice(piece);
                break;
            }
            let len = g.raw_in.len() + piece.len();
            // Not recording: only counted, so no copy (and no allocation) per frame.
            let data = if self.tx.is_none() {
                g.raw_in.clear();
                Vec::new()
            } else {
                let mut data = std::mem::take(&mut g.raw_in);
                data.extend_from_slice(piece);
                data
            };
            if len > 1 {
                self.raw_frame(g, LinkFrame::DIRECTION_MCU_TO_LINUX, data, t_ns);
            }
        }
    }

    /// Bytes written to the MCU (whole frames, possibly several).
    pub fn raw_out(&self, bytes: &[u8], t_ns: i64) {
        let mut g = self.inner.lock().unwrap();
        let g = &mut *g;
        for f in bytes.split_inclusive(|b| *b == 0) {
            if f.len() > 1 {
                self.raw_frame(g, LinkFrame::DIRECTION_LINUX_TO_MCU, f.to_vec(), t_ns);
            }
        }
    }

    /// A new connection: forget a half frame.
    pub fn raw_reset(&self) {
        self.inner.lock().unwrap().raw_in.clear();
    }

    fn raw_frame(&self, g: &mut TapInner, direction: u8, data: Vec<u8>, t_ns: i64) {
        let key = if direction == LinkFrame::DIRECTION_MCU_TO_LINUX {
            "mcu_to_linux"
        } else {
            "linux_to_mcu"
        };
        match g.counts.raw_frames.get_mut(key) {
            Some(n) => *n += 1,
            None => {
                g.counts.raw_frames.insert(key.into(), 1);
            }
        }
        if self.tx.is_none() {
            return;
        }
        // The frame header's time, through the same codec (stateless for one whole frame).
        g.raw_decoder.reset();
        let t_us = g
            .raw_decoder
            .push_slice(&data)
            .filter_map(|r| r.ok())
            .last()
            .map_or(0, |f| f.header.t_us);
        let m = LinkFrame {
            header: Header {
                stamp: Time::from_nanos(t_ns),
                frame_id: String::new(),
            },
            direction,
            t_us,
            data,
        };
        let topic = self.topic_of(topics::LINK_RAW_FRAMES.name);
        self.record(g, &topic, topics::LINK_RAW_FRAMES.qos, &m, t_ns);
    }

    /// The vehicle's armed state (for `record_on_arm`); only changes are forwarded.
    pub fn armed(&self, armed: bool) {
        let mut g = self.inner.lock().unwrap();
        if g.armed != Some(armed) {
            g.armed = Some(armed);
            if let Some(tx) = &self.tx {
                let _ = tx.send(Ev::Armed(armed));
            }
        }
    }

    pub fn counts(&self) -> Counts {
        let g = self.inner.lock().unwrap();
        let mut c = g.counts.clone();
        for e in g.names.values() {
            if e.published > 0 {
                *c.published.entry(e.topic.clone()).or_default() += e.published;
            }
            if e.received > 0 {
                *c.received.entry(e.topic.clone()).or_default() += e.received;
            }
        }
        c
    }

    /// Finish the recording (summary, footer, `PATH.counts.json`); returns the writer's report.
    /// Idempotent; waits at most `timeout` for the writer thread.
    pub fn finish(&self, timeout: Duration) -> Option<RecorderReport> {
        let tx = self.tx.as_ref()?;
        let (rtx, rrx) = mpsc::channel();
        tx.send(Ev::Finish(self.counts(), rtx)).ok()?;
        let r = rrx.recv_timeout(timeout).ok();
        if let Some(th) = self.thread.lock().unwrap().take() {
            if r.is_some() {
                let _ = th.join();
            }
        }
        r
    }
}

/// The sidecar next to the first file.
pub fn counts_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".counts.json");
    PathBuf::from(s)
}

/// `PATH` for index 0, `STEM_i.EXT` after.
pub fn split_path(path: &Path, i: usize) -> PathBuf {
    if i == 0 {
        return path.to_path_buf();
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mcap".into());
    path.with_file_name(format!("{stem}_{i}.{ext}"))
}

/// Any `Write + Seek` file the writer can use.
pub type McapFile = BufWriter<std::fs::File>;

/// Write options shared by the recorder and the benchmark's bare writer.
pub fn write_options(zstd: bool, chunk_bytes: u64) -> mcap::WriteOptions {
    mcap::WriteOptions::new()
        .profile("ros2")
        .library(concat!(
            "fcc-bridge ",
            env!("CARGO_PKG_VERSION"),
            " (mcap 0.26)"
        ))
        .compression(if zstd {
            Some(mcap::Compression::Zstd)
        } else {
            None
        })
        .compression_level(1)
        .chunk_size(Some(chunk_bytes))
        // Build each chunk in memory and write it whole when it is closed: the file never
        // holds a chunk header with the placeholder length (see the module doc).
        .disable_seeking(true)
}

/// One open MCAP file with its channel mapping.
pub struct BagWriter<W: Write + Seek> {
    pub writer: mcap::Writer<W>,
    /// Tap channel id → (MCAP channel id, next sequence number).
    map: Vec<Option<(u16, u32)>>,
    schemas: HashMap<String, u16>,
    pub bytes: u64,
}

impl<W: Write + Seek> BagWriter<W> {
    pub fn new(w: W, zstd: bool, chunk_bytes: u64) -> mcap::McapResult<Self> {
        Ok(BagWriter {
            writer: write_options(zstd, chunk_bytes).create(w)?,
            map: Vec::new(),
            schemas: HashMap::new(),
            bytes: 0,
        })
    }

    fn add_channel(&mut self, id: u16, d: &ChannelDesc) -> mcap::McapResult<u16> {
        let sid = match self.schemas.get(&d.schema_name) {
            Some(s) => *s,
            None => {
                let s = self
                    .writer
                    .add_schema(&d.schema_name, "ros2msg", d.schema.as_bytes())?;
                self.schemas.insert(d.schema_name.clone(), s);
                s
            }
        };
        let mut md = BTreeMap::new();
        md.insert("offered_qos_profiles".to_string(), d.qos.clone());
        let c = self.writer.add_channel(sid, &d.topic, "cdr", &md)?;
        let i = id as usize;
        if self.map.len() <= i {
            self.map.resize(i + 1, None);
        }
        self.map[i] = Some((c, 0));
        Ok(c)
    }

    fn write(&mut self, id: u16, desc: &ChannelDesc, t: u64, data: &[u8]) -> mcap::McapResult<()> {
        if !matches!(self.map.get(id as usize), Some(Some(_))) {
            self.add_channel(id, desc)?;
        }
        let e = self.map[id as usize].as_mut().expect("added");
        let seq = e.1;
        e.1 = e.1.wrapping_add(1);
        self.bytes += data.len() as u64 + 31;
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: e.0,
                sequence: seq,
                log_time: t,
                publish_time: t,
            },
            data,
        )
    }
}

/// An error with its chain of causes, one line: `outer: cause: cause` (a cause whose text the
/// outer message already contains is not repeated).
pub fn err_text(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        let t = c.to_string();
        if !out.contains(&t) {
            out.push_str(": ");
            out.push_str(&t);
        }
        src = c.source();
    }
    out.replace('\n', " ")
}

struct WriterThread {
    opts: RecordOptions,
    channels: Vec<Option<ChannelDesc>>,
    bag: Option<BagWriter<McapFile>>,
    file_index: usize,
    /// Log time (ns) of the open file's first message (for `split_s`).
    file_first_log: Option<u64>,
    last_flush: Instant,
    armed: bool,
    failed: bool,
    report: RecorderReport,
    /// Messages written per channel id (→ `report.recorded` at the end).
    written: Vec<u64>,
    /// Written messages' buffers go back to the tap ([`RECYCLED_BUFFERS`]).
    recycle: Option<mpsc::SyncSender<Vec<u8>>>,
}

impl WriterThread {
    fn new(opts: RecordOptions) -> Self {
        WriterThread {
            opts,
            channels: Vec::new(),
            bag: None,
            file_index: 0,
            file_first_log: None,
            last_flush: Instant::now(),
            armed: false,
            failed: false,
            report: RecorderReport::default(),
            written: Vec::new(),
            recycle: None,
        }
    }

    fn fail(&mut self, what: &str, e: impl std::fmt::Display) {
        // Callers pass `err_text(..)`: the error with its causes (mcap's I/O error hides the
        // OS error, e.g. "No space left on device", in its source).
        if !self.failed {
            let path = self.report.files.last().cloned().unwrap_or_default();
            let msg = format!(
                "recording to {} stopped: {what}: {e} (the bridge keeps running)",
                path.display()
            );
            tracing::error!("{msg}");
            self.report.error = Some(msg);
        }
        self.failed = true;
        // Drop without finishing: the file stays readable up to its last closed chunk.
        if let Some(b) = self.bag.take() {
            drop(b.writer.into_inner());
        }
    }

    fn open(&mut self) {
        if self.failed {
            return;
        }
        let path = split_path(&self.opts.path, self.file_index);
        self.file_index += 1;
        let r = std::fs::File::create(&path)
            .map_err(|e| err_text(&e))
            .and_then(|f| {
                BagWriter::new(
                    BufWriter::with_capacity(1 << 20, f),
                    self.opts.zstd,
                    self.opts.chunk_bytes,
                )
                .map_err(|e| err_text(&e))
            });
        self.report.files.push(path.clone());
        match r {
            Ok(b) => {
                tracing::info!(
                    "recording to {} (chunks closed every {} ms or {} MiB{})",
                    path.display(),
                    self.opts.chunk_interval.as_millis(),
                    self.opts.chunk_bytes >> 20,
                    if self.opts.zstd { ", zstd" } else { "" }
                );
                self.bag = Some(b);
                self.file_first_log = None;
                self.last_flush = Instant::now();
            }
            Err(e) => self.fail("create", e),
        }
    }

    fn close(&mut self) {
        if let Some(mut b) = self.bag.take() {
            match b.writer.finish() {
                Ok(_) => {
                    let mut inner = b.writer.into_inner();
                    if let Err(e) = inner.flush() {
                        self.fail("flush", err_text(&e));
                    }
                }
                Err(e) => self.fail("finish", err_text(&e)),
            }
        }
    }

    fn on_msg(&mut self, ch: u16, t: u64, data: &[u8]) {
        if !matches!(self.channels.get(ch as usize), Some(Some(_)))
            || self.failed
            || (self.opts.on_arm && !self.armed)
        {
            self.report.not_recorded += 1;
            return;
        }
        // Split on log time (before writing: the message that reaches the limit opens the
        // next file, so each file spans < split_s of log time).
        if let (Some(s), Some(first), true) =
            (self.opts.split_s, self.file_first_log, self.bag.is_some())
        {
            if t >= first.saturating_add((s * 1e9) as u64) {
                self.close();
                self.open();
            }
        }
        if self.bag.is_none() {
            self.open();
        }
        // Log time 0 = no time yet (`clock_source:=mcu` before the MCU's first message).
        if self.file_first_log.is_none() && self.bag.is_some() && t > 0 {
            self.file_first_log = Some(t);
        }
        let (Some(bag), Some(Some(desc))) = (self.bag.as_mut(), self.channels.get(ch as usize))
        else {
            self.report.not_recorded += 1;
            return;
        };
        if let Err(e) = bag.write(ch, desc, t, data) {
            self.report.not_recorded += 1;
            self.fail("write", err_text(&e));
            return;
        }
        let i = ch as usize;
        if self.written.len() <= i {
            self.written.resize(i + 1, 0);
        }
        self.written[i] += 1;
        let split_bytes = self
            .opts
            .split_mb
            .is_some_and(|mb| bag.bytes as f64 >= mb * 1e6);
        if split_bytes {
            self.close();
            self.open();
        }
    }

    fn maybe_flush(&mut self) {
        if self.last_flush.elapsed() >= self.opts.chunk_interval {
            self.last_flush = Instant::now();
            if let Some(b) = self.bag.as_mut() {
                if let Err(e) = b.writer.flush() {
                    self.fail("write", err_text(&e));
                }
            }
        }
    }

    fn run(mut self, rx: mpsc::Receiver<Ev>) {
        loop {
            let wait = self
                .opts
                .chunk_interval
                .saturating_sub(self.last_flush.elapsed())
                .max(Duration::from_millis(1));
            match rx.recv_timeout(wait) {
                Ok(ev) => {
                    if self.handle(ev, &rx) {
                        return;
                    }
                    // Batch what is queued before looking at the clock again.
                    for _ in 0..4096 {
                        match rx.try_recv() {
                            Ok(ev) => {
                                if self.handle(ev, &rx) {
                                    return;
                                }
                            }
                            Err(_) => break,
                        }
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    self.close();
                    return;
                }
            }
            self.maybe_flush();
        }
    }

    fn add_desc(&mut self, id: u16, d: ChannelDesc) {
        let i = id as usize;
        if self.channels.len() <= i {
            self.channels.resize_with(i + 1, || None);
        }
        self.channels[i] = Some(d);
    }

    /// One event; true when finished.
    fn handle(&mut self, ev: Ev, rx: &mpsc::Receiver<Ev>) -> bool {
        match ev {
            Ev::Channel(id, d) => self.add_desc(id, d),
            Ev::Msg { ch, t, data } => {
                self.on_msg(ch, t, &data);
                if let Some(r) = &self.recycle {
                    let _ = r.try_send(data);
                }
            }
            Ev::Armed(a) => {
                self.armed = a;
                if self.opts.on_arm {
                    if a {
                        if self.bag.is_none() {
                            self.open();
                        }
                    } else {
                        self.close();
                    }
                }
            }
            Ev::Finish(counts, reply) => {
                // Whatever is still queued was sent before Finish: drain it first.
                while let Ok(ev) = rx.try_recv() {
                    match ev {
                        Ev::Msg { ch, t, data } => self.on_msg(ch, t, &data),
                        Ev::Channel(id, d) => self.add_desc(id, d),
                        _ => {}
                    }
                }
                self.close();
                for (i, n) in self.written.iter().enumerate() {
                    if let Some(Some(c)) = self.channels.get(i) {
                        *self.report.recorded.entry(c.topic.clone()).or_default() += n;
                    }
                }
                let side = counts_path(&self.opts.path);
                let doc = serde_json::json!({
                    "bridge": counts,
                    "recorder": self.report,
                    "raw_frames_topic": self.channels.iter().flatten()
                        .find(|c| c.schema_name == "fcc_msgs/msg/LinkFrame").map(|c| c.topic.clone()),
                });
                if let Err(e) = std::fs::write(
                    &side,
                    serde_json::to_string_pretty(&doc).unwrap_or_default(),
                ) {
                    tracing::warn!("{}: {e}", side.display());
                }
                let _ = reply.send(self.report.clone());
                return true;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fcc_msgs::ros::Imu;

    #[test]
    fn cdr_has_encapsulation_header_and_roundtrips() {
        let m = Imu::default();
        let b = cdr_bytes(&m);
        assert_eq!(&b[..4], &[0, 1, 0, 0]);
        let back: Imu = from_cdr(&b).unwrap();
        assert_eq!(back, m);
        let f = LinkFrame {
            direction: 1,
            t_us: 7,
            data: vec![1, 2, 0],
            ..Default::default()
        };
        assert_eq!(from_cdr::<LinkFrame>(&cdr_bytes(&f)).unwrap(), f);
    }

    #[test]
    fn error_text_names_the_os_cause() {
        let io = std::io::Error::from_raw_os_error(28);
        let e = mcap::McapError::from(io);
        let t = err_text(&e);
        assert!(t.contains("No space left on device"), "{t}");
        assert!(!t.contains('\n'));
    }

    #[test]
    fn remapped_topics_are_counted_where_they_went_out() {
        let remaps = vec![
            ("/tf".to_string(), "tf".to_string()),
            ("battery".to_string(), "power/battery".to_string()),
        ];
        let tap = Tap::counting("/uav1").with_remaps(&remaps);
        assert_eq!(tap.topic_of("/tf"), "/uav1/tf");
        assert_eq!(tap.topic_of("battery"), "/uav1/power/battery");
        assert_eq!(tap.topic_of("/clock"), "/clock");
        assert_eq!(tap.topic_of("status"), "/uav1/status");
    }

    /// Log-time spans (ns) of each file of a recording, by reading them back.
    fn spans(files: &[PathBuf]) -> Vec<(u64, u64, usize)> {
        files
            .iter()
            .map(|f| {
                let buf = std::fs::read(f).unwrap();
                let ts: Vec<u64> = mcap::MessageStream::new(&buf)
                    .unwrap()
                    .map(|m| m.unwrap().log_time)
                    .collect();
                (
                    *ts.iter().min().unwrap(),
                    *ts.iter().max().unwrap(),
                    ts.len(),
                )
            })
            .collect()
    }

    #[test]
    fn split_s_follows_log_time_not_the_writer_clock() {
        let dir = std::env::temp_dir().join(format!("fcc-split-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut o = RecordOptions::new(dir.join("s.mcap"));
        o.split_s = Some(2.0);
        let tap = Tap::recording("/fcc", o).unwrap();
        // 7 s of log time at 100 Hz, queued in no time at all (the writer sees it all at once:
        // a wall-clock split would give one file), with a little disorder between two topics.
        let t0 = 1_700_000_000_000_000_000i64;
        for i in 0..700i64 {
            let t = t0 + i * 10_000_000;
            tap.published("imu/data_raw", QosInfo::TELEMETRY, &Imu::default(), t);
            tap.published(
                "state/imu",
                QosInfo::TELEMETRY,
                &Imu::default(),
                t - 1_000_000,
            );
        }
        let r = tap.finish(Duration::from_secs(10)).unwrap();
        assert_eq!(r.files.len(), 4, "{:?}", r.files);
        let sp = spans(&r.files);
        let total: usize = sp.iter().map(|s| s.2).sum();
        assert_eq!(total, 1400);
        for (i, (a, b, _)) in sp.iter().enumerate() {
            // < 2 s, plus the 1 ms disorder at most.
            assert!(b - a < 2_001_000_000, "file {i} spans {} ns", b - a);
            if i > 0 {
                // A split happens when the log time reaches first + 2 s, not before.
                assert!(
                    *a + 1_000_000 >= sp[i - 1].0 + 2_000_000_000,
                    "file {i} starts early"
                );
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn names_and_paths() {
        assert_eq!(full_topic("/fcc", "imu/data_raw"), "/fcc/imu/data_raw");
        assert_eq!(full_topic("/fcc/", "/tf"), "/tf");
        assert_eq!(
            split_path(Path::new("/x/b.mcap"), 0),
            PathBuf::from("/x/b.mcap")
        );
        assert_eq!(
            split_path(Path::new("/x/b.mcap"), 2),
            PathBuf::from("/x/b_2.mcap")
        );
        assert!(QosInfo::TELEMETRY
            .yaml()
            .starts_with("- history: 1\n  depth: 10\n  reliability: 1\n  durability: 2\n"));
    }
}
