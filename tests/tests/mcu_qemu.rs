//! The flight core cross-built for the Cortex-M4F and run in QEMU (mps2-an386) on a recorded
//! flight must give the host build's motor commands (scripts/test-mcu.sh does the work).
//!
//! When the cross toolchain (Debian rustc-web/cargo-web + rust-web-src, binutils-arm-none-eabi)
//! or qemu-system-arm is not installed, the test FAILS if `FCC_REQUIRE_MCU=1` (for a CI that
//! runs a plain `cargo test`), and otherwise skips with a message (a developer's plain
//! `cargo test`). `scripts/test.sh` skips this test and runs `scripts/test-mcu.sh` itself, beside
//! its other steps. `scripts/build-mcu.sh`
//! installs them and fetches the board crate's dependencies, which this test then builds offline.

use std::path::{Path, PathBuf};
use std::process::Command;

fn have(cmd: &str, arg: &str) -> bool {
    Command::new(cmd)
        .arg(arg)
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

#[test]
fn core_on_emulated_cortex_m4f_matches_host() {
    let root: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let missing: Vec<&str> = [
        ("/usr/bin/rustc", "-V"),
        ("/usr/bin/cargo", "-V"),
        ("arm-none-eabi-ld", "--version"),
        ("qemu-system-arm", "--version"),
    ]
    .iter()
    .filter(|(c, a)| !have(c, a))
    .map(|(c, _)| *c)
    .collect();
    let src_ok = Path::new("/usr/lib/rustlib/src/rust/library/core").is_dir();
    if !missing.is_empty() || !src_ok {
        let msg = format!(
            "cross toolchain or QEMU missing ({}{}); run scripts/build-mcu.sh / scripts/test-mcu.sh",
            missing.join(", "),
            if src_ok { "" } else { " rust-web-src" }
        );
        assert!(
            std::env::var("FCC_REQUIRE_MCU").as_deref() != Ok("1"),
            "FCC_REQUIRE_MCU=1 but {msg}"
        );
        eprintln!("SKIPPED mcu_qemu: {msg}");
        return;
    }
    let out = Command::new("bash")
        .arg(root.join("scripts/test-mcu.sh"))
        .env("MCU_SKIP_INSTALL", "1")
        .env("MCU_OFFLINE", "1")
        .output()
        .expect("run scripts/test-mcu.sh");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(out.status.success(), "scripts/test-mcu.sh failed:\n{text}");
    assert!(text.contains(": MATCH"), "no MATCH line:\n{text}");
    assert!(
        text.contains("per 500 Hz step"),
        "no instructions-per-step line:\n{text}"
    );
}
