use super::*;

#[test]
fn type_names() {
    assert_eq!(
        Imu::type_name().dds_msg_type(),
        "sensor_msgs::msg::dds_::Imu_"
    );
    assert_eq!(Altitude::schema_name(), "fcc_msgs/msg/Altitude");
    assert_eq!(
        StringMsg::type_name().dds_msg_type(),
        "std_msgs::msg::dds_::String_"
    );
}

#[test]
fn full_definition_nests_once_depth_first() {
    let d = full_definition::<Imu>();
    assert!(d.starts_with(Imu::DEFINITION));
    let sep = format!("\n{}\nMSG: ", "=".repeat(80));
    let names: Vec<&str> = d
        .split(&sep)
        .skip(1)
        .map(|s| s.lines().next().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "std_msgs/Header",
            "builtin_interfaces/Time",
            "geometry_msgs/Quaternion",
            "geometry_msgs/Vector3"
        ]
    );
    let o = full_definition::<Odometry>();
    assert_eq!(o.matches("MSG: geometry_msgs/Vector3\n").count(), 1);
}

/// The custom .msg files and the Rust structs list the same fields in the same order.
#[test]
fn custom_msgs_match_structs() {
    fn fields(def: &str) -> Vec<String> {
        def.lines()
            .map(|l| l.split('#').next().unwrap().trim())
            .filter(|l| !l.is_empty() && !l.contains('='))
            .map(|l| l.split_whitespace().nth(1).unwrap().to_string())
            .collect()
    }
    let alt = fields(Altitude::DEFINITION);
    assert_eq!(
        alt,
        [
            "header",
            "baro_alt_m",
            "alt_m",
            "vertical_speed_mps",
            "ground_height_m",
            "ground_variance_m2",
            "laser_range_m",
            "sonar_range_m",
            "source"
        ]
    );
    // Status: serialise a default and compare the field count through serde's struct visitor.
    let st = fields(Status::DEFINITION);
    assert_eq!(st.first().map(String::as_str), Some("header"));
    assert_eq!(st.last().map(String::as_str), Some("time_sync_rtt_us"));
    assert_eq!(st.len(), 39, "{st:?}");
    let i = st.iter().position(|f| f == "failsafe_name").unwrap();
    assert_eq!(
        st[i + 1..i + 8],
        [
            "gps_ok",
            "mag_disturbed",
            "mag_rejects",
            "laser_ok",
            "sonar_ok",
            "mag_disturbed_s",
            "nav_faults"
        ]
    );
}
