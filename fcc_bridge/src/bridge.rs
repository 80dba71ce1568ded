//! Serial IO and DDS: the only place with tokio, tokio-serial and ros2-client.

use crate::convert::{self, Config, SetpointLimits};
use crate::diag::{self, RateMeter};
use crate::now_ns;
use crate::ros_types::*;
use crate::state::{ClockSource, Fatal, Handshake, LinkState, Out};
use fcc_msgs as link;
use futures::StreamExt;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Context, Name, Node, NodeName, NodeOptions, Publisher, QosProfile};
use std::net::Ipv4Addr;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::sync::mpsc;
use tokio_serial::SerialPortBuilderExt;

/// Everything the bridge needs to run.
#[derive(Clone, Debug)]
pub struct Options {
    pub device: String,
    pub baud: u32,
    pub namespace: String,
    pub node_name: String,
    pub domain_id: u16,
    pub localhost_only: bool,
    pub cfg: Config,
    pub limits: SetpointLimits,
    pub clock: ClockSource,
    /// Time-sync ping period after the first fast burst.
    pub ping_period: Duration,
    /// Resend `HelloRequest` this often until the MCU answers.
    pub hello_period: Duration,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            device: String::new(),
            baud: 921_600,
            namespace: "/fcc".into(),
            node_name: "fcc_bridge".into(),
            domain_id: 0,
            localhost_only: true,
            cfg: Config::default(),
            limits: SetpointLimits::default(),
            clock: ClockSource::Sync,
            ping_period: Duration::from_secs(1),
            hello_period: Duration::from_millis(500),
        }
    }
}

/// Why the bridge stopped.
#[derive(Debug)]
pub enum BridgeError {
    /// The MCU speaks another protocol version or schema (exit code 2).
    Handshake(link::HandshakeError),
    /// DDS / ROS setup failed.
    Ros(String),
}

impl std::fmt::Display for BridgeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BridgeError::Handshake(e) => write!(f, "{e}"),
            BridgeError::Ros(e) => write!(f, "ROS 2 setup failed: {e}"),
        }
    }
}

fn ros_err(e: impl std::fmt::Debug) -> BridgeError {
    BridgeError::Ros(format!("{e:?}"))
}

/// Publishers of every topic.
pub struct Publishers {
    imu_raw: Publisher<Imu>,
    mag: Publisher<MagneticField>,
    baro: Publisher<FluidPressure>,
    gps_fix: Publisher<NavSatFix>,
    laser: Publisher<Range>,
    sonar: Publisher<Range>,
    battery: Publisher<BatteryState>,
    odom: Publisher<Odometry>,
    state_imu: Publisher<Imu>,
    tf: Publisher<TFMessage>,
    tf_static: Publisher<TFMessage>,
    altitude: Publisher<Altitude>,
    ground: Publisher<Range>,
    status: Publisher<Status>,
    diagnostics: Publisher<DiagnosticArray>,
    clock: Option<Publisher<Clock>>,
}

/// Reliable, volatile, keep-last: matches reliable and best-effort readers. A full send
/// window fails at once (counted) instead of stalling the serial loop.
fn telemetry_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

fn publisher<T: RosMsg>(
    node: &mut Node,
    name: &str,
    qos: &QosProfile,
) -> Result<Publisher<T>, BridgeError> {
    let topic = node
        .create_topic(&Name::parse(name).map_err(ros_err)?, T::type_name(), qos)
        .map_err(ros_err)?;
    node.create_publisher::<T>(&topic, None).map_err(ros_err)
}

impl Publishers {
    fn new(node: &mut Node, clock: ClockSource) -> Result<Self, BridgeError> {
        let q = telemetry_qos(10);
        Ok(Publishers {
            imu_raw: publisher(node, "imu/data_raw", &q)?,
            mag: publisher(node, "mag", &q)?,
            baro: publisher(node, "baro", &q)?,
            gps_fix: publisher(node, "gps/fix", &q)?,
            laser: publisher(node, "range/laser", &q)?,
            sonar: publisher(node, "range/sonar", &q)?,
            battery: publisher(node, "battery", &q)?,
            odom: publisher(node, "state/odom", &q)?,
            state_imu: publisher(node, "state/imu", &q)?,
            tf: publisher(node, "/tf", &telemetry_qos(100))?,
            tf_static: publisher(
                node,
                "/tf_static",
                &QosProfile::publisher_default()
                    .reliability_reliable(WhenFull::Fail)
                    .durability(Durability::TransientLocal)
                    .history(History::KeepLast { depth: 1 }),
            )?,
            altitude: publisher(node, "altitude", &q)?,
            ground: publisher(node, "altitude/ground", &q)?,
            status: publisher(node, "status", &q)?,
            diagnostics: publisher(node, "/diagnostics", &q)?,
            clock: if clock == ClockSource::Mcu {
                Some(publisher(node, "/clock", &telemetry_qos(1))?)
            } else {
                None
            },
        })
    }

    /// Publish; returns false if the write failed.
    fn publish(&self, o: Out) -> bool {
        fn p<T: serde::Serialize>(p: &Publisher<T>, m: T) -> bool {
            p.publish(m).is_ok()
        }
        match o {
            Out::ImuRaw(m) => p(&self.imu_raw, m),
            Out::Mag(m) => p(&self.mag, m),
            Out::Baro(m) => p(&self.baro, m),
            Out::GpsFix(m) => p(&self.gps_fix, m),
            Out::Laser(m) => p(&self.laser, m),
            Out::Sonar(m) => p(&self.sonar, m),
            Out::Battery(m) => p(&self.battery, m),
            Out::Odom(m) => p(&self.odom, m),
            Out::StateImu(m) => p(&self.state_imu, m),
            Out::Tf(m) => p(&self.tf, m),
            Out::Altitude(m) => p(&self.altitude, m),
            Out::Ground(m) => p(&self.ground, m),
            Out::Status(m) => p(&self.status, m),
            Out::Clock(m) => self.clock.as_ref().is_none_or(|c| p(c, m)),
        }
    }
}

/// What the subscriptions hand to the link task.
#[derive(Debug)]
enum Inbound {
    Setpoint(TwistStamped),
    Arm(Bool),
    Mode(StringMsg),
}

fn subscribe<T: RosMsg + Sync>(
    node: &mut Node,
    name: &str,
    tx: mpsc::Sender<Inbound>,
    wrap: fn(T) -> Inbound,
) -> Result<(), BridgeError> {
    // Best-effort reader: matches both reliable (`ros2 topic pub`) and best-effort writers.
    let qos = QosProfile::subscription_default().history(History::KeepLast { depth: 10 });
    let topic = node
        .create_topic(&Name::parse(name).map_err(ros_err)?, T::type_name(), &qos)
        .map_err(ros_err)?;
    let sub = node
        .create_subscription::<T>(&topic, None)
        .map_err(ros_err)?;
    let name = name.to_string();
    tokio::spawn(async move {
        let stream = sub.async_stream();
        tokio::pin!(stream);
        while let Some(r) = stream.next().await {
            match r {
                Ok((m, _info)) => {
                    if tx.send(wrap(m)).await.is_err() {
                        break;
                    }
                }
                Err(e) => tracing::warn!("{name}: read error {e:?}"),
            }
        }
    });
    Ok(())
}

/// Build the DDS participant: loopback only unless disabled.
fn context(opts: &Options) -> Result<Context, BridgeError> {
    let mut b = rustdds::DomainParticipantBuilder::new(opts.domain_id);
    if opts.localhost_only {
        b = b.with_only_networks([Ipv4Addr::LOCALHOST]);
    }
    let dp = b.build().map_err(ros_err)?;
    Context::from_domain_participant(dp).map_err(ros_err)
}

/// Run the bridge until a fatal error (the serial device is retried forever).
pub async fn run(opts: Options) -> Result<(), BridgeError> {
    let ctx = context(&opts)?;
    let mut node = ctx
        .new_node(
            NodeName::new(&opts.namespace, &opts.node_name).map_err(ros_err)?,
            NodeOptions::new().enable_rosout(true),
        )
        .map_err(ros_err)?;
    tokio::spawn(node.spinner().map_err(ros_err)?.spin());
    let pubs = Publishers::new(&mut node, opts.clock)?;
    let (tx, mut rx) = mpsc::channel::<Inbound>(64);
    subscribe::<TwistStamped>(
        &mut node,
        "setpoint/velocity",
        tx.clone(),
        Inbound::Setpoint,
    )?;
    subscribe::<Bool>(&mut node, "cmd/arm", tx.clone(), Inbound::Arm)?;
    subscribe::<StringMsg>(&mut node, "cmd/mode", tx, Inbound::Mode)?;
    tracing::info!(
        "node {}/{} on DDS domain {} ({}), device {} at {} baud",
        opts.namespace.trim_end_matches('/'),
        opts.node_name,
        opts.domain_id,
        if opts.localhost_only {
            "loopback only"
        } else {
            "all interfaces"
        },
        opts.device,
        opts.baud
    );

    let mut st = LinkState::new(opts.cfg.clone(), opts.limits, opts.clock);
    let _ = pubs.tf_static.publish(convert::static_transforms(
        Time::from_nanos(now_ns()),
        &st.cfg,
    ));
    let mut rates = RateMeter::default();
    let mut first = true;
    let mut logged_open_error = false;
    loop {
        let port = tokio_serial::new(&opts.device, opts.baud).open_native_async();
        let mut port = match port {
            Ok(p) => p,
            Err(e) => {
                if !logged_open_error {
                    tracing::warn!("cannot open {}: {e}; retrying every 0.5 s", opts.device);
                    logged_open_error = true;
                }
                drain_inbound(&mut rx, &mut st);
                publish_diag(&pubs, &st, &mut rates, &opts.device, false);
                tokio::time::sleep(Duration::from_millis(500)).await;
                continue;
            }
        };
        logged_open_error = false;
        let _ = port.set_exclusive(false);
        if !first {
            st.reconnect();
        }
        first = false;
        tracing::info!("opened {}", opts.device);
        match session(port, &opts, &mut st, &pubs, &mut rx, &mut rates).await {
            Ok(reason) => tracing::warn!("link to {} lost ({reason}); reopening", opts.device),
            Err(Fatal::Handshake(e)) => return Err(BridgeError::Handshake(e)),
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
}

/// While disconnected: refuse (and count) what arrives.
fn drain_inbound(rx: &mut mpsc::Receiver<Inbound>, st: &mut LinkState) {
    while let Ok(m) = rx.try_recv() {
        handle_inbound(m, st);
    }
}

fn handle_inbound(m: Inbound, st: &mut LinkState) -> Option<link::Message> {
    match m {
        Inbound::Setpoint(t) => st.on_setpoint(&t, now_ns()),
        Inbound::Arm(b) => st.on_command(
            Some(convert::arm_command(&b)),
            if b.data { "arm" } else { "disarm" },
        ),
        Inbound::Mode(s) => st.on_command(convert::mode_command(&s), &s.data),
    }
}

fn publish_diag(
    pubs: &Publishers,
    st: &LinkState,
    rates: &mut RateMeter,
    device: &str,
    connected: bool,
) {
    let now = now_ns();
    rates.update(st, now);
    let stamp = Time::from_nanos(st.ros_now_ns(now));
    let _ = pubs
        .diagnostics
        .publish(diag::diagnostics(st, rates, device, connected, stamp));
}

/// One connection: returns why it ended (IO), or a fatal handshake error.
async fn session(
    port: tokio_serial::SerialStream,
    opts: &Options,
    st: &mut LinkState,
    pubs: &Publishers,
    rx: &mut mpsc::Receiver<Inbound>,
    rates: &mut RateMeter,
) -> Result<String, Fatal> {
    let (mut rd, mut wr) = tokio::io::split(port);
    // A 0x00 first flushes any half frame at the MCU, then ask for its Hello.
    let mut hello = vec![0u8];
    hello.extend(st.encode(
        &link::Message::HelloRequest(link::HelloRequest::ours()),
        now_ns(),
    ));
    if let Err(e) = wr.write_all(&hello).await {
        return Ok(format!("write: {e}"));
    }
    let mut last_hello = tokio::time::Instant::now();
    let mut pings_sent = 0u32;
    let mut last_ping = tokio::time::Instant::now() - Duration::from_secs(10);
    let mut last_diag = tokio::time::Instant::now();
    let mut warned_no_hello = false;
    let started = tokio::time::Instant::now();
    let mut tick = tokio::time::interval(Duration::from_millis(50));
    let mut buf = vec![0u8; 4096];
    loop {
        let mut to_send: Vec<u8> = Vec::new();
        tokio::select! {
            r = rd.read(&mut buf) => {
                let n = match r {
                    Ok(0) => return Ok("end of file".into()),
                    Ok(n) => n,
                    Err(e) => return Ok(format!("read: {e}")),
                };
                let outs = st.on_bytes(&buf[..n], now_ns())?;
                for o in outs {
                    if !pubs.publish(o) {
                        st.counters.publish_errors += 1;
                    }
                }
            }
            Some(m) = rx.recv() => {
                if let Some(msg) = handle_inbound(m, st) {
                    to_send.extend(st.encode(&msg, now_ns()));
                }
            }
            _ = tick.tick() => {
                let now = tokio::time::Instant::now();
                if st.handshake == Handshake::Waiting {
                    if now - last_hello >= opts.hello_period {
                        to_send.extend(st.encode(&link::Message::HelloRequest(link::HelloRequest::ours()), now_ns()));
                        last_hello = now;
                    }
                    if !warned_no_hello && now - started > Duration::from_secs(3) {
                        tracing::warn!("no Hello from the MCU on {} yet (wrong device or baud?)", opts.device);
                        warned_no_hello = true;
                    }
                } else {
                    // Fast burst of 10 pings at 100 ms, then every ping_period.
                    let period = if pings_sent < 10 { Duration::from_millis(100) } else { opts.ping_period };
                    if now - last_ping >= period {
                        let ping = link::TimeSyncPing { linux_time_ns: now_ns() as u64 };
                        to_send.extend(st.encode(&link::Message::TimeSyncPing(ping), now_ns()));
                        pings_sent += 1;
                        last_ping = now;
                    }
                }
                if now - last_diag >= Duration::from_secs(1) {
                    publish_diag(pubs, st, rates, &opts.device, true);
                    last_diag = now;
                }
            }
        }
        if !to_send.is_empty() {
            if let Err(e) = wr.write_all(&to_send).await {
                return Ok(format!("write: {e}"));
            }
        }
    }
}
