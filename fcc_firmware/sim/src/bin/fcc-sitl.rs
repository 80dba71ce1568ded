//! `fcc-sitl`: fly a scenario in lockstep, faster than real time, and print paper A's figures.
//!
//! ```text
//! cargo run --release -p fcc_sim --bin fcc-sitl -- --scenario launch_configs/scenarios/hover.yaml
//! ```

use clap::Parser;
use fcc_sim::{metrics, scenario::Scenario, sim::Sim};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(
    name = "fcc-sitl",
    about = "Software-in-the-loop flight of the fcc_firmware core"
)]
struct Args {
    /// Scenario file (YAML), e.g. launch_configs/scenarios/hover.yaml
    #[arg(long)]
    scenario: PathBuf,
    /// Override the scenario's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Write the 50 Hz flight log as CSV here.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Serve the MCU link on a pseudo-terminal (the bridge opens it like a UART) instead of
    /// flying the scenario's plan with the in-process mission computer. Prints the device path.
    #[arg(long)]
    link_pty: bool,
    /// With --link-pty: also make this symlink to the pty device (e.g. /tmp/fcc-sitl.tty).
    #[arg(long, requires = "link_pty")]
    pty_link: Option<PathBuf>,
    /// Simulated seconds per wall-clock second; 0 = as fast as possible (lockstep).
    /// Default: 1 with --link-pty (real time, as a board), 0 otherwise.
    #[arg(long, allow_negative_numbers = true)]
    speed: Option<f64>,
}

fn main() -> ExitCode {
    let args = match fcc_mission::cli::parse::<Args, _, _>("fcc-sitl", std::env::args_os()) {
        Ok(a) => a,
        Err(code) => return ExitCode::from(code),
    };
    let mut scenario = match Scenario::load(&args.scenario) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("fcc-sitl: {e}");
            return ExitCode::from(2);
        }
    };
    if let Some(seed) = args.seed {
        scenario.seed = seed;
    }
    let name = scenario.name.clone();
    let mut sim = match Sim::new(scenario) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("fcc-sitl: {e}");
            return ExitCode::from(2);
        }
    };
    let speed = args.speed.unwrap_or(if args.link_pty { 1.0 } else { 0.0 });
    if !(speed.is_finite() && speed >= 0.0) {
        eprintln!("fcc-sitl: --speed: must be a finite number ≥ 0 (0 = as fast as possible)");
        return ExitCode::from(2);
    }
    if args.link_pty {
        let pty = match fcc_sim::pty::PtyLink::open(args.pty_link.as_deref()) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("fcc-sitl: cannot open a pseudo-terminal: {e}");
                return ExitCode::from(1);
            }
        };
        let _ = writeln!(
            std::io::stdout().lock(),
            "fcc-sitl: serving the link on {}",
            pty.slave_path().display()
        );
        if let Some(l) = pty.symlink() {
            let _ = writeln!(
                std::io::stdout().lock(),
                "fcc-sitl: link symlink {}",
                l.display()
            );
        }
        if let Err(e) = sim.serve_link(pty) {
            eprintln!("fcc-sitl: the scenario's telemetry rates: {e}");
            std::process::exit(2);
        }
        // A board-like run lasts as long as it is left running: its log waits on disk.
        if let Err(e) = sim.spill_log(&std::env::temp_dir()) {
            eprintln!("fcc-sitl: {e}; the flight log is kept in memory");
        }
    }
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, stop.clone());
    }
    let wall = Instant::now();
    while !sim.finished() && !stop.load(std::sync::atomic::Ordering::Relaxed) {
        sim.tick();
        if speed > 0.0 {
            let ahead = sim.t_s() / speed - wall.elapsed().as_secs_f64();
            if ahead > 0.0005 {
                std::thread::sleep(std::time::Duration::from_secs_f64(ahead));
            }
        }
    }
    sim.finish();
    let wall_s = wall.elapsed().as_secs_f64();
    let link = sim.link().map_or(String::new(), |(_, pty)| {
        format!(
            "pty link: {} frames ({} bytes) dropped whole with the transmit ring full\n",
            pty.tx_dropped_frames, pty.tx_dropped_bytes
        )
    });
    let report = format!(
        "scenario {name}: {:.1} s simulated in {:.2} s wall ({:.0}× real time)\n{link}{}",
        sim.t_s(),
        wall_s,
        sim.t_s() / wall_s,
        metrics::summary(&sim.log)
    );
    // A closed stdout (e.g. piped into `head`) is not an error worth a panic.
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), report.as_bytes());
    if let Some(path) = args.csv {
        if let Err(e) = fcc_sim::log::write_csv(&sim.log, &path) {
            eprintln!("fcc-sitl: {}: {e}", path.display());
            return ExitCode::from(1);
        }
        let _ = writeln!(
            std::io::stdout().lock(),
            "log written to {}",
            path.display()
        );
    }
    ExitCode::SUCCESS
}
