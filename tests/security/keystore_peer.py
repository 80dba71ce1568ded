#!/usr/bin/env python3
"""An fcc-keystore keystore judged by an independent DDS Security implementation (issue 19):
Debian's Cyclone DDS 0.10 with its security plugins (auth PKI-DH, access control, AES-GCM
crypto), through its Python binding built against it (scripts/security-setup.sh).

  keystore_peer.py KEYSTORE [--seconds 8]

Four Cyclone participants, each its own process with its own enclave of KEYSTORE:
  bridge    (/fcc/fcc_bridge):  writes rt/fcc/status, reads rt/fcc/cmd/mode
  ground    (/ground_station):  reads rt/fcc/status, writes rt/fcc/cmd/mode
  observer  (/observer):        reads rt/fcc/status; its writer on rt/fcc/cmd/mode must be refused
  plain     (no security):      reads rt/fcc/status; must receive nothing (authentication)
Pass: the ground station's commands reach the bridge enclave, the ground station and the
observer receive the status, the observer's writer is refused by access control, the plain
participant receives nothing. Exit 0 when every check holds; run inside a loopback-only
network namespace (tests/security/keystore.sh).
"""
import argparse
import json
import os
import subprocess
import sys
import time

def security_xml(enclave_dir):
    """Cyclone's <Security> for an enclave; the plugins are the ones beside the library the
    binding was built against (scripts/security-setup.sh links them there)."""
    from cyclonedds.__library__ import library_path
    plugins = os.path.dirname(library_path)
    f = lambda name: f"file:{os.path.join(enclave_dir, name)}"  # noqa: E731
    lib = lambda kind, fn: (f'<Library path="{plugins}/libdds_security_{kind}.so" '  # noqa: E731
                            f'initFunction="init_{fn}" finalizeFunction="finalize_{fn}"/>')
    return f"""<CycloneDDS><Domain id="any"><Security>
  <Authentication>{lib("auth", "authentication")}
    <IdentityCA>{f("identity_ca.cert.pem")}</IdentityCA>
    <IdentityCertificate>{f("cert.pem")}</IdentityCertificate>
    <PrivateKey>{f("key.pem")}</PrivateKey>
  </Authentication>
  <AccessControl>{lib("ac", "access_control")}
    <PermissionsCA>{f("permissions_ca.cert.pem")}</PermissionsCA>
    <Governance>{f("governance.p7s")}</Governance>
    <Permissions>{f("permissions.p7s")}</Permissions>
  </AccessControl>
  <Cryptographic>{lib("crypto", "crypto")}</Cryptographic>
</Security></Domain></CycloneDDS>"""


def run_roles(script, keystore, enclaves, roles, seconds, pythonpath=None):
    """Runs `script --role R --seconds S` per role, each its own process (a participant), with
    the Cyclone security configuration of `enclaves[R]` from `keystore` (none for a role
    without one); returns {role: its JSON line}, or None (printed FAIL) if one failed."""
    procs = {}
    for role in roles:
        env = dict(os.environ)
        if pythonpath:
            env["PYTHONPATH"] = os.pathsep.join(pythonpath)
        if role in enclaves:
            env["CYCLONEDDS_URI"] = security_xml(os.path.join(keystore, "enclaves", enclaves[role]))
        else:
            env.pop("CYCLONEDDS_URI", None)
        # Debugging: FCC_CYCLONE_TRACE_DIR=DIR writes each role's Cyclone trace to DIR/ROLE.log.
        trace_dir = os.environ.get("FCC_CYCLONE_TRACE_DIR")
        if trace_dir:
            prior = env.get("CYCLONEDDS_URI")
            env["CYCLONEDDS_URI"] = (prior + "," if prior else "") + (
                '<CycloneDDS><Domain id="any"><Tracing><Verbosity>finest</Verbosity>'
                f'<OutputFile>{os.path.join(trace_dir, role + ".log")}</OutputFile>'
                '</Tracing></Domain></CycloneDDS>')
        procs[role] = subprocess.Popen(
            [sys.executable, script, "--role", role, "--seconds", str(seconds)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = {}
    for role, p in procs.items():
        out, err = p.communicate(timeout=seconds + 60)
        lines = [ln for ln in out.splitlines() if ln.startswith("{")]
        if p.returncode != 0 or not lines:
            print(f"FAIL {role}: exit {p.returncode}; {err.strip()[-400:]}")
            return None
        seen[role] = json.loads(lines[-1])
        print(f"{role}: {seen[role]}")
    return seen


def report(checks):
    """Prints PASS/FAIL per (name, ok, detail) and the totals; the exit status."""
    fails = 0
    for name, ok, detail in checks:
        print(f"{'PASS' if ok else 'FAIL'} {name}: {detail}")
        fails += not ok
    print(f"{len(checks) - fails} passed, {fails} failed")
    return 1 if fails else 0


def participant(role, seconds):
    """One participant (this process); prints one JSON line of what it saw."""
    from dataclasses import dataclass
    from cyclonedds.core import DDSException
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.idl import IdlStruct
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    @dataclass
    class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
        data: str

    dp = DomainParticipant(0)
    status = Topic(dp, "rt/fcc/status", String)
    mode = Topic(dp, "rt/fcc/cmd/mode", String)
    out = {"role": role, "received": 0, "writer": None}
    writer, reader = None, None
    if role == "bridge":
        writer, reader = DataWriter(dp, status), DataReader(dp, mode)
    else:
        reader = DataReader(dp, status)
        if role in ("ground", "observer"):
            try:
                writer = DataWriter(dp, mode)
                out["writer"] = "created"
            except DDSException as e:
                out["writer"] = f"refused: {e}"
    t_end = time.time() + seconds
    k = 0
    while time.time() < t_end:
        if writer is not None:
            writer.write(String(data=f"{role} {k}"))
            k += 1
        out["received"] += len(reader.take(N=100))
        time.sleep(0.05)
    print(json.dumps(out), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("keystore", nargs="?")
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--role", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.role:
        participant(a.role, a.seconds)
        return 0
    enclaves = {"bridge": "fcc/fcc_bridge", "ground": "ground_station", "observer": "observer"}
    seen = run_roles(__file__, a.keystore, enclaves, ["bridge", "ground", "observer", "plain"],
                     a.seconds)
    if seen is None:
        return 1
    checks = [
        ("the ground station's cmd/mode reaches the bridge enclave", seen["bridge"]["received"] > 0,
         f"{seen['bridge']['received']} samples"),
        ("the ground station may write cmd/mode", seen["ground"]["writer"] == "created",
         seen["ground"]["writer"]),
        ("the ground station receives status", seen["ground"]["received"] > 0,
         f"{seen['ground']['received']} samples"),
        ("the observer receives status", seen["observer"]["received"] > 0,
         f"{seen['observer']['received']} samples"),
        ("the observer's cmd/mode writer is refused by access control",
         str(seen["observer"]["writer"]).startswith("refused"), seen["observer"]["writer"]),
        ("an unauthenticated participant receives nothing", seen["plain"]["received"] == 0,
         f"{seen['plain']['received']} samples"),
    ]
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
