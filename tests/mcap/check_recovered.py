#!/usr/bin/env python3
"""Check a bag recovered by fcc-bag-recover after a SIGKILL with independent readers.

  check_recovered.py RECOVERED.mcap --kill-ns NS [--raw KILLED.mcap] [--max-lost-s 1.0]

* Foxglove's `mcap` (make_reader + get_summary): the summary is there with chunk indexes and a
  Statistics record; iter_messages() (through the summary's index) and mcap_ros2's decoder
  decode every message; their number == Statistics.message_count.
* `rosbags` AnyReader opens the bare .mcap and deserializes every message; same per-topic counts.
* The loss = kill time − the last message's log time, printed; must be ≤ --max-lost-s.
* --raw: what the two readers say about the killed file itself (printed, for the record).
Exit 0 when everything holds.
"""
import argparse
import collections
import sys
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def fail(msg):
    print("FAIL " + msg)
    sys.exit(1)


def foxglove(path):
    counts = collections.Counter()
    last = 0
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        if reader.get_header().profile != "ros2":
            fail("profile is not ros2")
        s = reader.get_summary()
        if s is None:
            fail("no summary")
        if not s.chunk_indexes:
            fail("no chunk indexes in the summary")
        if s.statistics is None:
            fail("no Statistics record")
        for ch in s.channels.values():
            if "offered_qos_profiles" not in ch.metadata:
                fail(f"{ch.topic}: no offered_qos_profiles")
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            assert decoded is not None
            counts[channel.topic] += 1
            last = max(last, message.log_time)
        if sum(counts.values()) != s.statistics.message_count:
            fail(f"read {sum(counts.values())} messages, Statistics says {s.statistics.message_count}")
    return counts, last, len(s.chunk_indexes)


def rosbags(path):
    from rosbags.highlevel import AnyReader
    counts = collections.Counter()
    with AnyReader([Path(path)]) as r:
        for conn, t, raw in r.messages():
            r.deserialize(raw, conn.msgtype)
            counts[conn.topic] += 1
    return counts


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bag")
    ap.add_argument("--kill-ns", type=int, required=True)
    ap.add_argument("--raw")
    ap.add_argument("--max-lost-s", type=float, default=1.0)
    a = ap.parse_args()

    if a.raw:
        for name, fn in (("mcap make_reader().iter_messages()", lambda p: sum(1 for _ in make_reader(open(p, "rb")).iter_messages())),
                         ("rosbags AnyReader", lambda p: sum(rosbags(p).values()))):
            try:
                n = fn(a.raw)
                print(f"killed file as is: {name}: {n} messages")
            except Exception as e:  # what a reader says about the file without summary
                print(f"killed file as is: {name}: {type(e).__name__}: {str(e)[:120]}")

    counts, last, chunks = foxglove(a.bag)
    n = sum(counts.values())
    if n == 0:
        fail("no message recovered")
    print(f"recovered, mcap+mcap_ros2 (summary, {chunks} chunk indexes): decoded {n} messages on {len(counts)} topics")
    rb = rosbags(a.bag)
    if rb != counts:
        fail(f"rosbags counts differ: {dict(rb)} vs {dict(counts)}")
    print(f"recovered, rosbags AnyReader: deserialized {sum(rb.values())} messages, same per-topic counts")
    lost = (a.kill_ns - last) / 1e9
    print(f"ROW|recorder SIGKILL data lost (recovered bag)|{lost:.3f} s|goal ≤ {a.max_lost_s} s|{'met' if lost <= a.max_lost_s else 'NOT met'}")
    if not (0 <= lost <= a.max_lost_s):
        fail(f"lost {lost:.3f} s (goal 0 … {a.max_lost_s} s)")
    print(f"PASS recovered bag: both readers, {lost:.3f} s lost before the kill")


if __name__ == "__main__":
    main()
