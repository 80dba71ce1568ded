//! Standard ROS 2 (Jazzy) message types used by the bridge.
//!
//! Definitions are the `.msg` texts with comments stripped (fields and constants as in Jazzy).

use super::ros_msg;
use serde::{Deserialize, Serialize};
use serde_big_array::BigArray;

// ------------------------------------------------------------------ builtin_interfaces, std_msgs

/// builtin_interfaces/Time: seconds and nanoseconds since the epoch (or sim start).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}
ros_msg!(
    Time,
    "builtin_interfaces",
    "Time",
    "int32 sec\nuint32 nanosec\n"
);

impl Time {
    /// From nanoseconds (negative values clamp to 0; beyond 2038 saturates).
    pub fn from_nanos(ns: i64) -> Self {
        if ns <= 0 {
            return Time::default();
        }
        let sec = (ns / 1_000_000_000).min(i32::MAX as i64) as i32;
        Time {
            sec,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }
    pub fn to_nanos(&self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }
    pub fn is_zero(&self) -> bool {
        self.sec == 0 && self.nanosec == 0
    }
}

/// std_msgs/Header.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}
ros_msg!(
    Header,
    "std_msgs",
    "Header",
    "builtin_interfaces/Time stamp\nstring frame_id\n",
    [Time]
);

impl Header {
    pub fn new(stamp: Time, frame_id: &str) -> Self {
        Header {
            stamp,
            frame_id: frame_id.to_owned(),
        }
    }
}

/// std_msgs/Bool.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Bool {
    pub data: bool,
}
ros_msg!(Bool, "std_msgs", "Bool", "bool data\n");

/// std_msgs/String.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StringMsg {
    pub data: String,
}
ros_msg!(StringMsg, "std_msgs", "String", "string data\n");

/// rosgraph_msgs/Clock.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    pub clock: Time,
}
ros_msg!(
    Clock,
    "rosgraph_msgs",
    "Clock",
    "builtin_interfaces/Time clock\n",
    [Time]
);

// ------------------------------------------------------------------------------- geometry_msgs

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}
ros_msg!(
    Vector3,
    "geometry_msgs",
    "Vector3",
    "float64 x\nfloat64 y\nfloat64 z\n"
);

impl Vector3 {
    pub fn new(v: [f64; 3]) -> Self {
        Vector3 {
            x: v[0],
            y: v[1],
            z: v[2],
        }
    }
    pub fn to_array(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}
ros_msg!(
    Quaternion,
    "geometry_msgs",
    "Quaternion",
    "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
);

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

impl Quaternion {
    /// From `[w, x, y, z]`.
    pub fn from_wxyz(q: [f64; 4]) -> Self {
        Quaternion {
            w: q[0],
            x: q[1],
            y: q[2],
            z: q[3],
        }
    }
}

/// geometry_msgs/QuaternionStamped: an orientation in `header.frame_id`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct QuaternionStamped {
    pub header: Header,
    pub quaternion: Quaternion,
}
ros_msg!(
    QuaternionStamped,
    "geometry_msgs",
    "QuaternionStamped",
    "std_msgs/Header header\nQuaternion quaternion\n",
    [Header, Quaternion]
);

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}
ros_msg!(
    Point,
    "geometry_msgs",
    "Point",
    "float64 x\nfloat64 y\nfloat64 z\n"
);

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Point,
    pub orientation: Quaternion,
}
ros_msg!(
    Pose,
    "geometry_msgs",
    "Pose",
    "Point position\nQuaternion orientation\n",
    [Point, Quaternion]
);

/// `geometry_msgs/<Value>WithCovariance`: a value and its row-major 6×6 covariance
/// (x, y, z, rot x, rot y, rot z), zero by default.
macro_rules! with_covariance {
    ($name:ident, $field:ident: $inner:ident) => {
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub struct $name {
            pub $field: $inner,
            /// Row-major 6×6 (x, y, z, rot x, rot y, rot z).
            #[serde(with = "BigArray")]
            pub covariance: [f64; 36],
        }
        ros_msg!(
            $name,
            "geometry_msgs",
            stringify!($name),
            concat!(
                stringify!($inner),
                " ",
                stringify!($field),
                "\nfloat64[36] covariance\n"
            ),
            [$inner]
        );
        impl Default for $name {
            fn default() -> Self {
                $name {
                    $field: $inner::default(),
                    covariance: [0.0; 36],
                }
            }
        }
    };
}
with_covariance!(PoseWithCovariance, pose: Pose);

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    pub linear: Vector3,
    pub angular: Vector3,
}
ros_msg!(
    Twist,
    "geometry_msgs",
    "Twist",
    "Vector3  linear\nVector3  angular\n",
    [Vector3]
);

with_covariance!(TwistWithCovariance, twist: Twist);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TwistStamped {
    pub header: Header,
    pub twist: Twist,
}
ros_msg!(
    TwistStamped,
    "geometry_msgs",
    "TwistStamped",
    "std_msgs/Header header\nTwist twist\n",
    [Header, Twist]
);

/// geometry_msgs/Accel: linear (m/s²) and angular (rad/s²) acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Accel {
    pub linear: Vector3,
    pub angular: Vector3,
}
ros_msg!(
    Accel,
    "geometry_msgs",
    "Accel",
    "Vector3  linear\nVector3  angular\n",
    [Vector3]
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AccelStamped {
    pub header: Header,
    pub accel: Accel,
}
ros_msg!(
    AccelStamped,
    "geometry_msgs",
    "AccelStamped",
    "std_msgs/Header header\nAccel accel\n",
    [Header, Accel]
);

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    pub translation: Vector3,
    pub rotation: Quaternion,
}
ros_msg!(
    Transform,
    "geometry_msgs",
    "Transform",
    "Vector3 translation\nQuaternion rotation\n",
    [Vector3, Quaternion]
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}
ros_msg!(
    TransformStamped,
    "geometry_msgs",
    "TransformStamped",
    "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
    [Header, Transform]
);

// --------------------------------------------------------------------------------- sensor_msgs

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Imu {
    pub header: Header,
    pub orientation: Quaternion,
    pub orientation_covariance: [f64; 9],
    pub angular_velocity: Vector3,
    pub angular_velocity_covariance: [f64; 9],
    pub linear_acceleration: Vector3,
    pub linear_acceleration_covariance: [f64; 9],
}
ros_msg!(
    Imu,
    "sensor_msgs",
    "Imu",
    "std_msgs/Header header\n\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
    [Header, Quaternion, Vector3]
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MagneticField {
    pub header: Header,
    /// Tesla.
    pub magnetic_field: Vector3,
    pub magnetic_field_covariance: [f64; 9],
}
ros_msg!(
    MagneticField,
    "sensor_msgs",
    "MagneticField",
    "std_msgs/Header header\n\ngeometry_msgs/Vector3 magnetic_field\nfloat64[9] magnetic_field_covariance\n",
    [Header, Vector3]
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FluidPressure {
    pub header: Header,
    /// Pascal.
    pub fluid_pressure: f64,
    /// Pa²; 0 = unknown.
    pub variance: f64,
}
ros_msg!(
    FluidPressure,
    "sensor_msgs",
    "FluidPressure",
    "std_msgs/Header header\n\nfloat64 fluid_pressure\nfloat64 variance\n",
    [Header]
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NavSatStatus {
    pub status: i8,
    pub service: u16,
}
ros_msg!(
    NavSatStatus,
    "sensor_msgs",
    "NavSatStatus",
    "int8 STATUS_UNKNOWN = -2\nint8 STATUS_NO_FIX =  -1\nint8 STATUS_FIX =      0\nint8 STATUS_SBAS_FIX = 1\nint8 STATUS_GBAS_FIX = 2\n\nint8 status -2\n\nuint16 SERVICE_UNKNOWN = 0\nuint16 SERVICE_GPS =     1\nuint16 SERVICE_GLONASS = 2\nuint16 SERVICE_COMPASS = 4\nuint16 SERVICE_GALILEO = 8\n\nuint16 service\n"
);

impl NavSatStatus {
    pub const STATUS_NO_FIX: i8 = -1;
    pub const STATUS_FIX: i8 = 0;
    pub const SERVICE_GPS: u16 = 1;
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NavSatFix {
    pub header: Header,
    pub status: NavSatStatus,
    /// Degrees, + north.
    pub latitude: f64,
    /// Degrees, + east.
    pub longitude: f64,
    /// Metres above the WGS-84 ellipsoid.
    pub altitude: f64,
    /// ENU, m², row-major.
    pub position_covariance: [f64; 9],
    pub position_covariance_type: u8,
}
ros_msg!(
    NavSatFix,
    "sensor_msgs",
    "NavSatFix",
    "std_msgs/Header header\n\nNavSatStatus status\n\nfloat64 latitude\n\nfloat64 longitude\n\nfloat64 altitude\n\nfloat64[9] position_covariance\n\nuint8 COVARIANCE_TYPE_UNKNOWN = 0\nuint8 COVARIANCE_TYPE_APPROXIMATED = 1\nuint8 COVARIANCE_TYPE_DIAGONAL_KNOWN = 2\nuint8 COVARIANCE_TYPE_KNOWN = 3\n\nuint8 position_covariance_type\n",
    [Header, NavSatStatus]
);

impl NavSatFix {
    pub const COVARIANCE_TYPE_UNKNOWN: u8 = 0;
    pub const COVARIANCE_TYPE_APPROXIMATED: u8 = 1;
}

/// sensor_msgs/Range, **Jazzy** layout (with `variance`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Range {
    pub header: Header,
    pub radiation_type: u8,
    /// Radians, full cone angle.
    pub field_of_view: f32,
    pub min_range: f32,
    pub max_range: f32,
    /// Metres; +inf = no return within range, −inf = too close (REP-117).
    pub range: f32,
    /// m²; 0 = unknown.
    pub variance: f32,
}
ros_msg!(
    Range,
    "sensor_msgs",
    "Range",
    "std_msgs/Header header\n\nuint8 ULTRASOUND=0\nuint8 INFRARED=1\n\nuint8 radiation_type\n\nfloat32 field_of_view\n\nfloat32 min_range\nfloat32 max_range\n\nfloat32 range\n\nfloat32 variance\n",
    [Header]
);

impl Range {
    pub const ULTRASOUND: u8 = 0;
    pub const INFRARED: u8 = 1;
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BatteryState {
    pub header: Header,
    pub voltage: f32,
    pub temperature: f32,
    pub current: f32,
    pub charge: f32,
    pub capacity: f32,
    pub design_capacity: f32,
    pub percentage: f32,
    pub power_supply_status: u8,
    pub power_supply_health: u8,
    pub power_supply_technology: u8,
    pub present: bool,
    pub cell_voltage: Vec<f32>,
    pub cell_temperature: Vec<f32>,
    pub location: String,
    pub serial_number: String,
}
ros_msg!(
    BatteryState,
    "sensor_msgs",
    "BatteryState",
    "uint8 POWER_SUPPLY_STATUS_UNKNOWN = 0\nuint8 POWER_SUPPLY_STATUS_CHARGING = 1\nuint8 POWER_SUPPLY_STATUS_DISCHARGING = 2\nuint8 POWER_SUPPLY_STATUS_NOT_CHARGING = 3\nuint8 POWER_SUPPLY_STATUS_FULL = 4\n\nuint8 POWER_SUPPLY_HEALTH_UNKNOWN = 0\nuint8 POWER_SUPPLY_HEALTH_GOOD = 1\nuint8 POWER_SUPPLY_HEALTH_OVERHEAT = 2\nuint8 POWER_SUPPLY_HEALTH_DEAD = 3\nuint8 POWER_SUPPLY_HEALTH_OVERVOLTAGE = 4\nuint8 POWER_SUPPLY_HEALTH_UNSPEC_FAILURE = 5\nuint8 POWER_SUPPLY_HEALTH_COLD = 6\nuint8 POWER_SUPPLY_HEALTH_WATCHDOG_TIMER_EXPIRE = 7\nuint8 POWER_SUPPLY_HEALTH_SAFETY_TIMER_EXPIRE = 8\n\nuint8 POWER_SUPPLY_TECHNOLOGY_UNKNOWN = 0\nuint8 POWER_SUPPLY_TECHNOLOGY_NIMH = 1\nuint8 POWER_SUPPLY_TECHNOLOGY_LION = 2\nuint8 POWER_SUPPLY_TECHNOLOGY_LIPO = 3\nuint8 POWER_SUPPLY_TECHNOLOGY_LIFE = 4\nuint8 POWER_SUPPLY_TECHNOLOGY_NICD = 5\nuint8 POWER_SUPPLY_TECHNOLOGY_LIMN = 6\nuint8 POWER_SUPPLY_TECHNOLOGY_TERNARY = 7\nuint8 POWER_SUPPLY_TECHNOLOGY_VRLA = 8\n\nstd_msgs/Header  header\nfloat32 voltage\nfloat32 temperature\nfloat32 current\nfloat32 charge\nfloat32 capacity\nfloat32 design_capacity\nfloat32 percentage\nuint8   power_supply_status\nuint8   power_supply_health\nuint8   power_supply_technology\nbool    present\n\nfloat32[] cell_voltage\nfloat32[] cell_temperature\n\nstring location\nstring serial_number\n",
    [Header]
);

impl BatteryState {
    pub const POWER_SUPPLY_STATUS_UNKNOWN: u8 = 0;
    pub const POWER_SUPPLY_STATUS_DISCHARGING: u8 = 2;
    pub const POWER_SUPPLY_HEALTH_UNKNOWN: u8 = 0;
    pub const POWER_SUPPLY_TECHNOLOGY_LIPO: u8 = 3;
}

// ------------------------------------------------------------------------- nav_msgs, tf2_msgs

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    pub header: Header,
    pub child_frame_id: String,
    /// In `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// In `child_frame_id`.
    pub twist: TwistWithCovariance,
}
ros_msg!(
    Odometry,
    "nav_msgs",
    "Odometry",
    "std_msgs/Header header\n\nstring child_frame_id\n\ngeometry_msgs/PoseWithCovariance pose\n\ngeometry_msgs/TwistWithCovariance twist\n",
    [Header, PoseWithCovariance, TwistWithCovariance]
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TFMessage {
    pub transforms: Vec<TransformStamped>,
}
ros_msg!(
    TFMessage,
    "tf2_msgs",
    "TFMessage",
    "geometry_msgs/TransformStamped[] transforms\n",
    [TransformStamped]
);

// ---------------------------------------------------------------------------- diagnostic_msgs

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyValue {
    pub key: String,
    pub value: String,
}
ros_msg!(
    KeyValue,
    "diagnostic_msgs",
    "KeyValue",
    "string key\nstring value\n"
);

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    pub level: u8,
    pub name: String,
    pub message: String,
    pub hardware_id: String,
    pub values: Vec<KeyValue>,
}
ros_msg!(
    DiagnosticStatus,
    "diagnostic_msgs",
    "DiagnosticStatus",
    "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n\nbyte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n",
    [KeyValue]
);

impl DiagnosticStatus {
    pub const OK: u8 = 0;
    pub const WARN: u8 = 1;
    pub const ERROR: u8 = 2;
    pub const STALE: u8 = 3;
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    pub header: Header,
    pub status: Vec<DiagnosticStatus>,
}
ros_msg!(
    DiagnosticArray,
    "diagnostic_msgs",
    "DiagnosticArray",
    "std_msgs/Header header\nDiagnosticStatus[] status\n",
    [Header, DiagnosticStatus]
);
