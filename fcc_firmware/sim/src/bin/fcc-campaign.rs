//! `fcc-campaign`: the Monte-Carlo flight-safety campaign (`fcc_sim::campaign`):
//! seeds × scenario families, scored on the simulator's truth; prints the table of
//! percentiles and worst cases and every failure; exit status 1 if any flight failed.
//!
//! ```text
//! cargo run --release -p fcc_sim --bin fcc-campaign -- --per-family 72 --long
//! ```

use clap::Parser;
use fcc_sim::campaign;
use std::process::ExitCode;

/// `println!` that tolerates a closed stdout (e.g. piped into `head`).
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout().lock(), $($t)*);
    }};
}

#[derive(Parser, Debug)]
#[command(
    name = "fcc-campaign",
    about = "Monte-Carlo flight-safety campaign on the simulator's truth"
)]
struct Args {
    /// Flights per scenario family (8 families).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u64).range(1..=10_000))]
    per_family: u64,
    /// First seed (flight i of a family uses seed + i).
    #[arg(long, default_value_t = 1000)]
    seed: u64,
    /// Full durations (velocity cruise 5 min, gale hover 100 s) as the benchmark flies them.
    #[arg(long)]
    long: bool,
    /// Worker threads (default: the machine's cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Fly one flight only (`family:seed`), print its summary and write its 50 Hz CSV here.
    #[arg(long, value_name = "FAMILY:SEED", requires = "csv")]
    only: Option<String>,
    /// With --only: the CSV log.
    #[arg(long)]
    csv: Option<std::path::PathBuf>,
    /// Fly only this family (repeatable; default: every family).
    #[arg(long, value_name = "FAMILY")]
    family: Vec<String>,
    /// Also print every flight's figures, one line each (`FLIGHT family seed name=value …`).
    #[arg(long)]
    per_flight: bool,
    /// Also write the table here (Markdown).
    #[arg(long)]
    out: Option<std::path::PathBuf>,
}

fn main() -> ExitCode {
    let args = match Args::try_parse() {
        Ok(a) => a,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    if let (Some(only), Some(csv)) = (&args.only, &args.csv) {
        return fly_one(only, csv, args.long);
    }
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let families: Vec<&'static str> = if args.family.is_empty() {
        campaign::FAMILIES.to_vec()
    } else {
        let mut v = Vec::new();
        for f in &args.family {
            match campaign::family(f) {
                Some(x) => v.push(x),
                None => {
                    eprintln!(
                        "fcc-campaign: --family {f}: expected one of {}",
                        campaign::FAMILIES.join(", ")
                    );
                    return ExitCode::from(2);
                }
            }
        }
        v
    };
    let t0 = std::time::Instant::now();
    let out = campaign::run_families(
        &families,
        args.per_family as usize,
        args.seed,
        args.long,
        threads,
    );
    if args.per_flight {
        for o in &out {
            let f: Vec<String> = o
                .figures
                .iter()
                .map(|(k, v)| format!("{k}={v:.3}"))
                .collect();
            say!("FLIGHT {} {} {}", o.family, o.seed, f.join(" "));
        }
    }
    let table = campaign::table(&out);
    say!("{table}");
    say!(
        "wall time {:.1} s on {threads} threads",
        t0.elapsed().as_secs_f64()
    );
    if let Some(p) = &args.out {
        if let Err(e) = std::fs::write(p, &table) {
            eprintln!("fcc-campaign: {}: {e}", p.display());
            return ExitCode::from(1);
        }
    }
    if out.iter().any(|o| !o.failures.is_empty()) {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

fn fly_one(only: &str, csv: &std::path::Path, long: bool) -> ExitCode {
    let parsed = only
        .split_once(':')
        .and_then(|(f, s)| Some((campaign::family(f)?, s.parse::<u64>().ok()?)));
    let Some((family, seed)) = parsed else {
        eprintln!(
            "fcc-campaign: --only {only}: expected FAMILY:SEED with FAMILY one of {}",
            campaign::FAMILIES.join(", ")
        );
        return ExitCode::from(2);
    };
    let f = campaign::generate(family, seed, long);
    let (o, log) = campaign::fly_logged(&f);
    say!("{family} seed {seed}: {}", f.what);
    say!("{}", fcc_sim::metrics::summary(&log));
    say!("failures: {:?}", o.failures);
    if let Err(e) = fcc_sim::log::write_csv(&log, csv) {
        eprintln!("fcc-campaign: {}: {e}", csv.display());
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}
