//! Shared by the DDS acceptance tests: find a Python with the independent peer (`cyclonedds`)
//! and run one of the peer scripts in `tests/dds/` (each puts the bridge and the peer in one
//! loopback-only network namespace).

use std::path::PathBuf;
use std::process::Command;

/// Run `tests/dds/<script>` with the peer's Python; `None` (skipped, with a message) when that
/// Python lacks `cyclonedds`, unless `FCC_REQUIRE_DDS_PEER=1`. Returns the script's stdout
/// after asserting it exited 0.
pub fn run_peer_script(script: &str) -> Option<String> {
    let py = std::env::var("FCC_DDS_PYTHON").unwrap_or_else(|_| "python3".into());
    let required = std::env::var("FCC_REQUIRE_DDS_PEER").is_ok_and(|v| v == "1");
    let has_cyclone = Command::new(&py)
        .args(["-c", "import cyclonedds.domain"])
        .status()
        .is_ok_and(|s| s.success());
    if !has_cyclone {
        assert!(
            !required,
            "{py} cannot import cyclonedds (pip install cyclonedds)"
        );
        eprintln!("SKIPPED: {py} has no cyclonedds; set FCC_DDS_PYTHON to a python with it");
        return None;
    }
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_fcc-bridge"));
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = Command::new(root.join("tests/dds").join(script))
        .arg(&py)
        .env("FCC_BIN_DIR", bin.parent().unwrap())
        .output()
        .unwrap_or_else(|e| panic!("run tests/dds/{script}: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    println!("{stdout}");
    eprintln!("{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "tests/dds/{script} failed");
    Some(stdout)
}
