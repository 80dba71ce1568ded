#!/usr/bin/env bash
# fcc-bridge with ROS 2 security (issue 19), in ONE loopback-only network namespace:
#  1. start-up under ROS_SECURITY_STRATEGY=Enforce refuses, with one line naming the file and the
#     reason, a missing enclave, a tampered permissions file and an expired certificate;
#     Permissive runs without security and says so;
#  2. the bridge in enclave /fcc/fcc_bridge against the scripted fake MCU, judged by Debian's
#     Cyclone DDS 0.10 with its security plugins (tests/security/secure_peer.py, .venv-sec from
#     scripts/security-setup.sh): the ground station receives telemetry and its arm and setpoint
#     reach the MCU, the observer's writers are refused, an unauthenticated participant and one
#     of another CA receive nothing, a rogue node's writers (its own side not enforcing) are
#     denied by the bridge, which counts the refusals on /diagnostics and tells them on /rosout,
#     and a loopback capture holds no plaintext telemetry;
#  3. the square through fcc-launch with the bridge and the mission node in their enclaves (two
#     rustdds participants), and its bag in plaintext.
#   usage: [FCC_SECURITY_NO_FLIGHT=1] [FCC_SECURITY_KEEP=DIR] tests/security/secure_stack.sh   (~70 s)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0"
. "$root/tests/lib/fake_mcu.sh"
py="$root/.venv-sec/bin/python"
rc=0
check() { # NAME CONDITION-EXIT-STATUS DETAIL
  if [ "$2" -eq 0 ]; then echo "PASS $1${3:+: $3}"; else echo "FAIL $1${3:+: $3}"; rc=1; fi
}
ks="$tmp/keystore"
"$bin/fcc-keystore" create "$ks" > /dev/null
export ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce

# --- 1. Start-up checks (no DDS traffic: each refusal happens before the participant exists).
refused() { # NAME KEYSTORE ENCLAVE EXPECTED-TEXT
  local out s
  set +e
  out=$(ROS_SECURITY_KEYSTORE="$2" timeout 10 "$bin/fcc-bridge" --device /nonexistent \
        --ros-args --enclave "$3" 2>&1 | grep '^fcc-bridge:'); s=${PIPESTATUS[0]}
  set -e
  [ "$(printf '%s\n' "$out" | grep -c .)" -eq 1 ] && printf '%s' "$out" | grep -q "$4"
  check "Enforce refuses $1 with one line" $? "$out"
}
refused "a missing enclave" "$ks" /fcc/nope "no such enclave directory"
bad="$tmp/tampered"; cp -r "$ks" "$bad"
sed -i 's|rt/fcc/status|rt/fcc/statux|' "$bad/enclaves/fcc/fcc_bridge/permissions.p7s"
refused "a tampered permissions file" "$bad" /fcc/fcc_bridge "permissions.p7s: signature does not verify"
# An identity certificate from the same CA that expired in 2021 (openssl ca sets past dates).
old="$tmp/expired"; cp -r "$ks" "$old"; d="$old/enclaves/fcc/fcc_bridge"; ca="$tmp/ca"
mkdir -p "$ca/new"; : > "$ca/index.txt"; echo 1000 > "$ca/serial"
cat > "$ca/ca.cnf" <<EOF
[ca]
default_ca = c
[c]
database = $ca/index.txt
new_certs_dir = $ca/new
serial = $ca/serial
default_md = sha256
policy = p
[p]
commonName = supplied
EOF
openssl req -new -key "$d/key.pem" -subj '/CN=\/fcc\/fcc_bridge' -out "$ca/req.pem"
openssl ca -batch -config "$ca/ca.cnf" -in "$ca/req.pem" -out "$d/cert.pem" -notext \
  -cert "$ks/public/ca.cert.pem" -keyfile "$ks/private/ca.key.pem" \
  -startdate 20200101000000Z -enddate 20210101000000Z 2> "$ca/err" > /dev/null \
  || { cat "$ca/err"; exit 1; }
refused "an expired certificate" "$old" /fcc/fcc_bridge "cert.pem: certificate expired on"
set +e
out=$(ROS_SECURITY_STRATEGY=Permissive ROS_SECURITY_KEYSTORE="$ks" timeout 3 "$bin/fcc-bridge" \
      --device /nonexistent --ros-args --enclave /fcc/nope 2>&1)
set -e
printf '%s' "$out" | grep -q "running WITHOUT security"
check "Permissive runs without the missing enclave and says so" $? \
  "$(printf '%s\n' "$out" | grep -m1 -o 'security (Permissive).*')"

# --- 2. The secure bridge and the independent secure peers.
# A rogue enclave: the observer's identity and permissions with a governance that does not
# enforce write access control on its own side, signed by the same CA (a tampered node: its own
# Cyclone then creates the writers its permissions do not grant; the bridge must deny them).
rogue="$ks/enclaves/rogue"; cp -r "$ks/enclaves/observer" "$rogue"
sed 's|<enable_write_access_control>true|<enable_write_access_control>false|' \
  "$ks/enclaves/governance.xml" > "$tmp/governance_rogue.xml"
grep -q '<enable_write_access_control>false' "$tmp/governance_rogue.xml"
openssl smime -sign -text -in "$tmp/governance_rogue.xml" -out "$rogue/governance.p7s" \
  -signer "$ks/public/ca.cert.pem" -inkey "$ks/private/ca.key.pem"
# A participant of another keystore (another CA): authentication must fail.
"$bin/fcc-keystore" create "$tmp/foreign" > /dev/null
# One attempt: a fresh fake MCU and secure bridge, the five peers; sets s (the peer's status) and
# authenticated (how many participants completed the handshake with the bridge).
part2() {
  local n=$1
  start_fake_mcu 90 --log "$tmp/mcu$n.jsonl"
  ROS_SECURITY_KEYSTORE="$ks" RUST_LOG=info "$bin/fcc-bridge" --device "$pty" \
    --ros-args -r __ns:=/fcc --enclave /fcc/fcc_bridge > "$tmp/bridge$n.log" 2>&1 &
  bridge=$!
  set +e
  "$py" "$here/secure_peer.py" "$ks" --mcu-log "$tmp/mcu$n.jsonl" \
    --seconds "${FCC_SECURITY_SECONDS:-6}" --foreign "$tmp/foreign/enclaves/ground_station" \
    > "$tmp/peer$n.out" 2>&1
  s=$?
  set -e
  authenticated=$(grep -c "Authenticated successfully" "$tmp/bridge$n.log" || true)
}
part2 1
# A fixed defect (README, "Security"): until 2026-12-06, now and then (1 run in ~7 alone, ~1 in
# 4 under load) one of the three Cyclone participants with credentials never completed its
# handshake with the bridge (rustdds' stateless-message reader kept 1 message of all
# participants; it keeps 64 now, vendor/rustdds/VENDOR.md). Should the stall come back it is
# retried once and said: any other failure, or the same stall twice, fails the test.
if [ "$s" -ne 0 ] && [ "$authenticated" -lt 3 ] && kill -0 "$bridge" 2>/dev/null; then
  echo "RETRY part 2 (handshake stall, fixed once: a new cause?): only $authenticated of the 3 Cyclone participants" \
    "with credentials (ground, observer, rogue) authenticated with the bridge; attempt 1 saw:"
  sed 's/^/  attempt 1: /' "$tmp/peer1.out"
  kill -TERM "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
  part2 2
  cp "$tmp/bridge2.log" "$tmp/bridge.log"; cat "$tmp/peer2.out"
else
  cp "$tmp/bridge1.log" "$tmp/bridge.log"; cat "$tmp/peer1.out"
fi
check "Cyclone DDS 0.10 with its security plugins and the secure bridge" $s
if ! kill -0 "$bridge" 2>/dev/null; then echo "FAIL fcc-bridge died"; rc=1; fi
if [ $rc -ne 0 ]; then echo "--- bridge log"; grep -v '^\s*$' "$tmp/bridge.log" | tail -20; fi
kill -TERM "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
keep() { if [ -n "${FCC_SECURITY_KEEP:-}" ]; then mkdir -p "$FCC_SECURITY_KEEP"; cp "$tmp"/*.log "$tmp"/*.jsonl "$FCC_SECURITY_KEEP"/ 2>/dev/null || true; fi; }
if [ -n "${FCC_SECURITY_NO_FLIGHT:-}" ]; then keep; exit $rc; fi  # debugging: parts 1 and 2 only

# --- 3. The whole stack secure: fcc-sitl ⇄ fcc-bridge (/fcc/fcc_bridge) ⇄ fcc-mission
#     (/fcc/fcc_mission), two rustdds participants authenticating each other: the square flown
#     through fcc-launch at speed 4, every setpoint and command of the mission node over DDS
#     Security. A failed key exchange leaves the mission without a vehicle: it times out. The
#     bridge's bag of it is plaintext (the recorder is on the bridge's side of DDS Security).
part3() {
  t0=$SECONDS
  rm -rf "$tmp/square"
  set +e
  ROS_SECURITY_KEYSTORE="$ks" RUST_LOG=info timeout 150 "$bin/fcc-launch" \
    "$root/launch_configs/square_flight.yaml" BIN:="$bin" out:="$tmp/square" speed:=4 hover_s:=0 \
    record:="$tmp/square/secure.mcap" > "$tmp/launch.log" 2>&1
  lrc=$?
  set -e
}
part3
# A fixed defect (README, "Security"): now and then (3 of ~8 CI rehearsals until 2026-12-06,
# never alone) the mission node's rustdds hung at start-up on its security plugins' lock ("I
# need my lock!!" every 100 ms): a lock-order inversion, removed (vendor/rustdds/VENDOR.md;
# fcc_bridge/tests/secure_entity_race.rs). Should a hang come back (a new cause) it is retried
# once and said, with the holder: any other failure, or the same hang twice, fails the test.
if [ $lrc -ne 0 ] && grep -q 'I need my lock!!' "$tmp/launch.log" \
    && ! grep -q 'fcc-mission: mission complete' "$tmp/launch.log"; then
  echo "RETRY part 3 (rustdds security-lock hang of the mission node, fixed once: a new cause?): fcc-launch exit" \
    "$lrc after $((SECONDS - t0)) s, $(grep -c 'I need my lock!!' "$tmp/launch.log") lock" \
    "messages; attempt 1's launch log ends:"
  grep -v '^\s*$' "$tmp/launch.log" | grep -v 'I need my lock' | tail -15 | sed 's/^/  attempt 1: /'
  # rustdds names the waiting thread and call site and the lock's holder (thread, call site).
  grep -m2 'I need my lock' "$tmp/launch.log" | sed 's/^/  attempt 1 (first waits): /'
  mv "$tmp/launch.log" "$tmp/launch1.log"
  part3
fi
# The bag is recorded on the bridge's side of DDS Security: plaintext, read by Foxglove's mcap
# and rosbags (tests/mcap/check_bag.py), every message the bridge published in it.
bagpy="${FCC_DDS_PYTHON:-$root/.venv-dds/bin/python}"
s=0; "$bagpy" "$root/tests/mcap/check_bag.py" "$tmp/square/secure.mcap" \
  --counts "$tmp/square/secure.mcap.counts.json" --min-seconds 10 > "$tmp/bag.txt" 2>&1 || s=1
check "the secure flight's bag holds plaintext messages, read by independent readers" $s \
  "$(tail -1 "$tmp/bag.txt")"
grep -E '^\[mission\] fcc-mission: mission complete|^leg |^all ' "$tmp/launch.log" || true
for node in fcc_bridge fcc_mission; do
  s=0; grep "^\[${node#fcc_}\].*enclave" "$tmp/launch.log" | grep -qF "$ks/enclaves/fcc/$node" || s=1
  check "the $node node ran in its enclave /fcc/$node" $s
done
s=0; grep -q 'fcc-mission: mission complete' "$tmp/launch.log" && [ $lrc -eq 0 ] || s=1
check "the square flown through the secure bridge and mission node (fcc-launch exit $lrc, $((SECONDS - t0)) s)" $s
if [ $lrc -ne 0 ]; then echo "--- launch log"; grep -v '^\s*$' "$tmp/launch.log" | tail -25; fi
keep
exit $rc
