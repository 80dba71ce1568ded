//! A node from `fcc_ros::ros_node::node` reports the `use_sim_time` it runs with (fcc-mission
//! `-p use_sim_time:=true` read `false` through the parameter services before: ros2-client's
//! built-in default). Creates a DDS participant: run it in a loopback-only namespace
//! (`../shared/tools/netns-run cargo test -p fcc_ros`).

use fcc_ros::ros_node::{self, DdsEnv};
use ros2_client::parameters::ParameterValue;

#[tokio::test]
async fn node_declares_its_use_sim_time() {
    let ctx = ros_node::context(DdsEnv {
        domain_id: 0,
        localhost_only: true,
    })
    .unwrap();
    for on in [true, false] {
        let name = format!("use_sim_time_{on}");
        let node = ros_node::node(&ctx, "/fcc_ros_test", &name, on).unwrap();
        assert_eq!(
            node.get_parameter("use_sim_time"),
            Some(ParameterValue::Boolean(on))
        );
    }
}
