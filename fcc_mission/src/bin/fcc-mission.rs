//! `fcc-mission --mission FILE [--ros-args -r __ns:=/fcc -p name:=value …]`
//!
//! The mission node: flies a mission YAML (see `launch_configs/missions/`) through the bridge.
//! Subscribes `state/odom` (nav_msgs/Odometry, ENU/FLU) and `status` (fcc_msgs/Status),
//! publishes `setpoint/velocity` (geometry_msgs/TwistStamped, frame `map`, ENU) at `rate_hz`,
//! `cmd/arm` (std_msgs/Bool), `cmd/mode` (std_msgs/String "hold", "land") and `mission/status`
//! (std_msgs/String, one JSON object per message); logs to stdout and `/rosout`.
//!
//! After the last waypoint it lands (`cmd/mode` "land"), or with `-p hover_s:=S` (S > 0) first
//! hovers S seconds of ROS time in the MCU's HOLD mode (`cmd/mode` "hold", no setpoints; paper A
//! Fig. 16), then lands; the sequencing is `fcc_mission::EndSequence`.
//!
//! Exit codes: 0 when the vehicle is landed and disarmed after the mission, or on SIGTERM/SIGINT
//! (served by a thread of their own; a second signal, or a stop not begun within 1.5 s, exits
//! at once); 1 on a failure (timeout, disarmed in flight, DDS setup; also when the DDS start-up
//! stalled on each of 3 attempts: it restarts itself after a stall, see
//! `fcc_bridge::startup`); 2 on a bad mission file or bad arguments.

use clap::Parser;
use fcc_bridge::frames;
use fcc_bridge::params::{self, parse_bool};
use fcc_bridge::ros_node::{self, DdsEnv, RosClock};
use fcc_bridge::ros_types::{
    Bool, Clock, Header, Odometry, Status, StringMsg, Time, Twist, TwistStamped, Vector3,
};
use fcc_bridge::startup;
use fcc_mission::{EndPhase, EndSequence, McuMode, Mission, Phase, Request, WaypointFollower};
use futures::StreamExt;
use ros2_client::log::LogLevel;
use ros2_client::{NodeLoggingHandle, RosoutRaw};
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(
    name = "fcc-mission",
    about = "ROS 2 mission node: flies a waypoint mission through fcc-bridge",
    after_help = "ROS arguments: --ros-args [-r __ns:=/fcc] [-r __node:=fcc_mission] [-r topic:=new_name ...]\n\
  [-p name:=value ...] (remaps as the bridge's, e.g. -r /clock:=clock for a per-vehicle clock)\n\
Parameters: mission (file; or --mission), rate_hz (50), use_sim_time (false: stamp with the\n\
  Linux clock; true: with /clock, e.g. from fcc-bridge -p clock_source:=mcu),\n\
  timeout_s (600, from start), arm_timeout_s (60), localhost_only (true),\n\
  hover_s (0: land right after the last waypoint; S > 0: hover S s of ROS time in the MCU's\n\
  HOLD mode first, then land).\n\
Environment: ROS_DOMAIN_ID, ROS_LOCALHOST_ONLY, ROS_AUTOMATIC_DISCOVERY_RANGE,\n\
  FCC_MISSION_DDS_STARTUP_TIMEOUT_MS (5000: restart when the DDS set-up takes longer)."
)]
struct Cli {
    /// Mission YAML (launch_configs/missions/*.yaml).
    #[arg(long)]
    mission: Option<String>,
}

struct Options {
    mission_file: String,
    mission: Mission,
    namespace: String,
    node_name: String,
    dds: DdsEnv,
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

fn options() -> Options {
    let argv: Vec<String> = std::env::args().collect();
    let (prog, ros) = params::split_ros_args(&argv).unwrap_or_else(|e| fail(2, e));
    let cli = Cli::try_parse_from(prog).unwrap_or_else(|e| {
        if !e.use_stderr() {
            let _ = e.print();
            std::process::exit(0);
        }
        // One line, as for every other bad input (clap's own text spans several).
        let text = e.to_string();
        fail(
            2,
            format!(
                "{} (see --help)",
                text.split("\n\nUsage")
                    .next()
                    .unwrap_or("")
                    .split_whitespace()
                    .collect::<Vec<_>>()
                    .join(" ")
                    .trim_start_matches("error: ")
            ),
        )
    });
    let p = &ros.params;
    let known = [
        "mission",
        "rate_hz",
        "use_sim_time",
        "timeout_s",
        "arm_timeout_s",
        "localhost_only",
        "hover_s",
    ];
    if let Some(k) = p.keys().find(|k| !known.contains(&k.as_str())) {
        fail(2, format!("unknown parameter '{k}'"));
    }
    let num = |k: &str, def: f64| -> f64 {
        match p.get(k) {
            None => def,
            Some(v) => match v.parse::<f64>() {
                Ok(x) if x.is_finite() && x > 0.0 => x,
                _ => fail(2, format!("parameter {k}: '{v}' is not a positive number")),
            },
        }
    };
    let mission_file = cli
        .mission
        .or_else(|| p.get("mission").cloned())
        .unwrap_or_else(|| {
            fail(
                2,
                "no mission: use --mission FILE or -p mission:=FILE".into(),
            )
        });
    let text = std::fs::read_to_string(&mission_file)
        .unwrap_or_else(|e| fail(2, format!("{mission_file}: {e}")));
    let mission = fcc_mission::from_yaml_str(&text)
        .unwrap_or_else(|e| fail(2, format!("{mission_file}: {e}")));
    let use_sim_time = p
        .get("use_sim_time")
        .map(|v| parse_bool(v).unwrap_or_else(|e| fail(2, format!("parameter use_sim_time: {e}"))))
        .unwrap_or(false);
    let hover_s = p.get("hover_s").map_or(0.0, |v| {
        fcc_mission::ending::parse_hover_s(v)
            .unwrap_or_else(|e| fail(2, format!("parameter hover_s: {e}")))
    });
    let rate_hz = num("rate_hz", 50.0);
    if rate_hz < 20.0 {
        fail(2, format!("parameter rate_hz: {rate_hz} is below 20 Hz"));
    }
    Options {
        mission_file,
        mission,
        namespace: ros.namespace.clone().unwrap_or_else(|| "/fcc".into()),
        node_name: ros
            .node_name
            .clone()
            .unwrap_or_else(|| "fcc_mission".into()),
        dds: DdsEnv::from_env(&ros).unwrap_or_else(|e| fail(2, e)),
        rate_hz,
        use_sim_time,
        timeout_s: num("timeout_s", 600.0),
        arm_timeout_s: num("arm_timeout_s", 60.0),
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

fn phase_name(p: Phase) -> (&'static str, Option<usize>) {
    match p {
        Phase::Idle => ("idle", None),
        Phase::Takeoff => ("takeoff", None),
        Phase::Leg(i) => ("leg", Some(i)),
        Phase::Hold(i) => ("hold", Some(i)),
        Phase::Landing => ("landing", None),
        Phase::Done => ("done", None),
    }
}

/// Cross-track statistics of the estimated position on the legs (as the node sees it).
#[derive(Default)]
struct Track {
    n: usize,
    sum_sq: f64,
    max: f64,
}

impl Track {
    fn add(&mut self, from: [f32; 3], to: [f32; 3], pos: [f32; 3]) {
        let (dn, de) = ((to[0] - from[0]) as f64, (to[1] - from[1]) as f64);
        let len = (dn * dn + de * de).sqrt();
        if len < 1.0 {
            return;
        }
        let (pn, pe) = ((pos[0] - from[0]) as f64, (pos[1] - from[1]) as f64);
        let along = (pn * dn + pe * de) / len;
        if along < 0.0 || along > len {
            return;
        }
        let xt = (pn * de - pe * dn).abs() / len;
        self.n += 1;
        self.sum_sq += xt * xt;
        self.max = self.max.max(xt);
    }
    fn rms(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            (self.sum_sq / self.n as f64).sqrt()
        }
    }
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
    handle: NodeLoggingHandle,
    name: String,
}

impl Log {
    fn log(&self, level: LogLevel, now_ns: Option<i64>, msg: &str) {
        println!("fcc-mission: {msg}");
        self.handle.rosout_raw(
            ros2_client::builtin_interfaces::Time::from_nanos(
                now_ns.unwrap_or_else(fcc_bridge::now_ns),
            ),
            level,
            &self.name,
            msg,
            file!(),
            "",
            line!(),
        );
    }
    fn info(&self, now_ns: Option<i64>, msg: &str) {
        self.log(LogLevel::Info, now_ns, msg)
    }
    fn warn(&self, now_ns: Option<i64>, msg: &str) {
        self.log(LogLevel::Warn, now_ns, msg)
    }
}

/// The mission's view of a pilot override: paused while the MCU is in Pilot mode; after it,
/// `cmd/mode` "velocity" is re-sent (at most once a second) until the MCU flies velocity again.
#[derive(Default)]
struct PilotPause {
    paused: bool,
    last_resume_s: Option<f64>,
}

/// The MCU's mode and whether a failsafe is active, from `status`.
fn mcu_mode(st: &Status) -> (McuMode, bool) {
    let mode = McuMode::from_code(st.mode).unwrap_or(McuMode::Disarmed);
    (mode, st.failsafe != Status::FAILSAFE_NONE)
}

/// fcc-mission, for `fcc_bridge::startup` (messages and environment variables).
const APP: startup::App = startup::App {
    name: "fcc-mission",
    env_prefix: "FCC_MISSION",
};

#[tokio::main(flavor = "current_thread")]
async fn main() {
    let o = options();
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
    _ctx: ros2_client::Context,
    node: ros2_client::Node,
    odom_sub: ros2_client::Subscription<Odometry>,
    status_sub: ros2_client::Subscription<Status>,
    clock_sub: Option<ros2_client::Subscription<Clock>>,
    sp_pub: ros2_client::Publisher<TwistStamped>,
    arm_pub: ros2_client::Publisher<Bool>,
    mode_pub: ros2_client::Publisher<StringMsg>,
    status_pub: ros2_client::Publisher<StringMsg>,
}

/// The participant, node, subscriptions and publishers. Blocking (rustdds can deadlock here
/// when several participants start together): run under `startup::App::setup_dds`.
fn setup_dds(o: &DdsSetup, step: &startup::Step) -> Result<Dds, String> {
    step.set("creating the DDS participant");
    let ctx = ros_node::context(o.dds)?;
    step.set("creating the ROS node");
    let mut node = ros_node::node(&ctx, &o.namespace, &o.node_name)?;
    step.set("creating the subscriptions");
    let odom_sub =
        ros_node::subscription::<Odometry>(&mut node, &o.topics[0], &ros_node::best_effort_qos(1))?;
    let status_sub =
        ros_node::subscription::<Status>(&mut node, &o.topics[1], &ros_node::best_effort_qos(5))?;
    let clock_sub = if o.use_sim_time {
        Some(ros_node::subscription::<Clock>(
            &mut node,
            &o.topics[2],
            &ros_node::best_effort_qos(1),
        )?)
    } else {
        None
    };
    step.set("creating the publishers");
    let sp_pub =
        ros_node::publisher::<TwistStamped>(&mut node, &o.topics[3], &ros_node::reliable_qos(10))?;
    let arm_pub =
        ros_node::publisher::<Bool>(&mut node, &o.topics[4], &ros_node::reliable_qos(10))?;
    let mode_pub =
        ros_node::publisher::<StringMsg>(&mut node, &o.topics[5], &ros_node::reliable_qos(10))?;
    let status_pub =
        ros_node::publisher::<StringMsg>(&mut node, &o.topics[6], &ros_node::reliable_qos(10))?;
    Ok(Dds {
        _ctx: ctx,
        node,
        odom_sub,
        status_sub,
        clock_sub,
        sp_pub,
        arm_pub,
        mode_pub,
        status_pub,
    })
}

/// What [`setup_dds`] needs (owned: it runs on a thread of its own).
struct DdsSetup {
    dds: DdsEnv,
    namespace: String,
    node_name: String,
    use_sim_time: bool,
    /// state/odom, status, /clock, setpoint/velocity, cmd/arm, cmd/mode, mission/status.
    topics: [String; 7],
}

async fn run(o: Options) -> Result<(), Failure> {
    let setup = DdsSetup {
        dds: o.dds,
        namespace: o.namespace.clone(),
        node_name: o.node_name.clone(),
        use_sim_time: o.use_sim_time,
        topics: [
            "state/odom",
            "status",
            "/clock",
            "setpoint/velocity",
            "cmd/arm",
            "cmd/mode",
            "mission/status",
        ]
        .map(|t| o.name(t)),
    };
    let dds = match APP.setup_dds(move |st| setup_dds(&setup, st)).await {
        Ok(r) => r.map_err(|e| Failure::Exit(1, e))?,
        Err(startup::SetupError::Stalled(e)) => return Err(Failure::Stalled(e)),
        Err(startup::SetupError::Thread(e)) => return Err(Failure::Exit(1, e)),
    };
    let run_result: Result<(), (i32, String)> = fly(o, dds).await;
    run_result.map_err(Failure::from)
}

async fn fly(o: Options, dds: Dds) -> Result<(), (i32, String)> {
    // `_ctx` stays bound (the DDS participant lives as long as the flight).
    let Dds {
        _ctx,
        node,
        odom_sub,
        status_sub,
        clock_sub,
        sp_pub,
        arm_pub,
        mode_pub,
        status_pub,
    } = dds;
    let log = Log {
        handle: node.logging_handle(),
        name: fcc_bridge::ros_api::logger_name(&o.namespace, &o.node_name),
    };
    let n_wp = o.mission.waypoints.len();
    log.info(None, &format!(
        "node {}/{} (DDS domain {}, {}), mission {} ({} waypoints, {} m/s), setpoints at {} Hz, {} time, {}",
        o.namespace.trim_end_matches('/'),
        o.node_name,
        o.dds.domain_id,
        if o.dds.localhost_only { "loopback only" } else { "all interfaces" },
        o.mission_file,
        n_wp,
        o.mission.speed_mps,
        o.rate_hz,
        if o.use_sim_time { "sim (/clock)" } else { "system" },
        if o.hover_s > 0.0 {
            format!("then {} s in HOLD before landing", o.hover_s)
        } else {
            "landing after the last waypoint".into()
        }
    ));
    if o.mission.yaw_deg.is_some() {
        log.info(None, "note: yaw_deg is not sent (TwistStamped carries no heading; the bridge keeps the current heading)");
    }
    if o.hover_s > 0.0 && !o.mission.land_at_end {
        log.warn(
            None,
            "hover_s is ignored: the mission does not land at the end (land_at_end: false)",
        );
    }

    let odom_stream = odom_sub.async_stream();
    let status_stream = status_sub.async_stream();
    tokio::pin!(odom_stream);
    tokio::pin!(status_stream);
    let mut clock_stream = clock_sub.as_ref().map(|s| Box::pin(s.async_stream()));

    let mut clock = RosClock::new(o.use_sim_time);
    let mut odom: Option<Odometry> = None;
    let mut status: Option<Status> = None;
    let mut follower: Option<WaypointFollower> = None;
    let mut last_phase: Option<(&'static str, Option<usize>)> = None;
    let mut arm_sent_at: Option<Instant> = None;
    let mut arm_attempts = 0u32;
    let mut armed_at_ns: Option<i64> = None;
    let mut end = EndSequence::new(o.hover_s);
    let mut last_report = Instant::now() - Duration::from_secs(10);
    let mut setpoints = 0u64;
    let mut pilot = PilotPause::default();
    let mut track = Track::default();
    let mut last_reject = String::new();
    let started = Instant::now();
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / o.rate_hz));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut waiting_note = false;
    let mut t_first: Option<f64> = None;

    loop {
        tokio::select! {
            Some(r) = odom_stream.next() => { if let Ok((m, _)) = r { odom = Some(m); } continue; }
            Some(r) = status_stream.next() => { if let Ok((m, _)) = r { status = Some(m); } continue; }
            Some(r) = async {
                match clock_stream.as_mut() {
                    Some(s) => s.next().await,
                    None => std::future::pending().await,
                }
            } => { if let Ok((m, _)) = r { clock.on_clock(&m); } continue; }
            _ = tick.tick() => {}
        }
        let elapsed = started.elapsed().as_secs_f64();
        if elapsed > o.timeout_s {
            return Err((
                1,
                format!(
                    "timeout: mission not finished after {:.0} s (phase {:?})",
                    o.timeout_s, last_phase
                ),
            ));
        }
        let (Some(od), Some(st), Some(now_ns)) = (odom.as_ref(), status.as_ref(), clock.now_ns())
        else {
            if !waiting_note && elapsed > 5.0 {
                log.info(
                    clock.now_ns(),
                    &format!(
                        "waiting for the bridge: state/odom {}, status {}, clock {}",
                        if odom.is_some() { "ok" } else { "none yet" },
                        if status.is_some() { "ok" } else { "none yet" },
                        if clock.now_ns().is_some() {
                            "ok"
                        } else {
                            "no /clock yet"
                        }
                    ),
                );
                waiting_note = true;
            }
            continue;
        };
        let t_s = now_ns as f64 * 1e-9;
        // For messages: seconds since the first state (ROS time may be the epoch).
        let t0 = *t_first.get_or_insert(t_s);
        let tr = t_s - t0;
        let (pos, vel) = odom_to_ned(od);
        if st.last_reject != last_reject {
            last_reject = st.last_reject.clone();
            if !last_reject.is_empty() && last_reject != "accepted" {
                log.warn(Some(now_ns), &format!("MCU/bridge reject: {last_reject}"));
            }
        }

        // ---- before arming: the follower asks for Arm; home is captured when armed.
        if armed_at_ns.is_none() {
            if st.armed {
                armed_at_ns = Some(now_ns);
                let mut f = WaypointFollower::new(o.mission.clone());
                let _ = f.update(t_s, pos, vel);
                follower = Some(f);
                log.info(
                    Some(now_ns),
                    &format!(
                        "armed at t={tr:.2} s, home NED [{:.2}, {:.2}, {:.2}] m",
                        pos[0], pos[1], pos[2]
                    ),
                );
            } else {
                let mut probe = WaypointFollower::new(o.mission.clone());
                let g = probe.update(t_s, pos, vel);
                if g.request == Some(Request::Arm)
                    && arm_sent_at.is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
                {
                    if arm_attempts as f64 > o.arm_timeout_s {
                        return Err((
                            1,
                            format!(
                                "could not arm within {:.0} s (last reject: '{}')",
                                o.arm_timeout_s, st.last_reject
                            ),
                        ));
                    }
                    let _ = arm_pub.publish(Bool { data: true });
                    arm_sent_at = Some(Instant::now());
                    arm_attempts += 1;
                }
                report(
                    &status_pub,
                    &mut last_report,
                    "arming",
                    None,
                    n_wp,
                    None,
                    st,
                    t_s,
                    false,
                );
                continue;
            }
        }
        let f = follower.as_mut().expect("follower after arming");

        // ---- flying
        if !st.armed {
            let flight_s = (now_ns - armed_at_ns.unwrap_or(now_ns)) as f64 * 1e-9;
            if end.land_requested() && st.landed {
                let _ = status_pub.publish(StringMsg {
                    data: format!("{{\"phase\":\"finished\",\"waypoint\":{n_wp},\"of\":{n_wp},\"dist_to_go_m\":0.0,\"armed\":false,\"landed\":true}}"),
                });
                log.info(Some(now_ns), &format!(
                    "mission complete: {n_wp}/{n_wp} waypoints, {flight_s:.1} s armed, {setpoints} setpoints, cross-track (estimate, as seen on state/odom) RMS {:.3} m max {:.3} m; landed and disarmed",
                    track.rms(),
                    track.max
                ));
                // Stay on the graph a moment so reliable readers get the last messages
                // (a sample lost on a busy loopback is re-sent only while the writer lives).
                tokio::time::sleep(LINGER).await;
                return Ok(());
            }
            return Err((1, format!(
                "disarmed in flight after {flight_s:.1} s (phase {:?}, end {:?}, mode {}, failsafe {}, landed {})",
                last_phase, end.phase(), st.mode_name, st.failsafe_name, st.landed
            )));
        }
        // ---- pilot override (S.BUS switch on the MCU): the pilot flies, the MCU refuses our
        // setpoints and commands, so send none. When the pilot hands back (the MCU holds), the
        // mission resumes from where the vehicle is: `cmd/mode` "velocity", re-sent each second
        // until the MCU reports it (best effort, as the other commands).
        if st.mode == Status::MODE_PILOT {
            if !pilot.paused {
                log.warn(
                    Some(now_ns),
                    &format!("t={tr:.2} s pilot override: mission paused, no setpoints"),
                );
                pilot.paused = true;
            }
            report(
                &status_pub,
                &mut last_report,
                "pilot",
                None,
                n_wp,
                None,
                st,
                t_s,
                true,
            );
            continue;
        }
        if pilot.paused {
            let (mode, _) = mcu_mode(st);
            if mode == McuMode::Velocity {
                log.info(
                    Some(now_ns),
                    &format!("t={tr:.2} s pilot released control: mission resumed"),
                );
                pilot.paused = false;
            } else if pilot.last_resume_s.is_none_or(|t| t_s - t >= 1.0) {
                if pilot.last_resume_s.is_none() {
                    log.info(
                        Some(now_ns),
                        &format!("t={tr:.2} s pilot released control (MCU {}): resuming with cmd/mode velocity", st.mode_name),
                    );
                }
                let _ = mode_pub.publish(StringMsg {
                    data: "velocity".into(),
                });
                pilot.last_resume_s = Some(t_s);
            }
            if !pilot.paused {
                pilot.last_resume_s = None;
            }
            // Setpoints flow meanwhile (the MCU holds and keeps them; none is stale on resume).
        }
        let g = f.update(t_s, pos, vel);
        let (name, idx) = phase_name(g.phase);
        if last_phase != Some((name, idx)) {
            log.info(
                Some(now_ns),
                &format!(
                    "t={tr:.2} s {name}{}",
                    idx.map(|i| format!(" {i}")).unwrap_or_default()
                ),
            );
            last_phase = Some((name, idx));
        }
        if let (Phase::Leg(_), Some(leg)) = (g.phase, g.leg) {
            track.add(leg.from_ned_m, leg.to_ned_m, pos);
        }
        let dist = g.leg.map(|l| {
            let d = [
                l.to_ned_m[0] - pos[0],
                l.to_ned_m[1] - pos[1],
                l.to_ned_m[2] - pos[2],
            ];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        });
        // ---- the end: land, or hover in HOLD first (no setpoints), then land; commands are
        // re-sent until the MCU reports the mode (they travel best-effort).
        let (mode, failsafe) = mcu_mode(st);
        let step = end.update(t_s, g.request == Some(Request::Land), mode, failsafe);
        if let Some(e) = &step.event {
            let line = format!("t={tr:.2} s {e}");
            if e.is_warning() {
                log.warn(Some(now_ns), &line);
            } else {
                log.info(Some(now_ns), &line);
            }
        }
        if let Some(c) = step.command {
            let _ = mode_pub.publish(StringMsg {
                data: c.as_str().into(),
            });
        }
        if !step.send_setpoints {
            report(
                &status_pub,
                &mut last_report,
                if end.phase() == EndPhase::Hover {
                    "hover"
                } else {
                    "landing"
                },
                None,
                n_wp,
                None,
                st,
                t_s,
                true,
            );
            continue;
        }
        let v_enu = frames::ned_to_enu([
            g.vel_ned_mps[0] as f64,
            g.vel_ned_mps[1] as f64,
            g.vel_ned_mps[2] as f64,
        ]);
        let msg = TwistStamped {
            header: Header::new(stamp(now_ns), "map"),
            twist: Twist {
                linear: Vector3::new(v_enu),
                angular: Vector3::default(),
            },
        };
        if sp_pub.publish(msg).is_ok() {
            setpoints += 1;
        }
        report(
            &status_pub,
            &mut last_report,
            name,
            idx,
            n_wp,
            dist,
            st,
            t_s,
            false,
        );
    }
}

/// `mission/status` at 2 Hz: `{"phase":"leg","waypoint":1,"of":4,"dist_to_go_m":12.3,...}`.
#[allow(clippy::too_many_arguments)]
fn report(
    p: &ros2_client::Publisher<StringMsg>,
    last: &mut Instant,
    phase: &str,
    idx: Option<usize>,
    n: usize,
    dist: Option<f32>,
    st: &Status,
    t_s: f64,
    force: bool,
) {
    let _ = force;
    if last.elapsed() < Duration::from_millis(500) {
        return;
    }
    *last = Instant::now();
    let wp = idx.map(|i| i.to_string()).unwrap_or_else(|| "null".into());
    let d = dist
        .map(|d| format!("{d:.2}"))
        .unwrap_or_else(|| "null".into());
    let _ = p.publish(StringMsg {
        data: format!(
            "{{\"t_s\":{t_s:.2},\"phase\":\"{phase}\",\"waypoint\":{wp},\"of\":{n},\"dist_to_go_m\":{d},\"armed\":{},\"mode\":\"{}\"}}",
            st.armed, st.mode_name
        ),
    });
}
