#!/usr/bin/env python3
"""A late joiner gets /tf_static from fcc-replay (Cyclone DDS, independent of the Rust side):
late_tf_static.py BAG SECONDS [--prefix /replay]
Started after the replay has published the bag's /tf_static: a reliable, transient-local reader
on PREFIX/tf_static must receive it within SECONDS (the replay republishes the recorded QoS,
transient local, as the bridge does), equal to the bag's message (frames, stamps, translations,
rotations, bit for bit). A volatile reader created at the same time is printed for information."""
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

bag, secs = sys.argv[1], float(sys.argv[2])
prefix = sys.argv[sys.argv.index("--prefix") + 1] if "--prefix" in sys.argv else ""


def key(tf):
    out = []
    for t in tf.transforms:
        tr, r = t.transform.translation, t.transform.rotation
        out.append((t.header.frame_id, t.child_frame_id, t.header.stamp.sec, t.header.stamp.nanosec,
                    tr.x, tr.y, tr.z, r.x, r.y, r.z, r.w))
    return out


want = []
with open(bag, "rb") as f:
    for _, ch, m, d in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages(topics=["/tf_static"]):
        want.append(key(d))
if not want:
    print("FAIL the bag has no /tf_static"); sys.exit(1)
dp = DomainParticipant(0)
topic = Topic(dp, "rt" + prefix + "/tf_static", rt.TFMessage)
late = DataReader(dp, topic, qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                                     Policy.Durability.TransientLocal, Policy.History.KeepLast(10)))
vol = DataReader(dp, topic, qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                                    Policy.Durability.Volatile, Policy.History.KeepLast(10)))
t0 = time.monotonic()
got, got_vol, first_at = [], [], None
while time.monotonic() < t0 + secs:
    for m in late.take(N=10):
        got.append(m)
        if first_at is None:
            first_at = time.monotonic() - t0
    got_vol += vol.take(N=10)
    if got and time.monotonic() > t0 + first_at + 0.5:
        break
    time.sleep(0.02)
same = bool(got) and all(key(m) == want[-1] for m in got)
print(f"late joiner (Cyclone, transient local) on {prefix}/tf_static: {len(got)} received"
      + (f" {first_at:.2f} s after joining" if got else "")
      + f", equal to the bag's: {'yes' if same else 'no'} ({len(want[-1])} transforms); "
      f"a volatile reader got {len(got_vol)}")
if not got or not same:
    print("FAIL late joiner /tf_static"); sys.exit(1)
print("PASS late joiner got /tf_static from fcc-replay")
