//! Acceptance (issue 7): the bridge's ROS 2 interfaces — parameters over the rcl_interfaces
//! services (incl. a refused out-of-range set and gains reaching the MCU), std_srvs services,
//! /rosout levels, use_sim_time, remaps/namespace/--params-file, /tf_static for a late joiner —
//! against the independent Cyclone DDS peer (`tests/dds/run_ros_e2e.sh`, one loopback-only
//! network namespace). Skipped without a Python that imports `cyclonedds`, unless
//! `FCC_REQUIRE_DDS_PEER=1`.

mod common;

#[test]
fn ros_interfaces_against_cyclone_peer() {
    let Some(stdout) = common::run_peer_script("run_ros_e2e.sh") else {
        return;
    };
    assert!(stdout.contains(" passed, 0 failed"));
    assert!(!stdout.contains("FAIL"));
}
