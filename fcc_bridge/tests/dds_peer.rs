//! Acceptance: the bridge against an independent Cyclone DDS peer (PyPI `cyclonedds`), driven by
//! the scripted fake MCU on a pty. Runs `tests/dds/run_e2e.sh`, which puts the fake MCU, the
//! bridge and the peer into one loopback-only network namespace (netns-run).
//!
//! Python: `FCC_DDS_PYTHON` (default `python3`) must import `cyclonedds`. Without it the test
//! is skipped with a message, unless `FCC_REQUIRE_DDS_PEER=1` (CI), where it fails.

mod common;

#[test]
fn bridge_against_cyclone_peer() {
    let Some(stdout) = common::run_peer_script("run_e2e.sh") else {
        return;
    };
    assert!(stdout.contains(" passed, 0 failed"));
}
