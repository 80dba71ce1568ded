//! The middleware a node runs on, chosen the ROS way (`RMW_IMPLEMENTATION`), and the handles
//! the nodes use whatever it is: [`RosContext`], [`RosNode`], [`Pub`], [`Sub`], [`Srv`] (and
//! [`RawCdr`], a bag's bytes republished as they are).
//!
//! | `RMW_IMPLEMENTATION` | middleware | discovery |
//! |---|---|---|
//! | unset, `rmw_fastrtps_cpp`, `rmw_fastrtps_dynamic_cpp`, `rmw_cyclonedds_cpp`, `rmw_connextdds` | DDS (rustdds, RTPS on the wire: talks to all of them) | SPDP multicast on one network segment |
//! | `rmw_zenoh_cpp` | Zenoh (ros2-client's `zenoh` backend: rmw_zenoh's key expressions, liveliness tokens and attachments) | a Zenoh router (`tcp/localhost:7447` by default; `fcc-zenoh-router`) |
//!
//! On Zenoh the session follows rmw_zenoh's configuration conventions (ros2-client reads them):
//! `ZENOH_SESSION_CONFIG_URI` (a JSON5 session config; default: peer mode, the router at
//! `tcp/localhost:7447`, multicast scouting off) and `ZENOH_CONFIG_OVERRIDE`
//! (`key=value;…`, JSON5 values, e.g. `mode="client";connect/endpoints=["tcp/10.0.0.1:7447"]`).
//! `ROS_DOMAIN_ID` is the first chunk of every key expression, as in rmw_zenoh. DDS Security
//! (SROS2 enclaves) exists only on DDS: an enclave with Zenoh is refused at start-up.
//!
//! What differs between the two below this module: on DDS the writers' sample limits and the
//! spinner (discovery, `/clock`, parameter services); on Zenoh the parameter services are spun by
//! [`RosNode::spin_parameters`] and there is no discovery to serve.

use crate::topics::QosInfo;
use fcc_msgs::ros::RosMsg;
use ros2_client::log::LogLevel;
use ros2_client::parameters::ParameterValue;
use ros2_client::{dds, zenoh, Name, NodeName, NodeOptions, QosProfile};
use std::sync::Arc;

/// Which middleware ([`Rmw::from_env`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rmw {
    Dds,
    Zenoh,
}

/// The `RMW_IMPLEMENTATION` values that mean DDS: every one speaks RTPS, as rustdds does.
pub const DDS_RMWS: [&str; 4] = [
    "rmw_fastrtps_cpp",
    "rmw_fastrtps_dynamic_cpp",
    "rmw_cyclonedds_cpp",
    "rmw_connextdds",
];
/// The `RMW_IMPLEMENTATION` value that means Zenoh.
pub const ZENOH_RMW: &str = "rmw_zenoh_cpp";

impl Rmw {
    /// The middleware named by an `RMW_IMPLEMENTATION` value (unset or empty: DDS, ROS 2's
    /// default); an unknown name is an error that lists the known ones.
    pub fn from_env_value(v: Option<&str>) -> Result<Rmw, String> {
        match v.map(str::trim) {
            None | Some("") => Ok(Rmw::Dds),
            Some(ZENOH_RMW) => Ok(Rmw::Zenoh),
            Some(n) if DDS_RMWS.contains(&n) => Ok(Rmw::Dds),
            Some(n) => Err(format!(
                "RMW_IMPLEMENTATION={n}: unknown middleware (DDS: {}; Zenoh: {ZENOH_RMW})",
                DDS_RMWS.join(", ")
            )),
        }
    }

    /// [`Rmw::from_env_value`] of the environment's `RMW_IMPLEMENTATION`.
    pub fn from_env() -> Result<Rmw, String> {
        Rmw::from_env_value(std::env::var("RMW_IMPLEMENTATION").ok().as_deref())
    }

    pub fn label(self) -> &'static str {
        match self {
            Rmw::Dds => "DDS",
            Rmw::Zenoh => "Zenoh",
        }
    }

    /// What [`context`] does, for the start-up watchdog's step.
    pub fn opening(self) -> &'static str {
        match self {
            Rmw::Dds => "creating the DDS participant",
            Rmw::Zenoh => "opening the Zenoh session",
        }
    }

    /// Where the node's traffic may go, for its first log line.
    pub fn reach(self, localhost_only: bool) -> &'static str {
        match (self, localhost_only) {
            (Rmw::Zenoh, _) => "session from ZENOH_SESSION_CONFIG_URI / ZENOH_CONFIG_OVERRIDE",
            (Rmw::Dds, true) => "loopback only",
            (Rmw::Dds, false) => "all interfaces",
        }
    }
}

/// The tokio runtime of a node's main loop: current-thread on DDS (the serial port's readiness
/// and the session that reads it on one thread: one context switch per read); on Zenoh a
/// multi-thread runtime with one worker, since Zenoh's blocking calls (`wait()`, which
/// ros2-client's Zenoh publishers use) panic on a current-thread runtime.
pub fn runtime(rmw: Rmw) -> std::io::Result<tokio::runtime::Runtime> {
    match rmw {
        Rmw::Dds => tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build(),
        Rmw::Zenoh => tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build(),
    }
}

/// A ROS context on either middleware.
#[derive(Clone)]
pub enum RosContext {
    Dds(dds::Context),
    Zenoh(zenoh::Context),
}

/// The node's context on `rmw`: the DDS participant of [`crate::ros_node::context`], or the
/// Zenoh session ([`zenoh_context`]); an SROS2 enclave with Zenoh is refused (DDS Security only).
pub fn context(rmw: Rmw, env: crate::ros_node::DdsEnv) -> Result<RosContext, String> {
    match rmw {
        Rmw::Dds => crate::ros_node::context(env).map(RosContext::Dds),
        Rmw::Zenoh if env.enclave_dir.is_some() => Err(
            "ROS 2 security (an SROS2 enclave) is DDS-only in this stack: unset \
             ROS_SECURITY_ENABLE or run on DDS"
                .into(),
        ),
        Rmw::Zenoh => zenoh_context(env.domain_id),
    }
}

/// The Zenoh context: domain `domain_id`, the session from rmw_zenoh's environment variables.
/// Registers [`crate::type_hashes::TYPE_HASHES`] with ros2-client first, so that our entities
/// carry the REP-2016 type hashes an rmw_zenoh peer expects.
pub fn zenoh_context(domain_id: u16) -> Result<RosContext, String> {
    zenoh::register_type_hashes(crate::type_hashes::TYPE_HASHES);
    let opts = zenoh::ContextOptions::new().domain_id(domain_id);
    zenoh::Context::with_options(opts)
        .map(RosContext::Zenoh)
        .map_err(|e| format!("Zenoh session: {e:?}"))
}

/// A node on either middleware. The DDS node's spinner is started by its owner (it runs on a
/// thread or task of the owner's choice); the Zenoh node's parameter services by
/// [`RosNode::spin_parameters`].
pub enum RosNode {
    Dds(dds::Node),
    /// Shared with the parameter thread ([`RosNode::spin_parameters`]).
    Zenoh(Arc<zenoh::Node>),
}

fn node_name(namespace: &str, name: &str) -> Result<NodeName, String> {
    let ns = if namespace.starts_with('/') {
        namespace.to_string()
    } else {
        format!("/{namespace}")
    };
    NodeName::new(&ns, name).map_err(|e| format!("node name {ns}/{name}: {e:?}"))
}

fn parse_name(name: &str) -> Result<Name, String> {
    Name::parse(name).map_err(|e| format!("topic {name}: {e:?}"))
}

impl RosContext {
    /// A node `namespace/name` with these options (no spinner started).
    pub fn new_node(
        &self,
        namespace: &str,
        name: &str,
        opts: NodeOptions,
    ) -> Result<RosNode, String> {
        let n = node_name(namespace, name)?;
        match self {
            RosContext::Dds(c) => c
                .new_node(n, opts)
                .map(RosNode::Dds)
                .map_err(|e| format!("node: {e:?}")),
            RosContext::Zenoh(c) => c
                .new_node(n, opts)
                .map(|n| RosNode::Zenoh(Arc::new(n)))
                .map_err(|e| format!("node: {e:?}")),
        }
    }

    pub fn rmw(&self) -> Rmw {
        match self {
            RosContext::Dds(_) => Rmw::Dds,
            RosContext::Zenoh(_) => Rmw::Zenoh,
        }
    }
}

impl RosNode {
    /// Publisher on a ROS name (relative names go under the node's namespace) with `qos`; on
    /// DDS its writer holds at most [`crate::ros_node::WRITER_KEEP`] samples.
    pub fn publisher<T: RosMsg>(&mut self, name: &str, qos: &QosProfile) -> Result<Pub<T>, String> {
        match self {
            RosNode::Dds(n) => crate::ros_node::publisher(n, name, qos).map(Pub::Dds),
            RosNode::Zenoh(n) => {
                let topic = n.create_topic(&parse_name(name)?, T::type_name(), qos);
                n.create_publisher::<T>(&topic, None)
                    .map(Pub::Zenoh)
                    .map_err(|e| format!("publisher {name}: {e:?}"))
            }
        }
    }

    /// Publisher with a topic table entry's QoS.
    pub fn publisher_info<T: RosMsg>(
        &mut self,
        name: &str,
        qos: QosInfo,
    ) -> Result<Pub<T>, String> {
        self.publisher(name, &qos.publisher_profile())
    }

    /// Subscription on a ROS name with `qos` (on DDS, ros2-client's reader; the bridge builds its
    /// own bounded DDS readers and uses this on Zenoh only).
    pub fn subscription<T: RosMsg>(
        &mut self,
        name: &str,
        qos: &QosProfile,
    ) -> Result<Sub<T>, String> {
        match self {
            RosNode::Dds(n) => crate::ros_node::subscription(n, name, qos).map(Sub::Dds),
            RosNode::Zenoh(n) => {
                let topic = n.create_topic(&parse_name(name)?, T::type_name(), qos);
                n.create_subscription::<T>(&topic, None)
                    .map(Sub::Zenoh)
                    .map_err(|e| format!("subscription {name}: {e:?}"))
            }
        }
    }

    /// Publisher of already-serialised messages (a bag's CDR bodies, [`RawCdr`]) of the type
    /// `type_name` on a ROS name, with `qos` as given (its history depth too: a replayed topic
    /// keeps its recorded QoS).
    pub fn raw_publisher(
        &mut self,
        name: &str,
        type_name: ros2_client::MessageTypeName,
        qos: &QosProfile,
    ) -> Result<Pub<RawCdr>, String> {
        let n = parse_name(name)?;
        let fail = |e| format!("publisher {name}: {e:?}");
        match self {
            RosNode::Dds(node) => {
                let topic = node
                    .create_topic(&n, type_name, qos)
                    .map_err(|e| format!("topic {name}: {e:?}"))?;
                node.create_publisher::<RawCdr>(&topic, None)
                    .map(Pub::Dds)
                    .map_err(fail)
            }
            RosNode::Zenoh(node) => {
                let topic = node.create_topic(&n, type_name, qos);
                node.create_publisher::<RawCdr>(&topic, None)
                    .map(Pub::Zenoh)
                    .map_err(fail)
            }
        }
    }

    /// A service server on a ROS name, type `pkg/srv/Type` given as (package, type).
    pub fn server<Req, Resp>(
        &mut self,
        name: &str,
        pkg: &str,
        ty: &str,
        qos: &QosProfile,
    ) -> Result<Srv<Req, Resp>, String>
    where
        Req: ros2_client::Message + Clone + Send + Sync + 'static,
        Resp: ros2_client::Message + Send + Sync + 'static,
    {
        let n = parse_name(name)?;
        let t = ros2_client::ServiceTypeName::new(pkg, ty);
        match self {
            RosNode::Dds(node) => node
                .create_server::<Req, Resp>(
                    dds::ServiceMapping::Enhanced,
                    &n,
                    &t,
                    qos.clone(),
                    qos.clone(),
                )
                .map(Srv::Dds)
                .map_err(|e| format!("service {name}: {e:?}")),
            RosNode::Zenoh(node) => node
                .create_server::<Req, Resp>(&n, &t)
                .map(Srv::Zenoh)
                .map_err(|e| format!("service {name}: {e:?}")),
        }
    }

    /// The node's `/rosout` writer.
    pub fn rosout(&self) -> Rosout {
        match self {
            RosNode::Dds(n) => Rosout::Dds(n.logging_handle()),
            RosNode::Zenoh(n) => Rosout::Zenoh(n.clone()),
        }
    }

    pub fn get_parameter(&self, name: &str) -> Option<ParameterValue> {
        match self {
            RosNode::Dds(n) => n.get_parameter(name),
            RosNode::Zenoh(n) => n.parameter_server().and_then(|p| p.get_parameter(name)),
        }
    }

    pub fn set_parameter(&self, name: &str, v: ParameterValue) -> Result<(), String> {
        match self {
            RosNode::Dds(n) => n.set_parameter(name, v).map_err(|e| format!("{e:?}")),
            RosNode::Zenoh(n) => match n.parameter_server() {
                Some(p) => p.set_parameter(name, v),
                None => Err("no parameter services".into()),
            },
        }
    }

    /// On Zenoh, serve the parameter services (and `/parameter_events`) on a thread of their
    /// own until `stop` is true: the validator may block while the MCU acknowledges a set.
    /// Nothing on DDS (the spinner serves them).
    pub fn spin_parameters(
        &self,
        stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    ) -> Result<(), String> {
        let RosNode::Zenoh(n) = self else {
            return Ok(());
        };
        if n.parameter_server().is_none() {
            return Ok(());
        }
        let n = n.clone();
        std::thread::Builder::new()
            .name("ros-params".into())
            .spawn(move || {
                if let Some(server) = n.parameter_server() {
                    server.spin(std::time::Duration::from_millis(5), || {
                        stop.load(std::sync::atomic::Ordering::Relaxed)
                    })
                }
            })
            .map(drop)
            .map_err(|e| format!("parameter thread: {e}"))
    }
}

/// A publisher on either middleware.
pub enum Pub<T: ros2_client::Message> {
    Dds(dds::Publisher<T>),
    Zenoh(zenoh::Publisher<T>),
}

impl<T: ros2_client::Message + std::fmt::Debug> Pub<T> {
    /// Publish; a failure (full send window, closed session) is returned as text.
    pub fn publish(&self, m: T) -> Result<(), String> {
        match self {
            Pub::Dds(p) => p.publish(m).map_err(|e| format!("{e:?}")),
            Pub::Zenoh(p) => p.publish(m).map_err(|e| format!("{e:?}")),
        }
    }
}

/// A CDR body passed through unchanged (serialised as its raw bytes, without a length): what
/// [`RosNode::raw_publisher`] publishes. Publish-only.
#[derive(Clone, Debug)]
pub struct RawCdr(pub Vec<u8>);

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

/// A subscription on either middleware.
pub enum Sub<T> {
    Dds(dds::Subscription<T>),
    Zenoh(zenoh::Subscription<T>),
}

impl<T: ros2_client::Message + 'static> Sub<T> {
    /// The next message (waits); a message that could not be read is returned as text.
    pub async fn take(&self) -> Result<T, String> {
        match self {
            Sub::Dds(s) => s
                .async_take()
                .await
                .map(|(m, _)| m)
                .map_err(|e| format!("{e:?}")),
            Sub::Zenoh(s) => s
                .async_take()
                .await
                .map(|(m, _)| m)
                .map_err(|e| format!("{e:?}")),
        }
    }

    /// Every message, as a stream (a `select!` loop, a forwarding task).
    pub fn stream(&self) -> futures::stream::BoxStream<'_, Result<T, String>>
    where
        T: Send + Sync,
    {
        use futures::StreamExt;
        let text = |e| format!("{e:?}");
        match self {
            Sub::Dds(s) => s
                .async_stream()
                .map(move |r| r.map(|(m, _)| m).map_err(text))
                .boxed(),
            Sub::Zenoh(s) => s
                .async_stream()
                .map(move |r| r.map(|(m, _)| m).map_err(text))
                .boxed(),
        }
    }
}

/// A node's `/rosout` on either middleware ([`RosNode::rosout`]).
pub enum Rosout {
    Dds(dds::NodeLoggingHandle),
    Zenoh(Arc<zenoh::Node>),
}

impl Rosout {
    /// One record: ROS time `stamp_ns`, `logger` (`ns.node`), the source file and line. On
    /// Zenoh the record carries the node's base name and the current time (ros2-client's
    /// `Logger`).
    pub fn log(
        &self,
        stamp_ns: i64,
        level: LogLevel,
        logger: &str,
        msg: &str,
        file: &str,
        line: u32,
    ) {
        match self {
            Rosout::Dds(h) => {
                use dds::RosoutRaw;
                let t = ros2_client::builtin_interfaces::Time::from_nanos(stamp_ns);
                h.rosout_raw(t, level, logger, msg, file, "", line)
            }
            Rosout::Zenoh(n) => {
                if let Some(l) = n.logger() {
                    l.log_at(level, msg, file, "", line)
                }
            }
        }
    }
}

/// A service server on either middleware.
pub enum Srv<Req: ros2_client::Message, Resp: ros2_client::Message> {
    Dds(dds::Server<Req, Resp>),
    Zenoh(zenoh::Server<Req, Resp>),
}

impl<Req, Resp> Srv<Req, Resp>
where
    Req: ros2_client::Message + 'static,
    Resp: ros2_client::Message + 'static,
{
    /// The next request (waits).
    pub async fn receive(&self) -> Result<(ros2_client::service::RmwRequestId, Req), String> {
        match self {
            Srv::Dds(s) => s
                .async_receive_request()
                .await
                .map_err(|e| format!("{e:?}")),
            Srv::Zenoh(s) => s
                .async_receive_request()
                .await
                .map_err(|e| format!("{e:?}")),
        }
    }

    pub fn respond(&self, id: ros2_client::service::RmwRequestId, r: Resp) -> Result<(), String> {
        match self {
            Srv::Dds(s) => s.send_response(id, r).map_err(|e| format!("{e:?}")),
            Srv::Zenoh(s) => s.send_response(id, r).map_err(|e| format!("{e:?}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rmw_from_env_as_ros() {
        assert_eq!(Rmw::from_env_value(None), Ok(Rmw::Dds));
        assert_eq!(Rmw::from_env_value(Some("")), Ok(Rmw::Dds));
        assert_eq!(Rmw::from_env_value(Some("rmw_zenoh_cpp")), Ok(Rmw::Zenoh));
        for d in DDS_RMWS {
            assert_eq!(Rmw::from_env_value(Some(d)), Ok(Rmw::Dds));
        }
        let e = Rmw::from_env_value(Some("rmw_zenoh")).unwrap_err();
        assert!(
            e.contains("RMW_IMPLEMENTATION=rmw_zenoh: unknown") && e.contains("rmw_zenoh_cpp"),
            "{e}"
        );
    }
}
