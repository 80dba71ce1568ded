//! `fcc-zenoh-router [--listen ENDPOINT]... [--connect ENDPOINT]... [--config FILE]`
//!
//! A Zenoh router for fleets over Zenoh (issue 18): the `zenoh` crate's own router, run in
//! process (we do not write a relay). It is our equivalent of rmw_zenoh's `rmw_zenohd`
//! (`ros2 run rmw_zenoh_cpp rmw_zenohd`): ROS 2 nodes on `RMW_IMPLEMENTATION=rmw_zenoh_cpp`, our
//! bridge and mission node included, connect to it as peers to discover each other (gossip
//! scouting), and routers linked with `--connect` carry data and liveliness between sites.
//!
//! Configuration, in the order it is applied (each step overrides the ones before):
//! 1. a json5 Zenoh config file: `--config FILE`, else the file named by the environment variable
//!    `ZENOH_ROUTER_CONFIG_URI` (as rmw_zenohd), else none;
//! 2. `ZENOH_CONFIG_OVERRIDE="key=value;key=value"` (as rmw_zenoh): each value JSON5, inserted at
//!    its config path, e.g. `ZENOH_CONFIG_OVERRIDE='transport/shared_memory/enabled=false'`;
//! 3. `--listen` / `--connect` (each repeatable): replace `listen/endpoints` / `connect/endpoints`;
//! 4. what is still unset: mode `router`, multicast scouting off (routers link only where told,
//!    as rmw_zenohd's default config), listening on `tcp/127.0.0.1:7447` (rmw_zenoh's router
//!    port; loopback only unless asked, e.g. `--listen tcp/[::]:7447`).
//!
//! When open it prints one line on stdout, `fcc-zenoh-router: listening on <locators> (zid <id>)`,
//! then runs until SIGINT or SIGTERM (exit 0). A bad flag, config file or override: one error line
//! on stderr, exit 2. The router failing to open (e.g. the port in use): one line, exit 1.
//! Zenoh's own log goes to stderr, filtered by `RUST_LOG` (default `warn`).
//!
//! Examples:
//! ```text
//! fcc-zenoh-router                                   # site A: tcp/127.0.0.1:7447
//! fcc-zenoh-router --listen tcp/0.0.0.0:7448 --connect tcp/10.0.0.1:7447   # site B, linked to A
//! ZENOH_ROUTER_CONFIG_URI=router.json5 fcc-zenoh-router
//! ```

use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;
use zenoh::Config;

/// rmw_zenoh's router endpoint (its default is `tcp/[::]:7447`; we stay on loopback).
const DEFAULT_LISTEN: &str = "tcp/127.0.0.1:7447";
/// The config file environment variable rmw_zenohd reads.
const CONFIG_FILE_ENV: &str = "ZENOH_ROUTER_CONFIG_URI";
/// rmw_zenoh's `key=value;key=value` override environment variable.
const OVERRIDE_ENV: &str = "ZENOH_CONFIG_OVERRIDE";
const NAME: &str = "fcc-zenoh-router";

/// Exit code for a bad flag, config file or override.
const EXIT_USAGE: u8 = 2;
/// Exit code for a router that could not open (e.g. the listen port in use).
const EXIT_OPEN_FAILED: u8 = 1;

#[derive(Parser)]
#[command(name = NAME, about = "Zenoh router (rmw_zenohd equivalent) for fleets over Zenoh")]
struct Cli {
    /// Endpoint to listen on, e.g. tcp/127.0.0.1:7447 (repeatable; default tcp/127.0.0.1:7447
    /// unless the config file sets listen/endpoints).
    #[arg(long = "listen", value_name = "ENDPOINT")]
    listen: Vec<String>,
    /// Another router to link to, e.g. tcp/10.0.0.1:7447 (repeatable).
    #[arg(long = "connect", value_name = "ENDPOINT")]
    connect: Vec<String>,
    /// json5 Zenoh config file (default: $ZENOH_ROUTER_CONFIG_URI, if set).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help / --version: clap's text on stdout, exit 0.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return usage_error(&first_line(&e.to_string())),
    };
    init_logging();
    let config = match build_config(&cli) {
        Ok(config) => config,
        Err(message) => return usage_error(&message),
    };
    let runtime = match tokio::runtime::Runtime::new() {
        Ok(runtime) => runtime,
        Err(e) => return failure(EXIT_OPEN_FAILED, &format!("cannot start the runtime: {e}")),
    };
    runtime.block_on(run(config))
}

/// Opens the router, announces it, and serves until SIGINT/SIGTERM.
async fn run(config: Config) -> ExitCode {
    let configured_listen = config.get_json("listen/endpoints").unwrap_or_default();
    let session = match zenoh::open(config).await {
        Ok(session) => session,
        Err(e) => {
            return failure(
                EXIT_OPEN_FAILED,
                &format!("cannot open the router: {}", one_line(&e.to_string())),
            )
        }
    };
    announce(&session, &configured_listen).await;
    if let Err(e) = wait_for_stop_signal().await {
        return failure(EXIT_OPEN_FAILED, &format!("cannot wait for signals: {e}"));
    }
    if let Err(e) = session.close().await {
        tracing::warn!("closing the router: {e}");
    }
    ExitCode::SUCCESS
}

/// The one "listening" line on stdout, flushed (scripts wait for it). The locators are the bound
/// ones; `configured` (the config's endpoints) stands in if there are none to show (an unspecified
/// address such as `tcp/[::]:7447` lists only the non-loopback interfaces).
async fn announce(session: &zenoh::Session, configured: &str) {
    use std::io::Write;
    let locators: Vec<String> = session
        .info()
        .locators()
        .await
        .iter()
        .map(|l| l.to_string())
        .collect();
    let listening = if locators.is_empty() {
        configured.to_string()
    } else {
        locators.join(", ")
    };
    let mut out = std::io::stdout().lock();
    let _ = writeln!(
        out,
        "{NAME}: listening on {listening} (zid {})",
        session.zid()
    );
    let _ = out.flush();
}

async fn wait_for_stop_signal() -> std::io::Result<()> {
    use tokio::signal::unix::{signal, SignalKind};
    let mut interrupt = signal(SignalKind::interrupt())?;
    let mut terminate = signal(SignalKind::terminate())?;
    tokio::select! {
        _ = interrupt.recv() => {}
        _ = terminate.recv() => {}
    }
    Ok(())
}

/// The router's config: file, then env override, then flags, then our defaults for what is unset.
fn build_config(cli: &Cli) -> Result<Config, String> {
    let mut config = load_config_file(cli)?;
    if let Ok(overrides) = std::env::var(OVERRIDE_ENV) {
        apply_overrides(&mut config, &overrides)?;
    }
    set_endpoints(&mut config, "listen/endpoints", &cli.listen)?;
    set_endpoints(&mut config, "connect/endpoints", &cli.connect)?;
    apply_defaults(config)
}

fn load_config_file(cli: &Cli) -> Result<Config, String> {
    let from_env = std::env::var_os(CONFIG_FILE_ENV)
        .filter(|path| !path.is_empty())
        .map(PathBuf::from);
    match cli.config.clone().or(from_env) {
        Some(path) => Config::from_file(&path).map_err(|e| {
            format!(
                "config file {}: {}",
                path.display(),
                one_line(&e.to_string())
            )
        }),
        None => Ok(Config::default()),
    }
}

/// Applies `key=value;key=value` (values JSON5), as rmw_zenoh's `ZENOH_CONFIG_OVERRIDE`.
fn apply_overrides(config: &mut Config, overrides: &str) -> Result<(), String> {
    for item in overrides
        .split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| format!("{OVERRIDE_ENV}: `{item}` is not key=value"))?;
        insert(config, key.trim(), value.trim()).map_err(|e| format!("{OVERRIDE_ENV}: {e}"))?;
    }
    Ok(())
}

/// Replaces the endpoint list at `key` with `endpoints`, if any were given.
fn set_endpoints(config: &mut Config, key: &str, endpoints: &[String]) -> Result<(), String> {
    if endpoints.is_empty() {
        return Ok(());
    }
    let flag = key.split('/').next().unwrap_or(key);
    for endpoint in endpoints {
        endpoint
            .parse::<zenoh::config::EndPoint>()
            .map_err(|e| format!("--{flag} {endpoint}: {}", one_line(&e.to_string())))?;
    }
    let json = serde_json::to_string(endpoints).expect("a list of strings serializes");
    insert(config, key, &json).map_err(|e| format!("--{flag}: {e}"))
}

/// Router mode, no multicast scouting and the default listen endpoint, where still unset.
fn apply_defaults(mut config: Config) -> Result<Config, String> {
    if is_unset(&config, "mode") {
        insert(&mut config, "mode", "\"router\"")?;
    }
    if is_unset(&config, "scouting/multicast/enabled") {
        insert(&mut config, "scouting/multicast/enabled", "false")?;
    }
    if is_zenoh_default(&config, "listen/endpoints") {
        insert(
            &mut config,
            "listen/endpoints",
            &format!("[\"{DEFAULT_LISTEN}\"]"),
        )?;
    }
    Ok(config)
}

/// A config value not given (null).
fn is_unset(config: &Config, key: &str) -> bool {
    matches!(
        config.get_json(key).as_deref().map(str::trim),
        Ok("null") | Err(_)
    )
}

/// A config value as zenoh fills it in when not given (its listen default is `tcp/[::]:7447`).
fn is_zenoh_default(config: &Config, key: &str) -> bool {
    config.get_json(key).ok() == Config::default().get_json(key).ok()
}

fn insert(config: &mut Config, key: &str, json5_value: &str) -> Result<(), String> {
    config
        .insert_json5(key, json5_value)
        .map_err(|e| format!("{key}={json5_value}: {}", one_line(&e.to_string())))
}

fn init_logging() {
    let filter =
        tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into());
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
}

/// The first non-empty line of a (possibly multi-line) error text, without clap's `error: `.
fn first_line(text: &str) -> String {
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("error");
    line.strip_prefix("error: ").unwrap_or(line).to_string()
}

/// A zenoh error text on one line: its lines joined, without the ` at <source file>:<line>.`
/// locations that zenoh appends.
fn one_line(text: &str) -> String {
    let joined = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && *l != "|")
        .collect::<Vec<_>>()
        .join(" ");
    strip_source_locations(&joined)
}

fn strip_source_locations(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find(" at /") {
        out.push_str(&rest[..at]);
        let tail = &rest[at + 4..];
        let end = tail.find(".rs:").map(|i| i + 4).unwrap_or(tail.len());
        let digits = tail[end..]
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(tail.len() - end);
        let after = &tail[end + digits..];
        rest = after.strip_prefix('.').unwrap_or(after);
    }
    out.push_str(rest);
    out
}

fn usage_error(message: &str) -> ExitCode {
    failure(EXIT_USAGE, message)
}

fn failure(code: u8, message: &str) -> ExitCode {
    eprintln!("{NAME}: error: {message}");
    ExitCode::from(code)
}
