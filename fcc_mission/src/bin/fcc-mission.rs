//! `fcc-mission [--mission FILE] [--ros-args -r __ns:=/fcc -p name:=value …]`
//!
//! The mission node: serves the actions `mission/follow_waypoints`, `mission/go_to`,
//! `mission/takeoff` and `mission/land` (`fcc_msgs/action/*`, the table `actions::ACTIONS`:
//! local ENU or lat/lon waypoints, feedback, cancel = hold, a new goal of any of them preempts
//! the running one; `actions.rs`) and, with `--mission FILE`, flies that mission YAML (see
//! `launch_configs/missions/`) as its first goal through the same logic
//! (`fcc_mission::executive`), then exits with its result.
//! Subscribes `state/odom` (nav_msgs/Odometry, ENU/FLU), `status` (fcc_msgs/Status) and `home`
//! (sensor_msgs/NavSatFix: lat/lon goals are converted against it),
//! publishes `setpoint/velocity` (geometry_msgs/TwistStamped, frame `map`, ENU) at `rate_hz`,
//! with the mission's `yaw_deg` (if set) just before each on `setpoint/heading`
//! (geometry_msgs/QuaternionStamped, frame `map`, an ENU orientation about z),
//! `cmd/arm` (std_msgs/Bool), `cmd/mode` (std_msgs/String "hold", "land") and `mission/status`
//! (std_msgs/String, one JSON object per message); logs to stdout and `/rosout`.
//!
//! After the last waypoint it lands (`cmd/mode` "land"), or with `-p hover_s:=S` (S > 0) first
//! hovers S seconds of ROS time in the MCU's HOLD mode (`cmd/mode` "hold", no setpoints; paper A
//! Fig. 16), then lands. The sequencing (arming, the pilot's pause, the phases, the end) is
//! `fcc_mission::run::MissionRun` (pure, unit-tested); this file does the ROS/DDS I/O.
//!
//! Exit codes: 0 when the vehicle is landed and disarmed after the mission, or on SIGTERM/SIGINT
//! (served by a thread of their own; a second signal, or a stop not begun within 1.5 s, exits
//! at once); 1 on a failure (timeout, disarmed in flight, DDS setup; also when the DDS start-up
//! stalled on each of 3 attempts: it restarts itself after a stall, see
//! `fcc_ros::startup`); 2 on a bad mission file or bad arguments.

#[path = "fcc-mission/actions.rs"]
mod actions;

use actions::{GoalContext, Servers, ACTIONS};
use clap::Parser;
use fcc_mission::executive::{ExecConfig, Executive, Finished, GoalEnd};
use fcc_mission::goal::{Fence, Home};
use fcc_mission::run::{Input, Level, McuStatus, RunKind, Sample, Step};
use fcc_mission::{node_params, McuMode, Mission};
use fcc_msgs::ros::{
    Bool, Clock, Header, NavSatFix, Odometry, Quaternion, QuaternionStamped, Status, StringMsg,
    Time, Twist, TwistStamped, Vector3,
};
use fcc_ros::frames;
use fcc_ros::params::{self, parse_bool};
use fcc_ros::rmw::{Pub, Rmw, RosContext, RosNode, Rosout, Sub};
use fcc_ros::ros_node::{self, DdsEnv, RosClock};
use fcc_ros::startup;
use fcc_ros::topics;
use futures::StreamExt;
use ros2_client::action::GoalId;
use ros2_client::log::LogLevel;
use ros2_client::parameters::{NumericRange, ParameterDescriptor, ParameterType, ParameterValue};
use ros2_client::NodeOptions;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(
    name = "fcc-mission",
    about = "ROS 2 mission node: flies a waypoint mission through fcc-bridge"
)]
struct Cli {
    /// Mission YAML (launch_configs/missions/*.yaml).
    #[arg(long)]
    mission: Option<String>,
}

struct Options {
    /// The mission file ("" without one).
    mission_file: String,
    mission: Option<Mission>,
    namespace: String,
    node_name: String,
    dds: DdsEnv,
    /// DDS or Zenoh (`RMW_IMPLEMENTATION`, `fcc_ros::rmw`).
    rmw: Rmw,
    rate_hz: f64,
    use_sim_time: bool,
    timeout_s: f64,
    arm_timeout_s: f64,
    /// Seconds of ROS time in HOLD after the last waypoint before landing (0 = land at once).
    hover_s: f64,
    /// `-r from:=to` topic remaps (e.g. `-r /clock:=clock`: a per-vehicle simulated clock).
    remaps: Vec<(String, String)>,
}

impl Options {
    /// A topic name after the remaps (relative names resolve under the node's namespace).
    fn name(&self, n: &str) -> String {
        params::remap(&self.remaps, &self.namespace, n)
    }
}

fn fail(code: i32, msg: String) -> ! {
    eprintln!("fcc-mission: {msg}");
    std::process::exit(code)
}

/// `--help`'s text after the options: ROS arguments, the parameter table, the environment.
fn after_help() -> String {
    format!(
        "ROS arguments: --ros-args [-r __ns:=/fcc] [-r __node:=fcc_mission] [-r topic:=new_name ...]\n  \
         [-p name:=value ...] (remaps as the bridge's, e.g. -r /clock:=clock for a per-vehicle clock)\n\
         {}\
         Environment: ROS_DOMAIN_ID, ROS_LOCALHOST_ONLY, ROS_AUTOMATIC_DISCOVERY_RANGE,\n  \
         FCC_MISSION_DDS_STARTUP_TIMEOUT_MS (5000: restart when the DDS set-up takes longer).",
        node_params::help()
    )
}

fn options() -> Options {
    let argv: Vec<String> = std::env::args().collect();
    let (prog, ros) = params::split_ros_args(&argv).unwrap_or_else(|e| fail(2, e));
    let cli: Cli = fcc_mission::cli::parse_with_help("fcc-mission", prog, after_help())
        .unwrap_or_else(|code| std::process::exit(code.into()));
    let p = &ros.params;
    if let Some(k) = p.keys().find(|k| node_params::by_name(k).is_none()) {
        fail(2, format!("unknown parameter '{k}'"));
    }
    // A number parameter: its value, or its default (the table's).
    let num = |k: &str| -> f64 {
        let param = node_params::by_name(k).expect("a parameter of the table");
        match p.get(k) {
            None => param.default_number(),
            Some(v) => param.number(v).unwrap_or_else(|e| fail(2, e)),
        }
    };
    let mission_file = cli
        .mission
        .or_else(|| p.get("mission").cloned())
        .unwrap_or_default();
    let mission = (!mission_file.is_empty()).then(|| {
        let text = std::fs::read_to_string(&mission_file)
            .unwrap_or_else(|e| fail(2, format!("{mission_file}: {e}")));
        fcc_mission::from_yaml_str(&text)
            .unwrap_or_else(|e| fail(2, format!("{mission_file}: {e}")))
    });
    let use_sim_time = p
        .get("use_sim_time")
        .map(|v| parse_bool(v).unwrap_or_else(|e| fail(2, format!("parameter use_sim_time: {e}"))))
        .unwrap_or(false);
    let hover_s = num("hover_s");
    let rate_hz = num("rate_hz");
    Options {
        mission_file,
        mission,
        namespace: ros.namespace.clone().unwrap_or_else(|| "/fcc".into()),
        node_name: ros
            .node_name
            .clone()
            .unwrap_or_else(|| "fcc_mission".into()),
        dds: DdsEnv::from_env(&ros).unwrap_or_else(|e| fail(2, e)),
        rmw: Rmw::from_env().unwrap_or_else(|e| fail(2, e)),
        rate_hz,
        use_sim_time,
        timeout_s: num("timeout_s"),
        arm_timeout_s: num("arm_timeout_s"),
        hover_s,
        remaps: ros.remaps.clone(),
    }
}

/// The ONE place where ROS state (ENU position, FLU body twist) becomes the follower's NED:
/// position ENU → NED; velocity FLU → ENU (rotated by the ENU/FLU attitude) → NED.
fn odom_to_ned(o: &Odometry) -> ([f32; 3], [f32; 3]) {
    let p = &o.pose.pose.position;
    let q = &o.pose.pose.orientation;
    let pos = frames::enu_to_ned([p.x, p.y, p.z]);
    let v_enu = frames::quat_rotate(
        frames::quat_normalize([q.w, q.x, q.y, q.z]),
        o.twist.twist.linear.to_array(),
    );
    let vel = frames::enu_to_ned(v_enu);
    let f = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
    (f(pos), f(vel))
}

/// Wall time the node stays alive after its last message (reliable re-sends), before exiting.
const LINGER: Duration = Duration::from_millis(1000);

fn stamp(ns: i64) -> Time {
    Time::from_nanos(ns)
}

/// The node's log lines: stdout (`fcc-mission: …`, what fcc-launch shows) and `/rosout`,
/// stamped with ROS time (simulated time with use_sim_time; the system clock before the first
/// /clock).
struct Log {
    rosout: Rosout,
    name: String,
}

impl Log {
    fn log(&self, level: LogLevel, now_ns: Option<i64>, msg: &str) {
        println!("fcc-mission: {msg}");
        let stamp_ns = now_ns.unwrap_or_else(fcc_ros::now_ns);
        self.rosout
            .log(stamp_ns, level, &self.name, msg, file!(), line!());
    }
    fn info(&self, now_ns: Option<i64>, msg: &str) {
        self.log(LogLevel::Info, now_ns, msg)
    }
    /// A line of the mission logic, at its level.
    fn line(&self, level: Level, now_ns: Option<i64>, msg: &str) {
        let level = match level {
            Level::Info => LogLevel::Info,
            Level::Warn => LogLevel::Warn,
        };
        self.log(level, now_ns, msg)
    }
}

/// The MCU's status as the mission logic reads it: the ONE place where `fcc_msgs/Status`
/// modes become [`McuMode`] (Pilot is a flag of its own; other modes read as disarmed).
fn mcu_status(st: &Status) -> McuStatus<'_> {
    // Pilot is a flag of its own; an unknown code reads as disarmed.
    let mode = match McuMode::from_code(st.mode) {
        Some(McuMode::Pilot) | None => McuMode::Disarmed,
        Some(m) => m,
    };
    McuStatus {
        armed: st.armed,
        landed: st.landed,
        mode,
        pilot: st.mode == Status::MODE_PILOT,
        failsafe: st.failsafe != Status::FAILSAFE_NONE,
        mode_name: &st.mode_name,
        failsafe_name: &st.failsafe_name,
        last_reject: &st.last_reject,
    }
}

/// fcc-mission, for `fcc_ros::startup` (messages and environment variables).
const APP: startup::App = startup::App {
    name: "fcc-mission",
    env_prefix: "FCC_MISSION",
};

fn main() {
    // Zenoh's blocking calls refuse a current-thread runtime (`fcc_ros::rmw::runtime`).
    let rmw = Rmw::from_env().unwrap_or_else(|e| fail(2, e));
    let rt = fcc_ros::rmw::runtime(rmw)
        .unwrap_or_else(|e| fail(1, format!("cannot start the tokio runtime: {e}")));
    rt.block_on(async_main())
}

async fn async_main() {
    // The DDS libraries' warnings and errors (a failed key exchange, a refused handshake) on
    // stderr; the node's own lines are its Log's.
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "warn,rustdds=error,ros2_client=warn".into())
                // ros2-client echoes every /rosout record as an event: the node prints its lines.
                .add_directive("ros2_client::rosout=off".parse().expect("static directive")),
        )
        .with_writer(std::io::stderr)
        .init();
    let o = options();
    // Free heap pages back to the OS every 30 s: a flat RSS over hours (fcc_ros::heap).
    fcc_ros::heap::spawn_trimmer();
    // SIGTERM / SIGINT from now on, whatever the DDS start-up does.
    let stop = startup::Stop::install(APP)
        .unwrap_or_else(|e| fail(1, format!("cannot install the signal handlers: {e}")));
    let mut run = Box::pin(run(o));
    let r = tokio::select! {
        r = &mut run => r,
        _ = stop.wait() => Ok(()),
    };
    stop.stopping();
    // Exit without tearing down DDS entity by entity (rustdds joins its threads on drop).
    std::mem::forget(run);
    match r {
        Ok(()) => std::process::exit(0),
        Err(Failure::Stalled(e)) => {
            // The stalled participant cannot be recovered in this process: start afresh (same
            // pid, arguments and environment), a few times.
            APP.restart_after_stall(&e);
            fail(1, e)
        }
        Err(Failure::Exit(code, msg)) => fail(code, msg),
    }
}

/// Why [`run`] ended without success.
enum Failure {
    Exit(i32, String),
    /// The DDS start-up stalled (rustdds' deadlock): restart.
    Stalled(String),
}

impl From<(i32, String)> for Failure {
    fn from((code, msg): (i32, String)) -> Self {
        Failure::Exit(code, msg)
    }
}

/// The DDS side, created by [`setup_dds`] on the `dds-setup` thread.
struct Dds {
    _ctx: RosContext,
    node: RosNode,
    odom_sub: Sub<Odometry>,
    status_sub: Sub<Status>,
    clock_sub: Option<Sub<Clock>>,
    sp_pub: Pub<TwistStamped>,
    heading_pub: Pub<QuaternionStamped>,
    arm_pub: Pub<Bool>,
    mode_pub: Pub<StringMsg>,
    status_pub: Pub<StringMsg>,
    home_sub: Sub<NavSatFix>,
    actions: Servers,
}

/// The participant, node, subscriptions and publishers. Blocking (rustdds can deadlock here
/// when several participants start together): run under `startup::App::setup_dds`.
fn setup_dds(o: &DdsSetup, step: &startup::Step) -> Result<Dds, String> {
    step.set(o.rmw.opening());
    let ctx = fcc_ros::rmw::context(o.rmw, o.dds.clone())?;
    step.set("creating the ROS node");
    let live = Arc::new(AtomicBool::new(false));
    let opts = node_options(&o.params, live.clone());
    let mut node = match &ctx {
        RosContext::Dds(c) => {
            RosNode::Dds(ros_node::node_with(c, &o.namespace, &o.node_name, opts)?)
        }
        RosContext::Zenoh(_) => {
            let n = ctx.new_node(&o.namespace, &o.node_name, opts)?;
            // The parameter thread runs as long as the process: the node exits by process exit.
            n.spin_parameters(Arc::new(AtomicBool::new(false)))?;
            n
        }
    };
    live.store(true, Ordering::SeqCst); // from now on every parameter set is refused
    step.set("creating the subscriptions");
    let odom_sub = node.subscription::<Odometry>(&o.topics[0], &ros_node::best_effort_qos(1))?;
    let status_sub = node.subscription::<Status>(&o.topics[1], &ros_node::best_effort_qos(5))?;
    let clock_sub = if o.use_sim_time {
        Some(node.subscription::<Clock>(&o.topics[2], &ros_node::best_effort_qos(1))?)
    } else {
        None
    };
    step.set("creating the publishers");
    let sp_pub = node.publisher::<TwistStamped>(&o.topics[3], &ros_node::reliable_qos(10))?;
    let heading_pub =
        node.publisher::<QuaternionStamped>(&o.topics[7], &ros_node::reliable_qos(10))?;
    let arm_pub = node.publisher::<Bool>(&o.topics[4], &ros_node::reliable_qos(10))?;
    let mode_pub = node.publisher::<StringMsg>(&o.topics[5], &ros_node::reliable_qos(10))?;
    let status_pub = node.publisher::<StringMsg>(&o.topics[6], &ros_node::reliable_qos(10))?;
    // Latched: the reader is reliable and transient local, as the bridge's writer.
    let home_sub =
        node.subscription::<NavSatFix>(&o.topics[8], &topics::HOME.qos.publisher_profile())?;
    step.set("creating the action server");
    let actions = Servers::new(&mut node, &o.actions)?;
    Ok(Dds {
        _ctx: ctx,
        node,
        odom_sub,
        status_sub,
        clock_sub,
        sp_pub,
        heading_pub,
        arm_pub,
        mode_pub,
        status_pub,
        home_sub,
        actions,
    })
}

/// Every parameter of the table with the value this run uses (what `ros2 param get` shows).
fn declared_parameters(o: &Options) -> Vec<(&'static str, ParameterValue)> {
    use ParameterValue as P;
    node_params::NODE_PARAMS
        .iter()
        .map(|p| {
            let v = match p.name {
                "mission" => P::String(o.mission_file.clone()),
                "rate_hz" => P::Double(o.rate_hz),
                "use_sim_time" => P::Boolean(o.use_sim_time),
                "timeout_s" => P::Double(o.timeout_s),
                "arm_timeout_s" => P::Double(o.arm_timeout_s),
                "localhost_only" => P::Boolean(o.dds.localhost_only),
                "hover_s" => P::Double(o.hover_s),
                other => unreachable!("parameter {other} of the table has no value here"),
            };
            (p.name, v)
        })
        .collect()
}

/// The node's options: /rosout, the parameter services with every parameter declared, their
/// descriptors from the table, and a validator that refuses every set once the node runs (the
/// parameters are read at start-up: read-only).
fn node_options(params: &[(&'static str, ParameterValue)], live: Arc<AtomicBool>) -> NodeOptions {
    let mut opts = NodeOptions::new()
        .enable_rosout(true)
        .start_parameter_services(true)
        .parameter_describer(Box::new(|name| node_params::by_name(name).map(descriptor)));
    for (k, v) in params {
        opts = opts.declare_parameter(k, v.clone());
    }
    // The declared values are validated while the node is created (`live` still false).
    opts.parameter_validator(Box::new(move |name, _| {
        if live.load(Ordering::SeqCst) {
            Err(format!(
                "{name} is read-only: fcc-mission reads it at start-up (--ros-args -p {name}:=VALUE)"
            ))
        } else {
            Ok(())
        }
    }))
}

/// `describe_parameters`' answer for `p`: its meaning, unit and default, its range, read-only.
fn descriptor(p: &node_params::NodeParam) -> ParameterDescriptor {
    let range = match p.kind {
        node_params::Kind::Number { min, max, .. } => NumericRange::FloatingPointRange {
            from_value: min,
            to_value: max,
            step: 0.0,
        },
        _ => NumericRange::NotSpecified,
    };
    let additional_constraints = match p.kind {
        node_params::Kind::Number {
            min_excluded: true,
            min,
            ..
        } => format!("greater than {min}; set at start-up, read-only at run time"),
        _ => "set at start-up (-p / --params-file); read-only at run time".into(),
    };
    ParameterDescriptor {
        name: p.name.to_string(),
        param_type: ParameterType::NotSet,
        description: p.description(),
        additional_constraints,
        read_only: true,
        dynamic_typing: false,
        range,
    }
}

/// The mission node's own topic (std_msgs/String, JSON), named beside the bridge's topic table.
const MISSION_STATUS_TOPIC: &str = fcc_ros::topics::MISSION_STATUS;

/// What [`setup_dds`] needs (owned: it runs on a thread of its own).
struct DdsSetup {
    dds: DdsEnv,
    rmw: Rmw,
    /// Every parameter of [`node_params::NODE_PARAMS`] with the value in use.
    params: Vec<(&'static str, ParameterValue)>,
    namespace: String,
    node_name: String,
    use_sim_time: bool,
    /// state/odom, status, /clock, setpoint/velocity, cmd/arm, cmd/mode, mission/status,
    /// setpoint/heading, home.
    topics: [String; 9],
    /// The actions' names (after the remaps), in the order of `actions::ACTIONS`.
    actions: [String; 4],
}

async fn run(o: Options) -> Result<(), Failure> {
    let setup = DdsSetup {
        dds: o.dds.clone(),
        rmw: o.rmw,
        params: declared_parameters(&o),
        namespace: o.namespace.clone(),
        node_name: o.node_name.clone(),
        use_sim_time: o.use_sim_time,
        // The bridge's topics by their entries in the one topic table (name and type together).
        topics: [
            topics::ODOM.name,
            topics::STATUS.name,
            topics::CLOCK.name,
            topics::SETPOINT_VELOCITY.name,
            topics::CMD_ARM.name,
            topics::CMD_MODE.name,
            MISSION_STATUS_TOPIC,
            topics::SETPOINT_HEADING.name,
            topics::HOME.name,
        ]
        .map(|t| o.name(t)),
        actions: ACTIONS.map(|(name, _)| o.name(name)),
    };
    let dds = match APP.setup_dds(move |st| setup_dds(&setup, st)).await {
        Ok(r) => r.map_err(|e| Failure::Exit(1, e))?,
        Err(startup::SetupError::Stalled(e)) => return Err(Failure::Stalled(e)),
        Err(startup::SetupError::Thread(e)) => return Err(Failure::Exit(1, e)),
    };
    let run_result: Result<(), (i32, String)> = fly(o, dds).await;
    run_result.map_err(Failure::from)
}

/// What the loop heard last from the bridge.
#[derive(Default)]
struct Heard {
    odom: Option<Odometry>,
    status: Option<Status>,
    home: Option<Home>,
}

async fn fly(o: Options, dds: Dds) -> Result<(), (i32, String)> {
    let log = Log {
        rosout: dds.node.rosout(),
        name: fcc_ros::logger_name(&o.namespace, &o.node_name),
    };
    log_start(&o, &log);
    let mut exec: Executive<GoalId> = Executive::new(ExecConfig {
        timeout_s: o.timeout_s,
        arm_timeout_s: o.arm_timeout_s,
        hover_s: o.hover_s,
    });
    let started = Instant::now();
    // The mission file: the first goal, with an id of its own (not an action goal).
    let file_goal = o.mission.clone().map(|m| {
        let id = GoalId::new_random();
        let _ = exec.start(id, m, RunKind::MissionFile, 0.0);
        id
    });
    if let Some(m) = &o.mission {
        let probe = fcc_mission::MissionRun::new(fcc_mission::RunConfig {
            mission: m.clone(),
            timeout_s: o.timeout_s,
            arm_timeout_s: o.arm_timeout_s,
            hover_s: o.hover_s,
            kind: RunKind::MissionFile,
        });
        for (level, line) in probe.notes() {
            log.line(level, None, &line);
        }
    }
    let mut dds = dds;
    let mut odom_stream = dds.odom_sub.stream();
    let mut status_stream = dds.status_sub.stream();
    let mut home_stream = dds.home_sub.stream();
    let mut clock_stream = dds.clock_sub.as_ref().map(|s| s.stream());

    let mut clock = RosClock::new(o.use_sim_time);
    let mut heard = Heard::default();
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / o.rate_hz));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let fence = Fence::from_param_table();

    loop {
        tokio::select! {
            Some(r) = odom_stream.next() => { if let Ok(m) = r { heard.odom = Some(m); } continue; }
            Some(r) = status_stream.next() => { if let Ok(m) = r { heard.status = Some(m); } continue; }
            Some(r) = home_stream.next() => {
                if let Ok(m) = r { on_home(&mut heard, &m, &log); }
                continue;
            }
            Some(r) = async {
                match clock_stream.as_mut() {
                    Some(s) => s.next().await,
                    None => std::future::pending().await,
                }
            } => { if let Ok(m) = r { clock.on_clock(&m); } continue; }
            _ = tick.tick() => {}
        }
        let now_ns = clock.now_ns();
        let wall_s = started.elapsed().as_secs_f64();
        dds.actions.take_goals(&mut GoalContext {
            exec: &mut exec,
            heard: &heard,
            fence,
            wall_s,
            log: &log,
            now_ns,
        });
        let input = match (heard.odom.as_ref(), heard.status.as_ref(), now_ns) {
            (Some(od), Some(st), Some(now_ns)) => {
                let (pos_ned_m, vel_ned_mps) = odom_to_ned(od);
                Input::Ready(Sample {
                    now_ns,
                    pos_ned_m,
                    vel_ned_mps,
                    mcu: mcu_status(st),
                })
            }
            _ => Input::Waiting {
                odom: heard.odom.is_some(),
                status: heard.status.is_some(),
                clock: now_ns.is_some(),
            },
        };
        let out = exec.tick(wall_s, input);
        if send(&dds, &log, now_ns, &out.step) {
            exec.setpoint_published();
        }
        if let Some((id, p)) = out.feedback {
            dds.actions.feedback(id, &p);
        }
        if let Some(f) = out.finished {
            if Some(f.id) == file_goal && f.end != GoalEnd::Preempted {
                return file_goal_end(&f, &log, now_ns).await;
            }
            if Some(f.id) == file_goal {
                log.line(Level::Warn, now_ns, "the mission file's goal was preempted by an action goal: serving actions from now on (no exit)");
            }
            dds.actions.finish(&f, &log, now_ns);
        }
        dds.actions.poll_results();
    }
}

/// The mission file's goal ended: the node's exit (after a moment on the graph, so reliable
/// readers get the last messages: a sample lost on a busy loopback is re-sent only while the
/// writer lives).
async fn file_goal_end(
    f: &Finished<GoalId>,
    log: &Log,
    now_ns: Option<i64>,
) -> Result<(), (i32, String)> {
    match &f.end {
        GoalEnd::Succeeded => {
            tokio::time::sleep(LINGER).await;
            Ok(())
        }
        GoalEnd::Failsafe(m) | GoalEnd::PilotOverride(m) => Err((1, m.clone())),
        // Not reached: a preempted file goal keeps the node serving; only action goals cancel.
        GoalEnd::Preempted | GoalEnd::Canceled => {
            log.info(
                now_ns,
                &format!("the mission file's goal ended: {:?}", f.end),
            );
            Err((1, format!("mission file goal {:?}", f.end).to_lowercase()))
        }
    }
}

/// `home` from the bridge: the origin for lat/lon goals (logged when it is new or moves).
fn on_home(heard: &mut Heard, m: &NavSatFix, log: &Log) {
    let h = Home {
        latitude_deg: m.latitude,
        longitude_deg: m.longitude,
        altitude_m: m.altitude,
    };
    if heard.home != Some(h) {
        log.info(
            None,
            &format!(
                "home: {:.7}, {:.7}, {:.1} m (lat/lon goals are converted against it)",
                h.latitude_deg, h.longitude_deg, h.altitude_m
            ),
        );
        heard.home = Some(h);
    }
}

/// The first log line: the node, its DDS set-up, the mission and how it ends.
fn log_start(o: &Options, log: &Log) {
    let mission = match &o.mission {
        Some(m) => format!(
            "mission {} ({} waypoints, {} m/s)",
            o.mission_file,
            m.waypoints.len(),
            m.speed_mps
        ),
        None => "no mission file".into(),
    };
    log.info(
        None,
        &format!(
            "node {}/{} ({} domain {}, {}, {}), {mission}, actions {}, setpoints at {} Hz, {} time, {}",
            o.namespace.trim_end_matches('/'),
            o.node_name,
            o.rmw.label(),
            o.dds.domain_id,
            o.rmw.reach(o.dds.localhost_only),
            match &o.dds.enclave_dir {
                Some(d) => format!("DDS Security in enclave {}", d.display()),
                None => "no DDS Security".into(),
            },
            ACTIONS.map(|(name, _)| o.name(name)).join(", "),
            o.rate_hz,
            if o.use_sim_time {
                "sim (/clock)"
            } else {
                "system"
            },
            if o.hover_s > 0.0 {
                format!("then {} s in HOLD before landing", o.hover_s)
            } else {
                "landing after the last waypoint".into()
            }
        ),
    );
}

/// Does what one cycle of [`MissionRun`] asks: log lines (stamped `now_ns`), `cmd/arm`,
/// `cmd/mode`, the heading and the velocity setpoint, `mission/status`. True when a setpoint
/// went out.
fn send(dds: &Dds, log: &Log, now_ns: Option<i64>, step: &Step) -> bool {
    for (level, line) in &step.logs {
        log.line(*level, now_ns, line);
    }
    if step.arm {
        let _ = dds.arm_pub.publish(Bool { data: true });
    }
    for c in &step.mode_commands {
        let _ = dds.mode_pub.publish(StringMsg { data: (*c).into() });
    }
    // The heading first: the bridge attaches the latest one to the setpoints that follow.
    if let (Some(h), Some(ns)) = (step.heading_ned_rad, now_ns) {
        let _ = dds.heading_pub.publish(heading(h, ns));
    }
    let sent = match (step.setpoint_ned_mps, now_ns) {
        (Some(v), Some(ns)) => dds.sp_pub.publish(setpoint(v, ns)).is_ok(),
        _ => false,
    };
    if let Some(s) = &step.status {
        let _ = dds.status_pub.publish(StringMsg { data: s.clone() });
    }
    sent
}

/// The heading message: NED yaw → an ENU orientation about z, frame `map`, stamped `now_ns`.
fn heading(yaw_ned_rad: f32, now_ns: i64) -> QuaternionStamped {
    let q = frames::q_enu_of_yaw_enu(frames::yaw_ned_to_enu(yaw_ned_rad as f64));
    QuaternionStamped {
        header: Header::new(stamp(now_ns), "map"),
        quaternion: Quaternion::from_wxyz(q),
    }
}

/// The velocity setpoint message: NED → ENU, frame `map`, stamped `now_ns` (ROS time).
fn setpoint(vel_ned_mps: [f32; 3], now_ns: i64) -> TwistStamped {
    let v = vel_ned_mps.map(f64::from);
    TwistStamped {
        header: Header::new(stamp(now_ns), "map"),
        twist: Twist {
            linear: Vector3::new(frames::ned_to_enu(v)),
            angular: Vector3::default(),
        },
    }
}
