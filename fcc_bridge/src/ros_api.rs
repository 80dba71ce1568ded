//! The bridge's ROS 2 "citizen" interfaces on top of ros2-client: ROS parameters (the
//! `rcl_interfaces` services started by ros2-client, with our validator), `std_srvs` services
//! (`arm` SetBool, `land` / `hold` Trigger) answered after the MCU's acknowledgement, and a
//! `tracing` layer that forwards the bridge's log events to `/rosout` with their level.

use crate::mcu_params;
use ros2_client::parameters::ParameterValue;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;
use tokio::sync::{mpsc, oneshot};

// --------------------------------------------------------------------------- std_srvs types

/// `std_srvs/srv/SetBool` request.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct SetBoolRequest {
    pub data: bool,
}
/// `std_srvs/srv/SetBool` response.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct SetBoolResponse {
    pub success: bool,
    pub message: String,
}
/// `std_srvs/srv/Trigger` request (empty; rmw serialises one dummy byte, as here).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct TriggerRequest {
    pub structure_needs_at_least_one_member: u8,
}
/// `std_srvs/srv/Trigger` response.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct TriggerResponse {
    pub success: bool,
    pub message: String,
}
impl ros2_client::Message for SetBoolRequest {}
impl ros2_client::Message for SetBoolResponse {}
impl ros2_client::Message for TriggerRequest {}
impl ros2_client::Message for TriggerResponse {}

/// How long a service or parameter set waits for the MCU's acknowledgement.
pub const ACK_TIMEOUT: Duration = Duration::from_millis(1000);

// --------------------------------------------------------------------------- requests to the link task

/// A request from the ROS side that the link task must forward and answer.
#[derive(Debug)]
pub enum LinkRequest {
    /// Send a command; answer (accepted, message) when its `CommandAck` arrives.
    Command(fcc_msgs::CommandKind, oneshot::Sender<(bool, String)>),
    /// Send a `ParamSet`; answer Ok(value in use) or Err(reason) from the `ParamAck`.
    ParamSet(u16, f32, std::sync::mpsc::Sender<Result<f32, String>>),
    /// A bridge parameter changed (name, value), already validated.
    BridgeParam(String, ParameterValue),
}

// --------------------------------------------------------------------------- parameters

/// Kind of a bridge parameter's ROS value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Integer,
    Double,
}

/// One numeric bridge parameter: the ONE table its start-up (`-p`, `--params-file`) check, the
/// run-time validator (`ros2 param set`) and its ROS descriptor are derived from. Every range is
/// what is physically safe (issue 14): finite, strictly positive, bounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BridgeParam {
    pub name: &'static str,
    pub kind: Kind,
    pub default: f64,
    pub min: f64,
    pub max: f64,
    pub unit: &'static str,
    /// Can be changed at run time (else read-only after start).
    pub dynamic: bool,
    pub description: &'static str,
}

/// The bridge's numeric parameters. `ttl_ms` uses the link's range, which the MCU enforces on
/// every setpoint too ([`fcc_msgs::SETPOINT_TTL_MS_MIN`] / `_MAX`).
pub const BRIDGE_PARAMS: &[BridgeParam] = &[
    BridgeParam {
        name: "ttl_ms",
        kind: Kind::Integer,
        default: 300.0,
        min: fcc_msgs::SETPOINT_TTL_MS_MIN as f64,
        max: fcc_msgs::SETPOINT_TTL_MS_MAX as f64,
        unit: "ms",
        dynamic: true,
        description:
            "time-to-live of each velocity setpoint on the MCU (its stale-setpoint failsafe)",
    },
    BridgeParam {
        name: "max_speed_mps",
        kind: Kind::Double,
        default: 20.0,
        min: 0.1,
        max: 30.0,
        unit: "m/s",
        dynamic: true,
        description: "setpoints faster than this on any axis are refused",
    },
    BridgeParam {
        name: "max_stamp_age_ms",
        kind: Kind::Double,
        default: 500.0,
        min: 10.0,
        max: 5000.0,
        unit: "ms",
        dynamic: true,
        description: "setpoints stamped longer ago than this are refused",
    },
    BridgeParam {
        name: "max_stamp_future_ms",
        kind: Kind::Double,
        default: 500.0,
        min: 10.0,
        max: 5000.0,
        unit: "ms",
        dynamic: true,
        description: "setpoints stamped further in the future than this are refused",
    },
    BridgeParam {
        name: "ping_period_ms",
        kind: Kind::Integer,
        default: 1000.0,
        min: 100.0,
        max: 10000.0,
        unit: "ms",
        dynamic: false,
        description: "period of the link's time-sync pings",
    },
];

/// The table entry of a bridge parameter.
pub fn bridge_param(name: &str) -> Option<&'static BridgeParam> {
    BRIDGE_PARAMS.iter().find(|p| p.name == name)
}

impl BridgeParam {
    /// `[min, max] unit`, as the refusals print it.
    pub fn range_text(&self) -> String {
        format!("[{}, {}] {}", self.min, self.max, self.unit)
    }

    /// The value if it is finite, inside the range and (for an integer) whole; else the reason
    /// with the range.
    pub fn check(&self, x: f64) -> Result<f64, String> {
        let whole = self.kind == Kind::Double || x.fract() == 0.0;
        if x.is_finite() && whole && x >= self.min && x <= self.max {
            Ok(x)
        } else {
            Err(format!(
                "{}: {x:?} out of range {}{}",
                self.name,
                self.range_text(),
                if whole { "" } else { " (an integer)" }
            ))
        }
    }

    /// [`Self::check`] on a ROS value (an integer parameter takes only integers).
    pub fn check_value(&self, v: &ParameterValue) -> Result<f64, String> {
        match (self.kind, v) {
            (Kind::Integer, ParameterValue::Integer(i)) => self.check(*i as f64),
            (Kind::Double, ParameterValue::Double(d)) => self.check(*d),
            (Kind::Double, ParameterValue::Integer(i)) => self.check(*i as f64),
            _ => Err(format!(
                "{}: expected {} in {}",
                self.name,
                if self.kind == Kind::Integer {
                    "an integer"
                } else {
                    "a number"
                },
                self.range_text()
            )),
        }
    }

    /// A start-up (`-p` / `--params-file`) text value, checked.
    pub fn parse(&self, v: &str) -> Result<f64, String> {
        let x = v.trim().parse::<f64>().map_err(|_| {
            format!(
                "{}: '{v}' is not a number in {}",
                self.name,
                self.range_text()
            )
        })?;
        self.check(x)
    }

    /// The ROS parameter descriptor (type, range, description with unit, read-only) derived
    /// from the table, as `describe_parameters` answers it ([`describe`]).
    pub fn descriptor(&self) -> ros2_client::parameters::ParameterDescriptor {
        use ros2_client::parameters::{NumericRange, ParameterDescriptor, ParameterType};
        ParameterDescriptor {
            name: self.name.to_string(),
            param_type: match self.kind {
                Kind::Integer => ParameterType::Integer,
                Kind::Double => ParameterType::Double,
            },
            description: format!("{} ({})", self.description, self.unit),
            additional_constraints: format!("finite, in {}", self.range_text()),
            read_only: !self.dynamic,
            dynamic_typing: false,
            range: match self.kind {
                Kind::Integer => NumericRange::IntegerRange {
                    from_value: self.min as i64,
                    to_value: self.max as i64,
                    step: 1,
                },
                Kind::Double => NumericRange::FloatingPointRange {
                    from_value: self.min,
                    to_value: self.max,
                    step: 0.0,
                },
            },
        }
    }
}

/// The bridge's other parameters (not numeric, not the MCU's): set at start-up (`-p`,
/// `--params-file`) and read-only at run time ([`check_bridge_param`] refuses a live set of
/// any name outside [`BRIDGE_PARAMS`]), with what `describe_parameters` says of each.
pub const STARTUP_PARAMS: &[(&str, &str)] = &[
    (
        "clock_source",
        "stamp clock: sync (MCU time mapped to the Linux clock by the link's time sync) | mcu \
         (MCU time as ROS time; the bridge publishes /clock)",
    ),
    (
        "localhost_only",
        "DDS on loopback only (default; also from ROS_LOCALHOST_ONLY and \
         ROS_AUTOMATIC_DISCOVERY_RANGE)",
    ),
    ("record", "MCAP bag of every topic (path; empty = off)"),
    ("map_frame", "world frame (ENU, origin = home; REP-105 map)"),
    (
        "odom_frame",
        "odometry frame (ENU; REP-105 odom, identity under map: the estimate is GPS-referenced)",
    ),
    ("base_frame", "body frame (FLU; REP-105 base_link)"),
    (
        "imu_frame",
        "frame of imu/data_raw (FLU, aligned with the body)",
    ),
    ("mag_frame", "frame of mag (FLU, aligned with the body)"),
    ("baro_frame", "frame of baro"),
    ("gps_frame", "frame of gps/fix"),
    (
        "laser_frame",
        "frame of range/laser (x along the beam, down)",
    ),
    (
        "sonar_frame",
        "frame of range/sonar (x along the beam, down)",
    ),
];

/// `use_sim_time`'s descriptor text (ros2-client keeps that parameter itself; settable).
const USE_SIM_TIME_TEXT: &str = "stamp with /clock instead of the Linux clock (with \
     clock_source:=sync; with clock_source:=mcu the bridge is the clock)";

/// What `describe_parameters` answers for `name` (ros2-client's describer hook): the MCU
/// parameters from their table ([`mcu_params::descriptor`]), the numeric bridge parameters from
/// [`BRIDGE_PARAMS`], `use_sim_time`, and the read-only [`STARTUP_PARAMS`]. `None` for a name
/// the node does not declare. The type is filled in by ros2-client from the value.
pub fn describe(name: &str) -> Option<ros2_client::parameters::ParameterDescriptor> {
    use ros2_client::parameters::{NumericRange, ParameterDescriptor, ParameterType};
    if let Some(p) = mcu_params::by_name(name) {
        return Some(mcu_params::descriptor(p));
    }
    if let Some(p) = bridge_param(name) {
        return Some(p.descriptor());
    }
    let (description, read_only) = if name == "use_sim_time" {
        (USE_SIM_TIME_TEXT, false)
    } else {
        (STARTUP_PARAMS.iter().find(|(n, _)| *n == name)?.1, true)
    };
    Some(ParameterDescriptor {
        name: name.to_string(),
        param_type: ParameterType::NotSet,
        description: description.to_string(),
        additional_constraints: if read_only {
            "set at start-up (-p / --params-file); read-only at run time".into()
        } else {
            String::new()
        },
        read_only,
        dynamic_typing: false,
        range: NumericRange::NotSpecified,
    })
}

/// Bridge parameters that can be changed at run time (the rest are read-only after start):
/// the `dynamic` entries of [`BRIDGE_PARAMS`] (a test keeps the two equal).
pub const DYNAMIC_BRIDGE_PARAMS: [&str; 4] = [
    "ttl_ms",
    "max_speed_mps",
    "max_stamp_age_ms",
    "max_stamp_future_ms",
];

/// State shared between the parameter validator (ros2-client's spinner thread) and the link task.
pub struct ParamShared {
    /// False while the node is being created (declared values are only range-checked).
    pub live: AtomicBool,
    /// The MCU's value of each MCU parameter, as last acknowledged.
    pub mcu_values: Mutex<BTreeMap<u16, f32>>,
    pub link: mpsc::Sender<LinkRequest>,
    /// The serial link's baud: `rates.*` sets are checked against its budget.
    pub baud: u32,
}

pub fn as_f64(v: &ParameterValue) -> Option<f64> {
    match v {
        ParameterValue::Double(d) => Some(*d),
        ParameterValue::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Validate a bridge (non-MCU) parameter value: the numeric ones against [`BRIDGE_PARAMS`],
/// the others are read-only once the node is up.
pub fn check_bridge_param(name: &str, v: &ParameterValue, live: bool) -> Result<(), String> {
    match bridge_param(name) {
        Some(p) if live && !p.dynamic => Err(format!(
            "{name} is read-only (set it at start-up with -p, range {})",
            p.range_text()
        )),
        Some(p) => p.check_value(v).map(|_| ()),
        None if live => Err(format!("{name} is read-only (set it at start-up with -p)")),
        None => Ok(()),
    }
}

/// A telemetry rate set live: a lower rate is always taken (it only frees the line); a higher one
/// must keep the worst case within the budget of `--baud`, the other streams at the MCU's values.
fn check_rate_budget(
    shared: &ParamShared,
    id: u16,
    value: f32,
) -> Result<(), mcu_params::OverBudget> {
    let values = shared.mcu_values.lock().unwrap().clone();
    let current = values
        .get(&id)
        .copied()
        .or_else(|| mcu_params::by_id(id).map(|p| p.default));
    if current.is_some_and(|c| value <= c) {
        return Ok(());
    }
    let with_new = |i: u16| {
        if i == id {
            Some(value)
        } else {
            values.get(&i).copied()
        }
    };
    mcu_params::check_link_budget(with_new, shared.baud).map(|_| ())
}

/// The ros2-client validator: range checks; an MCU parameter that differs from the MCU's
/// value is sent to the MCU and the set succeeds only when the MCU accepts it (this blocks the
/// spinner thread for at most [`ACK_TIMEOUT`]).
pub fn validate(shared: &ParamShared, name: &str, v: &ParameterValue) -> Result<(), String> {
    let live = shared.live.load(Ordering::SeqCst);
    let Some(p) = mcu_params::by_name(name) else {
        return check_bridge_param(name, v, live);
    };
    let x = as_f64(v).ok_or_else(|| format!("{name}: expected a number"))?;
    p.check(x).map_err(|e| e.to_string())?;
    let value = x as f32;
    // At start-up (not live) the node declares its parameters one by one; the start-up rates
    // were checked as one set against --baud before (`main.rs`).
    if !live {
        return Ok(());
    }
    // The MCU's own value (the bridge mirroring an acknowledgement, or a set to what is in use).
    if shared.mcu_values.lock().unwrap().get(&p.id) == Some(&value) {
        return Ok(());
    }
    if fcc_msgs::Stream::by_param_id(p.id).is_some() {
        check_rate_budget(shared, p.id, value).map_err(|e| format!("{name} {x} refused: {e}"))?;
    }
    let (tx, rx) = std::sync::mpsc::channel();
    shared
        .link
        .try_send(LinkRequest::ParamSet(p.id, value, tx))
        .map_err(|_| "bridge busy".to_string())?;
    match rx.recv_timeout(ACK_TIMEOUT) {
        Ok(Ok(_)) => Ok(()),
        Ok(Err(reason)) => Err(reason),
        Err(_) => Err(format!(
            "{name}: the MCU did not acknowledge within {} ms",
            ACK_TIMEOUT.as_millis()
        )),
    }
}

// --------------------------------------------------------------------------- /rosout from tracing

/// A log event for `/rosout`: (level, message, file, line).
pub type RosLog = (ros2_client::log::LogLevel, String, String, u32);

static ROSOUT_TX: OnceLock<std::sync::mpsc::SyncSender<RosLog>> = OnceLock::new();

/// The receiving end of the rosout forwarder (call once; the bridge drains it).
pub fn rosout_channel() -> Option<std::sync::mpsc::Receiver<RosLog>> {
    let (tx, rx) = std::sync::mpsc::sync_channel(256);
    ROSOUT_TX.set(tx).ok().map(|_| rx)
}

/// A `tracing` layer forwarding events of the `fcc_bridge` targets (INFO and above) to the
/// channel from [`rosout_channel`]; events are dropped if nobody drains it.
pub struct RosoutLayer;

struct MsgVisitor(String);
impl tracing::field::Visit for MsgVisitor {
    fn record_debug(&mut self, f: &tracing::field::Field, v: &dyn std::fmt::Debug) {
        if f.name() == "message" {
            self.0 = format!("{v:?}");
        } else {
            self.0.push_str(&format!(" {}={v:?}", f.name()));
        }
    }
    fn record_str(&mut self, f: &tracing::field::Field, v: &str) {
        if f.name() == "message" {
            self.0 = v.to_string();
        } else {
            self.0.push_str(&format!(" {}={v}", f.name()));
        }
    }
}

impl<S: tracing::Subscriber> tracing_subscriber::Layer<S> for RosoutLayer {
    fn on_event(&self, e: &tracing::Event<'_>, _: tracing_subscriber::layer::Context<'_, S>) {
        let m = e.metadata();
        if !m.target().starts_with("fcc_bridge") || *m.level() > tracing::Level::INFO {
            return;
        }
        let Some(tx) = ROSOUT_TX.get() else { return };
        use ros2_client::log::LogLevel;
        let level = match *m.level() {
            tracing::Level::ERROR => LogLevel::Error,
            tracing::Level::WARN => LogLevel::Warn,
            _ => LogLevel::Info,
        };
        let mut v = MsgVisitor(String::new());
        e.record(&mut v);
        let _ = tx.try_send((
            level,
            v.0,
            m.file().unwrap_or("").to_string(),
            m.line().unwrap_or(0),
        ));
    }
}

/// Shared handle type of the parameter state.
pub type Shared = Arc<ParamShared>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The slow-link start-up (launch_configs/slow_link_115200.yaml at --baud 115200): the MCU
    /// acknowledges the profile's rates one by one while the others are still at their
    /// defaults (far over the budget). Lowering a rate is always taken, the bridge's mirror of
    /// an acknowledged value too; raising one over the budget is refused.
    #[test]
    fn lower_rates_pass_the_budget_one_by_one() {
        let (tx, _rx) = mpsc::channel(4);
        let sh = ParamShared {
            live: AtomicBool::new(true),
            mcu_values: Mutex::new(BTreeMap::new()),
            link: tx,
            baud: 115_200,
        };
        let id = |n: &str| mcu_params::by_name(n).unwrap().id;
        for (name, hz) in [("rates.gps_hz", 5.0), ("rates.battery_hz", 2.0)] {
            assert!(check_rate_budget(&sh, id(name), hz).is_ok(), "{name} {hz}");
            sh.mcu_values.lock().unwrap().insert(id(name), hz);
            assert!(
                validate(&sh, name, &ParameterValue::Integer(hz as i64)).is_ok(),
                "{name} mirror"
            );
        }
        assert!(check_rate_budget(&sh, id("rates.imu_hz"), 400.0).is_err());
    }

    #[test]
    fn validator_ranges_and_read_only() {
        let (tx, mut rx) = mpsc::channel(4);
        let sh = ParamShared {
            live: AtomicBool::new(false),
            mcu_values: Mutex::new(BTreeMap::new()),
            link: tx,
            baud: 460_800,
        };
        let d = ParameterValue::Double;
        assert!(validate(&sh, "limits.max_tilt_deg", &d(30.0)).is_ok());
        let e = validate(&sh, "limits.max_tilt_deg", &d(80.0)).unwrap_err();
        assert!(e.contains("out of range"), "{e}");
        assert!(validate(&sh, "ttl_ms", &ParameterValue::Integer(0)).is_err());
        assert!(validate(&sh, "clock_source", &ParameterValue::String("mcu".into())).is_ok());
        sh.live.store(true, Ordering::SeqCst);
        // Live: a rate the link can carry passes the budget; one it cannot is refused with it.
        let imu = fcc_msgs::param_id::RATES_IMU_HZ;
        assert!(check_rate_budget(&sh, imu, 1000.0).is_ok());
        sh.mcu_values.lock().unwrap().insert(imu, 1000.0);
        let e = validate(&sh, "rates.nav_state_hz", &ParameterValue::Integer(500)).unwrap_err();
        assert!(
            e.starts_with("rates.nav_state_hz 500 refused: the telemetry would need up to "),
            "{e}"
        );
        assert!(
            e.contains("% of the 46080 B/s a 460800-baud link carries (budget 90 %)"),
            "{e}"
        );
        assert!(validate(&sh, "clock_source", &ParameterValue::String("mcu".into())).is_err());
        // Live: the same value as the MCU's passes without a link round trip …
        sh.mcu_values
            .lock()
            .unwrap()
            .insert(fcc_msgs::param_id::MAX_TILT_DEG, 30.0);
        assert!(validate(&sh, "limits.max_tilt_deg", &d(30.0)).is_ok());
        // … another value goes to the link task and its answer decides.
        let h = std::thread::spawn(move || {
            let LinkRequest::ParamSet(id, v, reply) = rx.blocking_recv().unwrap() else {
                panic!()
            };
            assert_eq!((id, v), (fcc_msgs::param_id::MAX_TILT_DEG, 35.0));
            reply.send(Err("MCU refused".into())).unwrap();
        });
        assert_eq!(
            validate(&sh, "limits.max_tilt_deg", &d(35.0)).unwrap_err(),
            "MCU refused"
        );
        h.join().unwrap();
    }

    /// `describe_parameters` (ros2-client's describer hook) has a descriptor for every
    /// parameter the node declares, with a description; its `read_only` is what the validator
    /// enforces live; numeric ones carry their table's range and unit.
    #[test]
    fn every_declared_parameter_is_described() {
        use ros2_client::parameters::NumericRange;
        let (tx, _rx) = mpsc::channel(4);
        let sh = ParamShared {
            live: AtomicBool::new(true),
            mcu_values: Mutex::new(BTreeMap::new()),
            link: tx,
            baud: 921_600,
        };
        let declared = crate::bridge::declared_parameters(&crate::bridge::Options::default());
        assert!(declared.len() > MCU_PARAM_COUNT + BRIDGE_PARAMS.len());
        for (name, value) in &declared {
            let d = describe(name).unwrap_or_else(|| panic!("{name}: no descriptor"));
            assert_eq!(d.name, *name);
            assert!(!d.description.is_empty(), "{name}");
            // Live, a read-only parameter is refused and a writable one is not refused for
            // being read-only (use_sim_time is ros2-client's own and never reaches the
            // validator; MCU parameters would wait for the MCU here, so only the table is used).
            if *name != "use_sim_time" && mcu_params::by_name(name).is_none() {
                let refused = validate(&sh, name, value)
                    .err()
                    .is_some_and(|e| e.contains("read-only"));
                assert_eq!(d.read_only, refused, "{name}: read_only vs the validator");
            }
            match (bridge_param(name), mcu_params::by_name(name)) {
                (Some(p), _) => {
                    assert!(d.description.contains(p.unit), "{name}: {}", d.description);
                    assert!(!matches!(d.range, NumericRange::NotSpecified), "{name}");
                }
                (_, Some(p)) => {
                    assert!(d.description.contains(p.unit), "{name}: {}", d.description);
                    let range_ok = match d.range {
                        NumericRange::FloatingPointRange {
                            from_value,
                            to_value,
                            ..
                        } => from_value == p.min as f64 && to_value == p.max as f64,
                        NumericRange::IntegerRange {
                            from_value,
                            to_value,
                            ..
                        } => from_value == p.min as i64 && to_value == p.max as i64,
                        _ => false,
                    };
                    assert!(range_ok, "{name}");
                    // The declared value has the descriptor's type.
                    assert_eq!(
                        matches!(value, ParameterValue::Integer(_)),
                        mcu_params::is_integer(p),
                        "{name}"
                    );
                    assert!(!d.read_only, "{name}");
                }
                _ => assert!(matches!(d.range, NumericRange::NotSpecified), "{name}"),
            }
        }
        assert!(describe("use_sim_time").is_some_and(|d| !d.read_only));
        assert!(describe("clock_source").is_some_and(|d| d.read_only));
        assert!(describe("not_a_parameter").is_none());
    }

    const MCU_PARAM_COUNT: usize = mcu_params::MCU_PARAMS.len();

    #[test]
    fn bridge_param_table_is_safe() {
        for p in BRIDGE_PARAMS {
            assert!(
                p.min.is_finite() && p.max.is_finite() && p.min > 0.0 && p.min < p.max,
                "{p:?}"
            );
            assert!(p.check(p.default).is_ok(), "default of {} in range", p.name);
            assert!(
                p.check(p.min).is_ok() && p.check(p.max).is_ok(),
                "{}",
                p.name
            );
            for bad in [
                -0.0,
                0.0,
                5e-324,
                -1.0,
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
                p.max * 1.001,
            ] {
                let e = p.check(bad).unwrap_err();
                assert!(e.contains(&p.range_text()) && e.starts_with(p.name), "{e}");
            }
        }
        // The table's defaults are the ones in use.
        let l = crate::convert::SetpointLimits::default();
        let def = |n: &str| bridge_param(n).unwrap().default;
        assert_eq!(def("ttl_ms"), l.ttl_ms as f64);
        assert_eq!(def("max_speed_mps"), l.max_speed_mps);
        assert_eq!(def("max_stamp_age_ms"), l.max_age_ns as f64 / 1e6);
        assert_eq!(def("max_stamp_future_ms"), l.max_future_ns as f64 / 1e6);
        let dynamic: Vec<&str> = BRIDGE_PARAMS
            .iter()
            .filter(|p| p.dynamic)
            .map(|p| p.name)
            .collect();
        assert_eq!(dynamic, DYNAMIC_BRIDGE_PARAMS);
        // The setpoint TTL: a few seconds at most, the link's (and the MCU's) range.
        let ttl = bridge_param("ttl_ms").unwrap();
        assert_eq!((ttl.min, ttl.max), (50.0, 3000.0));
        assert_eq!(
            ttl.check(65535.0).unwrap_err(),
            "ttl_ms: 65535.0 out of range [50, 3000] ms"
        );
        assert!(ttl.check(300.5).unwrap_err().contains("an integer"));
        assert_eq!(ttl.parse(" 500 "), Ok(500.0));
        assert!(ttl.parse("fast").unwrap_err().contains("[50, 3000] ms"));
        let e = bridge_param("max_speed_mps")
            .unwrap()
            .check(5e-324)
            .unwrap_err();
        assert_eq!(e, "max_speed_mps: 5e-324 out of range [0.1, 30] m/s");
        let e = bridge_param("max_stamp_age_ms")
            .unwrap()
            .check(-0.0)
            .unwrap_err();
        assert_eq!(e, "max_stamp_age_ms: -0.0 out of range [10, 5000] ms");
        // The validator (start-up and live) uses the same table; types are checked.
        use ParameterValue as V;
        assert!(check_bridge_param("ttl_ms", &V::Integer(65535), true).is_err());
        assert!(check_bridge_param("ttl_ms", &V::Integer(0), false).is_err());
        assert!(check_bridge_param("ttl_ms", &V::Integer(500), true).is_ok());
        assert!(check_bridge_param("ttl_ms", &V::Double(500.0), true).is_err());
        assert!(check_bridge_param("max_speed_mps", &V::Double(-0.0), true).is_err());
        assert!(check_bridge_param("max_speed_mps", &V::Integer(5), true).is_ok());
        assert!(check_bridge_param("max_stamp_future_ms", &V::Double(f64::NAN), true).is_err());
        assert!(check_bridge_param("ping_period_ms", &V::Integer(1000), false).is_ok());
        assert!(check_bridge_param("ping_period_ms", &V::Integer(5), false).is_err());
        let e = check_bridge_param("ping_period_ms", &V::Integer(1000), true).unwrap_err();
        assert!(
            e.contains("read-only") && e.contains("[100, 10000] ms"),
            "{e}"
        );
        // Descriptors carry the same ranges.
        use ros2_client::parameters::NumericRange;
        let d = ttl.descriptor();
        assert!(matches!(
            d.range,
            NumericRange::IntegerRange {
                from_value: 50,
                to_value: 3000,
                step: 1
            }
        ));
        assert!(!d.read_only);
        let d = bridge_param("max_speed_mps").unwrap().descriptor();
        assert!(
            matches!(d.range, NumericRange::FloatingPointRange { from_value, to_value, .. }
            if from_value == 0.1 && to_value == 30.0)
        );
        assert!(
            bridge_param("ping_period_ms")
                .unwrap()
                .descriptor()
                .read_only
        );
    }
}
