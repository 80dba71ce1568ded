"""What the `ros2` CLI does, with the rclpy calls it makes (no `ros2` CLI wheel exists): node list,
topic list -t, topic echo's QoS choice, param list/get/set/describe, service calls, and spinning
until a condition holds (never a fixed sleep)."""
import importlib
import time

import rclpy
import rclpy.executors
import rclpy.parameter
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy)
from rcl_interfaces.msg import Parameter as ParamMsg, ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters


class Timeout(Exception):
    pass


class Peer:
    """One rclpy context with its executor; nodes are added with `node()`."""

    def __init__(self, name, use_sim_time=False):
        rclpy.init()
        self.executor = rclpy.executors.SingleThreadedExecutor()
        self.nodes = []
        self.main = self.node(name, use_sim_time)

    def node(self, name, use_sim_time=False):
        overrides = [rclpy.parameter.Parameter("use_sim_time", value=True)] if use_sim_time else []
        n = rclpy.create_node(name, parameter_overrides=overrides)
        self.executor.add_node(n)
        self.nodes.append(n)
        return n

    def spin(self, secs):
        end = time.monotonic() + secs
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.01, max(0.0, end - time.monotonic())))

    def wait(self, cond, secs, what):
        """Spin until cond() holds; raise Timeout(what) after secs (wall). cond() is evaluated
        every 20 ms of spinning, not after each callback (a costly cond would starve them)."""
        end = time.monotonic() + secs
        while not cond():
            if time.monotonic() > end:
                raise Timeout(f"timeout ({secs} s) waiting for {what}")
            self.spin(0.02)

    def call(self, node, srv_type, name, request, secs=10.0):
        """A service call as `ros2 service call` makes it: wait for the server, call, wait."""
        cli = node.create_client(srv_type, name)
        try:
            try:
                self.wait(cli.service_is_ready, secs, f"service {name}")
            except Timeout as e:
                raise Timeout(f"{e}; {service_graph(node, cli.srv_name)}") from None
            fut = cli.call_async(request)
            self.wait(fut.done, secs, f"the answer of {name}")
            return fut.result()
        finally:
            node.destroy_client(cli)

    def shutdown(self):
        for n in self.nodes:
            n.destroy_node()
        rclpy.shutdown()


def service_graph(node, srv_name):
    """What this participant's graph holds of a service's two topics (after a timeout: did the
    server's endpoints never arrive, or did they arrive and not match?)."""
    req, rep = f"rq{srv_name}Request", f"rr{srv_name}Reply"
    subs = node.get_subscriptions_info_by_topic(req, no_mangle=True)
    pubs = node.get_publishers_info_by_topic(rep, no_mangle=True)
    return (f"graph: {req} readers {[i.node_namespace + '/' + i.node_name for i in subs]}, "
            f"{rep} writers {[i.node_namespace + '/' + i.node_name for i in pubs]}")


def node_list(node):
    """`ros2 node list`: fully qualified names."""
    return sorted((ns.rstrip("/") + "/" + n) for n, ns in node.get_node_names_and_namespaces())


def topic_list(node):
    """`ros2 topic list -t`: {name: [types]}."""
    return {n: list(t) for n, t in node.get_topic_names_and_types()}


def msg_class(type_name):
    """'sensor_msgs/msg/Imu' → the generated class."""
    pkg, kind, cls = type_name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), cls)


def echo_qos(node, topic, depth=10):
    """The QoS `ros2 topic echo` picks (ros2topic's choose_qos): reliable / transient local only if
    every publisher offers it, else best effort / volatile."""
    infos = node.get_publishers_info_by_topic(topic)
    rel = ReliabilityPolicy.RELIABLE
    dur = DurabilityPolicy.VOLATILE
    if infos:
        if any(i.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT for i in infos):
            rel = ReliabilityPolicy.BEST_EFFORT
        if all(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos):
            dur = DurabilityPolicy.TRANSIENT_LOCAL
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=rel, durability=dur)


def value_of(v):
    """A ParameterValue as Python."""
    return {ParameterType.PARAMETER_BOOL: v.bool_value, ParameterType.PARAMETER_INTEGER: v.integer_value,
            ParameterType.PARAMETER_DOUBLE: v.double_value, ParameterType.PARAMETER_STRING: v.string_value,
            ParameterType.PARAMETER_NOT_SET: None}.get(v.type, f"<type {v.type}>")


def to_value(x):
    if isinstance(x, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=x)
    if isinstance(x, int):
        return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=x)
    if isinstance(x, float):
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=x)
    return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=str(x))


def param_list(peer, node, target):
    """`ros2 param list TARGET`."""
    r = peer.call(node, ListParameters, f"{target}/list_parameters", ListParameters.Request())
    return sorted(r.result.names)


def param_get(peer, node, target, names):
    """`ros2 param get TARGET NAME` for each name: {name: value}."""
    r = peer.call(node, GetParameters, f"{target}/get_parameters", GetParameters.Request(names=list(names)))
    return {n: value_of(v) for n, v in zip(names, r.values)}


def param_set(peer, node, target, name, x):
    """`ros2 param set TARGET NAME X`: (successful, reason)."""
    req = SetParameters.Request(parameters=[ParamMsg(name=name, value=to_value(x))])
    r = peer.call(node, SetParameters, f"{target}/set_parameters", req)
    return r.results[0].successful, r.results[0].reason


def param_describe(peer, node, target, names):
    """`ros2 param describe TARGET NAME...`: {name: ParameterDescriptor}."""
    r = peer.call(node, DescribeParameters, f"{target}/describe_parameters",
                  DescribeParameters.Request(names=list(names)))
    return {n: d for n, d in zip(names, r.descriptors)}


def describe_text(d):
    """One line as `ros2 param describe` would show it."""
    rng = ""
    if d.integer_range:
        r = d.integer_range[0]
        rng = f" range [{r.from_value}, {r.to_value}] step {r.step}"
    elif d.floating_point_range:
        r = d.floating_point_range[0]
        rng = f" range [{r.from_value}, {r.to_value}] step {r.step}"
    return (f"type {d.type} read_only {d.read_only}{rng} description '{d.description}' "
            f"constraints '{d.additional_constraints}'")


