//! Pure conversions: decoded link messages → ROS messages, and ROS setpoints/commands → link
//! messages (with validation). No IO, no clock: stamps and the latest state are arguments.
//! Frame maths comes from [`fcc_ros::frames`].

use crate::bounded;
use fcc_msgs as link;
use fcc_msgs::ros::*;
use fcc_ros::frames::{self, f64x3, frd_to_flu, ned_to_enu};

/// Laser sentinel for "no return" (passed through by the MCU).
pub use fcc_nav::ground_altitude::LASER_NO_RETURN_M;

/// Frame ids and sensor figures used in the published messages.
#[derive(Clone, Debug)]
pub struct Config {
    /// World frame (REP-105 `map`; ENU, origin = home): the root of the TF tree, and the frame
    /// of the world-fixed quantities (accelerations, altitude).
    pub map_frame: String,
    /// Odometry frame (REP-105 `odom`): the odometry pose's frame and TF parent of the body.
    /// `map → odom` is the identity, published once on `/tf_static`: the MCU has one
    /// estimate, GPS-referenced (it does not drift away from `map`), so there is no correction
    /// to carry; see [`fcc_ros::frames`].
    pub odom_frame: String,
    /// Body frame (FLU).
    pub base_frame: String,
    pub imu_frame: String,
    pub mag_frame: String,
    pub baro_frame: String,
    pub gps_frame: String,
    /// Range frames: x axis along the beam (pointing down).
    pub laser_frame: String,
    pub sonar_frame: String,
    pub laser: RangeSpec,
    pub sonar: RangeSpec,
}

#[derive(Clone, Copy, Debug)]
pub struct RangeSpec {
    pub radiation_type: u8,
    pub field_of_view_rad: f32,
    pub min_m: f32,
    pub max_m: f32,
    pub variance_m2: f32,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            map_frame: "map".into(),
            odom_frame: "odom".into(),
            base_frame: "base_link".into(),
            imu_frame: "imu_link".into(),
            mag_frame: "imu_link".into(),
            baro_frame: "base_link".into(),
            gps_frame: "gps_link".into(),
            laser_frame: "laser_link".into(),
            sonar_frame: "sonar_link".into(),
            // ILM-150-R class laser (SITL: 0.5–150 m, 5 cm 1σ, narrow beam).
            laser: RangeSpec {
                radiation_type: Range::INFRARED,
                field_of_view_rad: 0.005,
                min_m: 0.5,
                max_m: 150.0,
                variance_m2: 0.05 * 0.05,
            },
            // Ultrasonic (SITL: 0.2–10.68 m, 2 cm 1σ level, 15° half-angle beam).
            sonar: RangeSpec {
                radiation_type: Range::ULTRASOUND,
                field_of_view_rad: 30f32.to_radians(),
                min_m: 0.2,
                max_m: 10.68,
                variance_m2: 0.02 * 0.02,
            },
        }
    }
}

fn v3(v: [f64; 3]) -> Vector3 {
    Vector3::new(v)
}

fn quat_msg(q: frames::Quat) -> Quaternion {
    Quaternion::from_wxyz(q)
}

/// Raw IMU, body FRD → `sensor_msgs/Imu` in FLU without orientation (covariance[0] = −1).
pub fn imu_raw(m: &link::ImuRaw, stamp: Time, cfg: &Config) -> Imu {
    let mut orientation_covariance = [0.0; 9];
    orientation_covariance[0] = -1.0;
    Imu {
        header: Header::new(stamp, &cfg.imu_frame),
        orientation: Quaternion::default(),
        orientation_covariance,
        angular_velocity: v3(frd_to_flu(f64x3(m.gyro_frd_radps))),
        // MPU-9250 gyro noise 0.01 °/s/√Hz at ~100 Hz bandwidth, rounded up: (0.002 rad/s)².
        angular_velocity_covariance: frames::diag3(4e-6),
        linear_acceleration: v3(frd_to_flu(f64x3(m.accel_frd_mps2))),
        // 300 µg/√Hz over ~100 Hz ≈ 0.03 m/s² (vibration is not included).
        linear_acceleration_covariance: frames::diag3(1e-3),
    }
}

/// Magnetometer µT FRD → tesla FLU.
pub fn mag(m: &link::MagRaw, stamp: Time, cfg: &Config) -> MagneticField {
    let t = f64x3(m.mag_frd_ut).map(|x| x * 1e-6);
    MagneticField {
        header: Header::new(stamp, &cfg.mag_frame),
        magnetic_field: v3(frd_to_flu(t)),
        magnetic_field_covariance: [0.0; 9],
    }
}

/// Barometer → `FluidPressure` (Pa).
pub fn baro(m: &link::BaroRaw, stamp: Time, cfg: &Config) -> FluidPressure {
    FluidPressure {
        header: Header::new(stamp, &cfg.baro_frame),
        fluid_pressure: m.pressure_pa as f64,
        variance: 0.0,
    }
}

/// The MCU's home (the origin of `map` and `odom`) → `NavSatFix` on `home`: latitude and
/// longitude (WGS-84, deg) and altitude as the MCU's GPS gave them when it set home, frame `map`,
/// covariance unknown. `NavState` carries it about once a second ([`link::NavState::home`]).
pub fn home(m: &link::HomePosition, stamp: Time, cfg: &Config) -> NavSatFix {
    NavSatFix {
        header: Header::new(stamp, &cfg.map_frame),
        status: NavSatStatus {
            status: NavSatStatus::STATUS_FIX,
            service: NavSatStatus::SERVICE_GPS,
        },
        latitude: m.lat_deg,
        longitude: m.lon_deg,
        altitude: m.alt_m as f64,
        position_covariance: [0.0; 9],
        position_covariance_type: NavSatFix::COVARIANCE_TYPE_UNKNOWN,
    }
}

/// GPS → `NavSatFix` (covariance ENU from the receiver's horizontal accuracy, vertical 2×).
pub fn gps_fix(m: &link::GpsRaw, stamp: Time, cfg: &Config) -> NavSatFix {
    let h = (m.h_acc_m as f64).max(0.0);
    let (cov, cov_type) = if h.is_finite() && h > 0.0 {
        let mut c = [0.0; 9];
        c[0] = h * h;
        c[4] = h * h;
        c[8] = 4.0 * h * h;
        (c, NavSatFix::COVARIANCE_TYPE_APPROXIMATED)
    } else {
        ([0.0; 9], NavSatFix::COVARIANCE_TYPE_UNKNOWN)
    };
    NavSatFix {
        header: Header::new(stamp, &cfg.gps_frame),
        status: NavSatStatus {
            status: if m.fix_ok {
                NavSatStatus::STATUS_FIX
            } else {
                NavSatStatus::STATUS_NO_FIX
            },
            service: NavSatStatus::SERVICE_GPS,
        },
        latitude: m.lat_deg,
        longitude: m.lon_deg,
        altitude: m.alt_m as f64,
        position_covariance: cov,
        position_covariance_type: cov_type,
    }
}

/// REP-117 range value: the laser's no-return sentinel (and anything beyond max) → +inf;
/// NaN stays NaN (no reading).
pub fn rep117_range(range_m: f32, spec: &RangeSpec, laser: bool) -> f32 {
    if laser && range_m >= LASER_NO_RETURN_M {
        f32::INFINITY
    } else if range_m > spec.max_m && laser {
        f32::INFINITY
    } else {
        range_m
    }
}

/// Rangefinder → `Range`, and whether it is the laser (topic choice).
pub fn range(m: &link::RangeRaw, stamp: Time, cfg: &Config) -> (Range, bool) {
    let laser = matches!(m.sensor, link::RangeSensor::Laser);
    let (spec, frame) = if laser {
        (&cfg.laser, &cfg.laser_frame)
    } else {
        (&cfg.sonar, &cfg.sonar_frame)
    };
    (
        range_msg(rep117_range(m.range_m, spec, laser), spec, frame, stamp),
        laser,
    )
}

fn range_msg(range: f32, spec: &RangeSpec, frame: &str, stamp: Time) -> Range {
    Range {
        header: Header::new(stamp, frame),
        radiation_type: spec.radiation_type,
        field_of_view: spec.field_of_view_rad,
        min_range: spec.min_m,
        max_range: spec.max_m,
        range,
        variance: spec.variance_m2,
    }
}

/// Battery → `BatteryState` (unknowns NaN as the message asks).
pub fn battery(m: &link::Battery, stamp: Time, cfg: &Config) -> BatteryState {
    BatteryState {
        header: Header::new(stamp, &cfg.base_frame),
        voltage: m.voltage_v,
        temperature: f32::NAN,
        // ROS: negative while discharging. The link's current is the draw (positive).
        current: -m.current_a,
        charge: f32::NAN,
        capacity: f32::NAN,
        design_capacity: f32::NAN,
        percentage: f32::NAN,
        power_supply_status: BatteryState::POWER_SUPPLY_STATUS_DISCHARGING,
        power_supply_health: BatteryState::POWER_SUPPLY_HEALTH_UNKNOWN,
        power_supply_technology: BatteryState::POWER_SUPPLY_TECHNOLOGY_LIPO,
        present: true,
        cell_voltage: Vec::new(),
        cell_temperature: Vec::new(),
        location: String::new(),
        serial_number: String::new(),
    }
}

/// Navigation state → (`Odometry`, `state/imu`, TF odom → base_link).
///
/// Odometry: pose in `odom` (ENU, home = origin; `map → odom` is the identity), child
/// `base_link`, twist in `base_link` (FLU) per REP-105 / nav_msgs: linear = body-frame
/// velocity, angular = bias-corrected body rates.
pub fn nav_state(m: &link::NavState, stamp: Time, cfg: &Config) -> (Odometry, Imu, TFMessage) {
    let q_ned = frames::quat_f64(m.q_body_to_ned);
    let q_enu = frames::q_frd_ned_to_q_flu_enu(q_ned);
    let pos = ned_to_enu(f64x3(m.pos_ned_m));
    let vel_ned = f64x3(m.vel_ned_mps);
    let vel_flu = frd_to_flu(frames::ned_to_body_frd(q_ned, vel_ned));
    let rate_flu = frd_to_flu(f64x3(m.rate_frd_radps));
    // Specific force in the body = R^T (a − g), g = (0, 0, 9.81) NED.
    let a_ned = f64x3(m.accel_ned_mps2);
    let f_ned = [a_ned[0], a_ned[1], a_ned[2] - 9.80665];
    let f_flu = frd_to_flu(frames::ned_to_body_frd(q_ned, f_ned));

    let mut pose_cov = [0.0; 36];
    let mut twist_cov = [0.0; 36];
    let (ph, pv) = if m.gps_ok { (0.5, 0.15) } else { (10.0, 0.3) };
    for (i, v) in [ph, ph, pv, 0.02, 0.02, 0.05].iter().enumerate() {
        pose_cov[i * 7] = v * v;
    }
    for (i, v) in [0.1, 0.1, 0.1, 0.01, 0.01, 0.01].iter().enumerate() {
        twist_cov[i * 7] = v * v;
    }
    let odom = Odometry {
        header: Header::new(stamp, &cfg.odom_frame),
        child_frame_id: cfg.base_frame.clone(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point {
                    x: pos[0],
                    y: pos[1],
                    z: pos[2],
                },
                orientation: quat_msg(q_enu),
            },
            covariance: pose_cov,
        },
        twist: TwistWithCovariance {
            twist: Twist {
                linear: v3(vel_flu),
                angular: v3(rate_flu),
            },
            covariance: twist_cov,
        },
    };
    let imu = Imu {
        header: Header::new(stamp, &cfg.base_frame),
        orientation: quat_msg(q_enu),
        orientation_covariance: frames::diag3(0.02 * 0.02),
        angular_velocity: v3(rate_flu),
        angular_velocity_covariance: frames::diag3(1e-4),
        linear_acceleration: v3(f_flu),
        linear_acceleration_covariance: frames::diag3(1e-2),
    };
    let tf = TFMessage {
        transforms: vec![TransformStamped {
            header: Header::new(stamp, &cfg.odom_frame),
            child_frame_id: cfg.base_frame.clone(),
            transform: Transform {
                translation: v3(pos),
                rotation: quat_msg(q_enu),
            },
        }],
    };
    (odom, imu, tf)
}

/// Navigation state → (`accel/observer`, `accel/measured`), both `AccelStamped` in the map
/// frame (ENU): the Luenberger observer's horizontal acceleration estimate that the acceleration
/// controller feeds back on (z = 0: the observer is horizontal only), and the gravity-compensated
/// accelerometer (the kinematic acceleration, NED → ENU). Paper A Fig. 13.
pub fn accels(m: &link::NavState, stamp: Time, cfg: &Config) -> (AccelStamped, AccelStamped) {
    let obs = frames::ne_to_enu([m.accel_obs_ne_mps2[0] as f64, m.accel_obs_ne_mps2[1] as f64]);
    let meas = ned_to_enu(f64x3(m.accel_ned_mps2));
    let mk = |v| AccelStamped {
        header: Header::new(stamp, &cfg.map_frame),
        accel: Accel {
            linear: v3(v),
            angular: Vector3::default(),
        },
    };
    (mk(obs), mk(meas))
}

/// Static transforms: `map → odom` (the identity, see [`Config::odom_frame`]; left out if the
/// two names are the same) and `base_link` to the sensor frames (sensors aligned with the body;
/// the rangefinder frames' x axis points down the beam, REP-117/`sensor_msgs/Range`).
pub fn static_transforms(stamp: Time, cfg: &Config) -> TFMessage {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    // +90° about y (FLU): x → −z.
    let down = Quaternion {
        x: 0.0,
        y: s,
        z: 0.0,
        w: s,
    };
    let mut frames_seen: Vec<&str> = Vec::new();
    let mut out = Vec::new();
    if cfg.odom_frame != cfg.map_frame {
        out.push(TransformStamped {
            header: Header::new(stamp, &cfg.map_frame),
            child_frame_id: cfg.odom_frame.clone(),
            transform: Transform {
                translation: Vector3::default(),
                rotation: Quaternion::default(),
            },
        });
    }
    for (frame, rot) in [
        (&cfg.imu_frame, Quaternion::default()),
        (&cfg.mag_frame, Quaternion::default()),
        (&cfg.baro_frame, Quaternion::default()),
        (&cfg.gps_frame, Quaternion::default()),
        (&cfg.laser_frame, down),
        (&cfg.sonar_frame, down),
    ] {
        if frame == &cfg.base_frame || frames_seen.contains(&frame.as_str()) {
            continue;
        }
        frames_seen.push(frame);
        out.push(TransformStamped {
            header: Header::new(stamp, &cfg.base_frame),
            child_frame_id: frame.clone(),
            transform: Transform {
                translation: Vector3::default(),
                rotation: rot,
            },
        });
    }
    TFMessage { transforms: out }
}

pub fn altitude_source(s: link::AltitudeSource) -> u8 {
    s.code() // `Altitude.SOURCE_*`: fcc_msgs::vocab, tested against the .msg file
}

/// Altitude fusion → (`fcc_msgs/Altitude`, `altitude/ground` Range).
pub fn altitude(m: &link::AltitudeFusion, stamp: Time, cfg: &Config) -> (Altitude, Range) {
    let laser = if m.laser_m >= LASER_NO_RETURN_M {
        f32::INFINITY
    } else {
        m.laser_m
    };
    let alt = Altitude {
        header: Header::new(stamp, &cfg.map_frame),
        baro_alt_m: m.baro_alt_m,
        alt_m: m.alt_m,
        vertical_speed_mps: -m.vel_down_mps,
        ground_height_m: m.ground_height_m,
        ground_variance_m2: m.ground_var_m2,
        laser_range_m: laser,
        sonar_range_m: m.sonar_m,
        source: altitude_source(m.source),
    };
    let spec = match m.source {
        link::AltitudeSource::Sonar => cfg.sonar,
        _ => cfg.laser,
    };
    let ground = Range {
        header: Header::new(stamp, &cfg.base_frame),
        radiation_type: spec.radiation_type,
        field_of_view: spec.field_of_view_rad,
        min_range: 0.0,
        max_range: spec.max_m,
        range: m.ground_height_m,
        variance: if m.ground_var_m2.is_finite() {
            m.ground_var_m2
        } else {
            0.0
        },
    };
    (alt, ground)
}

pub fn mode_code(m: link::FlightMode) -> (u8, &'static str) {
    (m.code(), m.name()) // `Status.MODE_*`: fcc_msgs::vocab
}

pub fn failsafe_code(f: link::FailsafeCause) -> (u8, &'static str) {
    (f.code(), f.name()) // `Status.FAILSAFE_*`: fcc_msgs::vocab
}

pub fn reject_name(r: link::CommandResult) -> &'static str {
    match r {
        link::CommandResult::Accepted => "accepted",
        link::CommandResult::NotCalibrated => "not_calibrated",
        link::CommandResult::NoHome => "no_home",
        link::CommandResult::NotLanded => "not_landed",
        link::CommandResult::Disarmed => "disarmed",
        link::CommandResult::InvalidSetpoint => "invalid_setpoint",
        link::CommandResult::Incompatible => "incompatible",
        link::CommandResult::PilotOverride => "pilot_override",
        link::CommandResult::KillNotConfirmed => "kill_not_confirmed",
    }
}

/// The MCU's part of `fcc_msgs/Status`; the bridge fills in its own counters.
pub fn status(m: &link::Status, stamp: Time, cfg: &Config) -> Status {
    let (mode, mode_name) = mode_code(m.mode);
    let (failsafe, failsafe_name) = failsafe_code(m.failsafe);
    Status {
        header: Header::new(stamp, &cfg.base_frame),
        mode,
        mode_name: mode_name.into(),
        armed: m.armed,
        landed: m.landed,
        failsafe,
        failsafe_name: failsafe_name.into(),
        gps_ok: m.sensors.gps_ok,
        mag_disturbed: m.sensors.mag_disturbed,
        mag_rejects: m.sensors.mag_rejects,
        laser_ok: m.sensors.laser_ok,
        sonar_ok: m.sensors.sonar_ok,
        mag_disturbed_s: m.sensors.mag_disturbed_ds as f32 * 0.1,
        nav_faults: m.sensors.nav_faults,
        loop_time_max_us: m.loop_time_max_us,
        loop_time_avg_us: m.loop_time_avg_us,
        last_reject: reject_name(m.last_reject).into(),
        setpoint_rejects: m.setpoint_rejects,
        command_rejects: m.command_rejects,
        mcu_tx_frames: m.tx_frames,
        mcu_tx_dropped: m.tx_dropped,
        mcu_rx_frames: m.link_rx.rx_frames,
        mcu_crc_errors: m.link_rx.crc_errors,
        mcu_resyncs: m.link_rx.resyncs,
        mcu_frames_lost: m.link_rx.frames_lost,
        ..Status::default()
    }
}

// --------------------------------------------------------------------------- ROS → link

/// Limits for incoming setpoints.
#[derive(Clone, Copy, Debug)]
pub struct SetpointLimits {
    /// Largest accepted speed per axis, m/s.
    pub max_speed_mps: f64,
    /// Largest age of a stamped setpoint, ns (stamp 0 = unstamped is accepted).
    pub max_age_ns: i64,
    /// Largest amount a stamp may lie in the future, ns.
    pub max_future_ns: i64,
    /// Time-to-live given to the MCU, ms.
    pub ttl_ms: u16,
}

impl Default for SetpointLimits {
    fn default() -> Self {
        SetpointLimits {
            max_speed_mps: 20.0,
            max_age_ns: 500_000_000,
            max_future_ns: 500_000_000,
            ttl_ms: 300,
        }
    }
}

/// Why a setpoint was refused by the bridge.
#[derive(Clone, Debug, PartialEq)]
pub enum SetpointReject {
    NotFinite,
    TooLarge(f64),
    /// `header.frame_id` over [`bounded::MAX_FRAME_ID`] bytes.
    Oversize(bounded::Oversize),
    /// An unknown frame (the name as received, at most [`bounded::MAX_FRAME_ID`] bytes).
    UnknownFrame(String),
    /// `base_link` setpoint but no navigation state yet (heading unknown).
    NoHeading,
    /// `twist.angular.z` over [`link::SETPOINT_YAW_RATE_ABS_MAX_RADPS`], rad/s.
    YawRateTooLarge(f64),
    /// A `setpoint/heading` quaternion whose norm is not 1 (± [`HEADING_NORM_TOL`]).
    NotUnitQuaternion(f64),
    /// A `setpoint/heading` in a frame other than a world (ENU) frame (the name as received,
    /// at most [`bounded::MAX_FRAME_ID`] bytes).
    HeadingFrame(String),
    Stale {
        age_ms: i64,
    },
    Future {
        ahead_ms: i64,
    },
}

impl SetpointReject {
    /// The kind of refusal (for rate-limiting its warnings).
    pub fn kind(&self) -> &'static str {
        match self {
            SetpointReject::NotFinite => "setpoint_not_finite",
            SetpointReject::TooLarge(_) => "setpoint_too_large",
            SetpointReject::Oversize(_) => "setpoint_oversize",
            SetpointReject::UnknownFrame(_) => "setpoint_unknown_frame",
            SetpointReject::NoHeading => "setpoint_no_heading",
            SetpointReject::YawRateTooLarge(_) => "setpoint_yaw_rate_too_large",
            SetpointReject::NotUnitQuaternion(_) => "heading_not_unit",
            SetpointReject::HeadingFrame(_) => "heading_frame",
            SetpointReject::Stale { .. } => "setpoint_stale",
            SetpointReject::Future { .. } => "setpoint_future",
        }
    }
}

impl std::fmt::Display for SetpointReject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SetpointReject::NotFinite => write!(f, "non-finite value"),
            SetpointReject::TooLarge(v) => write!(f, "speed {v:.1} m/s over the limit"),
            SetpointReject::Oversize(o) => write!(f, "{o}"),
            SetpointReject::UnknownFrame(s) => write!(
                f,
                "unknown frame_id '{}' (use map, odom, empty = ENU, or base_link = FLU)",
                bounded::log_value(s, bounded::LOG_CHARS)
            ),
            SetpointReject::NoHeading => {
                write!(f, "base_link setpoint before any navigation state")
            }
            SetpointReject::YawRateTooLarge(r) => write!(
                f,
                "yaw rate {r:.2} rad/s over the limit {:.2}",
                link::SETPOINT_YAW_RATE_ABS_MAX_RADPS
            ),
            SetpointReject::NotUnitQuaternion(n) => {
                write!(f, "heading quaternion norm {n:.4}, not a unit quaternion")
            }
            SetpointReject::HeadingFrame(s) => write!(
                f,
                "frame_id '{}': a heading is an orientation in map, odom or empty (ENU)",
                bounded::log_value(s, bounded::LOG_CHARS)
            ),
            SetpointReject::Stale { age_ms } => write!(f, "stamp {age_ms} ms old"),
            SetpointReject::Future { ahead_ms } => write!(f, "stamp {ahead_ms} ms in the future"),
        }
    }
}

/// How far a `setpoint/heading` quaternion's norm may be from 1.
pub const HEADING_NORM_TOL: f64 = 1e-3;

/// A heading from `setpoint/heading` is attached to the velocity setpoints received at most
/// this long after it (bridge clock), ns; then it is dropped and the setpoints keep the heading.
pub const HEADING_MAX_AGE_NS: i64 = 2_000_000_000;

/// `frame_id` no longer than [`bounded::MAX_FRAME_ID`] (checked first on the read topics).
fn check_frame_id_len(h: &Header) -> Result<(), SetpointReject> {
    let id_len = h.frame_id.len();
    if id_len > bounded::MAX_FRAME_ID {
        return Err(SetpointReject::Oversize(bounded::Oversize {
            field: "frame_id",
            len: id_len,
            max: bounded::MAX_FRAME_ID,
        }));
    }
    Ok(())
}

/// Checks shared by the read topics after their values': stamp within the limits (0 = now),
/// then a world frame (`map`, `odom`, the configured ones, or empty = ENU) or the body frame.
/// `true` = the body frame.
fn check_header(
    h: &Header,
    now_ns: i64,
    cfg: &Config,
    lim: &SetpointLimits,
) -> Result<bool, SetpointReject> {
    if !h.stamp.is_zero() {
        let t = h.stamp.to_nanos();
        if now_ns - t > lim.max_age_ns {
            return Err(SetpointReject::Stale {
                age_ms: (now_ns - t) / 1_000_000,
            });
        }
        if t - now_ns > lim.max_future_ns {
            return Err(SetpointReject::Future {
                ahead_ms: (t - now_ns) / 1_000_000,
            });
        }
    }
    let f = h.frame_id.trim_start_matches('/');
    if f.is_empty() || f == "map" || f == "odom" || f == cfg.map_frame || f == cfg.odom_frame {
        Ok(false)
    } else if f == cfg.base_frame || f == "base_link" {
        Ok(true)
    } else {
        Err(SetpointReject::UnknownFrame(h.frame_id.clone()))
    }
}

/// `setpoint/heading` (`QuaternionStamped`) → the heading to hold, NED yaw (rad, from north
/// towards east, wrapped to (−π, π]).
///
/// The quaternion is an orientation in ENU (`frame_id` `map`, `odom` or empty; REP-103: yaw 0
/// faces east, counter-clockwise positive); only its yaw is used (roll and pitch are the
/// MCU's). Refused: a non-finite or non-unit quaternion (norm outside 1 ± [`HEADING_NORM_TOL`]),
/// any other frame (`base_link` too: a heading relative to the body is a turn, send a yaw rate),
/// a stamp outside the setpoint limits.
pub fn heading(
    m: &QuaternionStamped,
    now_ns: i64,
    cfg: &Config,
    lim: &SetpointLimits,
) -> Result<f64, SetpointReject> {
    check_frame_id_len(&m.header)?;
    let q = m.quaternion;
    let q = [q.w, q.x, q.y, q.z];
    if q.iter().any(|c| !c.is_finite()) {
        return Err(SetpointReject::NotFinite);
    }
    match check_header(&m.header, now_ns, cfg, lim) {
        Ok(false) => {}
        Ok(true) | Err(SetpointReject::UnknownFrame(_)) => {
            return Err(SetpointReject::HeadingFrame(m.header.frame_id.clone()))
        }
        Err(e) => return Err(e),
    }
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > HEADING_NORM_TOL {
        return Err(SetpointReject::NotUnitQuaternion(norm));
    }
    Ok(frames::yaw_enu_to_ned(frames::yaw_enu_of_q_enu(q)))
}

/// `TwistStamped` → link `VelocitySetpoint` (NED).
///
/// - `header.frame_id` `map`, `odom` (or the configured map frame) or empty: `twist.linear` is
///   ENU. `base_link` (the configured base frame): FLU body, levelled (rotated by the current
///   heading only, see [`frames::flu_heading_to_ned`]).
/// - Heading: `twist.angular.z` ≠ 0 (rad/s, z up: counter-clockwise seen from above, in either
///   frame) → [`link::YawSetpoint::Rate`] at the NED rate −`angular.z` (the MCU turns the
///   heading it holds at that rate; over [`link::SETPOINT_YAW_RATE_ABS_MAX_RADPS`] refused).
///   Else `heading_ned` (the latest `setpoint/heading`, see [`heading`]; the caller drops it
///   after [`HEADING_MAX_AGE_NS`] and after a yaw-rate setpoint) → [`link::YawSetpoint::Heading`];
///   else [`link::YawSetpoint::Keep`]: the vehicle keeps the heading it holds (where a turn
///   stopped, or the last heading sent). `angular.x`/`y` are ignored (must be finite).
/// - Stamp 0 (as `ros2 topic pub` sends without `--stamp`) is accepted as "now"; other stamps
///   must be within the limits of `now_ns`.
pub fn setpoint(
    m: &TwistStamped,
    now_ns: i64,
    yaw_ned: Option<f64>,
    heading_ned: Option<f64>,
    cfg: &Config,
    lim: &SetpointLimits,
) -> Result<link::VelocitySetpoint, SetpointReject> {
    check_frame_id_len(&m.header)?;
    let lin = m.twist.linear.to_array();
    let ang = m.twist.angular.to_array();
    if lin.iter().chain(ang.iter()).any(|v| !v.is_finite()) {
        return Err(SetpointReject::NotFinite);
    }
    if let Some(v) = lin.iter().map(|v| v.abs()).find(|v| *v > lim.max_speed_mps) {
        return Err(SetpointReject::TooLarge(v));
    }
    if ang[2].abs() > link::SETPOINT_YAW_RATE_ABS_MAX_RADPS as f64 {
        return Err(SetpointReject::YawRateTooLarge(ang[2]));
    }
    let ned = if check_header(&m.header, now_ns, cfg, lim)? {
        let yaw = yaw_ned.ok_or(SetpointReject::NoHeading)?;
        frames::flu_heading_to_ned(lin, yaw)
    } else {
        frames::enu_to_ned(lin)
    };
    let yaw = match (ang[2] != 0.0, heading_ned) {
        (true, _) => link::YawSetpoint::Rate {
            yaw_rate_ned_radps: frames::yaw_rate_enu_to_ned(ang[2]) as f32,
        },
        (false, Some(h)) => link::YawSetpoint::Heading {
            yaw_ned_rad: h as f32,
        },
        (false, None) => link::YawSetpoint::Keep,
    };
    Ok(link::VelocitySetpoint {
        vel_ned_mps: [ned[0] as f32, ned[1] as f32, ned[2] as f32],
        yaw,
        ttl_ms: lim.ttl_ms,
    })
}

/// `cmd/arm`: true → Arm, false → Disarm.
pub fn arm_command(m: &Bool) -> link::Command {
    link::Command {
        command: if m.data {
            link::CommandKind::Arm
        } else {
            link::CommandKind::Disarm
        },
        confirm: 0,
    }
}

/// The text `cmd/kill` must carry, exactly: the emergency kill is never a typo of a mode.
pub const KILL_TEXT: &str = "KILL";

/// `cmd/kill`: exactly [`KILL_TEXT`] → the MCU's emergency kill with its confirmation; any
/// other text → `None` (refused).
pub fn kill_command(m: &StringMsg) -> Option<link::Command> {
    (m.data == KILL_TEXT).then_some(link::Command {
        command: link::CommandKind::Kill,
        confirm: link::KILL_CONFIRM,
    })
}

/// `cmd/mode`: `hold`, `land`, `velocity` (also `arm`/`disarm`), case-insensitive; a text over
/// [`bounded::MAX_MODE`] bytes is no mode.
pub fn mode_command(m: &StringMsg) -> Option<link::Command> {
    if m.data.len() > bounded::MAX_MODE {
        return None;
    }
    let c = match m.data.trim().to_ascii_lowercase().as_str() {
        "hold" | "loiter" | "position" => link::CommandKind::Hold,
        "land" => link::CommandKind::Land,
        "velocity" | "offboard" => link::CommandKind::Velocity,
        "arm" => link::CommandKind::Arm,
        "disarm" => link::CommandKind::Disarm,
        _ => return None,
    };
    Some(link::Command {
        command: c,
        confirm: 0,
    })
}

#[cfg(test)]
mod tests;
