#!/usr/bin/env python3
"""The ground station of the Zenoh fault test (issue 18, tests/zenoh/faults.sh): an independent
rmw_zenoh peer (PyPI eclipse-zenoh, CDR decoded by rosbags: tests/zenoh/zenoh_ros.py), a client
of router B (site B), that records the wall-clock arrival of every /uavN/status and
/uavN/state/odom sample while faults.sh cuts the link between the sites and kills router A.

While it runs it rewrites --state-file every 0.2 s, one line per vehicle, for faults.sh to poll:
    uavN <last arrival, s since the epoch> <armed 0|1> <odom z, m> <mode> <failsafe> <landed 0|1> <samples>
After --until-file appears (faults.sh has stopped the vehicles: the simulators' CSVs are
written) it reads --events (lines `<name> <epoch s>`: airborne, cut, restore, kill_a, restart_a,
stop, written by faults.sh as it acts) and checks:
  * resume: the time from the link's restore, and from router A's restart, to the next /uav2
    sample at site B (printed), within RESUME_MAX_S; nothing of /uav2 arrived while cut off;
    both topics flow again afterwards;
  * /uav3 (this peer's own site) never had a gap > GAP_MAX_S from airborne to stop;
  * on each simulator's TRUTH (--csv-dir/uavN.csv): one ground contact only, the final landing,
    in LAND, touchdown ≤ 0.5 m/s down and ≤ 0.3 m/s horizontal; never farther than PATH_MAX_M
    from its mission's own path (home → waypoints, --missions-dir/uavN.yaml); uav2 after router
    A went down: hold, then land (SetpointStale → SetpointLost) within FAULT_MAX_M of where it
    was when the fault began; uav3 never in a failsafe; landed and disarmed at the end;
  * the simulator's own truth report (--csv-dir/sitlN.log): no crash, tip-over, flyaway or
    unplanned contact.
It prints uav2's mode/failsafe sequence (the CSV's) with the faults on its clock, and a summary.
Run only inside a loopback-only network namespace (../shared/tools/netns-run).
"""
import argparse
import bisect
import math
import os
import re
import sys
import threading
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
sys.path.insert(0, os.path.join(here, "..", "lib"))

import zenoh_ros as zr  # noqa: E402
from truth import Checks, load_csv, t_of  # noqa: E402

TOPICS = ("status", "state/odom")
RESUME_MAX_S = 10.0      # data back at site B within this after the fault ends
GAP_MAX_S = 1.0          # /uav3 (same site as the peer): no gap longer than this
PATH_MAX_M = 3.0         # truth: horizontal distance from the mission's own path
FAULT_MAX_M = 3.0        # truth: uav2 from where it was when router A went down, until disarmed
TOUCH_VZ_MPS = 0.5       # truth: touchdown vertical speed
TOUCH_VH_MPS = 0.3       # truth: touchdown horizontal speed
AIRBORNE_M = 0.1         # gear above the terrain: truly airborne (the simulator's own figure)
CONTACT_M = 0.02         # gear within this of its resting height: on the ground


class Recorder:
    """Every arrival: per vehicle, a list of (wall s, topic, stamp s); the newest status/odom."""

    def __init__(self, peer, vehicles):
        self.lock = threading.Lock()
        self.arrivals = {v: [] for v in vehicles}
        self.status = {}
        self.z = {}
        self.bad = []
        store = peer.store
        for v in vehicles:
            for topic in TOPICS:
                def on_sample(sample, v=v, topic=topic):
                    wall = time.time()
                    key = str(sample.key_expr)
                    try:
                        _, _, ros_type, _ = zr.split_data_key(key)
                        msg = store.deserialize_cdr(sample.payload.to_bytes(), ros_type)
                    except Exception as e:  # noqa: BLE001 — any decoder error is a finding
                        self.bad.append((key, repr(e)[:200]))
                        return
                    with self.lock:
                        self.arrivals[v].append((wall, topic, t_of(msg.header.stamp)))
                        if topic == "status":
                            self.status[v] = msg
                        else:
                            self.z[v] = msg.pose.pose.position.z
                sub = peer.session.declare_subscriber(
                    zr.topic_wildcard(peer.domain, f"/uav{v}/{topic}"), on_sample)
                peer._keep.append(sub)

    def write_state(self, path):
        lines = []
        with self.lock:
            for v, arr in self.arrivals.items():
                st = self.status.get(v)
                lines.append(" ".join(str(x) for x in (
                    f"uav{v}", f"{arr[-1][0]:.3f}" if arr else "0",
                    int(bool(st and st.armed)), f"{self.z.get(v, 0.0):.2f}",
                    st.mode_name if st else "-", st.failsafe_name if st else "-",
                    int(bool(st and st.landed)), len(arr))))
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            f.write("\n".join(lines) + "\n")
        os.replace(tmp, path)


def read_events(path):
    ev = {}
    if os.path.exists(path):
        for line in open(path):
            parts = line.split()
            if len(parts) == 2:
                ev[parts[0]] = float(parts[1])
    return ev


def sim_at(arr, wall):
    """A vehicle's simulated time at a wall time: the nearest sample's stamp plus the wall time
    since it arrived (speed 1; arrival latency is milliseconds)."""
    walls = [a[0] for a in arr]
    i = bisect.bisect_left(walls, wall)
    best = min((j for j in (i - 1, i) if 0 <= j < len(arr)), key=lambda j: abs(walls[j] - wall))
    return arr[best][2] + (wall - walls[best])


def mission_path(path):
    """Home (0, 0) then each waypoint, (north, east) m."""
    pts = [(0.0, 0.0)]
    for m in re.finditer(r"north_m:\s*([-\d.]+),\s*east_m:\s*([-\d.]+)", open(path).read()):
        pts.append((float(m.group(1)), float(m.group(2))))
    return pts


def dist_to_polyline(p, pts):
    best = math.inf
    for a, b in zip(pts, pts[1:]):
        d = (b[0] - a[0], b[1] - a[1])
        len2 = d[0] ** 2 + d[1] ** 2
        t = 0.0 if len2 < 1e-9 else max(0.0, min(1.0, ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2))
        best = min(best, math.hypot(p[0] - a[0] - t * d[0], p[1] - a[1] - t * d[1]))
    return best


def rows_of(log):
    return [dict(zip(log.keys(), vals)) for vals in zip(*log.values())]


def contacts(rows, gear):
    """Each ground contact after true flight: (index, vertical, horizontal speed at touchdown)
    — the largest over the last AIRBORNE_M of the descent and the contact sample."""
    out, airborne, since = [], False, 0
    for i, r in enumerate(rows):
        h = r["true_agl_m"] - gear
        if h > AIRBORNE_M:
            airborne, since = True, i
        elif airborne and h < CONTACT_M:
            near = rows[since + 1:i + 1]
            vz = max(r2["true_vd_mps"] for r2 in near)
            vh = max(math.hypot(r2["true_vn_mps"], r2["true_ve_mps"]) for r2 in near)
            out.append((i, vz, vh))
            airborne = False
    return out


def transitions(rows):
    out, last = [], None
    for r in rows:
        key = (r["mode"], r["failsafe"])
        if key != last:
            out.append((r["t_s"], *key))
            last = key
    return out


def analyze(a, rec, c):
    ev = read_events(a.events)
    figs = {}
    with rec.lock:
        arr = {v: list(x) for v, x in rec.arrivals.items()}
    c.check("every sample decodes (rosbags CDR)", not rec.bad, rec.bad[:3])
    need = ("airborne", "cut", "restore", "kill_a", "restart_a", "stop")
    c.check("the timeline ran (airborne, link cut and restored, router A killed and restarted)",
            all(k in ev for k in need), sorted(ev))
    if not all(k in ev for k in need) or not arr[2] or not arr[3]:
        return figs
    u2 = arr[2]
    # ---------------------------------------------------------------- resume at site B
    for name, down, up in (("link cut", "cut", "restore"), ("router A restart", "kill_a", "restart_a")):
        before = [w for w, _, _ in u2 if w <= ev[down]]
        after = {t: min((w for w, tt, _ in u2 if w > ev[up] and tt == t), default=None) for t in TOPICS}
        during = sum(1 for w, _, _ in u2 if ev[down] + 0.5 < w < ev[up])
        first = min((w for w in after.values() if w is not None), default=None)
        resume = None if first is None else first - ev[up]
        outage = None if first is None or not before else first - before[-1]
        figs[name] = (ev[up] - ev[down], resume, outage)
        per = ", ".join(f"{t} {'—' if w is None else f'{w - ev[up]:.2f} s'}" for t, w in after.items())
        print(f"RESUME {name}: /uav2 at site B {resume if resume is None else f'{resume:.2f}'} s "
              f"after the {'restore' if up == 'restore' else 'restart'} ({per}); fault "
              f"{ev[up] - ev[down]:.1f} s, no data for {outage if outage is None else f'{outage:.2f}'} s",
              flush=True)
        c.check(f"{name}: /uav2 (site A) unheard at site B while cut off", during == 0,
                f"{during} samples in the fault")
        c.check(f"{name}: /uav2 resumes at site B (both topics) within {RESUME_MAX_S:.0f} s, "
                "bridge not restarted", resume is not None and all(after.values())
                and resume <= RESUME_MAX_S, f"resume {resume if resume is None else f'{resume:.2f} s'}")
    later = sum(1 for w, t, _ in u2 if t == "status" and w > ev["restart_a"] + RESUME_MAX_S)
    c.check("/uav2 status keeps flowing after the resume", later >= 10, f"{later} status samples")
    # ---------------------------------------------------------------- uav3: no gap at site B
    w3 = [w for w, t, _ in arr[3] if t == "status" and ev["airborne"] <= w <= ev["stop"]]
    gaps = [b - x for x, b in zip(w3, w3[1:])]
    gap3 = max(gaps, default=math.inf)
    wo = [w for w, t, _ in arr[3] if t == "state/odom" and ev["airborne"] <= w <= ev["stop"]]
    gap3o = max((b - x for x, b in zip(wo, wo[1:])), default=math.inf)
    figs["uav3 gap"] = (gap3, gap3o)
    c.check(f"/uav3 (the peer's site B) never had a gap > {GAP_MAX_S:.0f} s through both faults",
            len(w3) > 50 and gap3 <= GAP_MAX_S,
            f"{len(w3)} status samples, longest gap status {gap3:.3f} s, odom {gap3o:.3f} s")
    # ---------------------------------------------------------------- truth
    for v in (2, 3):
        truth_checks(a, c, v, arr[v], ev, figs)
    return figs


def truth_checks(a, c, v, arr, ev, figs):
    path = os.path.join(a.csv_dir, f"uav{v}.csv")
    if not os.path.exists(path):
        c.check(f"uav{v}: truth CSV written", False, path)
        return
    rows = rows_of(load_csv(path))
    gear = rows[0]["true_agl_m"]
    n0, e0 = rows[0]["true_n_m"], rows[0]["true_e_m"]
    cs = contacts(rows, gear)
    last = rows[-1]
    modes = [(rows[i]["mode"], vz, vh) for i, vz, vh in cs]
    ok_touch = len(cs) == 1 and rows[cs[0][0]]["mode"] == "Land" and cs[0][1] <= TOUCH_VZ_MPS \
        and cs[0][2] <= TOUCH_VH_MPS
    c.check(f"uav{v} truth: one ground contact, the final landing in LAND, touchdown ≤ "
            f"{TOUCH_VZ_MPS} m/s down, ≤ {TOUCH_VH_MPS} m/s horizontal", ok_touch,
            "; ".join(f"t={rows[i]['t_s']:.2f} s {m}: down {vz:.2f} m/s, horizontal {vh:.2f} m/s"
                      for (i, vz, vh), (m, _, _) in zip(cs, modes)) or "no contact")
    c.check(f"uav{v} truth: landed and disarmed at the end", last["mode"] == "Disarmed"
            and last["armed"] == 0 and last["true_agl_m"] - gear < 0.05,
            f"mode {last['mode']}, armed {int(last['armed'])}, gear {last['true_agl_m'] - gear:.3f} m "
            "above rest")
    pts = mission_path(os.path.join(a.missions_dir, f"uav{v}.yaml"))
    fly = [r for r in rows if r["true_agl_m"] - gear > AIRBORNE_M]
    off = max((dist_to_polyline((r["true_n_m"] - n0, r["true_e_m"] - e0), pts) for r in fly), default=math.inf)
    top = max((r["true_agl_m"] - gear for r in rows), default=0.0)
    c.check(f"uav{v} truth: never > {PATH_MAX_M:.0f} m from its mission's path (no flyaway)",
            fly and off <= PATH_MAX_M, f"max {off:.2f} m, highest {top:.2f} m above ground")
    fs = sorted({r["failsafe"] for r in rows} - {"None"})
    figs[f"uav{v}"] = dict(contact=cs[0][1:] if cs else None, n_contacts=len(cs), off=off,
                           end=last["mode"], failsafes=fs)
    report = os.path.join(a.csv_dir, f"sitl{v}.log")
    text = open(report).read() if os.path.exists(report) else ""
    m = re.search(r"ground contacts (\d+) \(unplanned (\d+)\), crash/tip-over (\w+), flyaway (\w+)", text)
    c.check(f"uav{v} simulator's truth report: no crash, tip-over, flyaway or unplanned contact",
            m and m.group(2) == "0" and m.group(3) == "no" and m.group(4) == "no",
            m.group(0) if m else "no report in sitl log")
    if v == 3:
        c.check("uav3 (site B) never in a failsafe: the faults left its site alone", not fs, fs)
        return
    # uav2: the router fault on the simulator's clock
    tk, tr = sim_at(arr, ev["kill_a"]), sim_at(arr, ev["restart_a"])
    tc, to = sim_at(arr, ev["cut"]), sim_at(arr, ev["restore"])
    print(f"uav2 mode/failsafe sequence (CSV, simulator's clock; link cut {tc:.2f}–{to:.2f} s, "
          f"router A down {tk:.2f}–{tr:.2f} s):")
    for t, mode, f in transitions(rows):
        print(f"    t={t:7.2f} s  {mode:<9} {f}")
    in_cut = sorted({r["failsafe"] for r in rows if tc <= r["t_s"] <= to + 2.0} - {"None"})
    c.check("uav2: no failsafe during the link cut (its mission node is at its own site)",
            not in_cut, in_cut)
    seq = [(mode, f) for t, mode, f in transitions(rows) if t >= tk]
    want = [("Hold", "SetpointStale"), ("Land", "SetpointLost"), ("Disarmed", "SetpointLost")]
    it = iter(seq)
    c.check("uav2 after router A went down: the MCU's failsafes hold, then land "
            "(SetpointStale → SetpointLost), then disarm", all(w in it for w in want),
            " → ".join(f"{m}/{f}" for m, f in seq))
    k = min(range(len(rows)), key=lambda i: abs(rows[i]["t_s"] - tk))
    p0 = (rows[k]["true_n_m"], rows[k]["true_e_m"])
    hold = next((r for r in rows[k:] if r["mode"] == "Hold"), rows[k])
    during = [r for r in rows[k:] if r["armed"] > 0.5]
    far = max((math.hypot(r["true_n_m"] - p0[0], r["true_e_m"] - p0[1]) for r in during), default=0.0)
    far_h = max((math.hypot(r["true_n_m"] - hold["true_n_m"], r["true_e_m"] - hold["true_e_m"])
                 for r in during), default=0.0)
    v0 = math.hypot(rows[k]["true_vn_mps"], rows[k]["true_ve_mps"])
    land = next((r for r in rows[k:] if r["mode"] == "Land"), None)
    figs["uav2 fault"] = dict(far=far, far_hold=far_h, v0=v0, alt0=rows[k]["true_agl_m"] - gear,
                              hold_after=hold["t_s"] - tk,
                              land_after=None if land is None else land["t_s"] - tk,
                              mode0=rows[k]["mode"])
    c.check(f"uav2 truth: within {FAULT_MAX_M:.0f} m of where it was when router A went down, "
            "until disarmed", during and far <= FAULT_MAX_M,
            f"max {far:.2f} m (from the MCU's hold point {far_h:.2f} m); at the fault: "
            f"{rows[k]['mode']} at {v0:.2f} m/s, {rows[k]['true_agl_m'] - gear:.2f} m up; hold "
            f"{hold['t_s'] - tk:.2f} s and land "
            f"{'—' if land is None else format(land['t_s'] - tk, '.2f')} s after it")


def summary(figs):
    print("---- summary (zenoh faults)")
    print(f"{'fault':<18} {'length s':>9} {'resume s':>9} {'no data s':>10}")
    for name in ("link cut", "router A restart"):
        if name in figs:
            ln, rs, od = figs[name]
            f = lambda x: "—" if x is None else f"{x:.2f}"  # noqa: E731
            print(f"{name:<18} {ln:>9.1f} {f(rs):>9} {f(od):>10}")
    if "uav3 gap" in figs:
        print(f"/uav3 at site B: longest gap status {figs['uav3 gap'][0]:.3f} s, odom {figs['uav3 gap'][1]:.3f} s")
    for v in (2, 3):
        d = figs.get(f"uav{v}")
        if d:
            touch = "—" if not d["contact"] else f"{d['contact'][0]:.2f} down / {d['contact'][1]:.2f} horiz m/s"
            print(f"uav{v}: contacts {d['n_contacts']}, touchdown {touch}, max off path "
                  f"{d['off']:.2f} m, end {d['end']}, failsafes {d['failsafes'] or 'none'}")
    d = figs.get("uav2 fault")
    if d:
        land = "—" if d["land_after"] is None else f"{d['land_after']:.2f}"
        print(f"uav2 router fault: {d['mode0']} at {d['v0']:.2f} m/s {d['alt0']:.2f} m up; hold after "
              f"{d['hold_after']:.2f} s, land after {land} s; max {d['far']:.2f} m from "
              f"the fault's start ({d['far_hold']:.2f} m from the hold point)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--connect", default="tcp/127.0.0.1:7448", help="this peer's router (site B)")
    ap.add_argument("--vehicles", default="2,3")
    ap.add_argument("--state-file", required=True)
    ap.add_argument("--until-file", required=True)
    ap.add_argument("--events", required=True)
    ap.add_argument("--csv-dir", required=True)
    ap.add_argument("--missions-dir", required=True)
    ap.add_argument("--timeout", type=float, default=150)
    a = ap.parse_args()
    vehicles = [int(x) for x in a.vehicles.split(",")]
    peer = zr.RosPeer(connect=a.connect, node="ground_station")
    rec = Recorder(peer, vehicles)
    t0 = time.monotonic()
    while not os.path.exists(a.until_file) and time.monotonic() - t0 < a.timeout:
        rec.write_state(a.state_file)
        time.sleep(0.2)
    peer.close()
    c = Checks()
    figs = analyze(a, rec, c)
    summary(figs)
    return c.done()


if __name__ == "__main__":
    sys.exit(main())
