#!/usr/bin/env python3
"""Independent Cyclone DDS peer for the bridge's ROS 2 interfaces (issue 7): parameters over the
rcl_interfaces services (list/get/set, a refused out-of-range set, a gain reaching the fake MCU,
a start-up value from --params-file), the std_srvs services arm/land/hold answered after the MCU's
acknowledgement (then flying via the setpoint topic), /rosout WARN on a bad setpoint, use_sim_time
stamps following /clock, a topic remap under a namespace, and /tf_static for a late joiner.

Expects the bridge started as run_ros_e2e.sh does (namespace /uav1, battery remapped to
power/battery, use_sim_time:=true, params file with limits.max_horiz_speed_mps: 6.0).
Run only inside a loopback-only network namespace (../shared/tools/netns-run).
usage: peer_ros.py --mcu-log FILE [--ns /uav1] [--node fcc_bridge]
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
import ros_srv_types as st

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))
import mcu_params  # noqa: E402

RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(50))
TF_STATIC_QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                    Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
SIM_T0 = 1000  # s: the /clock this peer publishes starts here

# ParameterType
P_BOOL, P_INT, P_DOUBLE, P_STRING = 1, 2, 3, 4


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, name, ok, detail=""):
        self.passed += bool(ok)
        self.failed += not ok
        print(f"{'PASS' if ok else 'FAIL'} {name}{(': ' + str(detail)) if detail else ''}")
        sys.stdout.flush()


class Service:
    """A ROS 2 service client over plain DDS: request topic rq/<name>Request, reply topic
    rr/<name>Reply (the bridge uses the 'enhanced' RPC-over-DDS mapping, no payload header)."""

    def __init__(self, dp, name, req_t, resp_t):
        self.w = DataWriter(dp, Topic(dp, f"rq{name}Request", req_t), qos=RELIABLE)
        self.r = DataReader(dp, Topic(dp, f"rr{name}Reply", resp_t), qos=RELIABLE)
        self.name = name

    def call(self, req, timeout=3.0, tries=3):
        for _ in range(tries):
            self.r.take(N=100)
            self.w.write(req)
            t0 = time.time()
            while time.time() - t0 < timeout:
                got = self.r.take(N=1)
                if got:
                    return got[0]
                time.sleep(0.01)
        return None


def pv_double(x):
    return st.ParameterValue(type=P_DOUBLE, double_value=x)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcu-log", required=True)
    ap.add_argument("--ns", default="/uav1")
    ap.add_argument("--node", default="fcc_bridge")
    ap.add_argument("--domain", type=int, default=0)
    a = ap.parse_args()
    ns = a.ns.rstrip("/")
    fq = f"{ns}/{a.node}"
    c = Checks()

    dp = DomainParticipant(a.domain)
    status = DataReader(dp, Topic(dp, f"rt{ns}/status", rt.Status), qos=RELIABLE)
    imu = DataReader(dp, Topic(dp, f"rt{ns}/imu/data_raw", rt.Imu), qos=RELIABLE)
    battery = DataReader(dp, Topic(dp, f"rt{ns}/power/battery", rt.BatteryState), qos=RELIABLE)
    rosout = DataReader(dp, Topic(dp, "rt/rosout", st.Log),
                        qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(1000)))
    clock_w = DataWriter(dp, Topic(dp, "rt/clock", st.Clock), qos=RELIABLE)
    sp_w = DataWriter(dp, Topic(dp, f"rt{ns}/setpoint/velocity", rt.TwistStamped), qos=RELIABLE)
    mode_w = DataWriter(dp, Topic(dp, f"rt{ns}/cmd/mode", rt.String), qos=RELIABLE)
    get_p = Service(dp, f"{fq}/get_parameters", st.GetParametersRequest, st.GetParametersResponse)
    set_p = Service(dp, f"{fq}/set_parameters", st.SetParametersRequest, st.SetParametersResponse)
    list_p = Service(dp, f"{fq}/list_parameters", st.ListParametersRequest, st.ListParametersResponse)
    desc_p = Service(dp, f"{fq}/describe_parameters", st.DescribeParametersRequest, st.DescribeParametersResponse)
    arm = Service(dp, f"{ns}/arm", st.SetBoolRequest, st.SetBoolResponse)
    land = Service(dp, f"{ns}/land", st.TriggerRequest, st.TriggerResponse)
    hold = Service(dp, f"{ns}/hold", st.TriggerRequest, st.TriggerResponse)

    t_start = time.time()

    def tick_clock():
        el = time.time() - t_start
        clock_w.write(st.Clock(rt.Time(sec=SIM_T0 + int(el), nanosec=int((el % 1) * 1e9))))

    def pump(seconds):
        t0 = time.time()
        while time.time() - t0 < seconds:
            tick_clock()
            time.sleep(0.02)

    # Bridge up and the MCU handshake done (status flows), /clock running.
    first = None
    while time.time() - t_start < 20:
        tick_clock()
        if status.take(N=100):
            first = time.time()
            break
        time.sleep(0.02)
    c.check("bridge status arrives under the namespace", first is not None)
    if first is None:
        print(f"{c.passed} passed, {c.failed} failed")
        return 1
    pump(1.5)  # service discovery, parameter sync with the MCU

    # ---------------------------------------------------------------- parameters
    r = list_p.call(st.ListParametersRequest())
    names = set(r.result.names) if r else set()
    want = {"ttl_ms", "use_sim_time", "record", "limits.max_tilt_deg", "limits.max_horiz_speed_mps",
            "control.vel_p_per_s", "control.cross_track_k_per_s"}
    c.check("list_parameters", want <= names, sorted(names))

    def get(*ns_):
        r = get_p.call(st.GetParametersRequest(names=list(ns_)))
        return r.values if r else None

    v = get("ttl_ms", "limits.max_tilt_deg", "limits.max_horiz_speed_mps", "use_sim_time")
    c.check("get_parameters: ttl_ms integer 300", v and v[0].type == P_INT and v[0].integer_value == 300,
            v and v[0])
    tilt_default = mcu_params.default("limits.max_tilt_deg")
    c.check(f"get_parameters: MCU's max_tilt_deg {tilt_default:g} (the firmware default, read from the MCU)",
            v and v[1].type == P_DOUBLE and abs(v[1].double_value - tilt_default) < 1e-6, v and v[1])
    c.check("--params-file value for the MCU (max_horiz_speed_mps 6)",
            v and abs(v[2].double_value - 6.0) < 1e-6, v and v[2])
    c.check("use_sim_time true", v and v[3].type == P_BOOL and v[3].bool_value, v and v[3])

    # describe_parameters (what `ros2 param describe` shows): every listed parameter has a
    # description; ranges with units from the tables; read-only flags as the validator enforces.
    r = desc_p.call(st.DescribeParametersRequest(names=sorted(names)))
    ds = {d.name: d for d in r.descriptors} if r else {}
    undescribed = [n for n in sorted(names) if n not in ds or not ds[n].description
                   or "description missing" in ds[n].description]
    c.check(f"describe_parameters: all {len(names)} parameters described", bool(ds) and not undescribed, undescribed)
    d = ds.get("limits.max_tilt_deg")
    c.check("describe limits.max_tilt_deg: double, range 5..60, unit deg, writable",
            d is not None and d.type == P_DOUBLE and len(d.floating_point_range) == 1
            and (d.floating_point_range[0].from_value, d.floating_point_range[0].to_value) == (5.0, 60.0)
            and "deg" in d.description and not d.read_only, d)
    d = ds.get("ttl_ms")
    c.check("describe ttl_ms: integer, range 50..3000 step 1, unit ms, writable",
            d is not None and d.type == P_INT and len(d.integer_range) == 1
            and (d.integer_range[0].from_value, d.integer_range[0].to_value, d.integer_range[0].step) == (50, 3000, 1)
            and "ms" in d.description and not d.read_only, d)
    c.check("describe ping_period_ms and clock_source: read-only",
            all(ds.get(n) is not None and ds[n].read_only for n in ("ping_period_ms", "clock_source")),
            [(n, ds[n].read_only) for n in ("ping_period_ms", "clock_source") if n in ds])
    c.check("describe use_sim_time: writable", ds.get("use_sim_time") is not None and not ds["use_sim_time"].read_only)

    def set_(name, value):
        r = set_p.call(st.SetParametersRequest(parameters=[st.Parameter(name, value)]))
        return r.results[0] if r and r.results else None

    r = set_("limits.max_tilt_deg", pv_double(30.0))
    c.check("set max_tilt_deg 30 accepted (MCU acked)", r and r.successful, r)
    v = get("limits.max_tilt_deg")
    c.check("get after set: 30", v and abs(v[0].double_value - 30.0) < 1e-6, v)
    r = set_("limits.max_tilt_deg", pv_double(80.0))
    c.check("set max_tilt_deg 80 refused with a reason", r and not r.successful and "out of range" in r.reason, r)
    v = get("limits.max_tilt_deg")
    c.check("refused set leaves 30", v and abs(v[0].double_value - 30.0) < 1e-6, v)
    r = set_("control.vel_p_per_s", pv_double(4.5))
    c.check("set control.vel_p_per_s 4.5 accepted", r and r.successful, r)
    r = set_("clock_source", st.ParameterValue(type=P_STRING, string_value="mcu"))
    c.check("read-only clock_source refused", r and not r.successful and "read-only" in r.reason, r)
    r = set_("ttl_ms", st.ParameterValue(type=P_INT, integer_value=500))
    c.check("set ttl_ms 500 accepted", r and r.successful, r)

    # ---------------------------------------------------------------- services, then fly by topic
    r = arm.call(st.SetBoolRequest(data=True))
    c.check("arm service: MCU accepted", r and r.success and "accepted" in r.message, r)
    pump(0.2)
    mode_w.write(rt.String(data="velocity"))
    pump(0.2)
    sp_w.write(rt.TwistStamped(rt.Header(rt.Time(), "map"), rt.Twist(rt.Vector3(0.0, 1.0, 0.0))))
    pump(0.2)
    sp_w.write(rt.TwistStamped(rt.Header(rt.Time(), "map"), rt.Twist(rt.Vector3(math.nan, 0.0, 0.0))))
    pump(0.3)
    r = hold.call(st.TriggerRequest())
    c.check("hold service: MCU accepted", r and r.success, r)
    r = land.call(st.TriggerRequest())
    c.check("land service: MCU accepted", r and r.success, r)
    r = arm.call(st.SetBoolRequest(data=False))
    c.check("disarm via arm(false): MCU accepted", r and r.success and "Disarm" in r.message, r)
    pump(0.5)

    # ---------------------------------------------------------------- /rosout
    logs = rosout.take(N=1000)
    warns = [l for l in logs if l.level == 30 and "setpoint refused" in l.msg]
    c.check("/rosout WARN for the bad setpoint", bool(warns), [(l.level, l.name, l.msg) for l in logs][-5:])
    if warns:
        c.check("/rosout logger name", warns[0].name == fq.strip("/").replace("/", "."), warns[0].name)
    c.check("/rosout INFO present too (levels)", any(l.level == 20 for l in logs))

    # ---------------------------------------------------------------- sim time, remap
    samples = imu.take(N=500)
    stamps = [s.header.stamp.sec + s.header.stamp.nanosec * 1e-9 for s in samples[-20:]]
    c.check("use_sim_time: stamps follow /clock", bool(stamps) and all(SIM_T0 <= t < SIM_T0 + 120 for t in stamps),
            stamps[-1:] if stamps else None)
    c.check("remap battery:=power/battery under /uav1", len(battery.take(N=100)) > 0)

    # ---------------------------------------------------------------- late joiner, /tf_static
    dp2 = DomainParticipant(a.domain)
    late = DataReader(dp2, Topic(dp2, "rt/tf_static", rt.TFMessage), qos=TF_STATIC_QOS)
    got = []
    t0 = time.time()
    while time.time() - t0 < 5 and not got:
        got = late.take(N=10)
        time.sleep(0.05)
    frames = {t.child_frame_id for t in got[-1].transforms} if got else set()
    c.check(f"/tf_static received by a peer joining {time.time() - first:.0f} s later (transient local)",
            frames >= {"odom", "imu_link", "gps_link", "laser_link", "sonar_link"}, sorted(frames))

    # ---------------------------------------------------------------- what the MCU got
    recs = [json.loads(line) for line in open(a.mcu_log) if line.strip()]
    psets = [r for r in recs if r["msg"] == "ParamSet"]
    acc = [(r["name"], r["value"]) for r in psets if r["result"] == "Accepted"]
    c.check("MCU got start-up value max_horiz_speed_mps 6", ("limits.max_horiz_speed_mps", 6.0) in acc, acc)
    c.check("MCU got max_tilt_deg 30", ("limits.max_tilt_deg", 30.0) in acc, acc)
    c.check("MCU got control.vel_p_per_s 4.5", ("control.vel_p_per_s", 4.5) in acc, acc)
    c.check("out-of-range value never reached the MCU", not any(r["value"] == 80.0 for r in psets))
    cmds = [r["command"] for r in recs if r["msg"] == "Command"]
    c.check("MCU got Arm, Velocity, Hold, Land, Disarm", cmds == ["Arm", "Velocity", "Hold", "Land", "Disarm"], cmds)
    sps = [r for r in recs if r["msg"] == "VelocitySetpoint"]
    c.check("setpoint after arm-by-service, with the new ttl 500 ms", len(sps) == 1 and sps[0]["ttl_ms"] == 500
            and abs(sps[0]["vel_ned_mps"][0] - 1.0) < 1e-6, sps)
    print(f"{c.passed} passed, {c.failed} failed")
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
