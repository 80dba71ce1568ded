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
    /// Other `-r from:=to` remaps (topic remapping is not supported; they are reported).
    pub remaps: Vec<(String, String)>,
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
            "--log-level" => {
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

/// Loopback-only DDS unless the user opts out: `-p localhost_only:=false` wins, then
/// `ROS_LOCALHOST_ONLY` (1/0), then `ROS_AUTOMATIC_DISCOVERY_RANGE` (LOCALHOST → true,
/// SUBNET/SYSTEM_DEFAULT → false, OFF → true). Default: true.
pub fn localhost_only(
    param: Option<&str>,
    ros_localhost_only: Option<&str>,
    discovery_range: Option<&str>,
) -> Result<bool, String> {
    if let Some(p) = param {
        return parse_bool(p);
    }
    if let Some(v) = ros_localhost_only.filter(|v| !v.is_empty()) {
        return Ok(v.trim() != "0");
    }
    if let Some(r) = discovery_range.filter(|v| !v.is_empty()) {
        return Ok(!matches!(
            r.trim().to_ascii_uppercase().as_str(),
            "SUBNET" | "SYSTEM_DEFAULT"
        ));
    }
    Ok(true)
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
    fn dds_env() {
        assert!(localhost_only(None, None, None).unwrap());
        assert!(!localhost_only(Some("false"), Some("1"), None).unwrap());
        assert!(!localhost_only(None, Some("0"), None).unwrap());
        assert!(localhost_only(None, Some("1"), Some("SUBNET")).unwrap());
        assert!(!localhost_only(None, None, Some("SUBNET")).unwrap());
        assert!(localhost_only(None, None, Some("LOCALHOST")).unwrap());
        assert_eq!(domain_id(None).unwrap(), 0);
        assert_eq!(domain_id(Some("42")).unwrap(), 42);
        assert!(domain_id(Some("300")).is_err());
        assert!(domain_id(Some("x")).is_err());
    }
}
