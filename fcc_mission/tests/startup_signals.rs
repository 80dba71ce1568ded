//! fcc-mission shares fcc-bridge's start-up protection (`fcc_ros::startup`): a DDS start-up
//! that stalls (rustdds' discovery deadlock, simulated by `FCC_MISSION_TEST_STALL_DDS`) ends in
//! restarts and then one clear error line, and SIGTERM / SIGINT stop it promptly meanwhile.
//! Run in a loopback-only namespace
//! (`../shared/tools/netns-run cargo test -p fcc_mission --features ros`).

use std::io::Read;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn mission(env: &[(&str, &str)]) -> Child {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../launch_configs/missions/square.yaml"
    );
    let mut c = Command::new(env!("CARGO_BIN_EXE_fcc-mission"));
    c.args(["--mission", file])
        .args(["--ros-args", "-r", "__ns:=/startup_test"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    for (k, v) in env {
        c.env(k, v);
    }
    c.spawn().expect("spawn fcc-mission")
}

/// Wait for the exit; (code, seconds waited, stderr). Kills it after `limit` (code None).
fn wait_exit(mut child: Child, limit: Duration) -> (Option<i32>, f64, String) {
    use std::os::unix::process::ExitStatusExt;
    let t0 = Instant::now();
    let code = loop {
        if let Some(s) = child.try_wait().expect("try_wait") {
            break match s.signal() {
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
fn a_stalled_dds_startup_restarts_then_fails_with_one_line_and_signals_stop_it() {
    let c = mission(&[
        ("FCC_MISSION_TEST_STALL_DDS", "1"),
        ("FCC_MISSION_DDS_STARTUP_TIMEOUT_MS", "300"),
    ]);
    let (code, dt, err) = wait_exit(c, Duration::from_secs(10));
    assert_eq!(code, Some(1), "exit code; stderr:\n{err}");
    assert!(dt < 5.0, "took {dt:.2} s");
    let stalls: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("fcc-mission: DDS start-up stalled for 0.3 s"))
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

    // SIGTERM / SIGINT while the start-up is stalled (handled: exit 0, not killed by it).
    for sig in ["TERM", "INT"] {
        let c = mission(&[("FCC_MISSION_TEST_STALL_DDS", "1")]);
        std::thread::sleep(Duration::from_millis(400));
        let ok = Command::new("kill")
            .args([&format!("-{sig}"), &c.id().to_string()])
            .status()
            .expect("kill")
            .success();
        assert!(ok, "kill -{sig}");
        let (code, dt, err) = wait_exit(c, Duration::from_secs(5));
        assert_eq!(code, Some(0), "SIG{sig}: exit code; stderr:\n{err}");
        assert!(dt < 2.0, "SIG{sig}: took {dt:.2} s to stop; stderr:\n{err}");
    }
}
