//! The action servers of the mission node — `follow_waypoints`, `go_to`, `takeoff`, `land`
//! ([`ACTIONS`]; `fcc_msgs/action/*`): each is ros2-client's [`ActionServer`] on DDS or its Zenoh one ([`ActionSrv`]) (its `_action/send_goal`, `cancel_goal`, `get_result` services
//! and `feedback`, `status` topics, the names and wrappers rclpy's ActionClient uses), polled
//! once per cycle. This file keeps the goals' statuses and results and answers the services,
//! and turns goals into the mission logic's ([`take_goals`], [`finish`], [`feedback`]); what a
//! goal does is `fcc_mission::executive` and `fcc_mission::goal` (pure). ros2-client's `AsyncActionServer` is not
//! used: its result call waits for the client's result request, and two goals ending together
//! (a preemption) can each take the other's request (see the vendored crate's VENDOR.md).

use super::{Heard, Log};
use fcc_mission::executive::{Executive, Finished, GoalEnd};
use fcc_mission::goal::{self, Fence, GoalPoint, GoalSpec};
use fcc_mission::run::{Level, RunKind, RunProgress};
use fcc_msgs::ros::{
    FollowWaypointsFeedback, FollowWaypointsGoal, FollowWaypointsResult, GoToGoal, LandGoal,
    TakeoffGoal, Waypoint,
};
use fcc_ros::rmw::RosNode;
use ros2_client::action::{
    ActionServer, ActionServerQosPolicies, GetResultResponse, GoalId, GoalInfo, GoalStatusEnum,
};
use ros2_client::action_msgs::{
    CancelGoalResponse, CancelGoalResponseEnum, GoalStatus, GoalStatusArray,
};
use ros2_client::builtin_interfaces::Time as RosTime;
use ros2_client::dds::ServiceMapping;
use ros2_client::qos::{Durability, History};
use ros2_client::{ActionTypeName, Name, QosProfile, RmwRequestId};

/// Every action has FollowWaypoints' result and feedback (the mission executive's).
type Server<G> = ActionServer<G, FollowWaypointsResult, FollowWaypointsFeedback>;
type ZenohServer<G> =
    ros2_client::zenoh::ActionServer<G, FollowWaypointsResult, FollowWaypointsFeedback>;

/// One action's server on either middleware: the calls [`GoalServer`] makes. On Zenoh a cancel
/// request's stamp is not passed on by ros2-client (cancel by goal id or all goals), and the
/// goal response carries no acceptance stamp (the status array does). Send failures are not
/// reported (a client that went away), as before.
enum ActionSrv<G: ros2_client::Message + Clone> {
    Dds(Server<G>),
    Zenoh(ZenohServer<G>),
}

impl<G: ros2_client::Message + Clone + 'static> ActionSrv<G> {
    fn receive_goal(&self) -> Option<(RmwRequestId, GoalId, G)> {
        match self {
            ActionSrv::Dds(s) => s
                .receive_goal()
                .ok()
                .flatten()
                .map(|(q, r)| (q, r.goal_id, r.goal)),
            ActionSrv::Zenoh(s) => s.try_receive_goal(),
        }
    }
    fn accept(&self, req: RmwRequestId, stamp: RosTime) {
        let _ = match self {
            ActionSrv::Dds(s) => s
                .send_goal_response(
                    req,
                    ros2_client::action::SendGoalResponse {
                        accepted: true,
                        stamp,
                    },
                )
                .is_ok(),
            ActionSrv::Zenoh(s) => s.respond_goal(req, true).is_ok(),
        };
    }
    fn receive_cancel(&self) -> Option<(RmwRequestId, GoalInfo)> {
        match self {
            ActionSrv::Dds(s) => s
                .receive_cancel_request()
                .ok()
                .flatten()
                .map(|(q, r)| (q, r.goal_info)),
            ActionSrv::Zenoh(s) => s.try_receive_cancel().map(|(q, goal_id)| {
                (
                    q,
                    GoalInfo {
                        goal_id,
                        stamp: RosTime::ZERO,
                    },
                )
            }),
        }
    }
    fn respond_cancel(&self, req: RmwRequestId, r: CancelGoalResponse) {
        let _ = match self {
            ActionSrv::Dds(s) => s.send_cancel_response(req, r).is_ok(),
            ActionSrv::Zenoh(s) => s
                .respond_cancel(req, r.return_code, r.goals_canceling)
                .is_ok(),
        };
    }
    fn receive_result_request(&self) -> Option<(RmwRequestId, GoalId)> {
        match self {
            ActionSrv::Dds(s) => s
                .receive_result_request()
                .ok()
                .flatten()
                .map(|(q, r)| (q, r.goal_id)),
            ActionSrv::Zenoh(s) => s.try_receive_result_request(),
        }
    }
    fn send_result(
        &self,
        req: RmwRequestId,
        status: GoalStatusEnum,
        result: FollowWaypointsResult,
    ) {
        let _ = match self {
            ActionSrv::Dds(s) => s
                .send_result(req, GetResultResponse { status, result })
                .is_ok(),
            // action_msgs' status codes: the enum's values (`#[repr(i8)]`).
            ActionSrv::Zenoh(s) => s.respond_result(req, status as i8, result).is_ok(),
        };
    }
    fn send_feedback(&self, id: GoalId, f: FollowWaypointsFeedback) {
        let _ = match self {
            ActionSrv::Dds(s) => s.send_feedback(id, f).is_ok(),
            ActionSrv::Zenoh(s) => s.publish_feedback(id, f).is_ok(),
        };
    }
    fn send_statuses(&self, status_list: Vec<GoalStatus>) {
        let _ = match self {
            ActionSrv::Dds(s) => s
                .send_goal_statuses(GoalStatusArray { status_list })
                .is_ok(),
            ActionSrv::Zenoh(s) => s.publish_status(status_list).is_ok(),
        };
    }
}

/// Finished goals kept for late result requests.
const KEEP_FINISHED: usize = 16;

struct Entry {
    id: GoalId,
    accepted: RosTime,
    status: GoalStatusEnum,
    result: Option<FollowWaypointsResult>,
}

/// A goal request to decide on: accept it ([`GoalServer::accept`]) or not.
pub struct NewGoal<G> {
    pub id: GoalId,
    pub goal: G,
}

/// One action's server and its goals.
pub struct GoalServer<G: ros2_client::Message + Clone> {
    server: ActionSrv<G>,
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

impl<G> GoalServer<G>
where
    G: ros2_client::Message + Clone + 'static,
{
    /// The server of the action type `(package, name)` on the ROS name `name` (relative: under
    /// the node's namespace).
    pub fn new(node: &mut RosNode, name: &str, action_type: (&str, &str)) -> Result<Self, String> {
        let n = Name::parse(name).map_err(|e| format!("action {name}: {e:?}"))?;
        let (pkg, ty) = action_type;
        let t = ActionTypeName::new(pkg, ty);
        let server = match node {
            RosNode::Dds(node) => node
                .create_action_server::<G, FollowWaypointsResult, FollowWaypointsFeedback>(
                    ServiceMapping::Enhanced,
                    &n,
                    &t,
                    qos(),
                )
                .map(ActionSrv::Dds)
                .map_err(|e| format!("action {name}: {e:?}"))?,
            RosNode::Zenoh(node) => node
                .create_action_server::<G, FollowWaypointsResult, FollowWaypointsFeedback>(&n, &t)
                .map(ActionSrv::Zenoh)
                .map_err(|e| format!("action {name}: {e:?}"))?,
        };
        Ok(GoalServer {
            server,
            goals: Vec::new(),
            waiting_results: Vec::new(),
        })
    }

    /// Goal requests received since the last call (each must be accepted: refusals are
    /// accepted and aborted with the reason, so the client gets it in the result).
    pub fn new_goals(&mut self) -> Vec<(RmwRequestId, NewGoal<G>)> {
        let mut out = Vec::new();
        while let Some((req, id, goal)) = self.server.receive_goal() {
            if self.goals.iter().any(|g| g.id == id) {
                continue; // a duplicate id: ignored (its first request was answered)
            }
            out.push((req, NewGoal { id, goal }));
        }
        out
    }

    /// Accepts a goal (status ACCEPTED, then EXECUTING).
    pub fn accept(&mut self, req: RmwRequestId, id: GoalId) {
        let accepted = RosTime::now();
        self.server.accept(req, accepted);
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
        while let Some((req, GoalInfo { goal_id, stamp })) = self.server.receive_cancel() {
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
            self.server.respond_cancel(
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
        while let Some((req, goal_id)) = self.server.receive_result_request() {
            self.waiting_results.push((goal_id, req));
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
                    server.send_result(*req, status, result);
                    false
                }
                None => true,
            }
        });
    }

    /// Feedback of a running goal of this action (others' are not sent here).
    pub fn feedback(&self, id: GoalId, f: FollowWaypointsFeedback) {
        if self.goals.iter().any(|g| g.id == id) {
            self.server.send_feedback(id, f);
        }
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
        self.server.send_statuses(status_list);
    }
}

// ---- the actions' goals ↔ the mission logic (fcc_mission::executive, goal) ----

/// The mission node's actions, ONE table: (ROS name relative to the node's namespace,
/// `fcc_msgs/action` type). [`Servers`] holds one server per row, in this order.
pub const ACTIONS: [(&str, (&str, &str)); 4] = [
    ("mission/follow_waypoints", fcc_msgs::ros::FOLLOW_WAYPOINTS),
    ("mission/go_to", fcc_msgs::ros::GO_TO),
    ("mission/takeoff", fcc_msgs::ros::TAKEOFF),
    ("mission/land", fcc_msgs::ros::LAND),
];

/// The servers of [`ACTIONS`]. Every goal becomes a FollowWaypoints goal of the one
/// executive (goal ids are UUIDs: each server answers for its own).
pub struct Servers {
    follow: GoalServer<FollowWaypointsGoal>,
    go_to: GoalServer<GoToGoal>,
    takeoff: GoalServer<TakeoffGoal>,
    land: GoalServer<LandGoal>,
}

/// What turning goals into missions needs.
pub struct GoalContext<'a> {
    pub exec: &'a mut Executive<GoalId>,
    pub heard: &'a Heard,
    pub fence: Fence,
    pub wall_s: f64,
    pub log: &'a Log,
    pub now_ns: Option<i64>,
}

impl Servers {
    /// One server per row of [`ACTIONS`], on `names` (the rows' names after the remaps).
    pub fn new(node: &mut RosNode, names: &[String; 4]) -> Result<Self, String> {
        Ok(Servers {
            follow: GoalServer::new(node, &names[0], ACTIONS[0].1)?,
            go_to: GoalServer::new(node, &names[1], ACTIONS[1].1)?,
            takeoff: GoalServer::new(node, &names[2], ACTIONS[2].1)?,
            land: GoalServer::new(node, &names[3], ACTIONS[3].1)?,
        })
    }

    /// New goals (accepted; refused ones end at once with the reason; a started one preempts
    /// the running goal, whichever action it came from) and cancel requests (the vehicle holds).
    pub fn take_goals(&mut self, c: &mut GoalContext) {
        let here = c.heard.odom.as_ref().map(|o| {
            let p = &o.pose.pose.position;
            [p.x, p.y, p.z]
        });
        let armed = c.heard.status.as_ref().is_some_and(|s| s.armed);
        let mut ended = Vec::new();
        take(&mut self.follow, c, &mut ended, |g| Ok(goal_spec(g)));
        take(&mut self.go_to, c, &mut ended, |g| {
            let f = FollowWaypointsGoal {
                waypoints: vec![g.target.clone()],
                speed_mps: g.speed_mps,
                accept_radius_m: g.accept_radius_m,
                hold_s: g.hold_s,
                use_heading: g.use_heading,
                heading_deg: g.heading_deg,
                takeoff_alt_m: g.takeoff_alt_m,
                land_at_end: g.land_at_end,
            };
            Ok(goal_spec(&f))
        });
        take(&mut self.takeoff, c, &mut ended, |g| {
            goal::takeoff_spec(g.altitude_m, here)
        });
        take(&mut self.land, c, &mut ended, |g| {
            goal::land_spec(g.at_home, here, armed)
        });
        for f in ended {
            self.finish(&f, c.log, c.now_ns);
        }
    }

    /// A goal ended: its result on its action (and a log line).
    pub fn finish(&mut self, f: &Finished<GoalId>, log: &Log, now_ns: Option<i64>) {
        let (status, r) = end_result(f);
        let line = format!(
            "goal {:?} ended: {:?}{}{}",
            f.id,
            status,
            if r.reason.is_empty() { "" } else { ": " },
            r.reason
        );
        let level = if status == GoalStatusEnum::Succeeded {
            Level::Info
        } else {
            Level::Warn
        };
        log.line(level, now_ns, &line);
        self.follow.finish(f.id, status, r.clone());
        self.go_to.finish(f.id, status, r.clone());
        self.takeoff.finish(f.id, status, r.clone());
        self.land.finish(f.id, status, r);
    }

    /// Feedback of the running goal, on its action.
    pub fn feedback(&self, id: GoalId, p: &RunProgress) {
        let f = feedback(p);
        self.follow.feedback(id, f.clone());
        self.go_to.feedback(id, f.clone());
        self.takeoff.feedback(id, f.clone());
        self.land.feedback(id, f);
    }

    /// Result requests of every action (see [`GoalServer::poll_results`]).
    pub fn poll_results(&mut self) {
        self.follow.poll_results();
        self.go_to.poll_results();
        self.takeoff.poll_results();
        self.land.poll_results();
    }
}

/// One server's new goals and cancel requests; `spec` reads a goal (or refuses it). Goals it
/// ends elsewhere (preempted, canceled) go to `ended`, for [`Servers::finish`].
fn take<G>(
    srv: &mut GoalServer<G>,
    c: &mut GoalContext,
    ended: &mut Vec<Finished<GoalId>>,
    spec: impl Fn(&G) -> Result<GoalSpec, goal::Refusal>,
) where
    G: ros2_client::Message + Clone + 'static,
{
    for (req, g) in srv.new_goals() {
        srv.accept(req, g.id);
        match spec(&g.goal).and_then(|s| goal::to_mission(&s, c.heard.home, c.fence)) {
            Err(why) => {
                c.log.line(
                    Level::Warn,
                    c.now_ns,
                    &format!("goal {:?} refused: {why}", g.id),
                );
                let r = result(FollowWaypointsResult::OUTCOME_REFUSED, why.to_string(), 0);
                srv.finish(g.id, GoalStatusEnum::Aborted, r);
            }
            Ok(m) => {
                let then = if m.land_at_end {
                    ", then land"
                } else {
                    ", then hold"
                };
                let line = format!(
                    "goal {:?}: {} waypoints at {} m/s{then}",
                    g.id,
                    m.waypoints.len(),
                    m.speed_mps
                );
                c.log.info(c.now_ns, &line);
                ended.extend(c.exec.start(g.id, m, RunKind::ActionGoal, c.wall_s));
            }
        }
    }
    for id in srv.cancel_requests() {
        match c.exec.cancel(&id, c.wall_s) {
            Some(f) => ended.push(f),
            None => {
                let r = result(
                    FollowWaypointsResult::OUTCOME_CANCELED,
                    "canceled before it ran".into(),
                    0,
                );
                srv.finish(id, GoalStatusEnum::Canceled, r);
            }
        }
    }
}

/// The status and result of an ended goal.
fn end_result(f: &Finished<GoalId>) -> (GoalStatusEnum, FollowWaypointsResult) {
    use FollowWaypointsResult as R;
    let reached = f.reached as u32;
    match &f.end {
        GoalEnd::Succeeded => (
            GoalStatusEnum::Succeeded,
            result(R::OUTCOME_SUCCEEDED, String::new(), reached),
        ),
        GoalEnd::Failsafe(m) => (
            GoalStatusEnum::Aborted,
            result(R::OUTCOME_FAILSAFE, m.clone(), reached),
        ),
        GoalEnd::PilotOverride(m) => (
            GoalStatusEnum::Aborted,
            result(R::OUTCOME_PILOT_OVERRIDE, m.clone(), reached),
        ),
        GoalEnd::Preempted => (
            GoalStatusEnum::Aborted,
            result(
                R::OUTCOME_PREEMPTED,
                "preempted by a newer goal".into(),
                reached,
            ),
        ),
        GoalEnd::Canceled => (
            GoalStatusEnum::Canceled,
            result(
                R::OUTCOME_CANCELED,
                "canceled: holding at the current point (cmd/mode hold)".into(),
                reached,
            ),
        ),
    }
}

fn result(outcome: u8, reason: String, waypoints_reached: u32) -> FollowWaypointsResult {
    FollowWaypointsResult {
        outcome,
        reason,
        waypoints_reached,
    }
}

/// The action's goal as the plain goal the mission logic checks (the ONE place where
/// `fcc_msgs/Waypoint` frames are read).
fn goal_spec(g: &FollowWaypointsGoal) -> GoalSpec {
    let point = |w: &Waypoint| match w.frame {
        Waypoint::FRAME_GLOBAL => GoalPoint::Global {
            latitude_deg: w.latitude_deg,
            longitude_deg: w.longitude_deg,
            altitude_m: w.altitude_m,
        },
        // An unknown frame reads as NaN: refused as not finite.
        Waypoint::FRAME_LOCAL_ENU => GoalPoint::LocalEnu {
            x_m: w.x_m,
            y_m: w.y_m,
            z_m: w.z_m,
        },
        _ => GoalPoint::LocalEnu {
            x_m: f64::NAN,
            y_m: f64::NAN,
            z_m: f64::NAN,
        },
    };
    GoalSpec {
        points: g.waypoints.iter().map(point).collect(),
        speed_mps: g.speed_mps,
        accept_radius_m: g.accept_radius_m,
        hold_s: g.hold_s,
        heading_deg: if g.use_heading {
            g.heading_deg
        } else {
            f32::NAN
        },
        takeoff_alt_m: g.takeoff_alt_m,
        land_at_end: g.land_at_end,
    }
}

fn feedback(p: &RunProgress) -> FollowWaypointsFeedback {
    FollowWaypointsFeedback {
        current_waypoint: p.waypoint as u32,
        waypoint_count: p.waypoint_count as u32,
        phase: p.phase.into(),
        distance_to_go_m: p.distance_to_go_m,
        eta_s: p.eta_s,
        cross_track_m: p.cross_track_m,
    }
}
