#!/usr/bin/env python3
"""Hostile input against a running fcc-bridge, from an independent Cyclone DDS peer (issue 14).

  hostile_input.py --bridge-pid PID --bridge-log FILE [--ns /fcc] [--count 600] [--hz 10]

1. 600 setpoints (TwistStamped) whose frame_id is 1 MB (starting with a terminal escape) at
   10 Hz, and a 1 MB cmd/mode text once a second: the bridge's RSS (/proc/PID/status VmRSS)
   is sampled every 0.5 s; growth from before the first one to 3 s after the last ≤ 20 MB.
2. A NaN setpoint flood (~1 kHz for 5 s): the bridge's log grows by ≤ 64 KB (warnings are
   rate-limited per kind), and the refusals are still counted on `status`.
3. Throughout: no line of the bridge's log, no /rosout record and no /diagnostics value is
   longer than 2 KB or holds a raw control character (ESC, …).
Exit 0 when everything holds.
"""
import argparse
import math
import os
import re
import sys
import time

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

import ros_types as rt

RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10))
BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(1000))
MAX_TEXT = 2048


def rss_mb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS")


def bad_text(s):
    """Why a text shown by the bridge is not bounded/escaped, or None."""
    if len(s) > MAX_TEXT:
        return f"{len(s)} chars"
    ctl = [c for c in s if (ord(c) < 32 and c not in "\t") or ord(c) == 127]
    if ctl:
        return f"raw control characters {sorted(set(map(ord, ctl)))}"
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bridge-pid", type=int, required=True)
    ap.add_argument("--bridge-log", required=True)
    ap.add_argument("--ns", default="/fcc")
    ap.add_argument("--count", type=int, default=600)
    ap.add_argument("--hz", type=float, default=10.0)
    ap.add_argument("--max-growth-mb", type=float, default=20.0)
    ap.add_argument("--flood-s", type=float, default=5.0)
    ap.add_argument("--max-log-growth-kb", type=float, default=64.0)
    a = ap.parse_args()
    ns = a.ns.rstrip("/")
    pid = a.bridge_pid
    fails = []

    dp = DomainParticipant(0)
    name = lambda n: "rt" + (n if n.startswith("/") else f"{ns}/{n}")
    status = DataReader(dp, Topic(dp, name("status"), rt.Status), qos=RELIABLE)
    diag = DataReader(dp, Topic(dp, "rt/diagnostics", rt.DiagnosticArray), qos=BEST_EFFORT)
    rosout = DataReader(dp, Topic(dp, "rt/rosout", rt.Log), qos=BEST_EFFORT)
    sp = DataWriter(dp, Topic(dp, name("setpoint/velocity"), rt.TwistStamped), qos=RELIABLE)
    mode = DataWriter(dp, Topic(dp, name("cmd/mode"), rt.String), qos=RELIABLE)

    seen = {"rosout": 0, "diagnostics": 0, "rosout_max": 0, "diag_max": 0}
    last_status = [None]

    def poll():
        for s in status.take(N=100):
            last_status[0] = s
        for r in rosout.take(N=1000):
            seen["rosout"] += 1
            seen["rosout_max"] = max(seen["rosout_max"], len(r.msg))
            why = bad_text(r.msg)
            if why:
                fails.append(f"/rosout record: {why}: {r.msg[:80]!r}")
        for d in diag.take(N=100):
            for st in d.status:
                for t in [st.message] + [kv.value for kv in st.values]:
                    seen["diagnostics"] += 1
                    seen["diag_max"] = max(seen["diag_max"], len(t))
                    why = bad_text(t)
                    if why:
                        fails.append(f"/diagnostics {st.name}: {why}: {t[:80]!r}")

    # Wait for the link (status flowing) and for our writers to match the bridge's readers.
    t0 = time.time()
    while last_status[0] is None and time.time() - t0 < 30:
        poll()
        time.sleep(0.1)
    if last_status[0] is None:
        print("FAIL no status from the bridge")
        return 1
    while (sp.get_matched_subscriptions() == [] or mode.get_matched_subscriptions() == []) \
            and time.time() - t0 < 30:
        time.sleep(0.1)
    time.sleep(2.0)
    poll()
    rej0 = last_status[0].setpoint_rejects_bridge
    base = rss_mb(pid)
    print(f"bridge RSS before: {base:.1f} MB; setpoint rejects so far {rej0}")

    # 1. 600 setpoints with a 1 MB frame_id at 10 Hz (+ a 1 MB mode text once a second).
    big = "\x1b[2J\x1b]0;pwned\x07" + "A" * (1 << 20)
    peak = base
    period = 1.0 / a.hz
    start = time.time()
    for i in range(a.count):
        now = time.time()
        stamp = rt.Time(sec=int(now), nanosec=int((now % 1) * 1e9))
        sp.write(rt.TwistStamped(rt.Header(stamp, big), rt.Twist(rt.Vector3(1.0, 0.0, 0.0))))
        if i % int(a.hz) == 0:
            mode.write(rt.String(data="hold\n" + big))
        if i % 5 == 0:
            peak = max(peak, rss_mb(pid))
            poll()
        if (i + 1) % 100 == 0:
            print(f"  after {i + 1}: RSS {rss_mb(pid):.1f} MB", flush=True)
        nxt = start + (i + 1) * period
        time.sleep(max(0.0, nxt - time.time()))
    sent_s = time.time() - start
    for _ in range(6):
        time.sleep(0.5)
        peak = max(peak, rss_mb(pid))
        poll()
    end = rss_mb(pid)
    rej1 = last_status[0].setpoint_rejects_bridge
    growth = end - base
    print(f"sent {a.count} setpoints with a {len(big)} B frame_id in {sent_s:.1f} s; "
          f"bridge refused {rej1 - rej0} (counted on status)")
    print(f"ROW|bridge RSS growth, {a.count} × 1 MB frame_id|{growth:+.1f} MB "
          f"({base:.1f} → {end:.1f} MB, peak {peak:.1f})|goal ≤ {a.max_growth_mb:g} MB|"
          f"{'met' if growth <= a.max_growth_mb else 'NOT met'}")
    if growth > a.max_growth_mb:
        fails.append(f"RSS grew {growth:.1f} MB > {a.max_growth_mb} MB")
    if rej1 - rej0 < 1:
        fails.append("no oversized setpoint counted as refused")

    # Unknown frames with terminal escapes and a newline: refused, shown escaped.
    evil = "evil\x1b[2J\x1b]0;pwned\x07\nINFO fake line"
    for _ in range(5):
        sp.write(rt.TwistStamped(rt.Header(rt.Time(), evil), rt.Twist(rt.Vector3(1.0, 0.0, 0.0))))
        time.sleep(0.3)
    time.sleep(1.0)
    poll()
    rej1 = last_status[0].setpoint_rejects_bridge

    # 2. NaN flood.
    log0 = os.path.getsize(a.bridge_log)
    n = 0
    start = time.time()
    nan = rt.TwistStamped(rt.Header(rt.Time(), "map"), rt.Twist(rt.Vector3(math.nan, 0.0, 0.0)))
    while time.time() - start < a.flood_s:
        sp.write(nan)
        n += 1
        if n % 200 == 0:
            poll()
        time.sleep(0.001)
    time.sleep(2.0)
    poll()
    log_kb = (os.path.getsize(a.bridge_log) - log0) / 1024.0
    rej2 = last_status[0].setpoint_rejects_bridge
    print(f"NaN flood: {n} setpoints in {a.flood_s:g} s; bridge refused {rej2 - rej1} (counted); "
          f"its log grew {log_kb:.1f} KB")
    print(f"ROW|bridge log growth under a NaN flood ({n / a.flood_s:.0f}/s, {a.flood_s:g} s)|"
          f"{log_kb:.1f} KB|goal ≤ {a.max_log_growth_kb:g} KB|"
          f"{'met' if log_kb <= a.max_log_growth_kb else 'NOT met'}")
    if log_kb > a.max_log_growth_kb:
        fails.append(f"log grew {log_kb:.1f} KB under the NaN flood")
    if rej2 - rej1 < 1:
        fails.append("no NaN setpoint counted as refused")

    # 3. The bridge's own log: bounded, escaped, with the suppressed counts.
    with open(a.bridge_log, encoding="utf-8", errors="replace") as f:
        lines = f.read().split("\n")
    longest = max(len(l) for l in lines)
    sgr = re.compile(r"\x1b\[[0-9;]*m")  # the log's own colours (tracing's ANSI styling)
    for l in lines:
        why = bad_text(sgr.sub("", l))
        if why:
            fails.append(f"bridge log line: {why}: {l[:80]!r}")
            break
    esc = [l for l in lines if "unknown frame_id 'evil\\u{1b}[2J\\u{1b}]0;pwned\\u{7}\\nINFO fake line'" in l]
    print(f"bridge log: unknown frame with escapes shown as: {esc[0].split('refused: ')[-1] if esc else '-'}")
    if not esc:
        fails.append("the unknown frame_id with control characters is not in the log, escaped")
    sup = [l for l in lines if "suppressed)" in l]
    print(f"bridge log: {len(lines)} lines, longest {longest} chars, {len(sup)} with a suppressed count; "
          f"e.g. {sup[-1].split('WARN')[-1].strip()[:140] if sup else '-'}")
    if not sup:
        fails.append("no '(N suppressed)' warning in the bridge log")
    print(f"/rosout: {seen['rosout']} records, longest {seen['rosout_max']} chars; "
          f"/diagnostics: {seen['diagnostics']} texts, longest {seen['diag_max']} chars")
    try:
        os.kill(pid, 0)
    except OSError:
        fails.append("the bridge died")
    for f in fails[:10]:
        print("FAIL " + f)
    if not fails:
        print("PASS hostile input: bounded memory, bounded and escaped logs, refusals counted")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
