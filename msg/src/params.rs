//! The MCU parameters settable over the link: ONE table (id, `section.field`, unit, default,
//! range, doc) in [`for_each_mcu_param!`], from which everything else is derived:
//! - here: the link ids ([`param_id`]), the defaults ([`param_default`]) and [`PARAMS`] with
//!   its range check ([`ParamSpec::check`]);
//! - the firmware's `Params` defaults, its range validation and its table-driven `set_param`
//!   (`fcc_firmware::params`, by invoking the macro on the `Params` fields);
//! - the bridge's validation and ROS parameter descriptors (`fcc_bridge::mcu_params`);
//! - the README's parameter table and `launch_configs/mcu_params.yaml` (a test in
//!   `tests/tests/param_table.rs` fails when they are stale and rewrites them with
//!   `FCC_UPDATE_PARAM_DOCS=1`).
//!
//! Adding a parameter is one line in the table (the `Params` field must exist; the controllers
//! it feeds are rebuilt on a change by `fcc_firmware::control::cascade::Cascade::set_params`). The
//! schema hash ([`crate::SCHEMA_HASH`]) is computed over the table's ids and names as well (the
//! `params` line of `schema_text()`), so it changes with the table.

/// The table. Invokes `$m!` with one `id, CONST, section.field, "unit", default, min, max,
/// "doc";` row per parameter (each row's `section.field` is the firmware's `Params` field).
#[macro_export]
macro_rules! for_each_mcu_param {
    ($m:ident) => {
        $m! {
            // id CONST                section.field                unit    default min   max   doc
            1, MAX_HORIZ_SPEED_MPS, limits.max_horiz_speed_mps, "m/s", 8.0, 0.1, 30.0, "Horizontal speed limit of velocity setpoints and the pilot's sticks (velocity mode tracks at most 97 % of it)";
            // 45° (PX4's MPC_TILTMAX_AIR default): at 35° the gale hold (8 m/s + W20 30 kt)
            // ran out of authority in gusts (excursions to 3–5 m); with T/W 2.2 (8 × 12 N for
            // 4.5 kg) 45° keeps 1/cos 45° = 1.41× hover thrust, 65 % of the maximum.
            2, MAX_TILT_DEG, limits.max_tilt_deg, "deg", 45.0, 5.0, 60.0, "Tilt limit of the attitude command";
            3, CROSS_TRACK_K_PER_S, control.cross_track_k_per_s, "1/s", 2.0, 0.0, 5.0, "Cross-track compensation gain K_ct (paper A eq. 9)";
            4, VEL_P_PER_S, control.vel_p_per_s, "1/s", 3.0, 0.05, 10.0, "Horizontal velocity loop: acceleration command per m/s of error";
            5, MAX_CLIMB_MPS, limits.max_climb_mps, "m/s", 2.5, 0.1, 10.0, "Climb speed limit";
            6, MAX_DESCENT_MPS, limits.max_descent_mps, "m/s", 1.5, 0.1, 10.0, "Descent speed limit of commanded velocities";
            7, FENCE_RADIUS_M, limits.fence_radius_m, "m", 200.0, 5.0, 10000.0, "Geofence: horizontal radius around home (the MCU holds the vehicle inside; the mission node refuses goals outside)";
            8, FENCE_ALT_M, limits.fence_alt_m, "m", 100.0, 2.0, 1000.0, "Geofence: ceiling above the take-off altitude (the MCU stops climbing; the mission node refuses goals above it)";
            // Telemetry rates (MCU → Linux), one per `Stream`; 0 = off. Applied at once (the
            // streams restart their schedule); the worst-case total must fit the UART
            // (`StreamRates::worst_case_bytes_per_s`, checked by `Params::validate` on the MCU
            // and against the configured baud by the bridge).
            20, RATES_STATUS_HZ, rates.status_hz, "Hz", 10.0, 0.0, 100.0, "Rate of the Status stream";
            21, RATES_NAV_STATE_HZ, rates.nav_state_hz, "Hz", 100.0, 0.0, 500.0, "Rate of the NavState stream (odometry, TF)";
            22, RATES_ALTITUDE_HZ, rates.altitude_hz, "Hz", 50.0, 0.0, 500.0, "Rate of the AltitudeFusion stream (paper B)";
            23, RATES_IMU_HZ, rates.imu_hz, "Hz", 200.0, 0.0, 1000.0, "Rate of the raw IMU stream (at most every sample)";
            24, RATES_MAG_HZ, rates.mag_hz, "Hz", 50.0, 0.0, 500.0, "Rate of the raw magnetometer stream";
            25, RATES_BARO_HZ, rates.baro_hz, "Hz", 50.0, 0.0, 500.0, "Rate of the raw barometer stream";
            26, RATES_GPS_HZ, rates.gps_hz, "Hz", 10.0, 0.0, 100.0, "Rate of the raw GPS stream";
            27, RATES_LASER_HZ, rates.laser_hz, "Hz", 10.0, 0.0, 500.0, "Rate of the laser altimeter stream";
            28, RATES_SONAR_HZ, rates.sonar_hz, "Hz", 10.0, 0.0, 500.0, "Rate of the sonar stream";
            29, RATES_BATTERY_HZ, rates.battery_hz, "Hz", 5.0, 0.0, 100.0, "Rate of the battery stream";
        }
    };
}

/// One row of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// Link id ([`crate::ParamSet::id`]).
    pub id: u16,
    /// `section.field` of the firmware's `Params` (also the ROS parameter name).
    pub name: &'static str,
    pub unit: &'static str,
    /// The firmware's default.
    pub default: f32,
    pub min: f32,
    pub max: f32,
    pub doc: &'static str,
}

/// Why a value is refused by [`ParamSpec::check`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamRangeError {
    NotFinite,
    OutOfRange,
}

impl core::fmt::Display for ParamRangeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ParamRangeError::NotFinite => "not finite",
            ParamRangeError::OutOfRange => "out of range",
        })
    }
}

/// A refused value with its parameter, for messages: `name: not finite` or
/// `name: 80 out of range [5, 60]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamValueError {
    pub spec: &'static ParamSpec,
    pub value: f64,
    pub kind: ParamRangeError,
}

impl core::fmt::Display for ParamValueError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = self.spec;
        match self.kind {
            ParamRangeError::NotFinite => write!(f, "{}: not finite", s.name),
            ParamRangeError::OutOfRange => write!(
                f,
                "{}: {} out of range [{}, {}]",
                s.name, self.value, s.min, s.max
            ),
        }
    }
}

impl ParamSpec {
    /// Range check of one value (f32, as the MCU stores it).
    pub fn check_f32(&self, v: f32) -> Result<(), ParamRangeError> {
        if !v.is_finite() {
            Err(ParamRangeError::NotFinite)
        } else if v < self.min || v > self.max {
            Err(ParamRangeError::OutOfRange)
        } else {
            Ok(())
        }
    }

    /// Range check of a value from the Linux side (f64), with a readable error.
    pub fn check(&'static self, v: f64) -> Result<(), ParamValueError> {
        let kind = if !v.is_finite() {
            ParamRangeError::NotFinite
        } else if v < self.min as f64 || v > self.max as f64 {
            ParamRangeError::OutOfRange
        } else {
            return Ok(());
        };
        Err(ParamValueError {
            spec: self,
            value: v,
            kind,
        })
    }
}

macro_rules! impl_param_table {
    ($($id:literal, $konst:ident, $sec:ident . $field:ident, $unit:literal, $def:literal,
       $min:literal, $max:literal, $doc:literal;)*) => {
        /// Ids of the MCU parameters settable over the link (from [`for_each_mcu_param!`]).
        pub mod param_id {
            $(pub const $konst: u16 = $id;)*
            /// (id, name) of every settable parameter.
            pub const ALL: &[(u16, &str)] =
                &[$(($konst, concat!(stringify!($sec), ".", stringify!($field)))),*];
            /// Name of a parameter id.
            pub fn name(id: u16) -> Option<&'static str> {
                ALL.iter().find(|(i, _)| *i == id).map(|(_, n)| *n)
            }
            /// Id of a parameter name.
            pub fn by_name(name: &str) -> Option<u16> {
                ALL.iter().find(|(_, n)| *n == name).map(|(i, _)| *i)
            }
        }

        /// The firmware's default of each MCU parameter (from [`for_each_mcu_param!`]).
        pub mod param_default {
            $(pub const $konst: f32 = $def;)*
        }

        /// Every MCU parameter settable over the link.
        pub const PARAMS: &[ParamSpec] = &[$(ParamSpec {
            id: $id,
            name: concat!(stringify!($sec), ".", stringify!($field)),
            unit: $unit,
            default: $def,
            min: $min,
            max: $max,
            doc: $doc,
        }),*];
    };
}

for_each_mcu_param!(impl_param_table);

/// The row of a link id.
pub fn by_id(id: u16) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.id == id)
}

/// The row of a `section.field` name.
pub fn by_name(name: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_consistent() {
        for (i, p) in PARAMS.iter().enumerate() {
            assert!(p.min <= p.default && p.default <= p.max, "{}", p.name);
            assert_eq!(p.check_f32(p.default), Ok(()), "{}", p.name);
            assert_eq!(p.check_f32(f32::NAN), Err(ParamRangeError::NotFinite));
            assert_eq!(
                p.check_f32(p.max * 2.0 + 1.0),
                Err(ParamRangeError::OutOfRange)
            );
            assert_eq!(by_id(p.id), Some(p));
            assert_eq!(by_name(p.name), Some(p));
            assert_eq!(param_id::ALL[i], (p.id, p.name));
            assert!(PARAMS[..i].iter().all(|q| q.id != p.id && q.name != p.name));
        }
        assert_eq!(
            param_default::MAX_TILT_DEG,
            by_id(param_id::MAX_TILT_DEG).unwrap().default
        );
    }

    #[test]
    fn errors_read_as_before() {
        extern crate std;
        use std::string::ToString;
        let p = by_id(param_id::MAX_TILT_DEG).unwrap();
        assert_eq!(
            p.check(80.0).unwrap_err().to_string(),
            "limits.max_tilt_deg: 80 out of range [5, 60]"
        );
        assert_eq!(
            p.check(f64::NAN).unwrap_err().to_string(),
            "limits.max_tilt_deg: not finite"
        );
        assert!(p.check(60.0).is_ok());
    }
}
