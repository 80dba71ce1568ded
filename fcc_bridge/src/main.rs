//! `fcc-bridge --device /dev/pts/N [--baud 921600] [--ros-args -r __ns:=/fcc -p name:=value …]`
//!
//! Exit codes: 0 on SIGINT/SIGTERM, 1 on a setup error (also when the DDS start-up stalled on
//! each of 3 attempts: the bridge restarts itself after a stall, see `bridge::start_dds`), 2 on
//! a bad command-line/ROS argument or parameter value, or when the MCU's protocol version or
//! schema hash does not match (one line on stderr says which).

use clap::Parser;
use fcc_bridge::bridge::{self, BridgeError, Options};
use fcc_bridge::record::{RecordOptions, Tap};
use fcc_bridge::state::ClockSource;
use fcc_ros::params::{self, parse_bool};
use fcc_ros::startup::Stop;
use std::collections::BTreeMap;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "fcc-bridge",
    about = "ROS 2 bridge for the fcc flight controller's serial link",
    after_help = "ROS arguments: --ros-args [-r __ns:=/fcc] [-r __node:=fcc_bridge] [-r topic:=new_name ...]\n\
  [-p name:=value ...] [--params-file FILE.yaml ...]\n\
MCU parameters (ROS parameters, set on the MCU): limits.max_horiz_speed_mps, limits.max_tilt_deg,\n\
  control.cross_track_k_per_s, control.vel_p_per_s, limits.max_climb_mps, limits.max_descent_mps.\n\
Services: arm (std_srvs/SetBool), land, hold (std_srvs/Trigger).\n\
Parameters: localhost_only (true), ttl_ms (300, 50..=3000), max_speed_mps (20, 0.1..=30),\n\
  max_stamp_age_ms (500, 10..=5000), max_stamp_future_ms (500, 10..=5000), clock_source (sync | mcu),\n\
  ping_period_ms (1000, 100..=10000), use_sim_time,\n\
  map_frame (map), odom_frame (odom), base_frame (base_link), imu_frame (imu_link),\n\
  gps_frame (gps_link), laser_frame (laser_link), sonar_frame (sonar_link),\n\
  record (off: PATH), record_on_arm (false), record_split_s, record_split_mb (off),\n\
  record_compression (zstd | none), record_chunk_ms (500), record_chunk_mb (4).\n\
Environment: ROS_DOMAIN_ID, ROS_LOCALHOST_ONLY, ROS_AUTOMATIC_DISCOVERY_RANGE (LOCALHOST |\n\
  SUBNET | SYSTEM_DEFAULT; OFF is refused), ROS_STATIC_PEERS (not supported: warned), RUST_LOG,\n\
  FCC_BRIDGE_DDS_STARTUP_TIMEOUT_MS (5000: restart when the DDS set-up takes longer)."
)]
struct Cli {
    /// Serial device or pseudo-terminal (retried every 0.5 s until it exists).
    #[arg(long)]
    device: String,
    /// Baud rate.
    #[arg(long, default_value_t = 921_600)]
    baud: u32,
    /// Record every topic (published, received, raw link frames) to this MCAP file
    /// (rosbag2-compatible; same as `-p record:=PATH`).
    #[arg(long, value_name = "PATH")]
    record: Option<String>,
}

fn options() -> Result<(Options, Option<RecordOptions>), String> {
    let argv: Vec<String> = std::env::args().collect();
    let (prog, mut ros) = params::split_ros_args(&argv)?;
    let cli = parse_cli(prog);
    let mut o = Options {
        device: cli.device,
        baud: cli.baud,
        ..Options::default()
    };
    if let Some(ns) = ros.namespace.clone() {
        o.namespace = if ns.starts_with('/') {
            ns
        } else {
            format!("/{ns}")
        };
    }
    if let Some(n) = ros.node_name.clone() {
        o.node_name = n;
    }
    ros.load_params_files(&o.namespace, &o.node_name)?;
    // Errors about a parameter name the --params-file it came from.
    let ros_ref = ros.clone();
    (move || -> Result<(Options, Option<RecordOptions>), String> {
        o.remaps = ros.remaps.clone();
        let env = |k: &str| std::env::var(k).ok();
        o.domain_id = params::domain_id(env("ROS_DOMAIN_ID").as_deref())?;
        o.rmw = fcc_ros::rmw::Rmw::from_env()?;
        o.enclave_dir = fcc_ros::ros_node::security_from_env(&ros)?;
        let p = &ros.params;
        let rec = fcc_bridge::record::record_options(cli.record.as_deref(), p)?;
        o.localhost_only = params::localhost_only(
            p.get("localhost_only").map(String::as_str),
            env("ROS_LOCALHOST_ONLY").as_deref(),
            env("ROS_AUTOMATIC_DISCOVERY_RANGE").as_deref(),
        )?;
        bridge_params(&mut o, p)?;
        if let Some(v) = p.get("clock_source") {
            o.clock = match v.as_str() {
                "sync" => ClockSource::Sync,
                "mcu" => ClockSource::Mcu,
                _ => return Err(format!("parameter clock_source: '{v}' (sync | mcu)")),
            };
        }
        if let Some(v) = p.get("use_sim_time") {
            o.use_sim_time = parse_bool(v).map_err(|e| format!("parameter use_sim_time: {e}"))?;
        }
        if let Some(v) = p.get("localhost_only") {
            parse_bool(v).map_err(|e| format!("parameter localhost_only: {e}"))?;
        }
        o.record = rec
            .as_ref()
            .map(|r| r.path.display().to_string())
            .unwrap_or_default();
        mcu_params(&mut o, p)?;
        frame_params(&mut o.cfg, p);
        check_known(p)?;
        Ok((o, rec))
    })()
    .map_err(|e| ros_ref.locate(e))
}

/// The command line before `--ros-args`; on a bad one, one line and exit 2 (`--help` and
/// `--version`: printed, exit 0).
fn parse_cli(prog: Vec<String>) -> Cli {
    fcc_mission::cli::parse("fcc-bridge", prog).unwrap_or_else(|code| {
        std::process::exit(code.into());
    })
}

/// The numeric bridge parameters, each checked against its safe range (the table the run-time
/// validator uses too).
fn bridge_params(o: &mut Options, p: &BTreeMap<String, String>) -> Result<(), String> {
    for bp in fcc_bridge::ros_api::BRIDGE_PARAMS {
        let Some(v) = p.get(bp.name) else { continue };
        let x = bp.parse(v).map_err(|e| format!("parameter {e}"))?;
        match bp.name {
            "ttl_ms" => o.limits.ttl_ms = x as u16,
            "max_speed_mps" => o.limits.max_speed_mps = x,
            "max_stamp_age_ms" => o.limits.max_age_ns = (x * 1e6) as i64,
            "max_stamp_future_ms" => o.limits.max_future_ns = (x * 1e6) as i64,
            "ping_period_ms" => o.ping_period = Duration::from_millis(x as u64),
            other => return Err(format!("parameter {other}: not handled at start-up")),
        }
    }
    Ok(())
}

/// The MCU parameters given at start-up, each checked against its range.
fn mcu_params(o: &mut Options, p: &BTreeMap<String, String>) -> Result<(), String> {
    let num = |k: &str| -> Result<Option<f64>, String> {
        p.get(k)
            .map(|v| {
                v.parse::<f64>()
                    .map_err(|_| format!("parameter {k}: '{v}' is not a number"))
            })
            .transpose()
    };
    for mp in fcc_bridge::mcu_params::MCU_PARAMS {
        if let Some(x) = num(mp.name)? {
            mp.check(x).map_err(|e| format!("parameter {e}"))?;
            if fcc_bridge::mcu_params::is_integer(mp) && x.fract() != 0.0 {
                return Err(format!("parameter {}: {x} is not a whole number", mp.name));
            }
            o.mcu_params.insert(mp.name.to_string(), x);
        }
    }
    // Only rates given here are sent to the MCU (the others are read from it): check those.
    if !o.mcu_params.keys().any(|k| k.starts_with("rates.")) {
        return Ok(());
    }
    let start = |id: u16| {
        let name = fcc_bridge::mcu_params::by_id(id)?.name;
        o.mcu_params.get(name).map(|v| *v as f32)
    };
    fcc_bridge::mcu_params::check_link_budget(start, o.baud)
        .map_err(|e| format!("parameters rates.*: {e}"))?;
    Ok(())
}

/// The frame ids (`map_frame`, `odom_frame`, `base_frame`, the sensors' frames).
fn frame_params(c: &mut fcc_bridge::convert::Config, p: &BTreeMap<String, String>) {
    for (k, slot) in [
        ("map_frame", &mut c.map_frame),
        ("odom_frame", &mut c.odom_frame),
        ("base_frame", &mut c.base_frame),
        ("imu_frame", &mut c.imu_frame),
        ("mag_frame", &mut c.mag_frame),
        ("baro_frame", &mut c.baro_frame),
        ("gps_frame", &mut c.gps_frame),
        ("laser_frame", &mut c.laser_frame),
        ("sonar_frame", &mut c.sonar_frame),
    ] {
        if let Some(v) = p.get(k) {
            *slot = v.clone();
        }
    }
}

/// Every `-p`/`--params-file` parameter must be one the bridge knows.
fn check_known(p: &BTreeMap<String, String>) -> Result<(), String> {
    let known = [
        "localhost_only",
        "ttl_ms",
        "max_speed_mps",
        "max_stamp_age_ms",
        "max_stamp_future_ms",
        "ping_period_ms",
        "clock_source",
        "use_sim_time",
        "map_frame",
        "odom_frame",
        "base_frame",
        "imu_frame",
        "mag_frame",
        "baro_frame",
        "gps_frame",
        "laser_frame",
        "sonar_frame",
    ];
    for k in p.keys() {
        if !known.contains(&k.as_str())
            && !fcc_bridge::record::RECORD_PARAMS.contains(&k.as_str())
            && fcc_bridge::mcu_params::by_name(k).is_none()
        {
            return Err(format!("unknown parameter '{k}'"));
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    use tracing_subscriber::layer::SubscriberExt;
    use tracing_subscriber::util::SubscriberInitExt;
    // stderr, and /rosout (the bridge's own events, INFO and above).
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| {
                    "info,rustdds=error,ros2_client=warn,ros2_client::service=error".into()
                })
                // ros2-client echoes every /rosout record as an event of its own: the line is
                // already on stderr once, from the event itself.
                .add_directive("ros2_client::rosout=off".parse().expect("static directive")),
        )
        .with_writer(std::io::stderr)
        .finish()
        .with(fcc_bridge::ros_api::RosoutLayer)
        .init();
    let (opts, rec) = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("fcc-bridge: {e}");
            return ExitCode::from(2);
        }
    };
    // Free heap pages back to the OS every 30 s: a flat RSS over hours (fcc_ros::heap).
    fcc_ros::heap::spawn_trimmer();
    // SIGTERM / SIGINT from now on, whatever the DDS start-up does.
    let stop = match Stop::install(bridge::APP) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("fcc-bridge: cannot install the signal handlers: {e}");
            return ExitCode::from(1);
        }
    };
    let tap = match rec {
        None => Tap::counting(&opts.namespace),
        Some(r) => match Tap::recording(&opts.namespace, r.clone()) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("fcc-bridge: cannot record to {}: {e}", r.path.display());
                return ExitCode::from(2);
            }
        },
    }
    .with_remaps(&opts.remaps);
    // One thread: the serial port's readiness (epoll) and the session that reads it are on the
    // same thread. With the multi-thread runtime a worker woke on the read and woke this thread
    // (block_on) to run the session: two context switches per serial read instead of one.
    // Zenoh's blocking calls refuse a current-thread runtime: one worker thread there.
    let rt = fcc_ros::rmw::runtime(opts.rmw).expect("tokio runtime");
    let mut run = Box::pin(bridge::run(opts, tap.clone()));
    let r = rt.block_on(async {
        tokio::select! {
            r = &mut run => r,
            _ = stop.wait() => Ok(()),
        }
    });
    // On a stop the session is left as it is, not dropped: dropping it would tear DDS down
    // entity by entity while the subscription tasks still hold the participant, and rustdds logs
    // an ERROR for each entity removed after its event loop has gone (see the exit below).
    std::mem::forget(run);
    stop.stopping();
    if let Err(BridgeError::DdsStalled(e)) = &r {
        // The stalled participant cannot be recovered in this process: start afresh (same
        // pid, arguments and environment), a few times.
        bridge::APP.restart_after_stall(e);
    }
    // Per-topic counts (published / received / raw frames), one JSON line on stderr; the
    // recording is finished (summary, footer, PATH.counts.json).
    eprintln!(
        "fcc-bridge counts: {}",
        serde_json::to_string(&tap.counts()).unwrap_or_default()
    );
    if tap.is_recording() {
        match tap.finish(Duration::from_secs(20)) {
            Some(rep) => eprintln!(
                "fcc-bridge: recorded {} messages to {}{}",
                rep.recorded.values().sum::<u64>(),
                rep.files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                rep.error.map(|e| format!(" ({e})")).unwrap_or_default()
            ),
            None => eprintln!("fcc-bridge: the recorder did not finish in 20 s"),
        }
    }
    let code = match r {
        Ok(()) => 0,
        Err(BridgeError::Handshake(e)) => {
            eprintln!("fcc-bridge: {e}");
            2
        }
        Err(e) => {
            eprintln!("fcc-bridge: {e}");
            1
        }
    };
    // Exit without tearing down DDS entity by entity: rustdds logs errors for every entity
    // dropped after its participant; peers see the participant's lease expire instead.
    std::process::exit(code as i32)
}
