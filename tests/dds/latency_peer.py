#!/usr/bin/env python3
"""Latency / loss / CPU probe for fcc-bridge (a benchmark, not a test; see bench_latency.sh).

Subscribes to `imu/data_raw` (sensor_msgs/Imu) as an independent Cyclone DDS peer with a
RELIABLE reader (what a default `rclcpp` subscription is) and measures, per message:

  latency = arrival at the peer (CLOCK_REALTIME, taken right after the WaitSet wakes) −
            the message's header stamp

The bridge stamps with the fake MCU's frame time (µs, taken just before it writes the frame to
the pty) mapped to the Linux realtime clock by the ping/pong time sync (clock_source:=sync), so
the figure covers: frame written → pty → bridge decode/convert → DDS → peer's hands. The sync
error is bounded by half the best ping round trip (tens of µs on a pty). The DDS source
timestamp (when the bridge called write) splits it into bridge-side and DDS+peer-side parts.

Loss: the fake MCU runs with --imu-counter (its IMU frame counter modulo 32767 in gyro x =
angular_velocity.x in FLU, as a count of the link's gyro LSB, 2000 deg/s / 32768); every jump of
the unwrapped counter counts the frames skipped.
CPU: utime+stime of --bridge-pid over the window / wall time (percent of one core).

Prints one line `RESULT {json}`. Run only inside a loopback-only namespace (netns-run).
"""
import argparse
import json
import os
import sys
import time

from cyclonedds.core import Policy, Qos, ReadCondition, SampleState, ViewState, InstanceState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros_types as rt

from link_resolution import LSB

# The fake's counter travels as gyro counts (the schema's `fixed` gyro LSB, rad/s) and wraps at
# COUNTER_MOD (fcc_bridge/src/fake_mcu.rs IMU_COUNTER_MOD).
GYRO_LSB_RADPS = LSB["gyro"]
COUNTER_MOD = 32767


def cpu_ticks(pid):
    with open(f"/proc/{pid}/stat") as f:
        s = f.read()
    fields = s[s.rindex(")") + 2:].split()
    return int(fields[11]) + int(fields[12])  # utime, stime (fields 14, 15)


def pct(v, q):
    v = sorted(v)
    return v[min(len(v) - 1, int(q * len(v)))] if v else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ns", default="/fcc")
    ap.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    ap.add_argument("--rate", type=float, required=True, help="IMU frame rate of the fake MCU (Hz)")
    ap.add_argument("--warmup", type=float, default=3.0, help="seconds ignored after the first sample")
    ap.add_argument("--seconds", type=float, default=10.0, help="measurement window")
    ap.add_argument("--bridge-pid", type=int)
    ap.add_argument("--wait", type=float, default=20.0, help="give up if no sample within this")
    a = ap.parse_args()

    dp = DomainParticipant(a.domain)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(2000))
    rd = DataReader(dp, Topic(dp, f"rt{a.ns.rstrip('/')}/imu/data_raw", rt.Imu), qos=qos)
    cond = ReadCondition(rd, SampleState.NotRead | ViewState.Any | InstanceState.Any)
    ws = WaitSet(dp)
    ws.attach(cond)

    t_first = None
    t_start = t_end = None
    cpu0 = cpu1 = None
    lat, bridge_part, dds_part, stamps, seqs = [], [], [], [], []
    counter_base = 0
    batch_max = 0
    t_begin = time.time()
    while True:
        ws.wait(duration(milliseconds=50))
        now_ns = time.time_ns()
        ss = rd.take(N=1000)
        if not ss:
            if t_first is None and time.time() - t_begin > a.wait:
                print("RESULT " + json.dumps({"error": "no imu/data_raw sample"}), flush=True)
                return 1
            if t_start is not None and now_ns * 1e-9 > t_end:
                break
            continue
        now = now_ns * 1e-9
        if t_first is None:
            t_first = now
            t_start = t_first + a.warmup
            t_end = t_start + a.seconds
        if now < t_start:
            continue
        if cpu0 is None and a.bridge_pid:
            cpu0 = (cpu_ticks(a.bridge_pid), time.monotonic())
        if now > t_end:
            break
        n = 0
        for s in ss:
            if type(s).__name__ == "InvalidSample":
                continue
            n += 1
            st = s.header.stamp.sec * 1_000_000_000 + s.header.stamp.nanosec
            stamps.append(st)
            raw = int(round(s.angular_velocity.x / GYRO_LSB_RADPS))
            if seqs and raw < seqs[-1] % COUNTER_MOD - COUNTER_MOD // 2:
                counter_base += COUNTER_MOD
            seqs.append(counter_base + raw)
            lat.append((now_ns - st) * 1e-6)
            src = s.sample_info.source_timestamp
            if src and src > 0:
                bridge_part.append((src - st) * 1e-6)
                dds_part.append((now_ns - src) * 1e-6)
        batch_max = max(batch_max, n)
    if a.bridge_pid and cpu0 is not None:
        cpu1 = (cpu_ticks(a.bridge_pid), time.monotonic())
    tck = os.sysconf("SC_CLK_TCK")
    cpu = (100.0 * (cpu1[0] - cpu0[0]) / tck / (cpu1[1] - cpu0[1])) if cpu1 else None

    stamps.sort()
    missed = 0
    reordered = 0
    for x, y in zip(seqs, seqs[1:]):
        if y > x + 1:
            missed += y - x - 1
        elif y <= x:
            reordered += 1
    span = (stamps[-1] - stamps[0]) * 1e-9 if len(stamps) > 1 else 0.0
    r = {
        "rate_hz": a.rate,
        "received": len(stamps),
        "missed": missed,
        "loss": missed / max(1, missed + len(stamps)),
        "reordered_or_dup": reordered,
        "seq_span": (seqs[-1] - seqs[0] + 1) if seqs else 0,
        "rx_rate_hz": (len(stamps) - 1) / span if span > 0 else 0.0,
        "lat_p50_ms": pct(lat, 0.5),
        "lat_p99_ms": pct(lat, 0.99),
        "lat_max_ms": max(lat) if lat else float("nan"),
        "lat_min_ms": min(lat) if lat else float("nan"),
        "bridge_p50_ms": pct(bridge_part, 0.5),
        "bridge_p99_ms": pct(bridge_part, 0.99),
        "dds_peer_p50_ms": pct(dds_part, 0.5),
        "dds_peer_p99_ms": pct(dds_part, 0.99),
        "max_batch": batch_max,
        "cpu_pct": cpu,
        "window_s": a.seconds,
    }
    print("RESULT " + json.dumps(r), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
