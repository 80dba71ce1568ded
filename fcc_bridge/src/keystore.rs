//! SROS2 keystores on disk (issue 19), made with the `openssl` command — no home-made crypto.
//!
//! The layout is `ros2 security create_keystore` / `create_enclave`'s, so rmw and rustdds
//! (`DomainParticipantSecurityConfigFiles::with_ros_default_names`) read it as it is:
//!
//! ```text
//! KEYSTORE/public/ca.cert.pem            the CA (identity and permissions CA are one, as sros2's)
//! KEYSTORE/private/ca.key.pem            its key (keep it off the vehicle)
//! KEYSTORE/enclaves/governance.xml|.p7s  governance, signed by the CA (S/MIME)
//! KEYSTORE/enclaves/<enclave>/           cert.pem key.pem identity_ca.cert.pem
//!                                        permissions_ca.cert.pem governance.p7s
//!                                        permissions.xml permissions.p7s
//! ```
//!
//! Keys are ECDSA P-256 (prime256v1) and signatures SHA-256, as sros2 makes them; an enclave's
//! certificate has the subject `CN=<enclave>`, the name its permissions grant. The documents
//! themselves (and each role's least-privilege topics) are `fcc_ros::sros2`'s.

use anyhow::{bail, Context, Result};
use fcc_ros::sros2::{self, Role};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Validity of the CA and of every certificate and permissions document, days.
pub const VALID_DAYS: u32 = 3650;

/// `openssl req`'s arguments for a new ECDSA P-256 key, unencrypted, SHA-256 signature.
const NEW_KEY: &[&str] = &[
    "-newkey",
    "ec",
    "-pkeyopt",
    "ec_paramgen_curve:prime256v1",
    "-nodes",
    "-sha256",
];

/// Runs `openssl ARGS`; an error names the command and openssl's own message.
fn openssl(args: &[&str]) -> Result<()> {
    let out = Command::new("openssl")
        .args(args)
        .output()
        .context("running openssl (is it installed?)")?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = err
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect();
        bail!(
            "openssl {}: {}",
            args.first().unwrap_or(&""),
            lines.join("; ")
        );
    }
    Ok(())
}

fn path_str(p: &Path) -> Result<&str> {
    p.to_str()
        .with_context(|| format!("{}: not UTF-8", p.display()))
}

/// The CA files of `keystore`.
pub struct Ca {
    pub cert: PathBuf,
    pub key: PathBuf,
}

impl Ca {
    pub fn of(keystore: &Path) -> Ca {
        Ca {
            cert: keystore.join("public/ca.cert.pem"),
            key: keystore.join("private/ca.key.pem"),
        }
    }
}

/// Signs `doc` (a file) with the CA into `out` (S/MIME, text: the verifiers check it with
/// PKCS7_TEXT).
fn smime_sign(ca: &Ca, doc: &Path, out: &Path) -> Result<()> {
    openssl(&[
        "smime",
        "-sign",
        "-text",
        "-in",
        path_str(doc)?,
        "-out",
        path_str(out)?,
        "-signer",
        path_str(&ca.cert)?,
        "-inkey",
        path_str(&ca.key)?,
    ])
}

/// Creates `keystore` with a new CA and the signed governance document; refuses to overwrite
/// an existing CA.
pub fn create(keystore: &Path) -> Result<()> {
    let ca = Ca::of(keystore);
    if ca.key.exists() {
        bail!("{}: a keystore CA exists already", ca.key.display());
    }
    for d in ["public", "private", "enclaves"] {
        fs::create_dir_all(keystore.join(d))
            .with_context(|| format!("creating {}", keystore.join(d).display()))?;
    }
    let days = VALID_DAYS.to_string();
    #[rustfmt::skip]
    let args = [
        &["req", "-x509"], NEW_KEY,
        &["-days", &days, "-subj", "/CN=fcc_keystore_ca",
          "-addext", "basicConstraints=critical,CA:TRUE",
          "-keyout", path_str(&ca.key)?, "-out", path_str(&ca.cert)?],
    ]
    .concat();
    openssl(&args)?;
    let gov = keystore.join("enclaves/governance.xml");
    fs::write(&gov, sros2::governance_xml())?;
    smime_sign(&ca, &gov, &keystore.join("enclaves/governance.p7s"))
}

/// The directory of `enclave` (`/fcc/fcc_bridge`) in `keystore`.
pub fn enclave_dir(keystore: &Path, enclave: &str) -> Result<PathBuf> {
    let rel = enclave.trim_start_matches('/');
    let ok = enclave.starts_with('/')
        && !rel.is_empty()
        && rel
            .split('/')
            .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'));
    if !ok {
        bail!("enclave {enclave:?}: must be an absolute ROS name like /fcc/fcc_bridge");
    }
    Ok(keystore.join("enclaves").join(rel))
}

/// `YYYY-MM-DDThh:mm:ss` of the Unix time `t_s` (UTC), as permissions documents write it.
fn iso8601(t_s: i64) -> String {
    chrono::DateTime::from_timestamp(t_s, 0)
        .unwrap_or_default()
        .format("%Y-%m-%dT%H:%M:%S")
        .to_string()
}

/// Creates `enclave` with `role`'s permissions for the vehicle in namespace `ns`: a key, a
/// certificate `CN=<enclave>` from the CA, the CA certificates, the governance and the signed
/// permissions. `now_s` (Unix time) starts the permissions' validity.
pub fn add_enclave(keystore: &Path, enclave: &str, role: Role, ns: &str, now_s: i64) -> Result<()> {
    let ca = Ca::of(keystore);
    if !ca.key.exists() {
        bail!(
            "{}: no keystore CA (run `fcc-keystore create` first)",
            ca.key.display()
        );
    }
    let dir = enclave_dir(keystore, enclave)?;
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let (key, csr, cert) = (
        dir.join("key.pem"),
        dir.join("req.csr"),
        dir.join("cert.pem"),
    );
    let subject = format!("/CN={}", enclave.replace('/', "\\/"));
    #[rustfmt::skip]
    let args = [
        &["req", "-new"], NEW_KEY,
        &["-subj", &subject, "-keyout", path_str(&key)?, "-out", path_str(&csr)?],
    ]
    .concat();
    openssl(&args)?;
    openssl(&[
        "x509",
        "-req",
        "-in",
        path_str(&csr)?,
        "-CA",
        path_str(&ca.cert)?,
        "-CAkey",
        path_str(&ca.key)?,
        "-CAcreateserial",
        "-sha256",
        "-days",
        &VALID_DAYS.to_string(),
        "-out",
        path_str(&cert)?,
    ])?;
    fs::remove_file(&csr)?;
    for name in ["identity_ca.cert.pem", "permissions_ca.cert.pem"] {
        fs::copy(&ca.cert, dir.join(name))?;
    }
    fs::copy(
        keystore.join("enclaves/governance.p7s"),
        dir.join("governance.p7s"),
    )
    .context("the keystore's governance.p7s")?;
    let grant = sros2::grant(role, ns, enclave);
    let until = now_s + i64::from(VALID_DAYS) * 86_400;
    let xml = sros2::permissions_xml(enclave, &grant, &iso8601(now_s - 86_400), &iso8601(until));
    fs::write(dir.join("permissions.xml"), xml)?;
    smime_sign(
        &ca,
        &dir.join("permissions.xml"),
        &dir.join("permissions.p7s"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso8601_of_known_instants() {
        assert_eq!(iso8601(0), "1970-01-01T00:00:00");
        assert_eq!(iso8601(951_782_400), "2000-02-29T00:00:00");
        assert_eq!(iso8601(1_795_569_000), "2026-11-25T01:10:00");
    }

    #[test]
    fn enclave_names_are_checked() {
        let k = Path::new("/k");
        assert_eq!(
            enclave_dir(k, "/fcc/fcc_bridge").unwrap(),
            Path::new("/k/enclaves/fcc/fcc_bridge")
        );
        for bad in ["fcc", "/", "/a//b", "/a/../b", "/a b"] {
            assert!(enclave_dir(k, bad).is_err(), "{bad}");
        }
    }
}
