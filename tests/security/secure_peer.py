#!/usr/bin/env python3
"""fcc-bridge with ROS 2 security (issue 19), judged by an independent secure DDS: Debian's
Cyclone DDS 0.10 with its security plugins, through its Python binding built against it
(scripts/security-setup.sh). The bridge runs with ROS_SECURITY_STRATEGY=Enforce in enclave
/fcc/fcc_bridge against the scripted fake MCU (tests/security/secure_stack.sh).

  secure_peer.py KEYSTORE --mcu-log FILE [--seconds 8]

Five Cyclone participants, each its own process:
  ground    (enclave /ground_station): reads imu/data_raw and status, arms and sends a setpoint;
            reads /diagnostics and /rosout for the bridge's security events
  observer  (enclave /observer): reads imu/data_raw; its setpoint and cmd/arm writers must be
            refused by access control (by its own Cyclone, from its permissions)
  rogue     (the observer's identity and permissions, with a governance re-signed by the CA
            that does not enforce write access control on its own side, as a tampered node
            could be): Cyclone creates its writers and it sends a setpoint and cmd/arm false;
            the bridge's access control must deny both writers, count and report them
  foreign   (an enclave of another keystore: a certificate from another CA): must receive
            nothing; the bridge counts it as a refused participant
  plain     (no security): reads imu/data_raw; must receive nothing
foreign and plain also write a setpoint and cmd/arm false: neither may reach the MCU.
and, in this process, a packet capture on loopback (AF_PACKET) for the whole run: no plaintext
telemetry (the frame ids "base_link" and "imu_link", the odometry's position bytes) in any
UDP payload, while the unencrypted SPDP announcements ("DDS:Auth:PKI-DH") are seen (the
capture works). The fake MCU's log must hold the ground station's Arm command and setpoint
(map ENU (1, 2, 0.5) → NED (2, 1, −0.5)). Exit 0 when every check holds.
"""
import argparse
import json
import os
import socket
import struct
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "dds"))
from keystore_peer import report, run_roles  # noqa: E402

ENCLAVES = {"ground": "ground_station", "observer": "observer", "rogue": "rogue"}
# What the rogue sends: a setpoint of map ENU (7, 7, 7) (NED (7, 7, -7) at the MCU) and a disarm.
ROGUE_ENU = (7.0, 7.0, 7.0)
# What the participants without credentials or of another CA send (their own writers exist).
OUTSIDER_ENU = (9.0, 9.0, 9.0)
# Telemetry only the bridge writes: frame ids, and the fake MCU's position NED (10, 5, -3) as
# state/odom's ENU position (f64 little-endian). Each is on the wire when security is off (the
# permissions documents, sent in clear in the handshake by the spec, name topics: not a marker).
PLAINTEXT = {"base_link": b"base_link", "imu_link": b"imu_link",
             "odom position (5, 10, 3) f64": struct.pack("<3d", 5.0, 10.0, 3.0)}
SPDP_MARK = b"DDS:Auth:PKI-DH"


def participant(role, seconds):
    """One participant (this process); prints one JSON line of what it saw and did."""
    from cyclonedds.core import DDSException, Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
    import ros_types as rt

    reliable = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10))
    best_effort = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(50))
    dp = DomainParticipant(0)
    imu = DataReader(dp, Topic(dp, "rt/fcc/imu/data_raw", rt.Imu), qos=best_effort)
    odom = DataReader(dp, Topic(dp, "rt/fcc/state/odom", rt.Odometry), qos=best_effort)
    out = {"role": role, "imu": 0, "writers": {}, "sent": 0}
    writers = {}
    if role == "ground":  # the bridge's security events
        diag = DataReader(dp, Topic(dp, "rt/diagnostics", rt.DiagnosticArray), qos=reliable)
        rosout = DataReader(dp, Topic(dp, "rt/rosout", rt.Log),
                            qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                                    Policy.Durability.TransientLocal, Policy.History.KeepLast(100)))
        out["security"], out["rosout"] = None, []
    if role in ("ground", "observer", "rogue", "plain", "foreign"):
        for name, typ in (("setpoint/velocity", rt.TwistStamped), ("cmd/arm", rt.Bool)):
            try:
                writers[name] = DataWriter(dp, Topic(dp, f"rt/fcc/{name}", typ), qos=reliable)
                out["writers"][name] = "created"
            except DDSException as e:
                out["writers"][name] = f"refused: {e}"
    arm, enu = {"rogue": (False, ROGUE_ENU), "plain": (False, OUTSIDER_ENU),
                "foreign": (False, OUTSIDER_ENU)}.get(role, (True, (1.0, 2.0, 0.5)))
    t0 = time.time()
    first = None
    while time.time() - t0 < seconds + 20:
        n = len(imu.take(N=500))
        out["imu"] += n
        out["odom"] = out.get("odom", 0) + len(odom.take(N=500))
        now = time.time()
        if n and first is None:
            first = now
        if role == "ground":
            for a in diag.take(N=50):
                for st in a.status:
                    if st.name == "fcc_bridge: security":
                        out["security"] = {kv.key: kv.value for kv in st.values}
            out["rosout"] += [m.msg for m in rosout.take(N=100) if "DDS Security" in m.msg]
        # The rogue and the outsiders (they receive nothing) send from 1 s after the start.
        started = first if role in ("ground", "observer") else t0
        if started is not None and now - started > 1.0 and out["sent"] < 5 and writers:
            if "cmd/arm" in writers and out["sent"] == 0:
                writers["cmd/arm"].write(rt.Bool(data=arm))
                time.sleep(0.05)
            if "setpoint/velocity" in writers:
                stamp = rt.Time(sec=int(now), nanosec=int((now % 1) * 1e9))
                writers["setpoint/velocity"].write(
                    rt.TwistStamped(rt.Header(stamp, "map"), rt.Twist(rt.Vector3(*enu))))
            out["sent"] += 1
        if first is not None and now - first > seconds:
            # The ground station waits (up to 8 s more) for the bridge's report of the
            # rogue's writers and the refused participants.
            sec = out.get("security") or {}
            if role != "ground" or now - first > seconds + 8 or (
                    int(sec.get("writers_denied", 0)) >= 2
                    and int(sec.get("participants_rejected", 0)) >= 2):
                break
        if first is None and role in ("plain", "foreign") and now - t0 > seconds:
            break
        time.sleep(0.05)
    print(json.dumps(out), flush=True)


class Capture(threading.Thread):
    """Every UDP payload on loopback while it runs (the namespace's only interface)."""

    def __init__(self):
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003))
        self.sock.bind(("lo", 0))
        self.sock.settimeout(0.2)
        self.payloads = []
        self.stop = False

    def run(self):
        while not self.stop:
            try:
                frame = self.sock.recv(65535)
            except socket.timeout:
                continue
            ip = frame[14:]  # Ethernet header on lo
            if len(ip) < 28 or ip[0] >> 4 != 4 or ip[9] != 17:
                continue
            ihl = (ip[0] & 0x0F) * 4
            self.payloads.append(bytes(ip[ihl + 8:]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("keystore", nargs="?")
    ap.add_argument("--mcu-log")
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--foreign", required=False,
                    help="an enclave directory of another keystore (another CA)")
    ap.add_argument("--role", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.role:
        participant(a.role, a.seconds)
        return 0
    cap = Capture()
    cap.start()
    enclaves = dict(ENCLAVES, foreign=os.path.abspath(a.foreign))
    seen = run_roles(__file__, a.keystore, enclaves,
                     ["ground", "observer", "rogue", "foreign", "plain"], a.seconds,
                     pythonpath=[os.path.join(HERE, "..", "dds"), HERE])
    if seen is None:
        return 1
    cap.stop = True
    cap.join()
    udp = b"\n".join(cap.payloads)
    leaks = [name for name, m in PLAINTEXT.items() if m in udp]
    if os.environ.get("FCC_SECURITY_DEBUG"):
        for d in cap.payloads:
            for m in PLAINTEXT.values():
                i = d.find(m)
                if i >= 0:
                    print("LEAK", m, len(d), d[:20].hex(), d[max(0, i - 120):i + 40])  # noqa
                    break
    recs = [json.loads(line) for line in open(a.mcu_log) if line.strip()]
    sps = [r for r in recs if r["msg"] == "VelocitySetpoint"]
    cmds = [r["command"] for r in recs if r["msg"] == "Command"]
    g, o, p, r, f = (seen[k] for k in ("ground", "observer", "plain", "rogue", "foreign"))
    def sent_as(enu):  # the MCU's setpoints equal to map ENU `enu` (NED at the MCU)
        ned = (enu[1], enu[0], -enu[2])
        return [sp for sp in sps if all(abs(x - y) < 1e-6 for x, y in zip(sp["vel_ned_mps"], ned))]
    rogue_sps, outsider_sps = sent_as(ROGUE_ENU), sent_as(OUTSIDER_ENU)
    sec = g.get("security") or {}
    denied_lines = [m for m in g.get("rosout", []) if "denied by access control" in m]
    refused_lines = [m for m in g.get("rosout", []) if "authentication failed" in m]
    checks = [
        ("the ground station receives the bridge's IMU (DDS Security with rustdds)", g["imu"] > 0,
         f"{g['imu']} samples"),
        ("the ground station may write setpoints and cmd/arm",
         set(g["writers"].values()) == {"created"}, g["writers"]),
        ("the MCU got the ground station's Arm", "Arm" in cmds, cmds),
        ("the MCU got the ground station's setpoint, map ENU (1,2,0.5) → NED (2,1,-0.5)",
         bool(sps) and all(abs(x - y) < 1e-6 for x, y in zip(sps[0]["vel_ned_mps"], (2.0, 1.0, -0.5))),
         f"{len(sps)} setpoints, first {sps[0]['vel_ned_mps'] if sps else None}"),
        ("the ground station receives the odometry", g.get("odom", 0) > 0, f"{g.get('odom')} samples"),
        ("the observer receives the IMU", o["imu"] > 0, f"{o['imu']} samples"),
        ("the observer's setpoint and cmd/arm writers are refused by access control",
         all(str(v).startswith("refused") for v in o["writers"].values()) and len(o["writers"]) == 2,
         o["writers"]),
        ("an unauthenticated participant receives nothing", p["imu"] == 0, f"{p['imu']} samples"),
        ("a participant with a certificate of another CA receives nothing", f["imu"] == 0,
         f"{f['imu']} samples"),
        ("neither injects anything: their setpoints never reach the MCU",
         not outsider_sps and p["sent"] > 0 and f["sent"] > 0,
         f"{len(outsider_sps)} of {len(sps)} setpoints are theirs; sent {p['sent']} + {f['sent']}"),
        ("the rogue's own Cyclone lets it create its writers (the case the bridge must refuse)",
         set(r["writers"].values()) == {"created"} and r["sent"] > 0,
         f"{r['writers']}, {r['sent']} sends"),
        ("the bridge denies the rogue's writers: its setpoint never reaches the MCU",
         not rogue_sps, f"{len(rogue_sps)} of {len(sps)} setpoints are the rogue's"),
        ("the rogue's cmd/arm false never reaches the MCU", "Disarm" not in cmds, cmds),
        ("/diagnostics counts the rogue's two denied writers",
         int(sec.get("writers_denied", 0)) >= 2, sec),
        ("/diagnostics counts the refused participants (no security, another CA)",
         int(sec.get("participants_rejected", 0)) >= 2, sec.get("participants_rejected")),
        ("/rosout tells the denied writers", len(denied_lines) >= 2,
         denied_lines[:1] or g.get("rosout")),
        ("/rosout tells the refused participants", len(refused_lines) >= 2,
         refused_lines[:1] or g.get("rosout")),
        ("the capture saw the unencrypted SPDP announcements", SPDP_MARK in udp,
         f"{len(cap.payloads)} UDP datagrams, {len(udp)} bytes"),
        ("no plaintext telemetry on the wire", not leaks, f"found {leaks}" if leaks else
         f"none of {list(PLAINTEXT)}"),
    ]
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
