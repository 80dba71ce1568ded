#!/usr/bin/env python3
"""Open an fcc-bridge bag with independent readers and check it.

  check_bag.py BAG [--counts BAG.counts.json] [--min-seconds S] [--truncated --kill-ns NS]

* Foxglove's `mcap` + `mcap-ros2-support`: decode every message of every channel; check the
  profile, schema encodings (ros2msg), message encoding (cdr), offered_qos_profiles.
* `rosbags` AnyReader: open the bare .mcap and deserialize every message (complete bags).
* --counts: per-topic counts in the bag == what the bridge published/received (0 lost).
* --truncated: the bag was cut by SIGKILL (no summary): read what is there with the streaming
  reader, and print the data lost = kill time − last log time (must be ≤ 1 s).
Exit 0 when everything holds; one line per finding.
"""
import argparse
import collections
import json
import sys
from pathlib import Path

from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap.records import Channel, Schema, Message, Header as McapHeader
from mcap_ros2.decoder import DecoderFactory


def fail(msg):
    print("FAIL " + msg)
    sys.exit(1)


def read_foxglove(path):
    counts = collections.Counter()
    last = 0
    first = None
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        if header.profile != "ros2":
            fail(f"profile {header.profile!r} != 'ros2'")
        summary = reader.get_summary()
        if summary is None:
            fail("no summary section (bag not finished)")
        if summary.statistics is None:
            fail("no Statistics record")
        for ch in summary.channels.values():
            sc = summary.schemas[ch.schema_id]
            if sc.encoding != "ros2msg" or ch.message_encoding != "cdr":
                fail(f"{ch.topic}: schema encoding {sc.encoding}, message encoding {ch.message_encoding}")
            if "/msg/" not in sc.name:
                fail(f"{ch.topic}: schema name {sc.name} is not pkg/msg/Type")
            if "offered_qos_profiles" not in ch.metadata:
                fail(f"{ch.topic}: no offered_qos_profiles")
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            counts[channel.topic] += 1
            assert decoded is not None
            last = max(last, message.log_time)
            first = message.log_time if first is None else min(first, message.log_time)
        stats = summary.statistics
        if sum(counts.values()) != stats.message_count:
            fail(f"decoded {sum(counts.values())} messages, Statistics says {stats.message_count}")
    return counts, first, last


def read_truncated(path):
    """Stream-read a bag without summary (SIGKILL): messages of every complete chunk."""
    counts = collections.Counter()
    schemas, channels, decoders = {}, {}, {}
    factory = DecoderFactory()
    last = 0
    err = None
    with open(path, "rb") as f:
        try:
            for rec in StreamReader(f, skip_magic=False).records:
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, Message):
                    ch = channels[rec.channel_id]
                    sc = schemas[ch.schema_id]
                    dec = decoders.get(sc.id) or factory.decoder_for(ch.message_encoding, sc)
                    decoders[sc.id] = dec
                    dec(rec.data)
                    counts[ch.topic] += 1
                    last = max(last, rec.log_time)
        except Exception as e:  # the cut: an incomplete record at the end
            err = f"{type(e).__name__}: {e}"
    return counts, last, err


def read_rosbags(path):
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
    ap.add_argument("--counts")
    ap.add_argument("--min-seconds", type=float, default=0)
    ap.add_argument("--truncated", action="store_true")
    ap.add_argument("--kill-ns", type=int)
    ap.add_argument("--max-lost-s", type=float, default=1.0)
    a = ap.parse_args()

    if a.truncated:
        counts, last, err = read_truncated(a.bag)
        n = sum(counts.values())
        if n == 0:
            fail("no message readable after SIGKILL")
        lost = (a.kill_ns - last) / 1e9 if a.kill_ns else float("nan")
        print(f"SIGKILL: {n} messages on {len(counts)} topics readable (stream reader stopped at: {err}); "
              f"last log time {lost:.3f} s before the kill")
        print(f"ROW|recorder SIGKILL data lost|{lost:.3f} s|goal ≤ {a.max_lost_s} s|{'met' if lost <= a.max_lost_s else 'NOT met'}")
        if not (lost <= a.max_lost_s):
            fail(f"lost {lost:.3f} s > {a.max_lost_s} s")
        print("PASS truncated bag readable")
        return

    counts, first, last = read_foxglove(a.bag)
    dur = (last - first) / 1e9
    print(f"mcap+mcap_ros2: decoded {sum(counts.values())} messages on {len(counts)} channels over {dur:.1f} s")
    for t, n in sorted(counts.items()):
        print(f"  {t:32s} {n}")
    if dur < a.min_seconds:
        fail(f"bag spans {dur:.1f} s < {a.min_seconds} s")
    rb = read_rosbags(a.bag)
    if rb != counts:
        fail(f"rosbags counts differ: {dict(rb)} vs {dict(counts)}")
    print(f"rosbags AnyReader: deserialized {sum(rb.values())} messages, same per-topic counts")
    if a.counts:
        doc = json.load(open(a.counts))
        b = doc["bridge"]
        want = collections.Counter()
        for k in ("published", "received"):
            for t, n in b[k].items():
                want[t] += n
        raw_topic = doc.get("raw_frames_topic")
        if raw_topic:
            want[raw_topic] += sum(b["raw_frames"].values())
        lost = {t: want[t] - counts.get(t, 0) for t in set(want) | set(counts) if want[t] != counts.get(t, 0)}
        print(f"bridge counted {sum(want.values())} messages, bag has {sum(counts.values())}: lost {sum(want.values()) - sum(counts.values())}")
        print(f"ROW|recorder messages lost|{sum(want.values()) - sum(counts.values())} of {sum(want.values())}|goal 0|{'met' if not lost else 'NOT met'}")
        if lost:
            fail(f"per-topic differences (bridge − bag): {lost}")
    print("PASS bag read by independent readers")


if __name__ == "__main__":
    main()
