//! SIGTERM / SIGINT stop the bridge promptly at any point of its start-up, and a DDS start-up
//! that stalls (rustdds' discovery deadlock, simulated by `FCC_BRIDGE_TEST_STALL_DDS`) ends in
//! restarts and then one clear error line, never in a silent hang.
//! The tests that create a participant must run in a loopback-only namespace
//! (`../shared/tools/netns-run cargo test -p fcc_bridge`).

use std::io::Read;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn bridge(env: &[(&str, &str)]) -> Child {
    let mut c = Command::new(env!("CARGO_BIN_EXE_fcc-bridge"));
    c.args(["--device", "/nonexistent/fcc-startup-test-tty"])
        .args(["--ros-args", "-r", "__ns:=/startup_test"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    for (k, v) in env {
        c.env(k, v);
    }
    c.spawn().expect("spawn fcc-bridge")
}

fn kill(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{sig}"), &child.id().to_string()])
        .status()
        .expect("kill")
        .success();
    assert!(ok, "kill -{sig}");
}

/// Wait for the exit; (code, seconds waited, stderr). Kills it after `limit` (code None).
/// A process ended by `sig` itself (before its handlers were installed) counts as code 0.
fn wait_exit(mut child: Child, limit: Duration) -> (Option<i32>, f64, String) {
    use std::os::unix::process::ExitStatusExt;
    let t0 = Instant::now();
    let code = loop {
        if let Some(s) = child.try_wait().expect("try_wait") {
            break match s.signal() {
                Some(15) | Some(2) => Some(0),
                Some(n) => Some(128 + n),
                None => s.code(),
            };
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let dt = t0.elapsed().as_secs_f64();
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    (code, dt, err)
}

#[test]
fn sigterm_during_a_stalled_dds_startup_stops_at_once() {
    for sig in ["TERM", "INT"] {
        let c = bridge(&[("FCC_BRIDGE_TEST_STALL_DDS", "1")]);
        std::thread::sleep(Duration::from_millis(400));
        kill(&c, sig);
        let (code, dt, err) = wait_exit(c, Duration::from_secs(5));
        assert_eq!(code, Some(0), "SIG{sig}: exit code; stderr:\n{err}");
        assert!(dt < 2.0, "SIG{sig}: took {dt:.2} s to stop; stderr:\n{err}");
    }
}

#[test]
fn a_stalled_dds_startup_restarts_then_fails_with_one_line() {
    let c = bridge(&[
        ("FCC_BRIDGE_TEST_STALL_DDS", "1"),
        ("FCC_BRIDGE_DDS_STARTUP_TIMEOUT_MS", "300"),
    ]);
    let (code, dt, err) = wait_exit(c, Duration::from_secs(10));
    assert_eq!(code, Some(1), "exit code; stderr:\n{err}");
    assert!(dt < 5.0, "took {dt:.2} s");
    let stalls: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("fcc-bridge: DDS start-up stalled for 0.3 s"))
        .collect();
    assert_eq!(stalls.len(), 3, "stderr:\n{err}");
    assert!(
        stalls[0].ends_with("restarting (attempt 2 of 3)"),
        "{}",
        stalls[0]
    );
    assert!(
        stalls[1].ends_with("restarting (attempt 3 of 3)"),
        "{}",
        stalls[1]
    );
    assert!(!stalls[2].contains("restarting"), "{}", stalls[2]);
    assert_eq!(
        err.lines().last(),
        Some(stalls[2]),
        "the error is the last line"
    );
}

#[test]
fn signals_stop_the_bridge_promptly_during_and_after_dds_startup() {
    // Right after the start (the participant is being created), then once running.
    for (sig, after_ms) in [("TERM", 30), ("INT", 80), ("TERM", 1500), ("INT", 1500)] {
        let c = bridge(&[]);
        std::thread::sleep(Duration::from_millis(after_ms));
        kill(&c, sig);
        let (code, dt, err) = wait_exit(c, Duration::from_secs(5));
        assert_eq!(code, Some(0), "SIG{sig} at {after_ms} ms: stderr:\n{err}");
        assert!(
            dt < 2.0,
            "SIG{sig} at {after_ms} ms: {dt:.2} s; stderr:\n{err}"
        );
    }
}
