//! The mission node's ROS parameters: ONE table (name, kind, default, unit, range, meaning).
//! `fcc-mission` derives from it the `-p name:=value` check (unknown names, ranges), its help
//! text, the parameters it declares and what `describe_parameters` answers (all read-only:
//! they are read at start-up).
//!
//! Pure: no ROS types (the `ros` feature's binary turns [`NodeParam`] into a descriptor).

/// What a parameter holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A file path.
    File,
    Bool,
    /// A number in `[min, max]` (`min` itself excluded when `min_excluded`).
    Number {
        min: f64,
        max: f64,
        min_excluded: bool,
    },
}

/// One parameter of the mission node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeParam {
    pub name: &'static str,
    pub kind: Kind,
    /// The value when not given, as typed on a command line ("" = none).
    pub default: &'static str,
    /// Unit of a number ("" = none).
    pub unit: &'static str,
    pub doc: &'static str,
}

/// The longest time a parameter may name, s (a day).
pub const MAX_S: f64 = 86_400.0;

const fn seconds(min_excluded: bool) -> Kind {
    Kind::Number {
        min: 0.0,
        max: MAX_S,
        min_excluded,
    }
}

/// Every parameter of the mission node.
pub const NODE_PARAMS: [NodeParam; 7] = [
    NodeParam {
        name: "mission",
        kind: Kind::File,
        default: "",
        unit: "",
        doc: "the mission YAML file (or --mission FILE), flown as the first goal; empty: wait for action goals",
    },
    NodeParam {
        name: "rate_hz",
        kind: Kind::Number {
            min: 20.0,
            max: 100.0,
            min_excluded: false,
        },
        default: "50",
        unit: "Hz",
        doc: "rate of the setpoints and of the guidance cycle (the bridge forwards at most 100 Hz)",
    },
    NodeParam {
        name: "use_sim_time",
        kind: Kind::Bool,
        default: "false",
        unit: "",
        doc: "false: stamp and time with the Linux clock; true: with /clock (e.g. from fcc-bridge -p clock_source:=mcu)",
    },
    NodeParam {
        name: "timeout_s",
        kind: seconds(true),
        default: "600",
        unit: "s",
        doc: "a goal fails this long after it started (the mission file's: exit 1)",
    },
    NodeParam {
        name: "arm_timeout_s",
        kind: seconds(true),
        default: "60",
        unit: "s",
        doc: "give up when the vehicle has not armed this long after the first arm command",
    },
    NodeParam {
        name: "localhost_only",
        kind: Kind::Bool,
        default: "true",
        unit: "",
        doc: "DDS on loopback only (ROS_LOCALHOST_ONLY / ROS_AUTOMATIC_DISCOVERY_RANGE decide when not given)",
    },
    NodeParam {
        name: "hover_s",
        kind: seconds(false),
        default: "0",
        unit: "s",
        doc: "ROS time in the MCU's HOLD mode after the last waypoint, then land; 0 = land at once",
    },
];

/// The parameter called `name`.
pub fn by_name(name: &str) -> Option<&'static NodeParam> {
    NODE_PARAMS.iter().find(|p| p.name == name)
}

impl NodeParam {
    /// `v` as this parameter's number, or why not (names the parameter, the range and unit).
    pub fn number(&self, v: &str) -> Result<f64, String> {
        let Kind::Number {
            min,
            max,
            min_excluded,
        } = self.kind
        else {
            return Err(format!("parameter {}: not a number parameter", self.name));
        };
        let ok = |x: f64| x.is_finite() && x <= max && (x > min || (!min_excluded && x == min));
        match v.trim().parse::<f64>() {
            Ok(x) if ok(x) => Ok(x),
            _ => Err(format!(
                "parameter {}: '{v}' is outside {}{min}, {max}] {}",
                self.name,
                if min_excluded { "(" } else { "[" },
                self.unit
            )),
        }
    }

    /// The default as a number (numbers only; the table's defaults are checked by a test).
    pub fn default_number(&self) -> f64 {
        self.number(self.default).unwrap_or(f64::NAN)
    }

    /// The description `describe_parameters` gives: meaning, unit, default.
    pub fn description(&self) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" [{}]", self.unit)
        };
        let default = if self.default.is_empty() {
            String::new()
        } else {
            format!("; default {}", self.default)
        };
        format!("{}{unit}{default}", self.doc)
    }
}

/// The "Parameters:" part of `fcc-mission --help`.
pub fn help() -> String {
    let mut s = String::from("Parameters (read at start-up; read-only at run time):\n");
    for p in &NODE_PARAMS {
        s += &format!("  {}: {}\n", p.name, p.description());
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_names_unique() {
        for (i, p) in NODE_PARAMS.iter().enumerate() {
            if matches!(p.kind, Kind::Number { .. }) {
                assert!(p.number(p.default).is_ok(), "{}", p.name);
            }
            assert!(NODE_PARAMS[..i].iter().all(|q| q.name != p.name));
        }
    }

    #[test]
    fn numbers_are_checked_against_their_range() {
        let hover = by_name("hover_s").unwrap();
        assert_eq!(hover.number("30"), Ok(30.0));
        assert_eq!(hover.number("0"), Ok(0.0));
        assert_eq!(hover.number("2.5"), Ok(2.5));
        for bad in ["-1", "nan", "inf", "x", "1e9"] {
            assert_eq!(
                hover.number(bad),
                Err(format!(
                    "parameter hover_s: '{bad}' is outside [0, 86400] s"
                ))
            );
        }
        let timeout = by_name("timeout_s").unwrap();
        assert!(timeout
            .number("0")
            .unwrap_err()
            .contains("outside (0, 86400] s"));
        let rate = by_name("rate_hz").unwrap();
        assert_eq!(rate.default_number(), 50.0);
        assert!(rate
            .number("5")
            .unwrap_err()
            .contains("outside [20, 100] Hz"));
        assert!(by_name("use_sim_time").unwrap().number("1").is_err());
        assert!(by_name("nope").is_none());
    }

    #[test]
    fn help_lists_every_parameter() {
        let h = help();
        for p in &NODE_PARAMS {
            assert!(h.contains(&format!("  {}: ", p.name)), "{}", p.name);
        }
        assert!(h.contains("rate of the setpoints and of the guidance cycle (the bridge forwards at most 100 Hz) [Hz]; default 50"));
    }
}
