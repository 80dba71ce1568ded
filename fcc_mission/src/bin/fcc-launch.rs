//! `fcc-launch CONFIG.yaml [name:=value ...]` — a launcher that needs no ROS install.
//!
//! Starts the processes listed in the config in order (waiting for each one's `wait_for` path,
//! e.g. the simulator's pty symlink), prefixes their output with `[name]`, and when the `main`
//! process exits stops the others (SIGTERM in reverse order, SIGKILL after `stop_timeout_s`)
//! and exits with the main process's code. If another process exits first, everything is
//! stopped and the exit code is 1. SIGINT/SIGTERM to the launcher stop everything (exit 130).
//!
//! Config (see `launch_configs/square_flight.yaml`):
//! ```yaml
//! vars: { speed: "1", out: out }        # defaults; override with speed:=2 on the command line
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
//! Variables: `${BIN}` (the directory of this executable), `${CONFIG_DIR}`, `${RUN}` (a fresh
//! temporary directory, removed at the end), `vars`, command-line `name:=value`, and the
//! environment. `env:` per process adds environment variables.

use nix::sys::signal::{self, SigHandler, Signal};
use nix::unistd::Pid;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct Config {
    #[serde(default)]
    vars: BTreeMap<String, String>,
    #[serde(default = "default_stop")]
    stop_timeout_s: f64,
    processes: Vec<Proc>,
    #[serde(default)]
    report: Option<Report>,
}

fn default_stop() -> f64 {
    10.0
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct Proc {
    name: String,
    cmd: Vec<String>,
    #[serde(default)]
    env: BTreeMap<String, String>,
    /// Wait until this path exists before starting the next process.
    #[serde(default)]
    wait_for: Option<String>,
    #[serde(default = "default_wait")]
    wait_timeout_s: f64,
    /// The launcher exits when this process exits, with its code.
    #[serde(default)]
    main: bool,
    /// Wait this long after starting it before starting the next one.
    #[serde(default)]
    delay_s: f64,
}

fn default_wait() -> f64 {
    15.0
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct Report {
    csv: String,
    mission: String,
    #[serde(default)]
    append_to: Option<String>,
    #[serde(default)]
    title: Option<String>,
}

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: nix::libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

fn die(msg: String) -> ! {
    eprintln!("fcc-launch: {msg}");
    std::process::exit(2)
}

/// Expand `${NAME}` from `vars`, then the environment; values may use other variables.
fn expand(s: &str, vars: &BTreeMap<String, String>) -> Result<String, String> {
    let mut cur = s.to_string();
    for _ in 0..8 {
        let next = expand_once(&cur, vars)?;
        if next == cur {
            return Ok(next);
        }
        cur = next;
    }
    Err(format!("variables nest too deeply in '{s}'"))
}

fn expand_once(s: &str, vars: &BTreeMap<String, String>) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find("${") {
        out.push_str(&rest[..i]);
        let j = rest[i..]
            .find('}')
            .ok_or(format!("unclosed ${{ in '{s}'"))?
            + i;
        let name = &rest[i + 2..j];
        let v = vars
            .get(name)
            .cloned()
            .or_else(|| std::env::var(name).ok())
            .ok_or(format!("unknown variable ${{{name}}} in '{s}'"))?;
        out.push_str(&v);
        rest = &rest[j + 1..];
    }
    out.push_str(rest);
    Ok(out)
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
}

fn code_of(s: &ExitStatus) -> i32 {
    use std::os::unix::process::ExitStatusExt;
    s.code().unwrap_or_else(|| 128 + s.signal().unwrap_or(0))
}

/// SIGTERM the still-running processes in reverse start order, then SIGKILL after `timeout`.
fn stop_all(procs: &mut [Running], timeout: Duration) {
    for p in procs.iter_mut().rev() {
        if p.status.is_none() {
            if let Ok(Some(s)) = p.child.try_wait() {
                p.status = Some(s);
                continue;
            }
            println!("fcc-launch: stopping {} (SIGTERM)", p.name);
            let _ = signal::kill(Pid::from_raw(p.child.id() as i32), Signal::SIGTERM);
            let t0 = Instant::now();
            loop {
                if let Ok(Some(s)) = p.child.try_wait() {
                    p.status = Some(s);
                    break;
                }
                if t0.elapsed() > timeout {
                    eprintln!(
                        "fcc-launch: {} did not stop in {:.0} s; SIGKILL",
                        p.name,
                        timeout.as_secs_f64()
                    );
                    let _ = p.child.kill();
                    p.status = p.child.wait().ok();
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
        println!("usage: fcc-launch CONFIG.yaml [name:=value ...]\n(see launch_configs/square_flight.yaml)");
        std::process::exit(if args.is_empty() { 2 } else { 0 });
    }
    let cfg_path = PathBuf::from(&args[0]);
    let text = std::fs::read_to_string(&cfg_path)
        .unwrap_or_else(|e| die(format!("{}: {e}", cfg_path.display())));
    let cfg: Config =
        serde_yaml::from_str(&text).unwrap_or_else(|e| die(format!("{}: {e}", cfg_path.display())));
    let secs = |field: String, v: f64| {
        if !(v.is_finite() && (0.0..=86_400.0).contains(&v)) {
            die(format!(
                "{}: {field}: must be a number of seconds in [0, 86400], got {v}",
                cfg_path.display()
            ));
        }
    };
    secs("stop_timeout_s".into(), cfg.stop_timeout_s);
    for (i, p) in cfg.processes.iter().enumerate() {
        secs(format!("processes[{i}].delay_s"), p.delay_s);
        secs(format!("processes[{i}].wait_timeout_s"), p.wait_timeout_s);
    }
    let mut vars = cfg.vars.clone();
    for a in &args[1..] {
        let (k, v) = a
            .split_once(":=")
            .unwrap_or_else(|| die(format!("argument '{a}': expected name:=value")));
        vars.insert(k.to_string(), v.to_string());
    }
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
    let x =
        |s: &str| expand(s, &vars).unwrap_or_else(|e| die(format!("{}: {e}", cfg_path.display())));
    if cfg.processes.iter().filter(|p| p.main).count() != 1 {
        die(format!(
            "{}: exactly one process must have main: true",
            cfg_path.display()
        ));
    }

    let handler = SigHandler::Handler(on_signal);
    for s in [Signal::SIGINT, Signal::SIGTERM] {
        // SAFETY: the handler only stores to an atomic.
        unsafe {
            let _ = signal::signal(s, handler);
        }
    }

    let stop_timeout = Duration::from_secs_f64(cfg.stop_timeout_s);
    let mut running: Vec<Running> = Vec::new();
    let mut main_idx = 0;
    let t_start = Instant::now();
    let mut fail_early: Option<String> = None;
    'start: for p in &cfg.processes {
        let argv: Vec<String> = p.cmd.iter().map(|s| x(s)).collect();
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
            c.env(k, x(v));
        }
        let mut child = match c.spawn() {
            Ok(ch) => ch,
            Err(e) => {
                fail_early = Some(format!("cannot start {} ({}): {e}", p.name, argv[0]));
                break 'start;
            }
        };
        pipe_lines(p.name.clone(), child.stdout.take().unwrap(), false);
        pipe_lines(p.name.clone(), child.stderr.take().unwrap(), true);
        if p.main {
            main_idx = running.len();
        }
        running.push(Running {
            name: p.name.clone(),
            child,
            status: None,
        });
        if let Some(w) = &p.wait_for {
            let path = PathBuf::from(x(w));
            let t0 = Instant::now();
            while !path.exists() {
                let r = running.last_mut().unwrap();
                if let Ok(Some(s)) = r.child.try_wait() {
                    r.status = Some(s);
                    fail_early = Some(format!(
                        "{} exited ({}) before {} appeared",
                        p.name,
                        code_of(&s),
                        path.display()
                    ));
                    break 'start;
                }
                if t0.elapsed().as_secs_f64() > p.wait_timeout_s || STOP.load(Ordering::SeqCst) {
                    fail_early = Some(format!(
                        "{} did not appear within {:.0} s",
                        path.display(),
                        p.wait_timeout_s
                    ));
                    break 'start;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        if p.delay_s > 0.0 {
            std::thread::sleep(Duration::from_secs_f64(p.delay_s));
        }
    }

    let mut code = 1;
    if let Some(e) = fail_early {
        eprintln!("fcc-launch: {e}");
    } else {
        loop {
            if STOP.load(Ordering::SeqCst) {
                eprintln!("fcc-launch: interrupted; stopping everything");
                code = 130;
                break;
            }
            let mut ended = None;
            for (i, r) in running.iter_mut().enumerate() {
                if r.status.is_none() {
                    if let Ok(Some(s)) = r.child.try_wait() {
                        r.status = Some(s);
                        ended = Some(i);
                        break;
                    }
                }
            }
            if let Some(i) = ended {
                let s = running[i].status.unwrap();
                if i == main_idx {
                    code = code_of(&s);
                    println!(
                        "fcc-launch: {} exited with code {code} after {:.1} s; stopping the others",
                        running[i].name,
                        t_start.elapsed().as_secs_f64()
                    );
                } else {
                    eprintln!(
                        "fcc-launch: {} exited early with code {}; stopping everything",
                        running[i].name,
                        code_of(&s)
                    );
                    code = 1;
                }
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    stop_all(&mut running, stop_timeout);
    // Let the output threads flush the last lines.
    std::thread::sleep(Duration::from_millis(100));
    let _ = std::fs::remove_dir_all(&run_dir);

    if code == 0 {
        if let Some(r) = &cfg.report {
            let (csv, mission) = (x(&r.csv), x(&r.mission));
            let rep = std::fs::read_to_string(&csv)
                .map_err(|e| format!("{csv}: {e}"))
                .and_then(|c| {
                    let m =
                        std::fs::read_to_string(&mission).map_err(|e| format!("{mission}: {e}"))?;
                    let m =
                        fcc_mission::from_yaml_str(&m).map_err(|e| format!("{mission}: {e}"))?;
                    fcc_mission::track::report(&c, &m)
                });
            match rep {
                Ok(rep) => {
                    let title = r
                        .title
                        .clone()
                        .map(|t| x(&t))
                        .unwrap_or_else(|| "full-stack flight".into());
                    let text = format!(
                        "== {title} ({:.1} s wall)\n{rep}\n",
                        t_start.elapsed().as_secs_f64()
                    );
                    print!("{text}");
                    if let Some(a) = &r.append_to {
                        let a = x(a);
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
                Err(e) => {
                    eprintln!("fcc-launch: report: {e}");
                    code = 1;
                }
            }
        }
    }
    let _ = std::io::stdout().flush();
    std::process::exit(code)
}
