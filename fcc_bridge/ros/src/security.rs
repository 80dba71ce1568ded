//! ROS 2 security at node start-up (issue 19): the SROS2 environment, the enclave it selects,
//! and the checks that give a node one clear line instead of an opaque handshake failure.
//!
//! The conventions are rcl's (`rcl/security.c`):
//!
//! | setting | meaning |
//! |---|---|
//! | `ROS_SECURITY_ENABLE=true` | security on (only the exact word `true`) |
//! | `ROS_SECURITY_STRATEGY=Enforce` | a missing or bad enclave stops the node; any other value is *Permissive*: the node warns and runs without security |
//! | `ROS_SECURITY_KEYSTORE=DIR` | the keystore; an enclave `/a/b` is `DIR/enclaves/a/b` |
//! | `ROS_SECURITY_ENCLAVE_OVERRIDE=/a/b` | the enclave, over the command line's |
//! | `--ros-args --enclave /a/b` (`-e`) | the enclave; `/` (the keystore's `enclaves/`) when absent |
//!
//! An enclave directory holds the six files of [`ENCLAVE_FILES`]. Before the DDS participant is
//! built, [`check_enclave`] checks them the way the DDS Security plugins will (X.509 validity
//! dates, the identity certificate issued by the identity CA, the key belonging to it, the
//! governance and permissions documents signed by the permissions CA), so an expired
//! certificate or a tampered permissions file is named with its reason. The DDS side (PKI-DH
//! authentication, access control, AES-GCM) is rustdds' builtin security plugins
//! ([`crate::ros_node::context`]).

use crate::params::{enclave_parts, RosArgs};
use std::path::{Path, PathBuf};

/// The files of an SROS2 enclave (rmw_dds_common's names; rustdds'
/// `DomainParticipantSecurityConfigFiles::with_ros_default_names` reads the same).
pub const ENCLAVE_FILES: [&str; 6] = [
    "identity_ca.cert.pem",
    "cert.pem",
    "key.pem",
    "permissions_ca.cert.pem",
    "governance.p7s",
    "permissions.p7s",
];

/// `ROS_SECURITY_STRATEGY`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// A missing or bad enclave refuses the start.
    Enforce,
    /// A missing or bad enclave: a warning, and the node runs without security.
    Permissive,
}

/// The SROS2 settings of one node.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SecurityEnv {
    pub enabled: bool,
    pub strategy: Strategy,
    pub keystore: Option<PathBuf>,
    /// Absolute enclave name (`/` when none is given).
    pub enclave: String,
}

/// What the node does about security.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Decision {
    /// Run without security (disabled, or Permissive without a usable enclave).
    Off { warning: Option<String> },
    /// Build the participant with this enclave directory.
    On { enclave_dir: PathBuf },
}

impl SecurityEnv {
    /// From the environment (`get` reads a variable) and the command line's `--enclave`.
    pub fn from_env(ros: &RosArgs, get: impl Fn(&str) -> Option<String>) -> Self {
        let strategy = match get("ROS_SECURITY_STRATEGY").as_deref() {
            Some("Enforce") => Strategy::Enforce,
            _ => Strategy::Permissive,
        };
        let enclave = get("ROS_SECURITY_ENCLAVE_OVERRIDE")
            .filter(|e| !e.is_empty())
            .or_else(|| ros.enclave.clone())
            .unwrap_or_else(|| "/".to_string());
        SecurityEnv {
            enabled: get("ROS_SECURITY_ENABLE").as_deref() == Some("true"),
            strategy,
            keystore: get("ROS_SECURITY_KEYSTORE")
                .filter(|k| !k.is_empty())
                .map(PathBuf::from),
            enclave,
        }
    }

    /// The enclave directory, checked; `Err` is the one line an Enforce node stops with.
    pub fn decide(&self, now_unix_s: i64) -> Result<Decision, String> {
        if !self.enabled {
            return Ok(Decision::Off { warning: None });
        }
        match self
            .enclave_dir()
            .and_then(|d| check_enclave(&d, now_unix_s).map(|()| d))
        {
            Ok(enclave_dir) => Ok(Decision::On { enclave_dir }),
            Err(e) if self.strategy == Strategy::Enforce => {
                Err(format!("security (ROS_SECURITY_STRATEGY=Enforce): {e}"))
            }
            Err(e) => Ok(Decision::Off {
                warning: Some(format!(
                    "security (Permissive): {e}; running WITHOUT security"
                )),
            }),
        }
    }

    /// `KEYSTORE/enclaves/<enclave>`.
    pub fn enclave_dir(&self) -> Result<PathBuf, String> {
        let ks = self
            .keystore
            .as_ref()
            .ok_or("ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is not set")?;
        let parts = enclave_parts(&self.enclave)?;
        let mut d = ks.join("enclaves");
        d.extend(parts);
        Ok(d)
    }
}

/// Checks an enclave directory as the security plugins will; `Err` names the file and reason.
#[cfg(feature = "security")]
pub fn check_enclave(dir: &Path, now_unix_s: i64) -> Result<(), String> {
    pki::check(dir, now_unix_s)
}

/// Without the `security` feature no enclave can be used.
#[cfg(not(feature = "security"))]
pub fn check_enclave(dir: &Path, _now_unix_s: i64) -> Result<(), String> {
    Err(format!(
        "{}: this build has no DDS Security (cargo feature `security` of fcc_ros)",
        dir.display()
    ))
}

#[cfg(feature = "security")]
mod pki {
    use super::ENCLAVE_FILES;
    use openssl::asn1::Asn1Time;
    use openssl::pkcs7::{Pkcs7, Pkcs7Flags};
    use openssl::pkey::PKey;
    use openssl::stack::Stack;
    use openssl::x509::store::X509StoreBuilder;
    use openssl::x509::X509;
    use std::path::Path;

    pub fn check(dir: &Path, now_unix_s: i64) -> Result<(), String> {
        if !dir.is_dir() {
            return Err(format!("{}: no such enclave directory", dir.display()));
        }
        let read = |name: &str| {
            let p = dir.join(name);
            std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))
        };
        let bytes: Vec<Vec<u8>> = ENCLAVE_FILES
            .iter()
            .map(|f| read(f))
            .collect::<Result<_, _>>()?;
        let [id_ca, cert, key, perm_ca, gov, perm] = &bytes[..] else {
            unreachable!("six enclave files")
        };
        let at = |name: &str| dir.join(name).display().to_string();
        let now = Asn1Time::from_unix(now_unix_s).map_err(|e| e.to_string())?;
        let id_ca = certificate(id_ca, &at("identity_ca.cert.pem"), &now)?;
        let cert = certificate(cert, &at("cert.pem"), &now)?;
        let perm_ca = certificate(perm_ca, &at("permissions_ca.cert.pem"), &now)?;
        let ca_key = id_ca.public_key().map_err(|e| e.to_string())?;
        if !cert.verify(&ca_key).unwrap_or(false) {
            return Err(format!(
                "{}: not issued by the identity CA in identity_ca.cert.pem",
                at("cert.pem")
            ));
        }
        let key = PKey::private_key_from_pem(key).map_err(|_| {
            format!(
                "{}: not a PEM private key (or it is encrypted)",
                at("key.pem")
            )
        })?;
        let cert_key = cert.public_key().map_err(|e| e.to_string())?;
        if !key.public_eq(&cert_key) {
            return Err(format!("{}: not the key of cert.pem", at("key.pem")));
        }
        signed(gov, &at("governance.p7s"), &perm_ca)?;
        signed(perm, &at("permissions.p7s"), &perm_ca)?;
        Ok(())
    }

    /// A PEM X.509 certificate valid at `now`.
    fn certificate(pem: &[u8], at: &str, now: &Asn1Time) -> Result<X509, String> {
        let c = X509::from_pem(pem).map_err(|_| format!("{at}: not a PEM X.509 certificate"))?;
        if c.not_after() < now {
            return Err(format!("{at}: certificate expired on {}", c.not_after()));
        }
        if c.not_before() > now {
            return Err(format!(
                "{at}: certificate not valid before {}",
                c.not_before()
            ));
        }
        Ok(c)
    }

    /// An S/MIME document signed by `ca` (what `openssl smime -verify -CAfile` checks).
    fn signed(smime: &[u8], at: &str, ca: &X509) -> Result<(), String> {
        let (p7, content) =
            Pkcs7::from_smime(smime).map_err(|_| format!("{at}: not an S/MIME signed document"))?;
        let mut store = X509StoreBuilder::new().map_err(|e| e.to_string())?;
        store.add_cert(ca.clone()).map_err(|e| e.to_string())?;
        let store = store.build();
        let certs = Stack::new().map_err(|e| e.to_string())?;
        let mut out = Vec::new();
        p7.verify(&certs, &store, content.as_deref(), Some(&mut out), Pkcs7Flags::empty())
            .map_err(|_| {
                format!("{at}: signature does not verify against permissions_ca.cert.pem (tampered, or signed by another CA)")
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(vars: &[(&str, &str)], enclave: Option<&str>) -> SecurityEnv {
        let ros = RosArgs {
            enclave: enclave.map(str::to_string),
            ..Default::default()
        };
        let vars: Vec<(String, String)> = vars
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        SecurityEnv::from_env(&ros, |k| {
            vars.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone())
        })
    }

    #[test]
    fn rcl_conventions() {
        let e = env(&[], None);
        assert!(!e.enabled);
        assert_eq!(e.decide(0), Ok(Decision::Off { warning: None }));
        // Only the exact word enables it; only the exact word enforces.
        assert!(!env(&[("ROS_SECURITY_ENABLE", "1")], None).enabled);
        let e = env(
            &[
                ("ROS_SECURITY_ENABLE", "true"),
                ("ROS_SECURITY_STRATEGY", "enforce"),
            ],
            None,
        );
        assert_eq!(e.strategy, Strategy::Permissive);
        let e = env(
            &[
                ("ROS_SECURITY_ENABLE", "true"),
                ("ROS_SECURITY_KEYSTORE", "/ks"),
                ("ROS_SECURITY_ENCLAVE_OVERRIDE", "/over/ride"),
            ],
            Some("/fcc/fcc_bridge"),
        );
        assert_eq!(
            e.enclave_dir().unwrap(),
            PathBuf::from("/ks/enclaves/over/ride")
        );
        let e = env(&[("ROS_SECURITY_KEYSTORE", "/ks")], Some("/fcc/fcc_bridge"));
        assert_eq!(
            e.enclave_dir().unwrap(),
            PathBuf::from("/ks/enclaves/fcc/fcc_bridge")
        );
        let e = env(&[("ROS_SECURITY_KEYSTORE", "/ks")], None);
        assert_eq!(e.enclave_dir().unwrap(), PathBuf::from("/ks/enclaves"));
    }

    #[test]
    fn bad_enclave_names_are_refused() {
        for bad in ["fcc", "/a/../b", "/a//b", "/a b", "/1a"] {
            assert!(enclave_parts(bad).is_err(), "{bad}");
        }
        assert_eq!(enclave_parts("/a_1/b").unwrap(), vec!["a_1", "b"]);
    }

    #[test]
    fn enforce_refuses_and_permissive_warns() {
        let vars = |strategy| {
            [
                ("ROS_SECURITY_ENABLE", "true"),
                ("ROS_SECURITY_STRATEGY", strategy),
                ("ROS_SECURITY_KEYSTORE", "/nonexistent-keystore"),
            ]
        };
        let e = env(&vars("Enforce"), Some("/fcc/fcc_bridge"))
            .decide(0)
            .unwrap_err();
        assert!(
            e.starts_with("security (ROS_SECURITY_STRATEGY=Enforce): "),
            "{e}"
        );
        assert!(
            e.contains("/nonexistent-keystore/enclaves/fcc/fcc_bridge"),
            "{e}"
        );
        assert!(!e.contains('\n'));
        match env(&vars("Permissive"), None).decide(0).unwrap() {
            Decision::Off { warning: Some(w) } => assert!(w.contains("WITHOUT security"), "{w}"),
            d => panic!("{d:?}"),
        }
        let e = env(
            &[
                ("ROS_SECURITY_ENABLE", "true"),
                ("ROS_SECURITY_STRATEGY", "Enforce"),
            ],
            None,
        );
        assert!(e
            .decide(0)
            .unwrap_err()
            .contains("ROS_SECURITY_KEYSTORE is not set"));
    }
}
