#!/usr/bin/env bash
# Run every test of the project. Installs what the tests need, then runs them with no network
# beyond loopback (DDS discovery must never leave the machine).
#   usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
# Wall time of each step, for the CI budget (30 min on 2 cores): `mark NAME` prints the seconds
# since the start; the summary at the end lists every step's share.
marks=()
mark() { marks+=("$SECONDS $1"); echo "[test.sh] ${SECONDS} s: $1"; }
# Steps that mostly wait (downloads, fixed-length soaks) run beside others so the test command
# fits its 30 min on 2 cores: `bg_start NAME CMD…` runs CMD with its output kept; `bg_wait NAME`
# waits for it, prints that output and stops the run if the step failed.
declare -A bg_pid bg_log
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT
bg_start() {
  local n=$1; shift
  bg_log[$n]=$(mktemp)
  "$@" > "${bg_log[$n]}" 2>&1 &
  bg_pid[$n]=$!
  echo "[test.sh] ${SECONDS} s: $n started beside the next steps"
}
bg_wait() {
  local n=$1 rc=0
  wait "${bg_pid[$n]}" || rc=$?
  echo "=== $n (ran beside other steps; done at ${SECONDS} s, exit $rc)"
  cat "${bg_log[$n]}"; rm -f "${bg_log[$n]}"
  if [ "$rc" -ne 0 ]; then echo "test.sh: $n failed (exit $rc)" >&2; exit 1; fi
}
mark "fetch + venvs"

# 1. Dependencies (needs the package registries): Rust crates, and the independent DDS peer
#    (PyPI cyclonedds, Cyclone DDS) that stands in for a ROS 2 node in the bridge tests.
cargo fetch --locked
if [ ! -x .venv-dds/bin/python ] || ! .venv-dds/bin/python -c 'import cyclonedds' 2>/dev/null; then
  python3 -m venv .venv-dds
  .venv-dds/bin/pip install -q --disable-pip-version-check cyclonedds
fi
# The bag readers of the recorder tests (Foxglove's mcap + mcap-ros2-support, rosbags).
if ! .venv-dds/bin/python -c 'import mcap, mcap_ros2.decoder, rosbags.highlevel' 2>/dev/null; then
  .venv-dds/bin/pip install -q --disable-pip-version-check mcap mcap-ros2-support rosbags
fi
# The independent Zenoh peer of the fleet test (issue 18): Zenoh's Python binding, the same
# release as the zenoh crate the nodes link (1.10.2).
if ! .venv-dds/bin/python -c 'import zenoh' 2>/dev/null; then
  .venv-dds/bin/pip install -q --disable-pip-version-check eclipse-zenoh==1.10.2
fi
export FCC_DDS_PYTHON="$PWD/.venv-dds/bin/python" FCC_REQUIRE_DDS_PEER=1
# Real ROS 2 (issue 16): Jazzy and Kilted rclpy on Fast DDS from PyPI wheels, each in its venv
# under target/ros2/, and `colcon build` of our interface package msg/ (fcc_msgs) with them; the
# wheel workarounds are in the script. Skips what is done (stamp). Figures: the script's header.
# Only the "real ROS 2 peer" step needs it: it runs from here beside everything before that step
# (its downloads overlap the other installs and the MCU step's; every apt-get here waits for
# dpkg's lock).
bg_start ros2-setup scripts/ros2-setup.sh jazzy kilted
# The independent secure DDS peer (issue 19): Debian's Cyclone DDS 0.10 with its security plugins
# (apt-get: libddsc0debian, cyclonedds-dev; root in CI) and its Python binding built against it in
# .venv-sec (PyPI sdist). Skips what is done.
mark "security-setup"
scripts/security-setup.sh

# --- step "MCU: cross-build, size, QEMU replay" (issue 8) ---------------------------------------
# Installs what it needs when missing (apt-get: Debian's rustc-web, cargo-web, rust-web-src,
# binutils-arm-none-eabi, qemu-system-arm; root in CI): that part here, before the offline
# namespace. Then scripts/test-mcu.sh fetches the board crate's crates, cross-builds the TM4C129x
# image for thumbv7em-none-eabihf (flash/RAM use; fails on f64 arithmetic outside lat/lon and
# one-off init), records a 16 s SITL flight on the host, replays it through the core in QEMU
# (Cortex-M4, mps2-an386), requires bit-identical motor commands, and prints instructions per
# 500 Hz step and the share of the 240,000-cycle budget (QEMU counts instructions: the figures do
# not depend on the host's load). It is ~370 s of CPU with no deadline: it runs at nice 19 beside
# the builds and the workspace tests, on the CPU they leave idle (the release build's serial
# stretches: one big crate or a link at a time), and is waited for before the end-to-end steps
# (first in the test command it held both cores for ~235 s before the workspace build could
# start; running on beside end-to-end phase 1 it paused the mission node's setpoints past the
# MCU's 0.3 s TTL once in a CI rehearsal, robust_stack kill-mission). tests/tests/mcu_qemu.rs
# (the same script for a plain `cargo test`) is skipped in the workspace tests for that reason.
mark "MCU toolchain"
MCU_INSTALL_ONLY=1 MCU_WITH_QEMU=1 scripts/build-mcu.sh
bg_start test-mcu nice -n 19 scripts/test-mcu.sh
# --- end of step "MCU: cross-build, size, QEMU replay" ------------------------------------------

# 2. Everything that runs, in a private network namespace with loopback only when available.
netns=""
for c in ../shared/tools/netns-run /work/shared/tools/netns-run; do
  if [ -x "$c" ] && "$c" true 2>/dev/null; then netns=$c; break; fi
done
if [ -z "$netns" ]; then
  echo "test.sh: no network namespace available; running without one (no DDS test runs yet)" >&2
fi

run() { if [ -n "$netns" ]; then "$netns" "$@"; else "$@"; fi; }

# The MCU core builds without std (no heap, no OS) by default, and depends on nothing of the
# simulator (the nested crate fcc_sim) or of the Linux side.
mark "core builds + check-deps"
run cargo build --offline --locked -p fcc_firmware
core_deps=$(cargo tree --offline --locked -p fcc_firmware -e normal --prefix none --format '{p}' | awk '{print $1}' | sort -u)
if sim_deps=$(grep -xE 'fcc_sim|fcc_mission|fcc_bridge|serde_yaml|serde_path_to_error|rand|rand_chacha|rand_distr|clap|nix|signal-hook|tokio' <<<"$core_deps"); then
  echo "test.sh: fcc_firmware (the MCU core) depends on: $(echo $sim_deps)" >&2; exit 1
fi
run cargo build --offline --locked -p fcc_msgs --no-default-features
# The dependency rules (issue 15): who may depend on the bridge application, fcc_mission on
# fcc_msgs + fcc_ros only, the MCU crate's default build without the simulator, no import circles.
scripts/check-deps.sh
# Every program the end-to-end tests start (fcc-sitl, fcc-bridge, fcc-fake-mcu, fcc-mission,
# fcc-launch, fcc-wire-fault, fcc-report, the recorder's mission driver), built before the tests.
# One feature set for every workspace build and test below: fcc_mission's `ros` (fcc-mission,
# fcc-launch and their tests) unified with the rest, so cargo compiles each dependency once (a
# second resolution rebuilt rustdds with DDS Security, ring, openssl and ros2-client: ~3.5 min).
features=(--features fcc_mission/ros)
mark "release builds"
run cargo build --offline --locked --release --workspace --bins --examples "${features[@]}"
# Unit tests beside the code, the scenario tests in tests/ (optimised: whole flights), the DDS
# peer and recorder tests, and the ROS 2 side of fcc_mission (feature `ros`): fcc-mission's and
# fcc-launch's own tests, the mission node's start-up protection (stalled DDS set-up, SIGTERM
# during start-up).
# Two test binaries fly or drive whole stacks in real time and mostly wait (the recorder on a SITL
# square, hostile input and a killed recording: ~75 s each, run one after the other by cargo):
# they run below in the end-to-end lanes; here their tests are skipped by name (listed from the
# binaries themselves, so a new test in them moves with them).
waiting_tests=(--test recorder --test hostile_and_crash)
# The soak's short form (issue 14): scripts/soak.sh, the whole stack (BER 1e-6, recording, the
# bridge SIGKILLed and restarted at 0.85 of the run) for 6 min: 0 messages lost unexplained
# (after the restart too), and the RSS slope ≤ 10 MB/h of each process over its 4.3 min after
# warm-up. It starts here, beside the workspace tests, and ends in e2e phase 1 (it uses ~15 % of
# a core and measures memory, not time; host stalls are counted apart). It was 3.5 min in phase
# 1 with the kill half-way: each bridge instance's 1-minute window could not resolve 10 MB/h —
# the bridge's RSS rises 0.3–0.5 MB between its 30-s heap trims (fcc_ros::heap) and drops at
# each, and the same binary read −22 to +20 MB/h (a CI run failed on +19.6). With the kill
# half-way in 6 min, the restarted bridge (2.2 min after its warm-up) read +1.1, +6.6 and +12.8
# MB/h in three runs (22.9 → 23.3 and 23.3 → 23.9 MB: a bridge restarted into a running graph
# grows for its first minutes; the 40-min soak measured it at +0.23 MB/h after an 8-min
# warm-up) while the first read −1.8 to +0.6. The restarted instance's slope is the long soak's
# (BENCHMARKS.md, README); here its losses are checked. This catches the leaks the long soak
# found (77, 25–38 MB/h) but cannot certify the ≤ 1 MB/h goal; the ≥ 30-minute benchmark does.
bg_start soak scripts/soak.sh 6 --warmup-s 45 --sample-s 2 --goal-mb-h 10 --kill-at 0.85
mark "cargo test (workspace)"
run cargo test --offline --locked --workspace --release "${features[@]}" --no-run
skip=()
while read -r t; do skip+=(--skip "$t"); done < <(
  run cargo test --offline --locked --workspace --release "${features[@]}" "${waiting_tests[@]}" -q \
    -- --list --format terse 2>/dev/null | sed -n 's/: test$//p')
[ ${#skip[@]} -gt 0 ] || { echo "test.sh: listing the waiting tests failed (${skip[*]})" >&2; exit 1; }
# The MCU step's own script, run beside (above).
skip+=(--skip core_on_emulated_cortex_m4f_matches_host)
run cargo test --offline --locked --workspace --release "${features[@]}" -- --exact "${skip[@]}"
# The board's sensor/actuator drivers (MPU-9250, MS5611, UBX, laser, sonar, S.BUS, ESC PWM) on the
# host, against datasheet byte sequences (the board crate is not a workspace member).
mark "cargo test (board drivers)"
run cargo test --offline --locked --manifest-path fcc_firmware/board/Cargo.toml --features std
# The end-to-end steps below mostly wait on simulated flights (each ~0.5 core at speed 2) and on
# the clock (the soak), each in its own loopback-only namespace. Phase 1 runs the ones that do
# not mind sharing the CPU in two lanes beside the quiet soak and churn; phase 2 runs alone the
# four whose checks need the CPU (the setpoint flood's wall-clock latency, four_uav's rates, the
# rclpy observer's /clock rate, the DDS Security handshakes of five participants at once).
# Measured alone on this machine (wall s / CPU s): run_stack 85/55, robust_stack 118/59,
# flood_uplink 12/11, command_safety 26/11, heading 47/22, slow_link 46/14, keystore 8/3,
# secure_stack 64/35, churn 75/14, soak (3.5 min) 211/58, four_uav ~40/80, the two waiting cargo tests ~150.
# The MCU step (above) ends here: nothing timing-sensitive runs beside it.
mark "MCU (its wait, if it is still running)"
bg_wait test-mcu
mark "e2e phase 1 (two lanes beside the soak)"
# --- lane 3: leaks (issue 14): the churn test beside the soak (started above) ----------------------
# - participant churn: 40 cycles of 20 Cyclone DDS participants joining and leaving the bridge,
#   RSS growth ≤ 20 MB and flat over the second half (tests/e2e/churn.sh, ~75 s);
# - the soak's short form started before the workspace tests (below the release builds).
bg_start churn tests/e2e/churn.sh "$FCC_DDS_PYTHON"
# --- lane 2 ----------------------------------------------------------------------------------------
# The waiting cargo tests (above), then the full stack (fcc-sitl --link-pty ⇄ fcc-bridge ⇄
# fcc-mission, started by fcc-launch) against the independent Cyclone DDS peer, in ONE
# loopback-only namespace.
lane2() {
  run cargo test --offline --locked --workspace --release "${features[@]}" "${waiting_tests[@]}" &&
    tests/e2e/run_stack.sh "$FCC_DDS_PYTHON"
}
bg_start "waiting cargo tests + run_stack" lane2
# --- lane 1 ----------------------------------------------------------------------------------------
# Robustness through the real pty + bridge (issue 6): bad configuration, a noisy wire under the
# square mission, the mission node killed mid-leg, the bridge and the serial device lost and back.
tests/e2e/robust_stack.sh "$FCC_DDS_PYTHON"
# Command safety through the real pty + bridge (issue 14): cmd/arm false, cmd/mode disarm and arm
# toggled at 100 Hz at 5 m refused and counted with the vehicle holding ±0.5 m on the CSV truth,
# the emergency kill only by cmd/kill "KILL"; bridge parameters outside their safe range refused.
tests/e2e/command_safety.sh "$FCC_DDS_PYTHON"
# Heading and yaw rate through the real pty + bridge (issue 17): angular.z turns the vehicle at the
# commanded rate ±10 % and a setpoint/heading of east is held within 3° RMS on a leg, on the CSV
# truth; bad headings refused and counted; fcc-mission's yaw_deg 90 held on a leg. ~50 s.
tests/e2e/heading.sh "$FCC_DDS_PYTHON"
# The slow-link profile (issue 20): the square over a 115200-baud UART (fcc-wire-fault, 115200 baud
# in simulated time) with launch_configs/slow_link_115200.yaml's rates: cross-track RMS ≤ 0.3 m,
# ≤ 80 % of the line after start-up, the profile's rates in the bag, no CRC error, no failsafe. ~45 s.
tests/e2e/slow_link.sh "$FCC_DDS_PYTHON"
# SROS2 keystore (issue 19): `fcc-keystore create` (CA, governance, least-privilege enclaves from
# the topic table) checked with openssl and by Debian's Cyclone DDS 0.10 with its security
# plugins: ground-station commands pass, the observer's writer is refused, an unauthenticated
# participant sees nothing; bad enclave names and roles refused. ~15 s.
tests/security/keystore.sh
bg_wait "waiting cargo tests + run_stack"
bg_wait soak
bg_wait churn
# --- phase 2, alone --------------------------------------------------------------------------------
# Uplink budget (issue 14): a 10 kHz setpoint flood through a 921600-baud line (fcc-wire-fault --baud):
# land/hold at the MCU ≤ 100 ms after the peer's write (wall clock), uplink ≤ 25 % of the line,
# ≤ 101 setpoints/s. Alone: beside the lanes the flooding peer and the pty fell behind (CI).
mark "flood_uplink"
tests/e2e/flood_uplink.sh "$FCC_DDS_PYTHON"
# Four vehicles on one DDS domain (/uav1 … /uav4, each its own SITL, bridge and mission): every
# namespaced topic seen by the Cyclone peer, no message crossing namespaces, CPU use printed.
# At speed 1 (simulated time = wall time; the checks are in ROS time): at speed 2 the four
# simulated 921600-baud links carry twice their bytes per wall second, and on a noisy 2-core
# machine the bridges fell behind their ptys once in CI (IMU at 117–133 Hz of 200 at the peer,
# odometry at 93 of 100, the stack at 138 % of a core). ~70 s.
mark "four_uav"
FCC_E2E_SPEED=1 tests/e2e/four_uav.sh "$FCC_DDS_PYTHON"
# Zenoh (issue 18), two tests side by side, each in its own loopback-only namespace (each about
# half a core at speed 1; alone one after the other they took 75 + 67 s of the CI's 30 min):
# - a fleet (tests/zenoh/fleet.sh): four vehicles at two sites, each site's nodes clients of its
#   own fcc-zenoh-router, the routers linked; the independent eclipse-zenoh peer at site B checks
#   every vehicle's tokens and topics against its own truth and flies a vehicle of site A; then,
#   sites not linked, nothing of site A reaches site B. At speed 1 (four vehicles, as four_uav).
# - faults (tests/zenoh/faults.sh): the link between the sites cut (a TCP relay killed) for 5 s,
#   then router A killed for 5 s and restarted: the resume time at site B printed, no gap at the
#   peer's own site, uav2 landed by the MCU's failsafes and uav3's mission complete, checked on
#   the simulators' truth (touchdowns, no flyaway). At speed 1.
#   Then, in the same lane (tests/zenoh/launch_replay.sh, ~40 s): the square through
#   `fcc-launch … rmw:=rmw_zenoh_cpp` (the launcher starts the router; speed 4, with a bag), and
#   the bag replayed by fcc-replay on Zenoh to the independent peer, byte for byte.
mark "zenoh fleet + faults, launch_replay (side by side)"
zenoh_lane() {
  tests/zenoh/faults.sh "$FCC_DDS_PYTHON" && tests/zenoh/launch_replay.sh "$FCC_DDS_PYTHON"
}
bg_start "zenoh faults + launch_replay" zenoh_lane
tests/zenoh/fleet.sh "$FCC_DDS_PYTHON"
bg_wait "zenoh faults + launch_replay"
# The bridge with ROS 2 security (issue 19): Enforce refuses a missing enclave, a tampered
# permissions file and an expired certificate with one line; in enclave /fcc/fcc_bridge it
# authenticates with Debian's Cyclone DDS 0.10 (rustdds' DDS Security): the ground station gets
# telemetry and its arm and setpoint reach the MCU, the observer's writers are refused, a rogue
# node's writers (its own side not enforcing) are denied by the bridge, counted on /diagnostics and
# told on /rosout, participants without credentials or of another CA get nothing and are counted,
# a loopback capture holds no plaintext telemetry; then the square through fcc-launch with the
# bridge and the mission node each in its enclave, and its bag read in plaintext. ~70 s.
mark "security stack"
tests/security/secure_stack.sh
# Real ROS 2 (issue 16): rclpy (Jazzy, and a Kilted smoke run) against the whole stack, in ONE
# loopback-only namespace: node/topic list (one type per topic), echo of every topic with the
# CLI's and sensor-data QoS vs the simulator's truth, TF, parameters (describe with
# ranges/read-only), the arm/hold/land services, setpoints on rclpy's default QoS flying the
# vehicle, a late joiner, a restarted peer, use_sim_time at speed 1.5, no ERROR line from the stack
# (ROS_DISTRO unset, jazzy, kilted); and (part d, issue 17) the mission node's FollowWaypoints
# action through rclpy's ActionClient: the square as one goal (cross-track vs the YAML flight's),
# a goal outside the geofence refused, a lat/lon goal's feedback and result on the truth,
# cancel = hold, preemption (~80 s wall).
bg_wait ros2-setup
mark "ros2 peer"
tests/ros2/run_ros2_peer.sh
mark "end"
echo "=== test.sh: wall time per step (s)"
for ((i = 0; i + 1 < ${#marks[@]}; i++)); do
  read -r t0 n0 <<< "${marks[i]}"; read -r t1 _ <<< "${marks[i + 1]}"
  printf '  %5d  %s\n' $((t1 - t0)) "$n0"
done
echo "  total ${SECONDS} s"
