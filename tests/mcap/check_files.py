#!/usr/bin/env python3
"""Check a recording that the bridge split into several files (record_split_s, record_split_mb,
record_on_arm), from its PATH.counts.json (which lists the files):

  check_files.py PATH.counts.json [--min-files N] [--split-s S] [--split-mb MB]
                 [--compression zstd|none] [--on-arm --arm-periods N]

* every file: complete (summary, Statistics), every message decoded by Foxglove's mcap +
  mcap-ros2-support and by rosbags' AnyReader (same counts), chunk compression as asked;
* --split-s: the recorder splits on the messages' log time (a message at ≥ the log time of the
  file's first message + S opens the next file): no message in a file is ≥ S after the file's
  first (exact), each file spans < S + TOL of log time (min..max) and each next file
  starts ≥ S − TOL after the previous one (TOL = 10 ms: log times can step back a little when
  the time sync corrects the clock offset), however much the writer lags; --split-mb: each
  file holds ≤ MB·10^6 bytes of message data plus one message;
* the files together hold exactly what the recorder counted as recorded, and — unless
  --on-arm — everything the bridge published/received (0 lost across the splits);
* --on-arm: one file per arm period (N), every recorded status says armed, and the bridge's
  messages while disarmed were not recorded.
"""
import argparse, collections, json, sys
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader


def fail(msg):
    print("FAIL " + msg); sys.exit(1)


ap = argparse.ArgumentParser()
ap.add_argument("counts")
ap.add_argument("--min-files", type=int, default=1)
ap.add_argument("--split-s", type=float)
ap.add_argument("--split-mb", type=float)
ap.add_argument("--compression", choices=["zstd", "none"])
ap.add_argument("--on-arm", action="store_true")
ap.add_argument("--arm-periods", type=int)
a = ap.parse_args()
doc = json.load(open(a.counts))
files = doc["recorder"]["files"]
total = collections.Counter()
disarmed_status = 0
TOL = 0.010
starts = []
disorder = 0.0
for f in files:
    counts = collections.Counter(); first = last = None; data_bytes = 0; biggest = 0
    with open(f, "rb") as fh:
        r = make_reader(fh, decoder_factories=[DecoderFactory()])
        s = r.get_summary()
        if s is None or s.statistics is None:
            fail(f"{f}: not finished (no summary / Statistics)")
        comp = {c.compression for c in s.chunk_indexes}
        want = {"zstd": {"zstd"}, "none": {""}}.get(a.compression)
        if want is not None and comp and comp != want:
            fail(f"{f}: chunk compression {comp}, want {want}")
        first_written = None  # the file's first message in file order (the recorder's reference)
        for schema, ch, m, dec in r.iter_decoded_messages(log_time_order=False):
            if first_written is None and m.log_time > 0:  # 0 = no time yet (as the recorder)
                first_written = m.log_time
            counts[ch.topic] += 1
            data_bytes += len(m.data); biggest = max(biggest, len(m.data))
            first = m.log_time if first is None else min(first, m.log_time)
            if last is not None:
                disorder = max(disorder, (last - m.log_time) / 1e9)
            last = m.log_time if last is None else max(last, m.log_time)
            if schema.name == "fcc_msgs/msg/Status" and not dec.armed:
                disarmed_status += 1
    with AnyReader([Path(f)]) as rb:
        rbc = collections.Counter(c.topic for c, _, _ in rb.messages())
    if rbc != counts:
        fail(f"{f}: rosbags counts differ from mcap's")
    span = (last - first) / 1e9 if first is not None else 0.0
    starts.append(first)
    print(f"{Path(f).name}: {sum(counts.values())} messages, {span:.3f} s, {data_bytes/1e6:.2f} MB of messages, "
          f"chunks {sorted(comp) or '-'}; read by mcap and rosbags alike")
    # Exact: no message reaches the first written message's log time + S (it would open the
    # next file); with out-of-order messages the min..max span may exceed S by the disorder.
    if a.split_s and first_written is not None and (last - first_written) / 1e9 >= a.split_s:
        fail(f"{f}: a message {(last - first_written) / 1e9:.3f} s after the file's first ≥ split {a.split_s} s")
    if a.split_s and span >= a.split_s + TOL:
        fail(f"{f}: spans {span:.3f} s of log time ≥ split {a.split_s} s + {TOL} s")
    if a.split_s and len(starts) > 1 and None not in starts[-2:] \
            and (starts[-1] - starts[-2]) / 1e9 < a.split_s - TOL:
        fail(f"{f}: starts {(starts[-1] - starts[-2]) / 1e9:.3f} s after the previous file < split {a.split_s} s")
    if a.split_mb and data_bytes > a.split_mb * 1e6 + biggest:
        fail(f"{f}: {data_bytes} B of messages > split {a.split_mb} MB")
    total += counts
if a.split_s:
    gaps = [(b - a_) / 1e9 for a_, b in zip(starts, starts[1:]) if a_ is not None and b is not None]
    print(f"split on log time: every file spans < {a.split_s} s + {TOL} s; files start "
          f"{min(gaps, default=0):.3f}–{max(gaps, default=0):.3f} s apart; log times out of file order by ≤ {disorder * 1e3:.1f} ms")
if len(files) < a.min_files:
    fail(f"{len(files)} files < {a.min_files}")
rec = collections.Counter(doc["recorder"]["recorded"])
if +rec != +total:
    fail(f"files hold {sum(total.values())} messages, the recorder counted {sum(rec.values())}")
b = doc["bridge"]
want = collections.Counter()
for k in ("published", "received"):
    for t, n in b[k].items():
        want[t] += n
if doc.get("raw_frames_topic"):
    want[doc["raw_frames_topic"]] += sum(b["raw_frames"].values())
not_rec = doc["recorder"]["not_recorded"]
print(f"{len(files)} files hold {sum(total.values())} messages = the recorder's count; the bridge handled "
      f"{sum(want.values())}, not recorded {not_rec}")
if a.on_arm:
    if a.arm_periods is not None and len(files) != a.arm_periods:
        fail(f"{len(files)} files for {a.arm_periods} arm periods")
    if disarmed_status:
        fail(f"{disarmed_status} recorded status messages say disarmed")
    if not (not_rec > 0 and sum(total.values()) + not_rec == sum(want.values())):
        fail("with record_on_arm the disarmed time must be left out (and nothing else)")
    print(f"PASS record_on_arm: {len(files)} files, one per arm period, only armed status recorded")
else:
    if sum(total.values()) != sum(want.values()) or not_rec:
        fail(f"lost across the splits: bridge {sum(want.values())}, files {sum(total.values())}")
    print(f"PASS split recording: {len(files)} files, 0 lost")
