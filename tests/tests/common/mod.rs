//! Shared helpers for the scenario tests: load a scenario from `launch_configs/scenarios`,
//! fly it in the lockstep simulator, return its log.

#![allow(dead_code)]

use fcc_sim::log::FlightLog;
use fcc_sim::scenario::Scenario;
use fcc_sim::sim::Sim;
use std::path::PathBuf;

pub fn scenario_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../launch_configs/scenarios")
        .join(format!("{name}.yaml"))
}

pub fn load(name: &str) -> Scenario {
    Scenario::load(&scenario_path(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Fly a scenario as it is in the repository (its own seed).
pub fn fly(name: &str) -> FlightLog {
    fly_scenario(load(name))
}

pub fn fly_scenario(s: Scenario) -> FlightLog {
    let mut sim = Sim::new(s).unwrap_or_else(|e| panic!("{e}"));
    sim.run();
    sim.log
}
