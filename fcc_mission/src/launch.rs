//! `fcc-launch`'s config and its supervision rules (the launcher binary does the process I/O:
//! spawning, piping, signals, waiting).
//!
//! * [`Config`]: the YAML (`vars`, `when`, `stop_timeout_s`, `processes`, `report`), parsed with
//!   [`Config::from_yaml_str`] and checked with [`Config::check`];
//! * [`resolve_vars`]: the defaults, the `when` rules and the command line's `name:=value`;
//! * [`expand`]: `${NAME}` variables;
//! * [`apply_rmw`]: the middleware of every process (`rmw:=…`), and a Zenoh router when needed;
//! * [`next_after_exit`]: what to do when a process exits (main processes, groups, early exits).
//!
//! Pure logic: no I/O (the environment is passed in to [`expand`]).

use serde::Deserialize;
use std::collections::BTreeMap;

/// A launch config (see the [module docs](self)).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct Config {
    #[serde(default)]
    pub vars: BTreeMap<String, String>,
    /// Defaults that follow another variable (see [`When`]).
    #[serde(default)]
    pub when: Vec<When>,
    #[serde(default = "default_stop")]
    pub stop_timeout_s: f64,
    pub processes: Vec<Proc>,
    #[serde(default)]
    pub report: Option<Reports>,
}

/// A rule on the variables: when `var` is (`is`) or is not (`is_not`) a value, the variables of
/// `set` take these values unless the command line gives them. Values compare as numbers when
/// both read as numbers (`speed: "2.0"` is not `"1"`), else as text. E.g. a simulator faster than
/// real time needs ROS time to be the simulator's:
/// ```yaml
/// when:
///   - {var: speed, is_not: "1", set: {clock_source: mcu, use_sim_time: "true"}}
/// ```
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct When {
    pub var: String,
    #[serde(default)]
    pub is: Option<String>,
    #[serde(default)]
    pub is_not: Option<String>,
    pub set: BTreeMap<String, String>,
}

impl When {
    fn holds(&self, vars: &BTreeMap<String, String>) -> bool {
        let v = vars.get(&self.var).map(String::as_str).unwrap_or("");
        let same = |w: &str| match (v.trim().parse::<f64>(), w.trim().parse::<f64>()) {
            (Ok(a), Ok(b)) => a == b,
            _ => v == w,
        };
        self.is.as_deref().map_or(true, same) && self.is_not.as_deref().map_or(true, |w| !same(w))
    }
}

/// The variables of a run: the config's `vars`, then its `when` rules (in order; each sees the
/// values set so far), then the command line's `name:=value` (which always win). Returns the
/// variables and, for the log, the names each rule set.
pub fn resolve_vars(
    cfg: &Config,
    cli: &BTreeMap<String, String>,
) -> (BTreeMap<String, String>, Vec<String>) {
    let mut vars = cfg.vars.clone();
    vars.extend(cli.iter().map(|(k, v)| (k.clone(), v.clone())));
    let mut applied = Vec::new();
    for w in &cfg.when {
        if !w.holds(&vars) {
            continue;
        }
        for (k, v) in w.set.iter().filter(|(k, _)| !cli.contains_key(*k)) {
            vars.insert(k.clone(), v.clone());
            applied.push(format!("{k}:={v} (because {} is {})", w.var, vars[&w.var]));
        }
    }
    (vars, applied)
}

/// `report:` is one entry or a list of them.
#[derive(Deserialize, Debug)]
#[serde(untagged)]
pub enum Reports {
    One(Report),
    Many(Vec<Report>),
}

impl Reports {
    pub fn list(&self) -> Vec<&Report> {
        match self {
            Reports::One(r) => vec![r],
            Reports::Many(v) => v.iter().collect(),
        }
    }
}

fn default_stop() -> f64 {
    10.0
}

/// One process to start.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Proc {
    pub name: String,
    pub cmd: Vec<String>,
    #[serde(default)]
    pub env: BTreeMap<String, String>,
    /// Wait until this path exists before starting the next process.
    #[serde(default)]
    pub wait_for: Option<String>,
    #[serde(default = "default_wait")]
    pub wait_timeout_s: f64,
    /// The launcher exits when this process exits, with its code (with several main
    /// processes: when all have exited, with the worst code).
    #[serde(default)]
    pub main: bool,
    /// Processes of a group (e.g. one vehicle) are stopped when all the group's main processes
    /// have exited.
    #[serde(default)]
    pub group: Option<String>,
    /// Wait this long after starting it before starting the next one.
    #[serde(default)]
    pub delay_s: f64,
}

fn default_wait() -> f64 {
    15.0
}

/// A cross-track report to print (and append to a file) after a successful run.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Report {
    pub csv: String,
    pub mission: String,
    #[serde(default)]
    pub append_to: Option<String>,
    #[serde(default)]
    pub title: Option<String>,
}

/// The longest time a config may name, s (a day).
pub const MAX_CONFIG_S: f64 = 86_400.0;

impl Config {
    /// Parses the YAML text (unknown fields are errors).
    pub fn from_yaml_str(text: &str) -> Result<Config, serde_yaml::Error> {
        serde_yaml::from_str(text)
    }

    /// The times are seconds in [0, [`MAX_CONFIG_S`]] and at least one process is main; the
    /// error names the field.
    pub fn check(&self) -> Result<(), String> {
        let secs = |field: String, v: f64| {
            if v.is_finite() && (0.0..=MAX_CONFIG_S).contains(&v) {
                Ok(())
            } else {
                Err(format!(
                    "{field}: must be a number of seconds in [0, 86400], got {v}"
                ))
            }
        };
        secs("stop_timeout_s".into(), self.stop_timeout_s)?;
        for (i, p) in self.processes.iter().enumerate() {
            secs(format!("processes[{i}].delay_s"), p.delay_s)?;
            secs(format!("processes[{i}].wait_timeout_s"), p.wait_timeout_s)?;
        }
        for (i, w) in self.when.iter().enumerate() {
            if w.is.is_none() == w.is_not.is_none() {
                return Err(format!("when[{i}]: give exactly one of is / is_not"));
            }
        }
        if !self.processes.iter().any(|p| p.main) {
            return Err("at least one process must have main: true".into());
        }
        Ok(())
    }
}

/// The launch variable that chooses every process's middleware: `rmw:=rmw_zenoh_cpp` (else the
/// launcher's own `RMW_IMPLEMENTATION`, as ROS 2 launch inherits it).
pub const RMW_VAR: &str = "rmw";
/// The launch variable that keeps [`apply_rmw`] from adding a router: `zenoh_router:=false`
/// (one already runs, e.g. `rmw_zenohd`).
pub const ZENOH_ROUTER_VAR: &str = "zenoh_router";
/// The process [`apply_rmw`] adds on Zenoh.
pub const ROUTER_PROC: &str = "zenoh_router";
/// Programs that are Zenoh routers (the last path component of a process's `cmd[0]`).
const ROUTERS: [&str; 3] = ["fcc-zenoh-router", "rmw_zenohd", "zenohd"];

/// The middleware `rmw` (an `RMW_IMPLEMENTATION` value) applied to the processes of a run: each
/// gets `RMW_IMPLEMENTATION=rmw` unless its `env:` names one. On Zenoh (`zenoh`), with
/// `start_router` and no router among the processes, a router is put first — `fcc-zenoh-router`
/// on rmw_zenoh's port 7447 (loopback), where the nodes' default session looks — as
/// `ros2 run rmw_zenoh_cpp rmw_zenohd` is started before a launch on rmw_zenoh. It is not main
/// and has no group: it runs until the main processes end, and its early exit (e.g. the port
/// taken) ends the run. Returns what it did, for the log.
pub fn apply_rmw(cfg: &mut Config, rmw: &str, zenoh: bool, start_router: bool) -> Vec<String> {
    let mut notes = Vec::new();
    let mut set = 0;
    for p in &mut cfg.processes {
        if !p.env.contains_key("RMW_IMPLEMENTATION") {
            p.env.insert("RMW_IMPLEMENTATION".into(), rmw.into());
            set += 1;
        }
    }
    notes.push(format!(
        "RMW_IMPLEMENTATION={rmw} for {set} of {} processes",
        cfg.processes.len()
    ));
    let is_router = |p: &Proc| {
        p.cmd
            .first()
            .and_then(|c| c.rsplit('/').next())
            .is_some_and(|c| ROUTERS.contains(&c))
    };
    if zenoh && start_router && !cfg.processes.iter().any(is_router) {
        cfg.processes.insert(
            0,
            Proc {
                name: ROUTER_PROC.into(),
                cmd: vec!["${BIN}/fcc-zenoh-router".into()],
                env: BTreeMap::new(),
                wait_for: None,
                wait_timeout_s: default_wait(),
                main: false,
                group: None,
                delay_s: 0.5,
            },
        );
        notes.push(format!(
            "the config starts no Zenoh router: starting {ROUTER_PROC} (fcc-zenoh-router, \
             tcp/127.0.0.1:7447) first; {ZENOH_ROUTER_VAR}:=false if one already runs"
        ));
    }
    notes
}

/// Expand `${NAME}` from `vars`, then `env` (the environment); values may use other variables.
pub fn expand(
    s: &str,
    vars: &BTreeMap<String, String>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<String, String> {
    let mut cur = s.to_string();
    for _ in 0..8 {
        let next = expand_once(&cur, vars, env)?;
        if next == cur {
            return Ok(next);
        }
        cur = next;
    }
    Err(format!("variables nest too deeply in '{s}'"))
}

fn expand_once(
    s: &str,
    vars: &BTreeMap<String, String>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<String, String> {
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
            .or_else(|| env(name))
            .ok_or(format!("unknown variable ${{{name}}} in '{s}'"))?;
        out.push_str(&v);
        rest = &rest[j + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// A started process as the supervision rules see it.
#[derive(Clone, Debug, PartialEq)]
pub struct Slot {
    pub main: bool,
    pub group: Option<String>,
    /// Exit code once exited.
    pub code: Option<i32>,
    /// The launcher is stopping it (its group is done).
    pub stopping: bool,
}

/// What to do after process `i` of `slots` exited (its `code` is already set).
#[derive(Debug, PartialEq)]
pub enum Next {
    /// Keep supervising.
    Continue,
    /// Stop these still-running processes (a group whose main processes all exited).
    Stop(Vec<usize>),
    /// Every main process has exited: stop everything and exit with this code (the worst).
    Done(i32),
    /// A non-main process exited on its own while it was still needed: stop everything, exit 1.
    Early,
}

pub fn next_after_exit(slots: &[Slot], i: usize) -> Next {
    let s = &slots[i];
    if s.stopping {
        return Next::Continue;
    }
    let mains_running = |g: Option<&String>| {
        slots
            .iter()
            .any(|x| x.main && x.code.is_none() && (g.is_none() || x.group.as_ref() == g))
    };
    if !s.main {
        // Without a group (or in a group without a main process), a process is needed while
        // any main process runs.
        let g = s
            .group
            .as_ref()
            .filter(|g| slots.iter().any(|x| x.main && x.group.as_ref() == Some(*g)));
        return if mains_running(g) {
            Next::Early
        } else {
            Next::Continue
        };
    }
    if !mains_running(None) {
        let worst = slots
            .iter()
            .filter(|x| x.main)
            .filter_map(|x| x.code)
            .max()
            .unwrap_or(1);
        return Next::Done(worst);
    }
    match &s.group {
        Some(g) if !mains_running(Some(g)) => Next::Stop(
            (0..slots.len())
                .rev()
                .filter(|&k| {
                    let x = &slots[k];
                    x.group.as_ref() == Some(g) && x.code.is_none() && !x.stopping
                })
                .collect(),
        ),
        _ => Next::Continue,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slot(main: bool, group: Option<&str>) -> Slot {
        Slot {
            main,
            group: group.map(str::to_string),
            code: None,
            stopping: false,
        }
    }

    fn cfg(text: &str) -> Config {
        let c = Config::from_yaml_str(text).expect("yaml");
        c.check().expect("check");
        c
    }

    #[test]
    fn rmw_sets_every_process_and_adds_a_router_on_zenoh() {
        let text = "processes:\n  - {name: sitl, cmd: [a]}\n  - {name: bridge, cmd: [b], env: {RMW_IMPLEMENTATION: rmw_cyclonedds_cpp}}\n  - {name: mission, cmd: [c], main: true}\n";
        // DDS: the variable only; no router.
        let mut c = cfg(text);
        let notes = apply_rmw(&mut c, "rmw_fastrtps_cpp", false, true);
        assert_eq!(c.processes.len(), 3);
        assert_eq!(c.processes[0].env["RMW_IMPLEMENTATION"], "rmw_fastrtps_cpp");
        assert_eq!(
            c.processes[1].env["RMW_IMPLEMENTATION"], "rmw_cyclonedds_cpp",
            "a process's own env wins"
        );
        assert!(notes[0].contains("2 of 3"), "{notes:?}");
        // Zenoh: a router first, not main, no group, with the variable too.
        let mut c = cfg(text);
        let notes = apply_rmw(&mut c, "rmw_zenoh_cpp", true, true);
        assert_eq!(c.processes.len(), 4);
        let r = &c.processes[0];
        assert_eq!(
            (r.name.as_str(), r.main, r.group.is_none()),
            (ROUTER_PROC, false, true)
        );
        assert_eq!(r.cmd, vec!["${BIN}/fcc-zenoh-router".to_string()]);
        assert_eq!(c.processes[3].env["RMW_IMPLEMENTATION"], "rmw_zenoh_cpp");
        assert_eq!(notes.len(), 2, "{notes:?}");
        // zenoh_router:=false, or a config with its own router: none added.
        let mut c = cfg(text);
        apply_rmw(&mut c, "rmw_zenoh_cpp", true, false);
        assert_eq!(c.processes.len(), 3);
        let mut c = cfg("processes:\n  - {name: r, cmd: [/opt/ros/bin/rmw_zenohd]}\n  - {name: m, cmd: [c], main: true}\n");
        apply_rmw(&mut c, "rmw_zenoh_cpp", true, true);
        assert_eq!(c.processes.len(), 2);
    }

    #[test]
    fn one_main_as_before() {
        // sitl, bridge, mission (main): the mission's exit ends the run with its code.
        let mut s = vec![slot(false, None), slot(false, None), slot(true, None)];
        s[2].code = Some(3);
        assert_eq!(next_after_exit(&s, 2), Next::Done(3));
        // Another process first: early exit.
        let mut s = vec![slot(false, None), slot(false, None), slot(true, None)];
        s[0].code = Some(0);
        assert_eq!(next_after_exit(&s, 0), Next::Early);
    }

    #[test]
    fn several_mains_with_groups() {
        // Two vehicles: [sitl, bridge, mission] × 2.
        let g = |n| Some(if n == 1 { "uav1" } else { "uav2" });
        let mut s = vec![
            slot(false, g(1)),
            slot(false, g(1)),
            slot(true, g(1)),
            slot(false, g(2)),
            slot(false, g(2)),
            slot(true, g(2)),
        ];
        // uav1's mission ends: its bridge and sitl are stopped (reverse order), uav2 flies on.
        s[2].code = Some(0);
        assert_eq!(next_after_exit(&s, 2), Next::Stop(vec![1, 0]));
        s[0].stopping = true;
        s[1].stopping = true;
        s[0].code = Some(0);
        assert_eq!(next_after_exit(&s, 0), Next::Continue);
        // uav2's bridge dying while its mission runs is an early exit.
        let mut e = s.clone();
        e[4].code = Some(1);
        assert_eq!(next_after_exit(&e, 4), Next::Early);
        // uav2's mission fails: all mains done, the worst code wins.
        s[5].code = Some(1);
        assert_eq!(next_after_exit(&s, 5), Next::Done(1));
        s[5].code = Some(0);
        assert_eq!(next_after_exit(&s, 5), Next::Done(0));
    }

    #[test]
    fn several_mains_without_groups_wait_for_all() {
        let mut s = vec![slot(false, None), slot(true, None), slot(true, None)];
        s[1].code = Some(2);
        assert_eq!(next_after_exit(&s, 1), Next::Continue);
        s[2].code = Some(0);
        assert_eq!(next_after_exit(&s, 2), Next::Done(2));
        // A shared process that exits while a main runs: early.
        let mut s = vec![slot(false, None), slot(true, None), slot(true, None)];
        s[1].code = Some(0);
        s[0].code = Some(0);
        assert_eq!(next_after_exit(&s, 0), Next::Early);
        // Same for a process in a group that has no main process.
        let mut s = vec![slot(false, Some("tools")), slot(true, Some("uav1"))];
        s[0].code = Some(0);
        assert_eq!(next_after_exit(&s, 0), Next::Early);
    }

    #[test]
    fn variables_expand_from_vars_then_env_and_nest() {
        let vars: BTreeMap<String, String> = [
            ("out", "${RUN}/out"),
            ("RUN", "/tmp/r"),
            ("a", "${b}"),
            ("b", "${a}"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        let env = |n: &str| (n == "HOME").then(|| "/home/x".to_string());
        assert_eq!(
            expand("${out}/a.csv", &vars, &env).unwrap(),
            "/tmp/r/out/a.csv"
        );
        assert_eq!(
            expand("${HOME}:${RUN}", &vars, &env).unwrap(),
            "/home/x:/tmp/r"
        );
        assert_eq!(expand("plain $ {x}", &vars, &env).unwrap(), "plain $ {x}");
        assert_eq!(
            expand("${sped}", &vars, &env).unwrap_err(),
            "unknown variable ${sped} in '${sped}'"
        );
        assert!(expand("${out", &vars, &env)
            .unwrap_err()
            .starts_with("unclosed ${"));
        assert!(expand("${a}", &vars, &env)
            .unwrap_err()
            .contains("nest too deeply"));
    }

    #[test]
    fn config_check_names_the_field() {
        let c = |yaml: &str| Config::from_yaml_str(yaml).unwrap().check();
        assert_eq!(c("processes: [{name: a, cmd: [x], main: true}]\n"), Ok(()));
        assert_eq!(
            c("stop_timeout_s: -1\nprocesses: [{name: a, cmd: [x], main: true}]\n"),
            Err("stop_timeout_s: must be a number of seconds in [0, 86400], got -1".into())
        );
        assert!(
            c("processes: [{name: a, cmd: [x], main: true, delay_s: .nan}]\n")
                .unwrap_err()
                .starts_with("processes[0].delay_s: ")
        );
        assert!(
            c("processes: [{name: a, cmd: [x], main: true, wait_timeout_s: 1e6}]\n")
                .unwrap_err()
                .starts_with("processes[0].wait_timeout_s: ")
        );
        assert_eq!(
            c("processes: [{name: a, cmd: [x]}]\n"),
            Err("at least one process must have main: true".into())
        );
    }

    #[test]
    fn when_rules_set_defaults_the_command_line_overrides() {
        let cfg = Config::from_yaml_str(
            "vars: {speed: '1', clock_source: sync, use_sim_time: 'false'}\n\
             when: [{var: speed, is_not: '1', set: {clock_source: mcu, use_sim_time: 'true'}}]\n\
             processes: [{name: a, cmd: [x], main: true}]\n",
        )
        .unwrap();
        assert_eq!(cfg.check(), Ok(()));
        let cli = |kv: &[(&str, &str)]| -> BTreeMap<String, String> {
            kv.iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        // Speed 1 (default, or written as 1.0): the defaults stand.
        for c in [cli(&[]), cli(&[("speed", "1.0")])] {
            let (v, applied) = resolve_vars(&cfg, &c);
            assert_eq!(
                (v["clock_source"].as_str(), v["use_sim_time"].as_str()),
                ("sync", "false")
            );
            assert!(applied.is_empty());
        }
        // speed:=2 alone: the simulator's clock.
        let (v, applied) = resolve_vars(&cfg, &cli(&[("speed", "2")]));
        assert_eq!(
            (v["clock_source"].as_str(), v["use_sim_time"].as_str()),
            ("mcu", "true")
        );
        assert_eq!(applied.len(), 2);
        assert!(applied[0].contains("because speed is 2"), "{applied:?}");
        // What the command line gives wins over a rule.
        let (v, _) = resolve_vars(&cfg, &cli(&[("speed", "2"), ("clock_source", "sync")]));
        assert_eq!(
            (v["clock_source"].as_str(), v["use_sim_time"].as_str()),
            ("sync", "true")
        );
        // A rule needs exactly one condition.
        let bad = Config::from_yaml_str(
            "when: [{var: speed, set: {a: b}}]\nprocesses: [{name: a, cmd: [x], main: true}]\n",
        )
        .unwrap();
        assert_eq!(
            bad.check(),
            Err("when[0]: give exactly one of is / is_not".into())
        );
    }

    #[test]
    fn report_one_or_many() {
        let one = Config::from_yaml_str(
            "processes: [{name: a, cmd: [x], main: true}]\nreport: {csv: a.csv, mission: m.yaml}\n",
        )
        .unwrap();
        assert_eq!(one.report.unwrap().list().len(), 1);
        let many = Config::from_yaml_str(
            "processes: [{name: a, cmd: [x], main: true, group: g}]\nreport:\n  - {csv: a.csv, mission: m.yaml}\n  - {csv: b.csv, mission: m.yaml}\n",
        )
        .unwrap();
        assert_eq!(many.report.unwrap().list().len(), 2);
        assert!(Config::from_yaml_str(
            "processes: [{name: a, cmd: [x], main: true}]\nreport: {csv: a.csv, bogus: 1}\n"
        )
        .is_err());
    }
}
