//! The fixes carried in the vendored ros2-client (`vendor/ros2-client/VENDOR.md`) that can be
//! checked without a DDS participant. The `/clock` type name and the absence of ERROR lines at
//! start-up are checked on the running bridge (`fcc_bridge/tests/clean_start.rs`); the
//! parameter descriptors through the parameter services (`tests/dds/peer_ros.py`).

use log::Level;
use ros2_client::distributions::ros_distro_check;
use ros2_client::qos::{Durability, History, Reliability};
use ros2_client::{QosProfile, RosDistro, COMPILED_ROS_DISTRO};
use std::time::Duration;

#[test]
fn the_build_targets_jazzy() {
    assert_eq!(COMPILED_ROS_DISTRO, RosDistro::Jazzy);
}

/// Iron, Jazzy, Kilted and Rolling share the 16-byte GID wire form: no ERROR for those; Humble
/// (24-byte GIDs) keeps its ERROR.
#[test]
fn ros_distro_check_errs_only_for_another_wire_form() {
    let level = |d: Option<&str>| ros_distro_check(RosDistro::Jazzy, d).0;
    assert_eq!(level(Some("jazzy")), Level::Info);
    for d in ["kilted", "iron", "rolling", "lyrical"] {
        let (l, text) = ros_distro_check(RosDistro::Jazzy, Some(d));
        assert_eq!(l, Level::Info, "{d}: {text}");
        assert!(text.contains("16-byte"), "{text}");
    }
    assert_eq!(level(None), Level::Warn);
    for d in ["humble", "galactic", "foxy", "not-a-distro"] {
        assert_eq!(level(Some(d)), Level::Error, "{d}");
    }
    // A Humble build in a Jazzy shell is still the wrong wire form.
    assert_eq!(
        ros_distro_check(RosDistro::Humble, Some("jazzy")).0,
        Level::Error
    );
}

/// `/parameter_events` and `/rosout` as rcl offers them (Jazzy's `rmw/qos_profiles.h`
/// `rmw_qos_profile_parameter_events`, `rcl/logging_rosout.h` `rcl_qos_profile_rosout_default`).
#[test]
fn parameter_events_and_rosout_qos_are_rcl_s() {
    use ros2_client::builtin_topics::{parameter_events, rosout};
    let pe = QosProfile::from(&*parameter_events::QOS);
    assert!(matches!(pe.reliability, Reliability::Reliable { .. }));
    assert_eq!(pe.durability, Durability::Volatile);
    assert_eq!(pe.history, History::KeepLast { depth: 1000 });
    assert_eq!(pe.lifespan, None);
    let ro = QosProfile::from(&*rosout::QOS);
    assert!(matches!(ro.reliability, Reliability::Reliable { .. }));
    assert_eq!(ro.durability, Durability::TransientLocal);
    assert_eq!(ro.history, History::KeepLast { depth: 1000 });
    assert_eq!(ro.lifespan, Some(Duration::from_secs(10)));
}
