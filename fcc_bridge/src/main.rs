//! `fcc-bridge --device /dev/pts/N [--baud 921600] [--ros-args -r __ns:=/fcc -p name:=value …]`
//!
//! Exit codes: 0 on Ctrl-C, 1 on a setup error, 2 when the MCU's protocol version or schema
//! hash does not match (one line on stderr says which).

use clap::Parser;
use fcc_bridge::bridge::{self, BridgeError, Options};
use fcc_bridge::params::{self, parse_bool};
use fcc_bridge::state::ClockSource;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "fcc-bridge",
    about = "ROS 2 bridge for the fcc flight controller's serial link",
    after_help = "ROS arguments: --ros-args [-r __ns:=/fcc] [-r __node:=fcc_bridge] [-p name:=value ...]\n\
Parameters: localhost_only (true), ttl_ms (300), max_speed_mps (20), max_stamp_age_ms (500),\n\
  max_stamp_future_ms (500), clock_source (sync | mcu), ping_period_ms (1000),\n\
  map_frame (map), base_frame (base_link), imu_frame (imu_link), gps_frame (gps_link),\n\
  laser_frame (laser_link), sonar_frame (sonar_link).\n\
Environment: ROS_DOMAIN_ID, ROS_LOCALHOST_ONLY, ROS_AUTOMATIC_DISCOVERY_RANGE, RUST_LOG."
)]
struct Cli {
    /// Serial device or pseudo-terminal (retried every 0.5 s until it exists).
    #[arg(long)]
    device: String,
    /// Baud rate.
    #[arg(long, default_value_t = 921_600)]
    baud: u32,
}

fn options() -> Result<Options, String> {
    let argv: Vec<String> = std::env::args().collect();
    let (prog, ros) = params::split_ros_args(&argv)?;
    let cli = Cli::try_parse_from(prog).unwrap_or_else(|e| {
        let _ = e.print();
        std::process::exit(if e.use_stderr() { 1 } else { 0 });
    });
    let mut o = Options {
        device: cli.device,
        baud: cli.baud,
        ..Options::default()
    };
    if let Some(ns) = ros.namespace {
        o.namespace = if ns.starts_with('/') {
            ns
        } else {
            format!("/{ns}")
        };
    }
    if let Some(n) = ros.node_name {
        o.node_name = n;
    }
    for (k, v) in &ros.remaps {
        eprintln!("fcc-bridge: topic remapping '{k}:={v}' is not supported; ignored");
    }
    let env = |k: &str| std::env::var(k).ok();
    o.domain_id = params::domain_id(env("ROS_DOMAIN_ID").as_deref())?;
    let p = &ros.params;
    o.localhost_only = params::localhost_only(
        p.get("localhost_only").map(String::as_str),
        env("ROS_LOCALHOST_ONLY").as_deref(),
        env("ROS_AUTOMATIC_DISCOVERY_RANGE").as_deref(),
    )?;
    let num = |k: &str| -> Result<Option<f64>, String> {
        p.get(k)
            .map(|v| {
                v.parse::<f64>()
                    .map_err(|_| format!("parameter {k}: '{v}' is not a number"))
            })
            .transpose()
    };
    if let Some(v) = num("ttl_ms")? {
        if !(1.0..=65535.0).contains(&v) {
            return Err("parameter ttl_ms must be 1..=65535".into());
        }
        o.limits.ttl_ms = v as u16;
    }
    if let Some(v) = num("max_speed_mps")? {
        o.limits.max_speed_mps = v;
    }
    if let Some(v) = num("max_stamp_age_ms")? {
        o.limits.max_age_ns = (v * 1e6) as i64;
    }
    if let Some(v) = num("max_stamp_future_ms")? {
        o.limits.max_future_ns = (v * 1e6) as i64;
    }
    if let Some(v) = num("ping_period_ms")? {
        o.ping_period = Duration::from_millis(v.max(10.0) as u64);
    }
    if let Some(v) = p.get("clock_source") {
        o.clock = match v.as_str() {
            "sync" => ClockSource::Sync,
            "mcu" => ClockSource::Mcu,
            _ => return Err(format!("parameter clock_source: '{v}' (sync | mcu)")),
        };
    }
    if let Some(v) = p.get("use_sim_time") {
        if parse_bool(v)? {
            eprintln!("fcc-bridge: use_sim_time is ignored; the bridge is a clock source (see clock_source:=mcu)");
        }
    }
    let c = &mut o.cfg;
    for (k, slot) in [
        ("map_frame", &mut c.map_frame),
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
        "base_frame",
        "imu_frame",
        "mag_frame",
        "baro_frame",
        "gps_frame",
        "laser_frame",
        "sonar_frame",
    ];
    for k in p.keys() {
        if !known.contains(&k.as_str()) {
            return Err(format!("unknown parameter '{k}'"));
        }
    }
    Ok(o)
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "info,rustdds=error,ros2_client=warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let opts = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("fcc-bridge: {e}");
            return ExitCode::from(1);
        }
    };
    let rt = tokio::runtime::Runtime::new().expect("tokio runtime");
    let r = rt.block_on(async {
        tokio::select! {
            r = bridge::run(opts) => r,
            _ = tokio::signal::ctrl_c() => Ok(()),
        }
    });
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
