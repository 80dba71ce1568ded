#!/usr/bin/env python3
"""Heading and yaw-rate setpoints through the real pty + bridge (issue 17, part 3).

fcc-sitl --link-pty ⇄ fcc-bridge ⇄ this independent Cyclone DDS peer, which flies the vehicle
itself (cmd/arm, cmd/mode, TwistStamped setpoints in `map`, ENU):
  rate     hovering at ~5 m, `twist.angular.z` +0.3 rad/s (counter-clockwise seen from above)
           for 10 s, then −0.5 rad/s for 8 s: on the simulator's CSV truth the vehicle's true yaw
           turns at the commanded NED rate (−angular.z) within ±10 % (least-squares slope of the
           unwrapped true yaw, after 2 s of spin-up).
  heading  `setpoint/heading` (geometry_msgs/QuaternionStamped, frame `map`, ENU yaw 0 = east =
           NED 90°) at 10 Hz with the velocity setpoints: 5 s to turn, then a 10 s leg north at
           2 m/s (sideways: the nose stays east) — true heading within 3° RMS of 90° on the leg.
  refusals a non-unit and a NaN quaternion and a heading in `camera`: refused by the bridge,
           counted on /diagnostics (setpoint_rejects +3, last reason `heading: …`); the bridge's
           counters show the yaw-rate and heading setpoints it forwarded.
Then it lands.
  mission  fcc-mission flies a one-leg mission (25 m north at 3 m/s) with `yaw_deg: 90`, which it
           publishes on `setpoint/heading`: the true heading within 3° RMS of 90° while cruising
           (true horizontal speed ≥ 2.4 m/s) — sideways, the nose east.
Prints its figures; exit 0 = every check passed. Run ONLY inside a loopback-only
network namespace (tests/e2e/heading.sh does that).
usage: heading.py [--bin DIR] [--speed N] [--keep DIR]
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "dds"))
sys.path.insert(0, HERE)

from robust_stack import Checks, Peer, Procs, bridge_argv, load_csv, no_panic, stack_start  # noqa: E402

RATES_Z_UP = ((0.3, 10.0), (-0.5, 8.0))   # (angular.z rad/s, sim seconds)
SPIN_UP_S = 2.0
RATE_TOL = 0.10
HEADING_ENU_DEG = 0.0                     # east: NED 90°
HEADING_RMS_MAX_DEG = 3.0
TURN_S, LEG_S, LEG_SPEED = 5.0, 10.0, 2.0


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def slope(ts, ys):
    n = len(ts)
    mt, my = sum(ts) / n, sum(ys) / n
    return sum((t - mt) * (y - my) for t, y in zip(ts, ys)) / sum((t - mt) ** 2 for t in ts)


def unwrap(ys):
    out = [ys[0]]
    for y in ys[1:]:
        out.append(out[-1] + wrap(y - out[-1]))
    return out


class Flyer:
    """Streams velocity setpoints (50 Hz wall) with a yaw rate, and headings (10 Hz wall)."""

    def __init__(self, peer):
        from cyclonedds.core import Policy, Qos
        from cyclonedds.pub import DataWriter
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration
        self.peer = peer
        rt = peer.rt
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(50))
        self.heading_w = DataWriter(peer.dp, Topic(peer.dp, "rt/fcc/setpoint/heading", rt.QuaternionStamped), qos=qos)

    def stamp(self):
        rt = self.peer.rt
        sec = int(self.peer.now)
        return rt.Time(sec=sec, nanosec=int((self.peer.now - sec) * 1e9))

    def heading(self, q_wxyz, frame="map"):
        rt = self.peer.rt
        w, x, y, z = q_wxyz
        self.heading_w.write(rt.QuaternionStamped(rt.Header(self.stamp(), frame), rt.Quaternion(x=x, y=y, z=z, w=w)))

    def fly(self, sim_s, v_enu, yaw_rate_z=0.0, heading_enu_deg=None, wall_limit=60):
        rt = self.peer.rt
        t0, tw, last_h = self.peer.now, time.time(), 0.0
        while self.peer.now - t0 < sim_s and time.time() - tw < wall_limit:
            if heading_enu_deg is not None and time.time() - last_h >= 0.1:
                h = 0.5 * math.radians(heading_enu_deg)
                self.heading((math.cos(h), 0.0, 0.0, math.sin(h)))
                last_h = time.time()
            self.peer.sp.write(rt.TwistStamped(rt.Header(self.stamp(), "map"),
                                               rt.Twist(rt.Vector3(*v_enu), rt.Vector3(0.0, 0.0, yaw_rate_z))))
            time.sleep(0.02)
            self.peer.pump()


MISSION_YAML = """takeoff_alt_m: 5.0
speed_mps: 3.0
accel_limit_mps2: 1.0
accept_radius_m: 0.5
hold_s: 1.0
yaw_deg: 90.0
land_at_end: true
waypoints:
  - { north_m: 25.0, east_m: 0.0, alt_m: 5.0 }
"""


def heading_errors_deg(rows, want_rad):
    errs = [math.degrees(wrap(r["true_yaw_rad"] - want_rad)) for r in rows]
    rms = math.sqrt(sum(e * e for e in errs) / len(errs)) if errs else float("nan")
    return rms, max((abs(e) for e in errs), default=float("nan"))


def mission_flight(a, tmp, c, peer):
    """fcc-mission with yaw_deg 90 through the bridge: the heading held on the CSV truth."""
    from robust_stack import mission_argv
    pr = Procs(tmp)
    mission_file = os.path.join(tmp, "heading_mission.yaml")
    with open(mission_file, "w") as f:
        f.write(MISSION_YAML)
    csv_path = os.path.join(tmp, "mission.csv")
    try:
        sitl, _, dev = stack_start(pr, a, tmp, f"{ROOT}/launch_configs/scenarios/hover.yaml", csv_path)
        bridge = pr.start("bridge_m", bridge_argv(a, dev))
        peer.sleep(1.0)
        mission = pr.start("mission", mission_argv(a, mission_file))
        try:
            mrc = mission.wait(150)
        except subprocess.TimeoutExpired:
            mrc = None
        out = pr.log("mission", "out")
        c.check("mission: fcc-mission flew it and exited 0 (landed, disarmed)", mrc == 0,
                (mrc, out.strip().splitlines()[-1:] if out else pr.log("mission")[-300:]))
        c.check("mission: no 'yaw_deg is not sent' note any more", "yaw_deg is not sent" not in out, "")
        src = pr.stop(sitl)
        pr.stop(bridge)
        c.check("mission: fcc-sitl stops cleanly", src == 0, src)
        no_panic(c, pr, ["sitl", "bridge_m", "mission"])
    finally:
        pr.cleanup()
    rows = load_csv(csv_path)
    cruise = [r for r in rows if r["mode"] == "Velocity" and math.hypot(r["true_vn_mps"], r["true_ve_mps"]) >= 2.4]
    rms, mx = heading_errors_deg(cruise, math.pi / 2)
    print(f"CSV truth: fcc-mission leg north with yaw_deg 90: {len(cruise)} cruise samples "
          f"(sim {cruise[0]['t_s'] if cruise else float('nan'):.2f}..{cruise[-1]['t_s'] if cruise else float('nan'):.2f} s), "
          f"true heading error RMS {rms:.2f}° max {mx:.2f}°", flush=True)
    c.check("mission: the leg was cruised (≥ 2 s of samples at ≥ 2.4 m/s)", len(cruise) >= 100, len(cruise))
    c.check(f"mission: true heading within {HEADING_RMS_MAX_DEG}° RMS of 90° while cruising",
            rms <= HEADING_RMS_MAX_DEG, f"{rms:.2f}°")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.environ.get("FCC_BIN_DIR", f"{ROOT}/target/release"))
    ap.add_argument("--speed", type=float, default=2.0)
    ap.add_argument("--keep", help="keep logs and the CSV in this directory")
    a = ap.parse_args()
    tmp = a.keep or tempfile.mkdtemp(prefix="heading_")
    os.makedirs(tmp, exist_ok=True)
    print(f"=== heading and yaw rate through the bridge (speed {a.speed}, logs in {tmp})", flush=True)
    c = Checks("heading")
    pr = Procs(tmp)
    peer = Peer()
    fl = Flyer(peer)
    csv_path = os.path.join(tmp, "heading.csv")
    ev = {}
    t_wall = time.time()
    try:
        sitl, _, dev = stack_start(pr, a, tmp, f"{ROOT}/launch_configs/scenarios/hover.yaml", csv_path)
        bridge = pr.start("bridge", bridge_argv(a, dev))
        if not c.check("status and /clock from the bridge",
                       peer.wait(lambda: peer.st is not None and peer.now is not None, 30, "status and /clock")):
            raise SystemExit(1)
        if not c.check("armed through cmd/arm", peer.arm(), ""):
            raise SystemExit(1)
        peer.mode("velocity")
        fl.fly(5.0, (0.0, 0.0, 1.0))        # climb ≈ 5 m
        fl.fly(2.0, (0.0, 0.0, 0.0))
        for i, (z, secs) in enumerate(RATES_Z_UP):
            ev[f"rate{i}"] = (peer.now, None)
            fl.fly(secs, (0.0, 0.0, 0.0), yaw_rate_z=z)
            ev[f"rate{i}"] = (ev[f"rate{i}"][0], peer.now)
        fl.fly(TURN_S, (0.0, 0.0, 0.0), heading_enu_deg=HEADING_ENU_DEG)
        ev["leg"] = (peer.now, None)
        fl.fly(LEG_S, (0.0, LEG_SPEED, 0.0), heading_enu_deg=HEADING_ENU_DEG)
        ev["leg"] = (ev["leg"][0], peer.now)
        fl.fly(1.0, (0.0, 0.0, 0.0), heading_enu_deg=HEADING_ENU_DEG)

        d0 = peer.diag_values("fcc_bridge: setpoints")
        for q, frame in (((2.0, 0.0, 0.0, 0.0), "map"), ((float("nan"), 0.0, 0.0, 1.0), "map"),
                         ((1.0, 0.0, 0.0, 0.0), "camera")):
            fl.heading(q, frame)
        n = (lambda d, k: int(d.get(k, "-1")))
        # /diagnostics comes at 1 Hz (wall): up to 3 s for the refusals to show.
        tw = time.time()
        while time.time() - tw < 3.0:
            fl.fly(0.1, (0.0, 0.0, 0.0))
            d1 = peer.diag_values("fcc_bridge: setpoints")
            if n(d1, "setpoint_rejects") >= n(d0, "setpoint_rejects") + 3:
                break
        print("bridge /diagnostics: " + ", ".join(f"{k} {d1.get(k)}" for k in (
            "setpoints_forwarded", "yaw_rate_setpoints", "heading_setpoints", "headings_received",
            "setpoint_rejects", "last_setpoint_reject", "mcu_setpoint_rejects")), flush=True)
        c.check("bad headings (norm 2, NaN, frame camera) refused and counted (setpoint_rejects +3)",
                n(d0, "setpoint_rejects") >= 0 and n(d1, "setpoint_rejects") == n(d0, "setpoint_rejects") + 3,
                (n(d0, "setpoint_rejects"), n(d1, "setpoint_rejects")))
        c.check("  the last refusal's reason names the heading and the frame",
                d1.get("last_setpoint_reject", "").startswith("heading: frame_id 'camera'"),
                d1.get("last_setpoint_reject"))
        c.check("yaw-rate and heading setpoints forwarded (bridge counters), none refused by the MCU",
                n(d1, "yaw_rate_setpoints") > 100 and n(d1, "heading_setpoints") > 100
                and n(d1, "mcu_setpoint_rejects") == 0,
                (n(d1, "yaw_rate_setpoints"), n(d1, "heading_setpoints"), n(d1, "mcu_setpoint_rejects")))
        peer.mode("land")
        c.check("landed and disarmed", peer.wait(lambda: not peer.st.armed, 60, "disarmed"), peer.st.mode_name)
        src = pr.stop(sitl)
        brc = pr.stop(bridge)
        c.check("fcc-sitl and fcc-bridge stop cleanly", src == 0 and brc == 0, (src, brc))
        no_panic(c, pr, ["sitl", "bridge"])
    finally:
        pr.cleanup()

    # ---------------------------------------------------------------- CSV truth
    rows = load_csv(csv_path)
    for i, (z, _) in enumerate(RATES_Z_UP):
        t0, t1 = ev[f"rate{i}"]
        win = [r for r in rows if t0 + SPIN_UP_S <= r["t_s"] <= t1]
        want = -z
        got = slope([r["t_s"] for r in win], unwrap([r["true_yaw_rad"] for r in win])) if len(win) > 100 else float("nan")
        err = (got - want) / abs(want)
        print(f"CSV truth: angular.z {z:+.2f} rad/s (NED {want:+.2f}) over sim {t0 + SPIN_UP_S:.2f}..{t1:.2f} s: "
              f"true yaw rate {got:+.4f} rad/s ({math.degrees(got):+.2f} °/s), error {100 * err:+.2f} %", flush=True)
        c.check(f"true yaw rate within ±{100 * RATE_TOL:.0f} % of the commanded {want:+.2f} rad/s",
                abs(err) <= RATE_TOL, f"{got:+.4f} rad/s")
    t0, t1 = ev["leg"]
    want = math.pi / 2 - math.radians(HEADING_ENU_DEG)
    leg = [r for r in rows if t0 <= r["t_s"] <= t1]
    rms, mx = heading_errors_deg(leg, want)
    dn = (leg[-1]["true_n_m"] - leg[0]["true_n_m"]) if leg else float("nan")
    de = (leg[-1]["true_e_m"] - leg[0]["true_e_m"]) if leg else float("nan")
    print(f"CSV truth: leg north at {LEG_SPEED} m/s with heading NED {math.degrees(want):.0f}° over sim "
          f"{t0:.2f}..{t1:.2f} s ({len(leg)} samples, moved N {dn:+.1f} m E {de:+.1f} m): true heading error "
          f"RMS {rms:.2f}° max {mx:.2f}°", flush=True)
    c.check("the leg was flown (≥ 12 m north)", dn >= 12.0, f"{dn:.1f} m")
    c.check(f"true heading within {HEADING_RMS_MAX_DEG}° RMS of 90° during the leg", rms <= HEADING_RMS_MAX_DEG,
            f"{rms:.2f}°")
    mission_flight(a, tmp, c, peer)
    print(f"wall time {time.time() - t_wall:.1f} s", flush=True)
    rc = c.done()
    if not a.keep and rc == 0:
        subprocess.run(["rm", "-rf", tmp])
    elif rc != 0:
        print(f"logs kept in {tmp}")
    return rc


if __name__ == "__main__":
    sys.exit(main())
