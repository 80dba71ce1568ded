//! Checks of the generated [`crate::type_hashes`] table (rmw_zenoh interop): published Jazzy
//! hashes, coverage of the types the nodes use, and that ros2-client's Zenoh backend returns the
//! table's values once registered (its built-in values, which win, agree).

use crate::topics;
use crate::type_hashes::TYPE_HASHES;
use std::collections::HashMap;

fn table() -> HashMap<&'static str, &'static str> {
    let map: HashMap<_, _> = TYPE_HASHES.iter().copied().collect();
    assert_eq!(map.len(), TYPE_HASHES.len(), "a type is in the table twice");
    map
}

/// `pkg/kind/Name` → `pkg::kind::dds_::Name_`, as ros2-client names it.
fn dds(ros_type: &str) -> String {
    let parts: Vec<&str> = ros_type.split('/').collect();
    assert_eq!(parts.len(), 3, "{ros_type}");
    format!("{}::{}::dds_::{}_", parts[0], parts[1], parts[2])
}

/// REP-2016 hashes as ROS 2 Jazzy installs them (share/<pkg>/**/<Type>.json), known
/// independently of our hashing (String: rmw_zenoh's design document; the others: Jazzy's
/// values as rmw_zenoh peers advertise them; services: the service type's hash).
#[test]
fn published_jazzy_hashes() {
    let t = table();
    for (ros_type, want) in [
        (
            "sensor_msgs/msg/Imu",
            "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b",
        ),
        (
            "std_msgs/msg/String",
            "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
        ),
        (
            "nav_msgs/msg/Odometry",
            "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
        ),
        (
            "diagnostic_msgs/msg/DiagnosticArray",
            "RIHS01_5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e",
        ),
        (
            "std_srvs/srv/SetBool",
            "RIHS01_abe9e4bb6b41b40e6789712c00ec8871923e089af3f667a79992a428cff2da0a",
        ),
        (
            "std_srvs/srv/Trigger",
            "RIHS01_eeff2cd6fa5ad9d27cdf4dec64818317839b62f212a91e6b5304b634b2062c5f",
        ),
    ] {
        assert_eq!(t.get(dds(ros_type).as_str()), Some(&want), "{ros_type}");
    }
}

/// Every type the nodes put on Zenoh is in the table: the topic table's (fcc-mission's topics
/// are of the same types), the bridge's std_srvs services, each fcc_msgs action's parts.
#[test]
fn covers_the_nodes_types() {
    let t = table();
    let mut want: Vec<String> = topics::table().iter().map(|r| dds(&r.1)).collect();
    want.push(dds("std_srvs/srv/SetBool"));
    want.push(dds("std_srvs/srv/Trigger"));
    use fcc_msgs::ros::{FOLLOW_WAYPOINTS, GO_TO, LAND, TAKEOFF};
    for (pkg, name) in [FOLLOW_WAYPOINTS, GO_TO, TAKEOFF, LAND] {
        for part in ["SendGoal", "GetResult", "FeedbackMessage"] {
            want.push(format!("{pkg}::action::dds_::{name}_{part}_"));
        }
    }
    let missing: Vec<&String> = want
        .iter()
        .filter(|d| !t.contains_key(d.as_str()))
        .collect();
    assert!(
        missing.is_empty(),
        "not in type_hashes.rs (regenerate it): {missing:?}"
    );
    for (name, hash) in TYPE_HASHES {
        assert!(
            hash.len() == 71
                && hash.starts_with("RIHS01_")
                && hash[7..]
                    .bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)),
            "{name}: {hash}"
        );
    }
}

/// Registered with ros2-client, the backend's lookup (what its senders, servers and tokens use)
/// gives each table value; for the types it knows itself (std_msgs String, Bool) its value is
/// used, so this also checks that the two agree.
#[test]
fn backend_uses_the_table() {
    ros2_client::zenoh::register_type_hashes(TYPE_HASHES);
    for (name, hash) in TYPE_HASHES {
        assert_eq!(ros2_client::zenoh::type_hash(name), Some(*hash), "{name}");
    }
}
