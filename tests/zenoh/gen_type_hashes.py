#!/usr/bin/env python3
"""Generate fcc_bridge/ros/src/type_hashes.rs: the REP-2016 type hash (RIHS01) of every message,
service and action-part type that fcc-bridge and fcc-mission publish, subscribe or serve, keyed
by the DDS type name ros2-client's Zenoh backend puts in key expressions and liveliness tokens.

rmw_zenoh puts the type hash in every key expression and token; the vendored backend computes it
only for a few types (ros2-client/src/zenoh_backend/type_hash.rs) and used a placeholder for the
rest, so an rmw_zenoh C++ node would not match our publishers nor reach our servers. fcc_ros
registers this table with the backend when it creates a Zenoh context (rmw::zenoh_context).

The hashes come from tests/zenoh/zenoh_ros.py (rosbags' Jazzy type definitions plus msg/msg/*.msg
and msg/action/*.action). Before writing, the hashing is checked against hashes known
independently: std_msgs/String, sensor_msgs/Imu, example_interfaces/AddTwoInts (published by
ROS 2 Jazzy / rmw_zenoh's design document) and every locked value of the vendored backend's own
Jazzy table (ros2-client/src/zenoh_backend/jazzy_types.rs: rcl_interfaces, action_msgs, an
action's SendGoal/GetResult/FeedbackMessage).

Which types (keep in step with the code; fcc_ros's test `type_hashes` checks the topic table,
the bridge's services and fcc_msgs' actions are covered, and tests/zenoh/fleet_peer.py that every
token of our nodes advertises the hash computed here):
  * fcc_ros::topics (the bridge's topic table) and fcc-mission's topics (same types);
  * fcc-bridge's services arm (std_srvs/SetBool), land and hold (std_srvs/Trigger);
  * every fcc_msgs message (msg/msg/*.msg) and, for every action (msg/action/*.action), its
    `_SendGoal` and `_GetResult` services and `_FeedbackMessage` topic.
Types the backend computes itself (rcl_interfaces Log, ParameterEvent and the parameter
services; action_msgs CancelGoal and GoalStatusArray) are not in the table; std_msgs String and
Bool are in both (the same value: fcc_ros's test checks the backend's lookup returns the table's).

  gen_type_hashes.py            write the table
  gen_type_hashes.py --check    exit 1 if the file differs from what would be written
"""
import argparse
import re
import sys
from pathlib import Path

here = Path(__file__).resolve().parent
sys.path.insert(0, str(here))

import zenoh_ros as zr  # noqa: E402

ROOT = here.parents[1]
OUT = ROOT / "fcc_bridge" / "ros" / "src" / "type_hashes.rs"
JAZZY_TYPES = ROOT / "fcc_bridge/ros/vendor/ros2-client/src/zenoh_backend/jazzy_types.rs"

# The standard message types of the topic table and of fcc-mission's topics.
MESSAGES = [
    "sensor_msgs/msg/Imu", "sensor_msgs/msg/MagneticField", "sensor_msgs/msg/FluidPressure",
    "sensor_msgs/msg/NavSatFix", "sensor_msgs/msg/Range", "sensor_msgs/msg/BatteryState",
    "nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage", "geometry_msgs/msg/AccelStamped",
    "geometry_msgs/msg/TwistStamped", "geometry_msgs/msg/QuaternionStamped",
    "diagnostic_msgs/msg/DiagnosticArray", "rosgraph_msgs/msg/Clock", "std_msgs/msg/Bool",
    "std_msgs/msg/String",
]
# fcc-bridge's command services.
SERVICES = ["std_srvs/srv/SetBool", "std_srvs/srv/Trigger"]


def our_types():
    """[(ros type, is a service)] in table order."""
    types = [(t, False) for t in MESSAGES]
    types += [(f"{zr.OUR_PACKAGE}/msg/{p.stem}", False) for p in sorted(zr.MSG_DIR.glob("*.msg"))]
    types += [(t, True) for t in SERVICES]
    for p in sorted(zr.ACTION_DIR.glob("*.action")):
        action = f"{zr.OUR_PACKAGE}/action/{p.stem}"
        types += [(f"{action}_SendGoal", True), (f"{action}_GetResult", True),
                  (f"{action}_FeedbackMessage", False)]
    return types


def hash_of(store, ros_type, service):
    return zr.service_type_hash(store, ros_type) if service else zr.type_hash(store, ros_type)


def self_check(store):
    """The hashing against independently known values; raises on any difference."""
    store.register(zr.service_types("example_interfaces/srv/AddTwoInts",
                                    [("a", zr._base("int64")), ("b", zr._base("int64"))],
                                    [("sum", zr._base("int64"))]))
    store.register(zr.action_types("int32 order\n---\nint32[] sequence\n---\n"
                                   "int32[] partial_sequence\n",
                                   "action_tutorials_interfaces/action/Fibonacci"))
    want = {"std_msgs::msg::dds_::String_": zr.STRING_HASH,
            "sensor_msgs::msg::dds_::Imu_": zr.IMU_HASH,
            "example_interfaces::srv::dds_::AddTwoInts_": zr.ADD_TWO_INTS_HASH}
    locked = re.findall(r'\(\s*"([a-z_]+::[a-z]+::dds_::\w+)",\s*"(RIHS01_[0-9a-f]{64})",?\s*\)',
                        JAZZY_TYPES.read_text())
    if len(locked) < 10:
        raise SystemExit(f"{JAZZY_TYPES}: only {len(locked)} locked hashes found")
    want.update(locked)
    bad = []
    for dds, rihs in want.items():
        ros_type = zr.ros_type_name(dds)
        got = hash_of(store, ros_type, is_service(dds))
        if got != rihs:
            bad.append(f"{ros_type}: computed {got}, known {rihs}")
    if bad:
        raise SystemExit("REP-2016 hashing disagrees with known hashes:\n  " + "\n  ".join(bad))
    return len(want)


def is_service(dds):
    return "::srv::" in dds or dds.endswith(("_SendGoal_", "_GetResult_"))


def render(rows):
    lines = [
        "// @generated by tests/zenoh/gen_type_hashes.py — do not edit.",
        "// Regenerate (after changing a message, service or action, or the types the nodes use):",
        "//   .venv-dds/bin/python tests/zenoh/gen_type_hashes.py",
        "// (`--check` tells whether this file is current.)",
        "",
        "//! REP-2016 type hashes (RIHS01) of the types fcc-bridge and fcc-mission publish,",
        "//! subscribe or serve, for rmw_zenoh interop: (DDS type name as ros2-client's Zenoh",
        "//! backend names it, hash). Registered with the backend by [`crate::rmw::zenoh_context`].",
        "",
        "/// (DDS type name, `RIHS01_<sha256>`); services (`pkg::srv::dds_::Name_`, an action's",
        "/// `_SendGoal_` / `_GetResult_`) carry the service type's hash, as rmw_zenoh's keys do.",
        "pub const TYPE_HASHES: &[(&str, &str)] = &[",
    ]
    for dds, rihs in rows:
        one = f'    ("{dds}", "{rihs}"),'
        if len(one) <= 100:
            lines.append(one)
        else:
            lines += ["    (", f'        "{dds}",', f'        "{rihs}",', "    ),"]
    lines.append("];")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare with the file, write nothing")
    a = ap.parse_args()
    store = zr.make_typestore()
    checked = self_check(store)
    rows = [(zr.dds_type_name(t), hash_of(store, t, srv)) for t, srv in our_types()]
    text = render(rows)
    if a.check:
        current = OUT.read_text() if OUT.exists() else ""
        if current != text:
            print(f"{OUT.relative_to(ROOT)} is stale: run tests/zenoh/gen_type_hashes.py")
            return 1
        print(f"{OUT.relative_to(ROOT)} current ({len(rows)} types; hashing checked against "
              f"{checked} known hashes)")
        return 0
    OUT.write_text(text)
    print(f"wrote {OUT.relative_to(ROOT)}: {len(rows)} types (hashing checked against {checked} "
          f"known hashes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
