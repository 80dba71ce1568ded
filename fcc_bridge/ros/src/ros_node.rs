//! The ROS 2 node plumbing of `fcc-bridge` and `fcc-mission`: the DDS participant (loopback
//! only by default; the one place it is built), the DDS environment
//! (`ROS_DOMAIN_ID`, `ROS_LOCALHOST_ONLY`, `ROS_AUTOMATIC_DISCOVERY_RANGE`), publishers and
//! subscriptions by relative ROS name, and the ROS clock (system or `/clock`).

use crate::params::{self, RosArgs};
use crate::security::{Decision, SecurityEnv};
use fcc_msgs::ros::{Clock, RosMsg};
use ros2_client::dds::{Context, Node, Publisher, Subscription};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Name, NodeName, NodeOptions, QosProfile};
use std::net::Ipv4Addr;
use std::path::PathBuf;

/// DDS settings from the environment and the `localhost_only` parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct DdsEnv {
    pub domain_id: u16,
    pub localhost_only: bool,
    /// The checked SROS2 enclave directory when security is on ([`crate::security`]).
    pub enclave_dir: Option<PathBuf>,
}

impl DdsEnv {
    /// Read `ROS_DOMAIN_ID`, `ROS_LOCALHOST_ONLY`, `ROS_AUTOMATIC_DISCOVERY_RANGE`, the
    /// `localhost_only` ROS parameter (loopback only by default, as the bridge) and the SROS2
    /// settings ([`security_from_env`]).
    pub fn from_env(ros: &RosArgs) -> Result<Self, String> {
        let env = |k: &str| std::env::var(k).ok();
        Ok(DdsEnv {
            enclave_dir: security_from_env(ros)?,
            domain_id: params::domain_id(env("ROS_DOMAIN_ID").as_deref())?,
            localhost_only: params::localhost_only(
                ros.params.get("localhost_only").map(String::as_str),
                env("ROS_LOCALHOST_ONLY").as_deref(),
                env("ROS_AUTOMATIC_DISCOVERY_RANGE").as_deref(),
            )?,
        })
    }
}

/// The SROS2 enclave directory from `ROS_SECURITY_*` and `--enclave` ([`crate::security`]),
/// checked: `None` when security is off (a Permissive fallback is logged as a warning), `Err`
/// the one line an Enforce node stops with.
pub fn security_from_env(ros: &RosArgs) -> Result<Option<PathBuf>, String> {
    let sec = SecurityEnv::from_env(ros, |k| std::env::var(k).ok());
    let now_unix_s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64);
    match sec.decide(now_unix_s)? {
        Decision::On { enclave_dir } => {
            log::info!(
                "security: enclave {} ({})",
                sec.enclave,
                enclave_dir.display()
            );
            Ok(Some(enclave_dir))
        }
        Decision::Off { warning } => {
            if let Some(w) = warning {
                log::warn!("{w}");
            }
            Ok(None)
        }
    }
}

/// A ros2-client context on a participant restricted to loopback unless disabled (a
/// `ROS_STATIC_PEERS` it cannot honour is logged as a warning), with DDS Security's builtin
/// plugins on the enclave when [`DdsEnv::enclave_dir`] is set.
pub fn context(env: DdsEnv) -> Result<Context, String> {
    let peers = std::env::var("ROS_STATIC_PEERS").ok();
    if let Some(w) = params::static_peers_warning(peers.as_deref()) {
        log::warn!("{w}");
    }
    let mut b = rustdds::DomainParticipantBuilder::new(env.domain_id);
    if env.localhost_only {
        b = b.with_only_networks([Ipv4Addr::LOCALHOST]);
    }
    if let Some(dir) = env.enclave_dir {
        b = secure(b, dir)?;
    }
    let dp = b.build().map_err(|e| format!("DDS participant: {e:?}"))?;
    Context::from_domain_participant(dp).map_err(|e| format!("ROS context: {e:?}"))
}

#[cfg(feature = "security")]
fn secure(
    b: rustdds::DomainParticipantBuilder,
    dir: PathBuf,
) -> Result<rustdds::DomainParticipantBuilder, String> {
    use rustdds::DomainParticipantSecurityConfigFiles as Files;
    Ok(b.builtin_security(Files::with_ros_default_names(dir, String::new())))
}

#[cfg(not(feature = "security"))]
fn secure(
    _b: rustdds::DomainParticipantBuilder,
    dir: PathBuf,
) -> Result<rustdds::DomainParticipantBuilder, String> {
    Err(format!("{}: this build has no DDS Security", dir.display()))
}

/// A node `namespace/name` with `/rosout` and its `use_sim_time` parameter declared with the
/// value in use (else ros2-client's built-in `false` is what `ros2 param get` shows); spawns its
/// spinner on the current tokio runtime.
pub fn node(
    ctx: &Context,
    namespace: &str,
    name: &str,
    use_sim_time: bool,
) -> Result<Node, String> {
    let opts = NodeOptions::new().enable_rosout(true).declare_parameter(
        "use_sim_time",
        ros2_client::parameters::ParameterValue::Boolean(use_sim_time),
    );
    node_with(ctx, namespace, name, opts)
}

/// A node `namespace/name` with these options (its parameters, their descriptors and
/// validator); spawns its spinner on the current tokio runtime.
pub fn node_with(
    ctx: &Context,
    namespace: &str,
    name: &str,
    opts: NodeOptions,
) -> Result<Node, String> {
    let ns = if namespace.starts_with('/') {
        namespace.to_string()
    } else {
        format!("/{namespace}")
    };
    let mut node = ctx
        .new_node(
            NodeName::new(&ns, name).map_err(|e| format!("node name {ns}/{name}: {e:?}"))?,
            opts,
        )
        .map_err(|e| format!("node: {e:?}"))?;
    tokio::spawn(
        node.spinner()
            .map_err(|e| format!("spinner: {e:?}"))?
            .spin(),
    );
    Ok(node)
}

/// Reliable, volatile, keep-last `depth` (what rclcpp's default publisher does). Matches both
/// reliable and best-effort readers.
pub fn reliable_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

/// Best-effort keep-last `depth`: matches reliable and best-effort writers.
pub fn best_effort_qos(depth: usize) -> QosProfile {
    QosProfile::subscription_default().history(History::KeepLast { depth })
}

/// The topic of a ROS name (relative names go under the node's namespace) for type `T`.
fn topic<T: RosMsg>(
    node: &mut Node,
    name: &str,
    qos: &QosProfile,
) -> Result<rustdds::Topic, String> {
    node.create_topic(
        &Name::parse(name).map_err(|e| format!("topic {name}: {e:?}"))?,
        T::type_name(),
        qos,
    )
    .map_err(|e| format!("topic {name}: {e:?}"))
}

/// Samples a publisher's DDS writer may hold: rustdds' `ResourceLimits::max_samples` on its
/// topic, which is both the writer's reliable send window (unacknowledged samples before a write
/// fails, `WhenFull::Fail`) and the bound on the samples it retains. Without a limit rustdds
/// retains up to 8192 samples per writer until every matched reader has acknowledged them, and a
/// best-effort reader (fcc-mission's, most tools') never acknowledges: each writer grew until
/// 8192 (the bridge +36 MB/h, fcc-mission +4.8 MB/h in `scripts/soak.sh 8`). 256 samples are
/// 1.3 s at the 200 Hz IMU rate; a reliable reader acknowledges within a heartbeat (0.1 s).
pub const WRITER_KEEP: i32 = 256;

/// Publisher on a ROS name (relative names go under the node's namespace); its writer holds at
/// most [`WRITER_KEEP`] samples (and the profile's history depth, if smaller).
pub fn publisher<T: RosMsg>(
    node: &mut Node,
    name: &str,
    qos: &QosProfile,
) -> Result<Publisher<T>, String> {
    use rustdds::{policy::ResourceLimits, TopicDescription};
    let named = topic::<T>(node, name, qos)?;
    let limits = rustdds::QosPolicyBuilder::new()
        .resource_limits(ResourceLimits {
            max_samples: WRITER_KEEP,
            max_instances: 1,
            max_samples_per_instance: WRITER_KEEP,
        })
        .build();
    // The same DDS topic (name and type from ros2-client), with the limit in its QoS: a writer
    // takes its QoS from its topic.
    let topic = named
        .participant()
        .ok_or_else(|| format!("publisher {name}: DDS participant gone"))?
        .create_topic(
            named.name(),
            T::type_name().dds_msg_type(),
            &rustdds::QosPolicies::from(qos).modify_by(&limits),
            rustdds::TopicKind::NoKey,
        )
        .map_err(|e| format!("topic {name}: {e:?}"))?;
    node.create_publisher::<T>(&topic, None)
        .map_err(|e| format!("publisher {name}: {e:?}"))
}

/// Subscription on a ROS name.
pub fn subscription<T: RosMsg>(
    node: &mut Node,
    name: &str,
    qos: &QosProfile,
) -> Result<Subscription<T>, String> {
    let topic = topic::<T>(node, name, qos)?;
    node.create_subscription::<T>(&topic, None)
        .map_err(|e| format!("subscription {name}: {e:?}"))
}

/// ROS time: the Linux clock, or the latest `/clock` with `use_sim_time`.
#[derive(Clone, Debug, Default)]
pub struct RosClock {
    pub use_sim_time: bool,
    last_clock_ns: Option<i64>,
}

impl RosClock {
    pub fn new(use_sim_time: bool) -> Self {
        RosClock {
            use_sim_time,
            last_clock_ns: None,
        }
    }
    /// Feed a `/clock` message.
    pub fn on_clock(&mut self, c: &Clock) {
        self.last_clock_ns = Some(c.clock.to_nanos());
    }
    /// Now in ns, or None with `use_sim_time` before the first `/clock`.
    pub fn now_ns(&self) -> Option<i64> {
        if self.use_sim_time {
            self.last_clock_ns
        } else {
            Some(now_ns())
        }
    }
}

/// Linux realtime clock in ns since the epoch (ROS time without `use_sim_time`).
pub fn now_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as i64)
        .unwrap_or(0)
}

/// The ROS logger name of a node: `ns.name` without the leading slash (as rcl does).
pub fn logger_name(namespace: &str, node: &str) -> String {
    let ns = namespace.trim_matches('/').replace('/', ".");
    if ns.is_empty() {
        node.to_string()
    } else {
        format!("{ns}.{node}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logger_names_as_rcl() {
        assert_eq!(logger_name("/uav1", "fcc_bridge"), "uav1.fcc_bridge");
        assert_eq!(logger_name("/", "fcc_mission"), "fcc_mission");
        assert_eq!(logger_name("/a/b/", "n"), "a.b.n");
    }
}
