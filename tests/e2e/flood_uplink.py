#!/usr/bin/env python3
"""A 10 kHz setpoint flood against fcc-bridge on a baud-limited link, from an independent
Cyclone DDS peer (issue 14, uplink budget). Started by tests/e2e/flood_uplink.sh, which runs

  fcc-fake-mcu --log MCU.jsonl ⇄ fcc-wire-fault --baud 921600 --stats RELAY.jsonl ⇄ fcc-bridge

  flood_uplink.py --mcu-log MCU.jsonl --relay-stats RELAY.jsonl [--hz 10000] [--flood-s 6]

1. Arms and selects velocity mode, then publishes valid setpoints (TwistStamped, map) at
   --hz for --flood-s seconds. Each setpoint carries its index in linear.y (north), so the
   fake MCU's log tells which one arrived when.
2. During the flood, every --cmd-period s, a cmd/mode "land" (alternating with "hold").
3. Figures, all from monotonic clocks (CLOCK_MONOTONIC: the peer's time.monotonic_ns() at
   each write, the fake MCU's receive time `mono_us`, the relay's per-second stats):
   - command latency: the peer's write of each land/hold → the fake MCU's receipt of it (the
     fake MCU changes its mode on receipt). Goal: every one ≤ --max-cmd-ms (100 ms).
   - uplink bytes/s at the MCU end (relay, Linux → MCU) in the flood's whole seconds, and the
     largest backlog waiting in the Linux side's pty (bytes the UART could not take yet).
     Goal: ≤ --max-share of 921600/10 B/s, backlog ≤ --max-backlog bytes. Unshaped, the
     bridge offers ~4× what the line carries: the line runs at 100 % and the pty fills.
   - setpoints at the MCU per second (≤ 101: the bridge's 100 Hz bound) and their age (peer
     write → MCU receipt): coalesced to the newest, so the age stays small.
   - the bridge's coalescing counters on /diagnostics.
Exit 0 when every goal holds.
"""
import argparse
import json
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
BEST_EFFORT = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100))
INDEX_SCALE = 1e-4  # m/s per setpoint index in linear.y (max 2 m/s, below max_speed_mps)
INDEX_WRAP = 20000


def read_jsonl(path):
    out = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line:
                try:
                    out.append(json.loads(line))
                except json.JSONDecodeError:
                    pass  # a line being written
    return out


def pct(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ns", default="/fcc")
    ap.add_argument("--mcu-log", required=True)
    ap.add_argument("--relay-stats", required=True)
    ap.add_argument("--hz", type=float, default=10000.0)
    ap.add_argument("--min-hz", type=float, default=9000.0,
                    help="fail if the peer could not flood at least this fast")
    ap.add_argument("--flood-s", type=float, default=6.0)
    ap.add_argument("--cmd-period", type=float, default=0.5)
    ap.add_argument("--baud", type=int, default=921600)
    ap.add_argument("--max-cmd-ms", type=float, default=100.0)
    ap.add_argument("--max-share", type=float, default=0.25)
    ap.add_argument("--max-backlog", type=int, default=1024)
    a = ap.parse_args()
    ns = a.ns.rstrip("/")
    name = lambda n: "rt" + (n if n.startswith("/") else f"{ns}/{n}")
    fails = []

    dp = DomainParticipant(0)
    status = DataReader(dp, Topic(dp, name("status"), rt.Status), qos=RELIABLE)
    diag = DataReader(dp, Topic(dp, "rt/diagnostics", rt.DiagnosticArray), qos=BEST_EFFORT)
    sp = DataWriter(dp, Topic(dp, name("setpoint/velocity"), rt.TwistStamped), qos=RELIABLE)
    mode = DataWriter(dp, Topic(dp, name("cmd/mode"), rt.String), qos=RELIABLE)
    arm = DataWriter(dp, Topic(dp, name("cmd/arm"), rt.Bool), qos=RELIABLE)

    last = {"status": None, "setpoints": None}

    def poll():
        for s in status.take(N=100):
            last["status"] = s
        for d in diag.take(N=100):
            for st in d.status:
                if st.name.endswith("setpoints"):
                    last["setpoints"] = {kv.key: kv.value for kv in st.values}

    t0 = time.monotonic()
    while last["status"] is None and time.monotonic() - t0 < 30:
        poll()
        time.sleep(0.1)
    if last["status"] is None:
        print("FAIL no status from the bridge")
        return 1
    while any(w.get_matched_subscriptions() == [] for w in (sp, mode, arm)) \
            and time.monotonic() - t0 < 30:
        time.sleep(0.1)
    time.sleep(1.0)
    arm.write(rt.Bool(data=True))
    time.sleep(0.2)
    mode.write(rt.String(data="velocity"))
    time.sleep(1.0)
    poll()

    period_ns = int(1e9 / a.hz)
    n_total = int(a.hz * a.flood_s)
    sent_ns = [0] * n_total
    cmds = []  # (mono_ns at write, text)
    texts = ["land", "hold"]
    next_cmd = 1
    msg = rt.TwistStamped(rt.Header(rt.Time(), "map"), rt.Twist(rt.Vector3(0.0, 0.0, 0.0)))
    start = time.monotonic_ns()
    flood_start = start
    i = 0
    while i < n_total:
        now = time.monotonic_ns()
        if now < start + i * period_ns:
            continue
        if now >= start + next_cmd * int(a.cmd_period * 1e9) and \
                now < start + int((a.flood_s - 0.3) * 1e9):
            text = texts[(next_cmd - 1) % 2]
            t = time.monotonic_ns()
            mode.write(rt.String(data=text))
            cmds.append((t, text))
            next_cmd += 1
        wall = time.time()
        msg.header.stamp = rt.Time(sec=int(wall), nanosec=int((wall % 1) * 1e9))
        msg.twist.linear.y = (i % INDEX_WRAP) * INDEX_SCALE
        sent_ns[i] = time.monotonic_ns()
        sp.write(msg)
        i += 1
    flood_end = time.monotonic_ns()
    achieved = n_total / ((flood_end - flood_start) / 1e9)
    time.sleep(2.5)  # the relay's stats line for the last second, the MCU's last receipts
    poll()

    # --- figures -----------------------------------------------------------------------------
    mcu = [r for r in read_jsonl(a.mcu_log) if r.get("mono_us", 0) * 1000 >= flood_start]
    got_cmds = [r for r in mcu if r["msg"] == "Command" and r["command"] in ("Land", "Hold")]
    lat_ms = []
    for k, (t, text) in enumerate(cmds):
        if k >= len(got_cmds):
            fails.append(f"command {k + 1} ({text}) never reached the MCU")
            continue
        r = got_cmds[k]
        if r["command"].lower() != text:
            fails.append(f"command {k + 1}: sent {text}, MCU got {r['command']}")
        lat_ms.append((r["mono_us"] * 1000 - t) / 1e6)
    print(f"peer: {n_total} setpoints in {(flood_end - flood_start) / 1e9:.2f} s "
          f"({achieved:.0f}/s, asked {a.hz:.0f}/s), {len(cmds)} land/hold commands during it")
    if achieved < a.min_hz:
        fails.append(f"the peer flooded at {achieved:.0f}/s only (< {a.min_hz:.0f}/s)")
    if lat_ms:
        worst = max(lat_ms)
        print(f"ROW|land/hold command latency under a {achieved / 1000:.1f} kHz setpoint flood "
              f"(peer write → fake MCU receipt, CLOCK_MONOTONIC)|median {pct(lat_ms, 50):.2f} ms, "
              f"max {worst:.2f} ms over {len(lat_ms)}|goal ≤ {a.max_cmd_ms:g} ms|"
              f"{'met' if worst <= a.max_cmd_ms else 'NOT met'}")
        if worst > a.max_cmd_ms:
            fails.append(f"a command took {worst:.1f} ms > {a.max_cmd_ms:g} ms")
    else:
        fails.append("no command latency measured")

    # Relay stats: the whole seconds inside the flood.
    budget = a.baud / 10.0
    stats = read_jsonl(a.relay_stats)
    inside = [s for s in stats if flood_start + 1e9 <= s["mono_ns"] <= flood_end]
    if len(inside) < max(1, int(a.flood_s) - 2):
        fails.append(f"only {len(inside)} relay stats seconds inside the flood")
    if inside:
        up = [s["up_bytes"] for s in inside]
        backlog = max(s["up_backlog_max"] for s in inside)
        worst = max(up)
        print(f"ROW|uplink bytes/s at the MCU end under the flood ({a.baud} baud line, "
              f"{budget:.0f} B/s)|mean {sum(up) / len(up):.0f}, max {worst} B/s "
              f"({100 * worst / budget:.1f} % of the line); largest backlog in the pty "
              f"{backlog} B|goal ≤ {100 * a.max_share:g} %, backlog ≤ {a.max_backlog} B|"
              f"{'met' if worst <= a.max_share * budget and backlog <= a.max_backlog else 'NOT met'}")
        if worst > a.max_share * budget:
            fails.append(f"uplink {worst} B/s > {a.max_share:g} × {budget:.0f}")
        if backlog > a.max_backlog:
            fails.append(f"uplink backlog {backlog} B > {a.max_backlog} B")

    # Setpoints at the MCU: rate and age (which index arrived when).
    sps = [r for r in mcu if r["msg"] == "VelocitySetpoint" and r["mono_us"] * 1000 <= flood_end + 50e6]
    per_s = {}
    ages = []
    for r in sps:
        sec = int((r["mono_us"] * 1000 - flood_start) // 1e9)
        per_s[sec] = per_s.get(sec, 0) + 1
        idx = int(round(r["vel_ned_mps"][0] / INDEX_SCALE))
        # The newest index ≤ the receipt with that value modulo the wrap.
        cands = [j for j in range(idx, n_total, INDEX_WRAP) if sent_ns[j] and sent_ns[j] <= r["mono_us"] * 1000]
        if cands:
            ages.append((r["mono_us"] * 1000 - sent_ns[cands[-1]]) / 1e6)
    full = [per_s[s] for s in sorted(per_s) if 0 < s < int(a.flood_s)]
    if full:
        print(f"setpoints at the MCU: {len(sps)} in the flood, per whole second {min(full)}–{max(full)} "
              f"(bridge bound 100/s); age at the MCU median {pct(ages, 50):.1f} ms, "
              f"p99 {pct(ages, 99):.1f} ms, max {max(ages):.1f} ms")
        if max(full) > 101:
            fails.append(f"{max(full)} setpoints/s reached the MCU (> 101)")
        if min(full) < 90:
            fails.append(f"only {min(full)} setpoints/s reached the MCU in a second of the flood")
    else:
        fails.append("no setpoint reached the MCU during the flood")
    d = last["setpoints"]
    if d:
        print("bridge /diagnostics: " + ", ".join(
            f"{k} {d.get(k, '?')}" for k in ("setpoints_forwarded", "setpoints_sent",
                                           "setpoints_coalesced", "setpoints_superseded",
                                           "commands_forwarded")))
        if int(d.get("setpoints_coalesced", "0")) < n_total // 2:
            fails.append(f"setpoints_coalesced {d.get('setpoints_coalesced')} < {n_total // 2}")
    else:
        fails.append("no setpoint counters on /diagnostics")
    for f in fails[:10]:
        print("FAIL " + f)
    if not fails:
        print("PASS uplink shaped: commands first within the goal, setpoints coalesced, "
              "line within budget")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
