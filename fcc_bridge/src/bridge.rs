//! Serial IO and DDS: the only place with tokio, tokio-serial and ros2-client.

use crate::bounded;
use crate::convert::{self, Config, SetpointLimits};
use crate::diag::{self, RateMeter};
use crate::mcu_params::{self, MCU_PARAMS};
use crate::record::Tap;
use crate::ros_api::{self, LinkRequest, ParamShared};
use crate::state::{ClockSource, Fatal, Handshake, LinkState, Out};
use fcc_msgs as link;
use fcc_msgs::ros::*;
use fcc_ros::now_ns;
use fcc_ros::params;
use fcc_ros::rmw::{Pub, Rmw, RosContext, RosNode, Sub};
use fcc_ros::startup::{self, Step};
use fcc_ros::topics::{self, Topic};
use futures::StreamExt;
use ros2_client::dds::Context;
use ros2_client::parameters::ParameterValue;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Name, NodeName, NodeOptions, QosProfile};
use std::collections::BTreeMap;
use std::sync::atomic::Ordering;
use std::sync::Arc;
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
    /// DDS or Zenoh (`RMW_IMPLEMENTATION`, [`fcc_ros::rmw`]).
    pub rmw: Rmw,
    pub localhost_only: bool,
    /// The checked SROS2 enclave directory when security is on (`fcc_ros::security`).
    pub enclave_dir: Option<std::path::PathBuf>,
    pub cfg: Config,
    pub limits: SetpointLimits,
    pub clock: ClockSource,
    /// Time-sync ping period after the first fast burst.
    pub ping_period: Duration,
    /// Resend `HelloRequest` this often until the MCU answers.
    pub hello_period: Duration,
    /// `-r from:=to` topic/service remaps.
    pub remaps: Vec<(String, String)>,
    /// MCU parameters given at start-up (`-p limits.max_tilt_deg:=30`), sent after the handshake.
    pub mcu_params: BTreeMap<String, f64>,
    /// `use_sim_time` (ROS time from `/clock`; with `clock_source:=mcu` the bridge is the clock).
    pub use_sim_time: bool,
    /// The `record` parameter as given (read-only ROS parameter).
    pub record: String,
}

impl Options {
    /// A topic or service name after the remaps.
    pub fn name(&self, n: &str) -> String {
        params::remap(&self.remaps, &self.namespace, n)
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            device: String::new(),
            baud: 921_600,
            namespace: "/fcc".into(),
            node_name: "fcc_bridge".into(),
            domain_id: 0,
            rmw: Rmw::Dds,
            localhost_only: true,
            enclave_dir: None,
            cfg: Config::default(),
            limits: SetpointLimits::default(),
            clock: ClockSource::Sync,
            ping_period: Duration::from_secs(1),
            hello_period: Duration::from_millis(500),
            remaps: Vec::new(),
            mcu_params: BTreeMap::new(),
            use_sim_time: false,
            record: String::new(),
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
    /// The DDS set-up did not finish in time (see [`start_dds`]).
    DdsStalled(String),
}

impl std::fmt::Display for BridgeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BridgeError::Handshake(e) => write!(f, "{e}"),
            BridgeError::Ros(e) => write!(f, "ROS 2 setup failed: {e}"),
            BridgeError::DdsStalled(e) => write!(f, "{e}"),
        }
    }
}

fn ros_err(e: impl std::fmt::Debug) -> BridgeError {
    BridgeError::Ros(format!("{e:?}"))
}

/// Publishers of every topic.
pub struct Publishers {
    imu_raw: Pub<Imu>,
    mag: Pub<MagneticField>,
    baro: Pub<FluidPressure>,
    gps_fix: Pub<NavSatFix>,
    laser: Pub<Range>,
    sonar: Pub<Range>,
    battery: Pub<BatteryState>,
    odom: Pub<Odometry>,
    state_imu: Pub<Imu>,
    tf: Pub<TFMessage>,
    tf_static: Pub<TFMessage>,
    altitude: Pub<Altitude>,
    ground: Pub<Range>,
    status: Pub<Status>,
    accel_observer: Pub<AccelStamped>,
    accel_measured: Pub<AccelStamped>,
    diagnostics: Pub<DiagnosticArray>,
    home: Pub<NavSatFix>,
    clock: Option<Pub<Clock>>,
    /// DDS Security's refusals, for `/diagnostics` (with security on; [`setup_dds`]).
    security: Option<fcc_ros::security_events::SharedSecurityCounts>,
}

/// A publisher for a topic of the table, under the node's namespace and remaps.
fn publisher<T: RosMsg>(
    node: &mut RosNode,
    o: &Options,
    topic: &Topic<T>,
) -> Result<Pub<T>, BridgeError> {
    node.publisher_info(&o.name(topic.name), topic.qos)
        .map_err(BridgeError::Ros)
}

impl Publishers {
    fn new(node: &mut RosNode, o: &Options) -> Result<Self, BridgeError> {
        Ok(Publishers {
            imu_raw: publisher(node, o, &topics::IMU_RAW)?,
            mag: publisher(node, o, &topics::MAG)?,
            baro: publisher(node, o, &topics::BARO)?,
            gps_fix: publisher(node, o, &topics::GPS_FIX)?,
            laser: publisher(node, o, &topics::LASER)?,
            sonar: publisher(node, o, &topics::SONAR)?,
            battery: publisher(node, o, &topics::BATTERY)?,
            odom: publisher(node, o, &topics::ODOM)?,
            state_imu: publisher(node, o, &topics::STATE_IMU)?,
            tf: publisher(node, o, &topics::TF)?,
            tf_static: publisher(node, o, &topics::TF_STATIC)?,
            altitude: publisher(node, o, &topics::ALTITUDE)?,
            ground: publisher(node, o, &topics::GROUND)?,
            status: publisher(node, o, &topics::STATUS)?,
            accel_observer: publisher(node, o, &topics::ACCEL_OBSERVER)?,
            accel_measured: publisher(node, o, &topics::ACCEL_MEASURED)?,
            diagnostics: publisher(node, o, &topics::DIAGNOSTICS)?,
            home: publisher(node, o, &topics::HOME)?,
            clock: if o.clock == ClockSource::Mcu {
                Some(publisher(node, o, &topics::CLOCK)?)
            } else {
                None
            },
            security: None,
        })
    }

    /// Publish (and count/record at ROS time `t_ns`); returns false if the write failed.
    fn publish(&self, o: Out, tap: &Tap, t_ns: i64) -> bool {
        macro_rules! pb {
            ($pb:expr, $topic:expr, $m:expr) => {{
                tap.published_on(&$topic, &$m, t_ns);
                $pb.publish($m).is_ok()
            }};
        }
        match o {
            Out::ImuRaw(m) => pb!(self.imu_raw, topics::IMU_RAW, m),
            Out::Mag(m) => pb!(self.mag, topics::MAG, m),
            Out::Baro(m) => pb!(self.baro, topics::BARO, m),
            Out::GpsFix(m) => pb!(self.gps_fix, topics::GPS_FIX, m),
            Out::Laser(m) => pb!(self.laser, topics::LASER, m),
            Out::Sonar(m) => pb!(self.sonar, topics::SONAR, m),
            Out::Battery(m) => pb!(self.battery, topics::BATTERY, m),
            Out::Odom(m) => pb!(self.odom, topics::ODOM, m),
            Out::StateImu(m) => pb!(self.state_imu, topics::STATE_IMU, m),
            Out::Tf(m) => pb!(self.tf, topics::TF, m),
            Out::TfStatic(m) => pb!(self.tf_static, topics::TF_STATIC, m),
            Out::Altitude(m) => pb!(self.altitude, topics::ALTITUDE, m),
            Out::Ground(m) => pb!(self.ground, topics::GROUND, m),
            Out::Status(m) => {
                tap.armed(m.armed);
                pb!(self.status, topics::STATUS, m)
            }
            Out::AccelObserver(m) => pb!(self.accel_observer, topics::ACCEL_OBSERVER, m),
            Out::AccelMeasured(m) => pb!(self.accel_measured, topics::ACCEL_MEASURED, m),
            Out::Home(m) => pb!(self.home, topics::HOME, m),
            Out::Clock(m) => match &self.clock {
                Some(c) => pb!(c, topics::CLOCK, m),
                None => true,
            },
        }
    }
}

/// Log time of a recorded message: ROS time now (in `clock_source:=mcu`, 0 until the first
/// MCU time, as sim time before the first `/clock`).
fn rec_time(st: &LinkState) -> i64 {
    if st.clock == ClockSource::Mcu && st.last_mcu_us.is_none() {
        0
    } else {
        st.ros_now_ns(now_ns())
    }
}

/// What the subscriptions hand to the link task.
#[derive(Debug)]
enum Inbound {
    Setpoint(TwistStamped),
    /// `setpoint/heading`: kept for the velocity setpoints that follow.
    Heading(QuaternionStamped),
    Arm(Bool),
    Mode(StringMsg),
    /// `cmd/kill`: the emergency motor stop, confirmed by its text.
    Kill(StringMsg),
    Clock(Clock),
}

impl Inbound {
    /// Cut over-long strings (the setpoint's `frame_id`, the mode text) to their limits before
    /// the message is queued, recorded or used; which one was too long, if any.
    fn bound(&mut self) -> Option<bounded::Oversize> {
        let (s, field, max) = match self {
            Inbound::Setpoint(t) => (&mut t.header.frame_id, "frame_id", bounded::MAX_FRAME_ID),
            Inbound::Heading(q) => (&mut q.header.frame_id, "frame_id", bounded::MAX_FRAME_ID),
            Inbound::Mode(m) => (&mut m.data, "cmd/mode text", bounded::MAX_MODE),
            Inbound::Kill(m) => (&mut m.data, "cmd/kill text", bounded::MAX_MODE),
            // No strings in std_msgs/Bool and rosgraph_msgs/Clock.
            Inbound::Arm(_) | Inbound::Clock(_) => return None,
        };
        bounded::cap_string(s, max).map(|len| bounded::Oversize { field, len, max })
    }
}

/// A message from a subscription, with the string that was cut on arrival (if any).
type InboundMsg = (Inbound, Option<bounded::Oversize>);

/// Samples of an incoming topic that rustdds keeps in its topic cache. Without a resource
/// limit it keeps 64 per topic whatever the history depth: 64 MB per topic when a peer sends
/// 1 MB messages. The topic is created on the participant with this limit (ros2-client's
/// `QosProfile` has no resource limits, and rustdds only ever raises a topic's limit).
const INBOUND_KEEP: i32 = 4;

/// Subscribe to a read topic of the table (under the node's namespace and remaps); each message
/// goes to `tx` wrapped by `wrap`.
fn subscribe<T: RosMsg + Sync>(
    ctx: &RosContext,
    node: &mut RosNode,
    o: &Options,
    topic: &Topic<T>,
    tx: mpsc::Sender<InboundMsg>,
    wrap: fn(T) -> Inbound,
) -> Result<(), BridgeError> {
    let name = o.name(topic.name);
    let sub = match (ctx, &mut *node) {
        (RosContext::Dds(c), RosNode::Dds(n)) => Sub::Dds(dds_reader::<T>(c, n, o, &name)?),
        (_, n) => n
            .subscription::<T>(&name, &inbound_qos())
            .map_err(BridgeError::Ros)?,
    };
    tokio::spawn(async move { forward(sub.stream(), &name, tx, wrap).await });
    Ok(())
}

/// Best-effort keep-last [`INBOUND_KEEP`]: matches both reliable (`ros2 topic pub`) and
/// best-effort writers.
fn inbound_qos() -> QosProfile {
    QosProfile::subscription_default().history(History::KeepLast {
        depth: INBOUND_KEEP as usize,
    })
}

/// The DDS reader of an inbound topic, its cache bounded to [`INBOUND_KEEP`] samples.
fn dds_reader<T: RosMsg>(
    ctx: &Context,
    node: &mut ros2_client::dds::Node,
    o: &Options,
    name: &str,
) -> Result<ros2_client::dds::Subscription<T>, BridgeError> {
    let node_name = &NodeName::new(&o.namespace, &o.node_name).map_err(ros_err)?;
    use rustdds::policy::ResourceLimits;
    let limits = rustdds::QosPolicyBuilder::new()
        .resource_limits(ResourceLimits {
            max_samples: INBOUND_KEEP,
            max_instances: 1,
            max_samples_per_instance: INBOUND_KEEP,
        })
        .build();
    let dds_qos = rustdds::QosPolicies::from(&inbound_qos()).modify_by(&limits);
    let dds_name = Name::parse(name)
        .map_err(ros_err)?
        .to_dds_name("rt", node_name, "");
    let topic = ctx
        .domain_participant()
        .create_topic(
            dds_name,
            T::type_name().dds_msg_type(),
            &dds_qos,
            rustdds::TopicKind::NoKey,
        )
        .map_err(ros_err)?;
    node.create_subscription::<T>(&topic, None).map_err(ros_err)
}

/// Each message of `stream` (an inbound topic) to `tx`, cut to its bounds; read errors logged
/// (rate-limited). Ends when the bridge stops listening.
async fn forward<T: RosMsg>(
    stream: impl futures::Stream<Item = Result<T, String>>,
    name: &str,
    tx: mpsc::Sender<InboundMsg>,
    wrap: fn(T) -> Inbound,
) {
    tokio::pin!(stream);
    let mut warn = bounded::WarnLimiter::default();
    while let Some(r) = stream.next().await {
        match r {
            Ok(m) => {
                let mut m = wrap(m);
                let over = m.bound();
                if tx.send((m, over)).await.is_err() {
                    break;
                }
            }
            Err(e) => {
                let e = bounded::log_value(&e, 4 * bounded::LOG_CHARS);
                crate::warn_limited!(warn, "read_error", now_ns(), "{name}: read error {e}");
            }
        }
    }
}

/// The DDS participant (`fcc_ros::ros_node::context`): loopback only unless disabled.
/// On Zenoh, the session of rmw_zenoh's environment ([`fcc_ros::rmw`]); SROS2 is DDS-only.
fn context(opts: &Options) -> Result<RosContext, BridgeError> {
    let env = fcc_ros::ros_node::DdsEnv {
        domain_id: opts.domain_id,
        localhost_only: opts.localhost_only,
        enclave_dir: opts.enclave_dir.clone(),
    };
    fcc_ros::rmw::context(opts.rmw, env).map_err(BridgeError::Ros)
}

/// The ROS-side requests waiting for the MCU (services, parameter sets) and what the link
/// task needs to answer them.
struct RosSide<'a> {
    node: &'a RosNode,
    rx: mpsc::Receiver<LinkRequest>,
    shared: Arc<ParamShared>,
    cmds: Vec<(
        link::CommandKind,
        tokio::sync::oneshot::Sender<(bool, String)>,
        tokio::time::Instant,
    )>,
    params: BTreeMap<
        u16,
        (
            std::sync::mpsc::Sender<Result<f32, String>>,
            tokio::time::Instant,
        ),
    >,
    /// Start-up values of MCU parameters (sent after each handshake).
    initial: BTreeMap<String, f64>,
}

impl RosSide<'_> {
    /// A request from ROS: what to send to the MCU (if anything).
    fn request(&mut self, r: LinkRequest, st: &mut LinkState) -> Option<link::Message> {
        match r {
            LinkRequest::Command(kind, reply) => {
                match st.on_command(
                    Some(link::Command {
                        command: kind,
                        confirm: 0,
                    }),
                    "service",
                ) {
                    Some(m) => {
                        self.cmds.push((kind, reply, tokio::time::Instant::now()));
                        Some(m)
                    }
                    None => {
                        let _ = reply.send((false, "link to the MCU not connected".into()));
                        None
                    }
                }
            }
            LinkRequest::ParamSet(id, value, reply) => {
                if st.handshake == Handshake::Waiting {
                    let _ = reply.send(Err("link to the MCU not connected".into()));
                    return None;
                }
                self.params.insert(id, (reply, tokio::time::Instant::now()));
                Some(link::Message::ParamSet(link::ParamSet { id, value }))
            }
            LinkRequest::BridgeParam(name, v) => {
                let x = ros_api::as_f64(&v).unwrap_or(f64::NAN);
                match name.as_str() {
                    "ttl_ms" => st.limits.ttl_ms = x as u16,
                    "max_speed_mps" => st.limits.max_speed_mps = x,
                    "max_stamp_age_ms" => st.limits.max_age_ns = (x * 1e6) as i64,
                    "max_stamp_future_ms" => st.limits.max_future_ns = (x * 1e6) as i64,
                    _ => return None,
                }
                tracing::info!("parameter {name} set to {x}");
                None
            }
        }
    }

    /// Answer what the MCU acknowledged.
    fn acks(&mut self, st: &mut LinkState) {
        for m in std::mem::take(&mut st.acks) {
            match m {
                link::Message::CommandAck(a) => {
                    if let Some(i) = self.cmds.iter().position(|(k, _, _)| *k == a.command) {
                        let (_, reply, _) = self.cmds.remove(i);
                        let ok = a.result == link::CommandResult::Accepted;
                        let msg = if ok {
                            format!("MCU accepted {:?}", a.command)
                        } else {
                            format!(
                                "MCU refused {:?}: {}",
                                a.command,
                                convert::reject_name(a.result)
                            )
                        };
                        let _ = reply.send((ok, msg));
                    }
                }
                link::Message::ParamAck(a) => {
                    let name = mcu_params::by_id(a.id).map_or("?", |p| p.name);
                    if a.value.is_finite() {
                        self.shared.mcu_values.lock().unwrap().insert(a.id, a.value);
                    }
                    let accepted = a.result == link::ParamResult::Accepted;
                    if let Some((reply, _)) = self.params.remove(&a.id) {
                        let _ = reply.send(if accepted {
                            tracing::info!("MCU parameter {name} set to {}", a.value);
                            Ok(a.value)
                        } else {
                            Err(format!(
                                "{name}: MCU refused ({:?}); value in use {}",
                                a.result, a.value
                            ))
                        });
                    } else {
                        // Start-up sync (a read, or a -p value): mirror the MCU's value.
                        if let (true, Some(p)) = (a.value.is_finite(), mcu_params::by_id(a.id)) {
                            let v = mcu_params::ros_value(p, a.value as f64);
                            if let Err(e) = self.node.set_parameter(name, v) {
                                tracing::warn!("parameter {name}: {e}");
                            }
                        }
                        if !accepted && a.result != link::ParamResult::NotFinite {
                            tracing::warn!(
                                "MCU refused start-up value of {name} ({:?}); value in use {}",
                                a.result,
                                a.value
                            );
                        }
                    }
                }
                _ => {}
            }
        }
    }

    /// `use_sim_time` set at run time: ros2-client keeps that parameter itself (it calls
    /// neither our validator nor our set action for it), so it is read back here and applied:
    /// with `clock_source:=sync` the stamps follow `/clock` while it is true (the Linux clock
    /// until the first `/clock`, and again when false); with `clock_source:=mcu` the bridge is
    /// the clock and stamps with MCU time either way.
    fn sim_time(&self, st: &mut LinkState) {
        let on = matches!(
            self.node.get_parameter("use_sim_time"),
            Some(ParameterValue::Boolean(true))
        );
        if on == st.sim_time {
            return;
        }
        st.sim_time = on;
        if !on {
            st.sim_offset_ns = None;
        }
        match st.clock {
            ClockSource::Sync => tracing::info!(
                "use_sim_time {on}: stamps now follow {}",
                if on { "/clock" } else { "the Linux clock" }
            ),
            ClockSource::Mcu => tracing::info!(
                "use_sim_time {on}: with clock_source:=mcu the bridge publishes /clock and \
                 stamps with MCU time either way"
            ),
        }
    }

    /// Time out requests the MCU did not answer.
    fn expire(&mut self) {
        let now = tokio::time::Instant::now();
        let mut i = 0;
        while i < self.cmds.len() {
            if now - self.cmds[i].2 > ros_api::ACK_TIMEOUT {
                let (k, reply, _) = self.cmds.remove(i);
                tracing::warn!("MCU did not acknowledge {k:?}");
                let _ = reply.send((
                    false,
                    format!(
                        "MCU did not acknowledge {k:?} within {} ms",
                        ros_api::ACK_TIMEOUT.as_millis()
                    ),
                ));
            } else {
                i += 1;
            }
        }
        self.params
            .retain(|_, (_, t)| now - *t <= ros_api::ACK_TIMEOUT * 2);
    }

    /// After a handshake: read every MCU parameter (NaN set) or send its start-up value.
    fn sync_params(&self, st: &mut LinkState) -> Vec<u8> {
        let mut out = Vec::new();
        for p in MCU_PARAMS {
            let value = self.initial.get(p.name).map_or(f32::NAN, |v| *v as f32);
            out.extend(st.encode(
                &link::Message::ParamSet(link::ParamSet { id: p.id, value }),
                now_ns(),
            ));
        }
        out
    }
}

/// A `std_srvs` service that sends a command to the MCU and answers with its acknowledgement.
fn command_service<Req, Resp>(
    node: &mut RosNode,
    name: &str,
    srv_type: &str,
    tx: mpsc::Sender<LinkRequest>,
    to_cmd: fn(&Req) -> link::CommandKind,
    make: fn(bool, String) -> Resp,
) -> Result<(), BridgeError>
where
    Req: ros2_client::Message + Clone + Send + Sync + 'static,
    Resp: ros2_client::Message + Send + Sync + 'static,
{
    let qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    let server = node
        .server::<Req, Resp>(name, "std_srvs", srv_type, &qos)
        .map_err(BridgeError::Ros)?;
    let name = name.to_string();
    tokio::spawn(async move {
        loop {
            match server.receive().await {
                Ok((id, req)) => {
                    let kind = to_cmd(&req);
                    let (otx, orx) = tokio::sync::oneshot::channel();
                    let (ok, msg) = match tx.send(LinkRequest::Command(kind, otx)).await {
                        Ok(()) => orx.await.unwrap_or((false, "bridge stopping".into())),
                        Err(_) => (false, "bridge stopping".into()),
                    };
                    tracing::info!("service {name}: {kind:?} → {msg}");
                    if let Err(e) = server.respond(id, make(ok, msg)) {
                        tracing::warn!("service {name}: response failed: {e}");
                    }
                }
                Err(e) => {
                    tracing::warn!("service {name}: bad request {e}");
                    // A closed session fails every call: not a busy loop.
                    tokio::time::sleep(Duration::from_millis(100)).await;
                }
            }
        }
    });
    Ok(())
}

/// How long the DDS set-up (participant, node, publishers, subscriptions, services) may take
/// before the bridge gives up on it (normally some tens of ms; `FCC_BRIDGE_DDS_STARTUP_TIMEOUT_MS`
/// overrides it).
pub const DDS_STARTUP_TIMEOUT: Duration = startup::DDS_STARTUP_TIMEOUT;

/// The bridge, for [`startup`] (messages and environment variables).
pub const APP: startup::App = startup::App {
    name: "fcc-bridge",
    env_prefix: "FCC_BRIDGE",
};

/// The DDS side, created by [`setup_dds`].
struct Dds {
    /// Bound first in [`run`], so dropped last: see [`ContextLast`].
    ctx_last: ContextLast,
    node: RosNode,
    pubs: Publishers,
    /// Setpoints and /clock.
    rx: mpsc::Receiver<InboundMsg>,
    /// Commands (cmd/arm, cmd/mode, cmd/kill).
    crx: mpsc::Receiver<InboundMsg>,
    lrx: mpsc::Receiver<LinkRequest>,
    shared: Arc<ParamShared>,
}

/// Holds the DDS context until every entity is gone: dropped after the node (whose drop tells
/// the spinner to stop), it waits (≤ [`SPINNER_EXIT_WAIT`]) for the spinner thread to end — the
/// spinner drops the parameter services' readers and writers as it ends — and only then drops
/// the participant. Dropped the other way round, rustdds logs "Cannot remove Writer/Reader …
/// Disconnected" ERROR lines at every exit where the spinner is late (seen under load).
struct ContextLast {
    ctx: Option<RosContext>,
    spinner: Option<std::thread::JoinHandle<()>>,
    /// Tells the Zenoh parameter thread to end ([`RosNode::spin_parameters`]).
    stop_params: Arc<std::sync::atomic::AtomicBool>,
}

/// How long an exit waits for the spinner thread before dropping the participant anyway.
const SPINNER_EXIT_WAIT: Duration = Duration::from_secs(2);

impl Drop for ContextLast {
    fn drop(&mut self) {
        self.stop_params.store(true, Ordering::Relaxed);
        if let Some(h) = self.spinner.take() {
            let t0 = std::time::Instant::now();
            while !h.is_finished() && t0.elapsed() < SPINNER_EXIT_WAIT {
                std::thread::sleep(Duration::from_millis(5));
            }
            if h.is_finished() {
                let _ = h.join();
            }
        }
        drop(self.ctx.take());
    }
}

/// Create the DDS side on a thread of its own, under a watchdog ([`startup::App::setup_dds`]:
/// rustdds 0.15.1 can deadlock there when several participants start together). Run on the
/// tokio thread, that also starved the signal handling. A set-up that does not finish in
/// [`DDS_STARTUP_TIMEOUT`] is reported as [`BridgeError::DdsStalled`].
async fn start_dds(opts: &Options) -> Result<Dds, BridgeError> {
    let o = opts.clone();
    match APP.setup_dds(move |st| setup_dds(&o, st)).await {
        Ok(r) => r,
        Err(startup::SetupError::Stalled(e)) => Err(BridgeError::DdsStalled(e)),
        Err(startup::SetupError::Thread(e)) => Err(BridgeError::Ros(e)),
    }
}

/// The DDS participant, the node (its spinner and /rosout threads), publishers, subscriptions
/// and services. Blocking: called on the `dds-setup` thread.
fn setup_dds(opts: &Options, step: &Step) -> Result<Dds, BridgeError> {
    step.set(opts.rmw.opening());
    let ctx = context(opts)?;
    let (ltx, lrx) = mpsc::channel::<LinkRequest>(64);
    let shared = Arc::new(ParamShared {
        live: Default::default(),
        mcu_values: Default::default(),
        link: ltx.clone(),
        baud: opts.baud,
    });
    let nopts = node_options(opts, &shared);
    step.set("creating the ROS node");
    let mut node = ctx
        .new_node(&opts.namespace, &opts.node_name, nopts)
        .map_err(BridgeError::Ros)?;
    let stop_params = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let mut spinner = None;
    let mut security = None;
    match &mut node {
        RosNode::Dds(n) => {
            spinner = Some(spawn_spinner(n)?);
            // With security on, every refusal is a WARN (hence /rosout) and counted for
            // /diagnostics.
            security = opts
                .enclave_dir
                .as_ref()
                .and_then(|_| fcc_ros::security_events::watch(n, |line| tracing::warn!("{line}")));
        }
        RosNode::Zenoh(_) => node
            .spin_parameters(stop_params.clone())
            .map_err(BridgeError::Ros)?,
    }
    shared.live.store(true, Ordering::SeqCst);
    spawn_rosout(&node, opts)?;
    step.set("creating the publishers");
    let mut pubs = Publishers::new(&mut node, opts)?;
    pubs.security = security;
    step.set("creating the subscriptions");
    let (rx, crx) = subscribe_all(&ctx, &mut node, opts)?;
    step.set("creating the services");
    create_services(&mut node, opts, &ltx)?;
    drop(ltx);
    tracing::info!(
        "node {}/{} on {} domain {} ({}), device {} at {} baud",
        opts.namespace.trim_end_matches('/'),
        opts.node_name,
        opts.rmw.label(),
        opts.domain_id,
        opts.rmw.reach(opts.localhost_only),
        opts.device,
        opts.baud
    );
    Ok(Dds {
        ctx_last: ContextLast {
            ctx: Some(ctx),
            spinner,
            stop_params,
        },
        node,
        pubs,
        rx,
        crx,
        lrx,
        shared,
    })
}

/// Every parameter the node declares, with its start-up value: bridge, frames, MCU. Each has a
/// descriptor from [`ros_api::describe`] (a test keeps the two in step).
pub fn declared_parameters(opts: &Options) -> Vec<(&'static str, ParameterValue)> {
    use ParameterValue as P;
    let l = &opts.limits;
    let c = &opts.cfg;
    let clock = if opts.clock == ClockSource::Mcu {
        "mcu"
    } else {
        "sync"
    };
    let mut v = vec![
        ("use_sim_time", P::Boolean(opts.use_sim_time)),
        ("ttl_ms", P::Integer(l.ttl_ms as i64)),
        ("max_speed_mps", P::Double(l.max_speed_mps)),
        ("max_stamp_age_ms", P::Double(l.max_age_ns as f64 / 1e6)),
        (
            "max_stamp_future_ms",
            P::Double(l.max_future_ns as f64 / 1e6),
        ),
        ("clock_source", P::String(clock.into())),
        ("localhost_only", P::Boolean(opts.localhost_only)),
        (
            "ping_period_ms",
            P::Integer(opts.ping_period.as_millis() as i64),
        ),
        ("record", P::String(opts.record.clone())),
    ];
    for (k, f) in [
        ("map_frame", &c.map_frame),
        ("odom_frame", &c.odom_frame),
        ("base_frame", &c.base_frame),
        ("imu_frame", &c.imu_frame),
        ("mag_frame", &c.mag_frame),
        ("baro_frame", &c.baro_frame),
        ("gps_frame", &c.gps_frame),
        ("laser_frame", &c.laser_frame),
        ("sonar_frame", &c.sonar_frame),
    ] {
        v.push((k, P::String(f.clone())));
    }
    for p in MCU_PARAMS {
        let x = opts
            .mcu_params
            .get(p.name)
            .copied()
            .unwrap_or(p.default as f64);
        v.push((p.name, mcu_params::ros_value(p, x)));
    }
    v
}

/// The node's options: /rosout, the parameter services, every parameter of
/// [`declared_parameters`] with its descriptor, and the validator and set action of `shared`.
fn node_options(opts: &Options, shared: &Arc<ParamShared>) -> NodeOptions {
    let mut nopts = NodeOptions::new()
        .enable_rosout(true)
        .start_parameter_services(true)
        .parameter_describer(Box::new(ros_api::describe));
    for (k, v) in declared_parameters(opts) {
        nopts = nopts.declare_parameter(k, v);
    }
    let sh = shared.clone();
    let sh2 = shared.clone();
    nopts = nopts
        .parameter_validator(Box::new(move |n, v| ros_api::validate(&sh, n, v)))
        .parameter_set_action(Box::new(move |n, v| {
            if sh2.live.load(Ordering::SeqCst) && ros_api::DYNAMIC_BRIDGE_PARAMS.contains(&n) {
                let _ = sh2
                    .link
                    .try_send(LinkRequest::BridgeParam(n.to_string(), v.clone()));
            }
            Ok(())
        }));
    nopts
}

/// The spinner serves discovery, /clock and the parameter services. It runs on its own thread
/// because the parameter validator blocks while the MCU acknowledges a set.
fn spawn_spinner(
    node: &mut ros2_client::dds::Node,
) -> Result<std::thread::JoinHandle<()>, BridgeError> {
    let spinner = node.spinner().map_err(ros_err)?;
    std::thread::Builder::new()
        .name("ros-spinner".into())
        .spawn(move || {
            match tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
            {
                Ok(rt) => {
                    let _ = rt.block_on(spinner.spin());
                }
                Err(e) => tracing::error!("spinner runtime: {e}"),
            }
        })
        .map_err(ros_err)
}

/// /rosout: the bridge's tracing events (INFO and above), with their level.
fn spawn_rosout(node: &RosNode, opts: &Options) -> Result<(), BridgeError> {
    let Some(logs) = ros_api::rosout_channel() else {
        return Ok(());
    };
    let logger = fcc_ros::logger_name(&opts.namespace, &opts.node_name);
    let out = node.rosout();
    std::thread::Builder::new()
        .name("rosout".into())
        .spawn(move || {
            while let Ok((level, msg, file, line)) = logs.recv() {
                out.log(now_ns(), level, &logger, &msg, &file, line);
            }
        })
        .map_err(ros_err)?;
    Ok(())
}

/// The read topics. Setpoints (velocity, heading, and /clock) and commands on separate queues: a command never
/// waits behind a queue of setpoints from a flooding peer. Returns (setpoints, commands).
fn subscribe_all(
    ctx: &RosContext,
    node: &mut RosNode,
    opts: &Options,
) -> Result<(mpsc::Receiver<InboundMsg>, mpsc::Receiver<InboundMsg>), BridgeError> {
    let (tx, rx) = mpsc::channel::<InboundMsg>(64);
    let (ctx_tx, crx) = mpsc::channel::<InboundMsg>(64);
    subscribe::<TwistStamped>(
        ctx,
        node,
        opts,
        &topics::SETPOINT_VELOCITY,
        tx.clone(),
        Inbound::Setpoint,
    )?;
    subscribe::<QuaternionStamped>(
        ctx,
        node,
        opts,
        &topics::SETPOINT_HEADING,
        tx.clone(),
        Inbound::Heading,
    )?;
    subscribe::<Bool>(
        ctx,
        node,
        opts,
        &topics::CMD_ARM,
        ctx_tx.clone(),
        Inbound::Arm,
    )?;
    subscribe::<StringMsg>(
        ctx,
        node,
        opts,
        &topics::CMD_MODE,
        ctx_tx.clone(),
        Inbound::Mode,
    )?;
    subscribe::<StringMsg>(
        ctx,
        node,
        opts,
        &topics::CMD_KILL,
        ctx_tx.clone(),
        Inbound::Kill,
    )?;
    // With clock_source:=sync, /clock is read whatever use_sim_time says now: it can be set at
    // run time, and the link task applies /clock only while it is true.
    if opts.clock == ClockSource::Sync {
        subscribe::<Clock>(ctx, node, opts, &topics::CLOCK, tx, Inbound::Clock)?;
    }
    Ok((rx, crx))
}

/// The `arm` (SetBool), `land` and `hold` (Trigger) services, answered after the MCU's ack.
fn create_services(
    node: &mut RosNode,
    opts: &Options,
    ltx: &mpsc::Sender<LinkRequest>,
) -> Result<(), BridgeError> {
    use link::CommandKind as K;
    use ros_api::{SetBoolRequest, SetBoolResponse, TriggerRequest, TriggerResponse};
    command_service::<SetBoolRequest, SetBoolResponse>(
        node,
        &opts.name("arm"),
        "SetBool",
        ltx.clone(),
        |r| if r.data { K::Arm } else { K::Disarm },
        |success, message| SetBoolResponse { success, message },
    )?;
    for (srv, kind) in [("land", K::Land), ("hold", K::Hold)] {
        let to_cmd: fn(&TriggerRequest) -> K = match kind {
            K::Land => |_| K::Land,
            _ => |_| K::Hold,
        };
        command_service::<TriggerRequest, TriggerResponse>(
            node,
            &opts.name(srv),
            "Trigger",
            ltx.clone(),
            to_cmd,
            |success, message| TriggerResponse { success, message },
        )?;
    }
    Ok(())
}

/// Run the bridge until a fatal error (the serial device is retried forever).
///
/// `tap` counts every message published and received and records them when recording.
pub async fn run(opts: Options, tap: Arc<Tap>) -> Result<(), BridgeError> {
    let Dds {
        ctx_last: _ctx_last,
        node,
        pubs,
        rx,
        crx,
        lrx,
        shared,
    } = start_dds(&opts).await?;
    let mut inbound = InboundRx {
        setpoints: rx,
        commands: crx,
    };
    let mut ros = RosSide {
        node: &node,
        rx: lrx,
        shared: shared.clone(),
        cmds: Vec::new(),
        params: BTreeMap::new(),
        initial: opts.mcu_params.clone(),
    };

    let mut st = LinkState::new(opts.cfg.clone(), opts.limits, opts.clock);
    st.sim_time = opts.use_sim_time;
    st.uplink = crate::state::Uplink::for_baud(opts.baud);
    tracing::info!(
        "uplink: setpoints at most every {:.1} ms (coalesced to the newest), commands first",
        st.uplink.interval_ns() as f64 / 1e6
    );
    // With clock_source:=mcu, LinkState stamps /tf_static with the first MCU time instead.
    if opts.clock == ClockSource::Sync {
        let tf_static = convert::static_transforms(Time::from_nanos(now_ns()), &st.cfg);
        tap.published_on(&topics::TF_STATIC, &tf_static, rec_time(&st));
        let _ = pubs.tf_static.publish(tf_static);
    }
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
                drain_inbound(&mut inbound, &mut st, &tap);
                while let Ok(r) = ros.rx.try_recv() {
                    ros.request(r, &mut st);
                }
                publish_diag(&pubs, &st, &mut rates, &opts.device, false, &tap);
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
        tap.raw_reset();
        match session(
            port,
            &opts,
            &mut st,
            &pubs,
            &mut inbound,
            &mut ros,
            &mut rates,
            &tap,
        )
        .await
        {
            Ok(reason) => tracing::warn!("link to {} lost ({reason}); reopening", opts.device),
            Err(Fatal::Handshake(e)) => return Err(BridgeError::Handshake(e)),
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
}

/// The subscriptions' queues: setpoints and commands apart (see [`setup_dds`]).
struct InboundRx {
    setpoints: mpsc::Receiver<InboundMsg>,
    commands: mpsc::Receiver<InboundMsg>,
}

/// While disconnected: refuse (and count) what arrives.
fn drain_inbound(rx: &mut InboundRx, st: &mut LinkState, tap: &Tap) {
    while let Ok(m) = rx.commands.try_recv() {
        handle_inbound(m, st, tap);
    }
    while let Ok(m) = rx.setpoints.try_recv() {
        handle_inbound(m, st, tap);
    }
}

fn handle_inbound((m, over): InboundMsg, st: &mut LinkState, tap: &Tap) -> Option<link::Message> {
    let t = rec_time(st);
    match &m {
        Inbound::Setpoint(x) => tap.received_on(&topics::SETPOINT_VELOCITY, x, t),
        Inbound::Heading(x) => tap.received_on(&topics::SETPOINT_HEADING, x, t),
        Inbound::Arm(x) => tap.received_on(&topics::CMD_ARM, x, t),
        Inbound::Mode(x) => tap.received_on(&topics::CMD_MODE, x, t),
        Inbound::Kill(x) => tap.received_on(&topics::CMD_KILL, x, t),
        Inbound::Clock(_) => {}
    }
    // A string that arrived too long (cut on arrival, recorded cut): refused, counted.
    match (&m, over) {
        (Inbound::Setpoint(_) | Inbound::Heading(_), Some(o)) => {
            st.refuse_setpoint(convert::SetpointReject::Oversize(o), now_ns());
            return None;
        }
        (Inbound::Mode(_) | Inbound::Kill(_), Some(o)) => {
            st.refuse_oversize_mode(o, now_ns());
            return None;
        }
        _ => {}
    }
    match m {
        Inbound::Setpoint(t) => st.on_setpoint(&t, now_ns()),
        Inbound::Heading(q) => {
            st.on_heading(&q, now_ns());
            None
        }
        Inbound::Arm(b) => st.on_command(
            Some(convert::arm_command(&b)),
            if b.data { "arm" } else { "disarm" },
        ),
        Inbound::Mode(s) => st.on_command(convert::mode_command(&s), &s.data),
        Inbound::Kill(s) => st.on_kill(&s),
        Inbound::Clock(c) => {
            if st.sim_time {
                st.sim_offset_ns = Some(c.clock.to_nanos() - now_ns());
            }
            None
        }
    }
}

fn publish_diag(
    pubs: &Publishers,
    st: &LinkState,
    rates: &mut RateMeter,
    device: &str,
    connected: bool,
    tap: &Tap,
) {
    let now = now_ns();
    rates.update(st, now);
    let t = rec_time(st);
    let mut d = diag::diagnostics(st, rates, device, connected, Time::from_nanos(t));
    // Built under the lock: no copy of the counts (and their set of seen GUIDs) each second.
    if let Some(s) = pubs
        .security
        .as_ref()
        .and_then(|c| c.lock().ok().map(|c| diag::security_status(&c, device)))
    {
        d.status.push(s);
    }
    tap.published_on(&topics::DIAGNOSTICS, &d, t);
    let _ = pubs.diagnostics.publish(d);
}

/// The periodic work of a session (every 50 ms tick): Hello requests until the MCU answers
/// (and a warning after 3 s without one), then time-sync pings; `/diagnostics` every second.
struct SessionTimers {
    started: tokio::time::Instant,
    last_hello: tokio::time::Instant,
    warned_no_hello: bool,
    pings_sent: u32,
    last_ping: tokio::time::Instant,
    last_diag: tokio::time::Instant,
}

impl SessionTimers {
    fn new() -> Self {
        let now = tokio::time::Instant::now();
        SessionTimers {
            started: now,
            last_hello: now,
            warned_no_hello: false,
            pings_sent: 0,
            last_ping: now - Duration::from_secs(10),
            last_diag: now,
        }
    }

    /// A Hello request or a time-sync ping into `to_send` when one is due.
    fn link_upkeep(
        &mut self,
        now: tokio::time::Instant,
        opts: &Options,
        st: &mut LinkState,
        to_send: &mut Vec<u8>,
    ) {
        if st.handshake == Handshake::Waiting {
            if now - self.last_hello >= opts.hello_period {
                to_send.extend(st.encode(
                    &link::Message::HelloRequest(link::HelloRequest::ours()),
                    now_ns(),
                ));
                self.last_hello = now;
            }
            if !self.warned_no_hello && now - self.started > Duration::from_secs(3) {
                tracing::warn!(
                    "no Hello from the MCU on {} yet (wrong device or baud?)",
                    opts.device
                );
                self.warned_no_hello = true;
            }
        } else {
            // Fast burst of 10 pings at 100 ms, then every ping_period.
            let period = if self.pings_sent < 10 {
                Duration::from_millis(100)
            } else {
                opts.ping_period
            };
            if now - self.last_ping >= period {
                let ping = link::TimeSyncPing {
                    linux_time_ns: now_ns() as u64,
                };
                to_send.extend(st.encode(&link::Message::TimeSyncPing(ping), now_ns()));
                self.pings_sent += 1;
                self.last_ping = now;
            }
        }
    }

    /// Whether `/diagnostics` is due (once a second); if so, counted as sent.
    fn diag_due(&mut self, now: tokio::time::Instant) -> bool {
        let due = now - self.last_diag >= Duration::from_secs(1);
        if due {
            self.last_diag = now;
        }
        due
    }
}

/// One connection: returns why it ended (IO), or a fatal handshake error.
async fn session(
    port: tokio_serial::SerialStream,
    opts: &Options,
    st: &mut LinkState,
    pubs: &Publishers,
    rx: &mut InboundRx,
    ros: &mut RosSide<'_>,
    rates: &mut RateMeter,
    tap: &Tap,
) -> Result<String, Fatal> {
    let mut params_synced = false;
    let (mut rd, mut wr) = tokio::io::split(port);
    // A 0x00 first flushes any half frame at the MCU, then ask for its Hello.
    let mut hello = vec![0u8];
    hello.extend(st.encode(
        &link::Message::HelloRequest(link::HelloRequest::ours()),
        now_ns(),
    ));
    tap.raw_out(&hello, rec_time(st));
    if let Err(e) = wr.write_all(&hello).await {
        return Ok(format!("write: {e}"));
    }
    let mut timers = SessionTimers::new();
    let mut tick = tokio::time::interval(Duration::from_millis(50));
    let mut buf = vec![0u8; 4096];
    // The ROS messages decoded from one read (kept across reads: no allocation per read).
    let mut outs = Vec::new();
    loop {
        let mut to_send: Vec<u8> = Vec::new();
        // The held setpoint's turn on the uplink (see `state::Uplink`).
        let due = st.uplink.due_ns();
        let wait =
            Duration::from_nanos(due.map_or(0, |d| d.saturating_sub(now_ns()).max(0) as u64));
        tokio::select! {
            r = rd.read(&mut buf) => {
                let n = match r {
                    Ok(0) => return Ok("end of file".into()),
                    Ok(n) => n,
                    Err(e) => return Ok(format!("read: {e}")),
                };
                let now = now_ns();
                st.on_bytes_into(&buf[..n], now, &mut outs)?;
                let t = rec_time(st);
                tap.raw_in(&buf[..n], t);
                // Everything decoded from one read goes out with one wake of the DDS event
                // loop, after the last write (rustdds::defer_wakes, vendored), not one per sample.
                rustdds::defer_wakes(|| {
                    for o in outs.drain(..) {
                        if !pubs.publish(o, tap, t) {
                            st.counters.publish_errors += 1;
                        }
                    }
                });
                ros.acks(st);
                if !params_synced && st.handshake != Handshake::Waiting {
                    params_synced = true;
                    to_send.extend(ros.sync_params(st));
                }
            }
            Some(r) = ros.rx.recv() => {
                if let Some(msg) = ros.request(r, st) {
                    to_send.extend(st.encode(&msg, now_ns()));
                }
            }
            // Commands are written in this pass, ahead of any held setpoint.
            Some(m) = rx.commands.recv() => {
                if let Some(msg) = handle_inbound(m, st, tap) {
                    to_send.extend(st.encode(&msg, now_ns()));
                }
            }
            // Setpoints: sent at once if their turn has come, else held (the newest wins).
            Some(m) = rx.setpoints.recv() => {
                if let Some(msg) = handle_inbound(m, st, tap) {
                    to_send.extend(st.encode(&msg, now_ns()));
                }
            }
            _ = tokio::time::sleep(wait), if due.is_some() => {
                let now = now_ns();
                if let Some(msg) = st.uplink_due(now) {
                    to_send.extend(st.encode(&msg, now));
                }
            }
            _ = tick.tick() => {
                let now = tokio::time::Instant::now();
                timers.link_upkeep(now, opts, st, &mut to_send);
                ros.expire();
                ros.sim_time(st);
                if timers.diag_due(now) {
                    publish_diag(pubs, st, rates, &opts.device, true, tap);
                }
            }
        }
        // A held setpoint whose turn came while other branches were busy (a flood keeps the
        // setpoint queue always ready, and the timer above is re-armed on every pass).
        let now = now_ns();
        if let Some(msg) = st.uplink_due(now) {
            to_send.extend(st.encode(&msg, now));
        }
        if !to_send.is_empty() {
            tap.raw_out(&to_send, rec_time(st));
            if let Err(e) = wr.write_all(&to_send).await {
                return Ok(format!("write: {e}"));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    /// The table's `ping_period_ms` default is the one in use (the rest of the table's defaults
    /// are checked in `ros_api`, which does not depend on this module).
    #[test]
    fn ping_period_default_is_the_tables() {
        let def = crate::ros_api::bridge_param("ping_period_ms")
            .unwrap()
            .default;
        assert_eq!(
            def,
            super::Options::default().ping_period.as_millis() as f64
        );
    }
}
