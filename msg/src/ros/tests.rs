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

/// Field names of a struct as serde's derive lists them (declaration order): a deserializer
/// that records the `fields` of `deserialize_struct` and stops.
fn struct_fields<'de, T: serde::Deserialize<'de>>() -> Vec<&'static str> {
    use serde::de::{self, Visitor};
    struct Capture(Vec<&'static str>);
    #[derive(Debug)]
    struct Stop;
    impl std::fmt::Display for Stop {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("stop")
        }
    }
    impl std::error::Error for Stop {}
    impl de::Error for Stop {
        fn custom<M: std::fmt::Display>(_: M) -> Self {
            Stop
        }
    }
    impl<'de> de::Deserializer<'de> for &mut Capture {
        type Error = Stop;
        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
            Err(Stop)
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Stop> {
            self.0 = fields.to_vec();
            Err(Stop)
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
            option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
            ignored_any
        }
    }
    let mut c = Capture(Vec::new());
    let _ = T::deserialize(&mut c);
    c.0
}

/// The custom .msg files and the Rust structs list the same fields in the same order
/// (`FIELDS` is generated from the files by `msg/build.rs`).
#[test]
fn custom_fields_match_msg_files() {
    assert_eq!(struct_fields::<Altitude>(), Altitude::FIELDS);
    assert_eq!(struct_fields::<Status>(), Status::FIELDS);
    assert_eq!(struct_fields::<LinkFrame>(), LinkFrame::FIELDS);
    assert_eq!(Status::FIELDS.len(), 39);
    assert_eq!(Altitude::FIELDS.last(), Some(&"source"));
}

/// The generated constants carry the `.msg` values (spot checks of each file and kind).
#[test]
fn custom_constants_come_from_msg_files() {
    assert_eq!(Altitude::SOURCE_PREDICTED, 4);
    assert_eq!(Status::MODE_PILOT, 4);
    assert_eq!(Status::FAILSAFE_EMERGENCY_KILL, 7);
    assert_eq!(Status::NAV_FAULT_ATTITUDE, 4);
    assert_eq!(LinkFrame::DIRECTION_LINUX_TO_MCU, 1);
    // Every `NAME = value` line of the files is a constant of its struct.
    let n = |def: &str| {
        def.lines()
            .filter(|l| l.split('#').next().unwrap().contains('='))
            .count()
    };
    assert_eq!(n(Altitude::DEFINITION), 5);
    assert_eq!(n(Status::DEFINITION), 16);
    assert_eq!(n(LinkFrame::DEFINITION), 2);
}
