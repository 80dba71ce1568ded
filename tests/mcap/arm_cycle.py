#!/usr/bin/env python3
"""Arm and disarm the bridge's vehicle on a schedule over DDS (Cyclone, independent of the
Rust side): arm_cycle.py ON1 OFF1 [ON2 OFF2 …] — seconds from start; publishes std_msgs/Bool on
/fcc/cmd/arm (each command 3× 50 ms apart; repeats are harmless)."""
import os, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "dds"))
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from cyclonedds.util import duration
import ros_types as rt

dp = DomainParticipant(0)
w = DataWriter(dp, Topic(dp, "rt/fcc/cmd/arm", rt.Bool),
               qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10)))
t0 = time.monotonic()
times = [float(x) for x in sys.argv[1:]]
for i, t in enumerate(times):
    time.sleep(max(0.0, t0 + t - time.monotonic()))
    for _ in range(3):
        w.write(rt.Bool(data=(i % 2 == 0))); time.sleep(0.05)
    print(f"arm_cycle: {'arm' if i % 2 == 0 else 'disarm'} at {time.monotonic() - t0:.2f} s", flush=True)
