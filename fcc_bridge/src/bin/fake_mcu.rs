//! `fcc-fake-mcu [--duration S] [--log FILE] [--link PATH] [--schema-hash 0xHEX] [--garbage]
//!  [--firmware-rates] [--imu-hz N] [--nav-hz N] [--imu-counter]`
//!
//! Opens a pty, prints `PTY <slave path>` on stdout, and plays a scripted MCU on it (see
//! `fcc_bridge::fake_mcu`). For tests of the bridge without the simulator.

use clap::Parser;
use fcc_bridge::fake_mcu::{self, FakeOptions};
use std::time::Duration;

#[derive(Parser)]
struct Cli {
    /// Seconds to run (default: forever).
    #[arg(long)]
    duration: Option<f64>,
    /// JSON-lines log of the setpoints and commands received.
    #[arg(long)]
    log: Option<String>,
    /// Also create this symlink to the pty.
    #[arg(long)]
    link: Option<String>,
    /// Announce this schema hash instead of the real one (mismatch test).
    #[arg(long, value_parser = parse_hex)]
    schema_hash: Option<u32>,
    /// Mix garbage bytes into the stream once a second.
    #[arg(long)]
    garbage: bool,
    /// Stream at the firmware's default link rates (IMU 200, nav 100, mag/baro/altitude 50,
    /// GPS/ranges/status 10, battery 5 Hz) instead of the fake's own (nav 50, mag/baro/alt 20).
    #[arg(long)]
    firmware_rates: bool,
    /// IMU frame rate in Hz (the loop ticks at max(this, 200) Hz); e.g. 500 for the latency
    /// benchmark.
    #[arg(long)]
    imu_hz: Option<u16>,
    /// Navigation-state frame rate in Hz.
    #[arg(long)]
    nav_hz: Option<u16>,
    /// Put the IMU frame counter in gyro x (loss counting by a peer).
    #[arg(long)]
    imu_counter: bool,
}

fn parse_hex(s: &str) -> Result<u32, String> {
    u32::from_str_radix(s.trim_start_matches("0x"), 16).map_err(|e| e.to_string())
}

fn main() {
    let cli = Cli::parse();
    let pty = fake_mcu::open_pty().expect("openpty");
    if let Some(l) = &cli.link {
        let _ = std::fs::remove_file(l);
        std::os::unix::fs::symlink(&pty.path, l).expect("symlink");
    }
    println!("PTY {}", pty.path);
    let mut o = FakeOptions {
        duration: cli.duration.map(Duration::from_secs_f64),
        log: cli.log,
        garbage: cli.garbage,
        imu_counter: cli.imu_counter,
        ..FakeOptions::default()
    };
    if let Some(h) = cli.schema_hash {
        o.schema_hash = h;
    }
    if cli.firmware_rates {
        o.rates = fcc_msgs::StreamRates::DEFAULT;
    }
    if let Some(hz) = cli.imu_hz {
        o.rates.imu_raw_hz = hz;
    }
    if let Some(hz) = cli.nav_hz {
        o.rates.nav_state_hz = hz;
    }
    use std::io::Write;
    std::io::stdout().flush().ok();
    match fake_mcu::run_stats(pty, &o) {
        Ok(s) => eprintln!(
            "fcc-fake-mcu: sent {} frames ({} IMU at {} Hz, {} late ticks)",
            s.frames, s.imu_frames, o.rates.imu_raw_hz, s.late_ticks
        ),
        Err(e) => {
            eprintln!("fcc-fake-mcu: {e}");
            std::process::exit(1);
        }
    }
    if let Some(l) = &cli.link {
        let _ = std::fs::remove_file(l);
    }
}
