//! The `follow_waypoints` action server (`fcc_msgs/action/FollowWaypoints`) of the mission node:
//! ros2-client's [`ActionServer`] (its `_action/send_goal`, `cancel_goal`, `get_result` services
//! and `feedback`, `status` topics, the names and wrappers rclpy's ActionClient uses), polled
//! once per cycle. This file keeps the goals' statuses and results and answers the services;
//! what a goal does is `fcc_mission::executive` (pure). ros2-client's `AsyncActionServer` is not
//! used: its result call waits for the client's result request, and two goals ending together
//! (a preemption) can each take the other's request (see the vendored crate's VENDOR.md).

use fcc_msgs::ros::{FollowWaypointsFeedback, FollowWaypointsGoal, FollowWaypointsResult};
use ros2_client::action::{
    ActionServer, ActionServerQosPolicies, GetResultResponse, GoalId, GoalInfo, GoalStatusEnum,
};
use ros2_client::action_msgs::{
    CancelGoalResponse, CancelGoalResponseEnum, GoalStatus, GoalStatusArray,
};
use ros2_client::builtin_interfaces::Time as RosTime;
use ros2_client::qos::{Durability, History};
use ros2_client::{ActionTypeName, Name, Node, QosProfile, RmwRequestId, ServiceMapping};

type Server = ActionServer<FollowWaypointsGoal, FollowWaypointsResult, FollowWaypointsFeedback>;

/// Finished goals kept for late result requests.
const KEEP_FINISHED: usize = 16;

struct Entry {
    id: GoalId,
    accepted: RosTime,
    status: GoalStatusEnum,
    result: Option<FollowWaypointsResult>,
}

/// A goal request to decide on: accept it ([`FollowWaypointsServer::accept`]) or not.
pub struct NewGoal {
    pub id: GoalId,
    pub goal: FollowWaypointsGoal,
}

/// The server and its goals.
pub struct FollowWaypointsServer {
    server: Server,
    goals: Vec<Entry>,
    waiting_results: Vec<(GoalId, RmwRequestId)>,
}

fn is_terminal(s: GoalStatusEnum) -> bool {
    matches!(
        s,
        GoalStatusEnum::Succeeded | GoalStatusEnum::Canceled | GoalStatusEnum::Aborted
    )
}

/// The QoS rclpy's ActionClient uses: services reliable, volatile, keep last 10; feedback the
/// same; status reliable, transient local, keep last 1 (`qos_profile_action_status_default`).
fn qos() -> ActionServerQosPolicies {
    let services = fcc_ros::ros_node::reliable_qos(10);
    let status = QosProfile::publisher_default()
        .reliability_reliable(ros2_client::qos::WhenFull::Fail)
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 });
    ActionServerQosPolicies {
        goal_service: services.clone(),
        result_service: services.clone(),
        cancel_service: services.clone(),
        feedback_publisher: services,
        status_publisher: status,
    }
}

impl FollowWaypointsServer {
    /// The server on the ROS name `name` (relative: under the node's namespace).
    pub fn new(node: &mut Node, name: &str) -> Result<Self, String> {
        let n = Name::parse(name).map_err(|e| format!("action {name}: {e:?}"))?;
        let (pkg, ty) = fcc_msgs::ros::FOLLOW_WAYPOINTS;
        let server = node
            .create_action_server::<FollowWaypointsGoal, FollowWaypointsResult, FollowWaypointsFeedback>(
                ServiceMapping::Enhanced,
                &n,
                &ActionTypeName::new(pkg, ty),
                qos(),
            )
            .map_err(|e| format!("action {name}: {e:?}"))?;
        Ok(FollowWaypointsServer {
            server,
            goals: Vec::new(),
            waiting_results: Vec::new(),
        })
    }

    /// Goal requests received since the last call (each must be accepted: refusals are
    /// accepted and aborted with the reason, so the client gets it in the result).
    pub fn new_goals(&mut self) -> Vec<(RmwRequestId, NewGoal)> {
        let mut out = Vec::new();
        while let Ok(Some((req, r))) = self.server.receive_goal() {
            if self.goals.iter().any(|g| g.id == r.goal_id) {
                continue; // a duplicate id: ignored (its first request was answered)
            }
            out.push((
                req,
                NewGoal {
                    id: r.goal_id,
                    goal: r.goal,
                },
            ));
        }
        out
    }

    /// Accepts a goal (status ACCEPTED, then EXECUTING).
    pub fn accept(&mut self, req: RmwRequestId, id: GoalId) {
        let accepted = RosTime::now();
        let _ = self.server.send_goal_response(
            req,
            ros2_client::action::SendGoalResponse {
                accepted: true,
                stamp: accepted,
            },
        );
        self.goals.push(Entry {
            id,
            accepted,
            status: GoalStatusEnum::Executing,
            result: None,
        });
        self.publish_statuses();
    }

    /// Cancel requests since the last call: answered here (the running goals they name start
    /// canceling); returns those goals' ids.
    pub fn cancel_requests(&mut self) -> Vec<GoalId> {
        let mut out = Vec::new();
        while let Ok(Some((req, r))) = self.server.receive_cancel_request() {
            let GoalInfo { goal_id, stamp } = r.goal_info;
            let all = goal_id == GoalId::ZERO && stamp == RosTime::ZERO;
            let named = |g: &Entry| {
                all || (goal_id != GoalId::ZERO && g.id == goal_id)
                    || (stamp != RosTime::ZERO && g.accepted <= stamp)
            };
            let known = goal_id == GoalId::ZERO || self.goals.iter().any(|g| g.id == goal_id);
            let canceling: Vec<GoalInfo> = self
                .goals
                .iter_mut()
                .filter(|g| !is_terminal(g.status) && named(g))
                .map(|g| {
                    g.status = GoalStatusEnum::Canceling;
                    GoalInfo {
                        goal_id: g.id,
                        stamp: g.accepted,
                    }
                })
                .collect();
            let return_code = match (canceling.is_empty(), known) {
                (false, _) => CancelGoalResponseEnum::None,
                (true, false) => CancelGoalResponseEnum::UnknownGoal,
                (true, true) if goal_id != GoalId::ZERO => CancelGoalResponseEnum::GoalTerminated,
                (true, true) => CancelGoalResponseEnum::Rejected,
            };
            out.extend(canceling.iter().map(|g| g.goal_id));
            let _ = self.server.send_cancel_response(
                req,
                CancelGoalResponse {
                    return_code,
                    goals_canceling: canceling,
                },
            );
            self.publish_statuses();
        }
        out
    }

    /// A goal ended: its status and result (sent to a waiting result request, kept for later).
    pub fn finish(&mut self, id: GoalId, status: GoalStatusEnum, result: FollowWaypointsResult) {
        let Some(g) = self.goals.iter_mut().find(|g| g.id == id) else {
            return; // not an action goal (the mission file's)
        };
        g.status = status;
        g.result = Some(result);
        self.publish_statuses();
        self.answer_results();
        // Forget the oldest finished goals beyond KEEP_FINISHED.
        while self.goals.iter().filter(|g| is_terminal(g.status)).count() > KEEP_FINISHED {
            let i = self
                .goals
                .iter()
                .position(|g| is_terminal(g.status))
                .unwrap();
            self.goals.remove(i);
        }
    }

    /// Result requests since the last call: answered when the goal has ended (an unknown goal:
    /// status UNKNOWN), else kept until it ends.
    pub fn poll_results(&mut self) {
        while let Ok(Some((req, r))) = self.server.receive_result_request() {
            self.waiting_results.push((r.goal_id, req));
        }
        self.answer_results();
    }

    fn answer_results(&mut self) {
        let goals = &self.goals;
        let server = &self.server;
        self.waiting_results.retain(|(id, req)| {
            let reply = match goals.iter().find(|g| g.id == *id) {
                None => Some((GoalStatusEnum::Unknown, FollowWaypointsResult::default())),
                Some(g) => g.result.clone().map(|r| (g.status, r)),
            };
            match reply {
                Some((status, result)) => {
                    let _ = server.send_result(*req, GetResultResponse { status, result });
                    false
                }
                None => true,
            }
        });
    }

    /// Feedback of a running goal.
    pub fn feedback(&self, id: GoalId, f: FollowWaypointsFeedback) {
        let _ = self.server.send_feedback(id, f);
    }

    fn publish_statuses(&self) {
        let status_list = self
            .goals
            .iter()
            .map(|g| GoalStatus {
                goal_info: GoalInfo {
                    goal_id: g.id,
                    stamp: g.accepted,
                },
                status: g.status,
            })
            .collect();
        let _ = self
            .server
            .send_goal_statuses(GoalStatusArray { status_list });
    }
}
