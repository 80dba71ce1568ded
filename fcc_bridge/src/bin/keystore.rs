//! `fcc-keystore create KEYSTORE [--ns /fcc]` — an SROS2 keystore for the stack in one command:
//! a CA, the signed governance, and one enclave per role with least-privilege permissions
//! (`/fcc/fcc_bridge`, `/fcc/fcc_mission`, `/ground_station`, `/observer`).
//! `fcc-keystore enclave KEYSTORE ENCLAVE --role ROLE [--ns /fcc]` adds one more.
//!
//! The same layout as `ros2 security create_keystore KEYSTORE` followed by
//! `ros2 security create_enclave KEYSTORE /fcc/fcc_bridge` (and so on), with each enclave's
//! permissions made from the topic table (`fcc_ros::sros2`) instead of sros2's allow-all
//! default. Needs the `openssl` command. See `fcc_bridge::keystore`.

use clap::{Parser, Subcommand};
use fcc_bridge::keystore;
use fcc_ros::sros2::Role;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "fcc-keystore",
    about = "Create an SROS2 keystore for the flight stack"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// A new keystore: CA, governance, and the enclave of every role.
    Create {
        keystore: PathBuf,
        /// The vehicle's ROS namespace.
        #[arg(long, default_value = "/fcc")]
        ns: String,
    },
    /// One more enclave in an existing keystore.
    Enclave {
        keystore: PathBuf,
        /// Its name, an absolute ROS name (`/ground_station2`).
        enclave: String,
        /// bridge, mission, ground (may command) or observer (may only read).
        #[arg(long, value_parser = parse_role)]
        role: Role,
        /// The vehicle's ROS namespace.
        #[arg(long, default_value = "/fcc")]
        ns: String,
    },
}

fn parse_role(s: &str) -> Result<Role, String> {
    Role::parse(s).ok_or_else(|| {
        let names: Vec<_> = Role::ALL.iter().map(|r| r.name()).collect();
        format!("unknown role {s:?} (one of {})", names.join(", "))
    })
}

fn now_s() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64)
}

fn run(cmd: Cmd) -> anyhow::Result<()> {
    match cmd {
        Cmd::Create { keystore: k, ns } => {
            keystore::create(&k)?;
            for role in Role::ALL {
                let enclave = role.default_enclave(&ns);
                keystore::add_enclave(&k, &enclave, role, &ns, now_s())?;
                println!(
                    "fcc-keystore: {} enclave {enclave} ({})",
                    k.display(),
                    role.name()
                );
            }
        }
        Cmd::Enclave {
            keystore: k,
            enclave,
            role,
            ns,
        } => {
            keystore::add_enclave(&k, &enclave, role, &ns, now_s())?;
            println!(
                "fcc-keystore: {} enclave {enclave} ({})",
                k.display(),
                role.name()
            );
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = match fcc_mission::cli::parse::<Cli, _, _>("fcc-keystore", std::env::args_os()) {
        Ok(c) => c,
        Err(code) => return ExitCode::from(code),
    };
    match run(cli.cmd) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fcc-keystore: {e:#}");
            ExitCode::FAILURE
        }
    }
}
