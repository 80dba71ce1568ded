//! Acceptance (issue 6 point 8): recording onto a full disk. Runs `tests/dds/run_disk_full.sh`:
//! fake MCU ⇄ `fcc-bridge --record` on a 384 KiB tmpfs (private mount namespace; or a file-size
//! limit where mounting is not possible) ⇄ the independent Cyclone DDS peer, in one
//! loopback-only network namespace. One clear error line on stderr and on `/rosout` (naming the
//! OS cause), the bridge keeps running and publishing, the bag up to the error is readable.
//!
//! Python: `FCC_DDS_PYTHON` must import `cyclonedds` (and `mcap`, `mcap_ros2` for the bag
//! check); skipped without it unless `FCC_REQUIRE_DDS_PEER=1`.

mod common;

#[test]
fn recording_onto_a_full_disk() {
    let Some(stdout) = common::run_peer_script("run_disk_full.sh") else {
        return;
    };
    assert!(stdout.contains("disk-full: all passed"));
    assert!(stdout.contains("PASS the bridge keeps publishing after the error"));
}
