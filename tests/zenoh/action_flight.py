#!/usr/bin/env python3
"""A ground station flying a vehicle by an action goal over Zenoh (issue 18): the independent
peer (tests/zenoh/zenoh_ros.py: eclipse-zenoh + rosbags, rmw_zenoh's service protocol) sends a
fcc_msgs/action/FollowWaypoints goal to `/uavN/mission/follow_waypoints` (fcc-mission without
--mission serves it), checks the acceptance, collects feedback (`_action/feedback`) and status
(`_action/status`), asks for the result (`_action/get_result`) and checks it against the goal and
the simulator's truth (its CSV).

  action_flight.py --connect EP --vehicle 1 --csv uav1.csv --until-file F
      the one-vehicle test (tests/zenoh/action_one.sh): fly, wait for F (the simulator stopped,
      its CSV complete), check. fleet_peer.py imports fly_waypoints / check_flight.
"""
import argparse
import math
import os
import sys
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
sys.path.insert(0, os.path.join(here, "..", "lib"))

import zenoh_ros as zr  # noqa: E402
from truth import Checks, load_csv  # noqa: E402

ACTION_TYPE = "fcc_msgs/action/FollowWaypoints"
SUCCEEDED = 4            # action_msgs/GoalStatus
# 6 m legs at 3 m above home (x east, y north, z up, map = home), land at the last one.
WAYPOINTS = [(0.0, 6.0, 3.0), (6.0, 6.0, 3.0), (6.0, 0.0, 3.0)]
SPEED_MPS = 2.0


def action_server_hashes(peer, action, deadline_s=30.0, log=print):
    """Wait for the server's send_goal, get_result and cancel_goal (SS tokens); return the type
    hash each advertises, keyed by service."""
    want = {"send_goal": f"{ACTION_TYPE}_SendGoal", "get_result": f"{ACTION_TYPE}_GetResult",
            "cancel_goal": "action_msgs/srv/CancelGoal"}
    end = time.monotonic() + deadline_s
    while True:
        found = {}
        for e in peer.graph(1.0):
            for sub, srv in want.items():
                if e.kind == "SS" and e.topic == f"{action}/_action/{sub}" and e.type == srv:
                    found[sub] = e.type_hash
        if len(found) == len(want) or time.monotonic() > end:
            return found
        time.sleep(0.3)


def fly_waypoints(peer, c, v, log, waypoints=WAYPOINTS, result_timeout_s=90.0):
    """Fly uav`v` through `waypoints` by one FollowWaypoints goal; the checks on the action
    protocol go to `c`. Returns a dict of what happened (None if no goal was accepted)."""
    ts = peer.store.types
    action = f"/uav{v}/mission/follow_waypoints"
    hashes = action_server_hashes(peer, action, log=log)
    c.check(f"uav{v}: {action} served (SS tokens of send_goal, get_result, cancel_goal)",
            len(hashes) == 3, hashes)
    if len(hashes) < 3:
        return None
    # The client calls on the REP-2016 hashes (as rmw_zenoh's does): the server must advertise
    # and serve exactly those (fcc_ros's generated type_hashes.rs), not a placeholder.
    client = zr.ActionClient(peer, action, ACTION_TYPE)
    rep2016 = {"send_goal": client.send_goal_client.rihs, "get_result": client.get_result_client.rihs,
               "cancel_goal": client.cancel_client.rihs}
    for sub in hashes:
        same = hashes[sub] == rep2016[sub]
        log(f"{action}/_action/{sub}: server's hash {hashes[sub]} "
            f"{'= ' if same else '!= '}REP-2016 {rep2016[sub]}")
    mismatched = sorted(sub for sub in hashes if hashes[sub] != rep2016[sub])
    c.check(f"uav{v}: {action}'s servers advertise the REP-2016 hashes an rmw_zenoh client "
            "calls on (send_goal, get_result, cancel_goal)", not mismatched,
            f"mismatched: {mismatched}" if mismatched else "all three equal")
    log(f"send_goal key {client.send_goal_client.key}")
    Waypoint, Goal = ts["fcc_msgs/msg/Waypoint"], ts[f"{ACTION_TYPE}_Goal"]
    goal = Goal(
        waypoints=[Waypoint(frame=0, x_m=x, y_m=y, z_m=z, latitude_deg=0.0, longitude_deg=0.0,
                            altitude_m=0.0) for x, y, z in waypoints],
        speed_mps=SPEED_MPS, accept_radius_m=0.0, hold_s=0.0, use_heading=False, heading_deg=0.0,
        takeoff_alt_m=0.0, land_at_end=True)
    time.sleep(0.5)  # the feedback/status subscriptions reach the server's router
    goal_id, response, t_send = None, None, time.monotonic()
    for _ in range(10):
        try:
            goal_id, response = client.send_goal(goal, timeout_s=3.0)
            break
        except zr.ServiceError as e:
            log(f"send_goal: {e}")
            time.sleep(0.5)
    c.check(f"uav{v}: send_goal answered and the goal accepted",
            response is not None and response.accepted,
            f"accepted={response and response.accepted} stamp={response and response.stamp}")
    if response is None or not response.accepted:
        return None
    log(f"goal {goal_id.hex()} accepted in {time.monotonic() - t_send:.2f} s")
    result = None
    try:
        result = client.get_result(goal_id, timeout_s=result_timeout_s)
    except zr.ServiceError as e:
        log(f"get_result: {e}")
    t_result = time.monotonic()
    time.sleep(0.5)  # the last status array
    feedback = client.feedback_of(goal_id)
    statuses = client.statuses_of(goal_id)
    phases = []
    for f in feedback:
        if not phases or phases[-1] != f.feedback.phase:
            phases.append(f.feedback.phase)
    log(f"result after {t_result - t_send:.1f} s: status {result and result.status} "
        f"({zr.GOAL_STATUS.get(result.status) if result else None}) outcome "
        f"{result and result.result.outcome} reason {result and result.result.reason!r} "
        f"waypoints_reached {result and result.result.waypoints_reached}; "
        f"{len(feedback)} feedback messages, phases {phases}; status sequence "
        f"{_runs([zr.GOAL_STATUS.get(s, s) for s in statuses])}")
    c.check(f"uav{v}: get_result: SUCCEEDED (4), outcome 0, every waypoint reached",
            result is not None and result.status == SUCCEEDED and result.result.outcome == 0
            and result.result.waypoints_reached == len(waypoints),
            f"status {result and result.status} outcome {result and result.result.outcome} "
            f"reached {result and result.result.waypoints_reached}/{len(waypoints)}")
    legs = {f.feedback.current_waypoint for f in feedback if f.feedback.phase == "leg"}
    c.check(f"uav{v}: feedback on _action/feedback: >= 10 messages, for this goal, every "
            "waypoint flown to, waypoint_count right",
            len(feedback) >= 10 and legs == set(range(len(waypoints)))
            and all(f.feedback.waypoint_count == len(waypoints) for f in feedback),
            f"{len(feedback)} messages, legs to {sorted(legs)}, phases {phases}")
    c.check(f"uav{v}: status on _action/status: EXECUTING then SUCCEEDED",
            2 in statuses and statuses and statuses[-1] == SUCCEEDED,
            _runs([zr.GOAL_STATUS.get(s, s) for s in statuses]))
    return {"goal_id": goal_id, "result": result, "feedback": feedback, "statuses": statuses,
            "waypoints": waypoints}


def _runs(seq):
    out = []
    for s in seq:
        if not out or out[-1][0] != s:
            out.append([s, 0])
        out[-1][1] += 1
    return " -> ".join(f"{s} x{n}" for s, n in out)


def check_flight(c, v, log_csv, flown):
    """The simulator's truth (`log_csv`, from the start; x east, y north relative to where the
    vehicle stood first): each waypoint passed within 1 m horizontally (at 2-4 m up), then on the
    ground at the last one, disarmed."""
    n0, e0 = log_csv["true_n_m"][0], log_csv["true_e_m"][0]
    pts = list(zip(log_csv["true_e_m"], log_csv["true_n_m"], log_csv["true_d_m"]))
    misses = []
    for x, y, z in flown["waypoints"]:
        near = min(((math.hypot(e - e0 - x, n - n0 - y), -d) for e, n, d in pts if -d > 1.5),
                   default=(math.inf, 0.0))
        misses.append(near)
    c.check(f"uav{v} TRUTH: each waypoint passed within 1 m horizontally at 2-4 m up",
            all(m < 1.0 and 2.0 < up < 4.0 for m, up in misses),
            ", ".join(f"{m:.2f} m at {up:.2f} m" for m, up in misses))
    e, n, d = pts[-1]
    x, y, _ = flown["waypoints"][-1]
    up = -(d - log_csv["true_d_m"][0])  # above where it stood at the start
    off = math.hypot(e - e0 - x, n - n0 - y)
    armed = log_csv["armed"][-1]
    c.check(f"uav{v} TRUTH: landed at the last waypoint (< 1.5 m from it) and disarmed",
            abs(up) < 0.2 and off < 1.5 and armed < 0.5,
            f"{up:.2f} m above the start height, {off:.2f} m from it, armed {armed:.0f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--connect", default=zr.DEFAULT_ROUTER)
    ap.add_argument("--vehicle", type=int, default=1)
    ap.add_argument("--csv")
    ap.add_argument("--until-file")
    ap.add_argument("--timeout", type=float, default=120.0)
    a = ap.parse_args()
    c = Checks()
    t0 = time.monotonic()
    log = lambda s: print(f"[gs {time.monotonic() - t0:5.1f} s] {s}", flush=True)  # noqa: E731
    peer = zr.RosPeer(connect=a.connect, node="ground_station")
    try:
        flown = fly_waypoints(peer, c, a.vehicle, log)
    finally:
        peer.close()
    if a.until_file:
        open(a.until_file + ".flown", "w").close()
        while not os.path.exists(a.until_file) and time.monotonic() - t0 < a.timeout:
            time.sleep(0.2)
    if flown and a.csv:
        check_flight(c, a.vehicle, load_csv(a.csv), flown)
    return c.done()


if __name__ == "__main__":
    sys.exit(main())
