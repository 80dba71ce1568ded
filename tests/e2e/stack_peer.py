#!/usr/bin/env python3
"""Independent Cyclone DDS peer against the full stack (acceptance, scope 6).

Mode `observe` (while fcc-launch flies the square: fcc-sitl --link-pty ⇄ fcc-bridge ⇄
fcc-mission): subscribes to every bridge topic plus the mission node's topics, until --until-file
appears; then checks rates (in ROS time: the bridge runs with clock_source:=mcu, so stamps are
simulated time and rates do not depend on --speed), frames and values against the simulator's
truth log (--csv, written when the launcher stops fcc-sitl): odometry vs the logged estimate and
truth at the same times, ENU not NED (flying north shows as +y).

Also (issue 4 with the bridge present) the values on `altitude` and `altitude/ground`: the fused
above-ground height equals the MCU's (CSV ground_m) and follows the truth (true_agl_m) while
airborne; source, variance, barometric/vertical altitude and the raw laser/sonar ranges (laser
sentinel 99999 → +inf) match the log at the same simulated times.

Mode `fly` (fcc-sitl --link-pty ⇄ fcc-bridge, no mission node): the peer itself arms through
cmd/arm, publishes TwistStamped setpoints with RELIABLE QoS (as `ros2 topic pub` does), climbs,
flies north, switches to hold and then land through cmd/mode, waits for the disarm; the truth
check runs later (`check-fly`) on the CSV.

Run only inside a loopback-only network namespace (../shared/tools/netns-run).
"""
import argparse
import bisect
import csv
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "dds"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402

import ros_types as rt  # noqa: E402
from truth import interp, nearest, pct, qrot, stamp_of, t_of  # noqa: E402
from truth import load_csv as load_csv_all  # noqa: E402


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: rt.Time = field(default_factory=rt.Time)


RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(200))
BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(200))
LATCHED = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.TransientLocal,
              Policy.History.KeepLast(10))
# ros_discovery_info is keyless: one instance for every participant's writer, so a depth of 1
# kept only the newest of the bridge's and the mission node's announcements when both arrived
# between two polls (their transient-local replays come at the same match, t ≈ 1.6 s): CI saw
# only fcc_mission once. The depth keeps every participant's sample until it is taken.
DISCOVERY_QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                    Policy.Durability.TransientLocal, Policy.History.KeepLast(64))

# name: (type, min rate in ROS-time Hz, expected frame_id or None)
TOPICS = {
    "imu/data_raw": (rt.Imu, 150, "imu_link"),
    "mag": (rt.MagneticField, 15, None),
    "baro": (rt.FluidPressure, 15, None),
    "gps/fix": (rt.NavSatFix, 4, "gps_link"),
    "range/laser": (rt.Range, 7, "laser_link"),
    "range/sonar": (rt.Range, 7, "sonar_link"),
    "battery": (rt.BatteryState, 3, None),
    "state/odom": (rt.Odometry, 40, "odom"),
    "state/imu": (rt.Imu, 40, "base_link"),
    "/tf": (rt.TFMessage, 40, None),
    "/tf_static": (rt.TFMessage, None, None),
    "altitude": (rt.Altitude, 15, None),
    "altitude/ground": (rt.Range, 15, "base_link"),
    "status": (rt.Status, 4, None),
    "/diagnostics": (rt.DiagnosticArray, None, None),
    "/clock": (Clock, 40, None),
    # the mission node's
    "setpoint/velocity": (rt.TwistStamped, 20, "map"),
    "mission/status": (rt.String, None, None),
}


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, name, ok, detail=""):
        self.passed += bool(ok)
        self.failed += not ok
        print(f"{'PASS' if ok else 'FAIL'} {name}{(': ' + str(detail)) if detail else ''}", flush=True)

    def done(self):
        print(f"{self.passed} passed, {self.failed} failed", flush=True)
        return 0 if self.failed == 0 else 1


def load_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    cols = ["t_s", "armed", "true_n_m", "true_e_m", "true_d_m", "est_n_m", "est_e_m", "est_d_m",
            "true_vn_mps", "true_ve_mps", "true_vd_mps"]
    return {c: [float(r[c]) for r in rows] for c in cols}, [r["mode"] for r in rows]


# fcc_nav GroundSource (CSV, Debug names) → fcc_msgs/Altitude SOURCE_* codes.
SOURCE_CODE = {"None": 0, "Laser": 1, "Sonar": 2, "Both": 3, "Predicted": 4}


def check_altitude(c, alt, ground, path):
    """Issue 4 with the bridge present: `altitude` and `altitude/ground` carry the MCU's fused
    ground height (CSV ground_m), its source and variance and the raw ranges, and that height
    follows the truth (CSV true_agl_m) while airborne."""
    log = load_csv_all(path)
    n_ok = 0
    d_mcu, d_true, d_alt, d_baro, d_var = [], [], [], [], []
    src_same = src_n = 0
    laser = {"inf_ok": 0, "inf_bad": 0, "val": [], "nan": 0, "n": 0}
    sonar = {"val": [], "n": 0}
    by_stamp = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in alt}
    pair_diff, paired = [], 0
    for g in ground:
        a = by_stamp.get((g.header.stamp.sec, g.header.stamp.nanosec))
        if a is not None:
            paired += 1
            pair_diff.append(abs(g.range - a.ground_height_m))
    c.check("altitude/ground.range = altitude.ground_height_m (same stamp)",
            paired > 1000 and max(pair_diff) < 1e-6, f"{paired} pairs, max diff {max(pair_diff, default=float('nan')):.2g} m")
    for g in ground:
        t = t_of(g.header.stamp)
        gm, agl = interp(log, "ground_m", t), interp(log, "true_agl_m", t)
        i = nearest(log, t)
        if gm is None or i is None:
            continue
        n_ok += 1
        d_mcu.append(abs(g.range - gm))
        # Airborne, both rangefinders in their range (laser ≥ 0.5 m, sonar ≤ 10.68 m), not
        # in the first/last second of the flight.
        if log["armed"][i] == 1.0 and log["mode"][i] not in ("Disarmed",) and 0.8 < agl < 10.0:
            d_true.append(abs(g.range - agl))
    for a in alt:
        t = t_of(a.header.stamp)
        i = nearest(log, t)
        if i is None:
            continue
        src_n += 1
        src_same += a.source == SOURCE_CODE.get(log["ground_source"][i], -1)
        est_up = interp(log, "est_d_m", t)
        d_alt.append(abs(a.alt_m + est_up))
        d_var.append(abs(a.ground_variance_m2 - interp(log, "ground_var_m2", t)))
        # The raw ranges are held between their 9–10 Hz readings: a message between two log rows
        # carries one of the two rows' values (take the closer; rows are the bracketing pair).
        j = bisect.bisect_right(log["t_s"], t) - 1
        j = min(max(j, 0), len(log["t_s"]) - 2)
        # The barometric altitude is noisy from sample to sample (prop wash): it must equal one
        # of the log rows within ±1 row (±20 ms) of the frame.
        d_baro.append(min(abs(a.baro_alt_m - log["baro_alt_m"][k])
                          for k in range(max(0, j - 1), min(len(log["t_s"]), j + 3))))
        cl = min((log["laser_m"][j], log["laser_m"][j + 1]),
                 key=lambda v: abs(v - a.laser_range_m) if math.isfinite(v) and math.isfinite(a.laser_range_m) else 0.0)
        laser["n"] += 1
        if math.isnan(cl):
            laser["nan"] += math.isnan(a.laser_range_m)
        elif cl >= 99999.0:
            laser["inf_ok" if math.isinf(a.laser_range_m) and a.laser_range_m > 0 else "inf_bad"] += 1
        elif math.isfinite(a.laser_range_m):
            laser["val"].append(abs(a.laser_range_m - cl))
        sonar["n"] += 1
        cs = [v for v in (log["sonar_m"][j], log["sonar_m"][j + 1]) if math.isfinite(v)]
        if cs and math.isfinite(a.sonar_range_m):
            sonar["val"].append(min(abs(a.sonar_range_m - v) for v in cs))

    c.check("altitude/ground aligned with the simulator log", n_ok > 1000 and len(d_true) > 500,
            f"{n_ok} msgs, {len(d_true)} airborne in range")
    # Same value as the MCU computed; the CSV rows are 50 Hz samples at other instants than the
    # frames (interpolated), and written with 1 mm resolution.
    c.check("altitude/ground = the MCU's fused height (CSV ground_m) at the same sim time, p95 < 0.03 m, p99 < 0.1 m",
            pct(d_mcu, 0.95) < 0.03 and pct(d_mcu, 0.99) < 0.1,
            f"p50 {pct(d_mcu, 0.5) * 100:.2f} cm p95 {pct(d_mcu, 0.95) * 100:.2f} cm p99 {pct(d_mcu, 0.99) * 100:.2f} cm")
    c.check("altitude/ground vs truth (CSV true_agl_m) while airborne, p95 < 0.15 m",
            pct(d_true, 0.95) < 0.15,
            f"p50 {pct(d_true, 0.5) * 100:.1f} cm p95 {pct(d_true, 0.95) * 100:.1f} cm max {max(d_true, default=float('nan')) * 100:.1f} cm")
    c.check("altitude.source = the MCU's ground source (CSV ground_source) ≥ 95 % of messages",
            src_n > 0 and src_same / src_n >= 0.95, f"{src_same}/{src_n} = {100 * src_same / max(1, src_n):.1f} %")
    c.check("altitude.alt_m = the MCU's vertical estimate (−est_d_m), p95 < 0.05 m",
            pct(d_alt, 0.95) < 0.05, f"p50 {pct(d_alt, 0.5) * 100:.2f} cm p95 {pct(d_alt, 0.95) * 100:.2f} cm")
    c.check("altitude.baro_alt_m = the MCU's barometric altitude (CSV baro_alt_m, rows within ±20 ms), p99 < 1 cm",
            len(d_baro) > 1000 and pct(d_baro, 0.99) < 0.01,
            f"p50 {pct(d_baro, 0.5) * 100:.3f} cm p99 {pct(d_baro, 0.99) * 100:.3f} cm")
    c.check("altitude.ground_variance_m2 = CSV ground_var_m2, p95 < 1e-3 m²",
            pct(d_var, 0.95) < 1e-3, f"p95 {pct(d_var, 0.95):.2g} m²")
    lv = laser["val"]
    n_inf = laser["inf_ok"] + laser["inf_bad"]
    c.check("altitude.laser_range_m = the laser reading (CSV laser_m) p99 < 1 cm; sentinel 99999 → +inf",
            len(lv) > 100 and pct(lv, 0.99) < 0.01 and laser["inf_ok"] >= 0.95 * n_inf,
            f"{len(lv)} finite p50 {pct(lv, 0.5) * 100:.2f} cm p99 {pct(lv, 0.99) * 100:.2f} cm; "
            f"99999 rows {n_inf} → +inf {laser['inf_ok']}")
    sv = sonar["val"]
    c.check("altitude.sonar_range_m = the sonar reading (CSV sonar_m) p99 < 1 cm",
            len(sv) > 100 and pct(sv, 0.99) < 0.01, f"{len(sv)} p50 {pct(sv, 0.5) * 100:.2f} cm p99 {pct(sv, 0.99) * 100:.2f} cm")


def dds_name(ns, n):
    return "rt" + (n if n.startswith("/") else f"{ns}/{n}")


# ------------------------------------------------------------------------------------ observe

def observe(a):
    ns = a.ns.rstrip("/")
    dp = DomainParticipant(a.domain)
    qos = {"setpoint/velocity": BEST_EFFORT, "/tf_static": LATCHED}
    readers = {n: DataReader(dp, Topic(dp, dds_name(ns, n), ty), qos=qos.get(n, RELIABLE))
               for n, (ty, _, _) in TOPICS.items()}
    disc = DataReader(dp, Topic(dp, "ros_discovery_info", rt.ParticipantEntitiesInfo), qos=DISCOVERY_QOS)
    got = {n: [] for n in TOPICS}
    wall = {n: [] for n in TOPICS}
    nodes = set()
    t0 = time.time()
    print(f"peer: observing until {a.until_file} appears", flush=True)
    while not os.path.exists(a.until_file) and time.time() - t0 < a.timeout:
        now = time.time()
        for n, r in readers.items():
            for s in r.take(N=1000):
                if type(s).__name__ == "InvalidSample":  # writer gone (dispose/unregister)
                    continue
                got[n].append(s)
                wall[n].append(now)
        for s in disc.take(N=50):
            if type(s).__name__ == "InvalidSample":
                continue
            seen = sorted((ne.node_namespace, ne.node_name) for ne in s.node_entities_info_seq)
            if not set(seen) <= nodes:  # each node's first announcement, with its time
                print(f"peer: t={now - t0:.2f} s ros_discovery_info {bytes(s.gid.data[:12]).hex()}: {seen}",
                      flush=True)
            nodes.update(seen)
        time.sleep(0.005)
    # The launcher has stopped everything and fcc-sitl has written its CSV.
    c = Checks()
    log, modes = load_csv(a.csv)

    print("topic counts / rates seen by the peer (ROS time = simulated time, clock_source:=mcu):")
    for n, (_, min_hz, frame) in TOPICS.items():
        st = [x for x in (stamp_of(m) for m in got[n]) if x is not None]
        span = (max(st) - min(st)) if len(st) > 1 else 0.0
        hz = (len(st) - 1) / span if span > 0 else 0.0
        wall_span = (wall[n][-1] - wall[n][0]) if len(wall[n]) > 1 else 0.0
        whz = (len(wall[n]) - 1) / wall_span if wall_span > 0 else 0.0
        print(f"  {n:20s} {len(got[n]):6d} msgs  {hz:7.1f} Hz (ROS time)  {whz:7.1f} Hz (wall)")
        if n == "setpoint/velocity":
            # Setpoints flow only while flying: rate over the armed part.
            sp = sorted(st)
            gaps = [b - x for x, b in zip(sp, sp[1:])]
            big = [g for g in gaps if g > 0.2]
            c.check("setpoint/velocity ≥ 20 Hz while flying (wall clock of the node)",
                    whz * 1.0 >= 20 and len(got[n]) > 500, f"{whz:.1f} Hz wall, {len(got[n])} msgs, gaps>0.2 s: {len(big)}")
        elif min_hz is not None:
            c.check(f"rate {n} >= {min_hz} Hz", hz >= min_hz, f"{hz:.1f} Hz")
        else:
            c.check(f"{n} received", len(got[n]) > 0, len(got[n]))
        if frame and got[n]:
            frames = {m.header.frame_id for m in got[n]}
            c.check(f"{n} frame_id {frame}", frames == {frame}, frames)

    od = got["state/odom"]
    c.check("odom child frame base_link", bool(od) and {m.child_frame_id for m in od} == {"base_link"})
    # REP-105 tree: map → odom (static identity) → base_link (/tf) → sensors (static).
    tf_edges = {(x.header.frame_id, x.child_frame_id) for m in got["/tf"] for x in m.transforms}
    st_edges = {(x.header.frame_id, x.child_frame_id) for m in got["/tf_static"] for x in m.transforms}
    c.check("TF tree map → odom → base_link (/tf odom→base_link, /tf_static map→odom and base_link→sensors)",
            tf_edges == {("odom", "base_link")} and ("map", "odom") in st_edges
            and ("base_link", "imu_link") in st_edges, f"/tf {sorted(tf_edges)}, /tf_static {sorted(st_edges)}")
    # One clock on every stamp: /tf_static too carries the MCU's time (clock_source:=mcu), inside
    # the span of /clock, not the Linux clock.
    clk = [t_of(m.clock) for m in got["/clock"]]
    st_t = [t_of(x.header.stamp) for m in got["/tf_static"] for x in m.transforms]
    c.check("/tf_static stamped with the MCU clock (within the /clock span)",
            bool(clk) and bool(st_t) and all(min(clk) - 1.0 <= t <= max(clk) for t in st_t),
            f"stamps {sorted(set(st_t))[:3]} s, /clock {min(clk, default=math.nan):.3f}..{max(clk, default=math.nan):.3f} s")
    # Odometry vs the simulator's log at the same (simulated) times.
    est_err, true_h, true_v, n = [], [], [], 0
    # The estimate's origin is the GPS home on the ground; the truth is the body's centre, 0.25 m
    # above the ground on its landing gear: remove the offset at arming.
    i0 = log["armed"].index(1.0)
    dz0 = log["true_d_m"][i0] - log["est_d_m"][i0]
    for m in od:
        t = t_of(m.header.stamp)
        en, ee, ed = (interp(log, k, t) for k in ("est_n_m", "est_e_m", "est_d_m"))
        tn, te, td = (interp(log, k, t) for k in ("true_n_m", "true_e_m", "true_d_m"))
        if en is None or tn is None:
            continue
        p = m.pose.pose.position
        # ENU: x = east, y = north, z = up.
        est_err.append(math.dist((p.x, p.y, p.z), (ee, en, -ed)))
        true_h.append(math.hypot(p.x - te, p.y - tn))
        true_v.append(abs(p.z + (td - dz0)))
        n += 1

    c.check("odom aligned with the simulator log", n > 1000, n)
    c.check("odom = the MCU's estimate at the same sim time (ENU of NED log), p99 < 0.15 m",
            pct(est_err, 0.99) < 0.15, f"p50 {pct(est_err, 0.5):.3f} m p99 {pct(est_err, 0.99):.3f} m")
    c.check("odom vs truth horizontal p95 < 2.5 m (GPS-grade navigation)", pct(true_h, 0.95) < 2.5,
            f"p50 {pct(true_h, 0.5):.2f} m p95 {pct(true_h, 0.95):.2f} m")
    c.check("odom vs truth vertical p95 < 1.2 m (barometric, prop wash)", pct(true_v, 0.95) < 1.2,
            f"p50 {pct(true_v, 0.5):.2f} m p95 {pct(true_v, 0.95):.2f} m")
    # ENU, not NED: leg 0 flies north → +y grows, x stays.
    ys = [m.pose.pose.position.y for m in od]
    xs = [m.pose.pose.position.x for m in od]
    zs = [m.pose.pose.position.z for m in od]
    c.check("ENU: flying north shows as +y (max y ≈ 20 m)", 17 < max(ys) < 23, f"max y {max(ys):.1f}")
    c.check("ENU: east leg shows as +x (max x ≈ 20 m)", 17 < max(xs) < 23, f"max x {max(xs):.1f}")
    c.check("ENU: altitude is +z (max z ≈ 5 m)", 4 < max(zs) < 7.0 and min(zs) > -1.5, f"z {min(zs):.2f}..{max(zs):.2f}")
    # The body twist rotated into the world frame matches the truth's velocity (ENU).
    vel_err = []
    for m in od[::10]:
        t = t_of(m.header.stamp)
        vn, ve, vd = (interp(log, k, t) for k in ("true_vn_mps", "true_ve_mps", "true_vd_mps"))
        if vn is None:
            continue
        q = m.pose.pose.orientation
        v = m.twist.twist.linear
        w = qrot((q.w, q.x, q.y, q.z), (v.x, v.y, v.z))
        vel_err.append(math.dist(w, (ve, vn, -vd)))
    c.check("odom twist (FLU body) rotated to ENU ≈ true velocity, p95 < 0.5 m/s", pct(vel_err, 0.95) < 0.5,
            f"p50 {pct(vel_err, 0.5):.2f} p95 {pct(vel_err, 0.95):.2f} m/s")
    # Setpoints from the mission node: ENU (north leg → +y).
    sps = got["setpoint/velocity"]
    c.check("mission setpoints include north +y ≈ 3 m/s", any(abs(s.twist.linear.y - 3.0) < 0.05 for s in sps))
    c.check("mission setpoints include climb +z", any(s.twist.linear.z > 0.5 for s in sps))
    # IMU at rest before arming: specific force +g up in FLU.
    imu0 = got["imu/data_raw"][:50]
    az = sum(m.linear_acceleration.z for m in imu0) / max(1, len(imu0))
    c.check("imu at rest: +g on FLU z", 9.0 < az < 10.6, f"{az:.2f}")
    fix = got["gps/fix"]
    c.check("gps fix plausible", bool(fix) and all(-90 <= f.latitude <= 90 for f in fix))
    sts = got["status"]
    c.check("status: armed during the flight, disarmed and landed at the end",
            any(s.armed for s in sts) and not sts[-1].armed and sts[-1].landed,
            (sts[-1].armed, sts[-1].landed, sts[-1].mode_name) if sts else None)
    c.check("status: no CRC errors on the pty link", bool(sts) and sts[-1].crc_errors == 0, sts[-1].crc_errors if sts else None)
    ms = [json.loads(m.data) for m in got["mission/status"]]
    phases = [m.get("phase") for m in ms]
    c.check("mission/status JSON reports phases leg → finished",
            "leg" in phases and "finished" in phases and any(m.get("dist_to_go_m") for m in ms), sorted(set(phases)))
    c.check("bridge node in ros_discovery_info (what `ros2 node list` reads)",
            (ns, "fcc_bridge") in nodes, sorted(nodes))
    # The mission node announces itself once, at start-up; ros2-client's ros_discovery_info
    # writer does not reliably replay that to a reader that matches later, so a late match
    # can miss it (seen intermittently). Reported, not asserted: an open point, not a pass.
    print(f"INFO fcc_mission in ros_discovery_info: {(ns, 'fcc_mission') in nodes} ({sorted(nodes)})", flush=True)
    c.check("log: the vehicle landed and disarmed", modes[-1] == "Disarmed", modes[-1])
    if a.dump:
        dump_altitude(a.dump, got["altitude"], got["altitude/ground"])
    check_altitude(c, got["altitude"], got["altitude/ground"], a.csv)
    return c.done()


def dump_altitude(path, alt, ground):
    """The received altitude messages as JSON (for check-altitude on the same data)."""
    st = lambda m: [m.header.stamp.sec, m.header.stamp.nanosec]  # noqa: E731
    with open(path, "w") as f:
        json.dump({"altitude": [[*st(m), m.baro_alt_m, m.alt_m, m.vertical_speed_mps, m.ground_height_m,
                                 m.ground_variance_m2, repr(m.laser_range_m), repr(m.sonar_range_m), m.source] for m in alt],
                   "ground": [[*st(m), m.header.frame_id, m.range, m.variance] for m in ground]}, f)


def check_altitude_offline(a):
    """Re-run the altitude checks on a dump (observe --dump) and its CSV."""
    d = json.load(open(a.dump))
    alt = [rt.Altitude(rt.Header(rt.Time(sec=x[0], nanosec=x[1]), "map"), x[2], x[3], x[4], x[5], x[6],
                       float(x[7]), float(x[8]), x[9]) for x in d["altitude"]]
    ground = [rt.Range(rt.Header(rt.Time(sec=x[0], nanosec=x[1]), x[2]), 0, 0.0, 0.0, 0.0, x[3], x[4])
              for x in d["ground"]]
    c = Checks()
    check_altitude(c, alt, ground, a.csv)
    return c.done()


# ------------------------------------------------------------------------------------ fly

# (duration s of ROS/sim time, ENU velocity) flown by the peer.
PLAN = [(5.0, (0.0, 0.0, 1.0)), (8.0, (0.0, 2.0, 0.0)), (3.0, (0.0, 0.0, 0.0))]


def fly(a):
    ns = a.ns.rstrip("/")
    dp = DomainParticipant(a.domain)
    status = DataReader(dp, Topic(dp, dds_name(ns, "status"), rt.Status), qos=RELIABLE)
    clock = DataReader(dp, Topic(dp, "rt/clock", Clock), qos=BEST_EFFORT)
    sp = DataWriter(dp, Topic(dp, dds_name(ns, "setpoint/velocity"), rt.TwistStamped), qos=RELIABLE)
    arm = DataWriter(dp, Topic(dp, dds_name(ns, "cmd/arm"), rt.Bool), qos=RELIABLE)
    mode = DataWriter(dp, Topic(dp, dds_name(ns, "cmd/mode"), rt.String), qos=RELIABLE)
    st = None
    now = None
    events = []
    t0 = time.time()

    def pump():
        nonlocal st, now
        for s in status.take(N=100):
            if type(s).__name__ != "InvalidSample":
                st = s
        for cl in clock.take(N=100):
            if type(cl).__name__ != "InvalidSample":
                now = cl.clock

    def wait(cond, secs, what):
        t = time.time()
        while time.time() - t < secs:
            pump()
            if cond():
                return True
            time.sleep(0.01)
        print(f"peer: timeout waiting for {what} (status {st.mode_name if st else None}, last reject "
              f"{st.last_reject if st else None})", flush=True)
        return False

    if not wait(lambda: st is not None and now is not None, 30, "status and /clock"):
        return 1
    # Arm (retry: the MCU refuses until calibrated and the GPS home is set).
    last = 0
    t = time.time()
    while not (st and st.armed) and time.time() - t < 60:
        if time.time() - last > 0.5:
            arm.write(rt.Bool(data=True))
            last = time.time()
        pump()
        time.sleep(0.01)
    if not st.armed:
        print("peer: could not arm", flush=True)
        return 1
    events.append(("armed", t_of(now)))
    print(f"peer: armed at sim t={t_of(now):.2f} s (mode {st.mode_name})", flush=True)
    mode.write(rt.String(data="velocity"))
    for dur, v in PLAN:
        start = t_of(now)
        events.append((f"velocity {v}", start))
        print(f"peer: sim t={start:.2f} s: setpoint ENU {v} for {dur} s", flush=True)
        while t_of(now) - start < dur:
            # Stamped with ROS time (/clock, the bridge runs clock_source:=mcu), frame map (ENU).
            sp.write(rt.TwistStamped(rt.Header(rt.Time(sec=now.sec, nanosec=now.nanosec), "map"),
                                     rt.Twist(rt.Vector3(*v))))
            time.sleep(0.02)
            pump()
    mode.write(rt.String(data="hold"))
    events.append(("hold", t_of(now)))
    wait(lambda: st.mode_name == "hold", 5, "hold mode")
    print(f"peer: sim t={t_of(now):.2f} s: mode {st.mode_name}", flush=True)
    start = t_of(now)
    wait(lambda: t_of(now) - start > 3.0, 10, "3 s of hold")
    mode.write(rt.String(data="land"))
    events.append(("land", t_of(now)))
    ok_land = wait(lambda: st.mode_name == "land", 5, "land mode")
    print(f"peer: sim t={t_of(now):.2f} s: mode {st.mode_name}", flush=True)
    ok = wait(lambda: not st.armed and st.landed, 60, "landed and disarmed")
    events.append(("disarmed", t_of(now)))
    print(f"peer: sim t={t_of(now):.2f} s: armed {st.armed} landed {st.landed}", flush=True)
    with open(a.events, "w") as f:
        json.dump(events, f)
    print(f"peer: flight done in {time.time() - t0:.1f} s wall", flush=True)
    return 0 if (ok and ok_land) else 1


def check_fly(a):
    c = Checks()
    log, modes = load_csv(a.csv)
    ev = dict((k.split(" ")[0] if k.startswith("velocity") else k, None) for k, _ in [])
    events = json.load(open(a.events))
    vel = [(k, t) for k, t in events if k.startswith("velocity")]
    named = {k: t for k, t in events if not k.startswith("velocity")}
    t_climb, t_north, t_stop = vel[0][1], vel[1][1], vel[2][1]

    def at(col, t):
        return interp(log, col, t)
    dz = -(at("true_d_m", t_north) - at("true_d_m", t_climb))
    c.check("climb 1 m/s for 5 s: truth rises 3.5–5.5 m", 3.5 < dz < 5.5, f"{dz:.2f} m")
    dn = at("true_n_m", t_stop) - at("true_n_m", t_north)
    de = at("true_e_m", t_stop) - at("true_e_m", t_north)
    c.check("ENU (0, 2, 0) for 8 s = north: truth moves 6–17 m north", 6 < dn < 17, f"{dn:.2f} m")
    c.check("… and stays within 1.5 m east/west", abs(de) < 1.5, f"{de:.2f} m")
    # Truth velocity in the middle of the north segment ≈ 2 m/s north.
    vn = [log["true_vn_mps"][i] for i, t in enumerate(log["t_s"]) if t_stop - 2 < t < t_stop]
    c.check("true north speed in the last 2 s of the segment 1.0–2.5 m/s", vn and 1.0 < sum(vn) / len(vn) < 2.5,
            f"{sum(vn) / max(1, len(vn)):.2f} m/s")
    hold_modes = {modes[i] for i, t in enumerate(log["t_s"]) if named["hold"] + 0.5 < t < named["land"]}
    c.check("cmd/mode hold → MCU Hold", hold_modes == {"Hold"}, hold_modes)
    land_modes = {modes[i] for i, t in enumerate(log["t_s"]) if named["land"] + 0.5 < t < named["disarmed"] - 1}
    c.check("cmd/mode land → MCU Land", "Land" in land_modes, land_modes)
    c.check("landed and disarmed at the end", modes[-1] == "Disarmed" and log["true_d_m"][-1] > -0.5,
            (modes[-1], log["true_d_m"][-1]))
    c.check("armed by cmd/arm", any(log["armed"]), "")
    return c.done()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["observe", "fly", "check-fly", "check-altitude"])
    ap.add_argument("--ns", default="/fcc")
    ap.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    ap.add_argument("--csv")
    ap.add_argument("--until-file")
    ap.add_argument("--events")
    ap.add_argument("--dump", help="observe: also write the altitude messages here (JSON)")
    ap.add_argument("--timeout", type=float, default=300)
    a = ap.parse_args()
    return {"observe": observe, "fly": fly, "check-fly": check_fly,
            "check-altitude": check_altitude_offline}[a.mode](a)


if __name__ == "__main__":
    sys.exit(main())
