//! A clean start logs no ERROR line (issue 16): the bridge, on a fake MCU, with `ROS_DISTRO`
//! unset, `jazzy` and `kilted`, in both clock modes at once (`clock_source:=sync` subscribes to
//! `/clock`, `clock_source:=mcu` publishes it), with the default log filter. Before the
//! vendored ros2-client fixes this logged rustdds' "Inconsistent topic update" (the spinner's
//! `/clock` reader typed `builtin_interfaces/Time` beside our `rosgraph_msgs/Clock`) and, with
//! `ROS_DISTRO=kilted`, ros2-client's false distribution mismatch.
//! Creates DDS participants: run it in a loopback-only namespace
//! (`../shared/tools/netns-run cargo test -p fcc_bridge`).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn spawn_fake_mcu(link: &Path) -> Child {
    let c = Command::new(env!("CARGO_BIN_EXE_fcc-fake-mcu"))
        .args(["--duration", "20", "--link"])
        .arg(link)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn fcc-fake-mcu");
    let t0 = Instant::now();
    while !link.exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "no pty link {link:?}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    c
}

fn spawn_bridge(link: &Path, ns: &str, clock: &str, distro: Option<&str>) -> Child {
    let mut c = Command::new(env!("CARGO_BIN_EXE_fcc-bridge"));
    c.arg("--device")
        .arg(link)
        .args(["--ros-args", "-r", &format!("__ns:={ns}")])
        .args(["-p", &format!("clock_source:={clock}")])
        .env_remove("RUST_LOG")
        .env_remove("ROS_DISTRO")
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    if let Some(d) = distro {
        c.env("ROS_DISTRO", d);
    }
    c.spawn().expect("spawn fcc-bridge")
}

/// SIGTERM, wait, and the stderr.
fn stop(mut child: Child) -> String {
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let t0 = Instant::now();
    while child.try_wait().expect("try_wait").is_none() {
        if t0.elapsed() > Duration::from_secs(5) {
            let _ = child.kill();
            let _ = child.wait();
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    err
}

#[test]
fn a_clean_start_logs_no_error_line() {
    let dir = std::env::temp_dir().join(format!("fcc_clean_start_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for distro in [None, Some("jazzy"), Some("kilted")] {
        let links: Vec<PathBuf> = ["sync", "mcu"]
            .iter()
            .map(|c| dir.join(format!("{c}_{}.tty", distro.unwrap_or("unset"))))
            .collect();
        let mcus: Vec<Child> = links.iter().map(|l| spawn_fake_mcu(l)).collect();
        let bridges: Vec<Child> = ["sync", "mcu"]
            .iter()
            .zip(&links)
            .map(|(c, l)| spawn_bridge(l, &format!("/clean_{c}"), c, distro))
            .collect();
        // Discovery between the two bridges, the handshake and the first second of streaming.
        std::thread::sleep(Duration::from_millis(3000));
        for (clock, b) in ["sync", "mcu"].iter().zip(bridges) {
            let err = stop(b);
            assert!(
                err.contains("link handshake ok"),
                "ROS_DISTRO={distro:?} clock_source:={clock}: the bridge did not reach the MCU:\n{err}"
            );
            let errors: Vec<&str> = err.lines().filter(|l| l.contains("ERROR")).collect();
            assert!(
                errors.is_empty(),
                "ROS_DISTRO={distro:?} clock_source:={clock}: ERROR lines at start-up:\n{}",
                errors.join("\n")
            );
        }
        for m in mcus {
            stop(m);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
