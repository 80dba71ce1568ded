//! A mission goal as a ROS user gives it (the `FollowWaypoints` action's fields, no ROS types)
//! → a [`Mission`] whose waypoints are metres from home (the origin of `map`), or the reason it
//! is refused, before any motion: a bad field, a lat/lon point while home is unknown, a point
//! outside the geofence.
//!
//! Frames: a [`GoalPoint::LocalEnu`] is `map` (REP-103 ENU, origin = home: x east, y north,
//! z up); a [`GoalPoint::Global`] is WGS-84 latitude/longitude, converted with
//! `fcc_msgs::geodesy` (f64) on the tangent plane at [`Home`]. Altitudes are above home in both.
//! The geofence is the MCU's (`limits.fence_radius_m` around home, `limits.fence_alt_m` above
//! it; [`Fence::from_param_table`] takes the one parameter table's values).

use crate::mission::{Mission, MissionError, Waypoint, DEFAULT_ACCEL_LIMIT_MPS2};
use fcc_msgs::geodesy::{Lla, LocalNed};
use std::fmt;

/// Cruise speed when the goal leaves it 0, m/s.
pub const DEFAULT_SPEED_MPS: f32 = 3.0;
/// Acceptance radius when the goal leaves it 0, m.
pub const DEFAULT_ACCEPT_RADIUS_M: f32 = 0.5;

/// One point of a goal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GoalPoint {
    /// `map` metres: x east, y north, z up (above home).
    LocalEnu { x_m: f64, y_m: f64, z_m: f64 },
    /// WGS-84 latitude/longitude, deg; altitude above home, m.
    Global {
        latitude_deg: f64,
        longitude_deg: f64,
        altitude_m: f64,
    },
}

/// A goal: the points and how to fly them (zero speed/radius/takeoff = the defaults).
#[derive(Debug, Clone, PartialEq)]
pub struct GoalSpec {
    pub points: Vec<GoalPoint>,
    pub speed_mps: f32,
    pub accept_radius_m: f32,
    pub hold_s: f32,
    /// Degrees clockwise from north; NaN = keep the current heading.
    pub heading_deg: f32,
    /// Take-off height above home when starting on the ground, m (0 = the first point's).
    pub takeoff_alt_m: f32,
    pub land_at_end: bool,
}

/// The vehicle's home (the origin of `map`), as the bridge publishes it on `home`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Home {
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    pub altitude_m: f64,
}

/// The MCU's geofence: a cylinder around home.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fence {
    pub radius_m: f64,
    /// Ceiling above home, m.
    pub alt_m: f64,
}

impl Fence {
    /// The defaults of the MCU parameter table (`limits.fence_radius_m`, `limits.fence_alt_m`).
    pub fn from_param_table() -> Self {
        use fcc_msgs::params::param_default as d;
        Fence {
            radius_m: f64::from(d::FENCE_RADIUS_M),
            alt_m: f64::from(d::FENCE_ALT_M),
        }
    }
}

/// Why a goal is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum Refusal {
    NoWaypoints,
    /// A lat/lon point, and the bridge has not published `home` yet.
    NoHome {
        index: usize,
    },
    /// A coordinate is NaN or infinite.
    NotFinite {
        index: usize,
    },
    /// Horizontally farther from home than the fence radius.
    OutsideFence {
        index: usize,
        distance_m: f64,
        radius_m: f64,
    },
    /// Above the fence's ceiling.
    AboveFence {
        index: usize,
        altitude_m: f64,
        ceiling_m: f64,
    },
    /// A field out of its range (the mission's own checks).
    Invalid(MissionError),
    /// Take-off or landing: no odometry from the bridge yet (where the vehicle is).
    NoPosition,
    /// Landing: the vehicle is on the ground (disarmed).
    OnGround,
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::NoWaypoints => write!(f, "no waypoints"),
            Refusal::NoHome { index } => write!(
                f,
                "waypoints[{index}] is lat/lon but home is not known yet (no message on `home` from the bridge: the MCU sets home at its first GPS fix)"
            ),
            Refusal::NotFinite { index } => write!(f, "waypoints[{index}]: not finite"),
            Refusal::OutsideFence { index, distance_m, radius_m } => write!(
                f,
                "waypoints[{index}] is outside the geofence: {distance_m:.1} m from home, limits.fence_radius_m is {radius_m:.0} m"
            ),
            Refusal::AboveFence { index, altitude_m, ceiling_m } => write!(
                f,
                "waypoints[{index}] is above the geofence: {altitude_m:.1} m above home, limits.fence_alt_m is {ceiling_m:.0} m"
            ),
            Refusal::Invalid(e) => write!(f, "{e}"),
            Refusal::NoPosition => write!(
                f,
                "where the vehicle is is not known yet (no `state/odom` from the bridge)"
            ),
            Refusal::OnGround => write!(f, "the vehicle is on the ground (disarmed): nothing to land"),
        }
    }
}

/// A point in `map` ENU metres (x east, y north, z up), or why not.
fn to_enu(index: usize, p: &GoalPoint, home: Option<Home>) -> Result<[f64; 3], Refusal> {
    let enu = match *p {
        GoalPoint::LocalEnu { x_m, y_m, z_m } => [x_m, y_m, z_m],
        GoalPoint::Global {
            latitude_deg,
            longitude_deg,
            altitude_m,
        } => {
            let h = home.ok_or(Refusal::NoHome { index })?;
            if !(latitude_deg.is_finite() && longitude_deg.is_finite() && altitude_m.is_finite()) {
                return Err(Refusal::NotFinite { index });
            }
            let frame = LocalNed::new(Lla {
                lat_deg: h.latitude_deg,
                lon_deg: h.longitude_deg,
                alt_m: h.altitude_m,
            });
            let ned = frame.lla_to_ned(&Lla {
                lat_deg: latitude_deg,
                lon_deg: longitude_deg,
                alt_m: h.altitude_m + altitude_m,
            });
            [ned[1], ned[0], altitude_m]
        }
    };
    if enu.iter().all(|v| v.is_finite()) {
        Ok(enu)
    } else {
        Err(Refusal::NotFinite { index })
    }
}

/// The geofence check of one point (`map` ENU, m).
fn check_fence(index: usize, enu: [f64; 3], fence: Fence) -> Result<(), Refusal> {
    let distance_m = enu[0].hypot(enu[1]);
    if distance_m > fence.radius_m {
        return Err(Refusal::OutsideFence {
            index,
            distance_m,
            radius_m: fence.radius_m,
        });
    }
    if enu[2] > fence.alt_m {
        return Err(Refusal::AboveFence {
            index,
            altitude_m: enu[2],
            ceiling_m: fence.alt_m,
        });
    }
    Ok(())
}

/// The goal as a mission in metres from home (validated), or the reason it is refused.
pub fn to_mission(g: &GoalSpec, home: Option<Home>, fence: Fence) -> Result<Mission, Refusal> {
    if g.points.is_empty() {
        return Err(Refusal::NoWaypoints);
    }
    let mut waypoints = Vec::with_capacity(g.points.len());
    for (i, p) in g.points.iter().enumerate() {
        let enu = to_enu(i, p, home)?;
        check_fence(i, enu, fence)?;
        waypoints.push(Waypoint {
            north_m: enu[1] as f32,
            east_m: enu[0] as f32,
            alt_m: enu[2] as f32,
        });
    }
    let or = |v: f32, default: f32| if v == 0.0 { default } else { v };
    let m = Mission {
        takeoff_alt_m: or(g.takeoff_alt_m, waypoints[0].alt_m),
        speed_mps: or(g.speed_mps, DEFAULT_SPEED_MPS),
        accel_limit_mps2: DEFAULT_ACCEL_LIMIT_MPS2,
        accept_radius_m: or(g.accept_radius_m, DEFAULT_ACCEPT_RADIUS_M),
        hold_s: g.hold_s,
        yaw_deg: (!g.heading_deg.is_nan()).then_some(g.heading_deg),
        land_at_end: g.land_at_end,
        waypoints,
    };
    m.validate().map_err(Refusal::Invalid)?;
    Ok(m)
}

/// The `takeoff` action as a goal: the point above where the vehicle is (`here_enu_m`, `map`),
/// at `altitude_m` above home; taking off to that height when on the ground; then holding.
/// Refused without a position; the height is checked by [`to_mission`] (range, fence ceiling).
pub fn takeoff_spec(altitude_m: f32, here_enu_m: Option<[f64; 3]>) -> Result<GoalSpec, Refusal> {
    let [x_m, y_m, _] = here_enu_m.ok_or(Refusal::NoPosition)?;
    Ok(GoalSpec {
        points: vec![GoalPoint::LocalEnu {
            x_m,
            y_m,
            z_m: f64::from(altitude_m),
        }],
        speed_mps: 0.0,
        accept_radius_m: 0.0,
        hold_s: 0.0,
        heading_deg: f32::NAN,
        takeoff_alt_m: altitude_m,
        land_at_end: false,
    })
}

/// The `land` action as a goal: land where the vehicle is (`here_enu_m`), or at home after
/// flying there at its current height. Refused on the ground (not `armed`) or without a
/// position.
pub fn land_spec(
    at_home: bool,
    here_enu_m: Option<[f64; 3]>,
    armed: bool,
) -> Result<GoalSpec, Refusal> {
    if !armed {
        return Err(Refusal::OnGround);
    }
    let [x_m, y_m, z_m] = here_enu_m.ok_or(Refusal::NoPosition)?;
    let (x_m, y_m) = if at_home { (0.0, 0.0) } else { (x_m, y_m) };
    Ok(GoalSpec {
        points: vec![GoalPoint::LocalEnu { x_m, y_m, z_m }],
        speed_mps: 0.0,
        accept_radius_m: 0.0,
        hold_s: 0.0,
        heading_deg: f32::NAN,
        takeoff_alt_m: 0.0,
        land_at_end: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOME: Home = Home {
        latitude_deg: 47.397_742,
        longitude_deg: 8.545_594,
        altitude_m: 488.0,
    };

    fn spec(points: Vec<GoalPoint>) -> GoalSpec {
        GoalSpec {
            points,
            speed_mps: 0.0,
            accept_radius_m: 0.0,
            hold_s: 1.0,
            heading_deg: f32::NAN,
            takeoff_alt_m: 0.0,
            land_at_end: true,
        }
    }

    fn local(x_m: f64, y_m: f64, z_m: f64) -> GoalPoint {
        GoalPoint::LocalEnu { x_m, y_m, z_m }
    }

    /// Take-off: straight up where the vehicle stands, to the asked height, then hold; the
    /// fence ceiling and the height range still apply. Land: where it is or at home, at its
    /// height; refused on the ground and without a position.
    #[test]
    fn takeoff_and_land_goals() {
        let fence = Fence::from_param_table();
        let t = takeoff_spec(4.0, Some([3.0, -2.0, 0.1])).unwrap();
        assert_eq!(t.points, vec![local(3.0, -2.0, 4.0)]);
        assert_eq!((t.takeoff_alt_m, t.land_at_end), (4.0, false));
        let m = to_mission(&t, None, fence).unwrap();
        assert_eq!(m.takeoff_alt_m, 4.0);
        assert_eq!(takeoff_spec(4.0, None), Err(Refusal::NoPosition));
        let high = takeoff_spec(150.0, Some([0.0; 3])).unwrap();
        assert!(matches!(
            to_mission(&high, None, fence),
            Err(Refusal::AboveFence { .. })
        ));
        let l = land_spec(false, Some([3.0, -2.0, 6.0]), true).unwrap();
        assert_eq!(
            (l.points.clone(), l.land_at_end),
            (vec![local(3.0, -2.0, 6.0)], true)
        );
        let h = land_spec(true, Some([3.0, -2.0, 6.0]), true).unwrap();
        assert_eq!(h.points, vec![local(0.0, 0.0, 6.0)]);
        assert!(to_mission(&h, None, fence).is_ok());
        assert_eq!(
            land_spec(false, Some([0.0; 3]), false),
            Err(Refusal::OnGround)
        );
        assert_eq!(land_spec(false, None, true), Err(Refusal::NoPosition));
        assert!(Refusal::OnGround.to_string().contains("on the ground"));
    }

    /// A point 20 m north and 10 m east of home, by its latitude/longitude (the inverse
    /// conversion of fcc_nav), lands on those metres.
    #[test]
    fn lat_lon_becomes_metres_from_home() {
        let frame = LocalNed::new(Lla {
            lat_deg: HOME.latitude_deg,
            lon_deg: HOME.longitude_deg,
            alt_m: HOME.altitude_m,
        });
        let p = frame.ned_to_lla([20.0, 10.0, -5.0]);
        let g = spec(vec![GoalPoint::Global {
            latitude_deg: p.lat_deg,
            longitude_deg: p.lon_deg,
            altitude_m: 5.0,
        }]);
        let m = to_mission(&g, Some(HOME), Fence::from_param_table()).unwrap();
        let w = m.waypoints[0];
        assert!(
            (w.north_m - 20.0).abs() < 1e-3 && (w.east_m - 10.0).abs() < 1e-3,
            "{w:?}"
        );
        assert_eq!(w.alt_m, 5.0);
        // Defaults for the zero fields, heading NaN = keep.
        assert_eq!(
            (m.speed_mps, m.accept_radius_m, m.takeoff_alt_m),
            (3.0, 0.5, 5.0)
        );
        assert_eq!(m.yaw_deg, None);
    }

    #[test]
    fn local_enu_is_x_east_y_north_z_up() {
        let mut g = spec(vec![local(4.0, 7.0, 3.0)]);
        g.heading_deg = 90.0;
        g.speed_mps = 2.0;
        let m = to_mission(&g, None, Fence::from_param_table()).unwrap();
        assert_eq!(m.waypoints[0].ned_m(), [7.0, 4.0, -3.0]);
        assert_eq!((m.yaw_deg, m.speed_mps), (Some(90.0), 2.0));
    }

    #[test]
    fn refusals_say_why() {
        let fence = Fence::from_param_table();
        assert_eq!((fence.radius_m, fence.alt_m), (200.0, 100.0));
        let far = spec(vec![local(10.0, 0.0, 5.0), local(150.0, 150.0, 5.0)]);
        let e = to_mission(&far, None, fence).unwrap_err();
        assert_eq!(
            e.to_string(),
            "waypoints[1] is outside the geofence: 212.1 m from home, limits.fence_radius_m is 200 m"
        );
        let high = spec(vec![local(0.0, 0.0, 101.0)]);
        assert!(matches!(
            to_mission(&high, None, fence),
            Err(Refusal::AboveFence { index: 0, .. })
        ));
        let gl = spec(vec![GoalPoint::Global {
            latitude_deg: 47.4,
            longitude_deg: 8.5,
            altitude_m: 5.0,
        }]);
        assert_eq!(
            to_mission(&gl, None, fence),
            Err(Refusal::NoHome { index: 0 })
        );
        // 47.4, 8.5 is ~3.4 km from home.
        assert!(matches!(
            to_mission(&gl, Some(HOME), fence),
            Err(Refusal::OutsideFence { distance_m, .. }) if distance_m > 3000.0
        ));
        assert_eq!(
            to_mission(&spec(vec![]), None, fence),
            Err(Refusal::NoWaypoints)
        );
        let nan = spec(vec![local(f64::NAN, 0.0, 5.0)]);
        assert_eq!(
            to_mission(&nan, None, fence),
            Err(Refusal::NotFinite { index: 0 })
        );
        let low = spec(vec![local(1.0, 0.0, 0.2)]);
        assert!(matches!(
            to_mission(&low, None, fence),
            Err(Refusal::Invalid(_))
        ));
    }
}
