//! The topics of the bridge, each written once: name (relative to the node's namespace unless
//! absolute), message type (the table's type parameter), QoS and direction. The bridge's
//! publishers and subscriptions are created from these entries, and its recorder's tap files
//! each message under the entry's name and QoS — so a topic's name, type and QoS cannot differ
//! between the DDS side and the bag.
//!
//! | topic | type | QoS | direction |
//! |---|---|---|---|
//! | `imu/data_raw`, `state/imu` | sensor_msgs/Imu | telemetry | published |
//! | `mag` | sensor_msgs/MagneticField | telemetry | published |
//! | `baro` | sensor_msgs/FluidPressure | telemetry | published |
//! | `gps/fix` | sensor_msgs/NavSatFix | telemetry | published |
//! | `range/laser`, `range/sonar`, `altitude/ground` | sensor_msgs/Range | telemetry | published |
//! | `battery` | sensor_msgs/BatteryState | telemetry | published |
//! | `state/odom` | nav_msgs/Odometry | telemetry | published |
//! | `/tf` | tf2_msgs/TFMessage | telemetry, depth 100 | published |
//! | `/tf_static` | tf2_msgs/TFMessage | reliable, transient local, depth 1 | published |
//! | `altitude` | fcc_msgs/Altitude | telemetry | published |
//! | `status` | fcc_msgs/Status | telemetry | published |
//! | `accel/observer`, `accel/measured` | geometry_msgs/AccelStamped | telemetry | published |
//! | `/diagnostics` | diagnostic_msgs/DiagnosticArray | telemetry | published |
//! | `home` | sensor_msgs/NavSatFix | reliable, transient local, depth 1 | published (when set or moved) |
//! | `/clock` | rosgraph_msgs/Clock | telemetry, depth 1 | published (`clock_source:=mcu`) or read (`sync`) |
//! | `setpoint/velocity` | geometry_msgs/TwistStamped | best effort | read |
//! | `setpoint/heading` | geometry_msgs/QuaternionStamped | best effort | read |
//! | `cmd/arm` | std_msgs/Bool | best effort | read |
//! | `cmd/mode`, `cmd/kill` | std_msgs/String | best effort | read |
//! | `link/raw_frames` | fcc_msgs/LinkFrame | telemetry | recorded only |
//!
//! "Telemetry" is [`QosInfo::TELEMETRY`]: reliable, volatile, keep last 10 (what rclcpp's
//! default publisher offers; it matches reliable and best-effort readers). A read topic's QoS
//! is what the bag records for it; the reader itself is best effort (it matches reliable and
//! best-effort writers) with a bounded sample cache (see `fcc_bridge::bridge`).

use fcc_msgs::ros::*;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::QosProfile;
use std::marker::PhantomData;

/// QoS of a channel, as `offered_qos_profiles` (rmw integer enums).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QosInfo {
    pub reliable: bool,
    pub transient_local: bool,
    pub depth: u32,
}

impl QosInfo {
    pub const TELEMETRY: QosInfo = QosInfo {
        reliable: true,
        transient_local: false,
        depth: 10,
    };
    pub const BEST_EFFORT: QosInfo = QosInfo {
        reliable: false,
        transient_local: false,
        depth: 10,
    };

    /// The same QoS with another history depth.
    pub const fn with_depth(self, depth: u32) -> QosInfo {
        QosInfo { depth, ..self }
    }

    /// The publisher's profile: reliable (a full send window fails at once, counted, instead
    /// of stalling the caller) or best effort, volatile or transient local, keep last `depth`.
    pub fn publisher_profile(&self) -> QosProfile {
        let p = QosProfile::publisher_default();
        let p = if self.reliable {
            p.reliability_reliable(WhenFull::Fail)
        } else {
            p.reliability_best_effort()
        };
        p.durability(if self.transient_local {
            Durability::TransientLocal
        } else {
            Durability::Volatile
        })
        .history(History::KeepLast {
            depth: self.depth as usize,
        })
    }

    /// rosbag2's YAML (history 1 = keep last, reliability 1/2 = reliable/best effort,
    /// durability 1/2 = transient local/volatile, liveliness 1 = automatic).
    pub fn yaml(&self) -> String {
        let inf = "{sec: 9223372036, nsec: 854775807}";
        format!(
            "- history: 1\n  depth: {}\n  reliability: {}\n  durability: {}\n  deadline: {inf}\n  lifespan: {inf}\n  liveliness: 1\n  liveliness_lease_duration: {inf}\n  avoid_ros_namespace_conventions: false\n",
            self.depth,
            if self.reliable { 1 } else { 2 },
            if self.transient_local { 1 } else { 2 }
        )
    }
}

/// Which way a topic goes, as the bridge sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// The bridge publishes it.
    Published,
    /// The bridge subscribes to it.
    Read,
    /// `/clock`: published with `clock_source:=mcu`, read with `clock_source:=sync`.
    PublishedOrRead,
    /// Only in the bag (not on DDS).
    Recorded,
}

/// One topic of the table; `T` is its message type.
#[derive(Debug)]
pub struct Topic<T> {
    /// ROS name as the node writes it (relative names go under the namespace; remaps apply).
    pub name: &'static str,
    pub qos: QosInfo,
    pub direction: Direction,
    msg: PhantomData<fn() -> T>,
}

impl<T> Topic<T> {
    const fn new(name: &'static str, qos: QosInfo, direction: Direction) -> Self {
        Topic {
            name,
            qos,
            direction,
            msg: PhantomData,
        }
    }
}

impl<T: RosMsg> Topic<T> {
    /// `pkg/msg/Name` of the message type.
    pub fn schema_name(&self) -> String {
        T::schema_name()
    }
}

use Direction::{Published as P, PublishedOrRead, Read as R, Recorded};

const TELEMETRY: QosInfo = QosInfo::TELEMETRY;
const READ: QosInfo = QosInfo::BEST_EFFORT;

pub const IMU_RAW: Topic<Imu> = Topic::new("imu/data_raw", TELEMETRY, P);
pub const MAG: Topic<MagneticField> = Topic::new("mag", TELEMETRY, P);
pub const BARO: Topic<FluidPressure> = Topic::new("baro", TELEMETRY, P);
pub const GPS_FIX: Topic<NavSatFix> = Topic::new("gps/fix", TELEMETRY, P);
pub const LASER: Topic<Range> = Topic::new("range/laser", TELEMETRY, P);
pub const SONAR: Topic<Range> = Topic::new("range/sonar", TELEMETRY, P);
pub const BATTERY: Topic<BatteryState> = Topic::new("battery", TELEMETRY, P);
pub const ODOM: Topic<Odometry> = Topic::new("state/odom", TELEMETRY, P);
pub const STATE_IMU: Topic<Imu> = Topic::new("state/imu", TELEMETRY, P);
pub const TF: Topic<TFMessage> = Topic::new("/tf", TELEMETRY.with_depth(100), P);
pub const TF_STATIC: Topic<TFMessage> = Topic::new(
    "/tf_static",
    QosInfo {
        transient_local: true,
        depth: 1,
        ..TELEMETRY
    },
    P,
);
pub const ALTITUDE: Topic<Altitude> = Topic::new("altitude", TELEMETRY, P);
pub const GROUND: Topic<Range> = Topic::new("altitude/ground", TELEMETRY, P);
pub const STATUS: Topic<Status> = Topic::new("status", TELEMETRY, P);
pub const ACCEL_OBSERVER: Topic<AccelStamped> = Topic::new("accel/observer", TELEMETRY, P);
pub const ACCEL_MEASURED: Topic<AccelStamped> = Topic::new("accel/measured", TELEMETRY, P);
pub const DIAGNOSTICS: Topic<DiagnosticArray> = Topic::new("/diagnostics", TELEMETRY, P);
/// The MCU's home, the origin of `map` (latched: a late joiner gets the last one).
pub const HOME: Topic<NavSatFix> = Topic::new(
    "home",
    QosInfo {
        transient_local: true,
        depth: 1,
        ..TELEMETRY
    },
    P,
);
pub const CLOCK: Topic<Clock> = Topic::new("/clock", TELEMETRY.with_depth(1), PublishedOrRead);
pub const SETPOINT_VELOCITY: Topic<TwistStamped> = Topic::new("setpoint/velocity", READ, R);
/// An absolute heading (ENU orientation, only its yaw is used) for the velocity setpoints that
/// follow it (`fcc_bridge::convert::setpoint`).
pub const SETPOINT_HEADING: Topic<QuaternionStamped> = Topic::new("setpoint/heading", READ, R);
pub const CMD_ARM: Topic<Bool> = Topic::new("cmd/arm", READ, R);
pub const CMD_MODE: Topic<StringMsg> = Topic::new("cmd/mode", READ, R);
pub const CMD_KILL: Topic<StringMsg> = Topic::new("cmd/kill", READ, R);
pub const LINK_RAW_FRAMES: Topic<LinkFrame> = Topic::new("link/raw_frames", TELEMETRY, Recorded);

/// The mission node's own topic (std_msgs/String, JSON progress): the one name outside the
/// bridge's table, here so that the mission node and its SROS2 permissions ([`crate::sros2`])
/// name it once.
pub const MISSION_STATUS: &str = "mission/status";

/// Every entry as (name, `pkg/msg/Type`, QoS, direction), in the order above.
pub fn table() -> Vec<(&'static str, String, QosInfo, Direction)> {
    macro_rules! rows {
        ($($t:expr),*) => { vec![$(($t.name, $t.schema_name(), $t.qos, $t.direction)),*] };
    }
    rows!(
        IMU_RAW,
        MAG,
        BARO,
        GPS_FIX,
        LASER,
        SONAR,
        BATTERY,
        ODOM,
        STATE_IMU,
        TF,
        TF_STATIC,
        ALTITUDE,
        GROUND,
        STATUS,
        ACCEL_OBSERVER,
        ACCEL_MEASURED,
        DIAGNOSTICS,
        HOME,
        CLOCK,
        SETPOINT_VELOCITY,
        SETPOINT_HEADING,
        CMD_ARM,
        CMD_MODE,
        CMD_KILL,
        LINK_RAW_FRAMES
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_name_once_and_reads_are_best_effort() {
        let t = table();
        let mut names: Vec<&str> = t.iter().map(|r| r.0).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), t.len(), "a topic name is in the table twice");
        for (name, _, qos, dir) in &t {
            if *dir == Direction::Read {
                assert!(!qos.reliable, "{name}");
            } else {
                assert!(qos.reliable, "{name}");
            }
        }
        assert_eq!(STATUS.schema_name(), "fcc_msgs/msg/Status");
        assert_eq!(
            (TF.qos.depth, CLOCK.qos.depth, TF_STATIC.qos.depth),
            (100, 1, 1)
        );
        assert!(HOME.qos.transient_local && HOME.qos.reliable && HOME.qos.depth == 1);
    }

    /// The telemetry publisher profile is the one the bridge always used: reliable (fail when
    /// full), volatile, keep last 10.
    #[test]
    fn publisher_profile_from_the_table() {
        let want = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        assert_eq!(STATUS.qos.publisher_profile(), want);
        let want = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 });
        assert_eq!(TF_STATIC.qos.publisher_profile(), want);
    }
}
