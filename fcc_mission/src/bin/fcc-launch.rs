//! `fcc-launch CONFIG.yaml [name:=value ...]` — a launcher that needs no ROS install.
//!
//! Starts the processes listed in the config in order (waiting for each one's `wait_for` path,
//! e.g. the simulator's pty symlink), prefixes their output with `[name]`, and when the `main`
//! process exits stops the others (SIGTERM in reverse order, SIGKILL after `stop_timeout_s`)
//! and exits with the main process's code. If another process exits first, everything is
//! stopped and the exit code is 1. SIGINT/SIGTERM to the launcher stop everything (exit 130).
//!
//! Several processes may have `main: true` (e.g. one mission node per vehicle, see
//! `launch_configs/four_uav_flight.yaml`): the launcher then runs until ALL of them have exited
//! and exits with the worst (highest) of their codes. Processes may carry a `group:` (e.g. the
//! vehicle): when every main process of a group has exited, the rest of that group is stopped
//! (so a vehicle's simulator writes its CSV and its bridge ends while the other vehicles fly
//! on); a non-main process that exits on its own while a main process of its group (or, without
//! a group, any main process) still runs is an early exit: everything is stopped, exit code 1.
//!
//! At the end it prints the CPU time (user, system) of each process it started, measured when the
//! process is reaped (`getrusage(RUSAGE_CHILDREN)` deltas), its own, and the sum as % of one core
//! over the wall time: `fcc-launch: cpu NAME user U s sys S s (P % of one core)`.
//!
//! Config (see `launch_configs/square_flight.yaml`):
//! ```yaml
//! vars: { speed: "1", out: out }        # defaults; override with speed:=2 on the command line
//! when:                                 # defaults that follow another variable
//!   - {var: speed, is_not: "1", set: {clock_source: mcu}}
//! stop_timeout_s: 10
//! processes:
//!   - name: sitl
//!     cmd: ["${BIN}/fcc-sitl", --scenario, "${CONFIG_DIR}/scenarios/square.yaml", --link-pty,
//!           --pty-link, "${RUN}/link.tty", --speed, "${speed}"]
//!     wait_for: "${RUN}/link.tty"
//!   - name: bridge
//!     cmd: ["${BIN}/fcc-bridge", --device, "${RUN}/link.tty"]
//!   - name: mission
//!     cmd: ["${BIN}/fcc-mission", --mission, "${CONFIG_DIR}/missions/square.yaml"]
//!     main: true
//! report: { csv: "${out}/square_stack.csv", mission: "${CONFIG_DIR}/missions/square.yaml",
//!           append_to: "${out}/summary.txt" }
//! ```
//! `report:` may also be a list of such entries (one per vehicle); they are written when every
//! main process exited with 0.
//! Variables: `${BIN}` (the directory of this executable), `${CONFIG_DIR}`, `${RUN}` (a fresh
//! temporary directory, removed at the end), `vars`, the `when` rules (each printed when it sets
//! a variable), command-line `name:=value` (wins over both), and the environment. `env:` per process adds environment variables.
//!
//! The middleware: `rmw:=rmw_zenoh_cpp` (or any `RMW_IMPLEMENTATION` value; else the launcher's
//! own `RMW_IMPLEMENTATION`) sets `RMW_IMPLEMENTATION` for every process whose `env:` does not;
//! on Zenoh, a config that starts no Zenoh router gets `fcc-zenoh-router` first (rmw_zenoh's
//! port 7447 on loopback), unless `zenoh_router:=false` (one already runs). An unknown name:
//! one error line, exit 2.

use fcc_mission::launch::{
    apply_rmw, expand, next_after_exit, resolve_vars, Config, Next, Proc, Report, Reports, Slot,
    RMW_VAR, ZENOH_ROUTER_VAR,
};
use nix::sys::signal::{self, SigHandler, Signal};
use nix::unistd::Pid;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: nix::libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

fn die(msg: String) -> ! {
    eprintln!("fcc-launch: {msg}");
    std::process::exit(2)
}

fn pipe_lines(name: String, r: impl std::io::Read + Send + 'static, err: bool) {
    std::thread::spawn(move || {
        for line in BufReader::new(r).lines() {
            let Ok(line) = line else { break };
            if err {
                let _ = writeln!(std::io::stderr().lock(), "[{name}] {line}");
            } else {
                let _ = writeln!(std::io::stdout().lock(), "[{name}] {line}");
            }
        }
    });
}

struct Running {
    name: String,
    child: Child,
    status: Option<ExitStatus>,
    main: bool,
    group: Option<String>,
    /// Set when the launcher sent SIGTERM (its group is done): SIGKILL after the stop timeout.
    stopping_since: Option<Instant>,
    /// CPU time used (user, system), s, once reaped.
    cpu_s: Option<(f64, f64)>,
}

impl Running {
    /// Record the exit status of a process just reaped, and its CPU time.
    fn reaped(&mut self, s: Option<ExitStatus>, cpu: &mut CpuMeter) {
        self.status = s;
        self.cpu_s = Some(cpu.delta());
    }

    /// Asks it to stop.
    fn sigterm(&self) {
        println!("fcc-launch: stopping {} (SIGTERM)", self.name);
        let _ = signal::kill(Pid::from_raw(self.child.id() as i32), Signal::SIGTERM);
    }

    /// It did not stop within `timeout` of the SIGTERM: SIGKILL, and reap it.
    fn kill_after(&mut self, timeout: Duration, cpu: &mut CpuMeter) {
        eprintln!(
            "fcc-launch: {} did not stop in {:.0} s; SIGKILL",
            self.name,
            timeout.as_secs_f64()
        );
        let _ = self.child.kill();
        let s = self.child.wait().ok();
        self.reaped(s, cpu);
    }
}

/// CPU time of the reaped processes: `getrusage(RUSAGE_CHILDREN)` grows by each child's
/// user and system time when it is reaped; this thread reaps them one at a time, so each
/// growth is that child's (its own children included, once it has reaped them).
struct CpuMeter {
    last: (f64, f64),
}

impl CpuMeter {
    fn children() -> (f64, f64) {
        rusage_s(nix::sys::resource::UsageWho::RUSAGE_CHILDREN)
    }
    fn new() -> Self {
        CpuMeter {
            last: Self::children(),
        }
    }
    fn delta(&mut self) -> (f64, f64) {
        let now = Self::children();
        let d = (now.0 - self.last.0, now.1 - self.last.1);
        self.last = now;
        d
    }
}

/// CPU time (user, system) of `who`, s (0 when unavailable).
fn rusage_s(who: nix::sys::resource::UsageWho) -> (f64, f64) {
    let tv = |t: nix::sys::time::TimeVal| t.tv_sec() as f64 + t.tv_usec() as f64 * 1e-6;
    nix::sys::resource::getrusage(who)
        .map(|u| (tv(u.user_time()), tv(u.system_time())))
        .unwrap_or((0.0, 0.0))
}

fn code_of(s: &ExitStatus) -> i32 {
    use std::os::unix::process::ExitStatusExt;
    s.code().unwrap_or_else(|| 128 + s.signal().unwrap_or(0))
}

/// SIGTERM the still-running processes in reverse start order, then SIGKILL after `timeout`.
fn stop_all(procs: &mut [Running], timeout: Duration, cpu: &mut CpuMeter) {
    for p in procs.iter_mut().rev() {
        if p.status.is_none() {
            if let Ok(Some(s)) = p.child.try_wait() {
                p.reaped(Some(s), cpu);
                continue;
            }
            p.sigterm();
            let t0 = Instant::now();
            loop {
                if let Ok(Some(s)) = p.child.try_wait() {
                    p.reaped(Some(s), cpu);
                    break;
                }
                if t0.elapsed() > timeout {
                    p.kill_after(timeout, cpu);
                    break;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() || args.iter().any(|a| a == "-h" || a == "--help") {
        println!("usage: fcc-launch CONFIG.yaml [name:=value ...]\n(see launch_configs/square_flight.yaml; rmw:=rmw_zenoh_cpp runs every node on Zenoh)");
        std::process::exit(if args.is_empty() { 2 } else { 0 });
    }
    let launch = Launch::load(&args);
    install_signal_handlers();
    let stop_timeout = Duration::from_secs_f64(launch.cfg.stop_timeout_s);
    let mut running: Vec<Running> = Vec::new();
    let mut cpu = CpuMeter::new();
    let t_start = Instant::now();
    let mut code = match start_all(&launch, &mut running, &mut cpu) {
        Err(e) => {
            eprintln!("fcc-launch: {e}");
            1
        }
        Ok(()) => supervise(&mut running, stop_timeout, &mut cpu, t_start),
    };
    stop_all(&mut running, stop_timeout, &mut cpu);
    // Let the output threads flush the last lines.
    std::thread::sleep(Duration::from_millis(100));
    print_cpu(&running, t_start.elapsed().as_secs_f64());
    let _ = std::fs::remove_dir_all(&launch.run_dir);
    if code == 0 {
        code = write_reports(&launch, t_start);
    }
    let _ = std::io::stdout().flush();
    std::process::exit(code)
}

/// The config with its variables, as given on the command line.
struct Launch {
    cfg: Config,
    cfg_path: PathBuf,
    vars: BTreeMap<String, String>,
    /// `${RUN}`: a fresh temporary directory, removed at the end.
    run_dir: PathBuf,
}

impl Launch {
    /// Reads and checks the config `args[0]`, with the `name:=value` arguments that follow;
    /// exits (code 2) on bad input.
    fn load(args: &[String]) -> Launch {
        let cfg_path = PathBuf::from(&args[0]);
        let cfg = read_config(&cfg_path);
        let mut cli = BTreeMap::new();
        for a in &args[1..] {
            let (k, v) = a
                .split_once(":=")
                .unwrap_or_else(|| die(format!("argument '{a}': expected name:=value")));
            cli.insert(k.to_string(), v.to_string());
        }
        let (mut vars, applied) = resolve_vars(&cfg, &cli);
        for a in applied {
            eprintln!("fcc-launch: {a}");
        }
        let mut cfg = cfg;
        choose_rmw(&mut cfg, &vars);
        let exe_dir = std::env::current_exe()
            .ok()
            .and_then(|p| p.parent().map(Path::to_path_buf))
            .unwrap_or_else(|| PathBuf::from("."));
        let cfg_dir = cfg_path
            .canonicalize()
            .ok()
            .and_then(|p| p.parent().map(Path::to_path_buf))
            .unwrap_or_else(|| PathBuf::from("."));
        let run_dir = std::env::temp_dir().join(format!("fcc-launch.{}", std::process::id()));
        std::fs::create_dir_all(&run_dir)
            .unwrap_or_else(|e| die(format!("{}: {e}", run_dir.display())));
        vars.entry("BIN".into())
            .or_insert_with(|| exe_dir.display().to_string());
        vars.insert("CONFIG_DIR".into(), cfg_dir.display().to_string());
        vars.insert("RUN".into(), run_dir.display().to_string());
        Launch {
            cfg,
            cfg_path,
            vars,
            run_dir,
        }
    }

    /// `s` with its variables expanded; exits (code 2) on an unknown variable.
    fn x(&self, s: &str) -> String {
        let env = |name: &str| std::env::var(name).ok();
        expand(s, &self.vars, &env)
            .unwrap_or_else(|e| die(format!("{}: {e}", self.cfg_path.display())))
    }
}

/// The middleware of every process: `rmw:=NAME`, else the launcher's `RMW_IMPLEMENTATION`
/// (unset or empty: the processes' own choice, DDS by default). An unknown name exits (code 2)
/// with the known ones; on Zenoh a router is added when the config has none ([`apply_rmw`]).
fn choose_rmw(cfg: &mut Config, vars: &BTreeMap<String, String>) {
    let name = vars
        .get(RMW_VAR)
        .cloned()
        .or_else(|| std::env::var("RMW_IMPLEMENTATION").ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty());
    let Some(name) = name else { return };
    let rmw = fcc_ros::rmw::Rmw::from_env_value(Some(&name))
        .unwrap_or_else(|e| die(format!("{RMW_VAR}: {e}")));
    let start_router = match vars.get(ZENOH_ROUTER_VAR).map(String::as_str) {
        None | Some("true") => true,
        Some("false") => false,
        Some(v) => die(format!("{ZENOH_ROUTER_VAR}:={v}: expected true or false")),
    };
    let zenoh = rmw == fcc_ros::rmw::Rmw::Zenoh;
    for note in apply_rmw(cfg, &name, zenoh, start_router) {
        eprintln!("fcc-launch: {note}");
    }
}

/// Parses and checks the config file; exits (code 2) on bad input.
fn read_config(cfg_path: &Path) -> Config {
    let text = std::fs::read_to_string(cfg_path)
        .unwrap_or_else(|e| die(format!("{}: {e}", cfg_path.display())));
    let cfg = Config::from_yaml_str(&text)
        .unwrap_or_else(|e| die(format!("{}: {e}", cfg_path.display())));
    cfg.check()
        .unwrap_or_else(|e| die(format!("{}: {e}", cfg_path.display())));
    cfg
}

fn install_signal_handlers() {
    let handler = SigHandler::Handler(on_signal);
    for s in [Signal::SIGINT, Signal::SIGTERM] {
        // SAFETY: the handler only stores to an atomic.
        unsafe {
            let _ = signal::signal(s, handler);
        }
    }
}

/// Starts the processes in order (each after the previous one's `wait_for` and `delay_s`);
/// an error when one cannot start, exits before its `wait_for` path appears, or the path does
/// not appear in time (or the launcher is stopped meanwhile).
fn start_all(
    launch: &Launch,
    running: &mut Vec<Running>,
    cpu: &mut CpuMeter,
) -> Result<(), String> {
    for p in &launch.cfg.processes {
        let child = spawn(launch, p)?;
        running.push(Running {
            name: p.name.clone(),
            child,
            status: None,
            main: p.main,
            group: p.group.clone(),
            stopping_since: None,
            cpu_s: None,
        });
        if let Some(w) = &p.wait_for {
            let r = running.last_mut().expect("just pushed");
            wait_for_path(r, &PathBuf::from(launch.x(w)), p.wait_timeout_s, cpu)?;
        }
        if p.delay_s > 0.0 {
            std::thread::sleep(Duration::from_secs_f64(p.delay_s));
        }
    }
    Ok(())
}

/// Starts one process, its output piped through `[name]` prefixes.
fn spawn(launch: &Launch, p: &Proc) -> Result<Child, String> {
    let argv: Vec<String> = p.cmd.iter().map(|s| launch.x(s)).collect();
    if argv.is_empty() {
        die(format!("process {}: empty cmd", p.name));
    }
    println!("fcc-launch: starting {}: {}", p.name, argv.join(" "));
    let mut c = Command::new(&argv[0]);
    c.args(&argv[1..])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        // Own process group: a terminal Ctrl-C reaches only the launcher, which stops the
        // processes in order.
        .process_group(0);
    for (k, v) in &p.env {
        c.env(k, launch.x(v));
    }
    let mut child = c
        .spawn()
        .map_err(|e| format!("cannot start {} ({}): {e}", p.name, argv[0]))?;
    pipe_lines(p.name.clone(), child.stdout.take().unwrap(), false);
    pipe_lines(p.name.clone(), child.stderr.take().unwrap(), true);
    Ok(child)
}

/// Waits until `path` exists while `r` runs.
fn wait_for_path(
    r: &mut Running,
    path: &Path,
    timeout_s: f64,
    cpu: &mut CpuMeter,
) -> Result<(), String> {
    let t0 = Instant::now();
    while !path.exists() {
        if let Ok(Some(s)) = r.child.try_wait() {
            r.reaped(Some(s), cpu);
            return Err(format!(
                "{} exited ({}) before {} appeared",
                r.name,
                code_of(&s),
                path.display()
            ));
        }
        if t0.elapsed().as_secs_f64() > timeout_s || STOP.load(Ordering::SeqCst) {
            return Err(format!(
                "{} did not appear within {:.0} s",
                path.display(),
                timeout_s
            ));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Ok(())
}

/// Supervises the started processes until the run is over (see [`next_after_exit`]); the exit
/// code (130 when the launcher is stopped).
fn supervise(
    running: &mut [Running],
    stop_timeout: Duration,
    cpu: &mut CpuMeter,
    t_start: Instant,
) -> i32 {
    loop {
        if STOP.load(Ordering::SeqCst) {
            eprintln!("fcc-launch: interrupted; stopping everything");
            return 130;
        }
        // Processes of a finished group that ignore SIGTERM: SIGKILL after the timeout.
        for r in running.iter_mut() {
            if let (None, Some(t0)) = (r.status, r.stopping_since) {
                if t0.elapsed() > stop_timeout {
                    r.kill_after(stop_timeout, cpu);
                }
            }
        }
        let ended = running.iter_mut().position(|r| {
            r.status.is_none()
                && match r.child.try_wait() {
                    Ok(Some(s)) => {
                        r.reaped(Some(s), cpu);
                        true
                    }
                    _ => false,
                }
        });
        match ended {
            Some(i) => {
                if let Some(code) = on_exit(running, i, t_start.elapsed().as_secs_f64()) {
                    return code;
                }
            }
            None => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

/// Process `i` has exited (after `el` s): say so and apply the supervision rules; the exit code
/// when the run is over.
fn on_exit(running: &mut [Running], i: usize, el: f64) -> Option<i32> {
    let slots: Vec<Slot> = running
        .iter()
        .map(|r| Slot {
            main: r.main,
            group: r.group.clone(),
            code: r.status.as_ref().map(code_of),
            stopping: r.stopping_since.is_some(),
        })
        .collect();
    let c = code_of(&running[i].status.unwrap());
    let name = running[i].name.clone();
    match next_after_exit(&slots, i) {
        Next::Continue if running[i].stopping_since.is_some() => {}
        Next::Continue => println!("fcc-launch: {name} exited with code {c} after {el:.1} s"),
        Next::Stop(list) => {
            println!(
                "fcc-launch: {name} exited with code {c} after {el:.1} s; stopping group {}",
                running[i].group.as_deref().unwrap_or("")
            );
            for k in list {
                running[k].sigterm();
                running[k].stopping_since = Some(Instant::now());
            }
        }
        Next::Done(code) => {
            let mains: Vec<String> = running
                .iter()
                .filter(|r| r.main)
                .map(|r| {
                    format!(
                        "{} {}",
                        r.name,
                        r.status.as_ref().map(code_of).unwrap_or(-1)
                    )
                })
                .collect();
            if mains.len() == 1 {
                println!(
                    "fcc-launch: {name} exited with code {code} after {el:.1} s; stopping the others"
                );
            } else {
                println!(
                    "fcc-launch: all {} main processes exited after {el:.1} s ({}); exit code {code}; stopping the others",
                    mains.len(),
                    mains.join(", ")
                );
            }
            return Some(code);
        }
        Next::Early => {
            eprintln!("fcc-launch: {name} exited early with code {c}; stopping everything");
            return Some(1);
        }
    }
    None
}

/// CPU use of the run: each process, the launcher itself, the sum (% of one core).
fn print_cpu(running: &[Running], wall_s: f64) {
    let own = rusage_s(nix::sys::resource::UsageWho::RUSAGE_SELF);
    let mut total = own.0 + own.1;
    for r in running {
        if let Some((u, s)) = r.cpu_s {
            total += u + s;
            println!(
                "fcc-launch: cpu {} user {u:.2} s sys {s:.2} s ({:.1} % of one core)",
                r.name,
                100.0 * (u + s) / wall_s.max(1e-9)
            );
        }
    }
    println!(
        "fcc-launch: cpu fcc-launch user {:.2} s sys {:.2} s; all processes {total:.2} s in {wall_s:.1} s wall = {:.1} % of one core",
        own.0,
        own.1,
        100.0 * total / wall_s.max(1e-9)
    );
}

/// The `report:` entries (after a run whose main processes all exited with 0); the exit code:
/// 1 when a report could not be made or appended.
fn write_reports(launch: &Launch, t_start: Instant) -> i32 {
    let mut code = 0;
    for r in launch.cfg.report.iter().flat_map(Reports::list) {
        let text = match report_text(launch, r, t_start.elapsed().as_secs_f64()) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("fcc-launch: report: {e}");
                code = 1;
                continue;
            }
        };
        print!("{text}");
        if let Some(a) = &r.append_to {
            let a = launch.x(a);
            let res = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&a)
                .and_then(|mut f| f.write_all(text.as_bytes()));
            if let Err(e) = res {
                eprintln!("fcc-launch: {a}: {e}");
                code = 1;
            }
        }
    }
    code
}

/// One report: the cross-track figures of the flight in `csv` against `mission`.
fn report_text(launch: &Launch, r: &Report, wall_s: f64) -> Result<String, String> {
    let (csv, mission) = (launch.x(&r.csv), launch.x(&r.mission));
    let c = std::fs::read_to_string(&csv).map_err(|e| format!("{csv}: {e}"))?;
    let m = std::fs::read_to_string(&mission).map_err(|e| format!("{mission}: {e}"))?;
    let m = fcc_mission::from_yaml_str(&m).map_err(|e| format!("{mission}: {e}"))?;
    let rep = fcc_mission::track::report(&c, &m)?;
    let title = r
        .title
        .clone()
        .map(|t| launch.x(&t))
        .unwrap_or_else(|| "full-stack flight".into());
    Ok(format!("== {title} ({wall_s:.1} s wall)\n{rep}\n"))
}
