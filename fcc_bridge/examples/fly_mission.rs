//! Test helper: fly a mission YAML through the bridge's ROS topics (odom in, arm / mode /
//! velocity setpoints out) with `fcc_mission`'s waypoint follower — a minimal stand-in for the
//! mission node, so that a SITL flight over the real link can be recorded.
//!   fly_mission MISSION.yaml [--timeout S] [--hover-s S]    (run under netns-run, with the bridge)
//! `--hover-s S`: after the last waypoint, hover in the MCU's HOLD mode (`cmd/mode` = `hold`, no
//! setpoints) for S seconds of the bag's clock (odometry stamps), then land — the flight core's
//! hover test (paper A Fig. 16: climb, HOLD at the current estimate, land) through the stack.
//! Exits 0 when the vehicle has landed and disarmed after the mission.

use fcc_bridge::report::bag::odom_ned;
use fcc_mission::{Request, WaypointFollower};
use fcc_msgs::ros::*;
use fcc_ros::frames::ned_to_enu;
use futures::{FutureExt, StreamExt};
use ros2_client::dds::{Node, Publisher, Subscription};
use ros2_client::qos::{History, WhenFull};
use ros2_client::{Name, NodeName, NodeOptions, QosProfile};
use std::time::{Duration, Instant};

/// The bridge's topics this driver uses (reliable, keep last 10).
struct Endpoints {
    odom: Subscription<Odometry>,
    status: Subscription<Status>,
    sp: Publisher<TwistStamped>,
    arm: Publisher<Bool>,
    mode: Publisher<StringMsg>,
}

fn endpoints(node: &mut Node) -> anyhow::Result<Endpoints> {
    let rel = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Fail)
        .history(History::KeepLast { depth: 10 });
    let t_odom = node.create_topic(
        &Name::parse("/fcc/state/odom")?,
        Odometry::type_name(),
        &rel,
    )?;
    let t_status = node.create_topic(&Name::parse("/fcc/status")?, Status::type_name(), &rel)?;
    let t_sp = node.create_topic(
        &Name::parse("/fcc/setpoint/velocity")?,
        TwistStamped::type_name(),
        &rel,
    )?;
    let t_arm = node.create_topic(&Name::parse("/fcc/cmd/arm")?, Bool::type_name(), &rel)?;
    let t_mode = node.create_topic(&Name::parse("/fcc/cmd/mode")?, StringMsg::type_name(), &rel)?;
    let odom = node.create_subscription::<Odometry>(&t_odom, Some(rel.clone()))?;
    let status = node.create_subscription::<Status>(&t_status, Some(rel.clone()))?;
    let sp = node.create_publisher::<TwistStamped>(&t_sp, None)?;
    let arm = node.create_publisher::<Bool>(&t_arm, None)?;
    let mode = node.create_publisher::<StringMsg>(&t_mode, None)?;
    Ok(Endpoints {
        odom,
        status,
        sp,
        arm,
        mode,
    })
}

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let mission_path = args
        .get(1)
        .expect("usage: fly_mission MISSION.yaml [--timeout S]");
    let timeout = args
        .iter()
        .position(|a| a == "--timeout")
        .and_then(|i| args.get(i + 1)?.parse::<f64>().ok())
        .unwrap_or(300.0);
    let hover_s = args
        .iter()
        .position(|a| a == "--hover-s")
        .and_then(|i| args.get(i + 1)?.parse::<f64>().ok())
        .unwrap_or(0.0);
    let mission = fcc_mission::from_yaml_str(&std::fs::read_to_string(mission_path)?)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut follower = WaypointFollower::new(mission);
    // The one participant builder: ROS_DOMAIN_ID, and loopback only unless ROS_LOCALHOST_ONLY=0
    // or ROS_AUTOMATIC_DISCOVERY_RANGE says otherwise (as the bridge and the mission node).
    let dds = fcc_ros::ros_node::DdsEnv::from_env(&fcc_ros::params::RosArgs::default())
        .map_err(anyhow::Error::msg)?;
    let ctx = fcc_ros::ros_node::context(dds).map_err(anyhow::Error::msg)?;
    let mut node = ctx.new_node(NodeName::new("/fcc", "fly_mission")?, NodeOptions::new())?;
    tokio::spawn(node.spinner()?.spin());
    let Endpoints {
        odom,
        status,
        sp,
        arm,
        mode,
    } = endpoints(&mut node)?;
    let odom_s = odom.async_stream();
    let status_s = status.async_stream();
    tokio::pin!(odom_s);
    tokio::pin!(status_s);
    let start = Instant::now();
    let (mut armed, mut was_armed, mut land_sent, mut landed) = (false, false, false, false);
    let mut first_odom: Option<Instant> = None;
    let mut last_arm = Instant::now() - Duration::from_secs(10);
    let mut ready = false;
    // Hover after the mission: (odom stamp at the hold command, last hold command sent).
    let mut hover: Option<(f64, Instant)> = None;
    let mut mode_now = Status::MODE_DISARMED;
    loop {
        if start.elapsed().as_secs_f64() > timeout {
            anyhow::bail!("mission not finished in {timeout} s");
        }
        tokio::select! {
            Some(Ok((s, _))) = status_s.next() => {
                armed = s.armed;
                mode_now = s.mode;
                landed = s.landed;
                was_armed |= armed;
                ready |= s.time_synced || s.header.stamp.to_nanos() > 0;
                if was_armed && !armed && land_sent {
                    eprintln!("fly_mission: landed and disarmed after the mission");
                    return Ok(());
                }
            }
            Some(Ok((o, _))) = odom_s.next() => {
                // Work on the newest odometry only: on a loaded machine a backlog would make the
                // setpoints (stamped with their odometry) too old for the bridge's TTL check.
                let mut o = o;
                while let Some(Some(Ok((n, _)))) = odom_s.next().now_or_never() {
                    o = n;
                }
                // Let the navigation calibrate (≈ 5 s after the first state) before starting.
                let f = *first_odom.get_or_insert_with(Instant::now);
                if !ready || f.elapsed() < Duration::from_secs(6) || land_sent {
                    continue;
                }
                let t = o.header.stamp.to_nanos() as f64 * 1e-9;
                if let Some((t_hold, sent)) = hover {
                    // Hovering in HOLD: no setpoints (a fresh one would resume velocity mode).
                    if t - t_hold >= hover_s {
                        let _ = mode.publish(StringMsg { data: "land".into() });
                        land_sent = true;
                        eprintln!("fly_mission: hovered {:.1} s in HOLD, landing", t - t_hold);
                    } else if mode_now != Status::MODE_HOLD && sent.elapsed() > Duration::from_secs(1) {
                        let _ = mode.publish(StringMsg { data: "hold".into() });
                        hover = Some((t_hold, Instant::now()));
                    }
                    continue;
                }
                let (p, v, _) = odom_ned(&o);
                let g = follower.update(t, [p[0] as f32, p[1] as f32, p[2] as f32], [v[0] as f32, v[1] as f32, v[2] as f32]);
                match g.request {
                    Some(Request::Arm) if !armed && last_arm.elapsed() > Duration::from_secs(1) => {
                        let _ = arm.publish(Bool { data: true });
                        last_arm = Instant::now();
                    }
                    Some(Request::Land) if !land_sent && hover_s > 0.0 => {
                        let _ = mode.publish(StringMsg { data: "hold".into() });
                        hover = Some((t, Instant::now()));
                        eprintln!("fly_mission: mission done, hovering {hover_s} s in HOLD");
                        continue;
                    }
                    Some(Request::Land) if !land_sent => {
                        let _ = mode.publish(StringMsg { data: "land".into() });
                        land_sent = true;
                        eprintln!("fly_mission: mission done, landing");
                        continue;
                    }
                    _ => {}
                }
                if armed {
                    let vn = g.vel_ned_mps;
                    let mut m = TwistStamped::default();
                    m.header = Header::new(o.header.stamp, "map");
                    m.twist.linear = Vector3::new(ned_to_enu([vn[0] as f64, vn[1] as f64, vn[2] as f64]));
                    let _ = sp.publish(m);
                }
            }
        }
        let _ = landed;
    }
}
