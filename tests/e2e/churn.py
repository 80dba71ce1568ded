#!/usr/bin/env python3
"""Participant churn against a running fcc-bridge (issue 14): memory stays bounded.

  churn.py --bridge-pid PID [--ns /fcc] [--cycles 40] [--participants 20]

Each cycle creates `participants` Cyclone DDS DomainParticipants (an independent DDS
implementation), each with a reader on the bridge's `status` and `imu/data_raw` and a writer on
`setpoint/velocity` (so the bridge's discovery database learns readers, writers and
participants), waits until they have matched, then deletes them all and waits for the bridge to
see them go. The bridge's RSS (/proc/PID/status VmRSS) is sampled before the first cycle, after
every cycle, and after a final settling time. Pass: growth ≤ 20 MB at the peak, and the growth
over the second half of the cycles (least-squares slope × cycles) ≤ 5 MB: flat, not rising.
Exit 0 when it holds.
"""
import argparse
import sys
import time

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros_types as rt

BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(1))


def rss_mb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS")


def topic_name(ns, rel):
    return "rt" + (ns.rstrip("/") + "/" + rel)


def slope(ys):
    n = len(ys)
    if n < 2:
        return 0.0
    mx = (n - 1) / 2.0
    my = sum(ys) / n
    sxx = sum((i - mx) ** 2 for i in range(n))
    return sum((i - mx) * (y - my) for i, y in enumerate(ys)) / sxx


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bridge-pid", type=int, required=True)
    ap.add_argument("--ns", default="/fcc")
    ap.add_argument("--cycles", type=int, default=40)
    ap.add_argument("--participants", type=int, default=20)
    ap.add_argument("--settle-s", type=float, default=5.0)
    a = ap.parse_args()

    # Wait for the bridge to publish status (it is up and connected to the fake MCU).
    probe = DomainParticipant(0)
    st_topic = Topic(probe, topic_name(a.ns, "status"), rt.Status)
    rd = DataReader(probe, st_topic, qos=BEST_EFFORT)
    t_end = time.time() + 30
    while time.time() < t_end and not rd.take(N=10):
        time.sleep(0.2)
    del rd, st_topic, probe
    time.sleep(a.settle_s)

    rss0 = rss_mb(a.bridge_pid)
    samples = []
    t0 = time.time()
    for c in range(a.cycles):
        parts = []
        for _ in range(a.participants):
            dp = DomainParticipant(0)
            ents = [
                DataReader(dp, Topic(dp, topic_name(a.ns, "status"), rt.Status), qos=BEST_EFFORT),
                DataReader(dp, Topic(dp, topic_name(a.ns, "imu/data_raw"), rt.Imu), qos=BEST_EFFORT),
                DataWriter(dp, Topic(dp, topic_name(a.ns, "setpoint/velocity"), rt.TwistStamped),
                           qos=BEST_EFFORT),
            ]
            parts.append((dp, ents))
        time.sleep(1.0)  # discovery: SPDP/SEDP both ways
        parts.clear()  # participants deleted (their entities with them)
        time.sleep(0.5)
        samples.append(rss_mb(a.bridge_pid))
        print(f"cycle {c + 1:2d}: bridge RSS {samples[-1]:.1f} MB", flush=True)
    time.sleep(a.settle_s)
    rss_end = rss_mb(a.bridge_pid)
    peak = max(samples + [rss_end]) - rss0
    half = samples[len(samples) // 2:]
    trend = slope(half) * len(samples)
    print(f"churn: {a.cycles} cycles × {a.participants} participants in {time.time() - t0:.0f} s; "
          f"bridge RSS {rss0:.1f} → peak {rss0 + peak:.1f} → {rss_end:.1f} MB after {a.settle_s:.0f} s "
          f"(growth at peak {peak:.1f} MB, second-half trend {trend:+.1f} MB over {a.cycles} cycles)")
    ok = True
    if peak > 20.0:
        print(f"FAIL: growth {peak:.1f} MB > 20 MB")
        ok = False
    if trend > 5.0:
        print(f"FAIL: still rising: {trend:+.1f} MB over {a.cycles} cycles in the second half")
        ok = False
    print(("1 passed, 0 failed" if ok else "0 passed, 1 failed"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
