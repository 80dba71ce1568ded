#!/usr/bin/env python3
"""Receive what fcc-replay republishes, with Cyclone DDS (independent of the Rust side), and
compare it with the bag: replay_sub.py BAG TOPIC SECONDS [--prefix /replay]
TOPIC is a nav_msgs/Odometry topic of the bag (e.g. /fcc/state/odom); the subscriber listens on
PREFIX+TOPIC for SECONDS, then checks that every message received equals the bag's message
with the same stamp (pose and twist, bit for bit) and that 95–100 % of the bag's messages came (no more).
"""
import os, sys, time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "dds"))
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import ros_types as rt

bag, topic, secs = sys.argv[1], sys.argv[2], float(sys.argv[3])
prefix = sys.argv[sys.argv.index("--prefix") + 1] if "--prefix" in sys.argv else ""
dp = DomainParticipant(0)
rd = DataReader(dp, Topic(dp, "rt" + prefix + topic, rt.Odometry),
                qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(100000)))
got = []
end = time.monotonic() + secs
while time.monotonic() < end:
    for m in rd.take(N=1000):
        got.append(m)
    time.sleep(0.02)
want = {}
n_bag = 0
with open(bag, "rb") as f:
    for _, ch, m, d in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages(topics=[topic]):
        st = d.header.stamp
        p, q, v = d.pose.pose.position, d.pose.pose.orientation, d.twist.twist.linear
        n_bag += 1
        want[(st.sec, st.nanosec)] = (p.x, p.y, p.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z)
bad = 0
order = sorted(want)
have = {(m.header.stamp.sec, m.header.stamp.nanosec) for m in got}
missing = [i for i, k in enumerate(order) if k not in have]
if missing:
    print(f"missing {len(missing)}: bag indices {missing[:5]}…{missing[-3:]} of 0..{len(order) - 1}")
for m in got:
    st = m.header.stamp
    p, q, v = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist.linear
    if want.get((st.sec, st.nanosec)) != (p.x, p.y, p.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z):
        bad += 1
share = len(got) / max(n_bag, 1)
print(f"replay subscriber (Cyclone) on {prefix}{topic}: received {len(got)} of the bag's {n_bag} "
      f"({100*share:.1f} %), {bad} differ from the bag")
if bad or not 0.95 <= share <= 1.0:
    print("FAIL replayed messages"); sys.exit(1)
print("PASS replayed messages equal the bag's")
