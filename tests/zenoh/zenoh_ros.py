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
OUR_PACKAGE = "fcc_msgs"
GID_SIZE = 16
ATTACHMENT = struct.Struct("<qqB")  # sequence, source timestamp, GID length; then the GID

# ------------------------------------------------------------------------------------ types --


def make_typestore():
    """rosbags' ROS 2 Jazzy typestore plus our fcc_msgs messages (msg/msg/*.msg)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for path in sorted(MSG_DIR.glob("*.msg")):
        types.update(get_types_from_msg(path.read_text(), f"{OUR_PACKAGE}/msg/{path.stem}"))
    store.register(types)
    return store


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
# FieldType ids of type_description_interfaces/msg/FieldType.
_FIELD_TYPE_IDS = {
    "int8": 2, "uint8": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7, "int64": 8,
    "uint64": 9, "float32": 10, "float64": 11, "char": 13, "bool": 15, "byte": 16, "string": 17,
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
    main, pending = _individual_description(store, ros_type)
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

    def graph(self, timeout_s: float = 2.0) -> list[Entity]:
        """The alive tokens of this domain (what `ros2 node list` / `topic list` read)."""
        entities = []
        for reply in self.session.liveliness().get(f"{ADMIN_SPACE}/{self.domain}/**",
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


# --------------------------------------------------------------------------------- the CLI --

# REP-2016 hashes as ROS 2 Jazzy publishes them (String: rmw_zenoh's design document).
STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
IMU_HASH = "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b"


def selftest(connect: str, echo_connect: str, timeout_s: float) -> int:
    store = make_typestore()
    check(type_hash(store, "std_msgs/msg/String") == STRING_HASH,
          "REP-2016 hash of std_msgs/msg/String matches rmw_zenoh's design doc")
    check(type_hash(store, "sensor_msgs/msg/Imu") == IMU_HASH,
          "REP-2016 hash of sensor_msgs/msg/Imu (nested types) matches Jazzy's")
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
