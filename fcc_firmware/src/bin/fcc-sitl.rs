//! `fcc-sitl`: fly a scenario in lockstep, faster than real time, and print paper A's figures.
//!
//! ```text
//! cargo run --release -p fcc_firmware --bin fcc-sitl -- --scenario launch_configs/scenarios/hover.yaml
//! ```

use clap::Parser;
use fcc_firmware::sitl::{metrics, scenario::Scenario, sim::Sim};
use std::path::PathBuf;
use std::process::ExitCode;
use std::io::Write;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(name = "fcc-sitl", about = "Software-in-the-loop flight of the fcc_firmware core")]
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
}

fn main() -> ExitCode {
    let args = match Args::try_parse() {
        Ok(a) => a,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
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
    let wall = Instant::now();
    sim.run();
    let wall_s = wall.elapsed().as_secs_f64();
    let report = format!(
        "scenario {name}: {:.1} s simulated in {:.2} s wall ({:.0}× real time)\n{}",
        sim.t_s(),
        wall_s,
        sim.t_s() / wall_s,
        metrics::summary(&sim.log)
    );
    // A closed stdout (e.g. piped into `head`) is not an error worth a panic.
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), report.as_bytes());
    if let Some(path) = args.csv {
        if let Err(e) = fcc_firmware::sitl::log::write_csv(&sim.log, &path) {
            eprintln!("fcc-sitl: {}: {e}", path.display());
            return ExitCode::from(1);
        }
        let _ = writeln!(std::io::stdout().lock(), "log written to {}", path.display());
    }
    ExitCode::SUCCESS
}
