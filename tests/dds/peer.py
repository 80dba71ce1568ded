#!/usr/bin/env python3
"""Independent Cyclone DDS peer for fcc-bridge (acceptance test, scope 3).

Subscribes to every bridge topic with ROS 2 type names, checks values, frames and rates
against the fake MCU's script (fcc_bridge/src/fake_mcu.rs: nose down 10°, heading 30°, NED
velocity (2, 0, -0.5), NED position (10, 5, -3), ...), publishes TwistStamped setpoints with
RELIABLE QoS (as `ros2 topic pub` does) plus cmd/arm and cmd/mode, and checks in the fake MCU's
log that the MCU received the right NED setpoints and commands. Checks that the node appears in
`ros_discovery_info`.

Run only inside a loopback-only network namespace (../shared/tools/netns-run).
usage: peer.py --mcu-log FILE [--ns /fcc] [--seconds 6]
"""
import argparse
import json
import math
import os
import sys
import time

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros_types as rt
from link_resolution import LSB

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))
from truth import qmul, qrot  # noqa: E402

RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(50))
DISCOVERY_QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                    Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
TF_STATIC_QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                    Policy.Durability.TransientLocal, Policy.History.KeepLast(1))

# ---------------------------------------------------------------- independent expected values


def axis_angle(axis, ang):
    s = math.sin(ang / 2)
    return (math.cos(ang / 2), axis[0] * s, axis[1] * s, axis[2] * s)


# ENU/FLU attitude written directly (not via NED): heading 30° east of north = ENU yaw 60°;
# nose down 10° = +10° about the body's y (left) axis.
Q_EXPECT = qmul(axis_angle((0, 0, 1), math.radians(60)), axis_angle((0, 1, 0), math.radians(10)))
V_ENU = (0.0, 2.0, 0.5)  # north 2 m/s = ENU +y; climbing 0.5 m/s = +z
V_FLU = qrot((Q_EXPECT[0], -Q_EXPECT[1], -Q_EXPECT[2], -Q_EXPECT[3]), V_ENU)
P_ENU = (5.0, 10.0, 3.0)  # NED (10, 5, -3)

TOPICS = {
    # name: (type, expected min rate Hz)
    "imu/data_raw": (rt.Imu, 150),
    "mag": (rt.MagneticField, 15),
    "baro": (rt.FluidPressure, 15),
    "gps/fix": (rt.NavSatFix, 7),
    "range/laser": (rt.Range, 7),
    "range/sonar": (rt.Range, 7),
    "battery": (rt.BatteryState, 3),
    "state/odom": (rt.Odometry, 40),
    "state/imu": (rt.Imu, 40),
    "/tf": (rt.TFMessage, 40),
    "altitude": (rt.Altitude, 15),
    "altitude/ground": (rt.Range, 15),
    "status": (rt.Status, 7),
    "accel/observer": (rt.AccelStamped, 40),
    "accel/measured": (rt.AccelStamped, 40),
    "/diagnostics": (rt.DiagnosticArray, 0.5),
}


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, name, ok, detail=""):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
        print(f"{'PASS' if ok else 'FAIL'} {name}{(': ' + str(detail)) if detail else ''}")
        sys.stdout.flush()


# The link's fixed-point resolutions (the schema's `fixed` line): the IMU, magnetometer,
# attitude, rates and velocity cross the UART as i16 counts, so a value comes back within half
# a count (a frame or sign error is far larger).
GYRO_LSB = LSB["gyro"]                          # rad/s
ACCEL_LSB = LSB["accel"]                        # m/s^2
MAG_LSB_T = LSB["mag"] * 1e-6                   # tesla
Q_TOL = 2.0 * LSB["unit"]                       # quaternion components after the frame change
VEL_TOL = LSB["vel"] + 2.0 * Q_TOL * 2.0        # half a velocity count + the rotation's share


def close(a, b, tol=1e-4):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def vec(v):
    return (v.x, v.y, v.z)


def quat(q):
    w = (q.w, q.x, q.y, q.z)
    return w if w[0] >= 0 else tuple(-c for c in w)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcu-log", required=True)
    ap.add_argument("--ns", default="/fcc")
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--domain", type=int, default=0)
    a = ap.parse_args()
    ns = a.ns.rstrip("/")

    dp = DomainParticipant(a.domain)

    def dds_name(n):
        return "rt" + (n if n.startswith("/") else f"{ns}/{n}")

    readers = {}
    for n, (ty, _) in TOPICS.items():
        readers[n] = DataReader(dp, Topic(dp, dds_name(n), ty), qos=RELIABLE)
    # A best-effort reader too: the bridge's reliable writers must match it as well.
    be_imu = DataReader(dp, Topic(dp, dds_name("imu/data_raw"), rt.Imu),
                        qos=Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(50)))
    tf_static = DataReader(dp, Topic(dp, "rt/tf_static", rt.TFMessage), qos=TF_STATIC_QOS)
    disc = DataReader(dp, Topic(dp, "ros_discovery_info", rt.ParticipantEntitiesInfo),
                      qos=DISCOVERY_QOS)
    sp_writer = DataWriter(dp, Topic(dp, dds_name("setpoint/velocity"), rt.TwistStamped),
                           qos=RELIABLE)
    arm_writer = DataWriter(dp, Topic(dp, dds_name("cmd/arm"), rt.Bool), qos=RELIABLE)
    mode_writer = DataWriter(dp, Topic(dp, dds_name("cmd/mode"), rt.String), qos=RELIABLE)

    got = {n: [] for n in TOPICS}
    arrivals = {n: [] for n in TOPICS}
    be_count = 0
    static_tf = []
    nodes = set()
    t0 = time.time()
    sent = False
    # Wait for the first IMU sample (discovery + handshake), then measure for --seconds.
    first = None
    while time.time() - t0 < a.seconds + 15:
        now = time.time()
        for n, r in readers.items():
            for s in r.take(N=500):
                got[n].append(s)
                arrivals[n].append(now)
        be_count += len(be_imu.take(N=500))
        static_tf += tf_static.take(N=10)
        for s in disc.take(N=50):
            for ne in s.node_entities_info_seq:
                nodes.add((ne.node_namespace, ne.node_name))
        if first is None and got["imu/data_raw"]:
            first = now
        if first is not None and not sent and now - first > 1.5:
            # Setpoints and commands, reliable writers (like `ros2 topic pub`).
            stamp = rt.Time(sec=int(now), nanosec=int((now % 1) * 1e9))
            arm_writer.write(rt.Bool(data=True))
            time.sleep(0.05)
            mode_writer.write(rt.String(data="velocity"))
            time.sleep(0.05)
            # ENU (east 1, north 2, up 0.5) in map → NED (2, 1, -0.5).
            sp_writer.write(rt.TwistStamped(rt.Header(stamp, "map"), rt.Twist(rt.Vector3(1.0, 2.0, 0.5))))
            time.sleep(0.05)
            # Refused by the bridge: NaN, unknown frame, stale stamp, too fast.
            sp_writer.write(rt.TwistStamped(rt.Header(stamp, "map"), rt.Twist(rt.Vector3(math.nan, 0.0, 0.0))))
            sp_writer.write(rt.TwistStamped(rt.Header(stamp, "camera"), rt.Twist(rt.Vector3(1.0, 0.0, 0.0))))
            sp_writer.write(rt.TwistStamped(rt.Header(rt.Time(sec=int(now) - 10), "map"), rt.Twist(rt.Vector3(1.0, 0.0, 0.0))))
            sp_writer.write(rt.TwistStamped(rt.Header(stamp, "map"), rt.Twist(rt.Vector3(100.0, 0.0, 0.0))))
            time.sleep(0.05)
            # Body FLU forward 1 m/s (heading 30°) → NED (cos30, sin30, 0); unstamped, with a yaw
            # rate (ignored).
            sp_writer.write(rt.TwistStamped(rt.Header(rt.Time(), "base_link"),
                                            rt.Twist(rt.Vector3(1.0, 0.0, 0.0), rt.Vector3(0.0, 0.0, 0.3))))
            sent = True
        if first is not None and now - first > a.seconds:
            break
        time.sleep(0.01)

    c = Checks()
    c.check("bridge data arrived", first is not None)
    if first is None:
        print(f"{c.passed} passed, {c.failed} failed")
        return 1
    window = a.seconds - 0.5

    # Rates over the measuring window.
    print("topic counts / rates seen by the peer:")
    for n, (_, min_hz) in TOPICS.items():
        ts = [t for t in arrivals[n] if t >= first + 0.5]
        hz = len(ts) / window
        print(f"  {n:18s} {len(got[n]):5d} msgs  {hz:7.1f} Hz")
        c.check(f"rate {n} >= {min_hz} Hz", hz >= min_hz, f"{hz:.1f} Hz")
    c.check("best-effort reader matches reliable writer", be_count > 100, be_count)

    wall = time.time()

    def stamp_ok(h):
        t = h.stamp.sec + h.stamp.nanosec * 1e-9
        return abs(t - wall) < a.seconds + 20

    imu = got["imu/data_raw"][-1]
    c.check("imu frame_id", imu.header.frame_id == "imu_link", imu.header.frame_id)
    c.check("imu stamp is ROS (wall) time", stamp_ok(imu.header))
    c.check("imu orientation_covariance[0] = -1", imu.orientation_covariance[0] == -1.0)
    c.check("imu gyro FRD→FLU", close(vec(imu.angular_velocity), (0.1, -0.2, -0.3), 0.51 * GYRO_LSB), vec(imu.angular_velocity))
    c.check("imu accel FRD→FLU (+g up)", close(vec(imu.linear_acceleration), (0.5, 0.2, 9.81), 0.51 * ACCEL_LSB), vec(imu.linear_acceleration))

    mag = got["mag"][-1]
    c.check("mag in tesla FLU", close(vec(mag.magnetic_field), (20e-6, -5e-6, -40e-6), 0.51 * MAG_LSB_T), vec(mag.magnetic_field))
    c.check("baro Pa", abs(got["baro"][-1].fluid_pressure - 101000.0) < 1e-3)
    fix = got["gps/fix"][-1]
    c.check("gps fix", abs(fix.latitude - 47.397742) < 1e-9 and abs(fix.longitude - 8.545594) < 1e-9
            and fix.status.status == 0 and abs(fix.altitude - 488.0) < 1e-3)
    lasers = [s.range for s in got["range/laser"]]
    c.check("laser: value and no-return sentinel → +inf (REP-117)",
            any(math.isinf(x) and x > 0 for x in lasers) and any(abs(x - 3.2) < 1e-5 for x in lasers))
    las = got["range/laser"][-1]
    c.check("laser Range fields (Jazzy variance)", las.radiation_type == 1 and abs(las.max_range - 150) < 1e-3
            and abs(las.variance - 0.0025) < 1e-6 and las.header.frame_id == "laser_link")
    son = got["range/sonar"][-1]
    c.check("sonar Range", son.radiation_type == 0 and abs(son.range - 2.5) < 1e-5 and abs(son.max_range - 10.68) < 1e-4)
    bat = got["battery"][-1]
    c.check("battery", abs(bat.voltage - 15.8) < 1e-4 and abs(bat.current + 12.0) < 1e-4 and bat.present)

    od = got["state/odom"][-1]
    c.check("odom frames odom→base_link (REP-105)", od.header.frame_id == "odom" and od.child_frame_id == "base_link",
            (od.header.frame_id, od.child_frame_id))
    c.check("odom position ENU", close(vec(od.pose.pose.position), P_ENU), vec(od.pose.pose.position))
    c.check("odom orientation ENU/FLU (yaw 60°, nose down 10°)", close(quat(od.pose.pose.orientation), Q_EXPECT, Q_TOL),
            (quat(od.pose.pose.orientation), Q_EXPECT))
    c.check("odom twist in base_link FLU", close(vec(od.twist.twist.linear), V_FLU, VEL_TOL),
            (vec(od.twist.twist.linear), V_FLU))
    # The body velocity rotated into ENU must be north 2 (+y) and up 0.5, not NED.
    v_world = qrot(quat(od.pose.pose.orientation), vec(od.twist.twist.linear))
    c.check("odom velocity in world is ENU (+y north, +z up)", close(v_world, V_ENU, 1e-5), v_world)
    c.check("odom angular FLU", close(vec(od.twist.twist.angular), (0.1, -0.2, -0.3), 0.51 * GYRO_LSB))
    si = got["state/imu"][-1]
    c.check("state/imu orientation", close(quat(si.orientation), Q_EXPECT, Q_TOL) and si.header.frame_id == "base_link")
    tf = got["/tf"][-1].transforms[0]
    c.check("tf odom→base_link", tf.header.frame_id == "odom" and tf.child_frame_id == "base_link"
            and close(vec(tf.transform.translation), P_ENU) and close(quat(tf.transform.rotation), Q_EXPECT, Q_TOL))
    c.check("tf_static sensor frames", bool(static_tf) and {t.child_frame_id for t in static_tf[-1].transforms}
            >= {"imu_link", "laser_link", "sonar_link", "gps_link"})
    edges = {(t.header.frame_id, t.child_frame_id) for t in static_tf[-1].transforms} if static_tf else set()
    mo = [t.transform for t in static_tf[-1].transforms if t.child_frame_id == "odom"] if static_tf else []
    c.check("tf_static map→odom, the identity (tree map → odom → base_link → sensors)",
            ("map", "odom") in edges and len(mo) == 1 and close(vec(mo[0].translation), (0.0, 0.0, 0.0))
            and close(quat(mo[0].rotation), (1.0, 0.0, 0.0, 0.0)), sorted(edges))

    al = got["altitude"][-1]
    c.check("altitude: up-positive vertical speed, alt, laser, source",
            abs(al.vertical_speed_mps - 0.5) < 1e-5 and abs(al.alt_m - 3.0) < 1e-5
            and abs(al.laser_range_m - 3.2) < 1e-5 and al.source == 1, al)
    c.check("altitude/ground Range", abs(got["altitude/ground"][-1].range - 3.2) < 1e-5)

    st = got["status"][-1]
    c.check("status armed + velocity mode after cmd/arm, cmd/mode", st.armed and st.mode_name == "velocity", (st.armed, st.mode_name))
    c.check("status time synced", st.time_synced, st.time_sync_offset_ns)
    c.check("status counters", st.rx_frames > 500 and st.crc_errors == 0, (st.rx_frames, st.crc_errors))
    c.check("status bridge refused 4 setpoints", st.setpoint_rejects_bridge == 4 and st.setpoints_forwarded == 2,
            (st.setpoint_rejects_bridge, st.setpoints_forwarded))

    c.check("status sensor health (fake MCU: all healthy)",
            st.gps_ok and not st.mag_disturbed and st.laser_ok and st.sonar_ok and st.mag_rejects == 0,
            (st.gps_ok, st.mag_disturbed, st.mag_rejects, st.laser_ok, st.sonar_ok))
    ao = got["accel/observer"][-1]
    c.check("accel/observer ENU in map (MCU north 0.5, east -0.25 → x -0.25, y 0.5, z 0)",
            ao.header.frame_id == "map" and close(vec(ao.accel.linear), (-0.25, 0.5, 0.0), 1e-6), vec(ao.accel.linear))
    am = got["accel/measured"][-1]
    c.check("accel/measured in map", am.header.frame_id == "map" and close(vec(am.accel.linear), (0.0, 0.0, 0.0), 1e-6),
            vec(am.accel.linear))
    diag = got["/diagnostics"][-1]
    link = [s for s in diag.status if s.name == "fcc_bridge: link"]
    kv = {k.key: k.value for k in link[0].values} if link else {}
    c.check("diagnostics link status", bool(link) and float(kv.get("rx_frames_per_s", 0)) > 100, kv.get("rx_frames_per_s"))
    sens = [s for s in diag.status if s.name == "fcc: sensors"]
    c.check("diagnostics fcc: sensors OK", bool(sens) and sens[0].level == 0 and sens[0].message == "ok",
            (sens[0].level, sens[0].message) if sens else None)
    c.check("diagnostics per-type rate", float(kv.get("rate_hz.ImuRaw", 0)) > 150, kv.get("rate_hz.ImuRaw"))

    c.check("node in ros_discovery_info", (ns, "fcc_bridge") in nodes, sorted(nodes))

    # What the MCU received.
    recs = [json.loads(line) for line in open(a.mcu_log) if line.strip()]
    sps = [r for r in recs if r["msg"] == "VelocitySetpoint"]
    cmds = [r["command"] for r in recs if r["msg"] == "Command"]
    c.check("MCU got Arm and Velocity commands", cmds[:2] == ["Arm", "Velocity"], cmds)
    c.check("MCU got exactly the 2 valid setpoints", len(sps) == 2, sps)
    if len(sps) >= 1:
        c.check("map ENU (1,2,0.5) → NED (2,1,-0.5), ttl 300 ms",
                close(sps[0]["vel_ned_mps"], (2.0, 1.0, -0.5), 1e-6) and sps[0]["ttl_ms"] == 300
                and sps[0]["yaw"] == "Keep", sps[0])
    if len(sps) >= 2:
        # Rotated with the attitude the link carried (a quaternion of i16 counts).
        c.check("base_link forward 1 → NED (cos30°, sin30°, 0)",
                close(sps[1]["vel_ned_mps"], (math.cos(math.radians(30)), 0.5, 0.0), Q_TOL), sps[1])
    print(f"{c.passed} passed, {c.failed} failed")
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
