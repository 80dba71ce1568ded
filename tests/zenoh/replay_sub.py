#!/usr/bin/env python3
"""What fcc-replay republishes on Zenoh, received by the independent rmw_zenoh peer and compared
with the bag (issue 18): replay_sub.py BAG TOPIC SECONDS [--prefix /replay] [--connect EP]

A client of the router at EP (default tcp/127.0.0.1:7447; eclipse-zenoh, zenoh_ros.py) listens on
PREFIX+TOPIC for SECONDS with a subscription token, as rmw_zenoh's subscriber declares it. The bag
is read with Foxglove's `mcap` (no decoding of ours). Checks, each printed:
  * 95–100 % of the bag's messages on TOPIC arrive, and every one arrives byte for byte as the
    bag holds it (CDR with its encapsulation header: fcc-replay passes the bytes through);
  * rosbags decodes each as the bag's schema type;
  * the key expression's type is the bag's, with the REP-2016 hash the peer computes for it (what an
    rmw_zenoh subscriber's key carries), and every sample has rmw_zenoh's attachment with
    increasing sequence numbers;
  * with --late-transient T (a transient-local topic of the bag, e.g. /tf_static): a subscription
    declared --late-s seconds after the start (after the replay published T's one sample) as
    rmw_zenoh declares a TRANSIENT_LOCAL one — an AdvancedSubscriber that detects late publishers
    and queries their history — still gets the bag's sample, byte for byte.
Exit 0 when all hold.
"""
import argparse
import collections
import sys
import time

import zenoh
import zenoh.ext
from mcap.reader import make_reader

import zenoh_ros as zr


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("bag")
    ap.add_argument("topic")
    ap.add_argument("seconds", type=float)
    ap.add_argument("--prefix", default="")
    ap.add_argument("--connect", default="tcp/127.0.0.1:7447")
    ap.add_argument("--ready-file", help="written once the subscription is declared")
    ap.add_argument("--late-transient", help="a transient-local topic to join late (e.g. /tf_static)")
    ap.add_argument("--late-s", type=float, default=4.0)
    a = ap.parse_args()

    want = collections.Counter()
    ros_type = None
    with open(a.bag, "rb") as f:
        for schema, _, message in make_reader(f).iter_messages(topics=[a.topic]):
            want[bytes(message.data)] += 1
            ros_type = schema.name
    n_bag = sum(want.values())
    if not n_bag:
        print(f"FAIL the bag has no message on {a.topic}")
        return 1

    peer = zr.RosPeer(connect=a.connect, node="replay_sub")
    raw, decoded, keys, sequences = [], [], set(), []

    def on_raw(sample):
        raw.append(bytes(sample.payload.to_bytes()))
        keys.add(str(sample.key_expr))
        att = sample.attachment
        sequences.append(zr.Attachment.decode(att.to_bytes()).sequence_number if att is not None else None)

    topic = a.prefix + a.topic
    peer.subscribe(topic, ros_type, lambda r: decoded.append(r.message))
    peer.session.declare_subscriber(zr.topic_wildcard(peer.domain, topic), on_raw)
    if a.ready_file:
        open(a.ready_file, "w").close()
    late_want, late_got = set(), []
    if a.late_transient:
        with open(a.bag, "rb") as f:
            late_want = {bytes(m.data) for _, _, m in make_reader(f).iter_messages(topics=[a.late_transient])}
    start = time.monotonic()
    end = start + a.seconds
    late = None
    while time.monotonic() < end:
        if a.late_transient and late is None and time.monotonic() - start >= a.late_s:
            late = zenoh.ext.declare_advanced_subscriber(
                peer.session, zr.topic_wildcard(peer.domain, a.prefix + a.late_transient),
                lambda s: late_got.append(bytes(s.payload.to_bytes())),
                history=zenoh.ext.HistoryConfig(detect_late_publishers=True))
        time.sleep(0.05)
    peer.close()

    checks = []

    def check(name, ok, detail):
        checks.append(ok)
        print(f"{'PASS' if ok else 'FAIL'} {name}: {detail}")

    left = want.copy()
    differ = 0
    for b in raw:
        if left[b] > 0:
            left[b] -= 1
        else:
            differ += 1
    share = len(raw) / n_bag
    check(f"replayed {topic} received (Zenoh peer)", 0.95 <= share <= 1.0,
          f"{len(raw)} of the bag's {n_bag} ({100 * share:.1f} %)")
    check("every sample byte for byte a message of the bag", differ == 0 and raw != [],
          f"{differ} differ")
    check(f"rosbags decodes each as {ros_type}", len(decoded) == len(raw) and all(m is not None for m in decoded),
          f"{sum(m is not None for m in decoded)} of {len(raw)}")
    rihs = peer.type_hash(ros_type)
    expect = zr.topic_keyexpr(peer.domain, topic, ros_type, rihs)
    check("key expression with the type's REP-2016 hash", keys == {expect}, f"{sorted(keys)} (expected {expect})")
    seq_ok = all(s is not None for s in sequences) and all(b > a_ for a_, b in zip(sequences, sequences[1:]))
    check("rmw_zenoh attachment on every sample, sequence increasing", seq_ok and sequences != [],
          f"{len(sequences)} samples, first {sequences[:1]}, last {sequences[-1:]}")
    if a.late_transient:
        check(f"late TRANSIENT_LOCAL subscription to {a.prefix + a.late_transient} ({a.late_s:.0f} s after the "
              "start; AdvancedSubscriber with history) gets the bag's sample",
              bool(late_want) and bool(late_got) and set(late_got) <= late_want,
              f"{len(late_got)} received, {len(late_want)} in the bag, "
              f"{sum(b not in late_want for b in late_got)} differ")
    return 0 if all(checks) else 1


if __name__ == "__main__":
    sys.exit(main())
