//! `/diagnostics` (diagnostic_msgs/DiagnosticArray) from the bridge's state: statuses
//! `fcc_bridge: link`, `fcc_bridge: time sync`, `fcc_bridge: setpoints`, `fcc: vehicle` and
//! `fcc: sensors` (WARN while a sensor is unhealthy by the rules of [`crate::health`]),
//! `fcc_bridge: security` (with ROS 2 security on), and the link rates ([`RateMeter`]).

use crate::convert::Config;
use crate::health::{nav_fault_names, unhealthy};
use crate::state::{Handshake, LinkState};
use fcc_msgs as link;
use fcc_msgs::ros::*;
use fcc_ros::security_events::SecurityCounts;
use std::collections::BTreeMap;

/// The `fcc: sensors` diagnostic status: WARN while a sensor is unhealthy (see [`unhealthy`]).
pub fn sensors_status(
    s: &link::Status,
    ground_height_m: Option<f32>,
    cfg: &Config,
    hw: &str,
) -> DiagnosticStatus {
    let bad = unhealthy(s, ground_height_m, cfg);
    let names = [
        "GPS lost",
        "magnetometer disturbed",
        "laser not ok",
        "sonar not ok",
        "estimator fault",
    ];
    let problems: Vec<&str> = (0..names.len())
        .filter(|&i| bad[i])
        .map(|i| names[i])
        .collect();
    DiagnosticStatus {
        level: if problems.is_empty() {
            DiagnosticStatus::OK
        } else {
            DiagnosticStatus::WARN
        },
        name: "fcc: sensors".into(),
        message: if problems.is_empty() {
            "ok".into()
        } else {
            problems.join(", ")
        },
        hardware_id: hw.into(),
        values: vec![
            kv("gps_ok", s.sensors.gps_ok),
            kv("mag_disturbed", s.sensors.mag_disturbed),
            kv("mag_rejects", s.sensors.mag_rejects),
            kv("laser_ok", s.sensors.laser_ok),
            kv("sonar_ok", s.sensors.sonar_ok),
            kv("mag_disturbed_s", s.sensors.mag_disturbed_ds as f32 * 0.1),
            kv("nav_faults", nav_fault_names(s.sensors.nav_faults)),
            kv(
                "ground_height_m",
                ground_height_m.map_or(String::new(), |h| format!("{h:.2}")),
            ),
        ],
    }
}

/// Rates over the interval between two calls.
#[derive(Clone, Debug, Default)]
pub struct RateMeter {
    last_ns: Option<i64>,
    last_types: BTreeMap<&'static str, u64>,
    last_bytes: u64,
    last_frames: u64,
    last_crc: u64,
    /// Latest rates: per message type (Hz), bytes/s, frames/s.
    pub type_hz: BTreeMap<&'static str, f64>,
    pub bytes_per_s: f64,
    pub frames_per_s: f64,
    /// CRC errors in the last interval.
    pub crc_delta: u64,
}

impl RateMeter {
    pub fn update(&mut self, st: &LinkState, now_ns: i64) {
        let t = st.link_totals();
        if let Some(last) = self.last_ns {
            let dt = ((now_ns - last) as f64 * 1e-9).max(1e-3);
            self.type_hz = st
                .counters
                .rx_by_type
                .iter()
                .map(|(k, v)| {
                    (
                        *k,
                        (v - self.last_types.get(k).copied().unwrap_or(0)) as f64 / dt,
                    )
                })
                .collect();
            self.bytes_per_s = (t.rx_bytes - self.last_bytes) as f64 / dt;
            self.frames_per_s = (t.rx_frames - self.last_frames) as f64 / dt;
            self.crc_delta = t.crc_errors - self.last_crc;
        }
        self.last_ns = Some(now_ns);
        self.last_types = st.counters.rx_by_type.clone();
        self.last_bytes = t.rx_bytes;
        self.last_frames = t.rx_frames;
        self.last_crc = t.crc_errors;
    }
}

/// `fcc_bridge: link`: the serial link's health, counters and rates (ours and the MCU's).
fn link_status(
    st: &LinkState,
    rates: &RateMeter,
    device: &str,
    connected: bool,
) -> DiagnosticStatus {
    let t = st.link_totals();
    let c = &st.counters;
    let (level, message) = if !connected {
        (
            DiagnosticStatus::ERROR,
            "serial device not open".to_string(),
        )
    } else if st.handshake == Handshake::Waiting {
        (
            DiagnosticStatus::WARN,
            "waiting for the MCU's Hello".to_string(),
        )
    } else if rates.frames_per_s < 1.0 {
        (
            DiagnosticStatus::STALE,
            "no frames from the MCU".to_string(),
        )
    } else if rates.crc_delta > 0 {
        (
            DiagnosticStatus::WARN,
            format!("{} CRC errors in the last interval", rates.crc_delta),
        )
    } else {
        (DiagnosticStatus::OK, "ok".to_string())
    };
    let mut link_values = vec![
        kv("device", device),
        kv("connected", connected),
        kv(
            "handshake",
            match st.handshake {
                Handshake::Waiting => "waiting".to_string(),
                Handshake::Ok { firmware } => format!(
                    "ok (firmware {}.{}.{})",
                    firmware[0], firmware[1], firmware[2]
                ),
            },
        ),
        kv("protocol_version", fcc_msgs::PROTOCOL_VERSION),
        kv("schema_hash", format!("0x{:08x}", fcc_msgs::SCHEMA_HASH)),
        kv("rx_bytes_per_s", format!("{:.0}", rates.bytes_per_s)),
        kv("rx_frames_per_s", format!("{:.1}", rates.frames_per_s)),
        kv("rx_bytes", t.rx_bytes),
        kv("rx_frames", t.rx_frames),
        kv("crc_errors", t.crc_errors),
        kv("framing_errors", t.framing_errors),
        kv("overruns", t.overruns),
        kv("resyncs", t.resyncs),
        kv("decode_errors", t.decode_errors),
        kv("unknown_ids", t.unknown_ids),
        kv("version_errors", t.version_errors),
        kv("seq_gaps", t.seq_gaps),
        kv("frames_lost", t.frames_lost),
        kv("seq_resets", t.seq_resets),
        kv("dropped", c.dropped),
        kv("publish_errors", c.publish_errors),
        kv("reconnects", c.reconnects),
    ];
    for (k, hz) in &rates.type_hz {
        link_values.push(kv(&format!("rate_hz.{k}"), format!("{hz:.1}")));
    }
    if let Some(m) = &st.mcu_status {
        link_values.push(kv("mcu_rx_frames", m.link_rx.rx_frames));
        link_values.push(kv("mcu_crc_errors", m.link_rx.crc_errors));
        link_values.push(kv("mcu_resyncs", m.link_rx.resyncs));
        link_values.push(kv("mcu_frames_lost", m.link_rx.frames_lost));
        link_values.push(kv("mcu_tx_dropped", m.tx_dropped));
    }

    DiagnosticStatus {
        level,
        name: "fcc_bridge: link".into(),
        message,
        hardware_id: device.to_string(),
        values: link_values,
    }
}

/// `fcc_bridge: time sync`: the clock in use and the sync's offset and round trip.
fn sync_status(st: &LinkState, device: &str) -> DiagnosticStatus {
    let c = &st.counters;
    let ts = st.timesync.best();
    DiagnosticStatus {
        level: if ts.is_some() || st.clock == crate::state::ClockSource::Mcu {
            DiagnosticStatus::OK
        } else {
            DiagnosticStatus::WARN
        },
        name: "fcc_bridge: time sync".into(),
        message: match (st.clock, ts) {
            (crate::state::ClockSource::Mcu, _) => {
                "MCU clock used as ROS time (/clock published)".into()
            }
            (_, Some(_)) => "synced".into(),
            (_, None) => "not synced: stamping by arrival".into(),
        },
        hardware_id: device.to_string(),
        values: vec![
            kv(
                "offset_ns",
                ts.map_or("".into(), |s| s.offset_ns.to_string()),
            ),
            kv(
                "rtt_us",
                ts.map_or("".into(), |s| (s.rtt_ns / 1000).to_string()),
            ),
            kv("pongs_accepted", st.timesync.accepted),
            kv("pongs_rejected", st.timesync.rejected),
            kv("stamped_by_arrival", c.stamped_by_arrival),
        ],
    }
}

/// `fcc_bridge: setpoints`: setpoints and commands forwarded, shaped and refused.
fn setpoint_status(st: &LinkState, device: &str) -> DiagnosticStatus {
    let c = &st.counters;
    DiagnosticStatus {
        level: DiagnosticStatus::OK,
        name: "fcc_bridge: setpoints".into(),
        message: format!(
            "{} forwarded, {} refused",
            c.setpoints_forwarded, c.setpoint_rejects
        ),
        hardware_id: device.to_string(),
        values: vec![
            kv("setpoints_forwarded", c.setpoints_forwarded),
            // The uplink shaper (state::Uplink): sent to the MCU, replaced by a newer one
            // before their turn, dropped for a hold/land/disarm/kill sent after them.
            kv("setpoints_sent", st.uplink.sent),
            kv("setpoints_coalesced", st.uplink.coalesced),
            kv("setpoints_superseded", st.uplink.superseded),
            kv("setpoint_rejects", c.setpoint_rejects),
            kv("last_setpoint_reject", &c.last_setpoint_reject),
            kv("yaw_rate_setpoints", c.yaw_rate_setpoints),
            kv("heading_setpoints", c.heading_setpoints),
            kv("headings_received", c.headings_received),
            kv("commands_forwarded", c.commands_forwarded),
            kv("command_rejects", c.command_rejects),
            kv(
                "mcu_setpoint_rejects",
                st.mcu_status.map_or(0, |m| m.setpoint_rejects),
            ),
            kv(
                "mcu_command_rejects",
                st.mcu_status.map_or(0, |m| m.command_rejects),
            ),
        ],
    }
}

/// `fcc: vehicle`: the MCU's mode, arming and failsafe.
fn vehicle_status(m: &link::Status, device: &str) -> DiagnosticStatus {
    let (_, mode) = crate::convert::mode_code(m.mode);
    let (fs, fsn) = crate::convert::failsafe_code(m.failsafe);
    DiagnosticStatus {
        level: if fs == 0 {
            DiagnosticStatus::OK
        } else {
            DiagnosticStatus::WARN
        },
        name: "fcc: vehicle".into(),
        message: format!("{mode}, {}", if m.armed { "armed" } else { "disarmed" }),
        hardware_id: device.to_string(),
        values: vec![
            kv("mode", mode),
            kv("armed", m.armed),
            kv("landed", m.landed),
            kv("failsafe", fsn),
            kv("loop_time_max_us", m.loop_time_max_us),
            kv("loop_time_avg_us", m.loop_time_avg_us),
        ],
    }
}

/// `fcc_bridge: security` (with ROS 2 security on): what DDS Security refused — participants
/// that failed authentication, remote readers and writers denied by access control (each
/// counted once, [`fcc_ros::security_events`]); WARN once anything was refused.
pub fn security_status(c: &SecurityCounts, device: &str) -> DiagnosticStatus {
    let refused = c.participants_rejected + c.writers_denied + c.readers_denied;
    DiagnosticStatus {
        level: if refused == 0 {
            DiagnosticStatus::OK
        } else {
            DiagnosticStatus::WARN
        },
        name: "fcc_bridge: security".into(),
        message: if refused == 0 {
            "DDS Security on: nothing refused".into()
        } else {
            format!(
                "{} participants refused, {} writers and {} readers denied",
                c.participants_rejected, c.writers_denied, c.readers_denied
            )
        },
        hardware_id: device.to_string(),
        values: vec![
            kv("participants_rejected", c.participants_rejected),
            kv("writers_denied", c.writers_denied),
            kv("readers_denied", c.readers_denied),
            kv("last_event", c.last.as_deref().unwrap_or("")),
        ],
    }
}

fn kv(key: &str, value: impl ToString) -> KeyValue {
    KeyValue {
        key: key.into(),
        value: value.to_string(),
    }
}

/// Build the diagnostics array.
pub fn diagnostics(
    st: &LinkState,
    rates: &RateMeter,
    device: &str,
    connected: bool,
    stamp: Time,
) -> DiagnosticArray {
    let mut status = vec![
        link_status(st, rates, device, connected),
        sync_status(st, device),
        setpoint_status(st, device),
    ];
    if let Some(m) = &st.mcu_status {
        status.push(vehicle_status(m, device));
        status.push(sensors_status(m, st.ground_height_m, &st.cfg, device));
    }
    DiagnosticArray {
        header: Header::new(stamp, ""),
        status,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn security_status_warns_once_anything_was_refused() {
        let quiet = security_status(&SecurityCounts::default(), "/dev/x");
        assert_eq!(quiet.level, DiagnosticStatus::OK);
        let mut c = SecurityCounts::default();
        c.participants_rejected = 2;
        c.writers_denied = 1;
        let s = security_status(&c, "/dev/x");
        assert_eq!(s.level, DiagnosticStatus::WARN);
        assert_eq!(s.name, "fcc_bridge: security");
        assert!(
            s.message.contains("2 participants refused, 1 writers"),
            "{}",
            s.message
        );
        let v = |k: &str| {
            s.values
                .iter()
                .find(|kv| kv.key == k)
                .unwrap()
                .value
                .clone()
        };
        assert_eq!(
            (v("participants_rejected"), v("writers_denied")),
            ("2".into(), "1".into())
        );
    }
}
