//! The actions of the ROS 2 interface package `fcc_msgs` (`msg/action/*.action`): each action
//! `A` is three structs, `AGoal`, `AResult` and `AFeedback`, in the field order of the file's
//! parts (checked by the `action_fields_match_action_files` test against the `FIELDS` that
//! `msg/build.rs` generates from the files, with the constants such as
//! `FollowWaypointsResult::OUTCOME_PREEMPTED`). ros2-client wraps them in its action services
//! and topics (`SendGoalRequest<AGoal>`, `GetResultResponse<AResult>`,
//! `FeedbackMessage<AFeedback>`); [`FOLLOW_WAYPOINTS`] names the type for it.

use super::custom::Waypoint;
use serde::{Deserialize, Serialize};

/// `fcc_msgs/action/FollowWaypoints` as (package, name), for `ros2_client::ActionTypeName`.
pub const FOLLOW_WAYPOINTS: (&str, &str) = ("fcc_msgs", "FollowWaypoints");

/// The text of `msg/action/FollowWaypoints.action`.
pub const FOLLOW_WAYPOINTS_DEFINITION: &str = include_str!("../../action/FollowWaypoints.action");

/// The goal of fcc_msgs/action/FollowWaypoints (see the `.action` file for units and defaults).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FollowWaypointsGoal {
    pub waypoints: Vec<Waypoint>,
    pub speed_mps: f32,
    pub accept_radius_m: f32,
    pub hold_s: f32,
    pub use_heading: bool,
    pub heading_deg: f32,
    pub takeoff_alt_m: f32,
    pub land_at_end: bool,
}
impl ros2_client::Message for FollowWaypointsGoal {}

/// The result of fcc_msgs/action/FollowWaypoints.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FollowWaypointsResult {
    pub outcome: u8,
    pub reason: String,
    pub waypoints_reached: u32,
}
impl ros2_client::Message for FollowWaypointsResult {}

/// The feedback of fcc_msgs/action/FollowWaypoints.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FollowWaypointsFeedback {
    pub current_waypoint: u32,
    pub waypoint_count: u32,
    pub phase: String,
    pub distance_to_go_m: f32,
    pub eta_s: f32,
    pub cross_track_m: f32,
}
impl ros2_client::Message for FollowWaypointsFeedback {}

/// `fcc_msgs/action/GoTo` (result and feedback: FollowWaypoints', as [`GoToResult`] and
/// [`GoToFeedback`] say).
pub const GO_TO: (&str, &str) = ("fcc_msgs", "GoTo");
/// `fcc_msgs/action/Takeoff`.
pub const TAKEOFF: (&str, &str) = ("fcc_msgs", "Takeoff");
/// `fcc_msgs/action/Land`.
pub const LAND: (&str, &str) = ("fcc_msgs", "Land");

/// The goal of fcc_msgs/action/GoTo: FollowWaypoints' fields for one point.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GoToGoal {
    pub target: Waypoint,
    pub speed_mps: f32,
    pub accept_radius_m: f32,
    pub hold_s: f32,
    pub use_heading: bool,
    pub heading_deg: f32,
    pub takeoff_alt_m: f32,
    pub land_at_end: bool,
}
impl ros2_client::Message for GoToGoal {}

/// The goal of fcc_msgs/action/Takeoff.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TakeoffGoal {
    pub altitude_m: f32,
}
impl ros2_client::Message for TakeoffGoal {}

/// The goal of fcc_msgs/action/Land.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LandGoal {
    pub at_home: bool,
}
impl ros2_client::Message for LandGoal {}

include!(concat!(env!("OUT_DIR"), "/ros_action_consts.rs"));
