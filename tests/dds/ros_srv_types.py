"""ROS 2 (Jazzy) service and logging types as Cyclone DDS IDL structs, named as rmw names them
(`pkg::srv::dds_::Svc_Request_`, `pkg::msg::dds_::Type_`). Written from rcl_interfaces,
std_srvs and rosgraph_msgs .msg/.srv files, independently of the Rust bridge."""
from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int64, sequence, uint8, uint32, uint64

from ros_types import Time


def _m(pkg, name):
    return f"{pkg}::msg::dds_::{name}_"


def _s(pkg, name):
    return f"{pkg}::srv::dds_::{name}_"


@dataclass
class ParameterValue(IdlStruct, typename=_m("rcl_interfaces", "ParameterValue")):
    type: uint8 = 0
    bool_value: bool = False
    integer_value: int64 = 0
    double_value: float64 = 0.0
    string_value: str = ""
    byte_array_value: sequence[uint8] = field(default_factory=list)
    bool_array_value: sequence[bool] = field(default_factory=list)
    integer_array_value: sequence[int64] = field(default_factory=list)
    double_array_value: sequence[float64] = field(default_factory=list)
    string_array_value: sequence[str] = field(default_factory=list)


@dataclass
class Parameter(IdlStruct, typename=_m("rcl_interfaces", "Parameter")):
    name: str = ""
    value: ParameterValue = field(default_factory=ParameterValue)


@dataclass
class SetParametersResult(IdlStruct, typename=_m("rcl_interfaces", "SetParametersResult")):
    successful: bool = False
    reason: str = ""


@dataclass
class ListParametersResult(IdlStruct, typename=_m("rcl_interfaces", "ListParametersResult")):
    names: sequence[str] = field(default_factory=list)
    prefixes: sequence[str] = field(default_factory=list)


@dataclass
class GetParametersRequest(IdlStruct, typename=_s("rcl_interfaces", "GetParameters_Request")):
    names: sequence[str] = field(default_factory=list)


@dataclass
class GetParametersResponse(IdlStruct, typename=_s("rcl_interfaces", "GetParameters_Response")):
    values: sequence[ParameterValue] = field(default_factory=list)


@dataclass
class SetParametersRequest(IdlStruct, typename=_s("rcl_interfaces", "SetParameters_Request")):
    parameters: sequence[Parameter] = field(default_factory=list)


@dataclass
class SetParametersResponse(IdlStruct, typename=_s("rcl_interfaces", "SetParameters_Response")):
    results: sequence[SetParametersResult] = field(default_factory=list)


@dataclass
class ListParametersRequest(IdlStruct, typename=_s("rcl_interfaces", "ListParameters_Request")):
    prefixes: sequence[str] = field(default_factory=list)
    depth: uint64 = 0


@dataclass
class ListParametersResponse(IdlStruct, typename=_s("rcl_interfaces", "ListParameters_Response")):
    result: ListParametersResult = field(default_factory=ListParametersResult)


@dataclass
class FloatingPointRange(IdlStruct, typename=_m("rcl_interfaces", "FloatingPointRange")):
    from_value: float64 = 0.0
    to_value: float64 = 0.0
    step: float64 = 0.0


@dataclass
class IntegerRange(IdlStruct, typename=_m("rcl_interfaces", "IntegerRange")):
    from_value: int64 = 0
    to_value: int64 = 0
    step: uint64 = 0


@dataclass
class ParameterDescriptor(IdlStruct, typename=_m("rcl_interfaces", "ParameterDescriptor")):
    name: str = ""
    type: uint8 = 0
    description: str = ""
    additional_constraints: str = ""
    read_only: bool = False
    dynamic_typing: bool = False
    floating_point_range: sequence[FloatingPointRange, 1] = field(default_factory=list)
    integer_range: sequence[IntegerRange, 1] = field(default_factory=list)


@dataclass
class DescribeParametersRequest(IdlStruct, typename=_s("rcl_interfaces", "DescribeParameters_Request")):
    names: sequence[str] = field(default_factory=list)


@dataclass
class DescribeParametersResponse(IdlStruct, typename=_s("rcl_interfaces", "DescribeParameters_Response")):
    descriptors: sequence[ParameterDescriptor] = field(default_factory=list)


@dataclass
class SetBoolRequest(IdlStruct, typename=_s("std_srvs", "SetBool_Request")):
    data: bool = False


@dataclass
class SetBoolResponse(IdlStruct, typename=_s("std_srvs", "SetBool_Response")):
    success: bool = False
    message: str = ""


@dataclass
class TriggerRequest(IdlStruct, typename=_s("std_srvs", "Trigger_Request")):
    structure_needs_at_least_one_member: uint8 = 0


@dataclass
class TriggerResponse(IdlStruct, typename=_s("std_srvs", "Trigger_Response")):
    success: bool = False
    message: str = ""


@dataclass
class Log(IdlStruct, typename=_m("rcl_interfaces", "Log")):
    stamp: Time = field(default_factory=Time)
    level: uint8 = 0
    name: str = ""
    msg: str = ""
    file: str = ""
    function: str = ""
    line: uint32 = 0


@dataclass
class Clock(IdlStruct, typename=_m("rosgraph_msgs", "Clock")):
    clock: Time = field(default_factory=Time)
