#!/usr/bin/env python3
"""The mission node's FollowWaypoints action (fcc_msgs/action/FollowWaypoints, issue 17) driven by
real ROS 2: rclpy's ActionClient (Jazzy, Fast DDS, the colcon-built fcc_msgs), as
`ros2 action send_goal` drives it, against fcc-sitl ⇄ fcc-bridge ⇄ fcc-mission; judged on the
simulator's truth CSV. Run by tests/ros2/run_ros2_peer.sh (part d).

Modes:
  square   the paper-A square (launch_configs/missions/square.yaml's points, speed, radius, hold,
           take-off height) as one goal in `map` metres, from the ground, landing at the end; the
           launcher (fcc-launch, tests/ros2/square_action_flight.yaml) reports its cross-track.
  goals    on one flight: (d) a lat/lon goal 250 m from home (outside the 200 m geofence) is
           refused with its reason; (a) a lat/lon waypoint goal (three points around home): its
           feedback, its result; (b) a goal canceled mid-leg; (c) a goal preempted by a second
           one that lands. Writes the events (sim time) for `check`.
  check    the events against the truth CSV: nothing moved before the refusal; the true path
           within the acceptance radius of each lat/lon point; still and ≤ 1 m drift within 1 s
           of the cancel; the preempting goal's point reached.
Times are ROS time = the simulator's (fcc-bridge -p clock_source:=mcu, the peer on
use_sim_time), so they index the CSV directly.
"""
import argparse
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))

import truth  # noqa: E402
from truth import Checks  # noqa: E402

NS = "/fcc"
ACTION = f"{NS}/mission/follow_waypoints"
# WGS-84, for the peer's own lat/lon ↔ metres (the tangent plane at a point: radii of curvature;
# the simulator's GPS uses the same approximation, fcc-mission converts through ECEF).
A_M, E2 = 6_378_137.0, 6.694_379_990_14e-3


def radii(lat_deg):
    s = math.sin(math.radians(lat_deg))
    w = math.sqrt(1 - E2 * s * s)
    return A_M * (1 - E2) / w ** 3, A_M / w  # meridian M, prime vertical N


def offset_lat_lon(lat_deg, lon_deg, north_m, east_m):
    m, n = radii(lat_deg)
    return (lat_deg + math.degrees(north_m / m),
            lon_deg + math.degrees(east_m / (n * math.cos(math.radians(lat_deg)))))


def lat_lon_to_ne(lat0, lon0, lat, lon):
    m, n = radii(lat0)
    return (math.radians(lat - lat0) * m, math.radians(lon - lon0) * n * math.cos(math.radians(lat0)))


class Client:
    """rclpy's ActionClient on the mission node's action, with the node's ROS time."""

    def __init__(self):
        from fcc_msgs.action import FollowWaypoints
        from rclpy.action import ActionClient
        from ros_cli import Peer
        self.T = FollowWaypoints
        self.peer = Peer("rclpy_actions", use_sim_time=True)
        self.node = self.peer.main
        self.client = ActionClient(self.node, FollowWaypoints, ACTION)
        from fcc_msgs.action import GoTo, Land, Takeoff
        self.other = {k: (T, ActionClient(self.node, T, f"{NS}/mission/{k}"))
                      for k, T in (("go_to", GoTo), ("takeoff", Takeoff), ("land", Land))}
        self.status = None
        self.home = None
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from ros_cli import msg_class
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(msg_class("sensor_msgs/msg/NavSatFix"), f"{NS}/home",
                                      lambda m: setattr(self, "home", m), latched)
        self.node.create_subscription(msg_class("fcc_msgs/msg/Status"), f"{NS}/status",
                                      lambda m: setattr(self, "status", m), 10)

    def now(self):
        return self.node.get_clock().now().nanoseconds * 1e-9

    def ready(self, secs=60):
        self.peer.wait(lambda: self.client.server_is_ready(), secs, f"the action server {ACTION}")
        for k, (_, cl) in self.other.items():
            self.peer.wait(cl.server_is_ready, secs, f"the action server {NS}/mission/{k}")
        self.peer.wait(lambda: self.status is not None and self.now() > 0, secs, "status and /clock")

    def goal(self, points, speed=3.0, radius=0.0, hold=0.0, takeoff=0.0, land=False, heading=math.nan):
        from fcc_msgs.msg import Waypoint
        g = self.T.Goal()
        for p in points:
            w = Waypoint()
            if p[0] == "global":
                w.frame = Waypoint.FRAME_GLOBAL
                w.latitude_deg, w.longitude_deg, w.altitude_m = p[1:]
            else:
                w.frame = Waypoint.FRAME_LOCAL_ENU
                w.x_m, w.y_m, w.z_m = p[1:]
            g.waypoints.append(w)
        g.speed_mps, g.accept_radius_m, g.hold_s = float(speed), float(radius), float(hold)
        g.takeoff_alt_m, g.land_at_end = float(takeoff), land
        g.use_heading = not math.isnan(heading)
        g.heading_deg = 0.0 if math.isnan(heading) else float(heading)
        return g

    def other_goal(self, action, **fields):
        """A goal of `go_to`, `takeoff` or `land` with these fields."""
        g = self.other[action][0].Goal()
        for k, v in fields.items():
            setattr(g, k, v)
        return g

    def send(self, goal, name, action=None):
        """Sends a goal (of FollowWaypoints, or of `action`): a record with its handle, feedback
        [(wall, sim, fb)] and result."""
        rec = {"name": name, "feedback": [], "result": None, "sent_sim": self.now(), "handle": None}
        fb = lambda m: rec["feedback"].append((time.monotonic(), self.now(), m.feedback))  # noqa: E731
        client = self.other[action][1] if action else self.client
        fut = client.send_goal_async(goal, feedback_callback=fb)
        self.peer.wait(fut.done, 20, f"goal '{name}' answered")
        rec["handle"] = fut.result()
        if not rec["handle"].accepted:
            return rec
        rfut = rec["handle"].get_result_async()
        rfut.add_done_callback(lambda f: rec.update(result=f.result(), result_sim=self.now(),
                                                    result_wall=time.monotonic()))
        return rec

    def wait_result(self, rec, secs):
        self.peer.wait(lambda: rec["result"] is not None, secs, f"the result of '{rec['name']}'")
        return rec["result"]


# The leg canceled in (b) is flown at this speed.
CANCEL_SPEED_MPS = 2.0
OUTCOMES = ["SUCCEEDED", "REFUSED", "FAILSAFE", "PILOT_OVERRIDE", "PREEMPTED", "CANCELED"]
STATUS = {4: "SUCCEEDED", 5: "CANCELED", 6: "ABORTED"}


def describe(res):
    r = res.result
    return (f"status {STATUS.get(res.status, res.status)}, outcome {OUTCOMES[r.outcome]}, "
            f"{r.waypoints_reached} reached, reason '{r.reason}'")


def feedback_rates(rec):
    """(n, wall Hz, sim Hz, largest wall gap s) of a goal's feedback."""
    fb = rec["feedback"]
    if len(fb) < 2:
        return len(fb), 0.0, 0.0, float("inf")
    w = [f[0] for f in fb]
    s = [f[1] for f in fb]
    gap = max(b - a for a, b in zip(w, w[1:]))
    return len(fb), (len(fb) - 1) / (w[-1] - w[0]), (len(fb) - 1) / max(1e-9, s[-1] - s[0]), gap


# ------------------------------------------------------------------------------------- square

def square(a):
    import yaml
    c = Checks()
    m = yaml.safe_load(open(a.mission))
    cl = Client()
    cl.ready()
    pts = [("local", w["east_m"], w["north_m"], w["alt_m"]) for w in m["waypoints"]]
    rec = cl.send(cl.goal(pts, speed=m["speed_mps"], radius=m["accept_radius_m"], hold=m.get("hold_s", 0.0),
                          takeoff=m["takeoff_alt_m"], land=m.get("land_at_end", True)), "square")
    c.check("square goal accepted", rec["handle"].accepted)
    res = cl.wait_result(rec, 400)
    n, hz_w, hz_s, gap = feedback_rates(rec)
    print(f"square: {describe(res)}; feedback {n} messages, {hz_w:.1f} Hz wall, {hz_s:.1f} Hz ROS time, "
          f"largest gap {gap:.2f} s", flush=True)
    c.check("square: result SUCCEEDED (4 waypoints, landed)", res.status == 4 and res.result.outcome == 0
            and res.result.waypoints_reached == len(pts), describe(res))
    c.check("square: feedback ≥ 1 Hz (wall), no gap over 1 s", hz_w >= 1.0 and gap <= 1.0, f"{hz_w:.1f} Hz, gap {gap:.2f} s")
    cl.peer.shutdown()
    return c.done()


# -------------------------------------------------------------------------------------- goals

def goals(a):
    c = Checks()
    cl = Client()
    cl.ready()
    cl.peer.wait(lambda: cl.home is not None, 60, f"{NS}/home")
    h = cl.home
    print(f"home (from {NS}/home): {h.latitude:.7f}, {h.longitude:.7f}, {h.altitude:.1f} m, frame {h.header.frame_id}", flush=True)
    ev = {"home": [h.latitude, h.longitude]}

    # (d) outside the geofence: refused with the reason, before any motion.
    far = offset_lat_lon(h.latitude, h.longitude, 250.0, 0.0)
    rec = cl.send(cl.goal([("global", far[0], far[1], 10.0)]), "outside the fence")
    res = cl.wait_result(rec, 20)
    print(f"(d) 250 m north: {describe(res)}", flush=True)
    ev["refused"] = rec["result_sim"]
    c.check("(d) a goal 250 m from home: refused (ABORTED, OUTCOME_REFUSED) with the geofence in the reason",
            res.status == 6 and res.result.outcome == 1 and "geofence" in res.result.reason
            and "fence_radius_m is 200 m" in res.result.reason, describe(res))
    c.check("(d) the MCU still disarmed when the refusal arrived", not cl.status.armed, cl.status.mode_name)

    # (a) a lat/lon waypoint goal: three points around home, holding at the last.
    ne = [(15.0, 0.0), (15.0, 15.0), (0.0, 15.0)]
    pts = [("global", *offset_lat_lon(h.latitude, h.longitude, n, e), 5.0) for n, e in ne]
    radius = 2.0
    rec = cl.send(cl.goal(pts, speed=3.0, radius=radius, hold=1.0, takeoff=5.0), "lat/lon")
    c.check("(a) lat/lon goal accepted", rec["handle"].accepted)
    res = cl.wait_result(rec, 150)
    n, hz_w, hz_s, gap = feedback_rates(rec)
    phases = sorted({f[2].phase for f in rec["feedback"]})
    print(f"(a) lat/lon: {describe(res)}; feedback {n} messages, {hz_w:.1f} Hz wall, {hz_s:.1f} Hz ROS time, "
          f"largest gap {gap:.2f} s, phases {phases}", flush=True)
    mid = [f[2] for f in rec["feedback"] if f[2].phase == "leg"]
    if mid:
        f = mid[len(mid) // 2]
        print(f"(a) a feedback mid-flight: waypoint {f.current_waypoint}/{f.waypoint_count}, "
              f"{f.distance_to_go_m:.1f} m to go, ETA {f.eta_s:.1f} s, cross-track {f.cross_track_m:.2f} m", flush=True)
    c.check("(a) result SUCCEEDED, 3 waypoints reached", res.status == 4 and res.result.outcome == 0
            and res.result.waypoints_reached == 3, describe(res))
    c.check("(a) feedback ≥ 1 Hz (wall and ROS time), no gap over 1 s", hz_w >= 1.0 and hz_s >= 1.0 and gap <= 1.0,
            f"{hz_w:.1f} Hz wall, {hz_s:.1f} Hz ROS time, gap {gap:.2f} s")
    c.check("(a) feedback names the waypoints and the legs", {"leg", "hold"} <= set(phases)
            and max(f[2].current_waypoint for f in rec["feedback"]) == 2
            and all(f[2].waypoint_count == 3 for f in rec["feedback"]), phases)
    ev["latlon"] = {"points": [[p[1], p[2]] for p in pts], "radius": radius,
                    "from": rec["sent_sim"], "to": rec["result_sim"]}

    # (b) cancel mid-leg: a 30 m leg north at 2 m/s; canceled once 10 m are flown.
    rec = cl.send(cl.goal([("local", 15.0, 30.0, 5.0)], speed=CANCEL_SPEED_MPS, radius=0.5), "to be canceled")
    cl.peer.wait(lambda: any(f[2].phase == "leg" and f[2].distance_to_go_m < 20.0 for f in rec["feedback"]),
                 60, "the leg half flown")
    t_cancel = cl.now()
    cfut = rec["handle"].cancel_goal_async()
    cl.peer.wait(cfut.done, 10, "the cancel answer")
    res = cl.wait_result(rec, 10)
    print(f"(b) canceled at {t_cancel:.2f} s (ROS time): cancel answer return code {cfut.result().return_code}, "
          f"{len(cfut.result().goals_canceling)} canceling; {describe(res)}", flush=True)
    c.check("(b) cancel accepted, result CANCELED", cfut.result().return_code == 0 and res.status == 5
            and res.result.outcome == 5, describe(res))
    ev["cancel"] = t_cancel
    cl.peer.wait(lambda: cl.now() > t_cancel + 6.0, 30, "6 s of hold")
    c.check("(b) the MCU in HOLD after the cancel", cl.status.mode_name == "hold", cl.status.mode_name)

    # (c) preemption: a goal back south, replaced after 3 s by one to a point west that lands.
    rec_a = cl.send(cl.goal([("local", 15.0, 0.0, 5.0)], speed=3.0, radius=0.5), "to be preempted")
    cl.peer.wait(lambda: cl.now() > rec_a["sent_sim"] + 3.0, 30, "3 s of the first goal")
    b_point = (0.0, 10.0, 4.0)
    rec_b = cl.send(cl.goal([("local", *b_point)], speed=3.0, radius=0.5, land=True), "preempting")
    res_a = cl.wait_result(rec_a, 10)
    print(f"(c) first goal: {describe(res_a)}", flush=True)
    c.check("(c) the first goal ends ABORTED with OUTCOME_PREEMPTED", res_a.status == 6 and res_a.result.outcome == 4,
            describe(res_a))
    res_b = cl.wait_result(rec_b, 150)
    print(f"(c) preempting goal: {describe(res_b)}", flush=True)
    c.check("(c) the preempting goal SUCCEEDED (flown, landed, disarmed)", res_b.status == 4 and res_b.result.outcome == 0,
            describe(res_b))
    ev["preempt"] = {"at": rec_b["sent_sim"], "point": b_point, "first_result": rec_a["result_sim"],
                     "done": rec_b.get("result_sim")}
    takeoff_go_to_land(c, cl, ev)
    json.dump(ev, open(a.events, "w"))
    cl.peer.shutdown()
    return c.done()


def takeoff_go_to_land(c, cl, ev):
    """(e) `land` on the ground: refused; (f) `takeoff` to 4 m; (g) `go_to` a point; (h) `land`
    at home: each SUCCEEDED (judged on the truth by `check`)."""
    rec = cl.send(cl.other_goal("land"), "land on the ground", "land")
    res = cl.wait_result(rec, 20)
    print(f"(e) land while disarmed: {describe(res)}", flush=True)
    c.check("(e) land on the ground: refused with the reason", res.status == 6 and res.result.outcome == 1
            and "on the ground" in res.result.reason, describe(res))
    steps = [("takeoff", "(f) takeoff to 4 m", {"altitude_m": 4.0}),
             ("go_to", "(g) go_to (8, 8, 4) m", {"target": None, "speed_mps": 3.0, "accept_radius_m": 0.5}),
             ("land", "(h) land at home", {"at_home": True})]
    for action, name, fields in steps:
        if action == "go_to":
            from fcc_msgs.msg import Waypoint
            fields["target"] = Waypoint(frame=Waypoint.FRAME_LOCAL_ENU, x_m=8.0, y_m=8.0, z_m=4.0)
        rec = cl.send(cl.other_goal(action, **fields), name, action)
        res = cl.wait_result(rec, 120)
        n, hz_w, _, gap = feedback_rates(rec)
        print(f"{name}: {describe(res)}; feedback {n} messages, {hz_w:.1f} Hz wall", flush=True)
        c.check(f"{name}: SUCCEEDED, feedback ≥ 1 Hz", res.status == 4 and res.result.outcome == 0
                and hz_w >= 1.0 and gap <= 1.0, f"{describe(res)}; {hz_w:.1f} Hz, gap {gap:.2f} s")
        ev[action] = {"from": rec["sent_sim"], "to": rec.get("result_sim")}
    cl.peer.wait(lambda: not cl.status.armed, 30, "disarmed after the landing")
    c.check("(h) disarmed after land", not cl.status.armed, cl.status.mode_name)


def check_takeoff_go_to_land(c, log, ev, home_ne):
    """(f)-(h) on the truth: the take-off climbs where it stands to 4 m, go_to reaches its point,
    the landing at home ends on the ground within 2 m of home (the GPS error of the map frame)."""
    ts = log["t_s"]
    rows = lambda t0, t1: [i for i, t in enumerate(ts) if t0 <= t <= t1]  # noqa: E731
    pos = lambda i: (log["true_n_m"][i], log["true_e_m"][i], -log["true_d_m"][i])  # noqa: E731
    t = ev["takeoff"]
    up = rows(t["from"], t["to"])
    drift = max(math.dist(pos(i)[:2], pos(up[0])[:2]) for i in up)
    alt = pos(up[-1])[2]
    print(f"(f) takeoff: true height {alt:.2f} m at the result (asked 4 m above home), horizontal drift {drift:.2f} m", flush=True)
    c.check("(f) takeoff: true height at the result within 0.5 m of 4 m, straight up (drift ≤ 2 m: the GPS error of the hold)",
            abs(alt - 4.0) <= 0.5 and drift <= 2.0, f"{alt:.2f} m, drift {drift:.2f} m")
    g = ev["go_to"]
    d = min(math.dist(pos(i), (8.0 + home_ne[0], 8.0 + home_ne[1], 4.0)) for i in rows(g["from"], g["to"]))
    c.check("(g) go_to: the true path reaches the point (≤ 2 m)", d <= 2.0, f"closest {d:.2f} m")
    last = len(ts) - 1
    dh = math.dist(pos(last)[:2], home_ne)
    print(f"(h) land at home: {dh:.2f} m from home, mode {log['mode'][last]}", flush=True)
    c.check("(h) land at home: on the ground within 2 m of home, disarmed", dh <= 2.0 and pos(last)[2] < 0.3
            and log["mode"][last] == "Disarmed", f"{dh:.2f} m, height {pos(last)[2]:.2f} m, {log['mode'][last]}")


# -------------------------------------------------------------------------------------- check

def check(a):
    c = Checks()
    log = truth.load_csv(a.csv)
    ev = json.load(open(a.events))
    lat0, lon0 = a.origin
    ts = log["t_s"]
    rows = lambda t0, t1: [i for i, t in enumerate(ts) if t0 <= t <= t1]  # noqa: E731
    pos = lambda i: (log["true_n_m"][i], log["true_e_m"][i], -log["true_d_m"][i])  # noqa: E731

    # (d) nothing moved or armed until the refusal.
    before = rows(0.0, ev["refused"])
    moved = max(math.dist(pos(i), pos(before[0])) for i in before)
    armed = max(log["armed"][i] for i in before)
    c.check("(d) before the refusal: never armed, the true position still (< 0.1 m)", armed == 0 and moved < 0.1,
            f"armed {armed}, moved {moved:.3f} m in {ev['refused']:.1f} s")

    # (a) the true path within the acceptance radius of each lat/lon point (its true position:
    # the point's lat/lon against the simulator's origin).
    la = ev["latlon"]
    during = rows(la["from"], la["to"])
    home_ne = lat_lon_to_ne(lat0, lon0, *ev["home"])
    print(f"(a) the MCU's home is {math.hypot(*home_ne):.2f} m from the true start (its GPS error then)", flush=True)
    for k, (lat, lon) in enumerate(la["points"]):
        n, e = lat_lon_to_ne(lat0, lon0, lat, lon)
        p = (n, e, 5.0)
        d = min(math.dist(pos(i), p) for i in during)
        c.check(f"(a) the true path passes within the {la['radius']} m radius of lat/lon point {k}", d <= la["radius"],
                f"closest {d:.2f} m")

    # (b) cancel: HOLD within 1 s, still (true horizontal speed ≤ 0.3 m/s) within 1 s, then
    # within 1 m of where it stopped for 5 s.
    tc = ev["cancel"]
    hold_at = next((ts[i] for i in rows(tc, tc + 5.0) if log["mode"][i] == "Hold"), None)
    c.check("(b) the MCU in Hold within 1 s of the cancel (CSV mode)", hold_at is not None and hold_at - tc <= 1.0,
            f"{(hold_at - tc) if hold_at else float('nan'):.2f} s")
    spd = lambda i: math.hypot(log["true_vn_mps"][i], log["true_ve_mps"][i])  # noqa: E731
    at_cancel = spd(rows(tc, tc + 0.1)[0])
    still = next((ts[i] - tc for i in rows(tc, tc + 5.0) if spd(i) <= 0.3), None)
    ts_still = tc + (still if still is not None else 1.0)
    after = rows(ts_still, ts_still + 5.0)
    vmax = max(spd(i) for i in after)
    drift = max(math.dist(pos(i)[:2], pos(after[0])[:2]) for i in after)
    print(f"(b) true speed {at_cancel:.2f} m/s at the cancel, ≤ 0.3 m/s after {still if still is not None else float('nan'):.2f} s; "
          f"the 5 s after: speed ≤ {vmax:.2f} m/s, horizontal drift {drift:.2f} m from where it stopped", flush=True)
    c.check("(b) still within 1 s of the cancel (true horizontal speed ≤ 0.3 m/s)", still is not None and still <= 1.0,
            f"{still}")
    c.check("(b) holding: within 1 m of where it stopped for the 5 s after (truth)", drift <= 1.0, f"{drift:.2f} m")

    # (c) preempted: the second goal's point reached (truth vs the estimate's map frame: the GPS
    # error, so within 2 m), then landed and disarmed.
    pr = ev["preempt"]
    x, y, z = pr["point"]
    flown = rows(pr["at"], pr["done"] or ts[-1])
    d = min(math.dist(pos(i), (y + home_ne[0], x + home_ne[1], z)) for i in flown)
    c.check("(c) after the preemption the true path reaches the second goal's point (≤ 2 m)", d <= 2.0, f"closest {d:.2f} m")
    # The result's time is this peer's ROS time when rclpy ran the result callback; its /clock
    # subscription is served by the same executor and can lag the simulator by some tens of ms,
    # so the result may be seen a row or two before the disarm that ended the goal (CI once: the
    # row before it read Land). The goal must have ended by landing: the vehicle went from Land
    # to Disarmed within 0.5 s (ROS time) of the result, with nothing else in between.
    end = pr["done"] or ts[-1]
    near = rows(end - 0.5, end + 0.5)
    disarm = next((i for i in near if log["mode"][i] == "Disarmed"), None)
    before = [log["mode"][i] for i in flown if disarm is None or ts[i] < ts[disarm]]
    c.check("(c) landed and disarmed at the end of its goal (CSV: Land → Disarmed within 0.5 s of the result)",
            disarm is not None and before and before[-1] == "Land",
            f"modes around the result: {[log['mode'][i] for i in near][::10]}; disarmed at "
            f"{ts[disarm] - end if disarm is not None else float('nan'):+.2f} s")
    check_takeoff_go_to_land(c, log, ev, home_ne)
    return c.done()


def main():
    p = argparse.ArgumentParser()
    p.add_argument("mode", choices=["square", "goals", "check"])
    p.add_argument("--mission")
    p.add_argument("--events")
    p.add_argument("--csv")
    p.add_argument("--origin", type=lambda s: [float(v) for v in s.split(",")], default=[37.5665, 126.9780])
    a = p.parse_args()
    sys.exit({"square": square, "goals": goals, "check": check}[a.mode](a))


if __name__ == "__main__":
    main()
