//! The MCU parameters the bridge exposes as ROS 2 parameters: the one table in
//! [`fcc_msgs::params`] (name = the firmware's `section.field`, link id, the firmware's default,
//! range, unit, doc). The bridge checks the range before it sends a value; the MCU checks again
//! (same table) and has the last word.

use ros2_client::parameters::{NumericRange, ParameterDescriptor, ParameterType, ParameterValue};

pub use fcc_msgs::params::{by_id, by_name, ParamSpec as McuParam, PARAMS as MCU_PARAMS};

/// Whole-number parameters — the `rates.*` rows (Hz, one per telemetry stream) — are ROS
/// Integer parameters, so `ros2 param set /fcc/fcc_bridge rates.imu_hz 100` works as typed;
/// the others are Double.
pub fn is_integer(p: &McuParam) -> bool {
    fcc_msgs::Stream::by_param_id(p.id).is_some()
}

/// The ROS value of an MCU parameter's value (Integer or Double, see [`is_integer`]).
pub fn ros_value(p: &McuParam, x: f64) -> ParameterValue {
    if is_integer(p) {
        ParameterValue::Integer(x.round() as i64)
    } else {
        ParameterValue::Double(x)
    }
}

/// The ROS parameter descriptor of an MCU parameter (type, range, doc with unit), from the
/// table, as `describe_parameters` answers it ([`crate::ros_api::describe`]).
pub fn descriptor(p: &McuParam) -> ParameterDescriptor {
    let (param_type, range) = if is_integer(p) {
        (
            ParameterType::Integer,
            NumericRange::IntegerRange {
                from_value: p.min as i64,
                to_value: p.max as i64,
                step: 1,
            },
        )
    } else {
        (
            ParameterType::Double,
            NumericRange::FloatingPointRange {
                from_value: p.min as f64,
                to_value: p.max as f64,
                step: 0.0,
            },
        )
    };
    ParameterDescriptor {
        name: p.name.to_string(),
        param_type,
        description: format!("{} ({}; default {})", p.doc, p.unit, p.default),
        additional_constraints: format!("finite, in [{}, {}] {}", p.min, p.max, p.unit),
        read_only: false,
        dynamic_typing: false,
        range,
    }
}

/// Share of the line rate the telemetry may take at its worst case (every frame at its largest):
/// the rest is room for the MCU's replies (acknowledgements, time sync, hello) and clock error.
pub const TELEMETRY_BUDGET_SHARE: f64 = 0.9;

/// A set of `rates.*` values whose worst case exceeds the link budget.
#[derive(Clone, Debug, PartialEq)]
pub struct OverBudget {
    pub worst_case_bytes_per_s: u32,
    pub line_bytes_per_s: u32,
    pub baud: u32,
}

impl std::fmt::Display for OverBudget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the telemetry would need up to {} B/s = {:.1} % of the {} B/s a {}-baud link carries (budget {:.0} %)",
            self.worst_case_bytes_per_s,
            100.0 * self.worst_case_bytes_per_s as f64 / self.line_bytes_per_s as f64,
            self.line_bytes_per_s,
            self.baud,
            100.0 * TELEMETRY_BUDGET_SHARE
        )
    }
}

/// Checks the telemetry rates that `value(id)` gives (each stream's `rates.*` parameter; a
/// missing one is the table's default) against the budget of a link at `baud` (8N1: 10 bits a
/// byte). Ok: the worst-case share of the line rate.
pub fn check_link_budget(value: impl Fn(u16) -> Option<f32>, baud: u32) -> Result<f64, OverBudget> {
    let rates =
        fcc_msgs::StreamRates::from_params(|id| value(id).or_else(|| by_id(id).map(|p| p.default)));
    let line_bytes_per_s = (baud / 10).max(1);
    let share = rates.worst_case_share(line_bytes_per_s);
    if share <= TELEMETRY_BUDGET_SHARE {
        Ok(share)
    } else {
        Err(OverBudget {
            worst_case_bytes_per_s: rates.worst_case_bytes_per_s(),
            line_bytes_per_s,
            baud,
        })
    }
}

/// Marks around the generated table in the README.
pub const README_BEGIN: &str = "<!-- mcu-params:begin (generated from msg/src/params.rs) -->";
pub const README_END: &str = "<!-- mcu-params:end -->";

/// The README's parameter table (Markdown), from the table.
pub fn readme_table() -> String {
    let mut t = String::from(
        "| ROS / MCU parameter | link id | unit | default | range | meaning |\n\
         |---|---|---|---|---|---|\n",
    );
    for p in MCU_PARAMS {
        t += &format!(
            "| `{}` | {} | {} | {} | {}–{} | {} |\n",
            p.name, p.id, p.unit, p.default, p.min, p.max, p.doc
        );
    }
    t
}

/// `launch_configs/mcu_params.yaml`: a `--params-file` with every MCU parameter at its
/// default, grouped by section, each with its unit, range and meaning.
pub fn params_file_yaml() -> String {
    let mut y = String::from(
        "# Every MCU parameter at the firmware's default, as a ROS 2 --params-file for fcc-bridge:\n\
         #   fcc-bridge --device DEV --ros-args --params-file launch_configs/mcu_params.yaml\n\
         # (the bridge range-checks each value and sends it to the MCU after the handshake).\n\
         # GENERATED from the one table (msg/src/params.rs) by\n\
         #   FCC_UPDATE_PARAM_DOCS=1 cargo test -p fcc_bridge --lib mcu_params\n\
         # (a test fails when this file is stale): edit the table, not this file.\n\
         /**:\n  ros__parameters:\n",
    );
    let mut sections: Vec<&str> = Vec::new();
    for p in MCU_PARAMS {
        let (section, _) = p.name.split_once('.').unwrap_or(("", p.name));
        if !sections.contains(&section) {
            sections.push(section);
        }
    }
    for section in sections {
        y += &format!("    {section}:\n");
        for p in MCU_PARAMS {
            if let Some(field) = p
                .name
                .strip_prefix(section)
                .and_then(|f| f.strip_prefix('.'))
            {
                y += &format!(
                    "      # {} [{}], {}..{}\n      {field}: {:?}\n",
                    p.doc, p.unit, p.min, p.max, p.default
                );
            }
        }
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn link_budget_refuses_rates_the_baud_cannot_carry() {
        use fcc_msgs::param_id::RATES_IMU_HZ;
        let share = check_link_budget(|_| None, 921_600).unwrap();
        assert!(share > 0.1 && share < 0.6, "{share}");
        // The defaults need ~28 kB/s: a 115200-baud link (11.5 kB/s) cannot carry them.
        let e = check_link_budget(|_| None, 115_200).unwrap_err();
        assert_eq!(e.line_bytes_per_s, 11_520);
        assert!(
            e.to_string()
                .contains("of the 11520 B/s a 115200-baud link carries (budget 90 %)"),
            "{e}"
        );
        use fcc_msgs::param_id::RATES_NAV_STATE_HZ;
        let imu = |hz: f32| move |id: u16| (id == RATES_IMU_HZ).then_some(hz);
        let fast = check_link_budget(imu(1000.0), 921_600).unwrap();
        assert!(fast > share);
        let low = check_link_budget(imu(0.0), 921_600).unwrap();
        assert!(low < share);
        // IMU at 1 kHz and odometry at 500 Hz, the highest rates: within 921600 baud's budget,
        // more than a whole 460800-baud line.
        let both = |id: u16| match id {
            RATES_IMU_HZ => Some(1000.0),
            RATES_NAV_STATE_HZ => Some(500.0),
            _ => None,
        };
        let most = check_link_budget(both, 921_600).unwrap();
        assert!(most > 0.6 && most <= 0.9, "{most}");
        let e = check_link_budget(both, 460_800).unwrap_err();
        assert!(e.worst_case_bytes_per_s > e.line_bytes_per_s, "{e}");
        println!(
            "921600 baud, IMU 1 kHz + odometry 500 Hz: {:.1} %; 460800 baud: {e}",
            100.0 * most
        );
        let slow = check_link_budget(|_| None, 115_200).unwrap_err();
        println!("115200 baud, the defaults: {slow}");
    }

    #[test]
    fn table_matches_the_link_ids() {
        assert_eq!(MCU_PARAMS.len(), fcc_msgs::param_id::ALL.len());
        for (id, name) in fcc_msgs::param_id::ALL {
            let p = by_id(*id).unwrap();
            assert_eq!(p.name, *name);
            assert!(p.check(p.default as f64).is_ok());
            assert!(p.check(p.max as f64 * 2.0 + 1.0).is_err());
            let d = descriptor(p);
            assert!(match d.range {
                NumericRange::FloatingPointRange {
                    from_value,
                    to_value,
                    ..
                } => !is_integer(p) && from_value == p.min as f64 && to_value == p.max as f64,
                NumericRange::IntegerRange {
                    from_value,
                    to_value,
                    ..
                } => is_integer(p) && from_value == p.min as i64 && to_value == p.max as i64,
                _ => false,
            });
        }
        let e = by_name("limits.max_tilt_deg")
            .unwrap()
            .check(80.0)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "limits.max_tilt_deg: 80 out of range [5, 60]"
        );
    }

    /// The checked-in README table and example params file are the table's; with
    /// `FCC_UPDATE_PARAM_DOCS=1` this test rewrites them instead.
    #[test]
    fn readme_and_params_file_are_generated_from_the_table() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let update = std::env::var_os("FCC_UPDATE_PARAM_DOCS").is_some();
        let yaml_path = root.join("launch_configs/mcu_params.yaml");
        let yaml = params_file_yaml();
        let readme_path = root.join("README.md");
        let readme = std::fs::read_to_string(&readme_path).unwrap();
        let (head, rest) = readme
            .split_once(README_BEGIN)
            .expect("README: table begin mark");
        let (_, tail) = rest.split_once(README_END).expect("README: table end mark");
        let fresh = format!("{head}{README_BEGIN}\n{}{README_END}{tail}", readme_table());
        if update {
            std::fs::write(&yaml_path, &yaml).unwrap();
            std::fs::write(&readme_path, &fresh).unwrap();
        }
        let on_disk = std::fs::read_to_string(&yaml_path).unwrap_or_default();
        assert!(on_disk == yaml, "launch_configs/mcu_params.yaml is stale: FCC_UPDATE_PARAM_DOCS=1 cargo test -p fcc_bridge --lib mcu_params");
        assert!(readme == fresh || update, "README's MCU parameter table is stale: FCC_UPDATE_PARAM_DOCS=1 cargo test -p fcc_bridge --lib mcu_params");
        // The example file loads through the bridge's --params-file reader with every value.
        let p = fcc_ros::params::params_from_yaml(&yaml, "/fcc", "fcc_bridge").unwrap();
        assert_eq!(p.len(), MCU_PARAMS.len());
        for mp in MCU_PARAMS {
            let v: f64 = p[mp.name].parse().unwrap();
            assert_eq!(v as f32, mp.default, "{}", mp.name);
            assert!(mp.check(v).is_ok());
        }
    }
}
