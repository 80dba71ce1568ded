//! Sensor-health rules: which sensors of an MCU status are unhealthy ([`unhealthy`]: GPS lost,
//! magnetometer disturbed, laser / sonar without a valid reading while it should see the ground,
//! a navigation filter diverged), and [`SensorWatch`], which turns them into one `/rosout` WARN
//! per episode and an INFO on recovery. `/diagnostics` shows the same rules
//! (`crate::diag::sensors_status`).

use crate::convert::Config;
use fcc_msgs as link;

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
