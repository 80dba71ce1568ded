//! A node from `fcc_ros::ros_node::node` as another participant sees it, and its parameters.
//! Creates DDS participants: run it in a loopback-only namespace
//! (`../shared/tools/netns-run cargo test -p fcc_ros`).

use fcc_ros::ros_node::{self, DdsEnv};
use ros2_client::dds::Context;
use ros2_client::parameters::ParameterValue;
use ros2_client::Gid;
use rustdds::RTPSEntity;
use std::time::{Duration, Instant};

fn ctx() -> Context {
    ros_node::context(DdsEnv {
        domain_id: 0,
        localhost_only: true,
        enclave_dir: None,
    })
    .unwrap()
}

/// fcc-mission `-p use_sim_time:=true` read `false` through the parameter services before
/// (ros2-client's built-in default): the node declares the value in use.
#[tokio::test]
async fn node_declares_its_use_sim_time() {
    let ctx = ctx();
    for on in [true, false] {
        let name = format!("use_sim_time_{on}");
        let node = ros_node::node(&ctx, "/fcc_ros_test", &name, on).unwrap();
        assert_eq!(
            node.get_parameter("use_sim_time"),
            Some(ParameterValue::Boolean(on))
        );
    }
}

/// The spinner's `/clock` reader (vendored ros2-client) is typed `rosgraph_msgs/msg/Clock`
/// (was `builtin_interfaces/msg/Time`: two types on `/clock`) and is one of the node's readers
/// in `ros_discovery_info` (was outside the node: `ros2 topic info -v` showed an unknown node).
#[tokio::test]
async fn the_spinner_s_clock_reader_is_the_node_s_and_typed_clock() {
    let a = ctx();
    let _node = ros_node::node(&a, "/fcc_ros_test", "clock_reader", false).unwrap();
    let b = ctx();
    let prefix = a.domain_participant().guid().prefix;
    let t0 = Instant::now();
    let reader = loop {
        let found = b
            .domain_participant()
            .discovered_readers()
            .into_iter()
            .find(|r| {
                r.subscription_topic_data.topic_name() == "rt/clock"
                    && r.reader_proxy.remote_reader_guid.prefix == prefix
            });
        if let Some(r) = found {
            break r;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the node's /clock reader was not discovered"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    assert_eq!(
        reader.subscription_topic_data.type_name(),
        "rosgraph_msgs::msg::dds_::Clock_"
    );
    let gid = format!("{:?}", Gid::from(reader.reader_proxy.remote_reader_guid));
    let info = format!("{:?}", a.participant_entities_info());
    assert!(
        info.contains(&gid),
        "reader {gid} not among the node's readers: {info}"
    );
}
