//! The MCU parameters the bridge exposes as ROS 2 parameters: the one table in
//! [`fcc_msgs::params`] (name = the firmware's `section.field`, link id, the firmware's default,
//! range, unit, doc). The bridge checks the range before it sends a value; the MCU checks again
//! (same table) and has the last word.

use ros2_client::parameters::{NumericRange, ParameterDescriptor, ParameterType};

pub use fcc_msgs::params::{by_id, by_name, ParamSpec as McuParam, PARAMS as MCU_PARAMS};

/// The ROS parameter descriptor of an MCU parameter (type, range, doc with unit), from the
/// table, as `describe_parameters` answers it ([`crate::ros_api::describe`]).
pub fn descriptor(p: &McuParam) -> ParameterDescriptor {
    ParameterDescriptor {
        name: p.name.to_string(),
        param_type: ParameterType::Double,
        description: format!("{} ({}; default {})", p.doc, p.unit, p.default),
        additional_constraints: format!("finite, in [{}, {}] {}", p.min, p.max, p.unit),
        read_only: false,
        dynamic_typing: false,
        range: NumericRange::FloatingPointRange {
            from_value: p.min as f64,
            to_value: p.max as f64,
            step: 0.0,
        },
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
    fn table_matches_the_link_ids() {
        assert_eq!(MCU_PARAMS.len(), fcc_msgs::param_id::ALL.len());
        for (id, name) in fcc_msgs::param_id::ALL {
            let p = by_id(*id).unwrap();
            assert_eq!(p.name, *name);
            assert!(p.check(p.default as f64).is_ok());
            assert!(p.check(p.max as f64 * 2.0 + 1.0).is_err());
            let d = descriptor(p);
            assert!(matches!(
                d.range,
                NumericRange::FloatingPointRange { from_value, to_value, .. }
                    if from_value == p.min as f64 && to_value == p.max as f64
            ));
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
