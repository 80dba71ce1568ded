//! `fcc-bag-recover IN.mcap [-o OUT.mcap] [--killed-at-ns NS]`
//!
//! Rewrites a bag the recorder could not finish (the bridge was killed: SIGKILL, power loss)
//! into a complete MCAP with summary and indexes (like `mcap recover` / `ros2 bag reindex`),
//! and prints how many messages were kept and how much was lost before the kill. The input is
//! never modified. See `fcc_bridge::recover`.

use clap::Parser;
use fcc_bridge::recover::{self, secs};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "fcc-bag-recover",
    about = "Rewrite an unfinished (killed) fcc-bridge bag into a complete MCAP"
)]
struct Cli {
    /// The bag to recover (read only).
    input: PathBuf,
    /// Output file (default: IN_STEM.recovered.mcap beside the input).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// When the recorder was killed (Unix ns, e.g. `date +%s%N`): the loss is then exact
    /// (kill time − last message kept). Without it, the loss is estimated from the input's
    /// last modification, which can only make it look smaller.
    #[arg(long)]
    killed_at_ns: Option<u64>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let output = cli
        .output
        .clone()
        .unwrap_or_else(|| recover::default_output(&cli.input));
    let r = match recover::recover(&cli.input, &output) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("fcc-bag-recover: {e:#}");
            return ExitCode::FAILURE;
        }
    };
    let span = match (r.first_log_ns, r.last_log_ns) {
        (Some(a), Some(b)) => format!(", log time span {:.3} s", secs(b - a)),
        _ => String::new(),
    };
    println!(
        "fcc-bag-recover: {}: kept {} messages on {} topics ({} schemas, {} channels{})",
        cli.input.display(),
        r.messages,
        r.by_topic.len(),
        r.schemas,
        r.channels,
        span
    );
    if r.input_complete {
        println!("the input was complete (data end found): nothing lost");
    } else {
        if r.torn_bytes > 0 {
            println!(
                "dropped the last {} of {} B (no complete record: the chunk open at the kill){}",
                r.torn_bytes,
                r.input_bytes,
                r.stopped
                    .as_deref()
                    .map(|s| format!("; reading stopped at: {s}"))
                    .unwrap_or_default()
            );
        } else {
            println!(
                "the input ends at a record boundary without data end, summary or footer (the recorder was killed between chunks)"
            );
        }
        match (cli.killed_at_ns, r.last_log_ns) {
            (Some(k), Some(last)) => println!(
                "lost before the kill: {:.3} s (killed at {:.3}, last message kept at {:.3} log time)",
                (k as f64 - last as f64) / 1e9,
                secs(k),
                secs(last)
            ),
            (None, Some(last)) => {
                let mtime = std::fs::metadata(&cli.input)
                    .and_then(|m| m.modified())
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map(|d| d.as_nanos() as f64);
                match mtime {
                    // Log time on the wall clock (not sim time): compare.
                    Some(m) if (m - last as f64).abs() < 86_400e9 => println!(
                        "lost before the kill: ≥ {:.3} s (the file's last write − the last message kept; pass --killed-at-ns for the exact figure)",
                        (m - last as f64) / 1e9
                    ),
                    _ => println!(
                        "lost before the kill: unknown (log time is not the wall clock; pass --killed-at-ns)"
                    ),
                }
            }
            (_, None) => println!("no message was recoverable"),
        }
    }
    println!(
        "wrote {} (summary, chunk and message indexes, statistics)",
        output.display()
    );
    ExitCode::SUCCESS
}
