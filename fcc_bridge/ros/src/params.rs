//! Command line: `fcc-bridge --device PATH [--baud N] [--ros-args -r __ns:=/fcc -p k:=v …]`,
//! and the DDS environment (`ROS_DOMAIN_ID`, `ROS_LOCALHOST_ONLY`,
//! `ROS_AUTOMATIC_DISCOVERY_RANGE`).

use std::collections::BTreeMap;

/// ROS arguments after `--ros-args` (until `--`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RosArgs {
    /// `-r __ns:=/x`.
    pub namespace: Option<String>,
    /// `-r __node:=name` (or `__name`).
    pub node_name: Option<String>,
    /// `-p name:=value`.
    pub params: BTreeMap<String, String>,
    /// Other `-r from:=to` remaps (topic/service names; see [`remap`]).
    pub remaps: Vec<(String, String)>,
    /// `--params-file FILE` (in order; see [`RosArgs::load_params_files`]).
    pub params_files: Vec<String>,
    /// For parameters that came from a `--params-file`: which file (for error messages).
    pub param_origin: BTreeMap<String, String>,
    /// `--enclave /a/b` (`-e`): the SROS2 enclave ([`crate::security`]).
    pub enclave: Option<String>,
}

impl RosArgs {
    /// Merge the `--params-file` files into `params` for the node `namespace`/`node`: keys
    /// `/**`, `/**/node`, `node`, `ns/node`, `/ns/node`, each with `ros__parameters`; nested
    /// maps become dotted names. `-p` values win over files; later files win over earlier ones.
    pub fn load_params_files(&mut self, namespace: &str, node: &str) -> Result<(), String> {
        let mut from_files = BTreeMap::new();
        for f in &self.params_files {
            let text = std::fs::read_to_string(f).map_err(|e| format!("--params-file {f}: {e}"))?;
            for (k, v) in params_from_yaml(&text, namespace, node)
                .map_err(|e| format!("--params-file {f}: {e}"))?
            {
                from_files.insert(k, (v, f.clone()));
            }
        }
        for (k, (v, f)) in from_files {
            if !self.params.contains_key(&k) {
                self.param_origin.insert(k.clone(), f);
                self.params.insert(k, v);
            }
        }
        Ok(())
    }

    /// Prefix an error about parameter `name` with the file it came from, if it came from one.
    pub fn locate(&self, msg: String) -> String {
        let name = msg
            .strip_prefix("parameter ")
            .and_then(|r| r.split([':', ' ']).next());
        match name.and_then(|n| self.param_origin.get(n)) {
            Some(f) => format!("{f}: {msg}"),
            None => msg,
        }
    }
}

/// Parameters for one node from a ROS 2 parameter YAML text (see
/// [`RosArgs::load_params_files`]), as strings like `-p` values.
pub fn params_from_yaml(
    text: &str,
    namespace: &str,
    node: &str,
) -> Result<BTreeMap<String, String>, String> {
    let doc: serde_yaml::Value = serde_yaml::from_str(text).map_err(|e| format!("{e}"))?;
    let top = doc.as_mapping().ok_or("expected a mapping of node names")?;
    let ns = namespace.trim_matches('/');
    let fq = if ns.is_empty() {
        format!("/{node}")
    } else {
        format!("/{ns}/{node}")
    };
    let mut out = BTreeMap::new();
    // Wildcards first, so that a node's own section wins.
    let mut sections: Vec<(u8, &serde_yaml::Value)> = Vec::new();
    for (k, v) in top {
        let k = k.as_str().ok_or("node names must be strings")?;
        let rank = if k == "/**" {
            0
        } else if k == format!("/**/{node}") {
            1
        } else if k == node || k == fq || k == fq.trim_start_matches('/') {
            2
        } else {
            continue;
        };
        let p = v
            .get("ros__parameters")
            .ok_or_else(|| format!("section '{k}' has no ros__parameters"))?;
        sections.push((rank, p));
    }
    sections.sort_by_key(|(r, _)| *r);
    fn flatten(
        prefix: &str,
        v: &serde_yaml::Value,
        out: &mut BTreeMap<String, String>,
    ) -> Result<(), String> {
        use serde_yaml::Value as V;
        match v {
            V::Mapping(m) => {
                for (k, v) in m {
                    let k = match k {
                        V::String(s) => s.clone(),
                        other => serde_yaml::to_string(other)
                            .map_err(|e| e.to_string())?
                            .trim()
                            .to_string(),
                    };
                    let name = if prefix.is_empty() {
                        k
                    } else {
                        format!("{prefix}.{k}")
                    };
                    flatten(&name, v, out)?;
                }
            }
            V::Bool(b) => {
                out.insert(prefix.to_string(), b.to_string());
            }
            V::Number(n) => {
                out.insert(prefix.to_string(), n.to_string());
            }
            V::String(s) => {
                out.insert(prefix.to_string(), s.clone());
            }
            _ => {
                return Err(format!(
                "parameter {prefix}: unsupported value (arrays and null are not used by this node)"
            ))
            }
        }
        Ok(())
    }
    for (_, p) in sections {
        flatten("", p, &mut out)?;
    }
    Ok(out)
}

/// Apply `-r from:=to` remaps to a topic or service name as the node writes it (`name`,
/// relative or absolute) in namespace `ns`: a rule matches the name as written or its fully
/// qualified form; the result is returned as given (relative names stay relative).
pub fn remap(remaps: &[(String, String)], ns: &str, name: &str) -> String {
    let fq = if name.starts_with('/') {
        name.to_string()
    } else {
        format!("{}/{name}", ns.trim_end_matches('/'))
    };
    for (from, to) in remaps {
        if from == name || *from == fq {
            return to.clone();
        }
    }
    name.to_string()
}

/// The components of an absolute enclave name (`/`, `/a/b`; ROS name characters only).
pub fn enclave_parts(enclave: &str) -> Result<Vec<&str>, String> {
    let rest = enclave
        .strip_prefix('/')
        .ok_or_else(|| format!("enclave '{enclave}' is not absolute (it must start with /)"))?;
    if rest.is_empty() {
        return Ok(Vec::new());
    }
    let parts: Vec<&str> = rest.split('/').collect();
    let ok = |p: &&str| {
        !p.is_empty()
            && !p.starts_with(|c: char| c.is_ascii_digit())
            && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    match parts.iter().find(|p| !ok(p)) {
        Some(bad) => Err(format!("enclave '{enclave}': bad component '{bad}'")),
        None => Ok(parts),
    }
}

/// Split argv into (program args, ROS args). Accepts several `--ros-args` blocks, each ending
/// at `--` or the end.
pub fn split_ros_args(args: &[String]) -> Result<(Vec<String>, RosArgs), String> {
    let mut prog = Vec::new();
    let mut ros = RosArgs::default();
    let mut i = 0;
    let mut in_ros = false;
    while i < args.len() {
        let a = &args[i];
        if a == "--ros-args" {
            in_ros = true;
            i += 1;
            continue;
        }
        if !in_ros {
            prog.push(a.clone());
            i += 1;
            continue;
        }
        match a.as_str() {
            "--" => in_ros = false,
            "-r" | "--remap" | "-p" | "--param" => {
                let v = args
                    .get(i + 1)
                    .ok_or_else(|| format!("{a} needs a value"))?;
                let (k, val) = v
                    .split_once(":=")
                    .ok_or_else(|| format!("{a} {v}: expected name:=value"))?;
                if a.starts_with("-p") || a == "--param" {
                    ros.params.insert(k.to_string(), val.to_string());
                } else {
                    match k {
                        "__ns" => ros.namespace = Some(val.to_string()),
                        "__node" | "__name" => ros.node_name = Some(val.to_string()),
                        _ => ros.remaps.push((k.to_string(), val.to_string())),
                    }
                }
                i += 1;
            }
            "--params-file" => {
                let v = args.get(i + 1).ok_or_else(|| format!("{a} needs a file"))?;
                ros.params_files.push(v.clone());
                i += 1;
            }
            "--log-level" => {
                i += 1;
            }
            "-e" | "--enclave" => {
                let v = args
                    .get(i + 1)
                    .ok_or_else(|| format!("{a} needs an enclave name"))?;
                enclave_parts(v)?;
                ros.enclave = Some(v.clone());
                i += 1;
            }
            "--enable-rosout-logs"
            | "--disable-rosout-logs"
            | "--enable-stdout-logs"
            | "--disable-stdout-logs" => {}
            other => return Err(format!("unsupported ROS argument '{other}'")),
        }
        i += 1;
    }
    Ok((prog, ros))
}

/// Parse a ROS-style boolean parameter value.
pub fn parse_bool(v: &str) -> Result<bool, String> {
    match v.trim().to_ascii_lowercase().as_str() {
        "true" | "1" | "yes" | "on" => Ok(true),
        "false" | "0" | "no" | "off" => Ok(false),
        _ => Err(format!("'{v}' is not a boolean")),
    }
}

/// Whether DDS stays on loopback. `-p localhost_only:=…` wins; then, as rcl (Jazzy) reads the
/// environment: `ROS_LOCALHOST_ONLY=1` → loopback (deprecated in Jazzy, gone in Kilted, still
/// honoured); else `ROS_AUTOMATIC_DISCOVERY_RANGE`: `LOCALHOST` → loopback, `SUBNET` and
/// `SYSTEM_DEFAULT` → every interface (rustdds' default), `OFF` → an error (rustdds cannot turn
/// automatic discovery off), anything else → an error. With neither set: loopback (this
/// project's default, unlike ROS 2's SUBNET), except that `ROS_LOCALHOST_ONLY=0` alone means
/// every interface.
pub fn localhost_only(
    param: Option<&str>,
    ros_localhost_only: Option<&str>,
    discovery_range: Option<&str>,
) -> Result<bool, String> {
    if let Some(p) = param {
        return parse_bool(p);
    }
    let lo = ros_localhost_only.map(str::trim).filter(|v| !v.is_empty());
    if lo == Some("1") {
        return Ok(true);
    }
    let range = discovery_range
        .map(|r| r.trim().to_ascii_uppercase())
        .filter(|r| !r.is_empty());
    match range.as_deref() {
        None => Ok(lo.is_none()),
        Some("LOCALHOST") => Ok(true),
        Some("SUBNET") | Some("SYSTEM_DEFAULT") => Ok(false),
        Some("OFF") => Err(
            "ROS_AUTOMATIC_DISCOVERY_RANGE=OFF is not supported: rustdds cannot \
             turn automatic discovery off (nor take static peers); use LOCALHOST for loopback only"
                .into(),
        ),
        Some(other) => Err(format!(
            "ROS_AUTOMATIC_DISCOVERY_RANGE '{other}' is not one of SUBNET, LOCALHOST, OFF, \
             SYSTEM_DEFAULT"
        )),
    }
}

/// The warning for a non-empty `ROS_STATIC_PEERS`: rustdds 0.15 has no initial-peers list, so
/// the peers are not contacted (discovery is by multicast only).
pub fn static_peers_warning(ros_static_peers: Option<&str>) -> Option<String> {
    let v = ros_static_peers.map(str::trim).filter(|v| !v.is_empty())?;
    Some(format!(
        "ROS_STATIC_PEERS '{v}' ignored: rustdds has no static-peer list (multicast discovery \
         only)"
    ))
}

/// `ROS_DOMAIN_ID` (default 0, must be ≤ 232).
pub fn domain_id(env: Option<&str>) -> Result<u16, String> {
    match env.map(str::trim).filter(|s| !s.is_empty()) {
        None => Ok(0),
        Some(s) => match s.parse::<u16>() {
            Ok(d) if d <= 232 => Ok(d),
            _ => Err(format!("ROS_DOMAIN_ID '{s}' is not a domain id 0..=232")),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn ros_args() {
        let (p, r) = split_ros_args(&s(&[
            "fcc-bridge",
            "--device",
            "/dev/pts/3",
            "--ros-args",
            "-r",
            "__ns:=/uav1",
            "-p",
            "ttl_ms:=500",
            "-r",
            "__node:=b",
            "--",
            "--baud",
            "115200",
        ]))
        .unwrap();
        assert_eq!(
            p,
            s(&["fcc-bridge", "--device", "/dev/pts/3", "--baud", "115200"])
        );
        assert_eq!(r.namespace.as_deref(), Some("/uav1"));
        assert_eq!(r.node_name.as_deref(), Some("b"));
        assert_eq!(r.params["ttl_ms"], "500");
        assert!(split_ros_args(&s(&["x", "--ros-args", "-p"])).is_err());
        assert!(split_ros_args(&s(&["x", "--ros-args", "-p", "novalue"])).is_err());
    }

    #[test]
    fn params_file_and_remaps() {
        let y = "/**:\n  ros__parameters:\n    ttl_ms: 400\n    use_sim_time: true\n\
/uav1/fcc_bridge:\n  ros__parameters:\n    ttl_ms: 500\n    limits:\n      max_tilt_deg: 30.0\n\
other_node:\n  ros__parameters:\n    ttl_ms: 9\n";
        let p = params_from_yaml(y, "/uav1", "fcc_bridge").unwrap();
        assert_eq!(p["ttl_ms"], "500");
        assert_eq!(p["use_sim_time"], "true");
        assert_eq!(p["limits.max_tilt_deg"], "30.0");
        let p = params_from_yaml(y, "/uav2", "fcc_bridge").unwrap();
        assert_eq!(p["ttl_ms"], "400");
        assert!(
            params_from_yaml("/**:\n  ros__parameters:\n    a: [1, 2]\n", "/", "n")
                .unwrap_err()
                .contains("parameter a")
        );
        let dir = std::env::temp_dir().join(format!("fcc_params_{}.yaml", std::process::id()));
        std::fs::write(&dir, y).unwrap();
        let (_, mut r) = split_ros_args(&s(&[
            "x",
            "--ros-args",
            "--params-file",
            dir.to_str().unwrap(),
            "-p",
            "ttl_ms:=700",
        ]))
        .unwrap();
        r.load_params_files("/uav1", "fcc_bridge").unwrap();
        assert_eq!(r.params["ttl_ms"], "700", "-p wins over the file");
        assert_eq!(r.params["limits.max_tilt_deg"], "30.0");
        let _ = std::fs::remove_file(&dir);
        let rm = vec![
            ("imu/data_raw".to_string(), "imu/raw".to_string()),
            ("/fcc/mag".to_string(), "/sensors/mag".to_string()),
        ];
        assert_eq!(remap(&rm, "/fcc", "imu/data_raw"), "imu/raw");
        assert_eq!(remap(&rm, "/fcc", "mag"), "/sensors/mag");
        assert_eq!(remap(&rm, "/uav1", "mag"), "mag");
        assert_eq!(remap(&rm, "/fcc", "baro"), "baro");
    }

    #[test]
    fn dds_env() {
        assert!(localhost_only(None, None, None).unwrap());
        assert!(!localhost_only(Some("false"), Some("1"), None).unwrap());
        assert!(!localhost_only(None, Some("0"), None).unwrap());
        assert!(localhost_only(None, Some("1"), Some("SUBNET")).unwrap());
        assert!(!localhost_only(None, None, Some("SUBNET")).unwrap());
        assert!(!localhost_only(None, None, Some("system_default")).unwrap());
        assert!(localhost_only(None, None, Some("LOCALHOST")).unwrap());
        // ROS_LOCALHOST_ONLY=0 is "not enabled": the range decides (rcl, Jazzy).
        assert!(localhost_only(None, Some("0"), Some("LOCALHOST")).unwrap());
        assert!(!localhost_only(None, Some("0"), Some("SUBNET")).unwrap());
        // OFF cannot be done with rustdds: a clear error, not a silent loopback.
        let e = localhost_only(None, None, Some("OFF")).unwrap_err();
        assert!(e.contains("OFF") && e.contains("LOCALHOST"), "{e}");
        assert!(localhost_only(None, Some("1"), Some("OFF")).unwrap());
        assert!(localhost_only(Some("true"), None, Some("OFF")).unwrap());
        let e = localhost_only(None, None, Some("LAN")).unwrap_err();
        assert!(e.contains("'LAN'") && e.contains("SUBNET"), "{e}");
        assert_eq!(static_peers_warning(None), None);
        assert_eq!(static_peers_warning(Some(" ")), None);
        assert!(static_peers_warning(Some("192.168.0.2")).is_some_and(|w| w.contains("ignored")));
        assert_eq!(domain_id(None).unwrap(), 0);
        assert_eq!(domain_id(Some("42")).unwrap(), 42);
        assert!(domain_id(Some("300")).is_err());
        assert!(domain_id(Some("x")).is_err());
    }
}
