//! Acceptance for issue 14 ("hostile or mistaken input never endangers the vehicle"), through
//! the real binaries:
//!
//! - `tests/mcap/sigkill_recover.sh`: a recording bridge killed with SIGKILL; `fcc-bag-recover`
//!   rewrites the bag; Foxglove's `mcap` reader (summary, `iter_messages`) and `rosbags`'
//!   `AnyReader` read it with equal counts; the data lost before the kill is printed, ≤ 1 s.
//! - `tests/e2e/hostile_input.sh`: a Cyclone DDS peer sends 600 setpoints with a 1 MB frame_id
//!   at 10 Hz (and 1 MB mode texts), then a NaN flood: the bridge's RSS grows ≤ 20 MB, its log
//!   ≤ 64 KB under the flood, every refusal is counted, logs / `/rosout` / `/diagnostics` stay
//!   bounded and escaped.
//!
//! Both scripts put what starts DDS in one loopback-only network namespace (netns-run).
//! Python: `FCC_DDS_PYTHON` (default `python3`) with `cyclonedds`, `mcap`, `mcap-ros2-support`
//! and `rosbags`. Without them the tests are skipped with a message, unless
//! `FCC_REQUIRE_DDS_PEER=1` (scripts/test.sh), where they fail.

use std::path::PathBuf;
use std::process::Command;

fn python_with(modules: &str) -> Option<String> {
    let py = std::env::var("FCC_DDS_PYTHON").unwrap_or_else(|_| "python3".into());
    let required = std::env::var("FCC_REQUIRE_DDS_PEER").is_ok_and(|v| v == "1");
    let ok = Command::new(&py)
        .args(["-c", &format!("import {modules}")])
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        assert!(!required, "{py} cannot import {modules}");
        eprintln!("SKIPPED: {py} cannot import {modules}; set FCC_DDS_PYTHON");
        return None;
    }
    Some(py)
}

fn run(script: &str, py: &str) -> String {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_fcc-bridge"));
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = Command::new(root.join(script))
        .arg(py)
        .env("FCC_BIN_DIR", bin.parent().unwrap())
        .output()
        .unwrap_or_else(|e| panic!("run {script}: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    println!("{stdout}");
    eprintln!("{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{script} failed");
    stdout
}

#[test]
fn killed_recording_is_recovered_for_every_reader() {
    let Some(py) =
        python_with("cyclonedds.domain, mcap.reader, mcap_ros2.decoder, rosbags.highlevel")
    else {
        return;
    };
    // fcc-bag-recover is built beside fcc-bridge (same package).
    assert!(PathBuf::from(env!("CARGO_BIN_EXE_fcc-bag-recover")).exists());
    let s = run("tests/mcap/sigkill_recover.sh", &py);
    assert!(s.contains("PASS recovered bag: both readers"));
    assert!(s.contains("ROW|recorder SIGKILL data lost (recovered bag)|"));
    assert!(s.contains("lost before the kill: "));
    assert!(s.contains("PASS recovering a complete bag keeps it whole"));
}

#[test]
fn hostile_input_keeps_the_bridge_bounded() {
    let Some(py) = python_with("cyclonedds.domain") else {
        return;
    };
    let s = run("tests/e2e/hostile_input.sh", &py);
    assert!(s.contains("PASS hostile input"));
    assert!(s.contains("ROW|bridge RSS growth"));
}
