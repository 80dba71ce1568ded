#!/usr/bin/env python3
"""Command safety and parameter envelopes through the real pty + bridge (issue 14, points 1, 2).

fcc-sitl --link-pty ⇄ fcc-bridge ⇄ this independent Cyclone DDS peer:
  params  SetParameters (rcl_interfaces, as `ros2 param set` calls it) with ttl_ms=65535,
          max_speed_mps=-0.0 and 5e-324, max_stamp_age_ms=-0.0 and 5e-324: each refused with
          its range in SetParametersResult.reason, the value in use unchanged; a value inside
          the range accepted.
  flight  arm, climb to ~5 m, hold; then one cmd/arm false, one cmd/mode "disarm", cmd/arm
          toggled true/false at 100 Hz for 4 s (wall): on the simulator's CSV truth the vehicle
          stays armed, in hold, its true altitude within ±0.5 m of the hold height; on `status`
          every refusal counted (command_rejects grows by the disarms that reached the MCU,
          last_reject not_landed), armed throughout. Then cmd/kill "kill" and "KILL " are
          refused by the bridge (counted on /diagnostics, motors still running) and "KILL"
          stops the motors: status failsafe emergency_kill, disarmed; CSV disarmed.
  sim time  use_sim_time set at run time on a second bridge (clock_source:=sync, fcc-fake-mcu):
          IMU stamps follow the peer's /clock while true, the Linux clock when false again.
Prints its figures; exit 0 = every check passed. Run ONLY inside a loopback-only network
namespace (tests/e2e/command_safety.sh does that).
usage: command_safety.py [--bin DIR] [--speed N] [--keep DIR]
"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "dds"))
sys.path.insert(0, HERE)

from robust_stack import Checks, Peer, Procs, bridge_argv, load_csv, stack_start  # noqa: E402

P_BOOL, P_INT, P_DOUBLE = 1, 2, 3
HOLD_TOL_M = 0.5
TOGGLE_S = 4.0      # wall seconds of 100 Hz arm toggling


def params_checks(c, peer, fq):
    import ros_srv_types as st
    from peer_ros import Service
    set_p = Service(peer.dp, f"{fq}/set_parameters", st.SetParametersRequest, st.SetParametersResponse)
    get_p = Service(peer.dp, f"{fq}/get_parameters", st.GetParametersRequest, st.GetParametersResponse)

    def set_(name, value):
        r = set_p.call(st.SetParametersRequest(parameters=[st.Parameter(name, value)]))
        return r.results[0] if r and r.results else None

    def get(name):
        r = get_p.call(st.GetParametersRequest(names=[name]))
        return r.values[0] if r and r.values else None

    cases = [("ttl_ms", st.ParameterValue(type=P_INT, integer_value=65535), "[50, 3000]"),
             ("ttl_ms", st.ParameterValue(type=P_INT, integer_value=0), "[50, 3000]"),
             ("max_speed_mps", st.ParameterValue(type=P_DOUBLE, double_value=-0.0), "[0.1, 30]"),
             ("max_speed_mps", st.ParameterValue(type=P_DOUBLE, double_value=5e-324), "[0.1, 30]"),
             ("max_speed_mps", st.ParameterValue(type=P_DOUBLE, double_value=float("inf")), "[0.1, 30]"),
             ("max_stamp_age_ms", st.ParameterValue(type=P_DOUBLE, double_value=-0.0), "[10, 5000]"),
             ("max_stamp_age_ms", st.ParameterValue(type=P_DOUBLE, double_value=5e-324), "[10, 5000]"),
             ("max_stamp_future_ms", st.ParameterValue(type=P_DOUBLE, double_value=float("nan")), "[10, 5000]")]
    for name, v, rng in cases:
        before = get(name)
        r = set_(name, v)
        after = get(name)
        shown = v.integer_value if v.type == P_INT else v.double_value
        print(f"param set {name}={shown!r}: {'refused' if r and not r.successful else 'ACCEPTED'}: "
              f"{r.reason if r else 'no answer'}", flush=True)
        c.check(f"set {name}={shown!r} refused with the range {rng} in the reason",
                r is not None and not r.successful and rng in r.reason, r)
        val = (lambda x: None if x is None else (x.integer_value if x.type == P_INT else x.double_value))
        c.check(f"  {name} unchanged after the refused set", before is not None and after == before,
                (val(before), val(after)))
    r = set_("ttl_ms", st.ParameterValue(type=P_INT, integer_value=500))
    c.check("set ttl_ms=500 (inside the range) accepted", r is not None and r.successful, r)
    v = get("ttl_ms")
    c.check("  ttl_ms reads back 500", v is not None and v.integer_value == 500, v and v.integer_value)
    r = set_("ttl_ms", st.ParameterValue(type=P_INT, integer_value=300))
    c.check("set ttl_ms=300 accepted (back to the default)", r is not None and r.successful, r)


def sim_time_checks(c, a, tmp, peer):
    """use_sim_time set at run time on a bridge with clock_source:=sync (fcc-fake-mcu on a pty):
    the IMU stamps follow the peer's /clock (1000 s + wall) while true, the Linux clock again
    when false. ros2-client keeps use_sim_time itself; the bridge reads it back and applies it."""
    import ros_srv_types as st
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    from peer_ros import Service
    pr = Procs(tmp)
    rt = peer.rt
    clock_w = DataWriter(peer.dp, Topic(peer.dp, "rt/clock", st.Clock))
    set_p = Service(peer.dp, "/fcc/fcc_bridge/set_parameters", st.SetParametersRequest, st.SetParametersResponse)
    t0 = time.time()

    def tick():
        el = time.time() - t0
        clock_w.write(st.Clock(rt.Time(sec=1000 + int(el), nanosec=int((el % 1) * 1e9))))

    def stamps_after(wall):
        return [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for w, m in peer.got["imu/data_raw"] if w > wall]

    def set_sim(on):
        r = set_p.call(st.SetParametersRequest(parameters=[st.Parameter(
            "use_sim_time", st.ParameterValue(type=P_BOOL, bool_value=on))]))
        return r.results[0] if r and r.results else None
    try:
        fake = pr.start("fake", [f"{a.bin}/fcc-fake-mcu", "--duration", "60"])
        pty = None
        for _ in range(100):
            out = pr.log("fake", "out")
            if out.startswith("PTY"):
                pty = out.split()[1]
                break
            time.sleep(0.05)
        if not c.check("sim time: fcc-fake-mcu gives its pty", pty is not None, pr.log("fake")):
            return
        bridge = pr.start("bridge_sync", [f"{a.bin}/fcc-bridge", "--device", pty, "--ros-args", "-r", "__ns:=/fcc"])
        c.check("sim time: IMU from the bridge (clock_source sync)",
                peer.wait(lambda: len(stamps_after(t0)) > 20, 20, "imu", tick), len(stamps_after(t0)))
        peer.sleep(1.0, tick)
        w = time.time()
        peer.sleep(1.0, tick)
        before = stamps_after(w)
        r = set_sim(True)
        c.check("sim time: set use_sim_time true accepted", r is not None and r.successful, r)
        peer.sleep(0.5, tick)
        w = time.time()
        peer.sleep(1.0, tick)
        during = stamps_after(w)
        r = set_sim(False)
        c.check("sim time: set use_sim_time false accepted", r is not None and r.successful, r)
        peer.sleep(0.5, tick)
        w = time.time()
        peer.sleep(1.0, tick)
        after = stamps_after(w)
        now = time.time()
        sim = 1000 + now - t0
        fmt = (lambda x: f"{len(x)} stamps, {min(x):.2f}..{max(x):.2f} s" if x else "none")
        print(f"sim time: IMU stamps before: {fmt(before)}; with use_sim_time true (peer /clock ≈ {sim:.1f} s): "
              f"{fmt(during)}; after false: {fmt(after)} (Linux clock {now:.2f})", flush=True)
        c.check("sim time: before, IMU stamped with the Linux clock",
                bool(before) and all(abs(t - now) < 10 for t in before), fmt(before))
        c.check("sim time: use_sim_time true at run time → IMU stamped with the peer's /clock",
                bool(during) and all(1000 <= t <= sim + 1 for t in during), fmt(during))
        c.check("sim time: use_sim_time false again → the Linux clock",
                bool(after) and all(abs(t - now) < 10 for t in after), fmt(after))
        c.check("sim time: bridge still running", bridge.poll() is None, bridge.poll())
        pr.stop(bridge, signal.SIGINT)
        pr.stop(fake)
    finally:
        pr.cleanup()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.environ.get("FCC_BIN_DIR", f"{ROOT}/target/release"))
    ap.add_argument("--speed", type=float, default=2.0)
    ap.add_argument("--keep", help="keep logs and the CSV in this directory")
    a = ap.parse_args()
    tmp = a.keep or tempfile.mkdtemp(prefix="command_safety_")
    os.makedirs(tmp, exist_ok=True)
    print(f"=== command safety (speed {a.speed}, logs in {tmp})", flush=True)
    c = Checks("safety")
    pr = Procs(tmp)
    peer = Peer()
    from cyclonedds.core import Policy, Qos
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
    rt = peer.rt
    reliable = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(200))
    kill_w = DataWriter(peer.dp, Topic(peer.dp, "rt/fcc/cmd/kill", rt.String), qos=reliable)
    csv_path = os.path.join(tmp, "safety.csv")
    ev = {}
    fig = {}
    t_wall = time.time()
    try:
        sitl, _, dev = stack_start(pr, a, tmp, f"{ROOT}/launch_configs/scenarios/hover.yaml", csv_path)
        bridge = pr.start("bridge", bridge_argv(a, dev))
        if not c.check("status and /clock from the bridge",
                       peer.wait(lambda: peer.st is not None and peer.now is not None, 30, "status and /clock")):
            raise SystemExit(1)
        peer.sleep(1.0)   # parameter services discovered, parameters synced with the MCU

        # ---------------------------------------------------------------- (2) parameter envelopes
        params_checks(c, peer, "/fcc/fcc_bridge")

        # ---------------------------------------------------------------- (1) command safety
        if not c.check("armed through cmd/arm", peer.arm(), ""):
            raise SystemExit(1)
        peer.mode("velocity")
        peer.fly_for(5.0, (0.0, 0.0, 1.0))       # climb ≈ 5 m
        peer.fly_for(2.0, (0.0, 0.0, 0.0))
        peer.mode("hold")
        c.check("cmd/mode hold → hold", peer.wait(lambda: peer.st.mode_name == "hold", 5, "hold"), peer.st.mode_name)
        peer.sleep(2.0 / a.speed + 1.0)
        ev["hold_ref0"] = peer.now
        peer.sleep(2.0 / a.speed)
        ev["hold_ref1"] = peer.now
        st0 = peer.st
        r0 = st0.command_rejects
        print(f"hold at sim {ev['hold_ref0']:.2f} s; status: mode {st0.mode_name}, armed {st0.armed}, "
              f"landed {st0.landed}, command_rejects {r0}, last_reject '{st0.last_reject}'", flush=True)
        c.check("airborne in hold before the disarm attempts (status: armed, not landed)",
                st0.armed and not st0.landed and st0.mode_name == "hold", (st0.armed, st0.landed, st0.mode_name))

        # one cmd/arm false
        ev["first_cmd"] = peer.now
        tw_first = time.time()
        peer.arm_w.write(rt.Bool(data=False))
        ok = peer.wait(lambda: peer.st.command_rejects > r0, 3, "command_rejects to grow after cmd/arm false")
        st1 = peer.st
        print(f"cmd/arm false: command_rejects {r0} -> {st1.command_rejects}, last_reject '{st1.last_reject}', "
              f"armed {st1.armed}, mode {st1.mode_name}", flush=True)
        c.check("cmd/arm false in the air: refused and counted (command_rejects +1, last_reject not_landed)",
                ok and st1.command_rejects == r0 + 1 and st1.last_reject == "not_landed",
                (st1.command_rejects - r0, st1.last_reject))
        peer.sleep(1.0)
        c.check("  still armed, in hold", peer.st.armed and peer.st.mode_name == "hold", (peer.st.armed, peer.st.mode_name))

        # one cmd/mode "disarm"
        r1 = peer.st.command_rejects
        peer.mode("disarm")
        ok = peer.wait(lambda: peer.st.command_rejects > r1, 3, "command_rejects to grow after cmd/mode disarm")
        st2 = peer.st
        print(f"cmd/mode disarm: command_rejects {r1} -> {st2.command_rejects}, last_reject '{st2.last_reject}', "
              f"armed {st2.armed}, mode {st2.mode_name}", flush=True)
        c.check("cmd/mode \"disarm\" in the air: refused and counted (+1, not_landed)",
                ok and st2.command_rejects == r1 + 1 and st2.last_reject == "not_landed",
                (st2.command_rejects - r1, st2.last_reject))
        peer.sleep(1.0)
        c.check("  still armed, in hold", peer.st.armed and peer.st.mode_name == "hold", (peer.st.armed, peer.st.mode_name))

        # cmd/arm toggled at 100 Hz
        r2 = peer.st.command_rejects
        f2 = peer.st.commands_forwarded
        n_true = n_false = 0
        t_start = time.time()
        k = 0
        while True:
            t_next = t_start + k * 0.01
            if t_next - t_start >= TOGGLE_S:
                break
            while time.time() < t_next:
                time.sleep(0.0005)
            arm = k % 2 == 0
            peer.arm_w.write(rt.Bool(data=arm))
            n_true += arm
            n_false += not arm
            if k % 10 == 0:
                peer.pump()
            k += 1
        rate = k / (time.time() - t_start)
        peer.sleep(1.5)
        st3 = peer.st
        dr = st3.command_rejects - r2
        df = st3.commands_forwarded - f2
        toggle_status = [s for w, s in peer.got["status"] if w >= t_start]
        print(f"arm toggle: sent {n_true} true + {n_false} false at {rate:.1f} Hz for {TOGGLE_S} s wall; "
              f"bridge forwarded {df} commands; MCU command_rejects +{dr}, last_reject '{st3.last_reject}'; "
              f"status samples {len(toggle_status)}, all armed: {all(s.armed for s in toggle_status)}", flush=True)
        fig["toggle"] = (n_true, n_false, rate, df, dr)
        c.check("toggle ran at ~100 Hz", 90.0 <= rate <= 101.0, f"{rate:.1f} Hz")
        if df == n_true + n_false:
            c.check("every forwarded disarm refused and counted (MCU command_rejects + = disarms sent)",
                    dr == n_false and st3.last_reject == "not_landed", (dr, n_false, st3.last_reject))
        else:
            # Some commands did not reach the MCU: at least (forwarded − arms) of them were disarms.
            c.check("every forwarded disarm refused and counted (bounds, not all forwarded)",
                    max(df - n_true, 1) <= dr <= min(n_false, df) and st3.last_reject == "not_landed",
                    (dr, df, n_true, n_false, st3.last_reject))
        c.check("status armed and in hold throughout the toggling",
                bool(toggle_status) and all(s.armed and s.mode_name == "hold" for s in toggle_status),
                sorted({(s.armed, s.mode_name) for s in toggle_status}))
        ev["last_cmd"] = peer.now

        # cmd/kill: wrong texts refused by the bridge, "KILL" stops the motors
        d0 = peer.diag_values("fcc_bridge: setpoints")
        b0 = int(d0.get("command_rejects", "-1"))
        for text in ("kill", "KILL "):
            kill_w.write(rt.String(data=text))
        peer.sleep(1.5)
        d1 = peer.diag_values("fcc_bridge: setpoints")
        b1 = int(d1.get("command_rejects", "-1"))
        st4 = peer.st
        print(f"cmd/kill 'kill', 'KILL ': bridge command_rejects {b0} -> {b1}; status armed {st4.armed}, "
              f"failsafe '{st4.failsafe_name}'", flush=True)
        c.check("cmd/kill with a wrong text refused by the bridge (its command_rejects +2 on /diagnostics)",
                b0 >= 0 and b1 == b0 + 2, (b0, b1))
        c.check("  motors still running (armed, no emergency_kill)",
                st4.armed and st4.failsafe_name != "emergency_kill", (st4.armed, st4.failsafe_name))
        ev["kill"] = peer.now
        tk = time.time()
        kill_w.write(rt.String(data="KILL"))
        ok = peer.wait(lambda: peer.st.failsafe_name == "emergency_kill" and not peer.st.armed, 3,
                       "emergency_kill on status")
        st5 = peer.st
        print(f"cmd/kill 'KILL': status failsafe '{st5.failsafe_name}', armed {st5.armed}, mode {st5.mode_name} "
              f"after {time.time() - tk:.3f} s wall", flush=True)
        c.check("cmd/kill \"KILL\": status failsafe emergency_kill, disarmed", ok, (st5.failsafe_name, st5.armed))
        peer.sleep(1.0)
        src = pr.stop(sitl)
        brc = pr.stop(bridge)
        c.check("fcc-sitl and fcc-bridge stop cleanly", src == 0 and brc == 0, (src, brc))
    finally:
        pr.cleanup()

    # ---------------------------------------------------------------- CSV truth
    rows = load_csv(csv_path)
    ref = [-r["true_d_m"] for r in rows if ev["hold_ref0"] <= r["t_s"] <= ev["hold_ref1"]]
    hold_alt = sum(ref) / len(ref) if ref else float("nan")
    win = [r for r in rows if ev["first_cmd"] <= r["t_s"] <= ev["kill"]]
    dev = [-r["true_d_m"] - hold_alt for r in win]
    print(f"CSV truth: hold height {hold_alt:.3f} m (mean over sim {ev['hold_ref0']:.2f}..{ev['hold_ref1']:.2f} s); "
          f"from the first disarm attempt (sim {ev['first_cmd']:.2f} s) to the kill ({ev['kill']:.2f} s): "
          f"{len(win)} samples, altitude error min {min(dev):+.3f} max {max(dev):+.3f} m, "
          f"armed {sorted({int(r['armed']) for r in win})}, modes {sorted({r['mode'] for r in win})}", flush=True)
    c.check("CSV: hold height ≈ 5 m (4..6.5 m)", 4.0 <= hold_alt <= 6.5, f"{hold_alt:.3f} m")
    c.check(f"CSV: true altitude within ±{HOLD_TOL_M} m of the hold height from the first disarm attempt to the kill",
            len(win) > 100 and max(abs(d) for d in dev) <= HOLD_TOL_M, f"max |error| {max(abs(d) for d in dev):.3f} m")
    c.check("CSV: armed and in Hold throughout (never disarmed or re-armed)",
            all(r["armed"] == 1.0 and r["mode"] == "Hold" for r in win),
            sorted({(int(r["armed"]), r["mode"]) for r in win}))
    after = [r for r in rows if r["t_s"] >= ev["kill"] + 0.5]
    c.check("CSV: after cmd/kill \"KILL\" the motors stopped (disarmed, failsafe EmergencyKill)",
            bool(after) and all(r["armed"] == 0.0 for r in after) and after[-1]["failsafe"] == "EmergencyKill",
            (sorted({int(r["armed"]) for r in after}), after[-1]["failsafe"] if after else None))
    sim_time_checks(c, a, tmp, peer)
    print(f"wall time {time.time() - t_wall:.1f} s", flush=True)
    rc = c.done()
    if not a.keep and rc == 0:
        subprocess.run(["rm", "-rf", tmp])
    elif rc != 0:
        print(f"logs kept in {tmp}")
    return rc


if __name__ == "__main__":
    sys.exit(main())
