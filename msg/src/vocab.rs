//! The status vocabularies both ends and the ROS interface share, once: flight modes, failsafe
//! causes and altitude (ground) sources, with their ROS constant values (`Status.MODE_*`,
//! `Status.FAILSAFE_*`, `Altitude.SOURCE_*` in `msg/msg/*.msg`) and their names (`mode_name`,
//! `failsafe_name`, lower snake case). The firmware's `Mode`/`FailsafeCause` are these types;
//! the bridge publishes `code()`/`name()`; the mission node reads `from_code`/`from_name`.
//! A test parses the `.msg` files and fails when a constant and a variant disagree.

use crate::messages::{AltitudeSource, FailsafeCause, FlightMode};

macro_rules! vocabulary {
    ($ty:ident, $($variant:ident = $code:literal, $name:literal;)*) => {
        impl $ty {
            /// Every value, in code order.
            pub const ALL: &'static [$ty] = &[$($ty::$variant),*];
            /// The ROS constant (`.msg` file) of this value.
            pub const fn code(self) -> u8 {
                match self {
                    $($ty::$variant => $code,)*
                }
            }
            /// The lower snake case name the ROS status carries.
            pub const fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)*
                }
            }
            /// From a ROS constant.
            pub fn from_code(code: u8) -> Option<$ty> {
                Self::ALL.iter().copied().find(|v| v.code() == code)
            }
            /// From a ROS name.
            pub fn from_name(name: &str) -> Option<$ty> {
                Self::ALL.iter().copied().find(|v| v.name() == name)
            }
        }
    };
}

vocabulary!(FlightMode,
    Disarmed = 0, "disarmed";
    Hold = 1, "hold";
    Velocity = 2, "velocity";
    Land = 3, "land";
    Pilot = 4, "pilot";
);

vocabulary!(FailsafeCause,
    None = 0, "none";
    SetpointStale = 1, "setpoint_stale";
    SetpointLost = 2, "setpoint_lost";
    Geofence = 3, "geofence";
    GpsLost = 4, "gps_lost";
    WindLimit = 5, "wind_limit";
    EstimatorFault = 6, "estimator_fault";
    EmergencyKill = 7, "emergency_kill";
);

vocabulary!(AltitudeSource,
    None = 0, "none";
    Laser = 1, "laser";
    Sonar = 2, "sonar";
    Both = 3, "both";
    Predicted = 4, "predicted";
);

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::String;
    use std::vec::Vec;

    /// `(NAME, value)` of every `uint8 PREFIX_... = n` constant in a `.msg` file.
    fn constants(file: &str, prefix: &str) -> Vec<(String, u8)> {
        let path = std::format!("{}/msg/{file}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        text.lines()
            .filter_map(|l| l.split('#').next())
            .filter_map(|l| l.trim().strip_prefix("uint8 "))
            .filter_map(|l| l.split_once('='))
            .map(|(n, v)| (n.trim().into(), v.trim().parse().unwrap()))
            .filter(|(n, _): &(String, u8)| n.starts_with(prefix))
            .collect()
    }

    /// The `.msg` constants `PREFIX_<NAME>` are exactly the variants' names and codes.
    fn check(file: &str, prefix: &str, all: &[(&str, u8)]) {
        let mut want: Vec<(String, u8)> = all
            .iter()
            .map(|(n, c)| (std::format!("{prefix}{}", n.to_uppercase()), *c))
            .collect();
        let mut got = constants(file, prefix);
        want.sort();
        got.sort();
        assert!(!got.is_empty(), "{file}: no {prefix}* constants");
        assert_eq!(got, want, "{file} {prefix}* and fcc_msgs::vocab disagree");
    }

    #[test]
    fn codes_match_the_ros_msg_files() {
        check(
            "Status.msg",
            "MODE_",
            &FlightMode::ALL
                .iter()
                .map(|m| (m.name(), m.code()))
                .collect::<Vec<_>>(),
        );
        check(
            "Status.msg",
            "FAILSAFE_",
            &FailsafeCause::ALL
                .iter()
                .map(|m| (m.name(), m.code()))
                .collect::<Vec<_>>(),
        );
        check(
            "Altitude.msg",
            "SOURCE_",
            &AltitudeSource::ALL
                .iter()
                .map(|m| (m.name(), m.code()))
                .collect::<Vec<_>>(),
        );
    }

    #[test]
    fn names_and_codes_round_trip() {
        for m in FlightMode::ALL {
            assert_eq!(FlightMode::from_code(m.code()), Some(*m));
            assert_eq!(FlightMode::from_name(m.name()), Some(*m));
        }
        for f in FailsafeCause::ALL {
            assert_eq!(FailsafeCause::from_code(f.code()), Some(*f));
            assert_eq!(FailsafeCause::from_name(f.name()), Some(*f));
        }
        for s in AltitudeSource::ALL {
            assert_eq!(AltitudeSource::from_code(s.code()), Some(*s));
        }
        assert_eq!(FlightMode::from_name("loiter"), None);
        assert_eq!(FlightMode::from_code(9), None);
    }
}
