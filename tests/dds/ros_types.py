"""ROS 2 (Jazzy) message types as Cyclone DDS IDL structs, named exactly as rmw names them
(`pkg::msg::dds_::Type_`). Independent of the Rust bridge: written from the .msg files."""
from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import (array, float32, float64, int8, int32, int64, sequence, uint8,
                                  uint16, uint32, uint64)


def _t(pkg, name):
    return f"{pkg}::msg::dds_::{name}_"


@dataclass
class Time(IdlStruct, typename=_t("builtin_interfaces", "Time")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename=_t("std_msgs", "Header")):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Bool(IdlStruct, typename=_t("std_msgs", "Bool")):
    data: bool = False


@dataclass
class String(IdlStruct, typename=_t("std_msgs", "String")):
    data: str = ""


@dataclass
class Vector3(IdlStruct, typename=_t("geometry_msgs", "Vector3")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename=_t("geometry_msgs", "Quaternion")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class QuaternionStamped(IdlStruct, typename=_t("geometry_msgs", "QuaternionStamped")):
    header: Header = field(default_factory=Header)
    quaternion: Quaternion = field(default_factory=Quaternion)


@dataclass
class Point(IdlStruct, typename=_t("geometry_msgs", "Point")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Pose(IdlStruct, typename=_t("geometry_msgs", "Pose")):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseWithCovariance(IdlStruct, typename=_t("geometry_msgs", "PoseWithCovariance")):
    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Twist(IdlStruct, typename=_t("geometry_msgs", "Twist")):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class TwistWithCovariance(IdlStruct, typename=_t("geometry_msgs", "TwistWithCovariance")):
    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class TwistStamped(IdlStruct, typename=_t("geometry_msgs", "TwistStamped")):
    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@dataclass
class Accel(IdlStruct, typename=_t("geometry_msgs", "Accel")):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class AccelStamped(IdlStruct, typename=_t("geometry_msgs", "AccelStamped")):
    header: Header = field(default_factory=Header)
    accel: Accel = field(default_factory=Accel)


@dataclass
class Transform(IdlStruct, typename=_t("geometry_msgs", "Transform")):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename=_t("geometry_msgs", "TransformStamped")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class TFMessage(IdlStruct, typename=_t("tf2_msgs", "TFMessage")):
    transforms: sequence[TransformStamped] = field(default_factory=list)


@dataclass
class Imu(IdlStruct, typename=_t("sensor_msgs", "Imu")):
    header: Header
    orientation: Quaternion
    orientation_covariance: array[float64, 9]
    angular_velocity: Vector3
    angular_velocity_covariance: array[float64, 9]
    linear_acceleration: Vector3
    linear_acceleration_covariance: array[float64, 9]


@dataclass
class MagneticField(IdlStruct, typename=_t("sensor_msgs", "MagneticField")):
    header: Header
    magnetic_field: Vector3
    magnetic_field_covariance: array[float64, 9]


@dataclass
class FluidPressure(IdlStruct, typename=_t("sensor_msgs", "FluidPressure")):
    header: Header
    fluid_pressure: float64
    variance: float64


@dataclass
class NavSatStatus(IdlStruct, typename=_t("sensor_msgs", "NavSatStatus")):
    status: int8
    service: uint16


@dataclass
class NavSatFix(IdlStruct, typename=_t("sensor_msgs", "NavSatFix")):
    header: Header
    status: NavSatStatus
    latitude: float64
    longitude: float64
    altitude: float64
    position_covariance: array[float64, 9]
    position_covariance_type: uint8


@dataclass
class Range(IdlStruct, typename=_t("sensor_msgs", "Range")):
    """Jazzy layout: `variance` after `range`."""
    header: Header
    radiation_type: uint8
    field_of_view: float32
    min_range: float32
    max_range: float32
    range: float32
    variance: float32


@dataclass
class BatteryState(IdlStruct, typename=_t("sensor_msgs", "BatteryState")):
    header: Header
    voltage: float32
    temperature: float32
    current: float32
    charge: float32
    capacity: float32
    design_capacity: float32
    percentage: float32
    power_supply_status: uint8
    power_supply_health: uint8
    power_supply_technology: uint8
    present: bool
    cell_voltage: sequence[float32]
    cell_temperature: sequence[float32]
    location: str
    serial_number: str


@dataclass
class Odometry(IdlStruct, typename=_t("nav_msgs", "Odometry")):
    header: Header
    child_frame_id: str
    pose: PoseWithCovariance
    twist: TwistWithCovariance


@dataclass
class KeyValue(IdlStruct, typename=_t("diagnostic_msgs", "KeyValue")):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename=_t("diagnostic_msgs", "DiagnosticStatus")):
    level: uint8
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename=_t("diagnostic_msgs", "DiagnosticArray")):
    header: Header
    status: sequence[DiagnosticStatus]


@dataclass
class Log(IdlStruct, typename=_t("rcl_interfaces", "Log")):
    """rcl_interfaces/msg/Log (/rosout)"""
    stamp: Time
    level: uint8
    name: str
    msg: str
    file: str
    function: str
    line: uint32


@dataclass
class Altitude(IdlStruct, typename=_t("fcc_msgs", "Altitude")):
    """msg/msg/Altitude.msg"""
    header: Header
    baro_alt_m: float32
    alt_m: float32
    vertical_speed_mps: float32
    ground_height_m: float32
    ground_variance_m2: float32
    laser_range_m: float32
    sonar_range_m: float32
    source: uint8


@dataclass
class Status(IdlStruct, typename=_t("fcc_msgs", "Status")):
    """msg/msg/Status.msg"""
    header: Header
    mode: uint8
    mode_name: str
    armed: bool
    landed: bool
    failsafe: uint8
    failsafe_name: str
    gps_ok: bool
    mag_disturbed: bool
    mag_rejects: uint32
    laser_ok: bool
    sonar_ok: bool
    mag_disturbed_s: float32
    nav_faults: uint8
    loop_time_max_us: uint32
    loop_time_avg_us: uint32
    last_reject: str
    setpoint_rejects: uint32
    command_rejects: uint32
    mcu_tx_frames: uint32
    mcu_tx_dropped: uint32
    rx_bytes: uint64
    rx_frames: uint64
    crc_errors: uint64
    framing_errors: uint64
    resyncs: uint64
    decode_errors: uint64
    frames_lost: uint64
    dropped: uint64
    mcu_rx_frames: uint32
    mcu_crc_errors: uint32
    mcu_resyncs: uint32
    mcu_frames_lost: uint32
    setpoints_forwarded: uint64
    setpoint_rejects_bridge: uint64
    commands_forwarded: uint64
    time_synced: bool
    time_sync_offset_ns: int64
    time_sync_rtt_us: uint32


# rmw_dds_common (Jazzy: 16-byte GIDs) — what `ros2 node list` reads.
@dataclass
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: array[uint8, 16]


@dataclass
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: str
    node_name: str
    reader_gid_seq: sequence[Gid]
    writer_gid_seq: sequence[Gid]


@dataclass
class ParticipantEntitiesInfo(IdlStruct,
                              typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
    gid: Gid
    node_entities_info_seq: sequence[NodeEntitiesInfo]


# The mission node's actions (fcc_msgs/action/FollowWaypoints, GoTo, Takeoff, Land; issue 17):
# their topics, as
# rmw names them (`_action/feedback`, `_action/status`), written from the .action file and
# action_msgs/unique_identifier_msgs.
@dataclass
class UUID(IdlStruct, typename=_t("unique_identifier_msgs", "UUID")):
    uuid: array[uint8, 16]


@dataclass
class GoalInfo(IdlStruct, typename=_t("action_msgs", "GoalInfo")):
    goal_id: UUID
    stamp: Time


@dataclass
class GoalStatus(IdlStruct, typename=_t("action_msgs", "GoalStatus")):
    goal_info: GoalInfo
    status: int8


@dataclass
class GoalStatusArray(IdlStruct, typename=_t("action_msgs", "GoalStatusArray")):
    status_list: sequence[GoalStatus]


@dataclass
class FollowWaypointsFeedback(IdlStruct, typename="fcc_msgs::action::dds_::FollowWaypoints_Feedback_"):
    current_waypoint: uint32
    waypoint_count: uint32
    phase: str
    distance_to_go_m: float32
    eta_s: float32
    cross_track_m: float32


@dataclass
class FollowWaypointsFeedbackMessage(IdlStruct,
                                     typename="fcc_msgs::action::dds_::FollowWaypoints_FeedbackMessage_"):
    goal_id: UUID
    feedback: FollowWaypointsFeedback


# GoTo, Takeoff and Land share FollowWaypoints' feedback fields (msg/build.rs checks the .action
# files) under their own type names.
@dataclass
class GoToFeedback(IdlStruct, typename="fcc_msgs::action::dds_::GoTo_Feedback_"):
    current_waypoint: uint32
    waypoint_count: uint32
    phase: str
    distance_to_go_m: float32
    eta_s: float32
    cross_track_m: float32


@dataclass
class GoToFeedbackMessage(IdlStruct, typename="fcc_msgs::action::dds_::GoTo_FeedbackMessage_"):
    goal_id: UUID
    feedback: GoToFeedback


@dataclass
class TakeoffFeedback(IdlStruct, typename="fcc_msgs::action::dds_::Takeoff_Feedback_"):
    current_waypoint: uint32
    waypoint_count: uint32
    phase: str
    distance_to_go_m: float32
    eta_s: float32
    cross_track_m: float32


@dataclass
class TakeoffFeedbackMessage(IdlStruct, typename="fcc_msgs::action::dds_::Takeoff_FeedbackMessage_"):
    goal_id: UUID
    feedback: TakeoffFeedback


@dataclass
class LandFeedback(IdlStruct, typename="fcc_msgs::action::dds_::Land_Feedback_"):
    current_waypoint: uint32
    waypoint_count: uint32
    phase: str
    distance_to_go_m: float32
    eta_s: float32
    cross_track_m: float32


@dataclass
class LandFeedbackMessage(IdlStruct, typename="fcc_msgs::action::dds_::Land_FeedbackMessage_"):
    goal_id: UUID
    feedback: LandFeedback
