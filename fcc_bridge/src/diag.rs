//! `/diagnostics` (diagnostic_msgs/DiagnosticArray) from the bridge's state, and the sensor-health
//! rules: statuses `fcc_bridge: link`, `fcc_bridge: time sync`, `fcc_bridge: setpoints`,
//! `fcc: vehicle` and `fcc: sensors` (WARN while GPS is lost, the magnetometer is disturbed, the
//! laser / sonar gives no valid reading while it should see the ground, or a navigation filter
//! diverged); [`SensorWatch`]
//! turns the same rules into one `/rosout` WARN per episode and an INFO on recovery.

use crate::convert::Config;
use crate::ros_types::*;
use crate::state::{Handshake, LinkState};
use fcc_msgs as link;
use std::collections::BTreeMap;

/// The sensors whose health the MCU reports on `Status`.
pub const SENSORS: [&str; 5] = ["gps", "mag", "laser", "sonar", "estimator"];

/// After a sensor was reported unhealthy, it is reported healthy again only once it stayed
/// healthy this long (MCU time): a flag that flickers (a magnetometer near the innovation gate)
/// gives one WARN, not one per status frame.
pub const SENSOR_RECOVERY_HOLD_US: u64 = 2_000_000;

/// Which sensors are unhealthy in an MCU status, in [`SENSORS`] order. GPS: no fresh fix;
/// magnetometer: rejected by the attitude filter (disturbance). A rangefinder counts only while
/// it should see the ground: armed, in the air, and the estimated height above ground within its
/// range (0.5 m margin; a NaN height counts as in range) — a laser below its minimum range on
/// the ground, or a sonar above its 10 m, is no fault.
pub fn unhealthy(s: &link::Status, ground_height_m: Option<f32>, cfg: &Config) -> [bool; 5] {
    let flying = s.armed && !s.landed;
    let in_range = |min: f32, max: f32| match ground_height_m {
        Some(h) if h.is_finite() => h >= min + 0.5 && h <= max - 0.5,
        _ => true,
    };
    [
        !s.sensors.gps_ok,
        s.sensors.mag_disturbed,
        flying && in_range(cfg.laser.min_m, cfg.laser.max_m) && !s.sensors.laser_ok,
        flying && in_range(cfg.sonar.min_m, cfg.sonar.max_m) && !s.sensors.sonar_ok,
        s.sensors.nav_faults != 0,
    ]
}

fn problem_text(i: usize, s: &link::Status, ground_height_m: Option<f32>) -> String {
    let agl = ground_height_m
        .filter(|h| h.is_finite())
        .map_or(String::new(), |h| format!(" at {h:.1} m above ground"));
    match i {
        0 => "GPS lost (no fresh fix: the MCU navigates on baro/accel; in flight it lands)".into(),
        1 => format!(
            "magnetometer disturbed (rejected by the attitude filter for {:.1} s, {} readings so far): yaw on the gyro",
            s.sensors.mag_disturbed_ds as f32 * 0.1,
            s.sensors.mag_rejects
        ),
        2 => format!("laser altimeter gives no valid reading{agl} (dark surface or failure): ground altitude on the sonar"),
        4 => format!(
            "estimator fault: {} filter diverged (innovations beyond their gate): the MCU holds, then lands",
            nav_fault_names(s.sensors.nav_faults)
        ),
        _ => format!("ultrasonic rangefinder gives no valid reading{agl}: ground altitude on the laser"),
    }
}

/// The filters named by the `nav_faults` bits (`fcc_firmware::nav_health`).
pub fn nav_fault_names(bits: u8) -> String {
    let names: Vec<&str> = [(1u8, "vertical"), (2, "horizontal"), (4, "attitude")]
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| *n)
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join("+")
    }
}

fn recovery_text(i: usize, s: &link::Status) -> String {
    match i {
        0 => "GPS ok again".into(),
        1 => format!(
            "magnetometer ok again ({} readings rejected since start)",
            s.sensors.mag_rejects
        ),
        4 => "estimator faults cleared (at arming)".into(),
        2 if s.sensors.laser_ok => "laser altimeter ok again".into(),
        2 => {
            "laser altimeter: no longer expected to see the ground (landed or out of range)".into()
        }
        _ if s.sensors.sonar_ok => "ultrasonic rangefinder ok again".into(),
        _ => {
            "ultrasonic rangefinder: no longer expected to see the ground (landed or out of range)"
                .into()
        }
    }
}

/// Sensor-health transitions for `/rosout`: a WARN once when a sensor becomes unhealthy, an
/// INFO when it has been healthy for [`SENSOR_RECOVERY_HOLD_US`].
#[derive(Clone, Debug, Default)]
pub struct SensorWatch {
    /// Per sensor: reported unhealthy (WARN sent, no INFO yet).
    pub reported: [bool; 5],
    /// Per sensor: MCU time it was last seen unhealthy.
    last_bad_us: [u64; 5],
    /// WARNs and INFOs sent so far.
    pub warnings: u64,
    pub recoveries: u64,
}

/// A log line to send: (is a warning, text).
pub type HealthEvent = (bool, String);

impl SensorWatch {
    /// A new MCU status at MCU time `t_us`: the transitions to log.
    pub fn update(
        &mut self,
        s: &link::Status,
        ground_height_m: Option<f32>,
        cfg: &Config,
        t_us: u64,
    ) -> Vec<HealthEvent> {
        let bad = unhealthy(s, ground_height_m, cfg);
        let mut out = Vec::new();
        for (i, &is_bad) in bad.iter().enumerate() {
            if is_bad {
                self.last_bad_us[i] = t_us;
                if !self.reported[i] {
                    self.reported[i] = true;
                    self.warnings += 1;
                    out.push((
                        true,
                        format!("sensor health: {}", problem_text(i, s, ground_height_m)),
                    ));
                }
            } else if self.reported[i]
                && t_us.saturating_sub(self.last_bad_us[i]) >= SENSOR_RECOVERY_HOLD_US
            {
                self.reported[i] = false;
                self.recoveries += 1;
                out.push((false, format!("sensor health: {}", recovery_text(i, s))));
            }
        }
        out
    }
}

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
    let t = st.link_totals();
    let c = &st.counters;
    let hw = device.to_string();

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

    let ts = st.timesync.best();
    let sync = DiagnosticStatus {
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
        hardware_id: hw.clone(),
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
    };
    let sp = DiagnosticStatus {
        level: DiagnosticStatus::OK,
        name: "fcc_bridge: setpoints".into(),
        message: format!(
            "{} forwarded, {} refused",
            c.setpoints_forwarded, c.setpoint_rejects
        ),
        hardware_id: hw.clone(),
        values: vec![
            kv("setpoints_forwarded", c.setpoints_forwarded),
            // The uplink shaper (state::Uplink): sent to the MCU, replaced by a newer one
            // before their turn, dropped for a hold/land/disarm/kill sent after them.
            kv("setpoints_sent", st.uplink.sent),
            kv("setpoints_coalesced", st.uplink.coalesced),
            kv("setpoints_superseded", st.uplink.superseded),
            kv("setpoint_rejects", c.setpoint_rejects),
            kv("last_setpoint_reject", &c.last_setpoint_reject),
            kv("yaw_rate_ignored", c.yaw_rate_ignored),
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
    };
    let mut status = vec![
        DiagnosticStatus {
            level,
            name: "fcc_bridge: link".into(),
            message,
            hardware_id: hw.clone(),
            values: link_values,
        },
        sync,
        sp,
    ];
    if let Some(m) = &st.mcu_status {
        let (_, mode) = crate::convert::mode_code(m.mode);
        let (fs, fsn) = crate::convert::failsafe_code(m.failsafe);
        status.push(DiagnosticStatus {
            level: if fs == 0 {
                DiagnosticStatus::OK
            } else {
                DiagnosticStatus::WARN
            },
            name: "fcc: vehicle".into(),
            message: format!("{mode}, {}", if m.armed { "armed" } else { "disarmed" }),
            hardware_id: hw.clone(),
            values: vec![
                kv("mode", mode),
                kv("armed", m.armed),
                kv("landed", m.landed),
                kv("failsafe", fsn),
                kv("loop_time_max_us", m.loop_time_max_us),
                kv("loop_time_avg_us", m.loop_time_avg_us),
            ],
        });
        status.push(sensors_status(m, st.ground_height_m, &st.cfg, device));
    }
    DiagnosticArray {
        header: Header::new(stamp, ""),
        status,
    }
}
