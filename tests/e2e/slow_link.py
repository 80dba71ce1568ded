#!/usr/bin/env python3
"""Checks of the square flown over a 115200-baud UART with the slow-link profile (issue 20),
from what tests/e2e/slow_link.sh kept: the launcher's log (the mission node's cross-track), the
relay's per-second byte counts (link utilisation), the bag the bridge recorded (read with
Foxglove's `mcap` + `mcap_ros2`: the stream rates the profile asks for, the link's error
counters on `status`) and the simulator's CSV truth (no failsafe, landed).

  slow_link.py --dir DIR --baud 115200 --speed 2 --profile launch_configs/slow_link_115200.yaml
"""
import argparse
import collections
import csv
import json
import re
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


class Checks:
    def __init__(self):
        self.failed = 0
        self.passed = 0

    def check(self, what, ok, detail):
        print(f"{'PASS' if ok else 'FAIL'} {what}: {detail}", flush=True)
        if ok:
            self.passed += 1
        else:
            self.failed += 1


def profile_rates(path):
    """rates.<stream>_hz of the ROS params file (a two-level YAML read without a YAML library)."""
    rates, inside = {}, False
    for line in open(path):
        if re.match(r"^\s+rates:\s*$", line):
            inside = True
            continue
        m = re.match(r"^\s+(\w+)_hz:\s*([0-9.]+)", line)
        if inside and m:
            rates[m.group(1)] = float(m.group(2))
    return rates


def bag_topics(path):
    """Header stamps (s) per topic, and the last status message."""
    stamps, last_status = collections.defaultdict(list), None
    with open(path, "rb") as f:
        for _, channel, _, msg in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            if channel.topic.endswith("/status"):
                last_status = msg
            h = getattr(msg, "header", None)
            if h is not None:
                stamps[channel.topic].append(h.stamp.sec + h.stamp.nanosec * 1e-9)
    return stamps, last_status


def rate_hz(ts):
    """Messages per second of simulated time over the middle of the recording."""
    if len(ts) < 20:
        return 0.0
    ts = sorted(ts)
    a, b = ts[len(ts) // 10], ts[-len(ts) // 10]
    n = sum(1 for t in ts if a <= t <= b)
    return (n - 1) / (b - a) if b > a else 0.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", required=True)
    ap.add_argument("--baud", type=int, required=True)
    ap.add_argument("--speed", type=float, required=True)
    ap.add_argument("--profile", required=True)
    ap.add_argument("--ns", default="/fcc")
    a = ap.parse_args()
    c = Checks()
    log = open(f"{a.dir}/launch.log").read()

    m = re.search(r"mission complete: .*cross-track \(estimate, as seen on state/odom\) RMS ([0-9.]+) m max ([0-9.]+) m", log)
    c.check("mission complete, cross-track RMS ≤ 0.3 m (estimate, as the mission node saw it)",
            m is not None and float(m.group(1)) <= 0.3, m.group(0) if m else "no 'mission complete' line")
    stale = len(re.findall(r"setpoint refused: stamp", log))
    c.check("no setpoint refused as stale by the bridge", stale == 0, f"{stale} warnings")

    # Link utilisation: the relay's line runs at baud × speed, so bytes per wall second over
    # (baud × speed / 10) is the share of a `baud` line in simulated time.
    cap = a.baud * a.speed / 10
    rows = [json.loads(line) for line in open(f"{a.dir}/link_stats.jsonl")]
    down = sorted(r["down_bytes"] / cap for r in rows[2:-1])   # steady state (start-up burst apart)
    up = sorted(r["up_bytes"] / cap for r in rows[2:-1])
    first = [round(100 * r["down_bytes"] / cap, 1) for r in rows[:2]]
    print(f"link utilisation of a {a.baud}-baud line ({len(rows)} s wall at speed {a.speed:g}): "
          f"MCU→Linux p50 {100 * down[len(down) // 2]:.1f} % max {100 * down[-1]:.1f} % "
          f"(first two seconds {first} %, before the profile is in force); "
          f"Linux→MCU p50 {100 * up[len(up) // 2]:.1f} % max {100 * up[-1]:.1f} %; "
          f"largest backlog {max(r['down_backlog_max'] for r in rows)} B down, "
          f"{max(r['up_backlog_max'] for r in rows)} B up", flush=True)
    c.check("MCU→Linux ≤ 80 % of the line every second after start-up", bool(down) and down[-1] <= 0.80,
            f"max {100 * down[-1]:.1f} %")
    c.check("backlog drained after start-up (≤ 1 KB waiting)",
            max(r["down_backlog_max"] for r in rows[2:-1]) <= 1024,
            f"{max(r['down_backlog_max'] for r in rows[2:-1])} B")

    want = profile_rates(a.profile)
    stamps, status = bag_topics(f"{a.dir}/slow_link.mcap")
    for topic, key in [("state/odom", "nav_state"), ("imu/data_raw", "imu"), ("altitude", "altitude"),
                       ("mag", "mag"), ("baro", "baro")]:
        got = rate_hz(stamps.get(f"{a.ns}/{topic}", []))
        c.check(f"{topic} at the profile's rates.{key}_hz {want[key]:g} (±10 %, simulated time, from the bag)",
                abs(got - want[key]) <= 0.1 * want[key], f"{got:.1f} Hz")
    c.check("status: no CRC error and no frame lost on the link",
            status is not None and status.crc_errors == 0 and status.frames_lost == 0,
            f"crc_errors {status.crc_errors} frames_lost {status.frames_lost}" if status else "no status")

    fs, modes = collections.Counter(), []
    for r in csv.DictReader(open(f"{a.dir}/square_slow_link.csv")):
        fs[r["failsafe"]] += 1
        if not modes or modes[-1] != r["mode"]:
            modes.append(r["mode"])
    c.check("truth log: no failsafe (no setpoint-stale hold)", set(fs) == {"None"}, dict(fs))
    c.check("truth log: flew in velocity mode and ended landed and disarmed",
            "Velocity" in modes and modes[-1] == "Disarmed", modes)
    print(f"{c.passed} passed, {c.failed} failed")
    sys.exit(1 if c.failed else 0)


if __name__ == "__main__":
    main()
