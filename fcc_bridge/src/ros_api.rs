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

/// Bridge parameters that can be changed at run time (the rest are read-only after start).
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
}

pub fn as_f64(v: &ParameterValue) -> Option<f64> {
    match v {
        ParameterValue::Double(d) => Some(*d),
        ParameterValue::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Validate a bridge (non-MCU) parameter value.
pub fn check_bridge_param(name: &str, v: &ParameterValue, live: bool) -> Result<(), String> {
    let num = |lo: f64, hi: f64| -> Result<(), String> {
        match as_f64(v) {
            Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(()),
            Some(x) => Err(format!("{name}: {x} out of range [{lo}, {hi}]")),
            None => Err(format!("{name}: expected a number")),
        }
    };
    match name {
        "ttl_ms" => num(1.0, 65535.0),
        "max_speed_mps" => num(0.0, 100.0),
        "max_stamp_age_ms" | "max_stamp_future_ms" => num(0.0, 3.6e6),
        _ if live => Err(format!("{name} is read-only (set it at start-up with -p)")),
        _ => Ok(()),
    }
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
    p.check(x)?;
    if !live {
        return Ok(());
    }
    let value = x as f32;
    if shared.mcu_values.lock().unwrap().get(&p.id) == Some(&value) {
        return Ok(());
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

/// The ROS logger name of a node: `ns.name` without the leading slash (as rcl does).
pub fn logger_name(namespace: &str, node: &str) -> String {
    let ns = namespace.trim_matches('/').replace('/', ".");
    if ns.is_empty() {
        node.to_string()
    } else {
        format!("{ns}.{node}")
    }
}

/// Shared handle type of the parameter state.
pub type Shared = Arc<ParamShared>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validator_ranges_and_read_only() {
        let (tx, mut rx) = mpsc::channel(4);
        let sh = ParamShared {
            live: AtomicBool::new(false),
            mcu_values: Mutex::new(BTreeMap::new()),
            link: tx,
        };
        let d = ParameterValue::Double;
        assert!(validate(&sh, "limits.max_tilt_deg", &d(30.0)).is_ok());
        let e = validate(&sh, "limits.max_tilt_deg", &d(80.0)).unwrap_err();
        assert!(e.contains("out of range"), "{e}");
        assert!(validate(&sh, "ttl_ms", &ParameterValue::Integer(0)).is_err());
        assert!(validate(&sh, "clock_source", &ParameterValue::String("mcu".into())).is_ok());
        sh.live.store(true, Ordering::SeqCst);
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
        assert_eq!(logger_name("/uav1", "fcc_bridge"), "uav1.fcc_bridge");
    }
}
