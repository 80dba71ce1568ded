//! Mission description: parsing from YAML and validation.
//!
//! All positions are local metres relative to the home point (where the
//! vehicle is at the first [`crate::WaypointFollower::update`] call):
//! `north_m`, `east_m` horizontal, `alt_m` altitude **up** (positive above
//! home). The follower converts these to NED (`down = -alt_m`).
//!
//! Lat/lon waypoints are not supported yet: a waypoint with `lat_deg` /
//! `lon_deg` keys is rejected as an unknown field.

use serde::Deserialize;
use std::fmt;

/// Default of [`Mission::accel_limit_mps2`] when the YAML omits it.
pub const DEFAULT_ACCEL_LIMIT_MPS2: f32 = 1.0;
/// Valid range of [`Mission::speed_mps`]: `(0, MAX_SPEED_MPS]`.
pub const MAX_SPEED_MPS: f32 = 15.0;
/// Valid range of [`Mission::accel_limit_mps2`]: `(0, MAX_ACCEL_MPS2]`.
pub const MAX_ACCEL_MPS2: f32 = 5.0;
/// Valid range of [`Mission::accept_radius_m`]: `(0, MAX_ACCEPT_RADIUS_M]`.
pub const MAX_ACCEPT_RADIUS_M: f32 = 10.0;
/// Valid altitude range (takeoff and waypoints): `(MIN_ALT_M, MAX_ALT_M]`.
pub const MIN_ALT_M: f32 = 0.5;
/// See [`MIN_ALT_M`].
pub const MAX_ALT_M: f32 = 120.0;

fn default_accel_limit() -> f32 {
    DEFAULT_ACCEL_LIMIT_MPS2
}

fn default_true() -> bool {
    true
}

/// A waypoint mission.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Mission {
    /// Takeoff altitude above home, m (up positive). Range (0.5, 120].
    pub takeoff_alt_m: f32,
    /// Maximum commanded speed along a leg (3-D magnitude) and during the
    /// takeoff climb, m/s. Range (0, 15].
    pub speed_mps: f32,
    /// Limit on the rate of change of the commanded velocity, m/s².
    /// Range (0, 5]; default 1.0.
    #[serde(default = "default_accel_limit")]
    pub accel_limit_mps2: f32,
    /// A waypoint is reached when the vehicle is within this 3-D distance, m.
    /// Range (0, 10].
    pub accept_radius_m: f32,
    /// Time to hold (zero velocity command) at each waypoint, s. Default 0.
    #[serde(default)]
    pub hold_s: f32,
    /// Heading to command, degrees clockwise from north. `None`: keep current.
    #[serde(default)]
    pub yaw_deg: Option<f32>,
    /// Request the MCU's land mode after the last waypoint (default true);
    /// otherwise hover with zero velocity.
    #[serde(default = "default_true")]
    pub land_at_end: bool,
    /// Waypoints, flown in order in straight lines. At least one.
    pub waypoints: Vec<Waypoint>,
}

/// A waypoint in local metres relative to home; altitude up positive.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    /// North of home, m.
    pub north_m: f32,
    /// East of home, m.
    pub east_m: f32,
    /// Altitude above home, m (up positive). Range (0.5, 120].
    pub alt_m: f32,
}

impl Waypoint {
    /// The waypoint as an NED offset from home, m (`down = -alt_m`).
    pub fn ned_m(&self) -> [f32; 3] {
        [self.north_m, self.east_m, -self.alt_m]
    }
}

/// Why a mission could not be loaded.
#[derive(Clone, Debug, PartialEq)]
pub enum MissionError {
    /// The YAML did not parse or did not match the schema (unknown/missing
    /// field, wrong type). `message` is serde_yaml's, which names the field
    /// path and the location; `line`/`column` are 1-based when known.
    Parse {
        message: String,
        line: Option<usize>,
        column: Option<usize>,
    },
    /// A field has an invalid value. `field` is a path such as
    /// `waypoints[2].north_m`.
    Invalid { field: String, reason: String },
}

impl MissionError {
    fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        MissionError::Invalid {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for MissionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MissionError::Parse { message, .. } => write!(f, "mission YAML: {message}"),
            MissionError::Invalid { field, reason } => write!(f, "{field}: {reason}"),
        }
    }
}

impl std::error::Error for MissionError {}

/// Checks `lo < v <= hi` (or `lo <= v <= hi` when `lo_inclusive`).
fn check_range(
    field: &str,
    v: f32,
    lo: f32,
    lo_inclusive: bool,
    hi: f32,
) -> Result<(), MissionError> {
    if !v.is_finite() {
        return Err(MissionError::invalid(field, "not finite"));
    }
    let lo_ok = if lo_inclusive { v >= lo } else { v > lo };
    if !lo_ok || v > hi {
        let open = if lo_inclusive { '[' } else { '(' };
        return Err(MissionError::invalid(
            field,
            format!("must be in {open}{lo}, {hi}], got {v}"),
        ));
    }
    Ok(())
}

impl Mission {
    /// The heading to command, rad in (−π, π] (`yaw_deg` may be any finite angle: 270° is
    /// −90°), or `None` to keep the current one.
    pub fn yaw_rad(&self) -> Option<f32> {
        self.yaw_deg
            .map(|d| (180.0 - (180.0 - d).rem_euclid(360.0)).to_radians())
    }

    /// Parses and validates a mission from YAML. Same as [`from_yaml_str`].
    pub fn from_yaml_str(s: &str) -> Result<Mission, MissionError> {
        from_yaml_str(s)
    }

    /// Checks every field: all finite; speed in (0, 15] m/s; accel limit in
    /// (0, 5] m/s²; accept radius in (0, 10] m; takeoff altitude and waypoint
    /// altitudes in (0.5, 120] m; hold ≥ 0 s; at least one waypoint.
    /// The first problem found is returned.
    pub fn validate(&self) -> Result<(), MissionError> {
        check_range(
            "takeoff_alt_m",
            self.takeoff_alt_m,
            MIN_ALT_M,
            false,
            MAX_ALT_M,
        )?;
        check_range("speed_mps", self.speed_mps, 0.0, false, MAX_SPEED_MPS)?;
        check_range(
            "accel_limit_mps2",
            self.accel_limit_mps2,
            0.0,
            false,
            MAX_ACCEL_MPS2,
        )?;
        check_range(
            "accept_radius_m",
            self.accept_radius_m,
            0.0,
            false,
            MAX_ACCEPT_RADIUS_M,
        )?;
        check_range("hold_s", self.hold_s, 0.0, true, f32::MAX)?;
        if let Some(y) = self.yaw_deg {
            if !y.is_finite() {
                return Err(MissionError::invalid("yaw_deg", "not finite"));
            }
        }
        if self.waypoints.is_empty() {
            return Err(MissionError::invalid(
                "waypoints",
                "at least one waypoint is required",
            ));
        }
        for (i, w) in self.waypoints.iter().enumerate() {
            for (name, v) in [("north_m", w.north_m), ("east_m", w.east_m)] {
                if !v.is_finite() {
                    return Err(MissionError::invalid(
                        format!("waypoints[{i}].{name}"),
                        "not finite",
                    ));
                }
            }
            check_range(
                &format!("waypoints[{i}].alt_m"),
                w.alt_m,
                MIN_ALT_M,
                false,
                MAX_ALT_M,
            )?;
        }
        Ok(())
    }
}

/// Parses a mission from YAML and validates it ([`Mission::validate`]).
pub fn from_yaml_str(s: &str) -> Result<Mission, MissionError> {
    let mission: Mission = serde_yaml::from_str(s).map_err(|e| {
        let loc = e.location();
        MissionError::Parse {
            message: e.to_string(),
            line: loc.as_ref().map(|l| l.line()),
            column: loc.as_ref().map(|l| l.column()),
        }
    })?;
    mission.validate()?;
    Ok(mission)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "
takeoff_alt_m: 5.0
speed_mps: 3.0
accept_radius_m: 0.5
waypoints:
  - { north_m: 20.0, east_m: 0.0, alt_m: 5.0 }
  - north_m: 20.0
    east_m: 20.0
    alt_m: 6.0
";

    fn good() -> Mission {
        from_yaml_str(GOOD).unwrap()
    }

    #[test]
    fn parses_with_defaults() {
        let m = good();
        assert_eq!(m.takeoff_alt_m, 5.0);
        assert_eq!(m.speed_mps, 3.0);
        assert_eq!(m.accel_limit_mps2, 1.0);
        assert_eq!(m.accept_radius_m, 0.5);
        assert_eq!(m.hold_s, 0.0);
        assert_eq!(m.yaw_deg, None);
        assert!(m.land_at_end);
        assert_eq!(
            m.waypoints,
            vec![
                Waypoint {
                    north_m: 20.0,
                    east_m: 0.0,
                    alt_m: 5.0
                },
                Waypoint {
                    north_m: 20.0,
                    east_m: 20.0,
                    alt_m: 6.0
                },
            ]
        );
        assert_eq!(m.waypoints[1].ned_m(), [20.0, 20.0, -6.0]);
        assert_eq!(Mission::from_yaml_str(GOOD).unwrap(), m);
    }

    #[test]
    fn parses_all_fields() {
        let m = from_yaml_str(
            "takeoff_alt_m: 10\nspeed_mps: 2\naccel_limit_mps2: 0.5\naccept_radius_m: 1\n\
             hold_s: 3\nyaw_deg: 90\nland_at_end: false\nwaypoints: [{north_m: 1, east_m: 2, alt_m: 3}]\n",
        )
        .unwrap();
        assert_eq!(m.accel_limit_mps2, 0.5);
        assert_eq!(m.hold_s, 3.0);
        assert_eq!(m.yaw_deg, Some(90.0));
        use core::f32::consts::PI;
        for (deg, rad) in [
            (90.0, PI / 2.0),
            (270.0, -PI / 2.0),
            (-180.0, PI),
            (180.0, PI),
            (-90.0, -PI / 2.0),
            (720.0, 0.0),
            (-540.0, PI),
        ] {
            let m = Mission {
                yaw_deg: Some(deg),
                ..m.clone()
            };
            let got = m.yaw_rad().unwrap();
            assert!(
                (got - rad).abs() < 1e-6 && got > -PI && got <= PI,
                "{deg}° → {got} rad"
            );
        }
        assert!(!m.land_at_end);
    }

    #[test]
    fn repo_square_mission_parses() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../launch_configs/missions/square.yaml"
        );
        let text = std::fs::read_to_string(path).expect("square.yaml present");
        let m = from_yaml_str(&text).unwrap();
        assert_eq!(m.waypoints.len(), 4);
        assert_eq!(m.speed_mps, 3.0);
        assert_eq!(m.hold_s, 2.0);
        assert!(m.land_at_end);
    }

    #[test]
    fn unknown_field_in_waypoint_is_named_with_location() {
        let bad = GOOD.replace("east_m: 20.0", "esat_m: 20.0");
        let err = from_yaml_str(&bad).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("waypoints[1]"), "{text}");
        assert!(text.contains("esat_m"), "{text}");
        match err {
            MissionError::Parse { line, column, .. } => {
                assert_eq!(line, Some(8), "{text}");
                assert!(column.is_some());
            }
            other => panic!("expected parse error, got {other:?}"),
        }
    }

    #[test]
    fn wrong_type_and_missing_field_are_parse_errors() {
        let err = from_yaml_str(&GOOD.replace("speed_mps: 3.0", "speed_mps: fast")).unwrap_err();
        assert!(err.to_string().contains("speed_mps"), "{err}");
        let err = from_yaml_str(&GOOD.replace("accept_radius_m: 0.5\n", "")).unwrap_err();
        assert!(err.to_string().contains("accept_radius_m"), "{err}");
        let err = from_yaml_str(&GOOD.replace("speed_mps", "sped_mps")).unwrap_err();
        assert!(err.to_string().contains("sped_mps"), "{err}");
    }

    #[test]
    fn lat_lon_waypoints_rejected_for_now() {
        let err = from_yaml_str(
            "takeoff_alt_m: 5\nspeed_mps: 3\naccept_radius_m: 1\n\
             waypoints: [{lat_deg: 37.5, lon_deg: 127.0, alt_m: 5}]\n",
        )
        .unwrap_err();
        assert!(err.to_string().contains("lat_deg"), "{err}");
    }

    #[test]
    fn non_finite_waypoint_named() {
        let bad = GOOD.replace("north_m: 20.0\n    east_m", "north_m: .nan\n    east_m");
        let err = from_yaml_str(&bad).unwrap_err();
        assert_eq!(
            err,
            MissionError::Invalid {
                field: "waypoints[1].north_m".into(),
                reason: "not finite".into()
            }
        );
        assert_eq!(err.to_string(), "waypoints[1].north_m: not finite");
    }

    fn field_of(m: &Mission) -> String {
        match m.validate().unwrap_err() {
            MissionError::Invalid { field, .. } => field,
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn validation_ranges() {
        assert!(good().validate().is_ok());
        type Case = (fn(&mut Mission), &'static str);
        let cases: Vec<Case> = vec![
            (|m| m.speed_mps = 0.0, "speed_mps"),
            (|m| m.speed_mps = 15.5, "speed_mps"),
            (|m| m.speed_mps = f32::INFINITY, "speed_mps"),
            (|m| m.accel_limit_mps2 = 0.0, "accel_limit_mps2"),
            (|m| m.accel_limit_mps2 = 5.1, "accel_limit_mps2"),
            (|m| m.accept_radius_m = -1.0, "accept_radius_m"),
            (|m| m.accept_radius_m = 10.5, "accept_radius_m"),
            (|m| m.takeoff_alt_m = 0.5, "takeoff_alt_m"),
            (|m| m.takeoff_alt_m = 121.0, "takeoff_alt_m"),
            (|m| m.takeoff_alt_m = f32::NAN, "takeoff_alt_m"),
            (|m| m.hold_s = -1.0, "hold_s"),
            (|m| m.yaw_deg = Some(f32::NAN), "yaw_deg"),
            (|m| m.waypoints.clear(), "waypoints"),
            (
                |m| m.waypoints[1].east_m = f32::NEG_INFINITY,
                "waypoints[1].east_m",
            ),
            (|m| m.waypoints[0].alt_m = 0.0, "waypoints[0].alt_m"),
        ];
        for (mutate, field) in cases {
            let mut m = good();
            mutate(&mut m);
            assert_eq!(field_of(&m), field);
        }
        // Boundaries that are allowed.
        let mut m = good();
        m.speed_mps = 15.0;
        m.accel_limit_mps2 = 5.0;
        m.accept_radius_m = 10.0;
        m.takeoff_alt_m = 120.0;
        assert!(m.validate().is_ok());
    }

    #[test]
    fn range_error_message() {
        let err = from_yaml_str(&GOOD.replace("speed_mps: 3.0", "speed_mps: 20")).unwrap_err();
        assert_eq!(err.to_string(), "speed_mps: must be in (0, 15], got 20");
    }
}
