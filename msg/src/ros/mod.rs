//! ROS 2 message types (Jazzy wire format) as serde structs for ros2-client.
//!
//! Each struct's fields are in the exact order of its `.msg` file, so the CDR encoding is what
//! `rclcpp`/Cyclone produce. Fixed arrays longer than 32 (`float64[36]`) use `serde-big-array`
//! (serialised as a tuple, i.e. without a length, like CDR arrays).
//!
//! Every type implements [`RosMsg`]: its package, name, `.msg` text ([`RosMsg::DEFINITION`]) and
//! nested types, so an MCAP writer can build the `ros2msg` schema with [`full_definition`].
//!
//! **Distro**: Jazzy (ros2-client's default). `sensor_msgs/Range` has `float32 variance` after
//! `range` in Jazzy but not in Humble: a Humble reader misdecodes it.

pub mod action;
pub mod custom;
pub mod std_types;

pub use action::*;
pub use custom::*;
pub use std_types::*;

use ros2_client::MessageTypeName;

/// A ROS 2 message type with its name and `.msg` definition.
pub trait RosMsg: ros2_client::Message + Clone + Send + 'static {
    /// Package, e.g. `sensor_msgs`.
    const PACKAGE: &'static str;
    /// Type name, e.g. `Imu`.
    const NAME: &'static str;
    /// The type's own `.msg` text.
    const DEFINITION: &'static str;
    /// Directly nested message types as (`pkg/Name`, definition, their nested types).
    fn nested() -> Vec<NestedDef> {
        Vec::new()
    }
    /// ros2-client type name (→ DDS `pkg::msg::dds_::Name_`).
    fn type_name() -> MessageTypeName {
        MessageTypeName::new(Self::PACKAGE, Self::NAME)
    }
    /// `pkg/msg/Name`, as MCAP schemas and `ros2 topic info` show it.
    fn schema_name() -> String {
        format!("{}/msg/{}", Self::PACKAGE, Self::NAME)
    }
}

/// One nested type of a definition.
#[derive(Clone, Debug)]
pub struct NestedDef {
    /// `pkg/Name` (no `/msg/`, as in MCAP/rosbag2 schema texts).
    pub name: &'static str,
    pub definition: &'static str,
    pub nested: fn() -> Vec<NestedDef>,
}

/// Nested-definition entry for `T`.
pub fn nested_def<T: RosMsg>() -> NestedDef {
    NestedDef {
        name: leak_name::<T>(),
        definition: T::DEFINITION,
        nested: T::nested,
    }
}

fn leak_name<T: RosMsg>() -> &'static str {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static NAMES: OnceLock<Mutex<HashMap<(&'static str, &'static str), &'static str>>> =
        OnceLock::new();
    let mut m = NAMES.get_or_init(Default::default).lock().unwrap();
    m.entry((T::PACKAGE, T::NAME))
        .or_insert_with(|| Box::leak(format!("{}/{}", T::PACKAGE, T::NAME).into_boxed_str()))
}

/// The full `ros2msg` schema text of `T` (as rosbag2/MCAP store it): its own definition, then
/// each nested type once, depth-first, as `"\n" + 80×'=' + "\nMSG: pkg/Name\n" + text`.
pub fn full_definition<T: RosMsg>() -> String {
    let mut out = String::from(T::DEFINITION);
    let mut seen = Vec::new();
    fn walk(defs: Vec<NestedDef>, out: &mut String, seen: &mut Vec<&'static str>) {
        for d in defs {
            if seen.contains(&d.name) {
                continue;
            }
            seen.push(d.name);
            out.push('\n');
            out.push_str(&"=".repeat(80));
            out.push_str("\nMSG: ");
            out.push_str(d.name);
            out.push('\n');
            out.push_str(d.definition);
            walk((d.nested)(), out, seen);
        }
    }
    walk(T::nested(), &mut out, &mut seen);
    out
}

/// Implements [`ros2_client::Message`] and [`RosMsg`].
macro_rules! ros_msg {
    ($ty:ty, $pkg:literal, $name:expr, $def:expr $(, [$($nested:ty),*])?) => {
        impl ros2_client::Message for $ty {}
        impl $crate::ros::RosMsg for $ty {
            const PACKAGE: &'static str = $pkg;
            const NAME: &'static str = $name;
            const DEFINITION: &'static str = $def;
            $(fn nested() -> Vec<$crate::ros::NestedDef> {
                vec![$($crate::ros::nested_def::<$nested>()),*]
            })?
        }
    };
}
pub(crate) use ros_msg;

#[cfg(test)]
mod tests;
