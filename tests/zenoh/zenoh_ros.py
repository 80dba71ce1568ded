#!/usr/bin/env python3
"""An independent ROS 2 peer over Zenoh, speaking rmw_zenoh's wire protocol (issue 18).

Written from rmw_zenoh's design document (ros2/rmw_zenoh, docs/design.md: "Topic and Service
name mapping to Zenoh key expressions", "Graph Cache", "Publishers") and not from our Rust
(ros2-client's zenoh backend), so the tests that use it check our bridge against the spec.
Zenoh is PyPI's `eclipse-zenoh`; CDR is `rosbags` (its ROS 2 Jazzy typestore, plus our
fcc_msgs .msg files), another independent implementation.

Formats (domain id = $ROS_DOMAIN_ID, default 0):

* data key:   <domain>/<fully qualified name without leading '/'>/<dds type>/<type hash>
              e.g. 0/chatter/std_msgs::msg::dds_::String_/RIHS01_df66...1a18
              (dds type of pkg/msg/Name is pkg::msg::dds_::Name_; type hash REP-2016 RIHS01)
* liveliness: @ros2_lv/<domain>/<session id>/<node id>/<node id>/NN/<enclave>/<ns>/<node>
              @ros2_lv/<domain>/<session id>/<node id>/<entity id>/<MP|MS|SS|SC>/<enclave>/<ns>/
              <node>/<qualified name>/<dds type>/<type hash>/<qos>
              enclave, namespace and qualified name "mangled": '/' -> '%', empty -> '%'.
* attachment of every put: int64 LE sequence number | int64 LE source timestamp (ns since the
              UNIX epoch) | 1 byte length of the GID (16) | 16 bytes publisher GID  (33 bytes).
* service:    a Zenoh `get` on `<domain>/<service>/<dds type>/<service type hash>` (e.g.
              2/add_two_ints/example_interfaces::srv::dds_::AddTwoInts_/RIHS01_e118...c81a),
              target ALL_COMPLETE, consolidation NONE, the CDR request and the attachment above
              (client's sequence number and GID); the reply echoes sequence number and GID
              (design.md "Service Clients", rmw_client_data.cpp, rmw_service_data.cpp).
              Actions are services and topics under `<action>/_action/` (ActionClient).
* put encoding: none set (Zenoh's default), as rmw_zenoh's publisher; the payload is CDR
              (with its 4-byte encapsulation header), as rosbags' serialize_cdr makes it.

Peer config: client mode, connected to one router endpoint, multicast scouting off.

CLI:
  zenoh_ros.py --selftest [--connect EP] [--echo-connect EP]   publish std_msgs/String on
        /chatter through one session and receive it through a second one (another router:
        --echo-connect), decoded with rosbags; the second session also sees the talker's
        liveliness tokens. Exit 0 on success.
  zenoh_ros.py --graph [--connect EP]          print the ROS graph (liveliness tokens)
  zenoh_ros.py --echo TOPIC --type T [--count N] [--connect EP]   print decoded messages
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import os
import re
import secrets
import struct
import sys
import threading
import time
from pathlib import Path
from typing import Callable, Optional

import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import Nodetype

ADMIN_SPACE = "@ros2_lv"
DEFAULT_ROUTER = "tcp/127.0.0.1:7447"
MSG_DIR = Path(__file__).resolve().parents[2] / "msg" / "msg"
ACTION_DIR = MSG_DIR.parent / "action"
OUR_PACKAGE = "fcc_msgs"
GID_SIZE = 16
# Capacity of the channel a graph query's replies go through (RosPeer.graph).
GRAPH_REPLIES_MAX = 1 << 16
ATTACHMENT = struct.Struct("<qqB")  # sequence, source timestamp, GID length; then the GID

# ------------------------------------------------------------------------------------ types --


def make_typestore():
    """rosbags' ROS 2 Jazzy typestore plus our fcc_msgs messages (msg/msg/*.msg), our actions
    (msg/action/*.action: Goal/Result/Feedback and the messages of the action protocol, see
    action_types) and action_msgs/srv/CancelGoal."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for path in sorted(MSG_DIR.glob("*.msg")):
        types.update(get_types_from_msg(path.read_text(), f"{OUR_PACKAGE}/msg/{path.stem}"))
    store.register(types)
    types = {}
    for path in sorted(ACTION_DIR.glob("*.action")):
        types.update(action_types(path.read_text(), f"{OUR_PACKAGE}/action/{path.stem}"))
    if "action_msgs/srv/CancelGoal_Request" not in store.types:
        types.update(service_types("action_msgs/srv/CancelGoal",
                                   [("goal_info", _name("action_msgs/msg/GoalInfo"))],
                                   [("return_code", _base("int8")),
                                    ("goals_canceling", (Nodetype.SEQUENCE,
                                                         (_name("action_msgs/msg/GoalInfo"), 0)))],
                                   consts_response=[("ERROR_NONE", "int8", 0),
                                                    ("ERROR_REJECTED", "int8", 1),
                                                    ("ERROR_UNKNOWN_GOAL_ID", "int8", 2),
                                                    ("ERROR_GOAL_TERMINATED", "int8", 3)]))
    types.update(std_service_types(store))
    store.register(types)
    return store


def _seq(node, bound: int = 0):
    return (Nodetype.SEQUENCE, (node, bound))


def std_service_types(store) -> dict:
    """The services our nodes serve on top of rosbags' Jazzy messages (rosbags has no .srv):
    std_srvs/srv/SetBool and Trigger (fcc-bridge's arm, land, hold) and rcl_interfaces' six
    parameter services (every node), from their Jazzy .srv files (constants are not hashed)."""
    types = {}
    ok = [("success", _base("bool")), ("message", _base("string"))]
    strings = _seq(_base("string"))
    rcl = "rcl_interfaces/msg/"
    services = {
        "std_srvs/srv/SetBool": ([("data", _base("bool"))], ok),
        "std_srvs/srv/Trigger": ([], ok),
        "rcl_interfaces/srv/GetParameters": ([("names", strings)],
                                             [("values", _seq(_name(rcl + "ParameterValue")))]),
        "rcl_interfaces/srv/GetParameterTypes": ([("names", strings)],
                                                 [("types", _seq(_base("uint8")))]),
        "rcl_interfaces/srv/SetParameters": (
            [("parameters", _seq(_name(rcl + "Parameter")))],
            [("results", _seq(_name(rcl + "SetParametersResult")))]),
        "rcl_interfaces/srv/SetParametersAtomically": (
            [("parameters", _seq(_name(rcl + "Parameter")))],
            [("result", _name(rcl + "SetParametersResult"))]),
        "rcl_interfaces/srv/ListParameters": ([("prefixes", strings), ("depth", _base("uint64"))],
                                              [("result", _name(rcl + "ListParametersResult"))]),
        "rcl_interfaces/srv/DescribeParameters": (
            [("names", strings)], [("descriptors", _seq(_name(rcl + "ParameterDescriptor")))]),
    }
    for srv, (request, response) in services.items():
        if f"{srv}_Request" not in store.types:
            types.update(service_types(srv, request, response))
    return types


def _base(name: str):
    return (Nodetype.BASE, (name, 0))


def _name(ros_type: str):
    return (Nodetype.NAME, ros_type)


def service_types(srv: str, request: list, response: list, consts_response=()) -> dict:
    """rosbags type definitions of a service `pkg/srv/Name` (or an action's `pkg/action/Name_X`):
    `<srv>_Request`, `<srv>_Response` and `<srv>_Event` (rosidl's service event message:
    service_msgs/ServiceEventInfo info, Request[<=1] request, Response[<=1] response; part of
    the service's REP-2016 type hash)."""
    return {
        f"{srv}_Request": ([], list(request)),
        f"{srv}_Response": (list(consts_response), list(response)),
        f"{srv}_Event": ([], [("info", _name("service_msgs/msg/ServiceEventInfo")),
                              ("request", (Nodetype.SEQUENCE, (_name(f"{srv}_Request"), 1))),
                              ("response", (Nodetype.SEQUENCE, (_name(f"{srv}_Response"), 1)))]),
    }


def action_types(text: str, action: str) -> dict:
    """The types of an action `pkg/action/Name` from its .action text (goal, result, feedback
    separated by `---`), as rosidl generates them: `<action>_Goal`, `_Result`, `_Feedback`; the
    services `<action>_SendGoal` (request: unique_identifier_msgs/UUID goal_id + Goal goal;
    response: bool accepted + builtin_interfaces/Time stamp) and `<action>_GetResult` (request:
    UUID goal_id; response: int8 status + Result result); the message `<action>_FeedbackMessage`
    (UUID goal_id + Feedback feedback)."""
    sections = re.split(r"^---[ \t]*$", text, flags=re.M)
    if len(sections) != 3:
        raise ValueError(f"{action}: {len(sections)} sections, not 3 (goal, result, feedback)")
    types = {}
    for suffix, section in zip(("Goal", "Result", "Feedback"), sections):
        types.update(get_types_from_msg(section, f"{action}_{suffix}"))
    uuid = _name("unique_identifier_msgs/msg/UUID")
    types.update(service_types(f"{action}_SendGoal",
                               [("goal_id", uuid), ("goal", _name(f"{action}_Goal"))],
                               [("accepted", _base("bool")),
                                ("stamp", _name("builtin_interfaces/msg/Time"))]))
    types.update(service_types(f"{action}_GetResult", [("goal_id", uuid)],
                               [("status", _base("int8")), ("result", _name(f"{action}_Result"))]))
    types[f"{action}_FeedbackMessage"] = ([], [("goal_id", uuid),
                                                ("feedback", _name(f"{action}_Feedback"))])
    return types


def dds_type_name(ros_type: str) -> str:
    """`sensor_msgs/msg/Imu` -> `sensor_msgs::msg::dds_::Imu_` (the CDR type name in DDS)."""
    package, kind, name = ros_type.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def ros_type_name(dds_type: str) -> str:
    """Inverse of dds_type_name."""
    package, kind, _dds, name = dds_type.split("::")
    return f"{package}/{kind}/{name.rstrip('_')}"


# REP-2016 type hash (RIHS01): sha256 of the type description (fields of the type and of every
# type it references, by name; constants and default values are not hashed) as compact JSON.
# FieldType ids of type_description_interfaces/msg/FieldType. A .msg `char` is uint8 in rosidl's
# IDL (rosidl_adapter), so it hashes as uint8 (service_msgs/ServiceEventInfo's char[16]
# client_gid: with it the AddTwoInts service hash is rmw_zenoh's design document's).
_FIELD_TYPE_IDS = {
    "int8": 2, "uint8": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7, "int64": 8,
    "uint64": 9, "float32": 10, "float64": 11, "char": 3, "bool": 15, "byte": 16, "string": 17,
}
_NESTED, _BOUNDED_STRING = 1, 21
_ARRAY_OFFSET, _BOUNDED_SEQUENCE_OFFSET, _SEQUENCE_OFFSET = 48, 96, 144


def _field_type(node) -> tuple[dict, list[str]]:
    """A rosbags field type -> (FieldType dict, nested type names it references)."""
    kind, detail = node
    if kind == Nodetype.BASE:
        name, bound = detail
        type_id = _BOUNDED_STRING if name == "string" and bound else _FIELD_TYPE_IDS[name]
        return {"type_id": type_id, "capacity": 0, "string_capacity": bound,
                "nested_type_name": ""}, []
    if kind == Nodetype.NAME:
        return {"type_id": _NESTED, "capacity": 0, "string_capacity": 0,
                "nested_type_name": detail}, [detail]
    element, size = detail
    inner, refs = _field_type(element)
    if kind == Nodetype.ARRAY:
        offset = _ARRAY_OFFSET
    else:
        offset = _BOUNDED_SEQUENCE_OFFSET if size else _SEQUENCE_OFFSET
    return dict(inner, type_id=inner["type_id"] + offset, capacity=size), refs


def _individual_description(store, ros_type: str) -> tuple[dict, list[str]]:
    fields, refs = [], []
    for name, node in store.fielddefs[ros_type][1]:
        field_type, nested = _field_type(node)
        fields.append({"name": name, "type": field_type})
        refs += nested
    if not fields:  # rosidl's placeholder member of an empty message
        fields.append({"name": "structure_needs_at_least_one_member",
                       "type": {"type_id": 3, "capacity": 0, "string_capacity": 0,
                                "nested_type_name": ""}})
    return {"type_name": ros_type, "fields": fields}, refs


def type_hash(store, ros_type: str) -> str:
    """REP-2016 `RIHS01_<sha256>` of a message type known to `store`."""
    return _hash_description(store, *_individual_description(store, ros_type))


def service_type_hash(store, srv: str) -> str:
    """REP-2016 hash of a service `pkg/srv/Name` (or an action's `pkg/action/Name_SendGoal`):
    the description of a type `srv` with the fields request_message, response_message and
    event_message (nested `<srv>_Request`, `_Response`, `_Event`), as rosidl describes services
    and as rmw_zenoh puts it in the service's key expression."""
    fields = [{"name": name, "type": {"type_id": _NESTED, "capacity": 0, "string_capacity": 0,
                                      "nested_type_name": f"{srv}_{suffix}"}}
              for name, suffix in (("request_message", "Request"), ("response_message", "Response"),
                                   ("event_message", "Event"))]
    return _hash_description(store, {"type_name": srv, "fields": fields},
                             [f"{srv}_Request", f"{srv}_Response", f"{srv}_Event"])


def entity_type_hash(store, kind: str, ros_type: str) -> str:
    """The REP-2016 hash an rmw_zenoh entity of `kind` (liveliness MP, MS, SS, SC) with the
    type `ros_type` (as in the token, demangled) advertises: a message's hash for publishers and
    subscriptions, the service's hash for servers and clients (also an action's
    `pkg/action/Name_SendGoal` / `_GetResult`)."""
    if kind in ("SS", "SC"):
        return service_type_hash(store, ros_type)
    return type_hash(store, ros_type)


def _hash_description(store, main: dict, pending: list[str]) -> str:
    referenced: dict[str, dict] = {}
    while pending:
        name = pending.pop()
        if name not in referenced:
            referenced[name], more = _individual_description(store, name)
            pending += more
    description = {"type_description": main,
                   "referenced_type_descriptions": [referenced[k] for k in sorted(referenced)]}
    text = json.dumps(description, separators=(", ", ": "), ensure_ascii=True)
    return "RIHS01_" + hashlib.sha256(text.encode()).hexdigest()


# ------------------------------------------------------------------------- key expressions --


def domain_id() -> int:
    return int(os.environ.get("ROS_DOMAIN_ID", "0"))


def topic_keyexpr(domain: int, topic: str, ros_type: str, rihs: str) -> str:
    """The data key of a topic: `<domain>/<topic>/<dds type>/<type hash>`."""
    return f"{domain}/{topic.strip('/')}/{dds_type_name(ros_type)}/{rihs}"


def topic_wildcard(domain: int, topic: str) -> str:
    """Every type and hash of one topic: `<domain>/<topic>/*/*`."""
    return f"{domain}/{topic.strip('/')}/*/*"


def split_data_key(key: str) -> tuple[int, str, str, str]:
    """`0/uav1/imu/std_msgs::msg::dds_::X_/RIHS01_..` -> (0, '/uav1/imu', 'std_msgs/msg/X', hash)."""
    parts = key.split("/")
    return int(parts[0]), "/" + "/".join(parts[1:-2]), ros_type_name(parts[-2]), parts[-1]


def mangle(name: str) -> str:
    return name.replace("/", "%") if name else "%"


def demangle(name: str) -> str:
    return name.replace("%", "/")


@dataclasses.dataclass(frozen=True)
class Entity:
    """One liveliness token of the ROS graph, parsed (names demangled)."""
    domain: int
    session_id: str
    node_id: str
    entity_id: str
    kind: str            # NN node, MP publisher, MS subscription, SS service, SC client
    enclave: str
    namespace: str
    node: str
    topic: str = ""      # fully qualified topic or service name (entities only)
    type: str = ""       # ROS type, pkg/msg/Name (entities only)
    type_hash: str = ""
    qos: str = ""

    @property
    def node_fqn(self) -> str:
        return self.namespace.rstrip("/") + "/" + self.node


def parse_liveliness(key: str) -> Optional[Entity]:
    """A `@ros2_lv/...` key -> Entity, or None if it is not an rmw_zenoh token."""
    parts = key.split("/")
    if len(parts) not in (9, 13) or parts[0] != ADMIN_SPACE:
        return None
    head = dict(domain=int(parts[1]), session_id=parts[2], node_id=parts[3], entity_id=parts[4],
                kind=parts[5], enclave=demangle(parts[6]), namespace=demangle(parts[7]),
                node=parts[8])
    if len(parts) == 9:
        return Entity(**head)
    dds_type = parts[10]
    return Entity(**head, topic=demangle(parts[9]),
                  type=ros_type_name(dds_type) if "::dds_::" in dds_type else dds_type,
                  type_hash=parts[11], qos=parts[12])


def node_token(domain, session_id, node_id, namespace, node, enclave="") -> str:
    return (f"{ADMIN_SPACE}/{domain}/{session_id}/{node_id}/{node_id}/NN/"
            f"{mangle(enclave)}/{mangle(namespace)}/{node}")


def entity_token(domain, session_id, node_id, entity_id, kind, namespace, node, topic,
                 ros_type, rihs, qos, enclave="") -> str:
    return (f"{ADMIN_SPACE}/{domain}/{session_id}/{node_id}/{entity_id}/{kind}/"
            f"{mangle(enclave)}/{mangle(namespace)}/{node}/{mangle(topic)}/"
            f"{dds_type_name(ros_type)}/{rihs}/{qos}")


def transient_local(qos: str) -> bool:
    """Does rmw_zenoh's compact QoS (`rel:dur:...`, see `qos_string`) say TRANSIENT_LOCAL (the
    durability code 1 of rmw_qos_durability_policy_e; empty or 2 is volatile)?"""
    fields = qos.split(":")
    return len(fields) > 1 and fields[1] == "1"


def qos_string(depth: int = 10) -> str:
    """rmw_zenoh's compact QoS: `rel:dur:hist,depth:deadline:lifespan:liveliness`, a field left
    empty where it is the default (reliable, volatile, keep last, infinite, automatic)."""
    return f"::,{depth}:,:,:,,"


# ------------------------------------------------------------------------------ attachment --


@dataclasses.dataclass(frozen=True)
class Attachment:
    sequence_number: int
    source_timestamp_ns: int
    source_gid: bytes

    def encode(self) -> bytes:
        assert len(self.source_gid) == GID_SIZE
        return ATTACHMENT.pack(self.sequence_number, self.source_timestamp_ns, GID_SIZE) \
            + self.source_gid

    @staticmethod
    def decode(raw: bytes) -> "Attachment":
        if len(raw) != ATTACHMENT.size + GID_SIZE:
            raise ValueError(f"attachment of {len(raw)} bytes, not {ATTACHMENT.size + GID_SIZE}")
        sequence, stamp, gid_len = ATTACHMENT.unpack_from(raw)
        if gid_len != GID_SIZE:
            raise ValueError(f"attachment GID length {gid_len}, not {GID_SIZE}")
        return Attachment(sequence, stamp, bytes(raw[ATTACHMENT.size:]))


@dataclasses.dataclass
class Received:
    topic: str
    type: str
    type_hash: str
    message: object
    attachment: Optional[Attachment]
    key: str


# -------------------------------------------------------------------------------- the peer --


def peer_config(connect: str) -> zenoh.Config:
    """Client mode, connected to `connect`, multicast scouting off."""
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([connect]))
    config.insert_json5("scouting/multicast/enabled", "false")
    return config


class Publisher:
    def __init__(self, peer: "RosPeer", topic: str, ros_type: str, rihs: str, token: str):
        self._peer, self.topic, self.type = peer, topic, ros_type
        self.key = topic_keyexpr(peer.domain, topic, ros_type, rihs)
        self._publisher = peer.session.declare_publisher(self.key)
        self._token = peer.session.liveliness().declare_token(token)
        self.gid = secrets.token_bytes(GID_SIZE)
        self._sequence = 0

    def publish(self, message) -> None:
        """CDR-serialize `message` with rosbags and put it with rmw_zenoh's attachment."""
        self._sequence += 1
        payload = bytes(self._peer.store.serialize_cdr(message, self.type))
        attachment = Attachment(self._sequence, time.time_ns(), self.gid).encode()
        self._publisher.put(payload, attachment=attachment)


class RosPeer:
    """One Zenoh session = one ROS 2 context with one node in it."""

    def __init__(self, connect: str = DEFAULT_ROUTER, node: str = "zenoh_ros_py",
                 namespace: str = "/", domain: Optional[int] = None, store=None):
        self.domain = domain_id() if domain is None else domain
        self.store = store or make_typestore()
        self.session = zenoh.open(peer_config(connect))
        self.session_id = str(self.session.zid())
        self.namespace, self.node = namespace, node
        self._next_entity_id = 1
        self._keep = [self.session.liveliness().declare_token(
            node_token(self.domain, self.session_id, 0, namespace, node))]

    def close(self) -> None:
        self._keep.clear()
        self.session.close()

    def _entity_token(self, kind: str, topic: str, ros_type: str, rihs: str) -> str:
        entity_id, self._next_entity_id = self._next_entity_id, self._next_entity_id + 1
        return entity_token(self.domain, self.session_id, 0, entity_id, kind, self.namespace,
                            self.node, "/" + topic.strip("/"), ros_type, rihs, qos_string())

    def type_hash(self, ros_type: str) -> str:
        return type_hash(self.store, ros_type)

    def publisher(self, topic: str, ros_type: str) -> Publisher:
        rihs = self.type_hash(ros_type)
        return Publisher(self, topic, ros_type, rihs,
                         self._entity_token("MP", topic, ros_type, rihs))

    def subscribe(self, topic: str, ros_type: str, callback: Callable[[Received], None]):
        """Messages of `topic` whatever their type hash (a type name mismatch is skipped)."""
        self._keep.append(self.session.liveliness().declare_token(
            self._entity_token("MS", topic, ros_type, self.type_hash(ros_type))))
        return self.subscribe_keyexpr(topic_wildcard(self.domain, topic), callback,
                                      only_type=ros_type)

    def subscribe_keyexpr(self, keyexpr: str, callback: Callable[[Received], None],
                          only_type: Optional[str] = None):
        """Any data keys, e.g. `0/uav1/**` for a whole namespace; decoded where the type is
        known to the typestore."""
        def on_sample(sample):
            received = self._decode(sample, only_type)
            if received is not None:
                callback(received)
        subscriber = self.session.declare_subscriber(keyexpr, on_sample)
        self._keep.append(subscriber)
        return subscriber

    def _decode(self, sample, only_type: Optional[str]) -> Optional[Received]:
        key = str(sample.key_expr)
        _, topic, ros_type, rihs = split_data_key(key)
        if only_type and ros_type != only_type:
            return None
        raw = sample.attachment.to_bytes() if sample.attachment is not None else None
        attachment = Attachment.decode(raw) if raw is not None else None
        message = None
        if ros_type in self.store.types:
            message = self.store.deserialize_cdr(sample.payload.to_bytes(), ros_type)
        return Received(topic, ros_type, rihs, message, attachment, key)

    def service_client(self, service: str, srv_type: str, key_hash: Optional[str] = None):
        return ServiceClient(self, service, srv_type, key_hash)

    def call(self, service: str, srv_type: str, request, timeout_s: Optional[float] = None):
        """One call of `service` (a new client each time: sequence number 1)."""
        return ServiceClient(self, service, srv_type,
                             self.server_hash(service, srv_type)).call(request, timeout_s)

    def server_hash(self, service: str, srv_type: str, timeout_s: float = 2.0) -> Optional[str]:
        """The type hash in the SS liveliness token of a server of `service` with `srv_type`'s
        dds type name (None if none is alive). rmw_zenoh's client puts the service's REP-2016
        hash in its key; a server that advertises (and so serves) another hash is reachable
        only with that one."""
        service = "/" + service.strip("/")
        for e in self.graph(timeout_s):
            if e.kind == "SS" and e.topic == service and e.type == srv_type:
                return e.type_hash
        return None

    def graph(self, timeout_s: float = 2.0) -> list[Entity]:
        """The alive tokens of this domain (what `ros2 node list` / `topic list` read)."""
        entities = []
        # The replies go through a channel far larger than any graph: with a liveliness
        # subscriber on the session (watch_graph, history) the session answers from its own
        # token cache, in this thread, before get() returns — and the default channel (256)
        # then blocks this thread on the 257th token forever (a fleet of four vehicles has
        # ~300 tokens: fleet_peer.py hung in CI-like runs).
        for reply in self.session.liveliness().get(f"{ADMIN_SPACE}/{self.domain}/**",
                                                   zenoh.handlers.FifoChannel(GRAPH_REPLIES_MAX),
                                                   timeout=timeout_s):
            if reply.ok is not None:
                entity = parse_liveliness(str(reply.ok.key_expr))
                if entity is not None:
                    entities.append(entity)
        return entities

    def watch_graph(self, callback: Callable[[Entity, bool], None]):
        """callback(entity, alive) for each token appearing (and those alive now) or leaving."""
        def on_sample(sample):
            entity = parse_liveliness(str(sample.key_expr))
            if entity is not None:
                callback(entity, sample.kind == zenoh.SampleKind.PUT)
        subscriber = self.session.liveliness().declare_subscriber(
            f"{ADMIN_SPACE}/{self.domain}/**", on_sample, history=True)
        self._keep.append(subscriber)
        return subscriber


# ------------------------------------------------------------------------ services, actions --


class ServiceError(Exception):
    pass


class ServiceClient:
    """A ROS 2 service client as rmw_zenoh's (rmw_client_data.cpp; design.md "Service Clients"):
    a Zenoh `get` on the service's key `<domain>/<service>/<dds type>/<type hash>` (the dds type
    of `pkg/srv/Name` is `pkg::srv::dds_::Name_`, of an action's `pkg/action/Name_SendGoal`
    `pkg::action::dds_::Name_SendGoal_`; the hash is the service's REP-2016 hash), target
    ALL_COMPLETE (service queryables are complete), consolidation NONE, the CDR request as
    payload and the attachment sequence number (1, 2, ... per client) | source timestamp |
    client GID; the reply carries the response and the same sequence number and GID. An SC
    liveliness token announces the client. Timeout 10 s (Zenoh's default), unlimited for
    `**/_action/get_result/**` as rmw_zenoh's.

    `key_hash`: the hash put in the key if not the service's REP-2016 hash (see
    `RosPeer.server_hash`)."""

    def __init__(self, peer: "RosPeer", service: str, srv_type: str,
                 key_hash: Optional[str] = None):
        self._peer, self.service, self.type = peer, "/" + service.strip("/"), srv_type
        self.rihs = service_type_hash(peer.store, srv_type)
        self.key_hash = key_hash or self.rihs
        self.key = f"{peer.domain}/{self.service.strip('/')}/{dds_type_name(srv_type)}/" \
                   f"{self.key_hash}"
        self.gid = secrets.token_bytes(GID_SIZE)
        self._sequence = 0
        self.timeout_s = None if "/_action/get_result" in self.service else 10.0
        peer._keep.append(peer.session.liveliness().declare_token(
            peer._entity_token("SC", self.service, srv_type, self.rihs)))

    def call(self, request, timeout_s: Optional[float] = None):
        """Send `request` (a rosbags `<srv>_Request`) and return the decoded response."""
        self._sequence += 1
        sequence = self._sequence
        payload = bytes(self._peer.store.serialize_cdr(request, f"{self.type}_Request"))
        attachment = Attachment(sequence, time.time_ns(), self.gid).encode()
        timeout = timeout_s if timeout_s is not None else self.timeout_s
        replies = self._peer.session.get(
            self.key, payload=payload, attachment=attachment,
            target=zenoh.QueryTarget.ALL_COMPLETE, consolidation=zenoh.ConsolidationMode.NONE,
            timeout=timeout if timeout is not None else 1e6)
        errors = []
        for reply in replies:
            if reply.ok is None:
                errors.append(reply.err.payload.to_string())
                continue
            sample = reply.ok
            raw = sample.attachment.to_bytes() if sample.attachment is not None else b""
            got = Attachment.decode(raw)
            if got.sequence_number != sequence or got.source_gid != self.gid:
                errors.append(f"reply for seq {got.sequence_number} gid {got.source_gid.hex()}")
                continue
            return self._peer.store.deserialize_cdr(sample.payload.to_bytes(),
                                                    f"{self.type}_Response")
        raise ServiceError(f"no reply from {self.key}" + (f": {errors}" if errors else ""))


GOAL_STATUS = {0: "UNKNOWN", 1: "ACCEPTED", 2: "EXECUTING", 3: "CANCELING", 4: "SUCCEEDED",
               5: "CANCELED", 6: "ABORTED"}


class ActionClient:
    """A ROS 2 action client (rcl_action's composition, no middleware concept in rmw_zenoh):
    services `<action>/_action/send_goal` (`<type>_SendGoal`), `_action/get_result`
    (`<type>_GetResult`), `_action/cancel_goal` (action_msgs/srv/CancelGoal) and topics
    `_action/feedback` (`<type>_FeedbackMessage`), `_action/status`
    (action_msgs/msg/GoalStatusArray). Feedback and status of every goal are collected in
    `feedback` / `status` as (monotonic time, message)."""

    def __init__(self, peer: "RosPeer", action: str, action_type: str,
                 key_hashes: Optional[dict] = None):
        self._peer, self.action, self.type = peer, "/" + action.strip("/"), action_type
        hashes = key_hashes or {}
        base = f"{self.action}/_action"
        self.send_goal_client = ServiceClient(peer, f"{base}/send_goal", f"{action_type}_SendGoal",
                                              hashes.get("send_goal"))
        self.get_result_client = ServiceClient(peer, f"{base}/get_result",
                                               f"{action_type}_GetResult",
                                               hashes.get("get_result"))
        self.cancel_client = ServiceClient(peer, f"{base}/cancel_goal", "action_msgs/srv/CancelGoal",
                                           hashes.get("cancel_goal"))
        self.lock = threading.Lock()
        self.feedback: list[tuple[float, object]] = []
        self.status: list[tuple[float, object]] = []
        peer.subscribe(f"{base}/feedback", f"{action_type}_FeedbackMessage", self._on_feedback)
        peer.subscribe(f"{base}/status", "action_msgs/msg/GoalStatusArray", self._on_status)

    def _on_feedback(self, received: Received):
        with self.lock:
            self.feedback.append((time.monotonic(), received.message))

    def _on_status(self, received: Received):
        with self.lock:
            self.status.append((time.monotonic(), received.message))

    def send_goal(self, goal, timeout_s: Optional[float] = None):
        """(goal id: 16 bytes, `<type>_SendGoal_Response`)."""
        ts = self._peer.store.types
        goal_id = secrets.token_bytes(16)
        uuid = ts["unique_identifier_msgs/msg/UUID"](uuid=_uint8_array(goal_id))
        request = ts[f"{self.type}_SendGoal_Request"](goal_id=uuid, goal=goal)
        return goal_id, self.send_goal_client.call(request, timeout_s)

    def get_result(self, goal_id: bytes, timeout_s: Optional[float] = None):
        """`<type>_GetResult_Response` (status: action_msgs/GoalStatus, result)."""
        ts = self._peer.store.types
        uuid = ts["unique_identifier_msgs/msg/UUID"](uuid=_uint8_array(goal_id))
        return self.get_result_client.call(ts[f"{self.type}_GetResult_Request"](goal_id=uuid),
                                           timeout_s)

    def cancel(self, goal_id: bytes):
        ts = self._peer.store.types
        uuid = ts["unique_identifier_msgs/msg/UUID"](uuid=_uint8_array(goal_id))
        info = ts["action_msgs/msg/GoalInfo"](
            goal_id=uuid, stamp=ts["builtin_interfaces/msg/Time"](sec=0, nanosec=0))
        return self.cancel_client.call(ts["action_msgs/srv/CancelGoal_Request"](goal_info=info))

    def feedback_of(self, goal_id: bytes) -> list:
        with self.lock:
            return [m for _, m in self.feedback if bytes(m.goal_id.uuid) == goal_id]

    def statuses_of(self, goal_id: bytes) -> list[int]:
        """The goal's status in each status array that lists it, in order."""
        with self.lock:
            return [s.status for _, a in self.status for s in a.status_list
                    if bytes(s.goal_info.goal_id.uuid) == goal_id]


def _uint8_array(raw: bytes):
    import numpy
    return numpy.frombuffer(raw, dtype=numpy.uint8).copy()


# --------------------------------------------------------------------------------- the CLI --

# REP-2016 hashes as ROS 2 Jazzy publishes them (String: rmw_zenoh's design document).
STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
ADD_TWO_INTS_HASH = "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"
IMU_HASH = "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b"


def selftest(connect: str, echo_connect: str, timeout_s: float) -> int:
    store = make_typestore()
    check(type_hash(store, "std_msgs/msg/String") == STRING_HASH,
          "REP-2016 hash of std_msgs/msg/String matches rmw_zenoh's design doc")
    check(type_hash(store, "sensor_msgs/msg/Imu") == IMU_HASH,
          "REP-2016 hash of sensor_msgs/msg/Imu (nested types) matches Jazzy's")
    srv = "example_interfaces/srv/AddTwoInts"
    store.register(service_types(srv, [("a", _base("int64")), ("b", _base("int64"))],
                                 [("sum", _base("int64"))]))
    check(service_type_hash(store, srv) == ADD_TWO_INTS_HASH,
          "REP-2016 hash of the service example_interfaces/srv/AddTwoInts matches rmw_zenoh's "
          "design doc")
    check(attachment_matches_zenoh_ext(), "attachment bytes = zenoh-ext serializer's "
          "(int64, int64, 16 bytes), as rmw_zenoh's AttachmentData")
    check(split_data_key(topic_keyexpr(0, "/uav1/imu", "sensor_msgs/msg/Imu", "H"))
          == (0, "/uav1/imu", "sensor_msgs/msg/Imu", "H"), "data key round trip")
    talker = RosPeer(connect, node="selftest_talker", store=store)
    listener = RosPeer(echo_connect, node="selftest_listener", store=store)
    try:
        return _selftest_exchange(store, talker, listener, timeout_s)
    finally:
        talker.close()
        listener.close()


def _selftest_exchange(store, talker: RosPeer, listener: RosPeer, timeout_s: float) -> int:
    got: list[Received] = []
    arrived = threading.Event()

    def on_message(received: Received):
        got.append(received)
        arrived.set()

    listener.subscribe("/chatter", "std_msgs/msg/String", on_message)
    publisher = talker.publisher("/chatter", "std_msgs/msg/String")
    print(f"talker {talker.session_id} -> {publisher.key}")
    text = f"hello from zenoh_ros.py {secrets.token_hex(4)}"
    message = store.types["std_msgs/msg/String"](data=text)
    deadline = time.monotonic() + timeout_s
    while not arrived.is_set() and time.monotonic() < deadline:
        publisher.publish(message)  # again until the subscription has reached the talker
        arrived.wait(0.2)
    check(bool(got), f"listener {listener.session_id} received /chatter")
    first = got[0]
    print(f"received key {first.key}: data={first.message.data!r} "
          f"seq={first.attachment.sequence_number} gid={first.attachment.source_gid.hex()}")
    check(first.message.data == text, "payload decoded by rosbags")
    check(first.type_hash == STRING_HASH and first.attachment.source_gid == publisher.gid,
          "type hash and publisher GID carried")
    return _selftest_graph(talker, listener)


def _selftest_graph(talker: RosPeer, listener: RosPeer) -> int:
    deadline = time.monotonic() + 5.0
    while True:
        mine = [e for e in listener.graph() if e.session_id == talker.session_id]
        kinds = {(e.kind, e.topic) for e in mine}
        if {("NN", ""), ("MP", "/chatter")} <= kinds or time.monotonic() > deadline:
            break
        time.sleep(0.2)
    for entity in mine:
        print(f"  token {entity.kind} {entity.node_fqn} {entity.topic} {entity.type}")
    check({("NN", ""), ("MP", "/chatter")} <= kinds,
          "listener sees the talker's node and publisher liveliness tokens")
    print("selftest: OK")
    return 0


def attachment_matches_zenoh_ext() -> bool:
    import zenoh.ext as ext
    sample = Attachment(7, 0x0102030405060708, bytes(range(GID_SIZE)))
    reference = ext.z_serialize((ext.Int64(sample.sequence_number),
                                 ext.Int64(sample.source_timestamp_ns), sample.source_gid))
    raw = reference.to_bytes()
    return sample.encode() == raw and Attachment.decode(raw) == sample


class CheckFailed(Exception):
    pass


def check(ok: bool, what: str) -> None:
    print(f"{'ok  ' if ok else 'FAIL'} {what}", flush=True)
    if not ok:
        raise CheckFailed(what)


def print_graph(connect: str) -> int:
    peer = RosPeer(connect, node="zenoh_ros_graph")
    try:
        for e in sorted(peer.graph(), key=lambda e: (e.node_fqn, e.kind, e.topic)):
            if e.session_id != peer.session_id:
                print(f"{e.kind} {e.node_fqn} {e.topic} {e.type} {e.qos}".rstrip())
    finally:
        peer.close()
    return 0


def echo(connect: str, topic: str, ros_type: str, count: int, timeout_s: float) -> int:
    peer = RosPeer(connect, node="zenoh_ros_echo")
    done, seen = threading.Event(), []

    def on_message(received: Received):
        seen.append(received)
        print(f"{received.topic} seq={received.attachment and received.attachment.sequence_number}"
              f" {received.message}", flush=True)
        if count and len(seen) >= count:
            done.set()
    try:
        peer.subscribe(topic, ros_type, on_message)
        done.wait(timeout_s)
    finally:
        peer.close()
    return 0 if seen and (not count or len(seen) >= count) else 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--connect", default=DEFAULT_ROUTER, help="router endpoint")
    parser.add_argument("--echo-connect", help="selftest: the listener's router (default: --connect)")
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--selftest", action="store_true")
    mode.add_argument("--graph", action="store_true")
    mode.add_argument("--echo", metavar="TOPIC")
    parser.add_argument("--type", help="ROS type for --echo, e.g. sensor_msgs/msg/Imu")
    parser.add_argument("--count", type=int, default=1, help="--echo: messages to wait for (0 = all)")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds")
    args = parser.parse_args(argv)
    try:
        if args.selftest:
            return selftest(args.connect, args.echo_connect or args.connect, args.timeout)
        if args.graph:
            return print_graph(args.connect)
        if not args.type:
            parser.error("--echo needs --type")
        return echo(args.connect, args.echo, args.type, args.count, args.timeout)
    except CheckFailed:
        return 1


if __name__ == "__main__":
    sys.exit(main())
