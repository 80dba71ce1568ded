#!/usr/bin/env python3
"""Real ROS 2 (rclpy on Fast DDS, from the PyPI wheels; scripts/ros2-setup.sh) against the stack:
what a ROS user does with the `ros2` CLI, through the rclpy calls the CLI makes (ros_cli.py).
Issue 16. Our own types (fcc_msgs/Status, Altitude) and tf2_msgs/TFMessage are the classes that
`colcon build` generated (target/ros2/DISTRO/install, via env.sh).

Modes (run by tests/ros2/run_ros2_peer.sh, all inside one loopback-only network namespace):
  echo       `ros2 topic echo` of every topic (--qos cli: the CLI's QoS choice; --qos sensor:
             sensor-data QoS), each in its own process; figures (JSON) for `observe`.
  observe    while fcc-launch flies the square (speed 2, clock_source:=mcu, the mission node on
             use_sim_time): node list, topic list with EXACTLY one type per topic, topic info
             (every endpoint of a named node), the echoes' rates and frame_ids, TF
             (map → odom → base_link, the static sensor frames), a late joiner, use_sim_time with
             /clock, parameters of both nodes, QoS of /rosout and /parameter_events as rclpy's;
             after the flight, values against the simulator's CSV truth.
  fly        fcc-sitl ⇄ fcc-bridge (no mission node, speed 1, clock_source:=sync): parameters
             (list/get/set/describe with ranges and read-only, refusals), the `arm` service,
             `cmd/mode`, setpoints published with rclpy's default QoS, the `hold` and `land`
             services; latency of the telemetry; events for check-fly.
  probe      a restarted peer against the same bridge: node, topics, /tf_static, status, params.
  check-fly  the flight of `fly` on the simulator's CSV truth.
  smoke      (Kilted) node list, topics with one type each, a parameter set, a setpoint flown.
"""
import argparse
import copy
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))

import mcu_params  # noqa: E402
import truth  # noqa: E402
from truth import Checks, pct, stamp_of  # noqa: E402

NS = "/fcc"
BRIDGE = f"{NS}/fcc_bridge"
MISSION = f"{NS}/fcc_mission"
# topic: (type, min rate in ROS-time Hz or None, frame_id or None). The bridge's topic table
# (fcc_bridge/ros/src/topics.rs) and the mission node's.
TOPICS = {
    f"{NS}/imu/data_raw": ("sensor_msgs/msg/Imu", 150, "imu_link"),
    f"{NS}/mag": ("sensor_msgs/msg/MagneticField", 15, "imu_link"),
    f"{NS}/baro": ("sensor_msgs/msg/FluidPressure", 15, "base_link"),
    f"{NS}/gps/fix": ("sensor_msgs/msg/NavSatFix", 4, "gps_link"),
    f"{NS}/range/laser": ("sensor_msgs/msg/Range", 7, "laser_link"),
    f"{NS}/range/sonar": ("sensor_msgs/msg/Range", 7, "sonar_link"),
    f"{NS}/battery": ("sensor_msgs/msg/BatteryState", 3, None),
    f"{NS}/state/odom": ("nav_msgs/msg/Odometry", 40, "odom"),   # REP-105: odometry in odom
    f"{NS}/state/imu": ("sensor_msgs/msg/Imu", 40, "base_link"),
    "/tf": ("tf2_msgs/msg/TFMessage", 40, None),
    "/tf_static": ("tf2_msgs/msg/TFMessage", None, None),
    f"{NS}/altitude": ("fcc_msgs/msg/Altitude", 15, None),
    f"{NS}/altitude/ground": ("sensor_msgs/msg/Range", 15, "base_link"),
    f"{NS}/accel/observer": ("geometry_msgs/msg/AccelStamped", 15, "map"),
    f"{NS}/accel/measured": ("geometry_msgs/msg/AccelStamped", 15, "map"),
    f"{NS}/status": ("fcc_msgs/msg/Status", 4, None),
    "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", None, None),
    "/clock": ("rosgraph_msgs/msg/Clock", 40, None),
    f"{NS}/setpoint/velocity": ("geometry_msgs/msg/TwistStamped", None, "map"),
    f"{NS}/mission/status": ("std_msgs/msg/String", None, None),
    "/rosout": ("rcl_interfaces/msg/Log", None, None),
}
STATIC_CHILDREN = {"imu_link", "gps_link", "laser_link", "sonar_link"}


def tf_of(t):
    """A geometry_msgs/Transform as (translation, quaternion wxyz)."""
    p, q = t.translation, t.rotation
    return ((p.x, p.y, p.z), (q.w, q.x, q.y, q.z))


def tf_chain(edges, child="base_link"):
    """Walk child → parent through {child: (parent, tf)}: (path root..child, root→child tf)."""
    path, tf = [child], ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    while path[0] in edges and len(path) < 8:
        parent, t = edges[path[0]]
        tf = truth.compose(t, tf)
        path.insert(0, parent)
    return path, tf


class Recorder:
    """Subscriptions to every topic, each made once its first publisher is discovered (as a user
    runs `ros2 topic echo` on a listed topic): with the CLI's QoS choice, or, in the separate
    `echo-sensor` process (a second terminal), with sensor-data QoS. Every callback only keeps the
    serialized bytes (rclpy's `raw=True`); they are decoded by rclpy's type support when read
    (`msgs`, cached), so three Python processes reading ~1,500 messages/s each keep up on a
    loaded 2-core machine (decoding in the callbacks, the reliable echo fell behind: imu/data_raw
    150 Hz of 200 in a CI run, /clock 33-35 Hz of 100 with one CPU hog beside)."""

    def __init__(self, node, sensor=False, topics=None):
        from rclpy.clock import Clock, ClockType
        from ros_cli import msg_class
        self.node = node
        self.sensor = sensor
        self.topics = list(topics or TOPICS)
        self.got = {t: [] for t in self.topics}  # (wall, raw bytes)
        self.decoded = {t: [] for t in self.topics}  # the first len(...) of got[t], decoded
        self.qos = {}
        self.subs = []
        self.cls = {t: msg_class(TOPICS[t][0]) for t in self.topics}
        node.create_timer(0.05, self.poll, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def poll(self):
        from rclpy.qos import qos_profile_sensor_data
        from ros_cli import echo_qos
        for t in self.topics:
            if t in self.qos or not self.node.get_publishers_info_by_topic(t):
                continue
            # depth 1000: a loaded machine delays the Python callbacks; keep-last must not drop.
            self.qos[t] = echo_qos(self.node, t, depth=1000)
            cb = (lambda t: lambda m: self.got[t].append((time.monotonic(), m)))(t)
            # Sensor-data QoS (best effort, volatile) with the same depth: its 5 would count the
            # Python callbacks' delays on a loaded machine as losses (35 % of imu/data_raw taken
            # with one CPU hog beside); the rate checked is the bridge's delivery.
            qos = copy.copy(qos_profile_sensor_data) if self.sensor else self.qos[t]
            if self.sensor:
                qos.depth = 1000
            self.subs.append(self.node.create_subscription(self.cls[t], t, cb, qos, raw=True))

    def msgs(self, t):
        from rclpy.serialization import deserialize_message
        done = self.decoded[t]
        done.extend(deserialize_message(b, self.cls[t]) for _, b in self.got[t][len(done):])
        return list(done)

    def stamped(self, t):
        """[(wall, message)] of one topic."""
        return list(zip((w for w, _ in self.got[t]), self.msgs(t)))


def rates(rec, t):
    """(messages, ROS-time Hz from the stamps, wall Hz, frame_ids) of one topic."""
    ms = rec.msgs(t)
    st = sorted(x for x in (stamp_of(m) for m in ms) if x is not None)
    span = st[-1] - st[0] if len(st) > 1 else 0.0
    wt = [w for w, _ in rec.got[t]]
    first = [m.linear_acceleration.z for m in ms[:50] if hasattr(m, "linear_acceleration")]
    return {"n": len(ms), "hz": (len(st) - 1) / span if span > 0 else 0.0,
            "az0": sum(first) / len(first) if first else None,   # at rest, before arming
            "wall_hz": (len(wt) - 1) / (wt[-1] - wt[0]) if len(wt) > 1 and wt[-1] > wt[0] else 0.0,
            "frames": sorted({m.header.frame_id for m in ms if hasattr(m, "header")}),
            "transient_local": t in rec.qos and rec.qos[t].durability.name == "TRANSIENT_LOCAL"}


def echo(a):
    """`ros2 topic echo` on every topic in its own process (a terminal of its own), with the CLI's
    QoS choice (--qos cli) or sensor-data QoS (--qos sensor); writes the figures (JSON) for
    `observe` when --until-file appears."""
    from ros_cli import Peer
    peer = Peer(f"rclpy_echo_{a.qos}")
    rec = Recorder(peer.main, sensor=a.qos == "sensor")
    open(a.ready_file, "w").close()
    peer.wait(lambda: os.path.exists(a.until_file), a.timeout, a.until_file)
    drain(peer, rec)
    out = {t: rates(rec, t) for t in TOPICS}
    with open(a.json + ".tmp", "w") as f:
        json.dump(out, f)
    os.rename(a.json + ".tmp", a.json)
    peer.shutdown()
    return 0


def drain(peer, rec):
    """Take what the readers still hold (a loaded machine delays the callbacks), ≤ 20 s."""
    end, n = time.monotonic() + 20, -1
    while time.monotonic() < end and n != sum(len(v) for v in rec.got.values()):
        n = sum(len(v) for v in rec.got.values())
        peer.spin(0.3)


# ------------------------------------------------------------------------------------ observe

def check_graph(c, peer, node, expect_nodes, what=""):
    """`ros2 node list`, `ros2 topic list -t`: the nodes, every expected topic with its type, and
    exactly one type on every topic."""
    from ros_cli import Timeout, node_list, topic_list
    try:
        peer.wait(lambda: set(expect_nodes) <= set(node_list(node)), 20, f"nodes {expect_nodes}")
    except Timeout:
        graph_evidence(node, expect_nodes)
    nodes = node_list(node)
    print(f"ros2 node list{what}: {nodes}", flush=True)
    c.check(f"node list{what} shows {', '.join(expect_nodes)}", set(expect_nodes) <= set(nodes), nodes)
    unknown = [n for n in nodes if "UNKNOWN" in n.upper() or n.endswith("/")]
    c.check(f"node list{what}: no unnamed/unknown node", not unknown, unknown)
    tl = topic_list(node)
    for name in sorted(tl):
        print(f"  {name} {tl[name]}")
    multi = {n: t for n, t in tl.items() if len(t) != 1}
    c.check(f"topic list -t{what}: exactly one type on every topic", not multi, multi)
    # `ros2 topic info -v`: every endpoint belongs to a named node.
    def anonymous():
        return sorted({(t, i.node_namespace + "/" + i.node_name, i.topic_type) for t in tl
                       for i in node.get_publishers_info_by_topic(t) + node.get_subscriptions_info_by_topic(t)
                       if not i.node_name or "UNKNOWN" in i.node_name.upper()})
    try:  # the nodes' endpoint lists (ros_discovery_info) may arrive after the endpoints
        peer.wait(lambda: not anonymous(), 10, "every endpoint attributed to a node")
    except Timeout:
        pass
    anon = anonymous()
    c.check(f"topic info -v{what}: every publisher/subscription belongs to a named node", not anon, anon)
    return nodes, tl


def graph_evidence(node, expect_nodes):
    """What this peer's graph holds when an expected node is missing from `ros2 node list` (a
    rare Fast DDS discovery loss: fcc_bridge/ros/vendor/rustdds/VENDOR.md): the ros_discovery_info
    writers it matched, and who publishes the nodes' topics, to tell a lost ros_discovery_info
    sample from lost endpoints."""
    from ros_cli import node_list
    missing = sorted(set(expect_nodes) - set(node_list(node)))
    print(f"EVIDENCE after 20 s: missing {missing}; node list {node_list(node)}", flush=True)
    for t in ("/ros_discovery_info", f"{NS}/status", f"{NS}/mission/status", "/rosout"):
        pubs = sorted((i.node_namespace + "/" + i.node_name, str(i.endpoint_gid)[:40])
                      for i in node.get_publishers_info_by_topic(t))
        print(f"EVIDENCE publishers of {t}: {pubs}", flush=True)


def check_expected_types(c, tl, topics):
    wrong = {t: tl.get(t) for t in topics if tl.get(t) != [TOPICS[t][0]]}
    c.check(f"topic list -t: the {len(topics)} expected topics with their types", not wrong, wrong)


def check_endpoint_qos(c, node, own_node):
    """/rosout and /parameter_events: the bridge's and mission node's writers have rclpy's QoS
    (our own rclpy node's writers are the reference)."""
    for topic in ("/rosout", "/parameter_events"):
        infos = node.get_publishers_info_by_topic(topic)
        mine = [i for i in infos if i.node_name == own_node]
        if not mine:
            c.check(f"{topic}: rclpy's own writer found (reference QoS)", False, [i.node_name for i in infos])
            continue
        ref = mine[0].qos_profile
        for who in ("fcc_bridge", "fcc_mission"):
            theirs = [i.qos_profile for i in infos if i.node_name == who]
            got = [(q.reliability.name, q.durability.name) for q in theirs]
            c.check(f"{topic} writer of {who}: reliability/durability as rclpy's "
                    f"({ref.reliability.name}/{ref.durability.name})",
                    bool(theirs) and all((q.reliability, q.durability) == (ref.reliability, ref.durability) for q in theirs),
                    got)
        print(f"INFO {topic} type hashes: {sorted({(i.node_name, str(getattr(i, 'topic_type_hash', None))) for i in infos})}", flush=True)


def observe(a):
    from ros_cli import Peer, Timeout
    c = Checks()
    peer = Peer("rclpy_observer", use_sim_time=True)
    node = peer.main
    # The topics whose values are checked here; every topic's rates and frames: the echo processes.
    rec = Recorder(node, topics=[f"{NS}/status", "/tf_static", "/tf", "/clock", f"{NS}/state/odom",
                                 f"{NS}/altitude/ground", f"{NS}/setpoint/velocity", f"{NS}/mission/status", "/rosout"])
    clock_pairs = []   # (wall, node clock now)
    from rclpy.clock import Clock, ClockType
    # The newest /clock as rclpy's TimeSource takes it (best effort, depth 1: no backlog), the
    # reference the node's time is compared with.
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock as ClockMsg
    newest = {}
    node.create_subscription(ClockMsg, "/clock", lambda m: newest.update(t=stamp_of(m)),
                             QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
    last_clock = lambda: newest.get("t")  # noqa: E731
    node.create_timer(0.2, lambda: clock_pairs.append((time.monotonic(), node.get_clock().now().nanoseconds * 1e-9, last_clock())),
                      clock=Clock(clock_type=ClockType.STEADY_TIME))
    open(a.ready_file, "w").close()
    print(f"peer: subscribed to {len(TOPICS)} topics (CLI QoS + sensor-data QoS); waiting for the stack", flush=True)
    try:
        peer.wait(lambda: any(s.armed for s in rec.msgs(f"{NS}/status")), 120, "the vehicle armed")
        nodes, tl = check_graph(c, peer, node, [BRIDGE, MISSION])
        check_expected_types(c, tl, list(TOPICS))
        print("echo QoS (the CLI's choice from the publishers): " + ", ".join(
            f"{t}={q.reliability.name.lower()}/{q.durability.name.lower()}" for t, q in rec.qos.items()), flush=True)
        check_endpoint_qos(c, node, "rclpy_observer")
        check_params_observe(c, peer, node)
        late_joiner(c, peer)
        peer.wait(lambda: os.path.exists(a.until_file), a.timeout, f"{a.until_file} (the launcher's end)")
    except Timeout as e:
        c.check("observe: no timeout", False, e)
    drain(peer, rec)
    figures = {}
    for q, path in (("cli", a.echo_json), ("sensor", a.sensor_json)):
        try:
            peer.wait(lambda: os.path.exists(path), 60, f"the {q} echo's figures ({path})")
            figures[q] = json.load(open(path))
        except Timeout as e:
            c.check(f"the {q} echo process reported", False, e)
            figures[q] = {}
    report_rates(c, figures["cli"], figures["sensor"])
    worst_step = check_tf(c, rec)
    check_sim_time(c, rec, clock_pairs, a.speed)
    if os.path.exists(a.csv):
        log = truth.load_csv(a.csv)
        check_truth(c, rec, log)
        az = figures["cli"].get(f"{NS}/imu/data_raw", {}).get("az0")
        c.check("imu/data_raw at rest (first 50 messages): +g on FLU z", az is not None and 9.0 < az < 10.6, az)
        if worst_step[0] is not None:
            e0, e1 = truth.est_enu(log, worst_step[0]), truth.est_enu(log, worst_step[1])
            if e0 and e1:
                print(f"INFO the MCU's estimate (CSV) over the largest odom step: {truth.dist(e0, e1):.3f} m", flush=True)
    else:
        c.check("the simulator's CSV exists", False, a.csv)
    peer.shutdown()
    return c.done()


def check_params_observe(c, peer, node):
    """`ros2 param list/get` on both nodes (the bridge's set/describe: in `fly`)."""
    from ros_cli import param_get, param_list
    for target, must in ((BRIDGE, {"use_sim_time", "clock_source", "ttl_ms", "limits.max_tilt_deg"}),
                         (MISSION, {"use_sim_time"})):
        names = param_list(peer, node, target)
        print(f"ros2 param list {target}: {names}", flush=True)
        c.check(f"param list {target} has {sorted(must)}", must <= set(names), names)
    g = param_get(peer, node, BRIDGE, ["clock_source", "use_sim_time"])
    c.check("param get fcc_bridge clock_source = mcu", g["clock_source"] == "mcu", g)
    # fcc-launch starts it with -p use_sim_time:=true and it runs on /clock: the parameter
    # service must say so (`ros2 param get /fcc/fcc_mission use_sim_time`).
    g = param_get(peer, node, MISSION, ["use_sim_time"])
    c.check("param get fcc_mission use_sim_time = true (started with -p use_sim_time:=true)", g["use_sim_time"] is True, g)
    check_mission_params(c, peer, node)


def check_mission_params(c, peer, node):
    """The mission node's parameters (fcc_mission::node_params): every one listed with the value in
    use, described (range, unit, read-only), and a set refused with the reason."""
    from ros_cli import describe_text, param_describe, param_get, param_list, param_set
    want = {"mission", "rate_hz", "use_sim_time", "timeout_s", "arm_timeout_s", "localhost_only", "hover_s"}
    names = set(param_list(peer, node, MISSION))
    c.check(f"param list {MISSION}: every parameter of its table", want <= names, sorted(names))
    g = param_get(peer, node, MISSION, ["rate_hz", "timeout_s", "hover_s", "localhost_only", "mission"])
    print(f"ros2 param get {MISSION}: {g}", flush=True)
    # fcc-launch's square_flight.yaml: -p timeout_s:=400 -p hover_s:=${hover_s}; rate_hz its default.
    c.check("param get fcc_mission: the values in use (rate_hz 50.0, timeout_s 400.0, the mission file)",
            g["rate_hz"] == 50.0 and g["timeout_s"] == 400.0 and str(g["mission"]).endswith("square.yaml"), g)
    ds = param_describe(peer, node, MISSION, ["rate_hz", "hover_s", "use_sim_time"])
    for name, lo, hi in (("rate_hz", 20.0, 100.0), ("hover_s", 0.0, 86400.0)):
        d = ds[name]
        print(f"ros2 param describe {MISSION} {name}: {describe_text(d)}", flush=True)
        r = d.floating_point_range
        c.check(f"param describe fcc_mission {name}: range [{lo}, {hi}], read-only, a description",
                len(r) == 1 and math.isclose(r[0].from_value, lo) and math.isclose(r[0].to_value, hi)
                and d.read_only and len(d.description) > 10, describe_text(d))
    c.check("param describe fcc_mission use_sim_time: read-only", ds["use_sim_time"].read_only, describe_text(ds["use_sim_time"]))
    ok, why = param_set(peer, node, MISSION, "hover_s", 5.0)
    c.check("param set fcc_mission hover_s: refused (read at start-up) with the reason", not ok and "read-only" in why, (ok, why))


def late_joiner(c, peer):
    """A node created mid-flight: /tf_static (transient local) at once, odom and status flowing."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from ros_cli import msg_class
    t0 = time.monotonic()
    n = peer.node("rclpy_late_joiner")
    got = {"static": [], "odom": [], "status": []}
    static_qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    n.create_subscription(msg_class("tf2_msgs/msg/TFMessage"), "/tf_static", lambda m: got["static"].append(time.monotonic()), static_qos)
    n.create_subscription(msg_class("nav_msgs/msg/Odometry"), f"{NS}/state/odom", lambda m: got["odom"].append(time.monotonic()), 10)
    n.create_subscription(msg_class("fcc_msgs/msg/Status"), f"{NS}/status", lambda m: got["status"].append(time.monotonic()), 10)
    from ros_cli import Timeout
    try:
        peer.wait(lambda: got["static"] and len(got["odom"]) >= 10 and got["status"], 15, "the late joiner's data")
    except Timeout:
        pass
    lat = {k: (v[0] - t0 if v else None) for k, v in got.items()}
    c.check("late joiner: /tf_static (transient local), odom and status within 15 s",
            all(v is not None for v in lat.values()), {k: (f"{v:.2f} s" if v is not None else None) for k, v in lat.items()})
    return lat


def report_rates(c, cli, sensor):
    """Per topic: the CLI-QoS echo (rate in ROS time, frame_id) and the sensor-data echo (the
    same rate criterion; its share of the reliable reader's messages printed)."""
    print("topic                         CLI-QoS msgs  ROS-time Hz   wall Hz | sensor-data msgs  ROS-time Hz  frame_id")
    for t, (_, min_hz, frame) in TOPICS.items():
        none = {"n": 0, "hz": 0.0, "wall_hz": 0.0, "frames": [], "transient_local": False, "az0": None}
        r, q = cli.get(t, none), sensor.get(t, none)
        print(f"  {t:28s} {r['n']:7d} {r['hz']:12.1f} {r['wall_hz']:9.1f} | {q['n']:9d} {q['hz']:12.1f}  {r['frames']}", flush=True)
        if min_hz is not None:
            c.check(f"echo {t}: rate ≥ {min_hz} Hz (ROS time)", r["hz"] >= min_hz, f"{r['hz']:.1f} Hz")
        else:
            c.check(f"echo {t}: received", r["n"] > 0, r["n"])
        if frame:
            c.check(f"{t} frame_id {frame}", r["frames"] == [frame], r["frames"])
        # Not /tf_static: published once, transient local; a volatile reader matched after that
        # sample gets nothing (DDS semantics: `ros2 topic echo --qos-profile sensor_data` too).
        if r["transient_local"]:
            print(f"INFO {t}: sensor-data QoS (volatile) not checked on a transient-local topic ({q['n']} samples)")
            continue
        share = f"{q['n']}/{r['n']} = {100 * q['n'] / max(1, r['n']):.0f} % of the reliable reader's"
        if min_hz is not None:
            c.check(f"echo --qos-profile sensor_data {t}: rate ≥ {min_hz} Hz (ROS time)", q["hz"] >= min_hz,
                    f"{q['hz']:.1f} Hz; {share}")
        else:
            c.check(f"echo --qos-profile sensor_data {t}: received", q["n"] > 0, share)
        if frame:
            c.check(f"{t} (sensor-data QoS) frame_id {frame}", q["frames"] == [frame], q["frames"])


def static_edges(rec):
    """/tf_static as a tf2 buffer keeps it: {child: (parent, tf)}, the latest per child."""
    edges = {}
    for m in rec.msgs("/tf_static"):
        for t in m.transforms:
            edges[t.child_frame_id] = (t.header.frame_id, tf_of(t.transform))
    return edges


def tf_edges(static, m):
    """The tree at one /tf message: the static edges with the message's dynamic ones over them."""
    edges = dict(static)
    for t in m.transforms:
        edges[t.child_frame_id] = (t.header.frame_id, tf_of(t.transform))
    return edges


def check_tf(c, rec):
    """/tf + /tf_static (as tf2 combines them): map → odom → base_link (REP-105), odom → base_link
    continuous and dynamic; /tf_static: base_link → sensors, stamped on the same (MCU) clock as
    everything else."""
    static = static_edges(rec)
    edges_seen = {(p, k) for k, (p, _) in static.items()}
    chains, odom_steps, last_odom = set(), [], None
    for m in rec.msgs("/tf"):
        for t in m.transforms:
            edges_seen.add((t.header.frame_id, t.child_frame_id))
        edges = tf_edges(static, m)
        path, _ = tf_chain(edges)
        chains.add(tuple(path))
        dyn = {t.child_frame_id: t for t in m.transforms}
        if "base_link" in dyn and dyn["base_link"].header.frame_id == "odom":
            p = tf_of(dyn["base_link"].transform)[0]
            if last_odom is not None:
                # A jump is a step beyond what the vehicle can fly in the stamps' interval (8 m/s,
                # the MCU's horizontal limit; messages a loaded reader skipped widen the interval).
                d, dt = truth.dist(p, last_odom[1]), stamp_of(m) - last_odom[0]
                odom_steps.append((d - 8.0 * max(dt, 0.0), d, last_odom[0], stamp_of(m)))
            last_odom = (stamp_of(m), p)
    print(f"TF edges (/tf_static + /tf): {sorted(edges_seen)}; chains to base_link: {sorted(chains)}", flush=True)
    c.check("TF: map → odom → base_link (REP-105)", chains == {("map", "odom", "base_link")}, sorted(chains))
    worst = max(odom_steps, default=(float("nan"), float("nan"), None, None))
    c.check("/tf: odom → base_link dynamic and continuous (no step > 0.2 m + 8 m/s × Δt between messages)",
            len(odom_steps) > 100 and worst[0] < 0.2,
            f"{len(odom_steps)} steps, worst {worst[1]:.3f} m over {worst[2]} → {worst[3]} s")
    st = rec.msgs("/tf_static")
    kids = {(t.header.frame_id, t.child_frame_id) for m in st for t in m.transforms}
    want = {("base_link", k) for k in STATIC_CHILDREN}
    c.check("/tf_static: base_link → imu_link, gps_link, laser_link, sonar_link", want <= kids, sorted(kids))
    down = [t.transform.rotation for m in st for t in m.transforms if t.child_frame_id in ("laser_link", "sonar_link")]
    c.check("/tf_static: rangefinders look down (+90° about y)",
            down and all(abs(q.y - math.sqrt(0.5)) < 1e-6 and abs(q.w - math.sqrt(0.5)) < 1e-6 for q in down), len(down))
    # One clock on every stamp (clock_source:=mcu): /tf_static's stamp is MCU time like /clock's.
    clocks = [stamp_of(m) for m in rec.msgs("/clock")]
    sst = [stamp_of(m) for m in st]
    ok = bool(clocks and sst) and all(min(clocks) - 5.0 <= s <= max(clocks) + 1.0 for s in sst)
    c.check("/tf_static stamped on the MCU clock (within the /clock range)", ok,
            f"tf_static {sst[:2]} s, /clock {min(clocks, default=None)}..{max(clocks, default=None)} s")
    return worst[2:]


def slope(pts):
    """Least-squares slope of y over x."""
    n = len(pts)
    mx, my = sum(x for x, _ in pts) / n, sum(y for _, y in pts) / n
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx if sxx > 0 else float("nan")


def check_sim_time(c, rec, pairs, speed):
    """use_sim_time: the peer node's clock is the latest /clock (sampled every 0.2 s of wall time:
    node time minus the newest /clock received by then), and /clock runs at about `speed` × wall."""
    clk = [(w, stamp_of(m)) for w, m in rec.stamped("/clock")]
    p = [(w, r, last) for w, r, last in pairs if r > 0 and last is not None]
    if len(p) < 20 or len(clk) < 20:
        c.check("use_sim_time: the node clock follows /clock", False, f"{len(p)} samples, {len(clk)} /clock msgs")
        return
    d = [abs(r - last) for _, r, last in p]
    c.check("use_sim_time: the rclpy node's time = the newest /clock (p95 < 0.1 s of sim time)", pct(d, 0.95) < 0.1,
            f"{len(d)} samples, p50 {pct(d, 0.5) * 1e3:.1f} ms p95 {pct(d, 0.95) * 1e3:.1f} ms; worst (wall, node, /clock): "
            f"{[(round(w - p[0][0], 2), round(r, 3), round(last, 3)) for w, r, last in sorted(p, key=lambda x: -abs(x[1] - x[2]))[:3]]}")
    clock_rate = slope(clk)
    c.check(f"use_sim_time: /clock runs at the simulator's speed {speed} × wall (≥ 75 % of it: sim time, not wall time)",
            clock_rate >= 0.75 * speed, f"{clock_rate:.3f} × wall")


def check_truth(c, rec, log):
    """Values against the simulator's truth log at the same simulated times (ENU, not NED)."""
    od = rec.msgs(f"{NS}/state/odom")
    # The odometry's frame (odom) into map through /tf_static, as tf2 would.
    static = static_edges(rec)
    est, hor, pos = [], [], []
    for m in od:
        path, tf = tf_chain(static, m.header.frame_id)
        if path[0] != "map":
            continue
        p = m.pose.pose.position
        p = truth.compose(tf, ((p.x, p.y, p.z), (1.0, 0.0, 0.0, 0.0)))[0]
        pos.append(p)
        t = stamp_of(m)
        e, tr = truth.est_enu(log, t), truth.true_enu(log, t)
        if e is None:
            continue
        est.append(truth.dist(p, e))
        hor.append(math.hypot(p[0] - tr[0], p[1] - tr[1]))
    c.check("state/odom (in map via /tf_static) = the MCU's estimate (CSV, ENU of NED) at the same sim time, p99 < 0.15 m",
            len(est) > 1000 and pct(est, 0.99) < 0.15, f"{len(est)} msgs, p50 {pct(est, 0.5):.3f} m p99 {pct(est, 0.99):.3f} m")
    c.check("state/odom vs truth horizontal p95 < 2.5 m (GPS-grade)", pct(hor, 0.95) < 2.5,
            f"p50 {pct(hor, 0.5):.2f} m p95 {pct(hor, 0.95):.2f} m")
    xs = [p[0] for p in pos]
    ys = [p[1] for p in pos]
    c.check("ENU: the north leg shows as +y ≈ 20 m, the east leg as +x ≈ 20 m",
            ys and 17 < max(ys) < 23 and 17 < max(xs) < 23, f"max y {max(ys, default=0):.1f} max x {max(xs, default=0):.1f}")
    # TF: the chain to base_link at each /tf message = the estimate.
    tfe = []
    static = static_edges(rec)
    for m in rec.msgs("/tf"):
        path, tf = tf_chain(tf_edges(static, m))
        e = truth.est_enu(log, stamp_of(m))
        if path[0] == "map" and e is not None:
            tfe.append(truth.dist(tf[0], e))
    c.check("TF map → base_link (through /tf_static and /tf) = the MCU's estimate (CSV) at the same sim time, p99 < 0.15 m",
            len(tfe) > 1000 and pct(tfe, 0.99) < 0.15, f"{len(tfe)} msgs, p50 {pct(tfe, 0.5):.3f} m p99 {pct(tfe, 0.99):.3f} m")
    gr = []
    for m in rec.msgs(f"{NS}/altitude/ground"):
        g = truth.interp(log, "ground_m", stamp_of(m))
        if g is not None:
            gr.append(abs(m.range - g))
    c.check("altitude/ground = the MCU's fused height (CSV ground_m), p95 < 0.03 m",
            len(gr) > 500 and pct(gr, 0.95) < 0.03, f"{len(gr)} msgs, p50 {pct(gr, 0.5) * 100:.2f} cm p95 {pct(gr, 0.95) * 100:.2f} cm")
    sps = rec.msgs(f"{NS}/setpoint/velocity")
    c.check("the mission node's setpoints: north leg +y ≈ 3 m/s (ENU)", any(abs(s.twist.linear.y - 3.0) < 0.05 for s in sps), len(sps))
    sts = rec.msgs(f"{NS}/status")
    c.check("status: armed in flight, landed and disarmed at the end",
            any(s.armed for s in sts) and sts and not sts[-1].armed and sts[-1].landed,
            (sts[-1].mode_name, sts[-1].armed, sts[-1].landed) if sts else None)
    logs = {m.name for m in rec.msgs("/rosout")}
    c.check("echo /rosout: log lines of both nodes (fcc.fcc_bridge, fcc.fcc_mission)",
            {"fcc.fcc_bridge", "fcc.fcc_mission"} <= logs, sorted(logs))
    phases = {json.loads(m.data).get("phase") for m in rec.msgs(f"{NS}/mission/status")}
    c.check("mission/status: phases leg … finished", {"leg", "finished"} <= phases, sorted(p for p in phases if p))
    c.check("truth: the vehicle landed and disarmed (CSV)", log["mode"][-1] == "Disarmed", log["mode"][-1])


# ------------------------------------------------------------------------------------ fly

def check_params_fly(c, peer, node):
    """`ros2 param list/get/set/describe` on the bridge: ranges, units and read-only shown, values
    outside the range refused with the range, a set acknowledged and read back."""
    from ros_cli import Timeout, describe_text, param_describe, param_get, param_list, param_set
    names = param_list(peer, node, BRIDGE)
    print(f"ros2 param list {BRIDGE}: {names}", flush=True)
    c.check("param list: bridge and MCU parameters",
            {"ttl_ms", "max_speed_mps", "ping_period_ms", "clock_source", "limits.max_tilt_deg"} <= set(names), len(names))
    g = param_get(peer, node, BRIDGE, ["ttl_ms", "max_speed_mps", "limits.max_tilt_deg", "clock_source"])
    print(f"ros2 param get: {g}", flush=True)
    tilt = mcu_params.default("limits.max_tilt_deg")
    c.check(f"param get: defaults (ttl_ms 300, max_speed_mps 20.0, limits.max_tilt_deg {tilt}, clock_source sync)",
            g == {"ttl_ms": 300, "max_speed_mps": 20.0, "limits.max_tilt_deg": tilt, "clock_source": "sync"}, g)
    # (name, integer?, from, to, read_only)
    want = [("ttl_ms", True, 50, 3000, False), ("max_speed_mps", False, 0.1, 30.0, False),
            ("ping_period_ms", True, 100, 10000, True), ("limits.max_tilt_deg", False, 5.0, 60.0, False)]
    ds = param_describe(peer, node, BRIDGE, [w[0] for w in want])
    for name, is_int, lo, hi, ro in want:
        d = ds[name]
        print(f"ros2 param describe {BRIDGE} {name}: {describe_text(d)}", flush=True)
        rng = d.integer_range if is_int else d.floating_point_range
        ok_rng = len(rng) == 1 and math.isclose(rng[0].from_value, lo) and math.isclose(rng[0].to_value, hi)
        c.check(f"param describe {name}: range [{lo}, {hi}]", ok_rng, describe_text(d))
        c.check(f"param describe {name}: read_only {ro}", d.read_only == ro, d.read_only)
        c.check(f"param describe {name}: a description (with its unit)",
                d.description and "not implemented" not in d.description and "missing" not in d.description, d.description)
    from rcl_interfaces.msg import ParameterEvent
    from ros_cli import value_of
    events = []
    node.create_subscription(ParameterEvent, "/parameter_events", events.append, 1000)
    ok, why = param_set(peer, node, BRIDGE, "ttl_ms", 400)
    back = param_get(peer, node, BRIDGE, ["ttl_ms"])["ttl_ms"]
    c.check("param set ttl_ms 400: accepted and read back", ok and back == 400, (ok, why, back))
    seen = lambda: [(e.node, p.name, value_of(p.value)) for e in events for p in e.changed_parameters]  # noqa: E731
    try:
        peer.wait(lambda: (BRIDGE, "ttl_ms", 400) in seen(), 5, "the /parameter_events of ttl_ms")
    except Timeout:
        pass
    c.check("echo /parameter_events: the bridge announces ttl_ms = 400", (BRIDGE, "ttl_ms", 400) in seen(), seen())
    ok, why = param_set(peer, node, BRIDGE, "ttl_ms", 65535)
    c.check("param set ttl_ms 65535: refused with the range in the reason", not ok and "[50, 3000]" in why, why)
    ok, why = param_set(peer, node, BRIDGE, "limits.max_tilt_deg", 30.0)
    back = param_get(peer, node, BRIDGE, ["limits.max_tilt_deg"])["limits.max_tilt_deg"]
    c.check("param set limits.max_tilt_deg 30.0 (MCU parameter): acknowledged and read back", ok and back == 30.0, (ok, why, back))
    ok, why = param_set(peer, node, BRIDGE, "limits.max_tilt_deg", 90.0)
    c.check("param set limits.max_tilt_deg 90.0: refused", not ok, why)
    ok, why = param_set(peer, node, BRIDGE, "ping_period_ms", 500)
    c.check("param set ping_period_ms (read-only after start): refused", not ok, why)
    param_set(peer, node, BRIDGE, "ttl_ms", 300)
    param_set(peer, node, BRIDGE, "limits.max_tilt_deg", tilt)


def check_link_rates(c, peer, node):
    """`ros2 param set /fcc/fcc_bridge rates.imu_hz 50`: the MCU reschedules the IMU stream and
    the rate this peer measures (sample stamps) follows within 1 s; a set whose worst case
    exceeds the link budget is refused with the budget in the reason."""
    from ros_cli import param_set
    from sensor_msgs.msg import Imu
    stamps = []
    node.create_subscription(Imu, f"{NS}/imu/data_raw", lambda m: stamps.append(truth.t_of(m.header.stamp)), 100)

    def hz(t0, t1):
        return sum(1 for t in stamps if t0 <= t < t1) / (t1 - t0)
    now = lambda: node.get_clock().now().nanoseconds * 1e-9  # noqa: E731
    # The window starts no earlier than the first sample: a new subscription's DDS matching
    # (up to ~1 s on a loaded machine) is not a gap in the stream.
    peer.spin(2.0)
    deadline = now() + 5.0
    while (not stamps or now() - stamps[0] < 1.6) and now() < deadline:
        peer.spin(0.2)
    t = now()
    t0 = max(t - 1.5, stamps[0] if stamps else t - 1.5)
    ok, why = param_set(peer, node, BRIDGE, "rates.imu_hz", 50)
    # From the answer on (the set is in force then; a fresh service client's DDS matching, up to
    # ~3 s on a loaded machine, is not the link's doing).
    t_ack = now()
    peer.spin(2.6)
    after = hz(t_ack + 1.0, t_ack + 2.5)
    # The window before the set is counted only now: samples stamped in it that this executor
    # had not yet taken at `t` (a backlog behind the clock) have arrived by now.
    before = hz(t0, t)
    print(f"imu/data_raw: {before:.1f} Hz before `param set rates.imu_hz 50`, {after:.1f} Hz from 1 s after its "
          f"answer on (the call took {t_ack - t:.2f} s)", flush=True)
    c.check("param set rates.imu_hz 50: accepted", ok, why)
    c.check("imu/data_raw at the default 200 Hz before (±10 %)", abs(before - 200) <= 20, f"{before:.1f} Hz")
    c.check("imu/data_raw at 50 Hz from 1 s after the set's answer on (±10 %)", abs(after - 50) <= 5, f"{after:.1f} Hz")
    ok, why = param_set(peer, node, BRIDGE, "rates.imu_hz", 1000)
    c.check("param set rates.imu_hz 1000: within the link budget, accepted", ok, why)
    ok, why = param_set(peer, node, BRIDGE, "rates.nav_state_hz", 500)
    print(f"param set rates.nav_state_hz 500 (with rates.imu_hz 1000): {ok} {why!r}", flush=True)
    c.check("param set rates.nav_state_hz 500 on top: refused, the budget in the reason",
            not ok and "B/s" in why and "budget" in why and "460800-baud" in why, why)
    for name, v in (("rates.imu_hz", 200), ("rates.nav_state_hz", 100)):
        ok, why = param_set(peer, node, BRIDGE, name, v)
        c.check(f"param set {name} {v} (the default again): accepted", ok, why)


class Vehicle:
    """Status, odometry and telemetry latency as the flying peer sees them."""

    def sim_time(self):
        """MCU (= simulator) time of the last status: with clock_source:=sync its stamp is
        ROS time = MCU time + time_sync_offset_ns."""
        from truth import t_of
        return t_of(self.st.header.stamp) - self.st.time_sync_offset_ns * 1e-9

    def __init__(self, node):
        from ros_cli import msg_class
        from truth import t_of
        self.st = None
        self.odom = None
        self.lat_ms = {"imu/data_raw": [], "state/odom": []}
        self.node = node

        def lat(name):
            def cb(m):
                now = node.get_clock().now().nanoseconds * 1e-9
                self.lat_ms[name].append((now - t_of(m.header.stamp)) * 1e3)
                if name == "state/odom":
                    self.odom = m
            return cb
        node.create_subscription(msg_class("fcc_msgs/msg/Status"), f"{NS}/status", self._status, 10)
        node.create_subscription(msg_class("nav_msgs/msg/Odometry"), f"{NS}/state/odom", lat("state/odom"), 10)
        node.create_subscription(msg_class("sensor_msgs/msg/Imu"), f"{NS}/imu/data_raw", lat("imu/data_raw"), 10)

    def _status(self, m):
        self.st = m

    def mode(self):
        return self.st.mode_name if self.st else None


def fly_plan(peer, node, v, events, plan):
    """Setpoints with rclpy's DEFAULT publisher QoS (reliable, keep last 10; `ros2 topic pub`),
    stamped with the node's clock, frame map (ENU), 50 Hz."""
    from geometry_msgs.msg import TwistStamped
    pub = node.create_publisher(TwistStamped, f"{NS}/setpoint/velocity", 10)
    peer.wait(lambda: pub.get_subscription_count() > 0, 10, "the bridge's setpoint reader")
    for dur, vel in plan:
        t_start = time.monotonic()
        events.append((f"velocity {vel}", v.sim_time()))
        print(f"peer: setpoint ENU {vel} for {dur} s", flush=True)
        while time.monotonic() - t_start < dur:
            m = TwistStamped()
            m.header.stamp = node.get_clock().now().to_msg()
            m.header.frame_id = "map"
            m.twist.linear.x, m.twist.linear.y, m.twist.linear.z = vel
            pub.publish(m)
            peer.spin(0.02)
    return pub


def fly(a):
    from ros_cli import Peer, Timeout
    from std_msgs.msg import String
    from std_srvs.srv import SetBool, Trigger
    c = Checks()
    peer = Peer("rclpy_pilot")
    node = peer.main
    v = Vehicle(node)
    events = []
    t0 = time.monotonic()
    try:
        check_graph(c, peer, node, [BRIDGE])
        peer.wait(lambda: v.st is not None, 20, "status")
        check_params_fly(c, peer, node)
        check_link_rates(c, peer, node)
        # Arm through the service (retry: the MCU refuses until calibrated and its GPS home set).
        r = None
        end = time.monotonic() + 60
        while not (v.st and v.st.armed) and time.monotonic() < end:
            r = peer.call(node, SetBool, f"{NS}/arm", SetBool.Request(data=True))
            peer.spin(0.5)
        c.check("service arm (std_srvs/SetBool) true: armed", v.st.armed, (r.success, r.message) if r else None)
        events.append(("armed", v.sim_time()))
        mode = node.create_publisher(String, f"{NS}/cmd/mode", 10)
        peer.wait(lambda: mode.get_subscription_count() > 0, 10, "the bridge's cmd/mode reader")
        mode.publish(String(data="velocity"))
        # The hold is called the moment the setpoints stop, as a pilot node does with its client
        # already matched: a fresh client (`ros2 service call`) needs seconds to match, and by
        # then the MCU's own failsafe acts (setpoints stale → hold, lost → land).
        hold_cli = node.create_client(Trigger, f"{NS}/hold")
        peer.wait(hold_cli.service_is_ready, 10, "service hold")
        fly_plan(peer, node, v, events, [(5.0, (0.0, 0.0, 1.0)), (8.0, (0.0, 2.0, 0.0)), (3.0, (0.0, 0.0, 0.0))])
        c.check("velocity mode until the last setpoint", v.mode() == "velocity", v.mode())
        # Each event is stamped with the last status BEFORE its call: the mode switches after it
        # (a status received after the call may already show the new mode).
        t_call = v.sim_time()
        fut = hold_cli.call_async(Trigger.Request())
        peer.wait(fut.done, 10, "the answer of hold")
        r = fut.result()
        events.append(("hold", t_call))
        z = v.odom.pose.pose.position
        c.check("after climb 5 s and north 8 s: odom y > 6 m, z > 3 m (ENU)", z.y > 6 and z.z > 3, f"x {z.x:.2f} y {z.y:.2f} z {z.z:.2f}")
        peer.wait(lambda: v.mode() == "hold", 5, "hold mode")
        c.check("service hold (std_srvs/Trigger): success, MCU in hold", r.success and v.mode() == "hold", (r.success, r.message, v.mode()))
        peer.spin(3.0)
        t_call = v.sim_time()
        r = peer.call(node, Trigger, f"{NS}/land", Trigger.Request())
        events.append(("land", t_call))
        peer.wait(lambda: v.mode() == "land", 5, "land mode")
        c.check("service land (std_srvs/Trigger): success, MCU in land", r.success and v.mode() == "land", (r.success, r.message, v.mode()))
        peer.wait(lambda: not v.st.armed and v.st.landed, 60, "landed and disarmed")
        events.append(("disarmed", v.sim_time()))
        c.check("landed and disarmed", not v.st.armed and v.st.landed, v.mode())
    except Timeout as e:
        c.check("fly: no timeout", False, f"{e} (mode {v.mode()}, last reject {v.st.last_reject if v.st else None})")
    for k, l in v.lat_ms.items():
        print(f"latency {k}: stamp (MCU sample, Linux clock via time sync) → rclpy callback: "
              f"p50 {pct(l, 0.5):.2f} ms p95 {pct(l, 0.95):.2f} ms max {max(l, default=float('nan')):.2f} ms ({len(l)} msgs)", flush=True)
        c.check(f"latency {k} p95 < 50 ms", len(l) > 100 and pct(l, 0.95) < 50, f"{pct(l, 0.95):.2f} ms")
    with open(a.events, "w") as f:
        json.dump(events, f)
    print(f"peer: flight done in {time.monotonic() - t0:.1f} s wall", flush=True)
    peer.shutdown()
    return c.done()


def check_fly(a):
    c = Checks()
    log = truth.load_csv(a.csv)
    events = json.load(open(a.events))
    vel = [t for k, t in events if k.startswith("velocity")]
    named = {k: t for k, t in events if not k.startswith("velocity")}
    if len(vel) < 3 or not {"hold", "land", "disarmed"} <= set(named):
        c.check("the flight's events are complete", False, events)
        return c.done()
    at = lambda col, t: truth.interp(log, col, t)  # noqa: E731
    dz = -(at("true_d_m", vel[1]) - at("true_d_m", vel[0]))
    c.check("climb 1 m/s for 5 s: truth rises 3.5–5.5 m", 3.5 < dz < 5.5, f"{dz:.2f} m")
    dn = at("true_n_m", vel[2]) - at("true_n_m", vel[1])
    de = at("true_e_m", vel[2]) - at("true_e_m", vel[1])
    c.check("ENU (0, 2, 0) for 8 s = north: truth moves 6–17 m north, within 1.5 m east/west",
            6 < dn < 17 and abs(de) < 1.5, f"north {dn:.2f} m east {de:.2f} m")
    modes = log["mode"]
    # The MCU's mode sequence on the truth log, as runs (mode, start s, end s): the peer's hold and
    # land services must show as a Hold of about the 3 s the peer waited, then Land. (Judged on
    # the sequence, not on the peer's event times: those come from status stamps mapped back
    # through the sync offset, which can be off by seconds on a loaded machine.)
    runs = []
    for t, m in zip(log["t_s"], modes):
        if runs and runs[-1][0] == m:
            runs[-1][2] = t
        else:
            runs.append([m, t, t])
    seq = [(m, round(t1 - t0, 2)) for m, t0, t1 in runs]
    after_flight = [r for r in runs if r[1] >= vel[2] - 1.0]
    hold_then_land = any(a[0] == "Hold" and 2.0 <= a[2] - a[1] <= 10.0 and b[0] == "Land"
                         for a, b in zip(after_flight, after_flight[1:]))
    c.check("service hold → MCU Hold for ~3 s, then service land → MCU Land (CSV mode sequence)",
            hold_then_land, seq)
    # No failsafe on the way: the only Land after the flight is the commanded one, and the
    # failsafe column stays None from the hold on.
    lands = [r for r in after_flight if r[0] == "Land"]
    fs = {f for t, f in zip(log["t_s"], log["failsafe"]) if t >= named["hold"] + 0.5}
    c.check("no failsafe after the hold (one Land, failsafe None)", len(lands) == 1 and fs == {"None"},
            (len(lands), sorted(fs)))
    c.check("landed and disarmed at the end (CSV)", modes[-1] == "Disarmed" and log["true_d_m"][-1] > -0.5,
            (modes[-1], log["true_d_m"][-1]))
    return c.done()


# ------------------------------------------------------------------------------------ probe

def probe(a):
    """A restarted peer (a new process after the first one left): sees the bridge again, the
    transient-local /tf_static, the status, and reads a parameter."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from ros_cli import Peer, Timeout, msg_class, param_get
    c = Checks()
    t0 = time.monotonic()
    peer = Peer("rclpy_pilot")  # the same name as the peer that left
    node = peer.main
    got = {"static": None, "status": None}
    q = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(msg_class("tf2_msgs/msg/TFMessage"), "/tf_static",
                             lambda m: got.update(static=(time.monotonic() - t0, m)), q)
    node.create_subscription(msg_class("fcc_msgs/msg/Status"), f"{NS}/status",
                             lambda m: got.update(status=(time.monotonic() - t0, m)), 10)
    try:
        check_graph(c, peer, node, [BRIDGE], " (restarted peer)")
        peer.wait(lambda: got["static"] and got["status"], 15, "/tf_static and status")
        kids = {t.child_frame_id for t in got["static"][1].transforms}
        c.check("restarted peer: /tf_static replayed (transient local)", STATIC_CHILDREN <= kids,
                f"after {got['static'][0]:.2f} s: {sorted(kids)}")
        c.check("restarted peer: status flowing", got["status"] is not None, f"after {got['status'][0]:.2f} s")
        g = param_get(peer, node, BRIDGE, ["ttl_ms"])
        c.check("restarted peer: param get ttl_ms = 300 (restored by the first peer)", g["ttl_ms"] == 300, g)
    except Timeout as e:
        c.check("probe: no timeout", False, e)
    peer.shutdown()
    return c.done()


# ------------------------------------------------------------------------------------ smoke

def smoke(a):
    """Kilted: node list, topics (one type each), a parameter set, a setpoint flown."""
    from ros_cli import Peer, Timeout, param_get, param_set
    from std_msgs.msg import String
    from std_srvs.srv import SetBool, Trigger
    c = Checks()
    peer = Peer("rclpy_kilted")
    node = peer.main
    v = Vehicle(node)
    print(f"peer: ROS_DISTRO={os.environ.get('ROS_DISTRO')}, rclpy from {sys.modules['rclpy'].__file__}", flush=True)
    try:
        _, tl = check_graph(c, peer, node, [BRIDGE])
        bridge_topics = [t for t in TOPICS if not t.startswith(f"{NS}/setpoint") and not t.startswith(f"{NS}/mission")]
        peer.wait(lambda: v.st is not None and v.odom is not None, 20, "status and odom")
        from ros_cli import topic_list
        check_expected_types(c, topic_list(node), bridge_topics)
        ok, why = param_set(peer, node, BRIDGE, "max_speed_mps", 12.5)
        back = param_get(peer, node, BRIDGE, ["max_speed_mps"])["max_speed_mps"]
        c.check("param set max_speed_mps 12.5: accepted and read back", ok and back == 12.5, (ok, why, back))
        end = time.monotonic() + 60
        while not v.st.armed and time.monotonic() < end:
            peer.call(node, SetBool, f"{NS}/arm", SetBool.Request(data=True))
            peer.spin(0.5)
        c.check("service arm: armed", v.st.armed, v.mode())
        mode = node.create_publisher(String, f"{NS}/cmd/mode", 10)
        peer.wait(lambda: mode.get_subscription_count() > 0, 10, "the bridge's cmd/mode reader")
        mode.publish(String(data="velocity"))
        z0 = v.odom.pose.pose.position.z
        fly_plan(peer, node, v, [], [(4.0, (0.0, 0.0, 1.0))])
        dz = v.odom.pose.pose.position.z - z0
        c.check("setpoint ENU (0, 0, 1) for 4 s: odom climbs 2–5 m", 2.0 < dz < 5.0, f"{dz:.2f} m")
        r = peer.call(node, Trigger, f"{NS}/land", Trigger.Request())
        c.check("service land: success", r.success, r.message)
    except Timeout as e:
        c.check("smoke: no timeout", False, f"{e} (mode {v.mode()})")
    peer.shutdown()
    return c.done()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["observe", "echo", "fly", "probe", "check-fly", "smoke"])
    ap.add_argument("--qos", choices=["cli", "sensor"], help="echo: the CLI's QoS choice or sensor-data QoS")
    ap.add_argument("--json", help="echo: where to write its figures")
    ap.add_argument("--echo-json", help="observe: the CLI-QoS echo's figures")
    ap.add_argument("--sensor-json", help="observe: the sensor-data echo's figures")
    ap.add_argument("--csv")
    ap.add_argument("--until-file")
    ap.add_argument("--ready-file")
    ap.add_argument("--events")
    ap.add_argument("--speed", type=float, default=2.0)
    ap.add_argument("--timeout", type=float, default=240)
    a = ap.parse_args()
    return {"observe": observe, "echo": echo, "fly": fly, "probe": probe, "check-fly": check_fly, "smoke": smoke}[a.mode](a)


if __name__ == "__main__":
    sys.exit(main())
