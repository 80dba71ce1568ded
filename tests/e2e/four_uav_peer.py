#!/usr/bin/env python3
"""Independent Cyclone DDS peer for four vehicles on one DDS domain (issue 7, point 7).

While `fcc-launch launch_configs/four_uav_flight.yaml` flies four simulated vehicles, each in its
own namespace /uav1 … /uav4 (fcc-sitl --link-pty ⇄ fcc-bridge ⇄ fcc-mission per vehicle), the
peer subscribes to every vehicle's topics: a reader per known topic from the start, plus a reader
for any other topic it discovers under a vehicle's namespace (DDS built-in publication topic),
until --until-file appears. Then, with each simulator's CSV truth log (--csv-dir/uavN.csv), the
missions (--missions-dir/uavN.yaml) and the scenarios' GPS homes (--scenarios-dir/uavN.yaml):

  * every topic of every vehicle was received (the known list and all discovered ones);
  * DDS ownership: no participant (node) publishes or subscribes in two vehicle namespaces, and
    no vehicle node uses the global /tf, /tf_static, /clock or /diagnostics (the remaps work);
  * no message crosses namespaces — every message is checked against ITS vehicle:
      - state/odom and tf (odom → base_link) equal that vehicle's own estimate in its CSV at the
        same simulated time (none off by more than 1 m), and do NOT fit any other vehicle's log;
        the track stays on that vehicle's mission path (its own quadrant, size and altitude);
      - gps/fix lies nearest that vehicle's own GPS home (the homes stand 40 m apart);
      - clock never runs backwards (four unsynchronised simulated clocks would interleave);
      - setpoints are stamped inside that vehicle's own armed interval;
      - diagnostics name that vehicle's own device (uavN.tty);
      - frame ids are the standard ones (map, base_link, …): one TF tree per namespace;
  * each vehicle armed, landed and disarmed; its mission node reported "finished".

Prints a per-vehicle table of messages received and the peer's own CPU time.
Run only inside a loopback-only network namespace (../shared/tools/netns-run).
"""
import argparse
import csv
import json
import math
import os
import re
import resource
import sys
import time
import types
from dataclasses import dataclass, field

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "dds"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))

from cyclonedds.builtin import (BuiltinDataReader, BuiltinTopicDcpsPublication,  # noqa: E402
                                BuiltinTopicDcpsSubscription)
from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402

import ros_types as rt  # noqa: E402
from truth import interp, pct, stamp_of, t_of  # noqa: E402


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: rt.Time = field(default_factory=rt.Time)


RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(500))
BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(500))
LATCHED = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.TransientLocal,
              Policy.History.KeepLast(10))
# Latched topics (transient local in fcc_ros::topics) are read as a ROS node reads them: with a
# transient-local reader. Each is written once, maybe before the reader matches — always so for a
# topic this peer only learns of from discovery (`home`: its reader is made when the writer is
# seen); a volatile reader legitimately misses such a sample.
LATCHED_TOPICS = {"tf_static"}

# Topics of one vehicle (relative to its namespace): type, min rate in ROS (= simulated) time
# or None (only "received"), expected header frame_id or None.
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
    "tf": (rt.TFMessage, 40, None),
    "tf_static": (rt.TFMessage, None, None),
    "altitude": (rt.Altitude, 15, None),
    "altitude/ground": (rt.Range, 15, "base_link"),
    "status": (rt.Status, 4, None),
    "diagnostics": (rt.DiagnosticArray, None, None),
    "clock": (Clock, 40, None),
    # the mission node's
    "setpoint/velocity": (rt.TwistStamped, 20, "map"),
    "cmd/arm": (rt.Bool, None, None),
    "cmd/mode": (rt.String, None, None),
    "mission/status": (rt.String, None, None),
}
# Global topics the vehicles' nodes must NOT use (they are remapped into the namespace).
MUST_BE_NAMESPACED = {"rt/tf", "rt/tf_static", "rt/clock", "rt/diagnostics"}

# DDS type name → IDL class, for topics discovered at run time.
TYPES = {getattr(c, "__idl_typename__", None): c for c in vars(rt).values()
         if isinstance(c, type) and issubclass(c, IdlStruct)}
TYPES[Clock.__idl_typename__] = Clock

NS_RE = re.compile(r"^(rt|rq|rr)/uav(\d+)/")

# Topics of which only the header (stamp, frame) is checked: read as "header-only" types of the
# same DDS type name (Cyclone matches by name; the CDR reader stops after the header), about 3×
# cheaper to decode, which keeps the peer's share of a 2-core machine down.
LIGHT = {"imu/data_raw", "state/imu", "mag", "baro", "range/laser", "range/sonar", "battery",
         "altitude", "altitude/ground"}
_light_cache = {}


def header_only(cls):
    """A struct with only the leading `header` of `cls`, under the same DDS type name."""
    if list(getattr(cls, "__annotations__", {}))[:1] != ["header"]:
        return cls
    if cls not in _light_cache:
        def body(ns):
            ns["__annotations__"] = {"header": rt.Header}
            ns["header"] = field(default_factory=rt.Header)
        _light_cache[cls] = dataclass(types.new_class(
            cls.__name__ + "HeaderOnly", (IdlStruct,), {"typename": cls.__idl_typename__}, body))
    return _light_cache[cls]


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
    cols = ["t_s", "armed", "est_n_m", "est_e_m", "est_d_m"]
    return {c: [float(r[c]) for r in rows] for c in cols}


def simple_yaml_numbers(path):
    """The few numbers we need from a scenario/mission YAML (no PyYAML in the venv)."""
    text = open(path).read()
    out = {}
    for k in ("origin_lat_deg", "origin_lon_deg", "takeoff_alt_m"):
        m = re.search(rf"^\s*{k}:\s*([-\d.eE+]+)", text, re.M)
        if m:
            out[k] = float(m.group(1))
    out["waypoints"] = [(float(n), float(e), float(a)) for n, e, a in re.findall(
        r"north_m:\s*([-\d.]+),\s*east_m:\s*([-\d.]+),\s*alt_m:\s*([-\d.]+)", text)]
    return out


def dist_to_path(n, e, pts):
    """Horizontal distance from (n, e) to the polyline pts [(n, e), …]."""
    best = math.inf
    for (an, ae), (bn, be) in zip(pts, pts[1:]):
        dn, de = bn - an, be - ae
        L2 = dn * dn + de * de
        u = 0.0 if L2 == 0 else max(0.0, min(1.0, ((n - an) * dn + (e - ae) * de) / L2))
        best = min(best, math.hypot(n - an - u * dn, e - ae - u * de))
    return best


def geo_dist_m(lat, lon, lat0, lon0):
    return math.hypot((lat - lat0) * 110_990.0, (lon - lon0) * 111_320.0 * math.cos(math.radians(lat0)))


# ------------------------------------------------------------------------------------ observe

def observe(a):
    vehicles = list(range(1, a.vehicles + 1))
    dp = DomainParticipant(a.domain)
    me = str(dp.guid)
    readers = {}   # (vehicle, name) -> DataReader

    def add_reader(v, name, ty, latched=False):
        dds = f"rt/uav{v}/{name}"
        if name in LIGHT or name not in TOPICS:
            ty = header_only(ty)
        latched = latched or name in LATCHED_TOPICS
        qos = LATCHED if latched else (BEST_EFFORT if name == "setpoint/velocity" else RELIABLE)
        readers[(v, name)] = DataReader(dp, Topic(dp, dds, ty), qos=qos)

    for v in vehicles:
        for name, (ty, _, _) in TOPICS.items():
            add_reader(v, name, ty)
    pubs = BuiltinDataReader(dp, BuiltinTopicDcpsPublication)
    subs = BuiltinDataReader(dp, BuiltinTopicDcpsSubscription)
    endpoints = {}   # endpoint key -> (participant key, topic, type, "pub"/"sub")
    unknown_types = {}
    # Kept per message: only what the checks need (keeps the peer's CPU and memory small).
    count = {k: 0 for k in readers}
    stamps = {k: [] for k in readers}
    keep = {k: [] for k in readers}
    frames = {k: set() for k in readers}
    KEEP = {"state/odom", "tf", "tf_static", "gps/fix", "status", "diagnostics", "mission/status",
            "cmd/arm", "cmd/mode"}
    t0 = time.time()
    print(f"peer: observing {len(vehicles)} vehicles until {a.until_file} appears", flush=True)
    while not os.path.exists(a.until_file) and time.time() - t0 < a.timeout:
        for kind, br in (("pub", pubs), ("sub", subs)):
            for s in br.take(N=200):
                if type(s).__name__ == "InvalidSample" or not getattr(s, "topic_name", None):
                    continue  # disposed endpoints come without a name
                endpoints[str(s.key)] = (str(s.participant_key), s.topic_name, s.type_name, kind)
                m = NS_RE.match(s.topic_name)
                if kind == "pub" and m and m.group(1) == "rt" and str(s.participant_key) != me:
                    v, name = int(m.group(2)), s.topic_name[len(m.group(0)):]
                    if (v, name) not in readers and v in vehicles:
                        ty = TYPES.get(s.type_name)
                        if ty is None:
                            unknown_types[(v, name)] = s.type_name
                        else:
                            offered = s.qos[Policy.Durability] if Policy.Durability in s.qos else None
                            add_reader(v, name, ty, latched=offered == Policy.Durability.TransientLocal)
                            count[(v, name)] = 0
                            stamps[(v, name)], keep[(v, name)] = [], []
                            frames[(v, name)] = set()
        for k, r in list(readers.items()):
            for s in r.take(N=1000):
                if type(s).__name__ == "InvalidSample":
                    continue
                count[k] += 1
                h = getattr(s, "header", None)
                if h is not None:
                    stamps[k].append(h.stamp.sec + h.stamp.nanosec * 1e-9)
                    frames[k].add(h.frame_id)
                else:
                    st = stamp_of(s)
                    if st is not None:
                        stamps[k].append(st)
                if k[1] in KEEP:
                    keep[k].append(s)
        time.sleep(0.05)  # 20 polls/s: at most ~20 samples per reader each (history 500)

    # ---- the launcher has stopped everything; each simulator wrote its CSV
    c = Checks()
    names = sorted({n for (_, n) in readers}, key=lambda n: (n not in TOPICS, list(TOPICS).index(n) if n in TOPICS else 0, n))
    print("messages received per vehicle (namespaced topics; rate in ROS time = simulated time):")
    print(f"  {'topic':22s}" + "".join(f"{'/uav' + str(v):>16s}" for v in vehicles))
    for n in names:
        row = f"  {n:22s}"
        for v in vehicles:
            k = (v, n)
            st = stamps.get(k, [])
            span = (max(st) - min(st)) if len(st) > 1 else 0.0
            hz = (len(st) - 1) / span if span > 0 else 0.0
            row += f"{count.get(k, 0):8d} {hz:5.0f}Hz " if st else f"{count.get(k, 0):8d}        "
        print(row)
    totals = {v: sum(n for (vv, _), n in count.items() if vv == v) for v in vehicles}
    print("  total messages: " + ", ".join(f"/uav{v} {totals[v]}" for v in vehicles), flush=True)

    # Every topic of every vehicle: the known ones and every one discovered.
    for v in vehicles:
        # An action's topics carry messages only while a goal runs (none here: the missions
        # are files), `setpoint/heading` only with a mission heading (`yaw_deg`, none here):
        # discovered and typed, not required to carry data.
        on_demand = lambda n: "/_action/" in n or n == "setpoint/heading"  # noqa: E731
        missing = [n for n in names if count.get((v, n), 0) == 0 and not on_demand(n)]
        c.check(f"/uav{v}: every topic received ({sum(1 for n in names if (v, n) in readers)} topics)",
                not missing, f"none on {missing}" if missing else "")
        discovered = {t[len(f"rt/uav{v}/"):] for (pk, t, ty, kind) in endpoints.values()
                      if kind == "pub" and pk != me and t.startswith(f"rt/uav{v}/")}
        c.check(f"/uav{v}: every known topic is published (DDS discovery)",
                set(TOPICS) <= discovered, sorted(set(TOPICS) - discovered))
        for n in TOPICS:
            _, min_hz, frame = TOPICS[n]
            st = stamps[(v, n)]
            if min_hz is not None:
                span = (max(st) - min(st)) if len(st) > 1 else 0.0
                hz = (len(st) - 1) / span if span > 0 else 0.0
                if n == "setpoint/velocity":
                    c.check(f"/uav{v}: {n} > 500 msgs", count[(v, n)] > 500, count[(v, n)])
                else:
                    c.check(f"/uav{v}: rate {n} >= {min_hz} Hz", hz >= min_hz, f"{hz:.1f} Hz")
    c.check("every discovered vehicle topic has a known type", not unknown_types, unknown_types)

    # ---- DDS ownership: each node stays in one namespace; no vehicle node on the global names.
    parts = {}
    for pk, t, ty, kind in endpoints.values():
        if pk == me:
            continue
        parts.setdefault(pk, []).append((t, kind))
    crossing, global_use, global_sub, per_ns = [], [], set(), {v: set() for v in vehicles}
    for pk, eps in parts.items():
        nss = {int(m.group(2)) for t, _ in eps for m in [NS_RE.match(t)] if m}
        for v in nss:
            if v in per_ns:
                per_ns[v].add(pk)
        if len(nss) > 1:
            crossing.append((pk[:8], sorted(nss)))
        if nss:
            used = sorted({t for t, kind in eps if t in MUST_BE_NAMESPACED and kind == "pub"})
            if used:
                global_use.append((pk[:8], sorted(nss), used))
            global_sub |= {t for t, kind in eps if t in MUST_BE_NAMESPACED and kind == "sub"}
    c.check("no DDS participant publishes or subscribes in two vehicle namespaces", not crossing, crossing)
    c.check("no vehicle node publishes on the global /tf, /tf_static, /clock or /diagnostics",
            not global_use, global_use)
    # ros2-client's node spinner always reads the absolute /clock (for use_sim_time) and applies
    # no remaps to it; nothing publishes there (checked above), so it stays silent.
    print(f"INFO global names the vehicle nodes subscribe to: {sorted(global_sub)} "
          "(rt/clock: ros2-client's built-in sim-time reader, not remappable; no writer)", flush=True)
    for v in vehicles:
        c.check(f"/uav{v}: two nodes (bridge + mission node) in the namespace", len(per_ns[v]) >= 2,
                len(per_ns[v]))
        eps = [(t, kind) for pk, t, ty, kind in endpoints.values() if pk != me and NS_RE.match(t)
               and int(NS_RE.match(t).group(2)) == v]
        print(f"INFO /uav{v}: {sum(1 for t, k in eps if t.startswith('rt/') and k == 'pub')} topics published, "
              f"{sum(1 for t, k in eps if t.startswith('rt/') and k == 'sub')} subscribed, "
              f"{sum(1 for t, k in eps if not t.startswith('rt/'))} service request/reply endpoints "
              f"(parameters, arm, land, hold), all under /uav{v}", flush=True)

    # ---- per-message checks against each vehicle's own truth
    logs = {v: load_csv(os.path.join(a.csv_dir, f"uav{v}.csv")) for v in vehicles}
    missions = {v: simple_yaml_numbers(os.path.join(a.missions_dir, f"uav{v}.yaml")) for v in vehicles}
    homes = {v: simple_yaml_numbers(os.path.join(a.scenarios_dir, f"uav{v}.yaml")) for v in vehicles}
    paths = {v: [(0.0, 0.0)] + [(n, e) for n, e, _ in missions[v]["waypoints"]] for v in vehicles}

    def err_vs_log(log, t, x_e, y_n, z_u):
        en, ee, ed = (interp(log, k, t) for k in ("est_n_m", "est_e_m", "est_d_m"))
        if en is None:
            return None
        return math.dist((x_e, y_n, z_u), (ee, en, -ed))

    for v in vehicles:
        log = logs[v]
        od = keep[(v, "state/odom")]
        own, others, off_path, n_al = [], {w: [] for w in vehicles if w != v}, [], 0
        for m in od:
            t = t_of(m.header.stamp)
            p = m.pose.pose.position
            e = err_vs_log(log, t, p.x, p.y, p.z)
            if e is None:
                continue
            n_al += 1
            own.append(e)
            for w in others:
                ew = err_vs_log(logs[w], t, p.x, p.y, p.z)
                if ew is not None:
                    others[w].append(ew)
            off_path.append(dist_to_path(p.y, p.x, paths[v]))
        bad = sum(1 for e in own if e > 1.0)
        c.check(f"/uav{v}: state/odom = its own vehicle's estimate at the same sim time (none > 1 m off)",
                n_al > 1000 and bad == 0,
                f"{n_al} aligned, p50 {pct(own, 0.5):.3f} m p99 {pct(own, 0.99):.3f} m max {max(own, default=math.nan):.3f} m, {bad} > 1 m")
        # Against another vehicle's log the same test fails for most samples (all but the time
        # on the ground at home, where every local frame starts).
        fits = {w: sum(1 for e in ev if e > 1.0) / max(1, len(ev)) for w, ev in others.items()}
        c.check(f"/uav{v}: state/odom does not fit any other vehicle's log (> 50 % of samples > 1 m off)",
                all(f > 0.5 for f in fits.values()),
                ", ".join(f"uav{w} {100 * f:.0f} % (median {pct(others[w], 0.5):.1f} m)" for w, f in fits.items()))
        c.check(f"/uav{v}: track on its own mission path (horizontal, max < 2.5 m)",
                off_path and max(off_path) < 2.5, f"p99 {pct(off_path, 0.99):.2f} m max {max(off_path, default=math.nan):.2f} m")
        xs = [m.pose.pose.position.x for m in od]
        ys = [m.pose.pose.position.y for m in od]
        zs = [m.pose.pose.position.z for m in od]
        wps = missions[v]["waypoints"]
        n_ext = max(abs(n) for n, _, _ in wps) * (1 if max(n for n, _, _ in wps) > 0 else -1)
        e_ext = max(abs(e) for _, e, _ in wps) * (1 if max(e for _, e, _ in wps) > 0 else -1)
        far_y = max(ys, key=abs) if ys else math.nan
        far_x = max(xs, key=abs) if xs else math.nan
        c.check(f"/uav{v}: extent and quadrant of its square (north {n_ext:+.0f} m, east {e_ext:+.0f} m; ENU y, x)",
                abs(far_y - n_ext) < 1.5 and abs(far_x - e_ext) < 1.5, f"y {far_y:+.1f} m, x {far_x:+.1f} m")
        alt = missions[v]["takeoff_alt_m"]
        zf = [z for z in zs if z > 0.6 * alt]
        c.check(f"/uav{v}: cruise altitude {alt:.0f} m ± 0.5 (median while above 60 % of it)",
                zf and abs(pct(zf, 0.5) - alt) < 0.5, f"{pct(zf, 0.5):.2f} m" if zf else "never up")
        # frames: one standard TF tree per namespace
        c.check(f"/uav{v}: odom frames odom → base_link", bool(od) and {(m.header.frame_id, m.child_frame_id) for m in od} == {("odom", "base_link")},
                {(m.header.frame_id, m.child_frame_id) for m in od})
        for n in TOPICS:
            frame = TOPICS[n][2]
            if frame:
                c.check(f"/uav{v}: {n} frame_id {frame}", frames[(v, n)] == {frame}, frames[(v, n)])
        tf = [(t_of(x.header.stamp), x) for m in keep[(v, "tf")] for x in m.transforms
              if x.header.frame_id == "odom" and x.child_frame_id == "base_link"]
        tf_frames = {(x.header.frame_id, x.child_frame_id) for m in keep[(v, "tf")] for x in m.transforms}
        tf_err = [e for t, x in tf for e in [err_vs_log(log, t, x.transform.translation.x,
                                                       x.transform.translation.y, x.transform.translation.z)]
                  if e is not None]
        c.check(f"/uav{v}: tf odom → base_link = its own vehicle's estimate (none > 1 m off)",
                len(tf_err) > 1000 and max(tf_err) < 1.0 and tf_frames == {("odom", "base_link")},
                f"{len(tf_err)} aligned, max {max(tf_err, default=math.nan):.3f} m, frames {sorted(tf_frames)}")
        st_frames = {(x.header.frame_id, x.child_frame_id) for m in keep[(v, "tf_static")] for x in m.transforms}
        c.check(f"/uav{v}: tf_static (latched) map → odom and base_link → sensor frames",
                ("base_link", "imu_link") in st_frames and ("map", "odom") in st_frames,
                sorted(st_frames))
        # GPS: nearest its own home
        fixes = keep[(v, "gps/fix")]
        near = []
        for f_ in fixes:
            d = {w: geo_dist_m(f_.latitude, f_.longitude, homes[w]["origin_lat_deg"], homes[w]["origin_lon_deg"])
                 for w in vehicles}
            near.append(min(d, key=d.get))
        wrong = sum(1 for w in near if w != v)
        c.check(f"/uav{v}: every gps/fix nearest its own home (homes 40 m apart)",
                fixes and wrong == 0, f"{len(fixes)} fixes, {wrong} nearer another home")
        # clock: one vehicle's simulated time, never backwards
        cl = stamps[(v, "clock")]
        back = sum(1 for x, y in zip(cl, cl[1:]) if y < x)
        c.check(f"/uav{v}: clock never runs backwards (one simulator's time)", cl and back == 0,
                f"{len(cl)} msgs, {back} backwards, {min(cl, default=0):.1f}..{max(cl, default=0):.1f} s")
        # setpoints stamped with this vehicle's clock, within its armed interval (±1 s)
        armed_t = [t for t, ar in zip(log["t_s"], log["armed"]) if ar > 0.5]
        sp = stamps[(v, "setpoint/velocity")]
        if armed_t:
            lo, hi = armed_t[0] - 1.0, armed_t[-1] + 1.0
            out = sum(1 for t in sp if not lo <= t <= hi)
            c.check(f"/uav{v}: setpoints stamped inside its own armed interval", sp and out == 0,
                    f"{len(sp)} setpoints, {out} outside [{lo:.1f}, {hi:.1f}] s")
        else:
            c.check(f"/uav{v}: vehicle armed (CSV)", False)
        # diagnostics name its own device
        hw = {s.hardware_id for m in keep[(v, "diagnostics")] for s in m.status if s.hardware_id}
        c.check(f"/uav{v}: diagnostics hardware_id is its own device (uav{v}.tty)",
                hw and all(h.endswith(f"uav{v}.tty") for h in hw), sorted(hw))
        # status and the mission node's reports
        sts = keep[(v, "status")]
        c.check(f"/uav{v}: status armed in flight, then landed and disarmed",
                any(s.armed for s in sts) and sts and not sts[-1].armed and sts[-1].landed,
                (sts[-1].armed, sts[-1].landed, sts[-1].mode_name) if sts else None)
        ms = [json.loads(m.data) for m in keep[(v, "mission/status")]]
        c.check(f"/uav{v}: mission/status reports finished", any(m.get("phase") == "finished" for m in ms),
                sorted({m.get("phase") for m in ms}))
        c.check(f"/uav{v}: cmd/arm true and cmd/mode land from its mission node",
                any(m.data for m in keep[(v, "cmd/arm")]) and any(m.data == "land" for m in keep[(v, "cmd/mode")]))
    ru = resource.getrusage(resource.RUSAGE_SELF)
    print(f"peer cpu user {ru.ru_utime:.2f} s sys {ru.ru_stime:.2f} s", flush=True)
    return c.done()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--vehicles", type=int, default=4)
    ap.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0") or 0))
    ap.add_argument("--until-file", required=True)
    ap.add_argument("--timeout", type=float, default=400.0)
    ap.add_argument("--csv-dir", required=True)
    here = os.path.dirname(os.path.abspath(__file__))
    cfg = os.path.join(here, "..", "..", "launch_configs")
    ap.add_argument("--missions-dir", default=os.path.join(cfg, "missions"))
    ap.add_argument("--scenarios-dir", default=os.path.join(cfg, "scenarios"))
    sys.exit(observe(ap.parse_args()))


if __name__ == "__main__":
    main()
