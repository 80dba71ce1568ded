//! SROS2 (ROS 2 security, issue 19): the stack's enclaves and their DDS Security documents.
//!
//! Pure text: the governance document (who may join, what is protected) and, per enclave, a
//! least-privilege permissions document whose topic lists are derived from the topic table
//! ([`crate::topics::table`]), so a topic added there is granted to the right roles without a
//! second list. Signing and keys are `fcc_bridge::keystore`'s (openssl).
//!
//! DDS names (rmw's mangling): a ROS topic `/a/b` is the DDS topic `rt/a/b`; a service `/a/s`
//! is `rq/a/sRequest` and `rr/a/sReply`; an action `/a/x` is the services
//! `/a/x/_action/{send_goal,cancel_goal,get_result}` and the topics
//! `/a/x/_action/{feedback,status}`. Every node also writes `ros_discovery_info`, `rt/rosout`
//! and `rt/parameter_events`, and serves its parameters (`rq/<node>/…Request`). Topic names in
//! permissions are fnmatch patterns (DDS Security 1.1 §9.4.1.3).
//!
//! | role | enclave (ns `/fcc`) | publishes | subscribes |
//! |---|---|---|---|
//! | bridge | `/fcc/fcc_bridge` | the table's published topics, its services' replies | the table's read topics, requests to its services |
//! | mission | `/fcc/fcc_mission` | the table's read topics (setpoints, commands), `mission/status`, its actions' replies, feedback, status | the table's published topics, its actions' requests |
//! | ground | `/ground_station` | setpoints, commands, requests to every service and action in the ns | everything in the ns |
//! | observer | `/observer` | nothing of the vehicle's (its own node infrastructure only) | everything in the ns |

use crate::topics::{table, Direction};

/// What an enclave may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The bridge node: telemetry out, setpoints and commands in.
    Bridge,
    /// The mission node: setpoints and commands out, telemetry in, its action servers.
    Mission,
    /// A ground station: may command the vehicle (topics, services, actions) and read all.
    Ground,
    /// An observer: may read everything and command nothing.
    Observer,
}

impl Role {
    /// Every role, in the order of the table above.
    pub const ALL: [Role; 4] = [Role::Bridge, Role::Mission, Role::Ground, Role::Observer];

    pub fn name(self) -> &'static str {
        match self {
            Role::Bridge => "bridge",
            Role::Mission => "mission",
            Role::Ground => "ground",
            Role::Observer => "observer",
        }
    }

    pub fn parse(s: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.name() == s)
    }

    /// The enclave the stack's keystore gives this role in namespace `ns` (`/fcc`).
    pub fn default_enclave(self, ns: &str) -> String {
        match self {
            Role::Bridge => join(ns, "fcc_bridge"),
            Role::Mission => join(ns, "fcc_mission"),
            Role::Ground => "/ground_station".into(),
            Role::Observer => "/observer".into(),
        }
    }
}

/// DDS topic patterns an enclave may write and read.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Grant {
    pub publish: Vec<String>,
    pub subscribe: Vec<String>,
}

/// `ns` + `/` + `name` for a relative name; an absolute name stays as it is.
fn join(ns: &str, name: &str) -> String {
    if name.starts_with('/') {
        name.to_string()
    } else {
        format!("{}/{}", ns.trim_end_matches('/'), name)
    }
}

/// The DDS topic of ROS topic `name` (relative to `ns` unless absolute).
pub fn dds_topic(ns: &str, name: &str) -> String {
    format!("rt{}", join(ns, name))
}

/// The table's topics whose direction is one of `dirs`, as DDS topics.
fn table_topics(ns: &str, dirs: &[Direction]) -> Vec<String> {
    table()
        .into_iter()
        .filter(|(_, _, _, d)| dirs.contains(d))
        .map(|(name, _, _, _)| dds_topic(ns, name))
        .collect()
}

/// What every ROS node writes and reads to exist: discovery info, `/rosout`, parameter events,
/// and its own parameter services (node `fqn`, e.g. `/fcc/fcc_bridge`).
fn node_infrastructure(fqn: &str, g: &mut Grant) {
    g.publish.extend([
        "ros_discovery_info".into(),
        "rt/rosout".into(),
        "rt/parameter_events".into(),
        format!("rr{fqn}/*Reply"),
    ]);
    g.subscribe.extend([
        "ros_discovery_info".into(),
        "rt/parameter_events".into(),
        format!("rq{fqn}/*Request"),
    ]);
}

/// The least-privilege grant of `role` for the vehicle in namespace `ns`, its node being `fqn`.
pub fn grant(role: Role, ns: &str, fqn: &str) -> Grant {
    use Direction::{Published, PublishedOrRead, Read};
    let ns = ns.trim_end_matches('/');
    let mut g = Grant::default();
    node_infrastructure(fqn, &mut g);
    let telemetry = table_topics(ns, &[Published, PublishedOrRead]);
    let commands = table_topics(ns, &[Read, PublishedOrRead]);
    let everything = [
        format!("rt{ns}/*"),
        format!("rr{ns}/*Reply"),
        "rt/tf".into(),
        "rt/tf_static".into(),
        "rt/diagnostics".into(),
        "rt/clock".into(),
        "rt/rosout".into(),
    ];
    match role {
        Role::Bridge => {
            g.publish.extend(telemetry);
            g.publish.push(format!("rr{ns}/*Reply"));
            g.subscribe.extend(commands);
            g.subscribe.push(format!("rq{ns}/*Request"));
        }
        Role::Mission => {
            g.publish.extend(commands);
            g.publish.extend([
                format!("rt{ns}/{}", crate::topics::MISSION_STATUS),
                format!("rr{ns}/*/_action/*Reply"),
                format!("rt{ns}/*/_action/feedback"),
                format!("rt{ns}/*/_action/status"),
            ]);
            g.subscribe.extend(telemetry);
            g.subscribe.push(format!("rq{ns}/*/_action/*Request"));
        }
        Role::Ground => {
            g.publish.extend(commands);
            g.publish.push(format!("rq{ns}/*Request"));
            g.subscribe.extend(everything);
        }
        Role::Observer => g.subscribe.extend(everything),
    }
    for v in [&mut g.publish, &mut g.subscribe] {
        v.sort();
        v.dedup();
    }
    g
}

/// The DDS domains every document covers: 0–230, the largest range Cyclone DDS accepts (232, the
/// RTPS port mapping's limit, makes its governance parser fail); ROS 2 recommends 0–101.
const DOMAIN_MAX: u32 = 230;

/// The governance document: only authenticated participants join (join access control), and
/// discovery, liveliness, RTPS messages and every topic's data are encrypted and
/// access-controlled (read and write) — sros2's default governance.
pub fn governance_xml() -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id_range><min>0</min><max>{DOMAIN_MAX}</max></id_range>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
"#
    )
}

/// Escape `&`, `<`, `>` for XML text.
fn xml_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn topic_list(tag: &str, topics: &[String]) -> String {
    if topics.is_empty() {
        return String::new();
    }
    let items: String = topics
        .iter()
        .map(|t| format!("            <topic>{}</topic>\n", xml_text(t)))
        .collect();
    format!("        <{tag}>\n          <topics>\n{items}          </topics>\n        </{tag}>\n")
}

/// The permissions document of enclave `enclave` (its certificate's subject is `CN=<enclave>`):
/// `grant` allowed on every domain from `not_before` to `not_after` (`YYYY-MM-DDThh:mm:ss`),
/// everything else denied.
pub fn permissions_xml(enclave: &str, grant: &Grant, not_before: &str, not_after: &str) -> String {
    let e = xml_text(enclave);
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="{e}">
      <subject_name>CN={e}</subject_name>
      <validity>
        <not_before>{not_before}</not_before>
        <not_after>{not_after}</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id_range><min>0</min><max>{DOMAIN_MAX}</max></id_range>
        </domains>
{pub_}{sub}      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
"#,
        pub_ = topic_list("publish", &grant.publish),
        sub = topic_list("subscribe", &grant.subscribe),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn has(v: &[String], s: &str) -> bool {
        v.iter().any(|x| x == s)
    }

    #[test]
    fn bridge_publishes_telemetry_and_reads_commands_from_the_table() {
        let g = grant(Role::Bridge, "/fcc", "/fcc/fcc_bridge");
        assert!(has(&g.publish, "rt/fcc/imu/data_raw"));
        assert!(has(&g.publish, "rt/tf"), "absolute names stay absolute");
        assert!(has(&g.subscribe, "rt/fcc/setpoint/velocity"));
        assert!(has(&g.subscribe, "rt/fcc/cmd/arm"));
        assert!(!has(&g.publish, "rt/fcc/setpoint/velocity"));
        assert!(!has(&g.publish, "rt/fcc/link/raw_frames"), "recorded only");
        assert!(has(&g.publish, "rt/clock") && has(&g.subscribe, "rt/clock"));
    }

    #[test]
    fn observer_commands_nothing_and_ground_commands() {
        let o = grant(Role::Observer, "/fcc", "/observer");
        let ground = grant(Role::Ground, "/fcc", "/ground_station");
        for t in [
            "rt/fcc/setpoint/velocity",
            "rt/fcc/cmd/arm",
            "rq/fcc/*Request",
        ] {
            assert!(!has(&o.publish, t), "observer may not write {t}");
            assert!(has(&ground.publish, t), "ground may write {t}");
        }
        assert!(has(&o.subscribe, "rt/fcc/*"));
        // Its own node's infrastructure only.
        assert_eq!(
            o.publish,
            [
                "ros_discovery_info",
                "rr/observer/*Reply",
                "rt/parameter_events",
                "rt/rosout"
            ]
        );
    }

    #[test]
    fn mission_writes_setpoints_and_serves_its_actions() {
        let m = grant(Role::Mission, "/fcc/", "/fcc/fcc_mission");
        assert!(has(&m.publish, "rt/fcc/setpoint/velocity"));
        assert!(has(&m.publish, "rt/fcc/mission/status"));
        assert!(has(&m.publish, "rt/fcc/*/_action/feedback"));
        assert!(has(&m.subscribe, "rq/fcc/*/_action/*Request"));
        assert!(has(&m.subscribe, "rt/fcc/state/odom"));
        assert!(
            !has(&m.subscribe, "rq/fcc/*Request"),
            "not the bridge's services"
        );
    }

    #[test]
    fn documents_name_the_subject_and_escape_text() {
        let g = Grant {
            publish: vec!["rt/a<b".into()],
            subscribe: vec![],
        };
        let x = permissions_xml("/fcc/x&y", &g, "2026-01-01T00:00:00", "2036-01-01T00:00:00");
        assert!(x.contains("<subject_name>CN=/fcc/x&amp;y</subject_name>"));
        assert!(x.contains("<topic>rt/a&lt;b</topic>"));
        assert!(!x.contains("<subscribe>"));
        assert!(x.contains("<default>DENY</default>"));
        assert!(governance_xml().contains("<allow_unauthenticated_participants>false"));
    }

    #[test]
    fn roles_parse_and_name_their_enclaves() {
        for r in Role::ALL {
            assert_eq!(Role::parse(r.name()), Some(r));
        }
        assert_eq!(Role::parse("admin"), None);
        assert_eq!(Role::Bridge.default_enclave("/fcc"), "/fcc/fcc_bridge");
        assert_eq!(Role::Observer.default_enclave("/fcc"), "/observer");
    }
}
