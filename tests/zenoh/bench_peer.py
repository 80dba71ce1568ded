#!/usr/bin/env python3
"""The ground station of the Zenoh fleet benchmark (tests/zenoh/bench_fleet.sh): a client of one
router (eclipse-zenoh), it counts every sample's bytes per vehicle (payload + attachment: what
the vehicle's nodes put on the wire, before Zenoh's own framing) and measures the end-to-end
latency of imu/data_raw: the bridge stamps each message with the MCU sample's time on the Linux
clock (clock_source:=sync, time-synced over the link), so arrival − stamp is MCU frame → ground
peer, through the routers in between. The stamp is read straight from the CDR (header.stamp is
the first field: int32 sec, uint32 nanosec after the 4-byte encapsulation header) — no decoder
in the hot path, so the peer keeps up with many vehicles.

Prints one JSON line: per vehicle samples, bytes/s and latency p50/p99 (ms).
"""
import argparse
import json
import os
import re
import struct
import sys
import threading
import time
from collections import defaultdict

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
import zenoh  # noqa: E402
import zenoh_ros as zr  # noqa: E402


def pct(xs, q):
    if not xs:
        return float("nan")
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--connect", required=True)
    ap.add_argument("--seconds", type=float, default=30.0, help="measurement window")
    ap.add_argument("--warmup", type=float, default=10.0)
    ap.add_argument("--latency-from", default="", help="vehicles whose imu latency counts, e.g. 1,3,5")
    ap.add_argument("--until-file")
    a = ap.parse_args()
    lat_from = {int(x) for x in a.latency_from.split(",") if x}
    session = zenoh.open(zr.peer_config(a.connect))
    lock = threading.Lock()
    nbytes = defaultdict(int)
    samples = defaultdict(int)
    lat_ms = defaultdict(list)
    topic_bytes = defaultdict(int)     # topic → bytes (all vehicles)
    topic_samples = defaultdict(int)
    state = {"on": False}
    pat = re.compile(r"^\d+/uav(\d+)/(.+?)/[^/]+/[^/]+$")

    def on_sample(s):
        now = time.time()
        if not state["on"]:
            return
        m = pat.match(str(s.key_expr))
        if not m:
            return
        v, topic = int(m.group(1)), m.group(2)
        payload = s.payload.to_bytes()
        att = s.attachment.to_bytes() if s.attachment is not None else b""
        with lock:
            nbytes[v] += len(payload) + len(att)
            samples[v] += 1
            topic_bytes[topic] += len(payload) + len(att)
            topic_samples[topic] += 1
            if topic == "imu/data_raw" and v in lat_from and len(payload) >= 12:
                sec, nsec = struct.unpack_from("<iI", payload, 4)
                lat_ms[v].append((now - (sec + nsec * 1e-9)) * 1e3)

    session.declare_subscriber("0/**", on_sample)
    time.sleep(a.warmup)
    cpu0, t0 = time.process_time(), time.time()
    state["on"] = True
    time.sleep(a.seconds)
    state["on"] = False
    dt, cpu = time.time() - t0, time.process_time() - cpu0
    with lock:
        out = {"window_s": round(dt, 2), "peer_cpu_pct": round(100 * cpu / dt, 1), "vehicles": {}}
        for v in sorted(samples):
            out["vehicles"][v] = {
                "samples_per_s": round(samples[v] / dt, 1),
                "bytes_per_s": round(nbytes[v] / dt),
                "lat_p50_ms": round(pct(lat_ms[v], 0.5), 2) if lat_ms[v] else None,
                "lat_p99_ms": round(pct(lat_ms[v], 0.99), 2) if lat_ms[v] else None,
                "lat_n": len(lat_ms[v]),
            }
        nv = max(1, len(samples))
        out["topics"] = {t: {"hz": round(topic_samples[t] / dt / nv, 1),
                             "bytes_per_s": round(topic_bytes[t] / dt / nv),
                             "bytes_per_sample": round(topic_bytes[t] / max(1, topic_samples[t]))}
                         for t in sorted(topic_bytes, key=lambda t: -topic_bytes[t])}
        all_lat = [x for v in lat_ms for x in lat_ms[v]]
        out["lat_p50_ms"] = round(pct(all_lat, 0.5), 2)
        out["lat_p99_ms"] = round(pct(all_lat, 0.99), 2)
    print(json.dumps(out), flush=True)
    session.close()


if __name__ == "__main__":
    main()
